//! `sora render`: an image of the sky, PNG (display colours) or OpenEXR
//! (linear HDR).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use sora::ImageSettings;
use sora::camera::{Camera, PerspectiveCamera};
use sora::colour::{RgbColourSpace, SpectrumToXyz};
use sora::output::{
    ChannelKind, DisplayImage, ExrOptions, ExrSampleType, LinearImage, OutputFormat, write_exr,
    write_png,
};

use crate::arguments::{AtmosphereSource, ColourOptions, Scattering, SunAndObserver};

/// Render the sky to an image.
///
/// Scattering: multiple (default) adds to the sun's single scattering all
/// higher orders and the skylight reflected by the ground (a discrete-
/// ordinate field solved once per image); single is the paper's model.
///
/// The output format follows the file extension: .png (8-bit sRGB display
/// colours, or 16-bit with --png-16-bit) or .exr (linear radiance-scaled
/// RGB or XYZ, float or half; no exposure applied: 1.0 = the XYZ of a
/// spectrum of 1 W m^-2 sr^-1 nm^-1 integrated without the 683 lm/W factor).
///
/// Cameras:
///   fisheye      the whole sky in a disc, zenith at the centre, north up,
///                east LEFT (a sky chart seen from below); equidistant
///   equirect     360x180 panorama, north at the centre, east at 3/4 width,
///                zenith at the top row (an environment map)
///   perspective  a pinhole camera: --view-elevation, --view-azimuth, --fov-deg
///
/// Examples (the sun as angles; the sun over Tokyo at 05:30 local time):
///   sora render --preset earth-clear --sun-elevation 30 -o sky.png
///   sora render --preset earth-clear --time 2026-06-21T05:30:00+09:00 \
///       --location 35.68,139.77 -o tokyo.png
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct RenderArgs {
    #[command(flatten)]
    source: AtmosphereSource,

    #[command(flatten)]
    sun: SunAndObserver,

    /// Output image: .png or .exr
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,

    /// Projection
    #[arg(long, value_enum, default_value_t = CameraKind::Fisheye)]
    camera: CameraKind,

    /// Image width in pixels [default: 512; 1024 for equirect]
    #[arg(long, value_name = "PIXELS")]
    width: Option<u32>,

    /// Image height in pixels [default: the width; half of it for equirect]
    #[arg(long, value_name = "PIXELS")]
    height: Option<u32>,

    /// Perspective camera: elevation of the view direction, degrees
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 10.0,
        allow_hyphen_values = true
    )]
    view_elevation: f64,

    /// Perspective camera: azimuth of the view direction, degrees clockwise from north
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 180.0,
        allow_hyphen_values = true
    )]
    view_azimuth: f64,

    /// Perspective camera: horizontal field of view, degrees
    #[arg(long, value_name = "DEG", default_value_t = 90.0)]
    fov_deg: f64,

    /// fast (tables per image) or reference (the paper's march per pixel, slow)
    #[arg(long, value_enum, default_value_t = Method::Fast)]
    method: Method,

    /// multiple (all orders of scattering and skylight reflected by the
    /// ground) or single (sunlight scattered once, the paper's model)
    #[arg(long, value_enum, default_value_t = Scattering::Multiple)]
    scattering: Scattering,

    /// Do not draw the sun's disc
    #[arg(long)]
    no_sun_disc: bool,

    #[command(flatten)]
    colour: ColourOptions,

    /// Write 16-bit PNG instead of 8-bit
    #[arg(long)]
    png_16_bit: bool,

    /// OpenEXR: store half floats instead of 32-bit floats
    #[arg(long)]
    exr_half: bool,

    /// OpenEXR: store CIE XYZ channels instead of linear RGB
    #[arg(long)]
    exr_xyz: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum CameraKind {
    Fisheye,
    Equirect,
    Perspective,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Method {
    Fast,
    Reference,
}

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    // Check everything cheap before the expensive work.
    let format = OutputFormat::from_path(&args.output)?;
    let camera = match args.camera {
        CameraKind::Fisheye => Camera::Fisheye,
        CameraKind::Equirect => Camera::Equirectangular,
        CameraKind::Perspective => Camera::Perspective(PerspectiveCamera::new(
            args.view_elevation,
            args.view_azimuth,
            args.fov_deg,
        )?),
    };
    let width = args
        .width
        .unwrap_or(if args.camera == CameraKind::Equirect {
            1024
        } else {
            512
        });
    let height = args
        .height
        .unwrap_or(if args.camera == CameraKind::Equirect {
            width.div_ceil(2)
        } else {
            width
        });
    if let Some(parent) = args.output.parent().filter(|p| !p.as_os_str().is_empty())
        && !parent.is_dir()
    {
        bail!(
            "{}: the directory {} does not exist",
            args.output.display(),
            parent.display()
        );
    }
    let mut atmosphere = args.source.load()?;
    let started = Instant::now();
    let method = match args.method {
        Method::Fast => sora::Method::Fast,
        Method::Reference => sora::Method::REFERENCE_DEFAULT,
    };
    let sky = args
        .sun
        .sky(&mut atmosphere, args.scattering.to_library(), method)?;
    let to_xyz = SpectrumToXyz::new(sky.wavelengths(), args.colour.observer);
    let image = ImageSettings {
        camera,
        width,
        height,
        draw_sun_disc: !args.no_sun_disc,
    };
    let bar = progress_bar(height as u64);
    let xyz = sky.render_xyz(&image, &to_xyz, &|rows| bar.set_position(rows as u64))?;
    bar.finish_and_clear();
    let render_seconds = started.elapsed().as_secs_f64();

    let (w, h) = (width as usize, height as usize);
    match format {
        OutputFormat::Png => {
            let mapping = args.colour.display_mapping();
            if args.png_16_bit {
                let data = mapping.to_u16(&xyz)?.into_iter().flatten().collect();
                write_png(&args.output, &DisplayImage::new(w, h, data)?)?;
            } else {
                let data = mapping.to_u8(&xyz)?.into_iter().flatten().collect();
                write_png(&args.output, &DisplayImage::new(w, h, data)?)?;
            }
        }
        OutputFormat::Exr => {
            let (kind, pixels) = if args.exr_xyz {
                (
                    ChannelKind::Xyz,
                    xyz.iter()
                        .map(|c| [c.x as f32, c.y as f32, c.z as f32])
                        .collect(),
                )
            } else {
                let space = RgbColourSpace::Srgb;
                let pixels = xyz
                    .iter()
                    .map(|c| {
                        let rgb = space.linear_rgb_from_xyz(*c);
                        [rgb.r as f32, rgb.g as f32, rgb.b as f32]
                    })
                    .collect();
                (ChannelKind::Rgb, pixels)
            };
            let options = ExrOptions {
                sample_type: if args.exr_half {
                    ExrSampleType::F16
                } else {
                    ExrSampleType::F32
                },
                ..ExrOptions::default()
            };
            write_exr(
                &args.output,
                &LinearImage::new(w, h, kind, pixels)?,
                options,
            )
            .with_context(|| format!("writing {}", args.output.display()))?;
        }
    }
    let total_seconds = started.elapsed().as_secs_f64();
    let pixels_per_second = (w * h) as f64 / render_seconds;
    let rate = if pixels_per_second >= 1e5 {
        format!("{:.2} Mpixel/s", pixels_per_second / 1e6)
    } else {
        format!("{pixels_per_second:.0} pixel/s")
    };
    let (sun_elevation, sun_azimuth) = args.sun.sun_deg()?;
    eprintln!(
        "rendered {width}x{height} ({} wavelengths, {:?} method, {:?} scattering, sun at {sun_elevation:.4} deg elevation, {sun_azimuth:.4} deg azimuth) in {render_seconds:.3} s ({rate}), wrote {} in {total_seconds:.3} s total",
        args.sun.wavelengths.len(),
        args.method,
        args.scattering,
        args.output.display()
    );
    Ok(())
}

/// A progress bar on stderr when it is a terminal, hidden otherwise.
fn progress_bar(rows: u64) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(rows),
        indicatif::ProgressDrawTarget::stderr(),
    );
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{spinner} rendering [{bar:40}] {pos}/{len} rows, {eta} left",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
