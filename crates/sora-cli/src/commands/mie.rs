//! `sora mie`: Mie-theory optics of one sphere, of many (batch CSV), or of a
//! size distribution over wavelengths.

use std::io::{BufWriter, Write};
use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use sora::mie::Complex64;
use sora::mie::distribution::quadrature::RadiusQuadratureSettings;
use sora::mie::distribution::{RadiusWindow, SizeDistribution};
use sora::mie::ensemble::compute_ensemble_cross_sections;
use sora::mie::sphere::{MieSolution, compute_efficiencies};

use crate::arguments::{parse_number_list, parse_refractive_index};

/// Mie scattering by homogeneous spheres: efficiencies, asymmetry parameter,
/// phase function.
///
/// Examples:
///   sora mie --m 1.5+0.01i --x 10
///   sora mie --m 1.5+0.01i --radius-um 0.5 --wavelength-nm 550
///   sora mie --m 1.33 --x 5 --phase
///   sora mie --batch spheres.csv > results.csv
///   sora mie --m 1.5+0.01i --lognormal 0.1,2.0,0.1,2.5 --wavelengths 380:780:20
///
/// The refractive index is relative to the medium; a positive imaginary part
/// means absorption. The size parameter is x = 2 pi r / lambda.
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct MieArgs {
    /// Refractive index n+ki relative to the medium, e.g. 1.5+0.01i
    #[arg(long = "m", value_name = "N+Ki", value_parser = parse_refractive_index, allow_hyphen_values = true)]
    refractive_index: Option<Complex64>,

    /// Size parameter x = 2 pi r / lambda (dimensionless)
    #[arg(long = "x", value_name = "X", conflicts_with_all = ["radius_um", "wavelength_nm"])]
    size_parameter: Option<f64>,

    /// Sphere radius in micrometres (with --wavelength-nm instead of --x)
    #[arg(long, value_name = "UM", requires = "wavelength_nm")]
    radius_um: Option<f64>,

    /// Vacuum wavelength in nanometres (with --radius-um)
    #[arg(long, value_name = "NM", requires = "radius_um")]
    wavelength_nm: Option<f64>,

    /// Print the phase function table instead: angle_deg, phase function
    /// (normalised to 1 over 4 pi sr, unit sr^-1), S12/S11
    #[arg(long)]
    phase: bool,

    /// Angular step of the --phase table, degrees
    #[arg(long, value_name = "DEG", default_value_t = 1.0, requires = "phase")]
    angle_step_deg: f64,

    /// Read spheres from a CSV file with header m_re,m_im,x (one sphere per
    /// row) and write m_re,m_im,x,qext,qsca,qabs,qback,g to stdout ("-" reads stdin)
    #[arg(long, value_name = "FILE.csv", conflicts_with_all = ["refractive_index", "size_parameter", "radius_um", "phase"])]
    batch: Option<PathBuf>,

    /// A log-normal size distribution instead of one sphere: number median
    /// radius (um), geometric standard deviation, and optionally a radius
    /// window (um) it is truncated to, e.g. 0.1,2.0 or 0.1,2.0,0.1,2.5.
    /// Prints the per-particle ensemble optics at each of --wavelengths.
    #[arg(long, value_name = "MEDIAN_UM,SIGMA_G[,MIN_UM,MAX_UM]", conflicts_with_all = ["size_parameter", "radius_um", "phase", "batch", "gamma"])]
    lognormal: Option<String>,

    /// A modified gamma size distribution (Hansen & Travis 1974) by effective
    /// radius (um) and effective variance, e.g. 1.5,0.3
    #[arg(long, value_name = "REFF_UM,VEFF", conflicts_with_all = ["size_parameter", "radius_um", "phase", "batch"])]
    gamma: Option<String>,

    /// Wavelengths of the distribution forms, start:stop:step in nm
    #[arg(long, value_name = "START:STOP:STEP", default_value = "380:780:20")]
    wavelengths: sora::spectrum::WavelengthGrid,
}

pub fn run(args: MieArgs) -> anyhow::Result<()> {
    if let Some(path) = &args.batch {
        return run_batch(path);
    }
    let Some(m) = args.refractive_index else {
        bail!(
            "give the refractive index with --m (e.g. --m 1.5+0.01i), or --batch FILE.csv; see sora mie --help"
        );
    };
    if args.lognormal.is_some() || args.gamma.is_some() {
        return print_ensemble_table(m, &args);
    }
    let x = match (args.size_parameter, args.radius_um, args.wavelength_nm) {
        (Some(x), _, _) => x,
        (None, Some(radius_um), Some(wavelength_nm)) => size_parameter(radius_um, wavelength_nm)?,
        _ => bail!("give the size parameter with --x, or --radius-um and --wavelength-nm"),
    };
    if args.phase {
        print_phase_table(m, x, args.angle_step_deg)
    } else {
        print_efficiencies(m, x)
    }
}

/// The size distribution of `--lognormal` or `--gamma`.
fn size_distribution(args: &MieArgs) -> anyhow::Result<SizeDistribution> {
    if let Some(text) = &args.lognormal {
        let numbers = parse_number_list(text, "--lognormal").map_err(anyhow::Error::msg)?;
        let (median_um, sigma_g, window) = match numbers.as_slice() {
            [median, sigma] => (*median, *sigma, None),
            [median, sigma, min, max] => (*median, *sigma, Some((*min, *max))),
            _ => bail!(
                "--lognormal takes 2 or 4 numbers (MEDIAN_UM,SIGMA_G[,MIN_UM,MAX_UM]), got '{text}'"
            ),
        };
        let distribution =
            SizeDistribution::log_normal(median_um * 1e-6, sigma_g).context("--lognormal")?;
        return Ok(match window {
            None => distribution,
            Some((min, max)) => distribution
                .truncated_to(
                    RadiusWindow::from_micrometres(min, max)
                        .context("--lognormal radius window")?,
                )
                .context("--lognormal")?,
        });
    }
    let text = args
        .gamma
        .as_deref()
        .expect("called with --lognormal or --gamma");
    let numbers = parse_number_list(text, "--gamma").map_err(anyhow::Error::msg)?;
    let [effective_radius_um, effective_variance] = numbers.as_slice() else {
        bail!("--gamma takes 2 numbers (REFF_UM,VEFF), got '{text}'");
    };
    SizeDistribution::modified_gamma(effective_radius_um * 1e-6, *effective_variance)
        .context("--gamma")
}

/// The largest effective size parameter 2 pi r_eff / lambda (at the shortest
/// wavelength) of the distribution forms, checked before computing: about
/// half a minute of work per wavelength there.
const MAX_EFFECTIVE_SIZE_PARAMETER: f64 = 1e5;

/// The distribution forms: per-particle ensemble optics per wavelength, CSV.
fn print_ensemble_table(m: Complex64, args: &MieArgs) -> anyhow::Result<()> {
    let distribution = size_distribution(args)?;
    // The work grows with the size parameter (nodes and series terms both
    // ~ x): refuse at once rather than compute for hours (issue 17).
    let mut radius_m = distribution.shape().effective_radius_m();
    if let Some(window) = distribution.radius_window() {
        radius_m = radius_m.min(window.max_radius_m());
    }
    let shortest_nm = args
        .wavelengths
        .wavelengths_nm()
        .fold(f64::INFINITY, f64::min);
    let x_eff = 2.0 * std::f64::consts::PI * radius_m * 1e9 / shortest_nm;
    if x_eff.is_nan() || x_eff > MAX_EFFECTIVE_SIZE_PARAMETER {
        bail!(
            "the distribution's effective radius {radius_m:e} m is a size parameter of {x_eff:e} at {shortest_nm} nm, more than the limit of {MAX_EFFECTIVE_SIZE_PARAMETER:e}; give an effective radius below {:e} um",
            MAX_EFFECTIVE_SIZE_PARAMETER * shortest_nm * 1e-3 / (2.0 * std::f64::consts::PI)
        );
    }
    let settings = RadiusQuadratureSettings::cross_sections();
    let mut out = BufWriter::new(std::io::stdout().lock());
    writeln!(
        out,
        "wavelength_nm,c_ext_m2,c_sca_m2,c_abs_m2,single_scattering_albedo,asymmetry_g,paper_hg_asymmetry_g,number_fraction_in_window"
    )?;
    for wavelength_nm in args.wavelengths.wavelengths_nm() {
        let e = compute_ensemble_cross_sections(wavelength_nm, m, &distribution, &settings)
            .with_context(|| format!("at {wavelength_nm} nm"))?;
        writeln!(
            out,
            "{wavelength_nm},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e}",
            e.extinction_cross_section_m2,
            e.scattering_cross_section_m2,
            e.absorption_cross_section_m2,
            e.single_scattering_albedo,
            e.asymmetry_parameter,
            e.paper_asymmetry_parameter,
            e.number_fraction_in_window
        )?;
    }
    out.flush()?;
    Ok(())
}

/// x = 2 pi r / lambda, both lengths checked.
fn size_parameter(radius_um: f64, wavelength_nm: f64) -> anyhow::Result<f64> {
    if !(radius_um.is_finite() && radius_um > 0.0) {
        bail!("--radius-um = {radius_um} um is out of range: allowed > 0 um");
    }
    if !(wavelength_nm.is_finite() && wavelength_nm > 0.0) {
        bail!("--wavelength-nm = {wavelength_nm} nm is out of range: allowed > 0 nm");
    }
    Ok(2.0 * std::f64::consts::PI * radius_um * 1e3 / wavelength_nm)
}

fn print_efficiencies(m: Complex64, x: f64) -> anyhow::Result<()> {
    let q = compute_efficiencies(m, x)?;
    let imaginary = shortest_round_trip(m.im);
    let sign = if imaginary.starts_with('-') { "" } else { "+" };
    println!("m     = {}{sign}{imaginary}i", shortest_round_trip(m.re));
    println!("x     = {}", shortest_round_trip(x));
    println!("qext  = {:.12e}", q.qext);
    println!("qsca  = {:.12e}", q.qsca);
    println!("qabs  = {:.12e}", q.qabs);
    println!("qback = {:.12e}", q.qback);
    println!("g     = {:.12e}", q.g);
    // Where Q_ext is 0 (or underflows) the albedo is its limit: 0 for
    // m = 1 + 0i (no scattering at all, as for a non-scattering species in
    // the ensemble optics), else the Rayleigh limit x -> 0 (Q_sca ~ x^4,
    // Q_abs ~ x): 0 if the sphere absorbs, 1 if not (issue 17).
    let albedo = if q.qext > 0.0 && (q.qsca / q.qext).is_finite() {
        q.qsca / q.qext
    } else if m == Complex64::new(1.0, 0.0) || m.im > 0.0 {
        0.0
    } else {
        1.0
    };
    println!("single_scattering_albedo = {albedo:.12e}");
    Ok(())
}

/// Below this |m| x (and x), `sora mie --phase` prints the Rayleigh-limit
/// phase function, exact there to double precision, instead of the Mie
/// series, whose S11 ~ x^6 underflows for x below about 1e-55.
const RAYLEIGH_LIMIT_SIZE_PARAMETER: f64 = 1e-8;

/// The most rows `sora mie --phase` prints (checked before anything is
/// allocated): a step of 1e-4 deg.
const MAX_PHASE_TABLE_ROWS: usize = 1_800_001;

fn print_phase_table(m: Complex64, x: f64, step_deg: f64) -> anyhow::Result<()> {
    if !(step_deg.is_finite() && step_deg > 0.0 && step_deg <= 180.0) {
        bail!("--angle-step-deg = {step_deg} deg is out of range: allowed 0 < step <= 180 deg");
    }
    let solution = MieSolution::compute(m, x)?;
    if m == Complex64::new(1.0, 0.0) {
        bail!(
            "--m 1+0i: the sphere does not scatter (every Mie coefficient is 0, Q_sca = 0), so it has no phase function; give an index other than 1+0i"
        );
    }
    // Counted in floating point: a subnormal step gives an infinite count
    // (5e-324 overflowed the integer, found by the flag mutation tests).
    let rows = (180.0 / step_deg).floor() + 1.0;
    if rows > MAX_PHASE_TABLE_ROWS as f64 {
        bail!(
            "--angle-step-deg = {step_deg:e} deg gives {rows:e} rows, more than the limit of {MAX_PHASE_TABLE_ROWS}; give a step of at least {:e} deg",
            180.0 / (MAX_PHASE_TABLE_ROWS - 1) as f64
        );
    }
    let count = rows as usize;
    let angles_deg: Vec<f64> = (0..count)
        .map(|i| (i as f64 * step_deg).min(180.0))
        .collect();
    let cos_theta: Vec<f64> = angles_deg.iter().map(|a| a.to_radians().cos()).collect();
    let (mut phase, mut ratio) = (vec![0.0; count], vec![0.0; count]);
    if x * m.norm().max(1.0) <= RAYLEIGH_LIMIT_SIZE_PARAMETER {
        // The Rayleigh limit x -> 0 (exact to O((|m| x)^2) <= 1e-16 relative
        // here, where S11 underflows): P = 3 (1 + mu^2) / (16 pi),
        // S12 / S11 = -(1 - mu^2) / (1 + mu^2).
        for ((p, r), &mu) in phase.iter_mut().zip(&mut ratio).zip(&cos_theta) {
            *p = 3.0 * (1.0 + mu * mu) / (16.0 * std::f64::consts::PI);
            // + 0.0: 0, not -0, at the ends.
            *r = -(1.0 - mu * mu) / (1.0 + mu * mu) + 0.0;
        }
    } else {
        let (mut s11, mut s12) = (vec![0.0; count], vec![0.0; count]);
        solution.s11_s12_table(&cos_theta, &mut s11, &mut s12);
        // S11 / (pi x^2 Qsca) is the phase function normalised to 1 over 4 pi sr.
        let qsca = solution.efficiencies().qsca;
        let normalisation = 1.0 / (std::f64::consts::PI * x * x * qsca);
        for i in 0..count {
            ratio[i] = if s11[i] > 0.0 { s12[i] / s11[i] } else { 0.0 };
            phase[i] = s11[i] * normalisation;
        }
        if !normalisation.is_finite() || phase.iter().chain(&ratio).any(|v| !v.is_finite()) {
            bail!(
                "--m {}{:+}i --x {x}: the sphere scatters too weakly for its phase function to be computed in double precision (Q_sca = {qsca:e} underflows); m closer to 1 than about 1e-150 is out of range",
                m.re,
                m.im
            );
        }
    }
    let mut out = BufWriter::new(std::io::stdout().lock());
    writeln!(out, "angle_deg,phase_function_per_sr,s12_over_s11")?;
    for i in 0..count {
        writeln!(out, "{},{:.12e},{:.12e}", angles_deg[i], phase[i], ratio[i])?;
    }
    out.flush()?;
    Ok(())
}

/// The `--batch` form: CSV in (read whole, at most
/// [`sora::input::MAX_INPUT_BYTES`], by [`sora::table::NumericTable`], the
/// library's one CSV reader), CSV out, rows in order; a row the Mie code
/// refuses stops the run with an error naming its line (nothing is written
/// after it).
fn run_batch(path: &PathBuf) -> anyhow::Result<()> {
    let (text, name) = if path.as_os_str() == "-" {
        let name = "stdin".to_string();
        (
            sora::input::read_text_from(std::io::stdin().lock(), &name)?,
            name,
        )
    } else {
        (sora::input::read_text(path)?, path.display().to_string())
    };
    let table = sora::table::NumericTable::parse(&text, &name)?;
    if table.column_names != ["m_re", "m_im", "x"] {
        bail!(
            "{name}, line {}: the header must be m_re,m_im,x, found '{}'",
            table.header_line,
            table.column_names.join(",")
        );
    }
    let mut out = BufWriter::with_capacity(1 << 16, std::io::stdout().lock());
    writeln!(out, "m_re,m_im,x,qext,qsca,qabs,qback,g")?;
    for (row, line_number) in table.rows.iter().zip(&table.line_numbers) {
        let (re, im, x) = (row[0], row[1], row[2]);
        let q = compute_efficiencies(Complex64::new(re, im), x)
            .with_context(|| format!("{name}, line {line_number}"))?;
        writeln!(
            out,
            "{},{},{},{:.16e},{:.16e},{:.16e},{:.16e},{:.16e}",
            shortest_round_trip(re),
            shortest_round_trip(im),
            shortest_round_trip(x),
            q.qext,
            q.qsca,
            q.qabs,
            q.qback,
            q.g
        )?;
    }
    out.flush()?;
    Ok(())
}

/// `value` in the fewest digits that read back as the same double: plain
/// (`1.33`, `0.001`) between 1e-4 and 1e6, in exponent form outside (`5e-324`,
/// not 324 digits; `1e300`, not 301). Both of Rust's forms are the shortest
/// round-trip representation.
fn shortest_round_trip(value: f64) -> String {
    let magnitude = value.abs();
    if value.is_finite() && magnitude != 0.0 && !(1e-4..1e6).contains(&magnitude) {
        format!("{value:e}")
    } else {
        format!("{value}")
    }
}
