//! `sora irradiance`: the light on a horizontal (and a tilted) plane.

use std::io::Write;

use clap::{Args, ValueEnum};
use serde::Serialize;
use sora::spectrum::SampledSpectrum;
use sora::{Irradiance, Plane};

use crate::arguments::{
    AtmosphereSource, FilterOptions, MethodOptions, Resolution, SunAndObserver,
};
use crate::json::Members;

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
/// --format csv (default) prints one row per wavelength
/// (wavelength_nm,direct_normal_irradiance_w_m2_nm,... with units in every
/// name) and the broadband values on stderr; json prints both; table prints
/// the broadband values for people. Every broadband value integrates the
/// grid (each sample its step-wide band) and says so: the band in nm, and
/// the sun's own irradiance on that band and in its whole table (ASTM
/// E490: 1366.1 W m^-2 over 119.5 nm to 1 mm), so that a value is never
/// read as more of the spectrum than it holds.
///
/// --broadband: the grid becomes 300:2500:10 nm
/// (instead of --wavelengths; its samples' bands span 295-2505 nm, 95.8 %
/// of the ASTM E490 sun's energy). Left out, and named in the output: the
/// 1.1 % below 300 nm (ozone's Hartley band absorbs nearly all of it) and
/// the 3.3 % beyond 2500 nm (water and CO2 bands), which sora does not
/// solve (docs/spectrum.md).
///
/// With banded gases (an atmosphere file's [gases]) every value is the
/// library's sum of five solves, one per k-distribution term, weighted
/// (five times the time at the samples from the first a band absorbs to
/// the last; one solve elsewhere).
///
/// --method reference marches each of the 4,608 directions of the diffuse
/// integral: at its 1000 x 250 steps that is about 80 s a wavelength, past
/// the limit of docs/limits.md (1e8 steps), so it is a one-line error
/// before any work; the fast method (the default) gives the same integral
/// within 1e-3, path tracing an independent estimate with its error.
///
/// With --filter (repeatable; docs/filters.md) each row is an instrument
/// channel instead of a wavelength: filter,centre_nm and each quantity's
/// response-weighted mean over the channel (no broadband values).
///
/// Example:
///   sora irradiance --preset earth-clear --sun-elevation 30 --filter cimel
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
    /// degrees (read modulo 360)
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

    #[command(flatten)]
    filters: FilterOptions,

    /// Broadband over 300:2500:10 nm (95.8 % of the ASTM E490 sun; below
    /// 300 nm ozone lets almost nothing reach the ground), instead of
    /// --wavelengths
    #[arg(long, conflicts_with_all = ["wavelengths", "filter"])]
    broadband: bool,

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
struct Quantity {
    /// The name without its unit suffix, e.g. `global_horizontal_irradiance`.
    name: String,
    spectrum: SampledSpectrum,
    /// Irradiance (W m^-2 nm^-1, with broadband and lux) or a ratio.
    irradiance: bool,
}

/// The output's quantities of `sky`: horizontal, then on `tilted`.
fn quantities(sky: &sora::Sky, tilted: Option<Plane>) -> anyhow::Result<Vec<Quantity>> {
    let on_plane = |plane: Plane| -> anyhow::Result<Irradiance> { Ok(sky.irradiance(plane)?) };
    let horizontal = on_plane(Plane::HORIZONTAL)?;
    let tilted = tilted.map(on_plane).transpose()?;
    let quantity = |name: &str, spectrum: &SampledSpectrum, irradiance| Quantity {
        name: name.to_string(),
        spectrum: spectrum.clone(),
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
    Ok(quantities)
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
    let filters = args.filters.filters()?;
    let sun_options = if args.broadband {
        args.sun.with_wavelengths(broadband_grid())
    } else {
        args.sun.clone()
    };
    let atmosphere = args.source.load()?;
    // Banded gases: the sky sums its k-distribution terms.
    let solves = sora::atmosphere::gas_bands::solves_per_wavelength(&atmosphere);
    let sky = |sun: &SunAndObserver| sun.sky(&mut atmosphere.clone(), scattering, method);
    let planes = 1 + usize::from(tilted.is_some());
    let announce = |grid: &sora::spectrum::WavelengthGrid| {
        if let sora::Method::PathTracing { samples, .. } = method {
            crate::estimate::announce(crate::estimate::path_tracing_estimate(
                samples * solves as u64,
                planes,
                grid.len(),
            ));
        }
    };
    if !filters.is_empty() {
        // Per filter: the sky on its grid, each quantity's response-weighted
        // mean (a standard error's: a bound, however the wavelengths'
        // errors correlate).
        let mut rows: Vec<Vec<f64>> = Vec::new();
        let mut names = Vec::new();
        let mut first_sky = None;
        for filter in &filters {
            let grid = filter
                .grid()
                .map_err(|e| anyhow::anyhow!("--filter {}: {e}", filter.name()))?;
            let (sky, sun) = sky(&args.sun.with_wavelengths(grid))?;
            announce(&grid);
            let quantities = quantities(&sky, tilted)?;
            names = quantities
                .iter()
                .map(|q| (q.name.clone(), q.irradiance))
                .collect();
            rows.push(
                quantities
                    .iter()
                    .map(|q| filter.weighted_mean(&grid, &q.spectrum))
                    .collect::<sora::Result<Vec<f64>>>()?,
            );
            first_sky.get_or_insert((sky.sun_position_deg(), sun));
        }
        let ((sun_elevation_deg, sun_azimuth_deg), sun) = first_sky.expect("a filter");
        let quantities: Vec<Quantity> = names
            .iter()
            .enumerate()
            .map(|(k, (name, irradiance))| Quantity {
                name: name.clone(),
                spectrum: SampledSpectrum::from_values(rows.iter().map(|r| r[k]).collect()),
                irradiance: *irradiance,
            })
            .collect();
        let labels = filters
            .iter()
            .map(|f| Ok((f.name().to_string(), f.centre_nm()?)))
            .collect::<sora::Result<Vec<_>>>()?;
        return write_filtered(
            args.format,
            &quantities,
            &labels,
            (sun_elevation_deg, sun_azimuth_deg, sun),
        );
    }
    let mut moved = atmosphere.clone();
    let (sky, sun) = sun_options.sky(&mut moved, scattering, method)?;
    let grid = *sky.wavelengths();
    // The sun's own irradiance on the grid and in its whole table.
    let sun_in_band_w_m2 = moved.sun.grid_irradiance_w_m2(&grid)?;
    let sun_table = moved.sun.table_irradiance_w_m2();
    let band = format!("{}-{} nm", grid.start_nm(), grid.stop_nm());
    announce(&grid);
    let quantities = quantities(&sky, tilted)?;
    // Broadband: W m^-2 and lux of every irradiance (not of standard
    // errors, which do not add linearly).
    let mut broadband = Vec::new();
    for q in quantities
        .iter()
        .filter(|q| q.irradiance && !q.name.ends_with("standard_error"))
    {
        let watts = Irradiance::broadband_w_m2(&q.spectrum, &grid);
        let lux = Irradiance::illuminance_lx(&q.spectrum, &grid)?;
        broadband.push((q.name.clone(), watts, lux));
    }
    let (sun_elevation_deg, sun_azimuth_deg) = sky.sun_position_deg();
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    match args.format {
        Format::Csv => {
            let labels: Vec<String> = grid.wavelengths_nm().map(|w| w.to_string()).collect();
            write_csv(&mut out, "wavelength_nm", &labels, &quantities)?;
            for (name, watts, lux) in &broadband {
                let illuminance = name.replace("irradiance", "illuminance");
                eprintln!("{name}_w_m2 {watts:.6e}; {illuminance}_lx {lux:.6e}; over {band}");
            }
            eprintln!("{}", sun_share(sun_in_band_w_m2, sun_table, &band));
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
            writeln!(out, "{}", sun_share(sun_in_band_w_m2, sun_table, &band))?;
        }
        Format::Json => {
            let mut broadband_members = Vec::new();
            for (name, watts, lux) in &broadband {
                let illuminance = name.replace("irradiance", "illuminance");
                broadband_members.push((format!("{name}_w_m2"), *watts));
                broadband_members.push((format!("{illuminance}_lx"), *lux));
            }
            let wavelengths: Vec<f64> = grid.wavelengths_nm().collect();
            out.write_all(
                crate::json::to_string(&IrradianceJson {
                    sun: crate::json::Sun::new(sun_elevation_deg, sun_azimuth_deg, &sun),
                    wavelength_nm: Some(&wavelengths),
                    filter: None,
                    centre_nm: None,
                    quantities: quantity_members(&quantities),
                    broadband_range_nm: Some([grid.start_nm(), grid.stop_nm()]),
                    extraterrestrial_in_band_w_m2: Some(sun_in_band_w_m2),
                    sun_table_range_nm: sun_table.map(|((lo, hi), _)| [lo, hi]),
                    sun_table_irradiance_w_m2: sun_table.map(|(_, total)| total),
                    broadband: Members(broadband_members),
                })?
                .as_bytes(),
            )?;
        }
    }
    out.flush()?;
    Ok(())
}

/// Where the grid of --broadband starts, nm. Grids may start at 280 nm,
/// but the 280 and 290 nm samples add 4e-6 W m^-2 to the global
/// irradiance with the sun overhead (earth-clear-summer, 300 DU: ozone's
/// Hartley band), so the broadband values start at 300 nm, the band their
/// comparison with pvlib's clear-sky models was made on.
const BROADBAND_START_NM: f64 = 300.0;

/// The grid of --broadband: 300 nm to the longest wavelength sora solves,
/// every 10 nm.
fn broadband_grid() -> sora::spectrum::WavelengthGrid {
    use sora::spectrum::MAX_WAVELENGTH_NM;
    sora::spectrum::WavelengthGrid::new(BROADBAND_START_NM, MAX_WAVELENGTH_NM, 10.0)
        .expect("the broadband grid is valid")
}

/// One line for people: the sun's irradiance on the broadband values'
/// band and, for a tabulated sun, in its whole table.
fn sun_share(in_band_w_m2: f64, table: Option<((f64, f64), f64)>, band: &str) -> String {
    let mut line = format!("extraterrestrial irradiance over {band}: {in_band_w_m2:.4} W m^-2");
    if let Some(((lo, hi), total)) = table {
        line += &format!(
            " ({:.2} % of the sun's {total:.1} W m^-2 over {lo}-{hi} nm)",
            100.0 * in_band_w_m2 / total
        );
    }
    line
}

/// Writes the per-filter quantities: one row per filter (`name`,
/// `centre_nm`), no broadband values.
fn write_filtered(
    format: Format,
    quantities: &[Quantity],
    labels: &[(String, f64)],
    (sun_elevation_deg, sun_azimuth_deg, sun): (f64, f64, crate::arguments::SunUsed),
) -> anyhow::Result<()> {
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    match format {
        Format::Csv => {
            let labels: Vec<String> = labels
                .iter()
                .map(|(name, centre)| format!("{name},{centre:.4}"))
                .collect();
            write_csv(&mut out, "filter,centre_nm", &labels, quantities)?;
        }
        Format::Table => {
            writeln!(
                out,
                "sun at {sun_elevation_deg:.4} deg elevation, {sun_azimuth_deg:.4} deg azimuth{}; W m^-2 nm^-1 through each filter",
                sun.summary()
            )?;
            for (i, (name, centre)) in labels.iter().enumerate() {
                writeln!(out, "{name} ({centre:.2} nm)")?;
                for q in quantities.iter().filter(|q| q.irradiance) {
                    writeln!(
                        out,
                        "  {:<34} {:>12.6}",
                        q.name.replace('_', " "),
                        q.spectrum[i]
                    )?;
                }
            }
        }
        Format::Json => {
            let names: Vec<&str> = labels.iter().map(|(name, _)| name.as_str()).collect();
            let centres: Vec<f64> = labels.iter().map(|(_, centre)| *centre).collect();
            out.write_all(
                crate::json::to_string(&IrradianceJson {
                    sun: crate::json::Sun::new(sun_elevation_deg, sun_azimuth_deg, &sun),
                    wavelength_nm: None,
                    filter: Some(&names),
                    centre_nm: Some(&centres),
                    quantities: quantity_members(quantities),
                    broadband_range_nm: None,
                    extraterrestrial_in_band_w_m2: None,
                    sun_table_range_nm: None,
                    sun_table_irradiance_w_m2: None,
                    broadband: Members(Vec::new()),
                })?
                .as_bytes(),
            )?;
        }
    }
    out.flush()?;
    Ok(())
}

/// A quantity's name with its unit suffix.
fn unit_name(q: &Quantity) -> String {
    format!("{}{}", q.name, if q.irradiance { "_w_m2_nm" } else { "" })
}

/// The CSV: `axis` (the row label columns) and each quantity, one row per
/// label.
fn write_csv(
    out: &mut impl Write,
    axis: &str,
    labels: &[String],
    quantities: &[Quantity],
) -> anyhow::Result<()> {
    let header: Vec<String> = quantities.iter().map(unit_name).collect();
    writeln!(out, "{axis},{}", header.join(","))?;
    for (i, label) in labels.iter().enumerate() {
        let row: Vec<String> = quantities
            .iter()
            .map(|q| format!("{:.9e}", q.spectrum[i]))
            .collect();
        writeln!(out, "{label},{}", row.join(","))?;
    }
    Ok(())
}

/// `sora irradiance --format json` (docs/json.md): the sun, the rows'
/// axis (wavelengths or filters), each quantity's list and, per
/// wavelength, the broadband values.
#[derive(Serialize)]
struct IrradianceJson<'a> {
    #[serde(flatten)]
    sun: crate::json::Sun,
    #[serde(skip_serializing_if = "Option::is_none")]
    wavelength_nm: Option<&'a [f64]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    filter: Option<&'a [&'a str]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    centre_nm: Option<&'a [f64]>,
    /// Each quantity under its name with its unit ([`unit_name`]).
    #[serde(flatten)]
    quantities: Members<&'a [f64]>,
    /// The band every broadband value integrates.
    #[serde(skip_serializing_if = "Option::is_none")]
    broadband_range_nm: Option<[f64; 2]>,
    /// The sun's top-of-atmosphere irradiance on that band, W m^-2.
    #[serde(skip_serializing_if = "Option::is_none")]
    extraterrestrial_in_band_w_m2: Option<f64>,
    /// The whole solar table's range (not for a flat sun).
    #[serde(skip_serializing_if = "Option::is_none")]
    sun_table_range_nm: Option<[f64; 2]>,
    /// The sun's irradiance over its whole table, W m^-2.
    #[serde(skip_serializing_if = "Option::is_none")]
    sun_table_irradiance_w_m2: Option<f64>,
    /// `NAME_w_m2` and `NAME_lx` (illuminance) of every irradiance.
    #[serde(flatten)]
    broadband: Members<f64>,
}

/// Each quantity's values under its name with its unit.
fn quantity_members(quantities: &[Quantity]) -> Members<&[f64]> {
    Members(
        quantities
            .iter()
            .map(|q| (unit_name(q), q.spectrum.values()))
            .collect(),
    )
}
