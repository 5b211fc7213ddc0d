//! `sora retrieve`: the aerosol from measured sky radiances (issue 16).

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use serde::Serialize;
use sora::inversion::{
    AeronetScan, Estimate, IndexSpectrum, Measurements, PARAMETER_NAMES, Retrieval,
    RetrievalSettings, SkyGeometry, SpectralOptics, attach_nearest_optical_depths,
    parse_aeronet_aod, parse_aeronet_sky, parse_normalised_spectrum_csv, parse_optical_depth_csv,
    parse_sky_radiance_csv, retrieve,
};

use crate::arguments::AtmosphereSource;
use crate::json::Members;

/// Retrieve the aerosol from measured sky radiances: its optical depth,
/// size distribution and refractive index, and from them its single-
/// scattering albedo, asymmetry parameter, Angstrom exponent and effective
/// radii, each with a 1-sigma uncertainty.
///
/// The fit (Levenberg-Marquardt with a weak a priori, as sun-sky
/// photometer networks do it) compares ln radiance and the direct-sun
/// optical depths, where given, with sora's fast multiple-scattering model
/// of the measured directions, and reports chi^2, whether it converged,
/// and warnings: a fit that did not converge, a poor fit, parameters the
/// measurements did not constrain. A fit that did not converge is a
/// warning, not an error (exit status 0).
///
/// Each channel's sun and gas absorption are averaged over --band-nm
/// (default 10 nm for AERONET files, as the Cimel channels are wide), or
/// weighted by its --filter's response (docs/filters.md).
///
/// The model's assumptions: the particles are spheres (Mie theory; dust's
/// spheroids are not), with one complex refractive index for both modes
/// per wavelength, smooth in wavelength as AERONET's inversion has it (n
/// nearly flat, k along a smooth curve; --one-index: one for every
/// wavelength); the size distribution is two log-normal volume
/// modes (fine and coarse); the aerosol lies in one exponential layer
/// (--aerosol-scale-height-m); light is scalar (polarisation changes
/// radiances by up to a few per cent); the air, ozone and ground are the
/// atmosphere's (--preset, default earth-clear, or --atmosphere), whose
/// own aerosol species are set aside and replaced by the fitted one.
///
/// Inputs, exactly one of:
///   --radiances FILE.csv     sora's CSV: wavelength_nm, sun_elevation_deg,
///                            sun_azimuth_deg, view_elevation_deg,
///                            view_azimuth_deg, radiance_w_m2_sr_nm,
///                            uncertainty_w_m2_sr_nm (any order); with
///                            --optical-depths FILE.csv (wavelength_nm,
///                            aerosol_optical_depth, uncertainty)
///   --aeronet-almucantar FILE, --aeronet-principal-plane FILE
///                            AERONET version 3 raw sky scans (.alm, .ppl),
///                            with --aeronet-aod FILE (.lev15, .lev20,
///                            version 3 or 2) for the optical depths
///                            nearest in time; every
///                            usable scan of the file is retrieved, one
///                            after another, or the one --scan N names
///   --normalised-spectrum FILE.csv
///                            wavelength_nm, relative_radiance in one
///                            direction (--sun-elevation, --sun-azimuth,
///                            --view-elevation, --view-azimuth): a spectrum
///                            known up to a factor tells little (the result
///                            is mostly the a priori, and says so)
///
/// Output: --format table (default), csv (one row per scan, units in the
/// column names) or json (one object per scan: the state, its sigmas and
/// correlations, the spectral optics, every measurement's residual) on
/// stdout; warnings also on stderr. --residuals FILE.csv writes every sky
/// radiance with its fit; --plot FILE.png the measured against the fitted
/// radiances of the (first) scan. Both are checked before any work and
/// written atomically; on any error nothing is written.
///
/// Examples (the repository's sample files):
///   sora retrieve \
///       --aeronet-almucantar crates/sora/tests/data/aeronet/alm_synthetic_karlsruhe_20050321.alm \
///       --aeronet-aod crates/sora/tests/data/aeronet/aod_karlsruhe_20050321.lev15 \
///       --plot fit.png
///   sora retrieve \
///       --aeronet-principal-plane crates/sora/tests/data/aeronet/ppl_arm_graciosa_20190103.ppl \
///       --format json --residuals residuals.csv
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
#[group(skip)]
#[command(group(clap::ArgGroup::new("input").required(true).multiple(false)))]
pub struct RetrieveArgs {
    /// Sky radiances in sora's CSV (W m^-2 sr^-1 nm^-1, degrees)
    #[arg(long, value_name = "FILE.csv", group = "input")]
    radiances: Option<PathBuf>,

    /// With --radiances: direct-sun aerosol optical depths (wavelength_nm,
    /// aerosol_optical_depth, uncertainty), at wavelengths of the radiances
    #[arg(long, value_name = "FILE.csv", requires = "radiances")]
    optical_depths: Option<PathBuf>,

    /// An AERONET version 3 almucantar file (.alm)
    #[arg(long, value_name = "FILE", group = "input")]
    aeronet_almucantar: Option<PathBuf>,

    /// An AERONET version 3 principal-plane file (.ppl)
    #[arg(long, value_name = "FILE", group = "input")]
    aeronet_principal_plane: Option<PathBuf>,

    /// With an AERONET sky file: its site's direct-sun optical depths
    /// (.lev15, .lev20; version 3 or version 2); each scan gets those measured nearest in time
    /// (within 30 minutes)
    #[arg(
        long,
        value_name = "FILE",
        conflicts_with_all = ["radiances", "normalised_spectrum"]
    )]
    aeronet_aod: Option<PathBuf>,

    /// With an AERONET sky file: retrieve only its N-th usable scan
    /// (1-based, in the file's order) [default: every scan]
    #[arg(
        long,
        value_name = "N",
        value_parser = clap::value_parser!(u64).range(1..),
        conflicts_with_all = ["radiances", "normalised_spectrum"]
    )]
    scan: Option<u64>,

    /// With an AERONET sky file: the most scans one run retrieves (each
    /// takes tens of seconds); a file with more is refused before any work
    /// (retrieve them in parts with --scan, or raise this)
    #[arg(
        long,
        value_name = "N",
        default_value_t = 100,
        value_parser = clap::value_parser!(u64).range(1..),
        conflicts_with_all = ["radiances", "normalised_spectrum"]
    )]
    max_scans: u64,

    /// A spectrum in one direction, known up to a factor (wavelength_nm,
    /// relative_radiance)
    #[arg(
        long,
        value_name = "FILE.csv",
        group = "input",
        requires_all = ["sun_elevation", "sun_azimuth", "view_elevation", "view_azimuth"]
    )]
    normalised_spectrum: Option<PathBuf>,

    /// With --normalised-spectrum: the sun's elevation, degrees
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        requires = "normalised_spectrum"
    )]
    sun_elevation: Option<f64>,

    /// With --normalised-spectrum: the sun's azimuth clockwise from north,
    /// degrees
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        requires = "normalised_spectrum"
    )]
    sun_azimuth: Option<f64>,

    /// With --normalised-spectrum: the view's elevation, degrees
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        requires = "normalised_spectrum"
    )]
    view_elevation: Option<f64>,

    /// With --normalised-spectrum: the view's azimuth clockwise from north,
    /// degrees
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        requires = "normalised_spectrum"
    )]
    view_azimuth: Option<f64>,

    /// The 1-sigma uncertainty of each AERONET or normalised radiance, as
    /// a fraction of it (AERONET quotes about 5 % for its sky calibration)
    #[arg(long, value_name = "FRACTION", default_value_t = 0.05)]
    relative_uncertainty: f64,

    /// A built-in atmosphere for the air, gases and ground (its aerosol
    /// species are set aside) [default: earth-clear]
    #[arg(long, value_name = "NAME", conflicts_with = "atmosphere")]
    preset: Option<String>,

    /// An atmosphere file (TOML) instead of --preset
    #[arg(long, value_name = "FILE.toml")]
    atmosphere: Option<PathBuf>,

    /// The wavelength of the fitted optical depth, nm: one of the measured
    /// [default: 440 if measured, else the shortest]
    #[arg(long, value_name = "NM")]
    reference_wavelength: Option<f64>,

    /// Scale height of the aerosol's exponential profile, m
    #[arg(long, value_name = "M", default_value_t = 1200.0)]
    aerosol_scale_height_m: f64,

    /// Width of each measured channel, nm: the sun's spectrum and the gas
    /// absorption are averaged over it (0.01..=50) [default: 10 for AERONET
    /// files, the Cimel channels' width at 440-1020 nm (docs/filters.md);
    /// 1 otherwise]
    #[arg(long, value_name = "NM", allow_hyphen_values = true)]
    band_nm: Option<f64>,

    /// An instrument channel (repeatable): a CSV file wavelength_nm,response
    /// or a built-in sun-photometer channel (cimel-440, cimel-675,
    /// cimel-870, cimel-1020, ...; cimel: those of the seven that cover a
    /// measured wavelength). The measured wavelength inside the filter's
    /// support nearest its centre is computed as the channel sees it, the
    /// sun and the air weighted by the response, instead of --band-nm's box
    /// (docs/filters.md)
    #[arg(long, value_name = "FILE.csv|NAME")]
    filter: Vec<String>,

    /// Fit a refractive index per wavelength, smooth in wavelength (the
    /// default; smoothness priors across the channels, as AERONET's
    /// inversion has: docs/retrieval.md)
    #[arg(long)]
    index_per_wavelength: bool,

    /// Fit one refractive index for every wavelength instead of one per
    /// wavelength
    #[arg(long, conflicts_with = "index_per_wavelength")]
    one_index: bool,

    /// Starting points of the fit (fine-dominated, coarse-dominated, the a
    /// priori); the lowest chi^2 wins
    #[arg(
        long,
        value_name = "N",
        default_value_t = 2,
        value_parser = clap::value_parser!(u64).range(1..=3)
    )]
    starting_points: u64,

    /// The most Levenberg-Marquardt iterations in all, the starting points'
    /// scouting (3 each) included
    #[arg(
        long,
        value_name = "N",
        default_value_t = 30,
        value_parser = clap::value_parser!(u64).range(1..)
    )]
    max_iterations: u64,

    /// Output format on stdout
    #[arg(long, value_enum, default_value_t = Format::Table)]
    format: Format,

    /// Also write every sky radiance and its fit as CSV (scan,
    /// wavelength_nm, the geometry in degrees, measured, uncertainty and
    /// fitted in W m^-2 sr^-1 nm^-1, normalised_residual), replaced
    /// atomically (the optical depths' residuals are in --format json)
    #[arg(long, value_name = "FILE.csv")]
    residuals: Option<PathBuf>,

    /// Also write a plot of the (first) scan's measured and fitted
    /// radiances against scattering angle (PNG), replaced atomically
    #[arg(long, value_name = "FILE.png")]
    plot: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Format {
    Table,
    Csv,
    Json,
}

/// One scan to retrieve: its number (1-based, as --scan counts) and its
/// measurements.
struct Scan {
    number: usize,
    measurements: Measurements,
}

pub fn run(args: RetrieveArgs) -> anyhow::Result<()> {
    // Outputs first: a bad path is refused before any work.
    if let Some(plot) = &args.plot
        && !plot
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        bail!(
            "--plot {}: the plot is a PNG image: give a name ending in .png",
            plot.display()
        );
    }
    // Both checked together: writable, and not one file for both.
    let outputs: Vec<(&Path, &str)> = [
        (args.residuals.as_deref(), "--residuals"),
        (args.plot.as_deref(), "--plot"),
    ]
    .into_iter()
    .filter_map(|(path, option)| path.map(|path| (path, option)))
    .collect();
    let mut targets = sora::output::output_targets(&outputs)?.into_iter();
    let residuals_target = args.residuals.as_ref().and_then(|_| targets.next());
    let plot_target = args.plot.as_ref().and_then(|_| targets.next());

    let atmosphere = AtmosphereSource {
        preset: match (&args.preset, &args.atmosphere) {
            (_, Some(_)) => None,
            (Some(name), None) => Some(name.clone()),
            (None, None) => Some("earth-clear".to_string()),
        },
        atmosphere: args.atmosphere.clone(),
    }
    .load()?;
    let settings = RetrievalSettings {
        reference_wavelength_nm: args.reference_wavelength,
        aerosol_scale_height_m: args.aerosol_scale_height_m,
        max_iterations: args.max_iterations as usize,
        starting_points: args.starting_points as usize,
        band_nm: args.band_nm.unwrap_or(
            if args.aeronet_almucantar.is_some() || args.aeronet_principal_plane.is_some() {
                10.0
            } else {
                1.0
            },
        ),
        // The two flags conflict: --index-per-wavelength is the default's name.
        index: if args.one_index && !args.index_per_wavelength {
            IndexSpectrum::One
        } else {
            IndexSpectrum::PerWavelength
        },
        filters: Vec::new(),
    };
    if !(0.01..=50.0).contains(&settings.band_nm) {
        bail!(
            "--band-nm {} nm is out of range: allowed 0.01..=50 nm",
            settings.band_nm
        );
    }
    if !(settings.aerosol_scale_height_m.is_finite() && settings.aerosol_scale_height_m > 0.0) {
        bail!(
            "--aerosol-scale-height-m {}: must be a length > 0",
            settings.aerosol_scale_height_m
        );
    }
    let explicit: Vec<String> = args
        .filter
        .iter()
        .filter(|f| *f != "cimel")
        .cloned()
        .collect();
    let explicit = crate::arguments::parse_filters(&explicit)?;
    let cimel = if args.filter.iter().any(|f| f == "cimel") {
        crate::arguments::parse_filters(&["cimel".to_string()])?
    } else {
        Vec::new()
    };
    let scans = read_scans(&args)?;
    // Each scan's filters, checked before any work.
    let mut scan_settings = Vec::with_capacity(scans.len());
    for scan in &scans {
        let wavelengths = scan.measurements.wavelengths_nm();
        let mut filters = explicit.clone();
        filters.extend(
            cimel
                .iter()
                .filter(|f| wavelengths.iter().any(|w| f.response_at(*w) > 0.0))
                .cloned(),
        );
        sora::inversion::assign_filters(&filters, &wavelengths)
            .map_err(|e| anyhow::anyhow!("--filter: {}: {e}", scan.measurements.label))?;
        scan_settings.push(RetrievalSettings {
            filters,
            ..settings.clone()
        });
    }
    if let Some(reference) = args.reference_wavelength {
        for scan in &scans {
            let wavelengths = scan.measurements.wavelengths_nm();
            if !wavelengths.contains(&reference) {
                bail!(
                    "--reference-wavelength {reference}: {} has no radiance at {reference} nm (it has {})",
                    scan.measurements.label,
                    list(&wavelengths)
                );
            }
        }
    }

    // The retrievals, one after another (each uses every core); the bar
    // gives scans done of all and the time left from the mean time per
    // scan so far (nothing claimed before the first is done).
    let bar = crate::progress::bar(
        scans.len() as u64,
        "{spinner} retrieving [{bar:30}] {pos}/{len} scans, {elapsed} elapsed, {msg}",
    );
    bar.set_message("time left known after the first scan");
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let started = Instant::now();
    let mut retrievals: Vec<(usize, Retrieval)> = Vec::with_capacity(scans.len());
    for (done, (scan, settings)) in scans.iter().zip(&scan_settings).enumerate() {
        let retrieval = retrieve(&atmosphere, &scan.measurements, settings)
            .with_context(|| scan.measurements.label.clone())?;
        bar.suspend(|| {
            for warning in &retrieval.warnings {
                eprintln!("warning: {}: {warning}", retrieval.label);
            }
        });
        retrievals.push((scan.number, retrieval));
        bar.inc(1);
        let done = done + 1;
        let per_scan = started.elapsed().as_secs_f64() / done as f64;
        bar.set_message(format!(
            "about {:.0} s left",
            per_scan * (scans.len() - done) as f64
        ));
    }
    bar.finish_and_clear();

    // Everything in memory first, then the files, then stdout.
    let plot = retrievals
        .first()
        .filter(|_| plot_target.is_some())
        .map(|(_, r)| crate::fit_plot::fit_plot(r))
        .transpose()?;
    let text = match args.format {
        Format::Table => table(&retrievals),
        Format::Csv => csv(&retrievals),
        Format::Json => json(&retrievals)?,
    };
    // Both files or neither.
    let mut files = sora::output::OutputFiles::new();
    if let Some(target) = &residuals_target {
        files.text(target, &residuals_csv(&retrievals))?;
    }
    if let (Some(target), Some(image)) = (&plot_target, &plot) {
        files.png(target, image)?;
    }
    files.commit()?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    out.write_all(text.as_bytes())?;
    out.flush()?;
    eprintln!(
        "{} scan(s) retrieved in {:.1} s",
        retrievals.len(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The text of `path`, or a one-line error naming it.
fn read(path: &Path) -> anyhow::Result<String> {
    Ok(sora::input::read_text(path)?)
}

/// The scans the arguments name, read and checked; AERONET's notes on
/// stderr.
fn read_scans(args: &RetrieveArgs) -> anyhow::Result<Vec<Scan>> {
    if let Some(path) = &args.radiances {
        let what = path.display().to_string();
        let mut measurements = parse_sky_radiance_csv(&read(path)?, &what)?;
        if let Some(depths) = &args.optical_depths {
            measurements.optical_depths =
                parse_optical_depth_csv(&read(depths)?, &depths.display().to_string())?;
            measurements.validate()?;
        }
        return Ok(vec![Scan {
            number: 1,
            measurements,
        }]);
    }
    if let Some(path) = &args.normalised_spectrum {
        let geometry = SkyGeometry {
            sun_elevation_deg: args.sun_elevation.expect("clap requires it"),
            sun_azimuth_deg: args.sun_azimuth.expect("clap requires it"),
            view_elevation_deg: args.view_elevation.expect("clap requires it"),
            view_azimuth_deg: args.view_azimuth.expect("clap requires it"),
        };
        let measurements = parse_normalised_spectrum_csv(
            &read(path)?,
            &path.display().to_string(),
            geometry,
            args.relative_uncertainty,
        )?;
        return Ok(vec![Scan {
            number: 1,
            measurements,
        }]);
    }
    let (path, kind) = match (&args.aeronet_almucantar, &args.aeronet_principal_plane) {
        (Some(path), _) => (path, AeronetScan::Almucantar),
        (None, Some(path)) => (path, AeronetScan::PrincipalPlane),
        (None, None) => unreachable!("clap requires one input"),
    };
    let mut sky = parse_aeronet_sky(
        &read(path)?,
        kind,
        &path.display().to_string(),
        args.relative_uncertainty,
    )?;
    let mut notes = std::mem::take(&mut sky.notes);
    if let Some(aod) = &args.aeronet_aod {
        let entries = parse_aeronet_aod(&read(aod)?, &aod.display().to_string())?;
        notes.extend(attach_nearest_optical_depths(&mut sky.scans, &entries));
    }
    let count = sky.scans.len();
    let scans: Vec<Scan> = sky
        .scans
        .into_iter()
        .enumerate()
        .map(|(i, scan)| Scan {
            number: i + 1,
            measurements: scan.measurements,
        })
        .filter(|scan| args.scan.is_none_or(|n| n as usize == scan.number))
        .collect();
    if let Some(n) = args.scan
        && scans.is_empty()
    {
        bail!(
            "--scan {n}: {} has {count} usable scan(s): give 1..={count}",
            path.display()
        );
    }
    if scans.len() as u64 > args.max_scans {
        bail!(
            "{} has {} usable scans, more than --max-scans {}: retrieve one with --scan N, or raise --max-scans (each scan takes tens of seconds)",
            path.display(),
            scans.len(),
            args.max_scans
        );
    }
    for note in notes {
        eprintln!("note: {note}");
    }
    for scan in &scans {
        scan.measurements.validate()?;
    }
    Ok(scans)
}

/// `440, 675 nm`.
fn list(wavelengths: &[f64]) -> String {
    let names: Vec<String> = wavelengths.iter().map(|w| w.to_string()).collect();
    format!("{} nm", names.join(", "))
}

/// How a parameter is shown to people: its name and its unit.
fn parameter_label(name: &str, reference_nm: f64) -> (String, &'static str) {
    match name {
        "aerosol_optical_depth" => (format!("aerosol optical depth at {reference_nm} nm"), ""),
        "fine_volume_median_radius_um" => ("fine mode volume median radius".into(), "um"),
        "fine_width" => ("fine mode width (std. dev. of ln r)".into(), ""),
        "coarse_volume_median_radius_um" => ("coarse mode volume median radius".into(), "um"),
        "coarse_width" => ("coarse mode width (std. dev. of ln r)".into(), ""),
        "fine_volume_fraction" => ("fine mode volume fraction".into(), ""),
        "refractive_index_real" => ("refractive index, real part".into(), ""),
        "refractive_index_imaginary" => ("refractive index, imaginary part".into(), ""),
        other => (other.replace('_', " "), ""),
    }
}

/// `value ± sigma`, to the sigma's second significant digit (4 decimals
/// where the sigma is 0 or not finite; `n/a` for a value that is not).
fn plus_minus(e: Estimate) -> String {
    if !e.value.is_finite() {
        return "n/a".to_string();
    }
    if !e.sigma.is_finite() {
        return format!("{:.4} ± n/a", e.value);
    }
    let decimals = if e.sigma > 0.0 {
        (1.0 - e.sigma.log10().floor()).clamp(0.0, 8.0) as usize
    } else {
        4
    };
    format!("{:.decimals$} ± {:.decimals$}", e.value, e.sigma)
}

/// chi^2 per measurement.
fn reduced(r: &Retrieval) -> f64 {
    r.chi_square / r.measurement_count.max(1) as f64
}

fn table(retrievals: &[(usize, Retrieval)]) -> String {
    let mut out = String::new();
    for (k, (number, r)) in retrievals.iter().enumerate() {
        if k > 0 {
            out.push('\n');
        }
        let wavelengths: Vec<f64> = r.spectral.iter().map(|s| s.wavelength_nm).collect();
        let _ = writeln!(out, "scan {number}: {}", r.label);
        let _ = writeln!(
            out,
            "  {} sky radiances at {}, {} optical depth(s)",
            r.radiances.len(),
            list(&wavelengths),
            r.optical_depths.len()
        );
        let _ = writeln!(out, "  state (± 1 sigma):");
        for (name, e) in PARAMETER_NAMES.iter().zip(&r.parameters) {
            let (label, unit) = parameter_label(name, r.reference_wavelength_nm);
            let line = format!("    {label:<40} {} {unit}", plus_minus(*e));
            let _ = writeln!(out, "{}", line.trim_end());
        }
        if let Some(scale) = r.radiance_scale {
            let _ = writeln!(
                out,
                "    {:<40} {}",
                "radiance scale factor",
                plus_minus(scale)
            );
        }
        // The index's columns only where it differs between wavelengths
        // (by default); one index (`--one-index`) is the state's lines above.
        let index_varies = r.spectral.windows(2).any(|pair| {
            let index = |s: &SpectralOptics| {
                (
                    s.refractive_index_real.value,
                    s.refractive_index_imaginary.value,
                )
            };
            index(&pair[0]) != index(&pair[1])
        });
        let mut header = format!(
            "  {:>13}  {:<22}{:<26}{}",
            "wavelength nm", "optical depth", "single-scat. albedo", "asymmetry parameter"
        );
        if index_varies {
            header = format!(
                "{header:<91}{:<26}refr. index, imag. part",
                "refr. index, real part"
            );
        }
        let _ = writeln!(out, "{header}");
        for s in &r.spectral {
            let mut row = format!(
                "  {:>13}  {:<22}{:<26}{}",
                s.wavelength_nm,
                plus_minus(s.optical_depth),
                plus_minus(s.single_scattering_albedo),
                plus_minus(s.asymmetry)
            );
            if index_varies {
                row = format!(
                    "{row:<91}{:<26}{}",
                    plus_minus(s.refractive_index_real),
                    plus_minus(s.refractive_index_imaginary)
                );
            }
            let _ = writeln!(out, "{row}");
        }
        let _ = writeln!(
            out,
            "  {:<40}   {}",
            "Angstrom exponent",
            plus_minus(r.angstrom_exponent)
        );
        let _ = writeln!(
            out,
            "  {:<40}   {} um",
            "fine mode effective radius",
            plus_minus(r.fine_effective_radius_um)
        );
        let _ = writeln!(
            out,
            "  {:<40}   {} um",
            "coarse mode effective radius",
            plus_minus(r.coarse_effective_radius_um)
        );
        let _ = writeln!(
            out,
            "  chi^2 {:.3} over {} measurements ({:.3} per measurement), {} iterations, converged: {}",
            r.chi_square,
            r.measurement_count,
            reduced(r),
            r.iterations,
            if r.converged { "yes" } else { "no" }
        );
        if r.warnings.is_empty() {
            let _ = writeln!(out, "  warnings: none");
        } else {
            let _ = writeln!(out, "  warnings:");
            for warning in &r.warnings {
                let _ = writeln!(out, "    - {warning}");
            }
        }
    }
    out
}

/// A number for CSV: `{:.9e}`-free, shortest exact form; `missing` when
/// not finite.
fn number(value: f64, missing: &str) -> String {
    if value.is_finite() {
        value.to_string()
    } else {
        missing.to_string()
    }
}

fn csv(retrievals: &[(usize, Retrieval)]) -> String {
    // The union of the scans' wavelengths: a scan without one leaves its
    // cells empty.
    let mut wavelengths: Vec<f64> = retrievals
        .iter()
        .flat_map(|(_, r)| r.spectral.iter().map(|s| s.wavelength_nm))
        .collect();
    wavelengths.sort_by(f64::total_cmp);
    wavelengths.dedup();
    let mut header: Vec<String> = vec![
        "scan".into(),
        "label".into(),
        "reference_wavelength_nm".into(),
    ];
    let pair = |header: &mut Vec<String>, name: String| {
        header.push(format!("{name}_sigma"));
        let sigma = header.len() - 1;
        header.insert(sigma, name);
    };
    for w in &wavelengths {
        pair(&mut header, format!("aerosol_optical_depth_{w}nm"));
    }
    for name in &PARAMETER_NAMES[1..] {
        pair(&mut header, name.to_string());
    }
    for w in &wavelengths {
        pair(&mut header, format!("single_scattering_albedo_{w}nm"));
    }
    for w in &wavelengths {
        pair(&mut header, format!("asymmetry_parameter_{w}nm"));
    }
    for w in &wavelengths {
        pair(&mut header, format!("refractive_index_real_{w}nm"));
    }
    for w in &wavelengths {
        pair(&mut header, format!("refractive_index_imaginary_{w}nm"));
    }
    for name in [
        "angstrom_exponent",
        "fine_effective_radius_um",
        "coarse_effective_radius_um",
        "radiance_scale",
    ] {
        pair(&mut header, name.to_string());
    }
    header.extend(
        [
            "chi_square",
            "measurement_count",
            "chi_square_per_measurement",
            "iterations",
            "converged",
            "warnings",
        ]
        .map(String::from),
    );
    let mut out = header.join(",");
    out.push('\n');
    for (number_of_scan, r) in retrievals {
        let mut row: Vec<String> = vec![
            number_of_scan.to_string(),
            crate::csv::cell(&r.label),
            number(r.reference_wavelength_nm, ""),
        ];
        let estimate = |row: &mut Vec<String>, e: Option<Estimate>| match e {
            Some(e) => {
                row.push(number(e.value, ""));
                row.push(number(e.sigma, ""));
            }
            None => row.extend([String::new(), String::new()]),
        };
        let at = |w: f64| r.spectral.iter().find(|s| s.wavelength_nm == w);
        for w in &wavelengths {
            estimate(&mut row, at(*w).map(|s| s.optical_depth));
        }
        for e in &r.parameters[1..] {
            estimate(&mut row, Some(*e));
        }
        for w in &wavelengths {
            estimate(&mut row, at(*w).map(|s| s.single_scattering_albedo));
        }
        for w in &wavelengths {
            estimate(&mut row, at(*w).map(|s| s.asymmetry));
        }
        for w in &wavelengths {
            estimate(&mut row, at(*w).map(|s| s.refractive_index_real));
        }
        for w in &wavelengths {
            estimate(&mut row, at(*w).map(|s| s.refractive_index_imaginary));
        }
        estimate(&mut row, Some(r.angstrom_exponent));
        estimate(&mut row, Some(r.fine_effective_radius_um));
        estimate(&mut row, Some(r.coarse_effective_radius_um));
        estimate(&mut row, r.radiance_scale);
        row.push(number(r.chi_square, ""));
        row.push(r.measurement_count.to_string());
        row.push(number(reduced(r), ""));
        row.push(r.iterations.to_string());
        row.push(r.converged.to_string());
        // Always quoted, so that a reader sees one cell even when empty.
        row.push(crate::csv::quoted(&r.warnings.join("; ")));
        out.push_str(&row.join(","));
        out.push('\n');
    }
    out
}

/// `sora retrieve --format json`: one object per scan (docs/json.md).
#[derive(Serialize)]
struct RetrievalJson<'a> {
    scan: usize,
    label: &'a str,
    reference_wavelength_nm: f64,
    /// Each of [`PARAMETER_NAMES`] (its unit in its name).
    parameters: Members<EstimateJson>,
    correlations: CorrelationsJson,
    spectral: Vec<SpectralJson>,
    angstrom_exponent: EstimateJson,
    fine_effective_radius_um: EstimateJson,
    coarse_effective_radius_um: EstimateJson,
    radiance_scale: Option<EstimateJson>,
    chi_square: f64,
    measurement_count: usize,
    chi_square_per_measurement: f64,
    iterations: usize,
    converged: bool,
    warnings: &'a [String],
    residuals: ResidualsJson,
}

/// A value and its 1-sigma uncertainty, in the unit its name gives.
#[derive(Serialize)]
struct EstimateJson {
    value: f64,
    sigma: f64,
}

impl From<Estimate> for EstimateJson {
    fn from(e: Estimate) -> Self {
        EstimateJson {
            value: e.value,
            sigma: e.sigma,
        }
    }
}

#[derive(Serialize)]
struct CorrelationsJson {
    parameters: [&'static str; PARAMETER_NAMES.len()],
    /// Row-major, one row per parameter.
    matrix: Vec<Vec<f64>>,
}

#[derive(Serialize)]
struct SpectralJson {
    wavelength_nm: f64,
    aerosol_optical_depth: EstimateJson,
    single_scattering_albedo: EstimateJson,
    asymmetry_parameter: EstimateJson,
    refractive_index_real: EstimateJson,
    refractive_index_imaginary: EstimateJson,
}

#[derive(Serialize)]
struct ResidualsJson {
    radiances: Vec<RadianceResidualJson>,
    optical_depths: Vec<OpticalDepthResidualJson>,
}

#[derive(Serialize)]
struct RadianceResidualJson {
    wavelength_nm: f64,
    sun_elevation_deg: f64,
    sun_azimuth_deg: f64,
    view_elevation_deg: f64,
    view_azimuth_deg: f64,
    scattering_angle_deg: f64,
    measured_w_m2_sr_nm: f64,
    uncertainty_w_m2_sr_nm: f64,
    fitted_w_m2_sr_nm: f64,
    normalised_residual: f64,
}

#[derive(Serialize)]
struct OpticalDepthResidualJson {
    wavelength_nm: f64,
    measured: f64,
    uncertainty: f64,
    fitted: f64,
    normalised_residual: f64,
}

fn json(retrievals: &[(usize, Retrieval)]) -> anyhow::Result<String> {
    let objects: Vec<RetrievalJson> = retrievals
        .iter()
        .map(|(scan, r)| RetrievalJson {
            scan: *scan,
            label: &r.label,
            reference_wavelength_nm: r.reference_wavelength_nm,
            parameters: Members(
                PARAMETER_NAMES
                    .iter()
                    .zip(&r.parameters)
                    .map(|(name, e)| (name.to_string(), (*e).into()))
                    .collect(),
            ),
            correlations: CorrelationsJson {
                parameters: PARAMETER_NAMES,
                matrix: r
                    .correlations
                    .chunks(r.parameters.len().max(1))
                    .map(<[f64]>::to_vec)
                    .collect(),
            },
            spectral: r
                .spectral
                .iter()
                .map(|s| SpectralJson {
                    wavelength_nm: s.wavelength_nm,
                    aerosol_optical_depth: s.optical_depth.into(),
                    single_scattering_albedo: s.single_scattering_albedo.into(),
                    asymmetry_parameter: s.asymmetry.into(),
                    refractive_index_real: s.refractive_index_real.into(),
                    refractive_index_imaginary: s.refractive_index_imaginary.into(),
                })
                .collect(),
            angstrom_exponent: r.angstrom_exponent.into(),
            fine_effective_radius_um: r.fine_effective_radius_um.into(),
            coarse_effective_radius_um: r.coarse_effective_radius_um.into(),
            radiance_scale: r.radiance_scale.map(EstimateJson::from),
            chi_square: r.chi_square,
            measurement_count: r.measurement_count,
            chi_square_per_measurement: reduced(r),
            iterations: r.iterations,
            converged: r.converged,
            warnings: &r.warnings,
            residuals: ResidualsJson {
                radiances: r
                    .radiances
                    .iter()
                    .map(|f| {
                        let m = &f.measured;
                        RadianceResidualJson {
                            wavelength_nm: m.wavelength_nm,
                            sun_elevation_deg: m.sun_elevation_deg,
                            sun_azimuth_deg: m.sun_azimuth_deg,
                            view_elevation_deg: m.view_elevation_deg,
                            view_azimuth_deg: m.view_azimuth_deg,
                            scattering_angle_deg: m.scattering_angle_deg(),
                            measured_w_m2_sr_nm: m.radiance_w_m2_sr_nm,
                            uncertainty_w_m2_sr_nm: m.uncertainty_w_m2_sr_nm,
                            fitted_w_m2_sr_nm: f.fitted_w_m2_sr_nm,
                            normalised_residual: f.normalised_residual,
                        }
                    })
                    .collect(),
                optical_depths: r
                    .optical_depths
                    .iter()
                    .map(|f| OpticalDepthResidualJson {
                        wavelength_nm: f.measured.wavelength_nm,
                        measured: f.measured.aerosol_optical_depth,
                        uncertainty: f.measured.uncertainty,
                        fitted: f.fitted,
                        normalised_residual: f.normalised_residual,
                    })
                    .collect(),
            },
        })
        .collect();
    crate::json::to_string(&objects)
}

/// Columns of `--residuals`.
const RESIDUAL_COLUMNS: &str = "scan,wavelength_nm,sun_elevation_deg,sun_azimuth_deg,view_elevation_deg,view_azimuth_deg,scattering_angle_deg,measured_w_m2_sr_nm,uncertainty_w_m2_sr_nm,fitted_w_m2_sr_nm,normalised_residual";

fn residuals_csv(retrievals: &[(usize, Retrieval)]) -> String {
    let mut out = String::from(RESIDUAL_COLUMNS);
    out.push('\n');
    for (scan, r) in retrievals {
        for f in &r.radiances {
            let m = &f.measured;
            let _ = writeln!(
                out,
                "{scan},{},{},{},{},{},{},{},{},{},{}",
                m.wavelength_nm,
                m.sun_elevation_deg,
                m.sun_azimuth_deg,
                m.view_elevation_deg,
                m.view_azimuth_deg,
                number(m.scattering_angle_deg(), ""),
                number(m.radiance_w_m2_sr_nm, ""),
                number(m.uncertainty_w_m2_sr_nm, ""),
                number(f.fitted_w_m2_sr_nm, ""),
                number(f.normalised_residual, "")
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plus_minus_rounds_to_the_sigma() {
        let e = |value, sigma| Estimate { value, sigma };
        assert_eq!(plus_minus(e(0.23456, 0.0123)), "0.235 ± 0.012");
        assert_eq!(plus_minus(e(1.4567, 0.0346)), "1.457 ± 0.035");
        assert_eq!(plus_minus(e(12.0, 3.0)), "12.0 ± 3.0");
        assert_eq!(plus_minus(e(0.5, 0.0)), "0.5000 ± 0.0000");
        assert_eq!(plus_minus(e(0.5, f64::NAN)), "0.5000 ± n/a");
        assert_eq!(plus_minus(e(f64::NAN, 0.1)), "n/a");
    }
}
