//! `sora irradiance`: the light on a horizontal (and a tilted) plane.

use std::io::Write;

use clap::{Args, ValueEnum};
use sora::spectrum::SampledSpectrum;
use sora::{Irradiance, Plane};

use crate::arguments::{AtmosphereSource, MethodOptions, Resolution, SunAndObserver};

/// Irradiance on a horizontal plane (and on a tilted one): direct normal,
/// direct, diffuse and global, per wavelength and broadband.
///
/// The direct beam is the sun's irradiance times the transmittance toward
/// it; the diffuse irradiance is the sky's radiance (all orders of
/// scattering by default) integrated over the plane's hemisphere, weighted
/// by the cosine (Gauss-Legendre in the cosine, 48 nodes, times 96
/// azimuths); global = direct + diffuse. Spectral values in W m^-2 nm^-1;
/// broadband in W m^-2 and, for illuminance, lux (CIE 1931, 683 lm/W).
///
/// With banded gases (an atmosphere file's [gases]) every value is the sum
/// of five solves, one per k-distribution term, weighted (five times the
/// time).
///
/// --method reference marches each of the 4,608 directions of the diffuse
/// integral: at its 1000 x 250 steps that is about 80 s a wavelength, past
/// the limit of docs/limits.md (1e8 steps), so it is a one-line error
/// before any work; the fast method (the default) gives the same integral
/// within 1e-3, path tracing an independent estimate with its error.
///
/// --format csv (default) prints one row per wavelength
/// (wavelength_nm,direct_normal_irradiance_w_m2_nm,... with units in every
/// name) and the broadband values on stderr; json prints both; table prints
/// the broadband values for people.
///
/// Example:
///   sora irradiance --preset earth-clear --sun-elevation 30 --format table
///   sora irradiance --preset earth-clear --sun-elevation 30 --tilt-deg 35 --plane-azimuth-deg 180
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct IrradianceArgs {
    #[command(flatten)]
    source: AtmosphereSource,

    #[command(flatten)]
    sun: SunAndObserver,

    /// Also a plane tilted this far from horizontal, degrees (0..180; 90:
    /// vertical)
    #[arg(long, value_name = "DEG")]
    tilt_deg: Option<f64>,

    /// The tilted plane leans toward this azimuth, clockwise from north,
    /// degrees
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 180.0,
        requires = "tilt_deg",
        allow_hyphen_values = true
    )]
    plane_azimuth_deg: f64,

    #[command(flatten)]
    method: MethodOptions,

    #[command(flatten)]
    resolution: Resolution,

    /// Output format
    #[arg(long, value_enum, default_value_t = Format::Csv)]
    format: Format,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Format {
    Csv,
    Json,
    Table,
}

/// One named spectral quantity of the output.
struct Quantity<'a> {
    /// The name without its unit suffix, e.g. `global_horizontal_irradiance`.
    name: String,
    spectrum: &'a SampledSpectrum,
    /// Irradiance (W m^-2 nm^-1, with broadband and lux) or a ratio.
    irradiance: bool,
}

pub fn run(args: IrradianceArgs) -> anyhow::Result<()> {
    let tilted = args
        .tilt_deg
        .map(|tilt| Plane::new(tilt, args.plane_azimuth_deg))
        .transpose()?;
    let (scattering, method) = args
        .method
        .resolve(100_000, sora::Method::REFERENCE_DEFAULT)?;
    let scattering = args.resolution.apply(scattering, method)?;
    // The reference march's work, before loading anything (docs/limits.md).
    sora::sky::check_irradiance_work(method)?;
    let atmosphere = args.source.load()?;
    // Banded gases: one sky per k-distribution term, summed with the
    // terms' weights (one sky, weight 1, without them).
    let mut skies = Vec::new();
    for (weight, mut at_term) in sora::atmosphere::gas_bands::k_distribution_terms(&atmosphere) {
        skies.push((weight, args.sun.sky(&mut at_term, scattering, method)?));
    }
    let (sky, sun) = &skies[0].1;
    let grid = *sky.wavelengths();
    if let sora::Method::PathTracing { samples, .. } = method {
        let planes = 1 + usize::from(tilted.is_some());
        crate::estimate::announce(crate::estimate::path_tracing_estimate(
            samples * skies.len() as u64,
            planes,
            grid.len(),
        ));
    }
    let on_plane = |plane: Plane| -> anyhow::Result<Irradiance> {
        let parts = skies
            .iter()
            .map(|(weight, (sky, _))| Ok((*weight, sky.irradiance(plane)?)))
            .collect::<anyhow::Result<Vec<_>>>()?;
        Ok(Irradiance::weighted_sum(&parts))
    };
    let horizontal = on_plane(Plane::HORIZONTAL)?;
    let tilted = tilted.map(on_plane).transpose()?;
    let quantity = |name: &str, spectrum, irradiance| Quantity {
        name: name.to_string(),
        spectrum,
        irradiance,
    };
    let mut quantities = vec![
        quantity(
            "direct_normal_irradiance",
            &horizontal.direct_normal_w_m2_nm,
            true,
        ),
        quantity(
            "direct_beam_transmittance",
            &horizontal.direct_beam_transmittance,
            false,
        ),
        quantity(
            "direct_horizontal_irradiance",
            &horizontal.direct_w_m2_nm,
            true,
        ),
        quantity(
            "diffuse_horizontal_irradiance",
            &horizontal.diffuse_w_m2_nm,
            true,
        ),
        quantity(
            "global_horizontal_irradiance",
            &horizontal.global_w_m2_nm,
            true,
        ),
    ];
    if let Some(errors) = &horizontal.diffuse_standard_error_w_m2_nm {
        quantities.push(quantity("diffuse_horizontal_standard_error", errors, true));
    }
    if let Some(tilted) = &tilted {
        quantities.push(quantity(
            "direct_tilted_irradiance",
            &tilted.direct_w_m2_nm,
            true,
        ));
        quantities.push(quantity(
            "diffuse_tilted_irradiance",
            &tilted.diffuse_w_m2_nm,
            true,
        ));
        quantities.push(quantity(
            "global_tilted_irradiance",
            &tilted.global_w_m2_nm,
            true,
        ));
        if let Some(errors) = &tilted.diffuse_standard_error_w_m2_nm {
            quantities.push(quantity("diffuse_tilted_standard_error", errors, true));
        }
    }
    // Broadband: W m^-2 and lux of every irradiance (not of standard
    // errors, which do not add linearly).
    let mut broadband = Vec::new();
    for q in quantities
        .iter()
        .filter(|q| q.irradiance && !q.name.ends_with("standard_error"))
    {
        let watts = Irradiance::broadband_w_m2(q.spectrum, &grid);
        let lux = Irradiance::illuminance_lx(q.spectrum, &grid)?;
        broadband.push((q.name.clone(), watts, lux));
    }
    let (sun_elevation_deg, sun_azimuth_deg) = sky.sun_position_deg();
    let unit = |q: &Quantity| if q.irradiance { "_w_m2_nm" } else { "" };
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    match args.format {
        Format::Csv => {
            let header: Vec<String> = quantities
                .iter()
                .map(|q| format!("{}{}", q.name, unit(q)))
                .collect();
            writeln!(out, "wavelength_nm,{}", header.join(","))?;
            for (i, wavelength) in grid.wavelengths_nm().enumerate() {
                let row: Vec<String> = quantities
                    .iter()
                    .map(|q| format!("{:.9e}", q.spectrum[i]))
                    .collect();
                writeln!(out, "{wavelength},{}", row.join(","))?;
            }
            for (name, watts, lux) in &broadband {
                let illuminance = name.replace("irradiance", "illuminance");
                eprintln!("{name}_w_m2 {watts:.6e}; {illuminance}_lx {lux:.6e}");
            }
        }
        Format::Table => {
            writeln!(
                out,
                "sun at {sun_elevation_deg:.4} deg elevation, {sun_azimuth_deg:.4} deg azimuth{}; {} to {} nm",
                sun.summary(),
                grid.start_nm(),
                grid.stop_nm()
            )?;
            for (name, watts, lux) in &broadband {
                writeln!(
                    out,
                    "{:<30} {watts:>12.4} W m^-2 {lux:>14.1} lx",
                    name.replace('_', " ")
                )?;
            }
        }
        Format::Json => {
            let list = |values: &[f64]| {
                values
                    .iter()
                    .map(|v| format!("{v:.9e}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let mut members = vec![
                format!("\"sun_elevation_deg\": {sun_elevation_deg}"),
                format!(
                    "\"sun_azimuth_deg\": {sun_azimuth_deg}{}",
                    sun.json_members()
                ),
                format!(
                    "\"wavelength_nm\": [{}]",
                    grid.wavelengths_nm()
                        .map(|w| w.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ];
            for q in &quantities {
                members.push(format!(
                    "\"{}{}\": [{}]",
                    q.name,
                    unit(q),
                    list(q.spectrum.values())
                ));
            }
            // The band every broadband value integrates.
            members.push(format!(
                "\"broadband_range_nm\": [{}, {}]",
                grid.start_nm(),
                grid.stop_nm()
            ));
            for (name, watts, lux) in &broadband {
                let illuminance = name.replace("irradiance", "illuminance");
                members.push(format!("\"{name}_w_m2\": {watts:.9e}"));
                members.push(format!("\"{illuminance}_lx\": {lux:.9e}"));
            }
            writeln!(out, "{{{}}}", members.join(", "))?;
        }
    }
    out.flush()?;
    Ok(())
}
