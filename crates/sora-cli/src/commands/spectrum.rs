//! `sora spectrum`: the sky's spectral radiance in one direction.

use std::io::Write;
use std::time::Instant;

use clap::{Args, ValueEnum};
use sora::colour::{RgbColourSpace, SpectrumToXyz};
use sora::geometry::direction_from_elevation_azimuth;
use sora::spectrum::SampledSpectrum;
use sora::transport::multiple_scattering::{MultipleScatteringField, MultipleScatteringSettings};
use sora::transport::{PathTracer, SunColumns};

use crate::arguments::{AtmosphereSource, Scattering, SunAndObserver};

/// Spectral radiance of the sky in one direction.
///
/// Prints CSV wavelength_nm,radiance_w_m2_sr_nm on stdout (the colour of the
/// spectrum, CIE XYZ and linear sRGB, goes to stderr), or everything as JSON
/// with --format json. Radiance is in W m^-2 sr^-1 nm^-1 for the
/// atmosphere's sun.
///
/// Methods: fast and reference compute single scattering (plus the sunlit
/// ground) and, with --scattering multiple (the default), add all higher
/// orders and the skylight reflected by the ground (a discrete-ordinate
/// field, synthesised exactly along the view); --scattering single gives
/// the paper's model. path-tracing is the Monte Carlo reference for all
/// orders of scattering and ground reflection, and adds a third column,
/// standard_error_w_m2_sr_nm, the standard error of each value (it shrinks
/// as 1/sqrt(--samples); on a terminal a progress bar shows the time left).
///
/// Example (the paper's Table 1 geometry):
///   sora spectrum --preset paper-earth --sun-elevation 36 --sun-azimuth 207 \
///       --view-elevation 17 --view-azimuth 347
///   sora spectrum --preset clear-sky-reference --sun-elevation 36 \
///       --view-elevation 17 --view-azimuth 347 --method path-tracing --samples 100000
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

    /// How single scattering is integrated: fast (Gauss-Legendre column
    /// march) or reference (the paper's uniform double march, slow), each
    /// plus the higher orders of --scattering; or path-tracing (Monte Carlo,
    /// all orders of scattering, with standard errors)
    #[arg(long, value_enum, default_value_t = Method::Fast)]
    method: Method,

    /// fast and reference: multiple (all orders of scattering and skylight
    /// reflected by the ground) or single (sunlight scattered once, the
    /// paper's model) [default: multiple]
    #[arg(long, value_enum)]
    scattering: Option<Scattering>,

    /// Path tracing: number of paths (the standard error falls as
    /// 1/sqrt(N)) [default: 10000]
    #[arg(long, value_name = "N")]
    samples: Option<u64>,

    /// Path tracing: random seed (the same seed gives the same result on any
    /// number of threads) [default: 1]
    #[arg(long, value_name = "S")]
    seed: Option<u64>,

    /// Output format
    #[arg(long, value_enum, default_value_t = Format::Csv)]
    format: Format,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Method {
    Fast,
    Reference,
    PathTracing,
}

/// Paths traced by default: about 1% standard error for a clear sky.
const DEFAULT_SAMPLES: u64 = 10_000;

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
    if args.method != Method::PathTracing && (args.samples.is_some() || args.seed.is_some()) {
        anyhow::bail!("--samples and --seed apply to --method path-tracing only");
    }
    if args.method == Method::PathTracing && args.scattering.is_some() {
        anyhow::bail!(
            "--scattering applies to --method fast and reference only (path tracing has all orders)"
        );
    }
    let samples = args.samples.unwrap_or(DEFAULT_SAMPLES);
    if samples < 2 {
        anyhow::bail!(
            "--samples = {samples} is out of range: at least 2 (a standard error needs two paths)"
        );
    }
    let seed = args.seed.unwrap_or(1);
    let mut atmosphere = args.source.load()?;
    let sky = args.sun.sky(&mut atmosphere)?;
    let grid = args.sun.wavelengths;
    let view = direction_from_elevation_azimuth(args.view_elevation, args.view_azimuth);
    let (mut radiance, standard_error) = match args.method {
        Method::Fast => {
            let mut scratch = sky.scratch();
            let mut radiance = SampledSpectrum::zeros(grid.len());
            sky.compute_radiance(view, SunColumns::Exact, &mut scratch, &mut radiance);
            (radiance, None)
        }
        Method::Reference => (sky.compute_radiance_reference(view, 4000, 800), None),
        Method::PathTracing => {
            let started = Instant::now();
            let bar = progress_bar(samples);
            let traced = PathTracer::new(&sky).compute_radiance_with_progress(
                view,
                samples,
                seed,
                &|done| bar.set_position(done),
            )?;
            bar.finish_and_clear();
            let seconds = started.elapsed().as_secs_f64();
            eprintln!(
                "path tracing: {samples} paths (seed {seed}) in {seconds:.3} s ({:.0} paths/s); largest relative standard error {:.3}%",
                samples as f64 / seconds,
                100.0 * traced.total.worst_relative_standard_error()
            );
            (traced.total.mean, Some(traced.total.standard_error))
        }
    };
    let scattering = match args.method {
        Method::PathTracing => None,
        _ => Some(args.scattering.unwrap_or(Scattering::Multiple)),
    };
    if scattering == Some(Scattering::Multiple) {
        let field = MultipleScatteringField::compute_for_view(
            &sky,
            view,
            MultipleScatteringSettings::default(),
        );
        let mut multiple = vec![0.0; grid.len()];
        field.compute_radiance(view, SunColumns::Exact, &mut field.scratch(), &mut multiple);
        for (r, m) in radiance.values_mut().iter_mut().zip(&multiple) {
            *r += m;
        }
    }
    let xyz =
        SpectrumToXyz::new(&grid, sora::colour::Observer::Cie1931TwoDegree).to_xyz(&radiance)?;
    let rgb = RgbColourSpace::Srgb.linear_rgb_from_xyz(xyz);
    let mut out = std::io::stdout().lock();
    match args.format {
        Format::Csv => {
            match &standard_error {
                None => {
                    writeln!(out, "wavelength_nm,radiance_w_m2_sr_nm")?;
                    for (wavelength, value) in grid.wavelengths_nm().zip(radiance.values()) {
                        writeln!(out, "{wavelength},{value:.9e}")?;
                    }
                }
                Some(errors) => {
                    writeln!(
                        out,
                        "wavelength_nm,radiance_w_m2_sr_nm,standard_error_w_m2_sr_nm"
                    )?;
                    for ((wavelength, value), error) in grid
                        .wavelengths_nm()
                        .zip(radiance.values())
                        .zip(errors.values())
                    {
                        writeln!(out, "{wavelength},{value:.9e},{error:.3e}")?;
                    }
                }
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
            let errors = match &standard_error {
                None => String::new(),
                Some(errors) => {
                    let errors: Vec<String> =
                        errors.values().iter().map(|e| format!("{e:.3e}")).collect();
                    format!(
                        ", \"standard_error_w_m2_sr_nm\": [{}], \"samples\": {samples}, \"seed\": {seed}",
                        errors.join(", ")
                    )
                }
            };
            writeln!(
                out,
                "{{\"wavelength_nm\": [{}], \"radiance_w_m2_sr_nm\": [{}]{errors}, \"xyz\": [{:.9e}, {:.9e}, {:.9e}], \"linear_srgb\": [{:.9e}, {:.9e}, {:.9e}]}}",
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

/// A progress bar on stderr when it is a terminal, hidden otherwise.
fn progress_bar(paths: u64) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(paths),
        indicatif::ProgressDrawTarget::stderr(),
    );
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{spinner} path tracing [{bar:40}] {pos}/{len} paths, {eta} left",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
