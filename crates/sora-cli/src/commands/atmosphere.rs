//! `sora atmosphere`: inspect atmospheres. `presets` lists the built-in
//! ones; `show` loads one (a preset or a TOML file), puts it on a
//! wavelength grid and prints, per wavelength and species, the vertical
//! column optical depths (extinction, scattering), the single-scattering
//! albedo and the asymmetry parameter, as a table, CSV or JSON.

use std::fmt::Write as _;
use std::io::Write as _;

use anyhow::Context;
use clap::{Args, Subcommand, ValueEnum};
use serde::Serialize;
use sora::atmosphere::presets::PRESETS;
use sora::atmosphere::{Atmosphere, AtmosphereOptics, PhaseFunction};
use sora::spectrum::{Spectrum, WavelengthGrid};

use crate::arguments::AtmosphereSource;

/// What the sky is made of: built-in atmospheres and the optics of any
/// atmosphere, per wavelength and species.
///
/// Examples:
///   sora atmosphere presets
///   sora atmosphere show --preset earth-clear
///   sora atmosphere show --atmosphere my-planet.toml --wavelengths 400:700:50 --format csv
///
/// An atmosphere is a planet, a sun and a list of species (gases, aerosols),
/// each with a density profile and optical properties. Atmosphere files are
/// TOML, every key carrying its unit (radius_m, scale_height_m, ...); the
/// format, key by key with units, ranges and defaults, is documented in
/// docs/atmosphere-file.md in the repository, and the files in atmospheres/
/// (the presets) are annotated examples.
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct AtmosphereArgs {
    #[command(subcommand)]
    command: AtmosphereCommand,
}

#[derive(Debug, Subcommand)]
enum AtmosphereCommand {
    /// List the built-in atmospheres with a one-line description each
    Presets,
    /// Optical depths, albedo and asymmetry of each species, per wavelength
    ///
    /// For each wavelength and species: tau_extinction and tau_scattering, the
    /// vertical optical depths from the ground to the top of the atmosphere;
    /// single_scattering_albedo = scattering / extinction (0 for a gas that
    /// only absorbs); asymmetry_g = mean cosine of the scattering angle (0 for
    /// air, towards 1 for aerosol that scatters forward).
    ///
    /// Examples:
    ///   sora atmosphere show --preset mars-dust
    ///   sora atmosphere show --atmosphere my-planet.toml --format csv > optics.csv
    #[command(verbatim_doc_comment)]
    Show(ShowArgs),
}

/// The options of `sora atmosphere show`.
#[derive(Debug, Args)]
struct ShowArgs {
    #[command(flatten)]
    source: AtmosphereSource,

    /// Wavelengths, start:stop:step in nm (within 280-2500; colour uses 360-830), or one wavelength
    #[arg(long, value_name = "START:STOP:STEP", default_value = "380:780:20")]
    wavelengths: WavelengthGrid,

    /// Output format: a readable table, CSV (one row per wavelength and
    /// species) or JSON
    #[arg(long, value_enum, default_value_t = Format::Table)]
    format: Format,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Format {
    Table,
    Csv,
    Json,
}

/// The CSV header of `sora atmosphere show --format csv`.
const CSV_HEADER: &str =
    "wavelength_nm,species,tau_extinction,tau_scattering,single_scattering_albedo,asymmetry_g";

pub fn run(args: AtmosphereArgs) -> anyhow::Result<()> {
    let text = match args.command {
        AtmosphereCommand::Presets => presets_listing(),
        AtmosphereCommand::Show(show) => {
            let atmosphere = show.source.load()?;
            let optics = atmosphere
                .compute_optics(&show.wavelengths)
                .with_context(|| format!("atmosphere '{}'", atmosphere.name))?;
            match show.format {
                Format::Table => table(&atmosphere, &optics),
                Format::Csv => csv(&optics),
                Format::Json => json(&atmosphere, &optics)?,
            }
        }
    };
    let mut stdout = std::io::stdout().lock();
    stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
        .context("writing to stdout")
}

fn presets_listing() -> String {
    let width = PRESETS.iter().map(|p| p.name.len()).max().unwrap_or(0);
    let mut out = String::new();
    for preset in &PRESETS {
        let _ = writeln!(out, "{:width$}  {}", preset.name, preset.description);
    }
    out
}

/// A number for CSV: the shortest text that reads back to the same f64, in
/// exponent form when tiny or huge; `null` when not finite (which the
/// library does not produce).
fn number(value: f64) -> String {
    if !value.is_finite() {
        "null".to_string()
    } else if value != 0.0 && !(1e-4..1e15).contains(&value.abs()) {
        format!("{value:e}")
    } else {
        format!("{value}")
    }
}

fn csv(optics: &AtmosphereOptics) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "{CSV_HEADER}");
    for row in optics.summary_rows() {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{}",
            number(row.wavelength_nm),
            crate::csv::cell(row.species),
            number(row.tau_extinction),
            number(row.tau_scattering),
            number(row.single_scattering_albedo),
            number(row.asymmetry_g)
        );
    }
    out
}

fn describe_albedo(albedo: &Spectrum) -> String {
    match albedo {
        Spectrum::Constant(a) => format!("{a}"),
        Spectrum::Tabulated(table) => {
            let (lo, hi) = table.range_nm();
            format!("tabulated {lo}-{hi} nm")
        }
    }
}

fn table(atmosphere: &Atmosphere, optics: &AtmosphereOptics) -> String {
    let mut out = String::new();
    let planet = &atmosphere.planet;
    let sun = &atmosphere.sun;
    let _ = writeln!(out, "{}", atmosphere.name);
    if !atmosphere.description.is_empty() {
        let _ = writeln!(out, "  {}", atmosphere.description);
    }
    let _ = writeln!(
        out,
        "planet: radius {} km, atmosphere {} km thick, ground albedo {}",
        planet.radius_m() / 1e3,
        planet.atmosphere_height_m() / 1e3,
        describe_albedo(planet.ground_albedo())
    );
    let _ = writeln!(
        out,
        "sun: {} x {}, disc {} deg",
        sun.spectrum().name(),
        sun.irradiance_scale(),
        sun.angular_diameter_deg()
    );
    let name_width = optics
        .species
        .iter()
        .map(|s| s.name.chars().count())
        .max()
        .unwrap_or(0)
        .max("species".len());
    let _ = writeln!(out, "species:");
    for species in &optics.species {
        let density = match species.reference_number_density_m3 {
            Some(n) => format!(", {n:.4e} m^-3 at relative density 1"),
            None => String::new(),
        };
        // What a polarised computation (--stokes) does with it.
        let scatters = species.scattering_per_m.values().iter().any(|b| *b > 0.0);
        let polarisation = match species.phase_function {
            _ if !scatters => "",
            PhaseFunction::Tabulated(ref table) if !table.has_matrix_ratios() => {
                ", polarising (its phase matrix is computed for --stokes)"
            }
            ref function if function.is_polarising() => ", polarising",
            _ => ", non-polarising",
        };
        let _ = writeln!(
            out,
            "  {:name_width$}  {}; {}; column {:.1} m{}; phase {}{polarisation}",
            species.name,
            species.kind,
            species.profile.describe(),
            species.vertical_column_m,
            density,
            species.phase_function.kind()
        );
    }
    let _ = writeln!(
        out,
        "\nvertical optical depths, ground to top of the atmosphere ({} wavelengths):",
        optics.grid.len()
    );
    let _ = writeln!(
        out,
        "{:>9}  {:name_width$}  {:>10}  {:>10}  {:>8}  {:>7}",
        "lambda_nm", "species", "tau_ext", "tau_sca", "albedo", "g"
    );
    let total = optics.total_optical_depth_extinction();
    let rows = optics.summary_rows();
    for (i, chunk) in rows.chunks(optics.species.len().max(1)).enumerate() {
        for row in chunk {
            let _ = writeln!(
                out,
                "{:>9}  {:name_width$}  {:>10.6}  {:>10.6}  {:>8.5}  {:>7.4}",
                row.wavelength_nm,
                row.species,
                row.tau_extinction,
                row.tau_scattering,
                row.single_scattering_albedo,
                row.asymmetry_g
            );
        }
        if optics.species.len() > 1 {
            let _ = writeln!(
                out,
                "{:>9}  {:name_width$}  {:>10.6}",
                "", "(total)", total[i]
            );
        }
    }
    out
}

/// `sora atmosphere show --format json` (docs/json.md).
#[derive(Serialize)]
struct AtmosphereJson<'a> {
    name: &'a str,
    description: &'a str,
    planet: PlanetJson,
    sun: SunJson<'a>,
    species: Vec<SpeciesJson<'a>>,
    wavelengths_nm: Vec<f64>,
    optics: Vec<OpticsRowJson<'a>>,
}

#[derive(Serialize)]
struct PlanetJson {
    radius_m: f64,
    atmosphere_height_m: f64,
    /// A number, or for a tabulated albedo its description.
    ground_albedo: AlbedoJson,
}

#[derive(Serialize)]
#[serde(untagged)]
enum AlbedoJson {
    Constant(f64),
    Tabulated(String),
}

#[derive(Serialize)]
struct SunJson<'a> {
    spectrum: &'a str,
    irradiance_scale: f64,
    angular_diameter_deg: f64,
}

#[derive(Serialize)]
struct SpeciesJson<'a> {
    name: &'a str,
    kind: &'a str,
    profile: String,
    vertical_column_m: f64,
    reference_number_density_m3: Option<f64>,
    phase_function: &'a str,
}

/// One row of [`AtmosphereOptics::summary_rows`].
#[derive(Serialize)]
struct OpticsRowJson<'a> {
    wavelength_nm: f64,
    species: &'a str,
    tau_extinction: f64,
    tau_scattering: f64,
    single_scattering_albedo: f64,
    asymmetry_g: f64,
}

fn json(atmosphere: &Atmosphere, optics: &AtmosphereOptics) -> anyhow::Result<String> {
    let planet = &atmosphere.planet;
    let sun = &atmosphere.sun;
    crate::json::to_string(&AtmosphereJson {
        name: &atmosphere.name,
        description: &atmosphere.description,
        planet: PlanetJson {
            radius_m: planet.radius_m(),
            atmosphere_height_m: planet.atmosphere_height_m(),
            ground_albedo: match planet.ground_albedo() {
                Spectrum::Constant(a) => AlbedoJson::Constant(*a),
                albedo @ Spectrum::Tabulated(_) => AlbedoJson::Tabulated(describe_albedo(albedo)),
            },
        },
        sun: SunJson {
            spectrum: sun.spectrum().name(),
            irradiance_scale: sun.irradiance_scale(),
            angular_diameter_deg: sun.angular_diameter_deg(),
        },
        species: optics
            .species
            .iter()
            .map(|species| SpeciesJson {
                name: &species.name,
                kind: species.kind,
                profile: species.profile.describe(),
                vertical_column_m: species.vertical_column_m,
                reference_number_density_m3: species.reference_number_density_m3,
                phase_function: species.phase_function.kind(),
            })
            .collect(),
        wavelengths_nm: optics.grid.wavelengths_nm().collect(),
        optics: optics
            .summary_rows()
            .iter()
            .map(|row| OpticsRowJson {
                wavelength_nm: row.wavelength_nm,
                species: row.species,
                tau_extinction: row.tau_extinction,
                tau_scattering: row.tau_scattering,
                single_scattering_albedo: row.single_scattering_albedo,
                asymmetry_g: row.asymmetry_g,
            })
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_back_exactly() {
        for v in [
            0.0,
            1.0,
            0.4072515344,
            2.546899e25,
            1.16e-5,
            -3.5e-30,
            780.0,
        ] {
            assert_eq!(number(v).parse::<f64>().unwrap(), v, "{}", number(v));
        }
        assert_eq!(number(f64::NAN), "null");
        assert_eq!(number(380.0), "380");
    }
}
