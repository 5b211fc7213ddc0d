//! `sora render`: an image of the sky, PNG (display colours) or OpenEXR
//! (linear HDR).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use sora::ImageSettings;
use sora::camera::{Camera, PerspectiveCamera};
use sora::colour::SpectrumToXyz;
use sora::output::{
    ChannelKind, DisplayImage, ExrOptions, ExrSampleType, LinearImage, OutputFiles, OutputFormat,
    SkyImageUnits,
};

use crate::arguments::{
    AtmosphereSource, ColourOptions, Resolution, SunAndObserver, library_names,
};
use crate::estimate;
use crate::polarisation_maps;

/// Render the sky to an image.
///
/// Scattering: multiple (default) adds to the sun's single scattering all
/// higher orders and the skylight reflected by the ground (a discrete-
/// ordinate field solved once per image); single is the paper's model.
///
/// The output format follows the file extension: .png (8-bit sRGB display
/// colours, or 16-bit with --png-16-bit; --exposure or --ev100) or .exr
/// (linear RGB or XYZ, float or half, no exposure applied) in --units
/// radiance (default: 1.0 = the XYZ of a spectrum of 1 W m^-2 sr^-1 nm^-1,
/// without the 683 lm/W factor) or luminance (Y in cd/m^2); the unit, the
/// sun and whiteLuminance are written into the EXR header. Half floats end
/// at 65504: the sun's core exceeds that in luminance units, so
/// --exr-half fails then unless --half-overflow clamp is given (or
/// --no-sun-disc, or 32-bit floats).
///
/// Polarisation: by default the light is followed as Stokes vectors, so
/// the image is the intensity of polarised light (--polarisation off for
/// scalar light). --stokes adds the Stokes images S0..S3 (I, Q, U, V) to
/// an OpenEXR file as layers S0.R, S0.G, ... S3.B (or .X, .Y, .Z with
/// --exr-xyz; Q, U, V may be negative), Q and U referred to each pixel's
/// meridian plane (Q > 0: vertical); --dolp and --aop write the degree
/// and the angle of linear polarisation (luminance-weighted, the angle
/// from the vertical toward the observer's left) as PNG maps with a
/// legend (docs/polarisation.md).
///
/// Night: pixels darker than 1e-6 cd/m^2 (the night floor, 200 times below
/// the natural night sky's airglow and starlight, which the model lacks)
/// are written black; when the whole sky is that dark, auto exposure says
/// so on stderr and writes a black image.
///
/// Aerial perspective (--distance-m D, or --depth DEPTH.exr with the
/// distance per pixel in m): instead of the sky, the light the air
/// scatters into each pixel's view between the eye and the point, and the
/// segment's transmittance as the EXR layer transmittance; a scene pixel L
/// is then seen as L * transmittance + image (OpenEXR only).
///
/// Cameras:
///   fisheye      the whole sky in a disc, zenith at the centre, north up,
///                east LEFT (a sky chart seen from below); equidistant
///   equirect     360x180 panorama, north at the centre, east at 3/4 width,
///                zenith at the top row (an environment map); also
///                spelled equirectangular, as Python spells it
///   perspective  a pinhole camera: --view-elevation, --view-azimuth, --fov-deg
///
/// Examples (the sun as angles; the sun over Tokyo at 05:30 local time):
///   sora render --preset earth-clear --sun-elevation 30 -o sky.png
///   sora render --preset earth-clear --time 2026-06-21T05:30:00+09:00 \
///       --location 35.68,139.77 -o tokyo.png
///   sora render --preset earth-clear --sun-elevation 30 -o sky.exr \
///       --stokes --dolp degree.png --aop angle.png
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct RenderArgs {
    #[command(flatten)]
    source: AtmosphereSource,

    #[command(flatten)]
    sun: SunAndObserver,

    /// Output image: .png or .exr, replaced atomically. A symbolic link is
    /// followed (the file it points to is written, the link kept); a
    /// directory, a device or FIFO, a read-only file, a missing directory or
    /// a path given to two outputs is refused before any work; the outputs
    /// of a run (frames, --dolp, --aop) are written all or none
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,

    /// Projection
    #[arg(long, value_enum, default_value_t = CameraKind::Fisheye)]
    camera: CameraKind,

    /// Image width in pixels [default: 512; 1024 for equirect]
    #[arg(long, value_name = "PIXELS", allow_hyphen_values = true)]
    width: Option<i64>,

    /// Image height in pixels [default: the width; half of it for equirect]
    #[arg(long, value_name = "PIXELS", allow_hyphen_values = true)]
    height: Option<i64>,

    /// Perspective camera: elevation of the view direction, degrees
    /// [default: 10] (an error with the other cameras, which show the whole
    /// sky)
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    view_elevation: Option<f64>,

    /// Perspective camera: azimuth of the view direction, degrees clockwise
    /// from north, read modulo 360 [default: 180]
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    view_azimuth: Option<f64>,

    /// Perspective camera: horizontal field of view, degrees [default: 90]
    #[arg(long, value_name = "DEG")]
    fov_deg: Option<f64>,

    /// fast (tables per image) or reference (the paper's march per pixel, slow)
    #[arg(
        long,
        value_parser = library_names::<sora::Method>(RENDER_METHODS),
        default_value = "fast"
    )]
    method: sora::Method,

    /// multiple (all orders of scattering and skylight reflected by the
    /// ground) or single (sunlight scattered once, the paper's model)
    #[arg(
        long,
        value_parser = library_names::<sora::Scattering>(&sora::Scattering::NAMES),
        default_value = "multiple"
    )]
    scattering: sora::Scattering,

    #[command(flatten)]
    resolution: Resolution,

    /// Do not draw the sun's disc
    #[arg(long)]
    no_sun_disc: bool,

    /// A sequence: frames from --sun-elevation (or the sun's elevation at
    /// --time, at its azimuth) to this elevation, degrees,
    /// written as OUTPUT_000.png, OUTPUT_001.png, ... at one exposure (the
    /// first frame's auto exposure, or --exposure/--ev100)
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        requires = "sun_elevation"
    )]
    sun_elevation_to: Option<f64>,

    /// A sequence: the step between frames, degrees
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 1.0,
        requires = "sun_elevation_to"
    )]
    sun_elevation_step: f64,

    #[command(flatten)]
    colour: ColourOptions,

    /// Write 16-bit PNG instead of 8-bit
    #[arg(long)]
    png_16_bit: bool,

    /// OpenEXR: store half floats instead of 32-bit floats
    #[arg(long)]
    exr_half: bool,

    /// OpenEXR half floats: values beyond 65504 are an error (default) or
    /// are clamped to 65504
    #[arg(long, value_enum, default_value_t = HalfOverflow::Error, requires = "exr_half")]
    half_overflow: HalfOverflow,

    /// OpenEXR: radiance (XYZ of W m^-2 sr^-1 nm^-1 over nm, i.e.
    /// W m^-2 sr^-1, y-bar weighted) or luminance (x 683 lm/W: Y in cd/m^2)
    #[arg(long, value_enum, default_value_t = Units::Radiance)]
    units: Units,

    /// OpenEXR: store CIE XYZ channels instead of linear RGB
    #[arg(long)]
    exr_xyz: bool,

    /// OpenEXR: add the Stokes images S0..S3 as layers (needs polarised
    /// light, the default)
    #[arg(long)]
    stokes: bool,

    /// Also write the degree of linear polarisation as a PNG map with a
    /// legend (viridis, 0..1)
    #[arg(long, value_name = "FILE.png")]
    dolp: Option<PathBuf>,

    /// Also write the angle of polarisation as a PNG map with a legend (a
    /// cyclic perceptual colour map, -90..90 degrees from the vertical)
    #[arg(long, value_name = "FILE.png")]
    aop: Option<PathBuf>,

    /// Aerial perspective: instead of the sky, the light the air scatters
    /// into each pixel's view between the eye and a point this far along
    /// it (m, > 0), and its transmittance as the EXR layer "transmittance"
    #[arg(
        long,
        value_name = "M",
        allow_hyphen_values = true,
        conflicts_with = "depth"
    )]
    distance_m: Option<f64>,

    /// Aerial perspective with a distance per pixel: an OpenEXR of the
    /// image's size whose channel Z (or its only channel) holds the
    /// distance along each pixel's view, m (> 0; infinity for the sky)
    #[arg(long, value_name = "FILE.exr")]
    depth: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum HalfOverflow {
    Error,
    Clamp,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Units {
    Radiance,
    Luminance,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum CameraKind {
    Fisheye,
    #[value(alias = "equirectangular")]
    Equirect,
    Perspective,
}

/// The methods that render images (the library's first two; the path
/// tracer gives views, not images).
const RENDER_METHODS: &[&str] = sora::Method::NAMES.split_at(2).0;

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    // Check everything cheap before the expensive work.
    let format = OutputFormat::from_path(&args.output)?;
    let camera = camera(&args)?;
    // Any integer parses; the library checks the range (one message for
    // --width -5, --width=-5 and --width 0).
    let side = |name, side: Option<i64>| side.map(|s| sora::sky::image_side(name, s)).transpose();
    let width = side("image width", args.width)?.unwrap_or(camera.default_width_px());
    let height = side("image height", args.height)?.unwrap_or(camera.default_height_px(width));
    // The limits of docs/limits.md, before any work: the image's sides,
    // the exposure (--ev100), the number of frames.
    sora::sky::check_image_size(width, height)?;
    args.colour.display_mapping()?;
    let frame_count = frame_count(&args)?;
    // Aerial perspective: its distances read and checked before any work.
    let depth = aerial_depth(&args, (width, height), (format, frame_count))?;
    // The polarisation outputs: polarised light, one frame, the right
    // formats, writable paths.
    let polarisation_outputs = args.stokes || args.dolp.is_some() || args.aop.is_some();
    let method = args.method;
    if polarisation_outputs {
        if args.sun.polarisation(method) == sora::Polarisation::Scalar {
            bail!(
                "--stokes, --dolp and --aop need polarised light: the fast method (the default) without --polarisation off"
            );
        }
        if frame_count > 1 {
            bail!(
                "--stokes, --dolp and --aop make one image, not a sequence (leave out --sun-elevation-to)"
            );
        }
        if args.stokes && format != OutputFormat::Exr {
            bail!(
                "--stokes writes the Stokes images as OpenEXR layers: give -o FILE.exr (PNG maps of the polarisation: --dolp FILE.png, --aop FILE.png)"
            );
        }
    }
    for (option, path) in [("--dolp", &args.dolp), ("--aop", &args.aop)] {
        if let Some(path) = path
            && OutputFormat::from_path(path)? != OutputFormat::Png
        {
            bail!(
                "{option} {}: the map is a PNG (give FILE.png)",
                path.display()
            );
        }
    }
    // Every file the run will write, checked together before any work
    // (`sora::output::output_targets`): a directory, a device, a read-only
    // file, a missing directory or two outputs on one file are refused now,
    // not after the render.
    let frame_paths: Vec<PathBuf> = if frame_count == 1 {
        vec![args.output.clone()]
    } else {
        (0..frame_count)
            .map(|frame| frame_path(&args.output, frame))
            .collect()
    };
    let frame_option = if frame_count == 1 {
        "-o"
    } else {
        "-o (a frame of the sequence)"
    };
    let mut outputs: Vec<(&Path, &str)> = frame_paths
        .iter()
        .map(|path| (path.as_path(), frame_option))
        .collect();
    for (option, path) in [("--dolp", &args.dolp), ("--aop", &args.aop)] {
        if let Some(path) = path {
            outputs.push((path, option));
        }
    }
    let mut targets = sora::output::output_targets(&outputs)?;
    let map_targets = {
        let mut maps = targets.split_off(frame_count).into_iter();
        (
            args.dolp.as_ref().and_then(|_| maps.next()),
            args.aop.as_ref().and_then(|_| maps.next()),
        )
    };
    // Image buffers bounded before any work (see `estimate`).
    let (encoded_bytes_per_pixel, format_name) = match (format, args.png_16_bit) {
        (OutputFormat::Png, false) => (6, "8-bit PNG"),
        (OutputFormat::Png, true) => (12, "16-bit PNG"),
        (OutputFormat::Exr, _) => (24, "OpenEXR"),
    };
    // The polarisation outputs' buffers beside the image's: the Stokes XYZ
    // (4 x 24 bytes), the EXR's four layers (4 x 12) and two maps (2 x 3).
    let encoded_bytes_per_pixel =
        encoded_bytes_per_pixel + if polarisation_outputs { 96 + 48 + 6 } else { 0 };
    estimate::check_render_memory(width, height, encoded_bytes_per_pixel, format_name)?;
    estimate::announce(estimate::render_estimate(
        width,
        height,
        frame_count,
        args.sun.wavelengths.len(),
        match args.method {
            sora::Method::Fast => estimate::RenderSpeed::Fast,
            _ => estimate::RenderSpeed::Reference,
        },
        encoded_bytes_per_pixel,
    ));
    let scattering = args.resolution.apply(args.scattering, method)?;
    let mut atmosphere = args.source.load()?;
    let started = Instant::now();
    // Colour alone: the gas terms are folded where colour allows.
    let (sky, sun) = args.sun.sky_for(
        &mut atmosphere,
        (scattering, method),
        Some(args.colour.observer),
    )?;
    if polarisation_outputs {
        crate::arguments::warn_non_polarising_species(&sky);
    }
    let to_xyz = SpectrumToXyz::new(sky.wavelengths(), args.colour.observer);
    let image = ImageSettings {
        camera,
        width,
        height,
        draw_sun_disc: !args.no_sun_disc,
    };
    if let Some(depth) = depth {
        let mut files = OutputFiles::new();
        render_aerial_perspective(
            &args,
            &sky,
            &image,
            &to_xyz,
            &depth,
            (&targets[0], &mut files),
        )?;
        files.commit()?;
        return Ok(());
    }
    // The frames: one, or a sequence of sun elevations at one azimuth.
    let elevations = frame_elevations(&args, sky.sun_position_deg().0)?;
    let mut exposure = None;
    // Every frame and map staged, then all renamed into place at the end:
    // a failure in frame 7 leaves none of the sequence.
    let mut files = OutputFiles::new();
    debug_assert_eq!(elevations.len(), targets.len());
    for (elevation, output) in elevations.iter().zip(&targets) {
        let frame_sky;
        let sky = if elevations.len() == 1 {
            &sky
        } else {
            frame_sky = sky.with_sun_deg(*elevation, sky.sun_position_deg().1)?;
            &frame_sky
        };
        let scale = render_frame(
            &args,
            (sky, &sun),
            &image,
            &to_xyz,
            (format, output, (&map_targets.0, &map_targets.1)),
            exposure,
            started,
            &mut files,
        )?;
        // A sequence keeps the first frame's automatic exposure (a fixed
        // one is the same for every frame anyway).
        let automatic = args.colour.ev100.is_none()
            && matches!(args.colour.exposure, sora::colour::Exposure::Auto { .. });
        if automatic && exposure.is_none() && elevations.len() > 1 {
            exposure = scale.map(sora::colour::Exposure::Fixed);
            if let Some(scale) = scale {
                eprintln!("sequence exposure: {scale:.6e} (frame 0's, fixed for every frame)");
            }
        }
    }
    files.commit()?;
    Ok(())
}

/// The distances of an aerial-perspective image (--distance-m, one for
/// every pixel, or --depth, one per pixel), checked: None without either.
fn aerial_depth(
    args: &RenderArgs,
    (width, height): (u32, u32),
    (format, frame_count): (OutputFormat, usize),
) -> anyhow::Result<Option<Vec<f64>>> {
    let depth = match (&args.distance_m, &args.depth) {
        (None, None) => return Ok(None),
        (Some(distance), _) => {
            if distance.is_nan() || *distance <= 0.0 {
                bail!(
                    "--distance-m {distance}: the distance to the points must be > 0 m (infinity: the whole sky)"
                );
            }
            vec![*distance]
        }
        (None, Some(path)) => read_depth(path, (width, height))?,
    };
    if format != OutputFormat::Exr {
        bail!(
            "--distance-m and --depth write the in-scattered light and its transmittance as OpenEXR layers: give -o FILE.exr"
        );
    }
    if frame_count > 1 || args.stokes || args.dolp.is_some() || args.aop.is_some() {
        bail!(
            "--distance-m and --depth make one image of the air's light, without --stokes, --dolp, --aop or a sequence"
        );
    }
    Ok(Some(depth))
}

/// The distances of a depth EXR (channel Z, or its only channel), m, one
/// per pixel of a `width` x `height` image, row-major, each > 0.
fn read_depth(path: &Path, (width, height): (u32, u32)) -> anyhow::Result<Vec<f64>> {
    let (w, h, depth) =
        sora::output::read_exr_channel(path, "Z").map_err(|e| anyhow::anyhow!("--depth {e}"))?;
    if (w, h) != (width as usize, height as usize) {
        bail!(
            "--depth {}: {w} x {h} pixels, the image is {width} x {height}",
            path.display()
        );
    }
    if let Some(k) = depth.iter().position(|d| d.is_nan() || *d <= 0.0) {
        bail!(
            "--depth {}: the distance at pixel ({}, {}) is {} m; distances must be > 0 m (infinity: the sky)",
            path.display(),
            k % width as usize,
            k / width as usize,
            depth[k]
        );
    }
    Ok(depth)
}

/// Writes the aerial-perspective image: the in-scattered light as the
/// main layer (in --units, RGB or XYZ as the sky's image would be) and
/// the transmittance as the layer "transmittance" (per channel: the XYZ or
/// RGB of the transmittance spectrum over that of a spectrum of ones).
fn render_aerial_perspective(
    args: &RenderArgs,
    sky: &sora::Sky,
    image: &ImageSettings,
    to_xyz: &SpectrumToXyz,
    depth: &[f64],
    (output, files): (&Path, &mut OutputFiles),
) -> anyhow::Result<()> {
    let started = Instant::now();
    let (radiance, transmittance) = sky.render_aerial_perspective_xyz(image, depth, to_xyz)?;
    let (w, h) = (image.width as usize, image.height as usize);
    let ones = sora::spectrum::SampledSpectrum::from_values(vec![1.0; sky.wavelengths().len()]);
    // The transmittance is a ratio: its channels without --units' scale.
    let (kind, ratio) = (exr_kind(args), SkyImageUnits::Radiance);
    let white = ratio.channels(kind, to_xyz.to_xyz(&ones)?);
    let main = exr_units(args).image(kind, w, h, radiance.iter().copied())?;
    let through = LinearImage::new(
        w,
        h,
        kind,
        transmittance
            .iter()
            .map(|c| {
                let v = ratio.channels(kind, *c);
                [0, 1, 2].map(|k| (v[k] / white[k]) as f32)
            })
            .collect(),
    )?;
    let attributes = vec![(
        "aerial_perspective".into(),
        "the main image is the light the air scatters into each view between the eye and the point at its distance; the layer transmittance is the segment's transmittance per channel (1 = all of the point's light); a scene pixel L is seen as L * transmittance + main (sora docs/aerial_perspective.md)".into(),
    )];
    stage_exr(
        args,
        sky,
        (output, files),
        (&main, &[("transmittance", &through)]),
        attributes,
    )?;
    eprintln!(
        "rendered the aerial perspective {w}x{h} in {:.3} s, wrote {}",
        started.elapsed().as_secs_f64(),
        output.display()
    );
    Ok(())
}

/// The camera of the options. The view direction and field of view
/// belong to the perspective camera only: given with another, they would be
/// silently ignored, so they are an error naming the option and the camera.
fn camera(args: &RenderArgs) -> anyhow::Result<Camera> {
    let perspective_only = [
        ("--view-elevation", args.view_elevation),
        ("--view-azimuth", args.view_azimuth),
        ("--fov-deg", args.fov_deg),
    ];
    let (name, whole_sky) = match args.camera {
        CameraKind::Fisheye => ("fisheye", Camera::Fisheye),
        CameraKind::Equirect => ("equirect", Camera::Equirectangular),
        CameraKind::Perspective => {
            return Ok(Camera::Perspective(PerspectiveCamera::new(
                args.view_elevation
                    .unwrap_or(PerspectiveCamera::DEFAULT_ELEVATION_DEG),
                args.view_azimuth
                    .unwrap_or(PerspectiveCamera::DEFAULT_AZIMUTH_DEG),
                args.fov_deg.unwrap_or(PerspectiveCamera::DEFAULT_FOV_DEG),
            )?));
        }
    };
    if let Some((option, _)) = perspective_only.iter().find(|(_, value)| value.is_some()) {
        bail!(
            "{option} applies to --camera perspective only; the {name} camera shows the whole sky (add --camera perspective, or leave {option} out)"
        );
    }
    Ok(whole_sky)
}

/// The most frames of one sequence (docs/limits.md).
const MAX_FRAMES: usize = 10_000;

/// How many frames the run writes: 1, or a sequence's (checked: at most
/// [`MAX_FRAMES`]), before any work (a --time's sun is computed here).
fn frame_count(args: &RenderArgs) -> anyhow::Result<usize> {
    let Some(last) = args.sun_elevation_to else {
        return Ok(1);
    };
    // The first frame's sun: --sun-elevation, or the sun's at --time.
    let first = args.sun.sun_deg()?.0;
    let step = args.sun_elevation_step;
    if !(step.is_finite() && step > 0.0) {
        bail!("--sun-elevation-step = {step} deg is out of range: allowed > 0 deg");
    }
    if !(-90.0..=90.0).contains(&last) {
        bail!("--sun-elevation-to = {last} deg is out of range: allowed -90..=90 deg");
    }
    let frames = ((last - first).abs() / step + 1e-9).floor() + 1.0;
    if frames.is_nan() || frames > MAX_FRAMES as f64 {
        bail!(
            "{frames} frames from {first} to {last} deg every {step} deg: at most {MAX_FRAMES} (a larger --sun-elevation-step)"
        );
    }
    Ok(frames as usize)
}

/// The sun elevations of the frames: `--sun-elevation` alone, or from it
/// to `--sun-elevation-to` every `--sun-elevation-step` degrees.
fn frame_elevations(args: &RenderArgs, first: f64) -> anyhow::Result<Vec<f64>> {
    let Some(last) = args.sun_elevation_to else {
        return Ok(vec![first]);
    };
    let step = args.sun_elevation_step;
    let count = frame_count(args)?;
    let direction = if last >= first { 1.0 } else { -1.0 };
    Ok((0..count)
        .map(|k| first + direction * step * k as f64)
        .collect())
}

/// `sky_007.png` for frame 7 of `sky.png`.
fn frame_path(output: &std::path::Path, frame: usize) -> PathBuf {
    let stem = output
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let extension = output
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    output.with_file_name(format!("{stem}_{frame:03}.{extension}"))
}

/// Renders `sky` and stages it in `files` for `output` (and the
/// polarisation maps for `maps`, the targets of --dolp and --aop); with
/// `exposure` (a sequence's) in place of the options'. Returns the PNG's
/// exposure scale.
#[allow(clippy::too_many_arguments)]
fn render_frame(
    args: &RenderArgs,
    (sky, sun): (&sora::Sky, &crate::arguments::SunUsed),
    image: &ImageSettings,
    to_xyz: &SpectrumToXyz,
    (format, output, (dolp, aop)): (
        OutputFormat,
        &std::path::Path,
        (&Option<PathBuf>, &Option<PathBuf>),
    ),
    exposure: Option<sora::colour::Exposure>,
    started: Instant,
    files: &mut OutputFiles,
) -> anyhow::Result<Option<f64>> {
    let (width, height) = (image.width, image.height);
    let frame_started = Instant::now();
    // Two phases, each shown for what it is: the tables (an estimate of
    // the time left would be a guess), then the rows.
    let spinner = crate::progress::spinner("{spinner} building tables ({elapsed})");
    sky.prepare_images()?;
    spinner.finish_and_clear();
    let bar = crate::progress::bar(
        height as u64,
        "{spinner} rendering [{bar:40}] {pos}/{len} rows, {eta} left",
    );
    let progress = |rows: usize| bar.set_position(rows as u64);
    // The Stokes images when asked for (S0 is the image), else the image.
    let (mut xyz, mut stokes) = if args.stokes || dolp.is_some() || aop.is_some() {
        let stokes = sky.render_stokes_xyz(image, to_xyz, &progress)?;
        (stokes.iter().map(|s| s[0]).collect(), stokes)
    } else {
        (sky.render_xyz(image, to_xyz, &progress)?, Vec::new())
    };
    bar.finish_and_clear();
    // Below the night floor the model has nothing to show (no airglow, no
    // stars), only numerical floors: such pixels are written black, and
    // their polarisation with them.
    let brightest_cd_m2 = sora::colour::apply_night_floor(&mut xyz);
    for (s, i) in stokes.iter_mut().zip(&xyz) {
        if i.y == 0.0 {
            *s = [sora::colour::Xyz::BLACK; 4];
        }
    }
    let (w, h) = (width as usize, height as usize);
    if let Some(path) = dolp {
        let degrees = polarisation_maps::degrees(&stokes);
        files.png(path, &polarisation_maps::degree_map(&degrees, w, h)?)?;
    }
    if let Some(path) = aop {
        let angles = polarisation_maps::angles_deg(&stokes);
        files.png(path, &polarisation_maps::angle_map(&angles, w, h)?)?;
    }
    let render_seconds = frame_started.elapsed().as_secs_f64();

    let mut png_scale = None;
    match format {
        OutputFormat::Png => {
            let mut mapping = args.colour.display_mapping()?;
            if let Some(exposure) = exposure {
                mapping.exposure = exposure;
            }
            if brightest_cd_m2 == 0.0
                && matches!(mapping.exposure, sora::colour::Exposure::Auto { .. })
            {
                eprintln!(
                    "night: the whole sky is darker than the night floor of {:e} cd/m^2 (the model has no airglow or stars), so auto exposure writes a black image; a fixed --exposure or --ev100 shows the same",
                    sora::colour::NIGHT_FLOOR_CD_M2
                );
            }
            png_scale = Some(mapping.exposure.scale_for_image(&xyz)?);
            if args.png_16_bit {
                let data = mapping.to_u16(&xyz)?.into_iter().flatten().collect();
                files.png(output, &DisplayImage::new(w, h, data)?)?;
            } else {
                let data = mapping.to_u8(&xyz)?.into_iter().flatten().collect();
                files.png(output, &DisplayImage::new(w, h, data)?)?;
            }
        }
        OutputFormat::Exr => {
            let (kind, units) = (exr_kind(args), exr_units(args));
            let main = units.image(kind, w, h, xyz.iter().copied())?;
            // --stokes: S0..S3 as layers (S0 the same as the main image).
            let layers = if args.stokes {
                (0..4)
                    .map(|c| units.image(kind, w, h, stokes.iter().map(|s| s[c])))
                    .collect::<sora::Result<Vec<_>>>()?
            } else {
                Vec::new()
            };
            let names = ["S0", "S1", "S2", "S3"];
            let layers: Vec<(&str, &LinearImage)> = names.into_iter().zip(&layers).collect();
            let attributes = sun
                .distance_au
                .map(|d| ("sun_distance_au".into(), d.to_string()))
                .into_iter()
                .chain([
                    ("sun_disc".into(), (!args.no_sun_disc).to_string()),
                    ("polarisation".into(), sky.polarisation().to_string()),
                ])
                .chain(args.stokes.then(|| {
                    (
                        "stokes".into(),
                        "layers S0..S3 are Stokes I, Q, U, V in the units above; Q and U referred to each pixel's meridian plane (Q > 0: vertical), the angle of polarisation 0.5 atan2(U, Q) from the vertical toward the observer's left (sora docs/polarisation.md)".into(),
                    )
                }))
                .collect();
            stage_exr(args, sky, (output, files), (&main, &layers), attributes)?;
        }
    }
    let total_seconds = started.elapsed().as_secs_f64();
    let pixels_per_second = (w * h) as f64 / render_seconds;
    let rate = if pixels_per_second >= 1e5 {
        format!("{:.2} Mpixel/s", pixels_per_second / 1e6)
    } else {
        format!("{pixels_per_second:.0} pixel/s")
    };
    let (sun_elevation, sun_azimuth) = sky.sun_position_deg();
    eprintln!(
        "rendered {width}x{height} ({} wavelengths, {} method, {} scattering, polarisation {}, sun at {sun_elevation:.4} deg elevation, {sun_azimuth:.4} deg azimuth{}) in {render_seconds:.3} s ({rate}), wrote {} in {total_seconds:.3} s total",
        args.sun.wavelengths.len(),
        args.method,
        args.scattering,
        sky.polarisation(),
        sun.summary(),
        output.display()
    );
    Ok(png_scale)
}

/// The EXR image's channels: X, Y, Z with --exr-xyz, linear sRGB
/// otherwise.
fn exr_kind(args: &RenderArgs) -> ChannelKind {
    if args.exr_xyz {
        ChannelKind::Xyz
    } else {
        ChannelKind::Rgb
    }
}

/// The EXR image's units, from --units.
fn exr_units(args: &RenderArgs) -> SkyImageUnits {
    match args.units {
        Units::Radiance => SkyImageUnits::Radiance,
        Units::Luminance => SkyImageUnits::Luminance,
    }
}

/// Stages a rendered EXR, the image `main` and its `layers`: 32-bit
/// floats, or half floats by --exr-half with --half-overflow's handling of
/// values beyond 65504; the units and whiteLuminance of --units and the
/// sun's position as attributes, then `attributes`.
fn stage_exr(
    args: &RenderArgs,
    sky: &sora::Sky,
    (output, files): (&Path, &mut OutputFiles),
    (main, layers): (&LinearImage, &[(&str, &LinearImage)]),
    attributes: Vec<(String, String)>,
) -> anyhow::Result<()> {
    let (sun_elevation, sun_azimuth) = sky.sun_position_deg();
    let mut options = ExrOptions::sky_image(exr_units(args), sun_elevation, sun_azimuth);
    options.sample_type = match (args.exr_half, args.half_overflow) {
        (false, _) => ExrSampleType::F32,
        (true, HalfOverflow::Error) => ExrSampleType::F16,
        (true, HalfOverflow::Clamp) => ExrSampleType::F16Clamped,
    };
    options.text_attributes.extend(attributes);
    let half_hint = if args.exr_half && args.half_overflow == HalfOverflow::Error {
        " (half floats end at 65504: --half-overflow clamp clamps, --no-sun-disc leaves the sun out, and without --exr-half 32-bit floats hold everything)"
    } else {
        ""
    };
    files
        .exr_with_layers(output, main, layers, options)
        .with_context(|| format!("writing {}{half_hint}", output.display()))?;
    Ok(())
}
