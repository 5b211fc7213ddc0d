//! `sora self-test`: a few seconds of reference cases shipped in the binary.
//!
//! Each check prints one line (its name, its worst error against the stored
//! value and the tolerance, `ok` or `FAILED`); any failure makes the command
//! fail (exit status 1). The reference values and their tolerances are those
//! of the project's tests:
//! - Mie efficiencies of single spheres against scattnlay 2.4 in 100-digit
//!   arithmetic (`self_test_mie.csv`, rows of
//!   `crates/sora-mie/tests/data/efficiencies.csv`; 1e-9 relative, Q_back
//!   1e-8, as in `sora-mie/tests/sphere_reference.rs`);
//! - single scattering of the clear-sky reference atmosphere, case (a) (sun
//!   36 deg at azimuth 207, view 17 deg at 347) against the independent
//!   spherical quadrature (`L_single_spherical` of
//!   `crates/sora/tests/data/clear_sky_radiance.csv`; 1e-6 relative, as in
//!   `sora-cli/tests/sky_cli.rs`);
//! - all orders of scattering for the same case, plane-parallel (a planet of
//!   radius 6.36e9 m), against DISORT 32 streams (`L_multi_plane_parallel`;
//!   8e-4 relative, the field's bound in
//!   `sora/src/transport/reference_tests/multiple_scattering_reference.rs`);
//! - every preset atmosphere file parses, matches its preset, and has
//!   finite non-negative optics.

use anyhow::bail;
use clap::Args;
use sora::atmosphere::{Atmosphere, PRESETS, Planet};
use sora::mie::Complex64;
use sora::mie::sphere::compute_efficiencies;
use sora::spectrum::{Spectrum, WavelengthGrid};
use sora::{Scattering, Sky, ViewDirection};

/// Run reference cases shipped in the binary and report each check.
///
/// Checks Mie efficiencies against 100-digit reference values, single and
/// multiple scattering of the clear-sky reference atmosphere against
/// independent radiative-transfer codes (quadrature, DISORT), and that every
/// preset atmosphere file parses. Prints one line per check with its worst
/// relative error and tolerance; exits with status 1 if any check fails.
/// Takes a few seconds.
///
/// Example:
///   sora self-test
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct SelfTestArgs {}

/// Rows of `crates/sora-mie/tests/data/efficiencies.csv` (see its header
/// line for the provenance): m_re,m_im,x,qext,qsca,qabs,qback,g.
const MIE_REFERENCE: &str = include_str!("self_test_mie.csv");

/// Case (a) of the clear-sky reference: (wavelength nm, L_single_spherical,
/// L_multi_plane_parallel), per unit top-of-atmosphere solar irradiance
/// (sr^-1), from `crates/sora/tests/data/clear_sky_radiance.csv` (single
/// scattering by quadrature; DISORT 32 streams for all orders), which copies
/// `../shared/reference/sky/clear_sky_radiance.csv`.
const CASE_A: [(f64, f64, f64); 3] = [
    (380.0, 2.319739874e-02, 5.935491378e-02),
    (400.0, 2.364897365e-02, 5.479498520e-02),
    (780.0, 6.343935200e-03, 8.346120119e-03),
];

const SUN_DEG: (f64, f64) = (36.0, 207.0);
const VIEW_DEG: (f64, f64) = (17.0, 347.0);

/// A group of checks: each returns its outcomes, or fails as a whole.
type CheckGroup = fn() -> anyhow::Result<Vec<Check>>;

/// One check's outcome: its name, whether it passed, and what was measured.
struct Check {
    name: String,
    passed: bool,
    detail: String,
}

impl Check {
    /// A check of a worst relative error against a tolerance (NaN fails).
    fn within(name: String, worst: f64, tolerance: f64) -> Check {
        Check {
            name,
            passed: worst <= tolerance,
            detail: format!("worst relative error {worst:.2e} (tolerance {tolerance:.0e})"),
        }
    }
}

pub fn run(_args: SelfTestArgs) -> anyhow::Result<()> {
    let start = std::time::Instant::now();
    let checks: [(&str, CheckGroup); 4] = [
        ("mie", mie_checks),
        ("single scattering", single_scattering_check),
        ("multiple scattering", multiple_scattering_check),
        ("atmosphere files", atmosphere_file_checks),
    ];
    let mut failures = 0;
    let mut count = 0;
    for (group, check) in checks {
        match check() {
            Ok(results) => {
                for c in results {
                    count += 1;
                    if !c.passed {
                        failures += 1;
                    }
                    println!(
                        "{} {}: {}",
                        if c.passed { "ok    " } else { "FAILED" },
                        c.name,
                        c.detail
                    );
                }
            }
            Err(error) => {
                count += 1;
                failures += 1;
                println!("FAILED {group}: {error:#}");
            }
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    if failures > 0 {
        bail!("self-test: {failures} of {count} checks failed ({seconds:.1} s)");
    }
    println!("self-test: all {count} checks passed ({seconds:.1} s)");
    Ok(())
}

/// Relative error; absolute when the reference is zero.
fn relative_error(value: f64, reference: f64) -> f64 {
    let error = if reference == 0.0 {
        value.abs()
    } else {
        (value - reference).abs() / reference.abs()
    };
    // NaN must fail, never compare as within tolerance.
    if error.is_nan() { f64::INFINITY } else { error }
}

fn mie_checks() -> anyhow::Result<Vec<Check>> {
    let mut checks = Vec::new();
    let table = sora::table::NumericTable::parse(MIE_REFERENCE, "self_test_mie.csv")?;
    let header = "m_re,m_im,x,qext,qsca,qabs,qback,g";
    if table.column_names.join(",") != header {
        bail!("self_test_mie.csv: the header is not {header}");
    }
    for row in &table.rows {
        let [m_re, m_im, x, qext, qsca, qabs, qback, g] = row[..] else {
            bail!("self_test_mie.csv: a row has {} fields, not 8", row.len());
        };
        let m = Complex64::new(m_re, m_im);
        let q = compute_efficiencies(m, x)?;
        let pairs = [
            (q.qext, qext, 1e-9),
            (q.qsca, qsca, 1e-9),
            (q.qabs, qabs, 1e-9),
            (q.qback, qback, 1e-8),
            (q.g, g, 1e-9),
        ];
        let errors = pairs.map(|(value, reference, _)| relative_error(value, reference));
        let worst = [errors[0], errors[1], errors[2], errors[4]]
            .into_iter()
            .fold(0.0, f64::max);
        checks.push(Check {
            name: format!("mie efficiencies, m = {m_re}+{m_im}i, x = {x}, vs 100-digit scattnlay"),
            passed: pairs
                .iter()
                .zip(errors)
                .all(|(&(_, _, tolerance), error)| error <= tolerance),
            detail: format!(
                "worst relative error Qext Qsca Qabs g {worst:.2e} (tolerance 1e-9), Qback {:.2e} (tolerance 1e-8)",
                errors[3]
            ),
        });
    }
    Ok(checks)
}

fn case_a_radiance(atmosphere: &Atmosphere, scattering: Scattering) -> anyhow::Result<Vec<f64>> {
    let sky = Sky::builder(atmosphere)
        .sun_deg(SUN_DEG.0, SUN_DEG.1)
        .scattering(scattering)
        .polarisation(sora::Polarisation::Scalar)
        .build()?;
    let radiance = sky.radiance(ViewDirection::new(VIEW_DEG.0, VIEW_DEG.1)?)?;
    let grid = sky.wavelengths();
    let values = radiance.radiance_w_m2_sr_nm.values();
    CASE_A
        .iter()
        .map(|&(nm, _, _)| {
            grid.wavelengths_nm()
                .zip(values.iter())
                .find(|(w, _)| *w == nm)
                .map(|(_, v)| *v)
                .ok_or_else(|| anyhow::anyhow!("{nm} nm is not on the default grid"))
        })
        .collect()
}

fn single_scattering_check() -> anyhow::Result<Vec<Check>> {
    let atmosphere = Atmosphere::preset("clear-sky-reference")?;
    let got = case_a_radiance(&atmosphere, Scattering::Single)?;
    let worst = CASE_A
        .iter()
        .zip(&got)
        .map(|(&(_, expected, _), &value)| relative_error(value, expected))
        .fold(0.0, f64::max);
    Ok(vec![Check::within(
        "single scattering, clear-sky-reference, sun 36/207, view 17/347, 380 400 780 nm, vs spherical quadrature".into(),
        worst,
        1e-6,
    )])
}

fn multiple_scattering_check() -> anyhow::Result<Vec<Check>> {
    let mut atmosphere = Atmosphere::preset("clear-sky-reference")?;
    let height = atmosphere.planet.atmosphere_height_m();
    atmosphere.planet = Planet::new(6.36e9, height, Spectrum::Constant(0.0))?;
    let got = case_a_radiance(&atmosphere, Scattering::multiple())?;
    let worst = CASE_A
        .iter()
        .zip(&got)
        .map(|(&(_, _, expected), &value)| relative_error(value, expected))
        .fold(0.0, f64::max);
    Ok(vec![Check::within(
        "multiple scattering, plane-parallel clear-sky-reference, same case, vs DISORT 32 streams"
            .into(),
        worst,
        8e-4,
    )])
}

fn atmosphere_file_checks() -> anyhow::Result<Vec<Check>> {
    let grid = WavelengthGrid::new(400.0, 700.0, 100.0)?;
    let mut checks = Vec::new();
    for preset in PRESETS {
        let name = format!("atmosphere file {}", preset.name);
        let parsed = match Atmosphere::from_toml_str(preset.toml) {
            Ok(parsed) => parsed,
            Err(error) => {
                checks.push(Check {
                    name,
                    passed: false,
                    detail: format!("does not parse: {error}"),
                });
                continue;
            }
        };
        let (passed, detail) = if parsed != Atmosphere::preset(preset.name)? {
            (false, "parses, but differs from the preset".to_string())
        } else {
            match parsed.compute_optics(&grid) {
                Err(error) => (false, format!("parses, but its optics fail: {error}")),
                Ok(optics) => {
                    let bad = optics.species.iter().any(|species| {
                        [&species.extinction_per_m, &species.scattering_per_m]
                            .iter()
                            .any(|s| s.values().iter().any(|v| !v.is_finite() || *v < 0.0))
                    });
                    if bad {
                        (
                            false,
                            "parses, but its optics are not finite and non-negative".into(),
                        )
                    } else {
                        (
                            true,
                            format!(
                                "parses, equals the preset, {} species with finite non-negative optics at 400 500 600 700 nm",
                                optics.species.len()
                            ),
                        )
                    }
                }
            }
        };
        checks.push(Check {
            name,
            passed,
            detail,
        });
    }
    Ok(checks)
}
