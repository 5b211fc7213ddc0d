//! `sora spectrum`: the sky's spectral radiance in one direction.

use std::io::Write;

use clap::{Args, ValueEnum};
use sora::colour::{RgbColourSpace, SpectrumToXyz};
use sora::geometry::direction_from_elevation_azimuth;
use sora::spectrum::SampledSpectrum;
use sora::transport::SunColumns;

use crate::arguments::{AtmosphereSource, SunAndObserver};

/// Spectral radiance of the sky in one direction (single scattering).
///
/// Prints CSV wavelength_nm,radiance_w_m2_sr_nm on stdout (the colour of the
/// spectrum, CIE XYZ and linear sRGB, goes to stderr), or everything as JSON
/// with --format json. Radiance is in W m^-2 sr^-1 nm^-1 for the
/// atmosphere's sun.
///
/// Example (the paper's Table 1 geometry):
///   sora spectrum --preset paper-earth --sun-elevation 36 --sun-azimuth 207 \
///       --view-elevation 17 --view-azimuth 347
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct SpectrumArgs {
    #[command(flatten)]
    source: AtmosphereSource,

    #[command(flatten)]
    sun: SunAndObserver,

    /// View elevation above the horizon, degrees (-90..90)
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    view_elevation: f64,

    /// View azimuth clockwise from north, degrees
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    view_azimuth: f64,

    /// fast (Gauss-Legendre column march) or reference (the paper's uniform
    /// double march, slow)
    #[arg(long, value_enum, default_value_t = Method::Fast)]
    method: Method,

    /// Output format
    #[arg(long, value_enum, default_value_t = Format::Csv)]
    format: Format,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Method {
    Fast,
    Reference,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Format {
    Csv,
    Json,
}

pub fn run(args: SpectrumArgs) -> anyhow::Result<()> {
    if !(-90.0..=90.0).contains(&args.view_elevation) {
        anyhow::bail!(
            "--view-elevation = {} deg is out of range: allowed -90..=90 deg",
            args.view_elevation
        );
    }
    if !args.view_azimuth.is_finite() {
        anyhow::bail!(
            "--view-azimuth = {} deg is not a finite angle",
            args.view_azimuth
        );
    }
    let mut atmosphere = args.source.load()?;
    let sky = args.sun.sky(&mut atmosphere)?;
    let grid = args.sun.wavelengths;
    let view = direction_from_elevation_azimuth(args.view_elevation, args.view_azimuth);
    let radiance = match args.method {
        Method::Fast => {
            let mut scratch = sky.scratch();
            let mut radiance = SampledSpectrum::zeros(grid.len());
            sky.compute_radiance(view, SunColumns::Exact, &mut scratch, &mut radiance);
            radiance
        }
        Method::Reference => sky.compute_radiance_reference(view, 4000, 800),
    };
    let xyz =
        SpectrumToXyz::new(&grid, sora::colour::Observer::Cie1931TwoDegree).to_xyz(&radiance)?;
    let rgb = RgbColourSpace::Srgb.linear_rgb_from_xyz(xyz);
    let mut out = std::io::stdout().lock();
    match args.format {
        Format::Csv => {
            writeln!(out, "wavelength_nm,radiance_w_m2_sr_nm")?;
            for (wavelength, value) in grid.wavelengths_nm().zip(radiance.values()) {
                writeln!(out, "{wavelength},{value:.9e}")?;
            }
            eprintln!(
                "XYZ {:.6e} {:.6e} {:.6e}; linear sRGB {:.6e} {:.6e} {:.6e}",
                xyz.x, xyz.y, xyz.z, rgb.r, rgb.g, rgb.b
            );
        }
        Format::Json => {
            let values: Vec<String> = radiance
                .values()
                .iter()
                .map(|v| format!("{v:.9e}"))
                .collect();
            let wavelengths: Vec<String> = grid.wavelengths_nm().map(|w| format!("{w}")).collect();
            writeln!(
                out,
                "{{\"wavelength_nm\": [{}], \"radiance_w_m2_sr_nm\": [{}], \"xyz\": [{:.9e}, {:.9e}, {:.9e}], \"linear_srgb\": [{:.9e}, {:.9e}, {:.9e}]}}",
                wavelengths.join(", "),
                values.join(", "),
                xyz.x,
                xyz.y,
                xyz.z,
                rgb.r,
                rgb.g,
                rgb.b
            )?;
        }
    }
    Ok(())
}
