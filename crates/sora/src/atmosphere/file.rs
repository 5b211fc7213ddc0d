//! Atmosphere files: the TOML schema, and the one place where a parsed file
//! becomes validated model types.
//!
//! The format, key by key (units, ranges, defaults, examples), is
//! documented for users in `docs/atmosphere-file.md` in the repository;
//! the serde structs below are its truth, and a test checks that the page
//! lists exactly the keys they accept ([`accepted_keys`]). In short: every
//! quantity carries its unit in its key (`radius_m`, `number_density_m3`,
//! `wavelength_nm`); unknown keys are errors; errors are one line, giving
//! the TOML line or the key as a path
//! (`species[2].profile.exponential.scale_height_m`), the value, its unit
//! and the allowed range.
//!
//! ```toml
//! name = "my planet"
//!
//! [planet]
//! radius_m = 6360e3
//! atmosphere_height_m = 100e3
//!
//! [sun]
//! spectrum = "astm-e490"
//!
//! [[species]]
//! name = "air"
//! number_density_m3 = 2.546899e25
//! profile.exponential.scale_height_m = 8435
//! scattering.rayleigh = { gas = "air", depolarization = true }
//! ```
//!
//! Tables that must cover the wavelength grid (ground albedo, refractive
//! index, absorption cross-section, solar spectrum) are checked against it
//! when the optics are computed ([`super::Atmosphere::compute_optics`]).

use std::fmt;
use std::marker::PhantomData;

use serde::Deserialize;
use serde::de::{self, MapAccess, SeqAccess, Visitor};

use super::aerosol::{AerosolPhase, ParametricAerosol};
use super::gas_bands;
use super::mie_species::{MieAerosol, ParticleAmount};
use super::o2_o2;
use super::ozone::{
    AbsorbingGas, AbsorptionCrossSection, BinnedCrossSection, GasAmount,
    MOLECULES_PER_CM2_PER_DOBSON_UNIT,
};
use super::planet::Planet;
use super::profile::{DensityProfile, ProfileTable};
use super::rayleigh::RayleighGas;
use super::refractive_index::parse_refractive_index_csv;
use super::sun::{EARTH_SUN_ANGULAR_DIAMETER_DEG, Sun};
use super::{Atmosphere, RayleighScatterer, Species, SpeciesModel};
use crate::error::{Error, Result};
use crate::mie::Complex64;
use crate::mie::distribution::{
    MIN_EFFECTIVE_VARIANCE, MIN_GEOMETRIC_STANDARD_DEVIATION, RadiusQuadrature,
    RadiusQuadratureSettings, RadiusWindow, SizeDistribution, SizeDistributionShape,
    TabulatedVolumeDistribution,
};
use crate::mie::paper_phase::AerosolPhaseMode;
use crate::mie::refractive_index::{
    MARS_DUST_WOLFF2009_CSV, RefractiveIndexModel, TabulatedRefractiveIndex,
};
use crate::spectrum::{MIN_WAVELENGTH_NM, SolarSpectrum, Spectrum, TabulatedSpectrum};

/// Names of the built-in refractive-index tables (`refractive_index.builtin`).
pub const BUILTIN_REFRACTIVE_INDICES: [&str; 1] = ["mars-dust-wolff2009"];

/// The built-in refractive index table `name`, if there is one.
pub(crate) fn builtin_refractive_index(name: &str) -> Option<TabulatedRefractiveIndex> {
    match name {
        "mars-dust-wolff2009" => Some(
            parse_refractive_index_csv(MARS_DUST_WOLFF2009_CSV, "built-in refractive index table")
                .expect("the embedded Mars dust table is valid"),
        ),
        _ => None,
    }
}

// ---------------------------------------------------------------------------
// The schema: what serde reads. Every struct rejects unknown keys.
// ---------------------------------------------------------------------------

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AtmosphereFile {
    name: String,
    description: Option<String>,
    planet: PlanetFile,
    sun: SunFile,
    #[serde(default)]
    species: Vec<SpeciesFile>,
    gases: Option<GasesFile>,
}

/// `[gases]`: the banded gases of `gas_bands.rs`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct GasesFile {
    precipitable_water_cm: f64,
    water_scale_height_m: Option<f64>,
    mixed_gases: Option<bool>,
    co2_ppm: Option<f64>,
    ch4_ppm: Option<f64>,
    o2_o2: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanetFile {
    radius_m: f64,
    atmosphere_height_m: f64,
    ground_altitude_m: Option<f64>,
    ground_albedo: Option<NumberOr<AlbedoTableFile>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AlbedoTableFile {
    wavelength_nm: Vec<f64>,
    albedo: Vec<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SunFile {
    spectrum: String,
    irradiance_w_m2_nm: Option<f64>,
    csv_file: Option<String>,
    irradiance_scale: Option<f64>,
    angular_diameter_deg: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpeciesFile {
    name: String,
    number_density_m3: Option<f64>,
    optical_depth: Option<f64>,
    reference_wavelength_nm: Option<f64>,
    column_dobson_units: Option<f64>,
    column_molecules_cm2: Option<f64>,
    profile: ProfileFile,
    scattering: Option<ScatteringFile>,
    absorption: Option<AbsorptionFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ProfileFile {
    exponential: Option<ExponentialFile>,
    tent: Option<TentFile>,
    layers: Option<ProfileTableFile>,
    table: Option<ProfileTableFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ExponentialFile {
    scale_height_m: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TentFile {
    peak_altitude_m: f64,
    half_width_m: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ProfileTableFile {
    altitude_m: Vec<f64>,
    relative_density: Vec<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScatteringFile {
    rayleigh: Option<RayleighFile>,
    mie: Option<MieFile>,
    parametric: Option<ParametricFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RayleighFile {
    gas: Option<String>,
    depolarization: Option<bool>,
    coefficient_per_m: Option<f64>,
    reference_wavelength_nm: Option<f64>,
    wavelength_exponent: Option<f64>,
    depolarization_ratio: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ParametricFile {
    angstrom_exponent: f64,
    single_scattering_albedo: f64,
    phase: AerosolPhaseFile,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AerosolPhaseFile {
    henyey_greenstein: Option<AsymmetryFile>,
    cornette_shanks: Option<AsymmetryFile>,
    tabulated: Option<TabulatedPhaseFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TabulatedPhaseFile {
    angle_deg: Vec<f64>,
    value: Vec<f64>,
    f12_over_f11: Option<Vec<f64>>,
    f33_over_f11: Option<Vec<f64>>,
    f34_over_f11: Option<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AsymmetryFile {
    g: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MieFile {
    refractive_index: RefractiveIndexFile,
    size_distribution: SizeDistributionFile,
    phase: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RefractiveIndexFile {
    builtin: Option<String>,
    wavelength_nm: Option<Vec<f64>>,
    n: Option<NumberOr<Vec<f64>>>,
    k: Option<NumberOr<Vec<f64>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SizeDistributionFile {
    lognormal: Option<LognormalFile>,
    gamma: Option<GammaFile>,
    tabulated: Option<TabulatedSizeFile>,
}

/// A measured volume size distribution: dV/dlnr (um^3 um^-2) at radii (um).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TabulatedSizeFile {
    radius_um: Vec<f64>,
    dv_dlnr_um3_per_um2: Vec<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LognormalFile {
    median_radius_um: Option<f64>,
    geometric_std_dev: Option<f64>,
    effective_radius_um: Option<f64>,
    effective_variance: Option<f64>,
    min_radius_um: Option<f64>,
    max_radius_um: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct GammaFile {
    effective_radius_um: f64,
    effective_variance: f64,
    min_radius_um: Option<f64>,
    max_radius_um: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AbsorptionFile {
    gas: Option<String>,
    wavelength_nm: Option<Vec<f64>>,
    cross_section_m2: Option<Vec<f64>>,
}

/// A key that holds either a number or something else (an array, a table).
#[derive(Debug)]
enum NumberOr<T> {
    Number(f64),
    Other(T),
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for NumberOr<T> {
    fn deserialize<D: de::Deserializer<'de>>(
        deserializer: D,
    ) -> std::result::Result<Self, D::Error> {
        struct NumberOrVisitor<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for NumberOrVisitor<T> {
            type Value = NumberOr<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number, or an array or table of numbers")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Self::Value, E> {
                Ok(NumberOr::Number(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Self::Value, E> {
                Ok(NumberOr::Number(v as f64))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Self::Value, E> {
                Ok(NumberOr::Number(v))
            }
            fn visit_seq<A: SeqAccess<'de>>(
                self,
                seq: A,
            ) -> std::result::Result<Self::Value, A::Error> {
                T::deserialize(de::value::SeqAccessDeserializer::new(seq)).map(NumberOr::Other)
            }
            fn visit_map<A: MapAccess<'de>>(
                self,
                map: A,
            ) -> std::result::Result<Self::Value, A::Error> {
                T::deserialize(de::value::MapAccessDeserializer::new(map)).map(NumberOr::Other)
            }
        }
        deserializer.deserialize_any(NumberOrVisitor(PhantomData))
    }
}

// ---------------------------------------------------------------------------
// Validation: file structs -> model types.
// ---------------------------------------------------------------------------

/// Parses `text` and validates it into an [`Atmosphere`]; `read_file`
/// supplies the text of files the atmosphere names.
pub(crate) fn parse_atmosphere(
    text: &str,
    read_file: &mut dyn FnMut(&str) -> std::result::Result<String, String>,
) -> Result<Atmosphere> {
    let file: AtmosphereFile = toml::from_str(text).map_err(|e| syntax_error(text, &e))?;
    if file.name.trim().is_empty() {
        return Err(invalid("name", "must not be empty"));
    }
    let planet = convert_planet(file.planet)?;
    let sun = convert_sun(file.sun, read_file)?;
    let mut species = Vec::with_capacity(file.species.len());
    for (index, species_file) in file.species.into_iter().enumerate() {
        let path = format!("species[{index}]");
        if species_file.name.trim().is_empty() {
            return Err(invalid(&format!("{path}.name"), "must not be empty"));
        }
        if let Some(first) = species
            .iter()
            .position(|s: &Species| s.name == species_file.name)
        {
            return Err(invalid(
                &format!("{path}.name"),
                &format!(
                    "'{}' is already the name of species[{first}]",
                    species_file.name
                ),
            ));
        }
        species.push(convert_species(species_file, &path, &planet)?);
    }
    if let Some(gases) = file.gases {
        let o2_o2 = if gases.o2_o2.unwrap_or(false) {
            Some(o2_o2::o2_o2_species(&species).map_err(|e| invalid("gases.o2_o2", &e))?)
        } else {
            None
        };
        species.extend(convert_gases(gases)?);
        species.extend(o2_o2);
        // The gases' species are named by sora; a file's own species of the
        // same name would make outputs ambiguous.
        for (index, s) in species.iter().enumerate() {
            if let Some(later) = species[index + 1..].iter().position(|t| t.name == s.name) {
                return Err(invalid(
                    &format!("species[{index}].name"),
                    &format!(
                        "'{}' is the name [gases] gives its species[{}]: rename it",
                        s.name,
                        index + 1 + later
                    ),
                ));
            }
        }
    }
    Ok(Atmosphere {
        name: file.name,
        description: file.description.unwrap_or_default(),
        planet,
        sun,
        species,
    })
}

/// The `[gases]` table as species (`gas_bands.rs`).
fn convert_gases(gases: GasesFile) -> Result<Vec<Species>> {
    let water = check(
        "gases.precipitable_water_cm",
        gases.precipitable_water_cm,
        "cm",
        "0..=15",
        (0.0..=15.0).contains(&gases.precipitable_water_cm),
    )?;
    let scale = match gases.water_scale_height_m {
        Some(h) => check(
            "gases.water_scale_height_m",
            h,
            "m",
            "100..=20000",
            (100.0..=20_000.0).contains(&h),
        )?,
        None => gas_bands::WATER_SCALE_HEIGHT_M,
    };
    let mixed_gases = gases.mixed_gases.unwrap_or(true);
    let co2_ppm = match gases.co2_ppm {
        Some(_) if !mixed_gases => {
            return Err(invalid(
                "gases.co2_ppm",
                "goes with the O2 and CO2 bands, but mixed_gases = false",
            ));
        }
        Some(ppm) => check_range("gases.co2_ppm", ppm, "ppm", 0.0, 10_000.0)?,
        None => gas_bands::CO2_REFERENCE_PPM,
    };
    let ch4_ppm = match gases.ch4_ppm {
        Some(ppm) => check_range("gases.ch4_ppm", ppm, "ppm", 0.0, 1000.0)?,
        None => 0.0,
    };
    Ok(gas_bands::banded_gas_species(&gas_bands::BandedGases {
        water: Some((water, scale)),
        mixed_gases,
        co2_ppm,
        ch4_ppm,
    }))
}

/// A TOML syntax or type error as one line with its line number.
fn syntax_error(text: &str, e: &toml::de::Error) -> Error {
    let line = e
        .span()
        .map(|span| text[..span.start.min(text.len())].matches('\n').count() + 1)
        .unwrap_or(0);
    let message = e.message().trim().replace('\n', "; ");
    Error::parse("atmosphere file", line, message)
}

/// A structural error at `path` (a missing or conflicting key).
fn invalid(path: &str, message: &str) -> Error {
    Error::parse("atmosphere file", 0, format!("{path}: {message}"))
}

/// `value` must satisfy `ok`; else an out-of-range error at `path`.
fn check(path: &str, value: f64, unit: &'static str, allowed: &str, ok: bool) -> Result<f64> {
    if ok && value.is_finite() {
        Ok(value)
    } else {
        Err(Error::out_of_range(path, value, unit, allowed))
    }
}

fn check_range(path: &str, value: f64, unit: &'static str, lo: f64, hi: f64) -> Result<f64> {
    check(
        path,
        value,
        unit,
        &format!("{lo}..={hi}"),
        (lo..=hi).contains(&value),
    )
}

fn check_wavelength(path: &str, value: f64) -> Result<f64> {
    check_range(path, value, "nm", 100.0, 100_000.0)
}

/// `key` is not used by this kind of species.
fn not_used(path: &str, key: &str, present: bool, kind: &str, instead: &str) -> Result<()> {
    if present {
        Err(invalid(
            &format!("{path}.{key}"),
            &format!("is not used by {kind} ({instead})"),
        ))
    } else {
        Ok(())
    }
}

fn convert_planet(file: PlanetFile) -> Result<Planet> {
    let albedo = match file.ground_albedo {
        None => Spectrum::Constant(0.0),
        Some(NumberOr::Number(a)) => Spectrum::Constant(a),
        Some(NumberOr::Other(table)) => Spectrum::Tabulated(
            TabulatedSpectrum::new(table.wavelength_nm, table.albedo, "planet.ground_albedo")
                .map_err(|e| table_error(&e))?,
        ),
    };
    Planet::new(file.radius_m, file.atmosphere_height_m, albedo)?
        .with_ground_altitude_m(file.ground_altitude_m.unwrap_or(0.0))
}

fn convert_sun(
    file: SunFile,
    read_file: &mut dyn FnMut(&str) -> std::result::Result<String, String>,
) -> Result<Sun> {
    let spectrum = match file.spectrum.as_str() {
        "flat" => {
            not_used(
                "sun",
                "csv_file",
                file.csv_file.is_some(),
                "a flat sun",
                "give csv_file with spectrum = \"csv\"",
            )?;
            let Some(irradiance) = file.irradiance_w_m2_nm else {
                return Err(invalid(
                    "sun.irradiance_w_m2_nm",
                    "is required with spectrum = \"flat\" (the irradiance at every wavelength, W m^-2 nm^-1)",
                ));
            };
            check(
                "sun.irradiance_w_m2_nm",
                irradiance,
                "W m^-2 nm^-1",
                "> 0",
                irradiance > 0.0,
            )?;
            SolarSpectrum::flat(irradiance)?
        }
        "astm-e490" => {
            not_used(
                "sun",
                "irradiance_w_m2_nm",
                file.irradiance_w_m2_nm.is_some(),
                "the ASTM E490 spectrum",
                "scale it with irradiance_scale",
            )?;
            not_used(
                "sun",
                "csv_file",
                file.csv_file.is_some(),
                "the ASTM E490 spectrum",
                "give csv_file with spectrum = \"csv\"",
            )?;
            SolarSpectrum::astm_e490()
        }
        "csv" => {
            not_used(
                "sun",
                "irradiance_w_m2_nm",
                file.irradiance_w_m2_nm.is_some(),
                "a CSV spectrum",
                "scale it with irradiance_scale",
            )?;
            let Some(path) = file.csv_file else {
                return Err(invalid(
                    "sun.csv_file",
                    "is required with spectrum = \"csv\" (a table wavelength_nm,irradiance_w_m2_nm)",
                ));
            };
            let text = read_file(&path)
                .map_err(|reason| invalid("sun.csv_file", &format!("cannot read it: {reason}")))?;
            SolarSpectrum::parse_csv(&text, &path)?
        }
        other => {
            return Err(invalid(
                "sun.spectrum",
                &format!(
                    "'{other}' is not a known spectrum: use \"flat\", \"astm-e490\" or \"csv\""
                ),
            ));
        }
    };
    Sun::new(
        spectrum,
        file.irradiance_scale.unwrap_or(1.0),
        file.angular_diameter_deg
            .unwrap_or(EARTH_SUN_ANGULAR_DIAMETER_DEG),
    )
}

fn convert_profile(file: ProfileFile, path: &str, planet: &Planet) -> Result<DensityProfile> {
    let path = format!("{path}.profile");
    let given = [
        file.exponential.is_some(),
        file.tent.is_some(),
        file.layers.is_some(),
        file.table.is_some(),
    ];
    if given.iter().filter(|g| **g).count() != 1 {
        return Err(invalid(
            &path,
            "give exactly one of exponential, tent, layers, table",
        ));
    }
    let top_m = planet.top_above_sea_level_m();
    let profile = if let Some(exponential) = file.exponential {
        DensityProfile::exponential(
            exponential.scale_height_m,
            &format!("{path}.exponential.scale_height_m"),
        )?
    } else if let Some(tent) = file.tent {
        DensityProfile::tent(
            tent.peak_altitude_m,
            tent.half_width_m,
            &format!("{path}.tent"),
        )?
    } else if let Some(layers) = file.layers {
        DensityProfile::PiecewiseLinear(ProfileTable::new(
            layers.altitude_m,
            layers.relative_density,
            false,
            &format!("{path}.layers"),
        )?)
    } else {
        let table = file.table.expect("exactly one profile kind is present");
        let name = format!("{path}.table");
        let table = ProfileTable::new(table.altitude_m, table.relative_density, true, &name)?;
        let altitudes = table.altitudes_m();
        if altitudes[0] > 0.0 {
            return Err(Error::out_of_range(
                format!("{name}.altitude_m[0]"),
                altitudes[0],
                "m",
                "the table must start at or below the ground: <= 0",
            ));
        }
        let last = altitudes.len() - 1;
        if altitudes[last] < top_m {
            return Err(Error::out_of_range(
                format!("{name}.altitude_m[{last}]"),
                altitudes[last],
                "m",
                format!(
                    "the table must reach the top of the atmosphere, planet.atmosphere_height_m: >= {top_m}"
                ),
            ));
        }
        DensityProfile::LogLinear(table)
    };
    let column_m = profile.vertical_column_m(top_m);
    if !(column_m > 0.0 && column_m.is_finite()) {
        return Err(invalid(
            &path,
            &format!(
                "the profile has no density between the ground and the top of the atmosphere ({top_m} m)"
            ),
        ));
    }
    Ok(profile)
}

fn convert_species(file: SpeciesFile, path: &str, planet: &Planet) -> Result<Species> {
    let profile = convert_profile(file.profile, path, planet)?;
    if let Some(n) = file.number_density_m3 {
        check(
            &format!("{path}.number_density_m3"),
            n,
            "m^-3",
            ">= 0 and <= 1e35",
            (0.0..=1e35).contains(&n),
        )?;
    }
    if let Some(tau) = file.optical_depth {
        check_range(&format!("{path}.optical_depth"), tau, "1", 0.0, 1000.0)?;
    }
    if let Some(w) = file.reference_wavelength_nm {
        check_wavelength(&format!("{path}.reference_wavelength_nm"), w)?;
        if file.optical_depth.is_none() {
            return Err(invalid(
                &format!("{path}.reference_wavelength_nm"),
                "goes with optical_depth (the wavelength at which it is given), which is missing",
            ));
        }
    }
    if let Some(du) = file.column_dobson_units {
        check_range(&format!("{path}.column_dobson_units"), du, "DU", 0.0, 1e6)?;
    }
    if let Some(n) = file.column_molecules_cm2 {
        // The same range as column_dobson_units' 0..=1e6 DU.
        check(
            &format!("{path}.column_molecules_cm2"),
            n,
            "molecules cm^-2",
            "0..=2.6867e22",
            (0.0..=1e6 * MOLECULES_PER_CM2_PER_DOBSON_UNIT).contains(&n),
        )?;
    }
    let column_dobson_units = match (file.column_dobson_units, file.column_molecules_cm2) {
        (Some(_), Some(_)) => {
            return Err(invalid(
                path,
                "give the column as column_dobson_units or column_molecules_cm2, not both",
            ));
        }
        (du, None) => du,
        (None, Some(n)) => Some(n / MOLECULES_PER_CM2_PER_DOBSON_UNIT),
    };
    let keys = AmountKeys {
        number_density_m3: file.number_density_m3,
        optical_depth: file.optical_depth,
        reference_wavelength_nm: file.reference_wavelength_nm,
        column_dobson_units,
        column_key: if file.column_molecules_cm2.is_some() {
            "column_molecules_cm2"
        } else {
            "column_dobson_units"
        },
    };
    // Each converter takes the amount keys its model uses and rejects the others.
    let model = match (file.scattering, file.absorption) {
        (Some(scattering), None) => convert_scattering(scattering, path, &keys)?,
        (None, Some(absorption)) => convert_absorption(absorption, path, &keys)?,
        (Some(_), Some(_)) => {
            return Err(invalid(
                path,
                "give either scattering or absorption, not both (make two species)",
            ));
        }
        (None, None) => {
            return Err(invalid(
                path,
                "needs an optical model: scattering.rayleigh, scattering.mie, scattering.parametric or absorption",
            ));
        }
    };
    Ok(Species {
        name: file.name,
        profile,
        model,
    })
}

/// The amount keys of a species (how much of it there is).
#[derive(Debug, Clone, Copy)]
struct AmountKeys {
    number_density_m3: Option<f64>,
    optical_depth: Option<f64>,
    reference_wavelength_nm: Option<f64>,
    /// The column in DU, from `column_dobson_units` or
    /// `column_molecules_cm2`.
    column_dobson_units: Option<f64>,
    /// Which of the two keys gave the column (for errors).
    column_key: &'static str,
}

fn convert_scattering(file: ScatteringFile, path: &str, keys: &AmountKeys) -> Result<SpeciesModel> {
    let given = [
        file.rayleigh.is_some(),
        file.mie.is_some(),
        file.parametric.is_some(),
    ];
    if given.iter().filter(|g| **g).count() != 1 {
        return Err(invalid(
            &format!("{path}.scattering"),
            "give exactly one of rayleigh, mie, parametric",
        ));
    }
    not_used(
        path,
        keys.column_key,
        keys.column_dobson_units.is_some(),
        "a scattering species",
        "only an absorbing gas takes a column (Dobson units or molecules cm^-2)",
    )?;
    if let Some(rayleigh) = file.rayleigh {
        return convert_rayleigh(rayleigh, path, keys);
    }
    if let Some(parametric) = file.parametric {
        return convert_parametric(parametric, path, keys);
    }
    convert_mie(
        file.mie.expect("exactly one scattering kind is present"),
        path,
        keys,
    )
}

fn convert_rayleigh(file: RayleighFile, path: &str, keys: &AmountKeys) -> Result<SpeciesModel> {
    let here = format!("{path}.scattering.rayleigh");
    match (file.gas, file.coefficient_per_m) {
        (Some(gas), None) => {
            let gas = match gas.as_str() {
                "air" => RayleighGas::Air,
                "co2" => RayleighGas::Co2,
                other => {
                    return Err(invalid(
                        &format!("{here}.gas"),
                        &format!("'{other}' is not a known gas: use \"air\" or \"co2\""),
                    ));
                }
            };
            let kind = "a Rayleigh gas";
            for (key, present) in [
                (
                    "reference_wavelength_nm",
                    file.reference_wavelength_nm.is_some(),
                ),
                ("wavelength_exponent", file.wavelength_exponent.is_some()),
                ("depolarization_ratio", file.depolarization_ratio.is_some()),
            ] {
                not_used(
                    &here,
                    key,
                    present,
                    kind,
                    "they belong to coefficient_per_m; a gas' depolarisation comes from its King factor with depolarization = true",
                )?;
            }
            not_used(
                path,
                "optical_depth",
                keys.optical_depth.is_some(),
                kind,
                "give number_density_m3",
            )?;
            let Some(number_density_m3) = keys.number_density_m3 else {
                return Err(invalid(
                    &format!("{path}.number_density_m3"),
                    "is required for a Rayleigh gas (molecules per m^3 at relative density 1)",
                ));
            };
            Ok(SpeciesModel::Rayleigh(RayleighScatterer::Gas {
                gas,
                number_density_m3,
                depolarization: file.depolarization.unwrap_or(false),
            }))
        }
        (None, Some(coefficient_per_m)) => {
            let kind = "a parametric Rayleigh species";
            not_used(
                &here,
                "depolarization",
                file.depolarization.is_some(),
                kind,
                "give depolarization_ratio",
            )?;
            not_used(
                path,
                "number_density_m3",
                keys.number_density_m3.is_some(),
                kind,
                "its amount is coefficient_per_m",
            )?;
            not_used(
                path,
                "optical_depth",
                keys.optical_depth.is_some(),
                kind,
                "its amount is coefficient_per_m",
            )?;
            check(
                &format!("{here}.coefficient_per_m"),
                coefficient_per_m,
                "m^-1",
                ">= 0",
                coefficient_per_m >= 0.0,
            )?;
            let Some(reference_wavelength_nm) = file.reference_wavelength_nm else {
                return Err(invalid(
                    &format!("{here}.reference_wavelength_nm"),
                    "is required with coefficient_per_m (the wavelength at which it is given)",
                ));
            };
            check_wavelength(
                &format!("{here}.reference_wavelength_nm"),
                reference_wavelength_nm,
            )?;
            let wavelength_exponent = file.wavelength_exponent.unwrap_or(4.0);
            check_range(
                &format!("{here}.wavelength_exponent"),
                wavelength_exponent,
                "1",
                -10.0,
                10.0,
            )?;
            let depolarization_ratio = file.depolarization_ratio.unwrap_or(0.0);
            check_range(
                &format!("{here}.depolarization_ratio"),
                depolarization_ratio,
                "1",
                0.0,
                1.0,
            )?;
            Ok(SpeciesModel::Rayleigh(RayleighScatterer::Parametric {
                coefficient_per_m,
                reference_wavelength_nm,
                wavelength_exponent,
                depolarization_ratio,
            }))
        }
        (Some(_), Some(_)) => Err(invalid(
            &here,
            "give either gas (physical) or coefficient_per_m (parametric), not both",
        )),
        (None, None) => Err(invalid(
            &here,
            "give gas (\"air\" or \"co2\", with number_density_m3) or coefficient_per_m",
        )),
    }
}

/// `optical_depth` + `reference_wavelength_nm` of a species, both required.
fn optical_depth_at_reference(path: &str, keys: &AmountKeys, kind: &str) -> Result<(f64, f64)> {
    match (keys.optical_depth, keys.reference_wavelength_nm) {
        (Some(tau), Some(w)) => Ok((tau, w)),
        (None, _) => Err(invalid(
            &format!("{path}.optical_depth"),
            &format!(
                "is required for {kind} (the column extinction optical depth at reference_wavelength_nm)"
            ),
        )),
        (Some(_), None) => Err(invalid(
            &format!("{path}.reference_wavelength_nm"),
            "is required with optical_depth (the wavelength at which it is given)",
        )),
    }
}

fn check_asymmetry(path: &str, g: f64) -> Result<f64> {
    check(path, g, "1", "-1 < g < 1", g > -1.0 && g < 1.0)
}

fn convert_parametric(file: ParametricFile, path: &str, keys: &AmountKeys) -> Result<SpeciesModel> {
    let here = format!("{path}.scattering.parametric");
    let kind = "a parametric aerosol";
    not_used(
        path,
        "number_density_m3",
        keys.number_density_m3.is_some(),
        kind,
        "its amount is optical_depth",
    )?;
    let (optical_depth, reference_wavelength_nm) = optical_depth_at_reference(path, keys, kind)?;
    let angstrom_exponent = check_range(
        &format!("{here}.angstrom_exponent"),
        file.angstrom_exponent,
        "1",
        -10.0,
        10.0,
    )?;
    let single_scattering_albedo = check_range(
        &format!("{here}.single_scattering_albedo"),
        file.single_scattering_albedo,
        "1",
        0.0,
        1.0,
    )?;
    let phase = match (
        file.phase.henyey_greenstein,
        file.phase.cornette_shanks,
        file.phase.tabulated,
    ) {
        (Some(hg), None, None) => AerosolPhase::HenyeyGreenstein {
            g: check_asymmetry(&format!("{here}.phase.henyey_greenstein.g"), hg.g)?,
        },
        (None, Some(cs), None) => AerosolPhase::CornetteShanks {
            g: check_asymmetry(&format!("{here}.phase.cornette_shanks.g"), cs.g)?,
        },
        (None, None, Some(table)) => {
            convert_tabulated_phase(table, &format!("{here}.phase.tabulated"))?
        }
        _ => {
            return Err(invalid(
                &format!("{here}.phase"),
                "give exactly one of henyey_greenstein, cornette_shanks, tabulated",
            ));
        }
    };
    Ok(SpeciesModel::ParametricAerosol(ParametricAerosol {
        optical_depth,
        reference_wavelength_nm,
        angstrom_exponent,
        single_scattering_albedo,
        phase,
    }))
}

/// A tabulated phase function: scattering angles from exactly 0 to exactly
/// 180 degrees, increasing, and values >= 0 (any normalisation, not all
/// zero), linear in cos theta between the angles.
fn convert_tabulated_phase(file: TabulatedPhaseFile, here: &str) -> Result<AerosolPhase> {
    let TabulatedPhaseFile {
        angle_deg,
        value,
        f12_over_f11,
        f33_over_f11,
        f34_over_f11,
    } = file;
    if angle_deg.len() != value.len() || angle_deg.len() < 2 {
        return Err(invalid(
            here,
            &format!(
                "angle_deg and value need the same length, at least 2 (got {} and {})",
                angle_deg.len(),
                value.len()
            ),
        ));
    }
    if angle_deg[0] != 0.0 || angle_deg[angle_deg.len() - 1] != 180.0 {
        return Err(invalid(
            &format!("{here}.angle_deg"),
            &format!(
                "must run from 0 to 180 deg (got {} to {} deg)",
                angle_deg[0],
                angle_deg[angle_deg.len() - 1]
            ),
        ));
    }
    for (i, a) in angle_deg.iter().enumerate() {
        check(
            &format!("{here}.angle_deg[{i}]"),
            *a,
            "deg",
            "0..=180",
            (0.0..=180.0).contains(a),
        )?;
    }
    if let Some(i) = angle_deg.windows(2).position(|w| w[1] <= w[0]) {
        return Err(invalid(
            &format!("{here}.angle_deg[{}]", i + 1),
            &format!(
                "angles must increase, but {} deg follows {} deg",
                angle_deg[i + 1],
                angle_deg[i]
            ),
        ));
    }
    for (i, v) in value.iter().enumerate() {
        check(
            &format!("{here}.value[{i}]"),
            *v,
            "1",
            ">= 0",
            v.is_finite() && *v >= 0.0,
        )?;
    }
    // Nodes in increasing cos theta: from 180 deg (-1) to 0 deg (1), the
    // ends exact.
    let last = angle_deg.len() - 1;
    let cos_theta: Vec<f64> = (0..=last)
        .rev()
        .map(|i| match i {
            0 => 1.0,
            i if i == last => -1.0,
            i => angle_deg[i].to_radians().cos(),
        })
        .collect();
    if let Some(i) = cos_theta.windows(2).position(|w| w[1] <= w[0]) {
        return Err(invalid(
            &format!("{here}.angle_deg"),
            &format!(
                "angles {} and {} deg are too close to tell apart in cos theta",
                angle_deg[last - i - 1],
                angle_deg[last - i]
            ),
        ));
    }
    // The phase matrix: all three ratios or none (non-polarising).
    let count = angle_deg.len();
    let ratio = |name: &str, column: Option<Vec<f64>>, none: f64| -> Result<Vec<f64>> {
        let Some(column) = column else {
            return Ok(vec![none; count]);
        };
        if column.len() != count {
            return Err(invalid(
                &format!("{here}.{name}"),
                &format!("needs one value per angle ({count}), got {}", column.len()),
            ));
        }
        for (i, v) in column.iter().enumerate() {
            check(
                &format!("{here}.{name}[{i}]"),
                *v,
                "1",
                "-1..=1",
                (-1.0..=1.0).contains(v),
            )?;
        }
        Ok(column.into_iter().rev().collect())
    };
    let given = [&f12_over_f11, &f33_over_f11, &f34_over_f11]
        .iter()
        .filter(|c| c.is_some())
        .count();
    if given != 0 && given != 3 {
        return Err(invalid(
            here,
            "give all three of f12_over_f11, f33_over_f11, f34_over_f11 (the phase matrix), or none (non-polarising)",
        ));
    }
    let ratios = crate::mie::ensemble::PhaseMatrixRatios {
        cos_theta: cos_theta.clone(),
        f12_over_f11: ratio("f12_over_f11", f12_over_f11, 0.0)?,
        f33_over_f11: ratio("f33_over_f11", f33_over_f11, 1.0)?,
        f34_over_f11: ratio("f34_over_f11", f34_over_f11, 0.0)?,
    };
    let values: Vec<f64> = value.into_iter().rev().collect();
    let table = crate::mie::ensemble::TabulatedPhaseFunction::from_nodes(cos_theta, values)
        .map_err(|e| invalid(&format!("{here}.value"), &e.to_string()))?;
    Ok(AerosolPhase::Tabulated { table, ratios })
}

fn convert_refractive_index(file: RefractiveIndexFile, here: &str) -> Result<RefractiveIndexModel> {
    let here = format!("{here}.refractive_index");
    if let Some(name) = file.builtin {
        if file.n.is_some() || file.k.is_some() || file.wavelength_nm.is_some() {
            return Err(invalid(&here, "give either builtin or n and k, not both"));
        }
        return builtin_refractive_index(&name)
            .map(RefractiveIndexModel::Tabulated)
            .ok_or_else(|| {
                invalid(
                    &format!("{here}.builtin"),
                    &format!("'{name}' is not a built-in table: use one of {BUILTIN_REFRACTIVE_INDICES:?}"),
                )
            });
    }
    let (Some(n), Some(k)) = (file.n, file.k) else {
        return Err(invalid(
            &here,
            "give n and k (numbers, or arrays with wavelength_nm), or builtin",
        ));
    };
    let check_n = |i: Option<usize>, v: f64| {
        let key = match i {
            Some(i) => format!("{here}.n[{i}]"),
            None => format!("{here}.n"),
        };
        check(&key, v, "1", "> 0 and <= 10", v > 0.0 && v <= 10.0)
    };
    let check_k = |i: Option<usize>, v: f64| {
        let key = match i {
            Some(i) => format!("{here}.k[{i}]"),
            None => format!("{here}.k"),
        };
        check(
            &key,
            v,
            "1",
            ">= 0 and <= 10 (absorption)",
            (0.0..=10.0).contains(&v),
        )
    };
    match (n, k, file.wavelength_nm) {
        (NumberOr::Number(n), NumberOr::Number(k), None) => {
            check_n(None, n)?;
            check_k(None, k)?;
            RefractiveIndexModel::constant(Complex64::new(n, k))
                .map_err(|e| invalid(&here, &e.to_string()))
        }
        (NumberOr::Other(n), NumberOr::Other(k), Some(wavelengths)) => {
            if n.len() != wavelengths.len() || k.len() != wavelengths.len() || wavelengths.len() < 2
            {
                return Err(invalid(
                    &here,
                    &format!(
                        "wavelength_nm, n and k need the same number of rows, at least 2 (got {}, {} and {})",
                        wavelengths.len(),
                        n.len(),
                        k.len()
                    ),
                ));
            }
            for (i, w) in wavelengths.iter().enumerate() {
                check_wavelength(&format!("{here}.wavelength_nm[{i}]"), *w)?;
            }
            for (i, v) in n.iter().enumerate() {
                check_n(Some(i), *v)?;
            }
            for (i, v) in k.iter().enumerate() {
                check_k(Some(i), *v)?;
            }
            TabulatedRefractiveIndex::from_columns(wavelengths, n, k)
                .map(RefractiveIndexModel::Tabulated)
                .map_err(|e| invalid(&here, &e.to_string()))
        }
        (NumberOr::Number(_), NumberOr::Number(_), Some(_)) => Err(invalid(
            &format!("{here}.wavelength_nm"),
            "goes with arrays of n and k; constant n and k need no wavelengths",
        )),
        (NumberOr::Other(_), NumberOr::Other(_), None) => Err(invalid(
            &format!("{here}.wavelength_nm"),
            "is required when n and k are arrays (one wavelength per row)",
        )),
        _ => Err(invalid(
            &here,
            "n and k must both be numbers (constant) or both arrays (tabulated)",
        )),
    }
}

fn radius_window(
    here: &str,
    min_radius_um: Option<f64>,
    max_radius_um: Option<f64>,
) -> Result<Option<RadiusWindow>> {
    match (min_radius_um, max_radius_um) {
        (None, None) => Ok(None),
        (Some(lo), Some(hi)) => {
            check_range(&format!("{here}.min_radius_um"), lo, "um", 1e-4, 1e3)?;
            check(
                &format!("{here}.max_radius_um"),
                hi,
                "um",
                &format!("> min_radius_um ({lo}) and <= 1000"),
                hi > lo && hi <= 1e3,
            )?;
            RadiusWindow::from_micrometres(lo, hi)
                .map(Some)
                .map_err(|e| invalid(here, &e.to_string()))
        }
        _ => Err(invalid(
            here,
            "give both min_radius_um and max_radius_um (a radius window), or neither",
        )),
    }
}

fn convert_size_distribution(file: SizeDistributionFile, here: &str) -> Result<SizeDistribution> {
    let here = format!("{here}.size_distribution");
    let (distribution, window, key) = match (file.lognormal, file.gamma, file.tabulated) {
        (Some(lognormal), None, None) => {
            let key = format!("{here}.lognormal");
            let distribution = match (
                lognormal.median_radius_um,
                lognormal.geometric_std_dev,
                lognormal.effective_radius_um,
                lognormal.effective_variance,
            ) {
                (Some(r_m), Some(sigma), None, None) => {
                    check_range(&format!("{key}.median_radius_um"), r_m, "um", 1e-4, 1e3)?;
                    check(&format!("{key}.geometric_std_dev"), sigma, "1", &format!(">= {MIN_GEOMETRIC_STANDARD_DEVIATION} (narrower populations are not resolved) and <= 5"), (MIN_GEOMETRIC_STANDARD_DEVIATION..=5.0).contains(&sigma))?;
                    SizeDistribution::log_normal(r_m * 1e-6, sigma)
                }
                (None, None, Some(r_eff), Some(v_eff)) => {
                    check_range(&format!("{key}.effective_radius_um"), r_eff, "um", 1e-4, 1e3)?;
                    check(&format!("{key}.effective_variance"), v_eff, "1", &format!(">= {MIN_EFFECTIVE_VARIANCE:e} (narrower populations are not resolved) and <= 10"), (MIN_EFFECTIVE_VARIANCE..=10.0).contains(&v_eff))?;
                    SizeDistribution::log_normal_from_effective_radius_and_variance(r_eff * 1e-6, v_eff)
                }
                _ => {
                    return Err(invalid(
                        &key,
                        "give median_radius_um and geometric_std_dev, or effective_radius_um and effective_variance",
                    ));
                }
            }
            .map_err(|e| invalid(&key, &e.to_string()))?;
            let window = radius_window(&key, lognormal.min_radius_um, lognormal.max_radius_um)?;
            (distribution, window, key)
        }
        (None, Some(gamma), None) => {
            let key = format!("{here}.gamma");
            check_range(
                &format!("{key}.effective_radius_um"),
                gamma.effective_radius_um,
                "um",
                1e-4,
                1e3,
            )?;
            let v_eff = gamma.effective_variance;
            check(
                &format!("{key}.effective_variance"),
                v_eff,
                "1",
                &format!(
                    ">= {MIN_EFFECTIVE_VARIANCE:e} (narrower populations are not resolved) and < 0.5"
                ),
                (MIN_EFFECTIVE_VARIANCE..0.5).contains(&v_eff),
            )?;
            let distribution =
                SizeDistribution::modified_gamma(gamma.effective_radius_um * 1e-6, v_eff)
                    .map_err(|e| invalid(&key, &e.to_string()))?;
            let window = radius_window(&key, gamma.min_radius_um, gamma.max_radius_um)?;
            (distribution, window, key)
        }
        (None, None, Some(table)) => {
            let key = format!("{here}.tabulated");
            let table = TabulatedVolumeDistribution::from_micrometres(
                &table.radius_um,
                &table.dv_dlnr_um3_per_um2,
            )
            .map_err(|e| invalid(&key, &e.to_string()))?;
            (SizeDistribution::tabulated_volume(table), None, key)
        }
        _ => {
            return Err(invalid(
                &here,
                "give exactly one of lognormal, gamma, tabulated",
            ));
        }
    };
    let distribution = match window {
        None => distribution,
        Some(window) => distribution
            .truncated_to(window)
            .map_err(|e| invalid(&key, &e.to_string()))?,
    };
    check_radius_range(&distribution, &key)?;
    Ok(distribution)
}

/// Largest particle radius sora integrates over, m: size parameter ~2240
/// at 280 nm, the shortest wavelength of any grid. Larger particles are not
/// aerosol (they fall out within minutes), and their Mie series grow long
/// enough to make a preset slow.
const MAX_INTEGRATED_RADIUS_M: f64 = 100e-6;

/// Smallest: size parameter 1e-6 (the Mie solver's tested domain) at 1100
/// nm, the longest wavelength of any grid (1.75e-13 m, rounded up).
const MIN_INTEGRATED_RADIUS_M: f64 = 1.8e-13;

/// The radii that matter in `distribution` (the nodes of the engine's own
/// cross-section quadrature at 280 nm, the shortest wavelength of any
/// grid) must lie in the range the Mie engine handles quickly.
fn check_radius_range(distribution: &SizeDistribution, key: &str) -> Result<()> {
    let wavenumber_per_m = 2.0 * std::f64::consts::PI / (MIN_WAVELENGTH_NM * 1e-9);
    let quadrature = RadiusQuadrature::gauss_legendre(
        distribution,
        wavenumber_per_m,
        &RadiusQuadratureSettings::cross_sections(),
    )
    .map_err(|e| invalid(key, &e.to_string()))?;
    let radii = quadrature.radii_m();
    let largest = radii.iter().copied().fold(0.0, f64::max);
    let smallest = radii.iter().copied().fold(f64::INFINITY, f64::min);
    if largest > MAX_INTEGRATED_RADIUS_M {
        return Err(invalid(
            key,
            &format!(
                "particles up to {:.3e} um in radius carry this distribution's cross-section; sora handles up to {} um (narrow it, or cut it with max_radius_um)",
                largest * 1e6,
                MAX_INTEGRATED_RADIUS_M * 1e6
            ),
        ));
    }
    if smallest < MIN_INTEGRATED_RADIUS_M {
        return Err(invalid(
            key,
            &format!(
                "particles down to {:.3e} um in radius carry this distribution's cross-section; sora handles down to {:e} um (narrow it, or cut it with min_radius_um)",
                smallest * 1e6,
                MIN_INTEGRATED_RADIUS_M * 1e6
            ),
        ));
    }
    Ok(())
}

fn convert_mie(file: MieFile, path: &str, keys: &AmountKeys) -> Result<SpeciesModel> {
    let here = format!("{path}.scattering.mie");
    let refractive_index = convert_refractive_index(file.refractive_index, &here)?;
    let size_distribution = convert_size_distribution(file.size_distribution, &here)?;
    let phase_mode = match file.phase.as_deref() {
        None | Some("mie") => AerosolPhaseMode::Mie,
        Some("paper-hg") => AerosolPhaseMode::PaperHenyeyGreenstein,
        Some(other) => {
            return Err(invalid(
                &format!("{here}.phase"),
                &format!(
                    "'{other}' is not a phase mode: use \"mie\" (exact) or \"paper-hg\" (the paper's eq. 3)"
                ),
            ));
        }
    };
    let amount = match (keys.number_density_m3, keys.optical_depth) {
        (Some(n), None) => ParticleAmount::NumberDensityM3(n),
        (None, Some(_)) => {
            let (optical_depth, reference_wavelength_nm) =
                optical_depth_at_reference(path, keys, "a Mie aerosol")?;
            if let RefractiveIndexModel::Tabulated(table) = &refractive_index {
                let (lo, hi) = table.wavelength_range_nm();
                if !(lo..=hi).contains(&reference_wavelength_nm) {
                    return Err(Error::out_of_range(
                        format!("{path}.reference_wavelength_nm"),
                        reference_wavelength_nm,
                        "nm",
                        format!("within the refractive-index table, {lo}..={hi}"),
                    ));
                }
            }
            ParticleAmount::OpticalDepth {
                optical_depth,
                reference_wavelength_nm,
            }
        }
        // A measured table is absolute: its column volume fixes the amount.
        (None, None) => match size_distribution.shape() {
            SizeDistributionShape::TabulatedVolume(table) => {
                ParticleAmount::ColumnNumberPerM2(table.column_number_per_m2_from_um3_per_um2())
            }
            _ => {
                return Err(invalid(
                    path,
                    "a Mie aerosol needs exactly one of number_density_m3 or optical_depth (with reference_wavelength_nm), or neither with a tabulated size distribution (its column volume is the amount)",
                ));
            }
        },
        _ => {
            return Err(invalid(
                path,
                "a Mie aerosol needs exactly one of number_density_m3 or optical_depth (with reference_wavelength_nm), or neither with a tabulated size distribution (its column volume is the amount)",
            ));
        }
    };
    Ok(SpeciesModel::Mie(MieAerosol {
        refractive_index,
        size_distribution,
        phase_mode,
        amount,
    }))
}

fn convert_absorption(file: AbsorptionFile, path: &str, keys: &AmountKeys) -> Result<SpeciesModel> {
    let here = format!("{path}.absorption");
    let kind = "an absorbing gas";
    not_used(
        path,
        "optical_depth",
        keys.optical_depth.is_some(),
        kind,
        "give column_dobson_units, column_molecules_cm2 or number_density_m3",
    )?;
    let cross_section = match (file.gas, file.wavelength_nm, file.cross_section_m2) {
        (Some(gas), None, None) => match gas.as_str() {
            "ozone" => AbsorptionCrossSection::Binned(BinnedCrossSection::ozone_233k()),
            "no2" => AbsorptionCrossSection::Binned(BinnedCrossSection::no2_294k()),
            other => {
                return Err(invalid(
                    &format!("{here}.gas"),
                    &format!(
                        "'{other}' has no built-in cross-section: use \"ozone\" or \"no2\", or give wavelength_nm and cross_section_m2"
                    ),
                ));
            }
        },
        (None, Some(wavelengths), Some(values)) => {
            for (i, v) in values.iter().enumerate() {
                check(
                    &format!("{here}.cross_section_m2[{i}]"),
                    *v,
                    "m^2",
                    ">= 0",
                    *v >= 0.0,
                )?;
            }
            AbsorptionCrossSection::Tabulated(
                TabulatedSpectrum::new(wavelengths, values, &here).map_err(|e| table_error(&e))?,
            )
        }
        _ => {
            return Err(invalid(
                &here,
                "give gas = \"ozone\" or \"no2\", or wavelength_nm and cross_section_m2 (a table), not both",
            ));
        }
    };
    let amount = match (keys.column_dobson_units, keys.number_density_m3) {
        (Some(du), None) => GasAmount::ColumnDobsonUnits(du),
        (None, Some(n)) => GasAmount::NumberDensityM3(n),
        _ => {
            return Err(invalid(
                path,
                "an absorbing gas needs exactly one of column_dobson_units, column_molecules_cm2 or number_density_m3",
            ));
        }
    };
    Ok(SpeciesModel::AbsorbingGas(AbsorbingGas {
        cross_section,
        amount,
    }))
}

/// A table that does not make a spectrum, as a file error (the message
/// already starts with the table's key).
fn table_error(e: &Error) -> Error {
    match e {
        Error::InvalidSpectrum(message) => Error::parse("atmosphere file", 0, message.clone()),
        other => other.clone(),
    }
}

// ---------------------------------------------------------------------------
// The accepted keys, read off the schema (for the documentation's test).
// ---------------------------------------------------------------------------

/// Every key an atmosphere file may hold, tables included, as sorted
/// dotted paths from the top of the file: `planet.radius_m`,
/// `planet.ground_albedo.wavelength_nm`, and for the keys of a species
/// `species.profile.tent.peak_altitude_m` (TOML's path to the last
/// `[[species]]`; errors name one, `species[2].profile...`).
///
/// Not a hand-kept list: a tracing deserializer walks the serde structs
/// above, taking each struct's field names from serde itself (the names
/// `deserialize_struct` is handed, and those a struct reports when it
/// rejects an unknown key), so a key added to, renamed in or removed from
/// the schema changes this list. `docs/atmosphere-file.md`'s test checks
/// that the page documents exactly these keys.
#[doc(hidden)]
pub fn accepted_keys() -> Vec<String> {
    key_trace::accepted_keys::<AtmosphereFile>()
}

mod key_trace {
    //! A `Deserializer` that produces a value of every struct of the schema
    //! and records the path of every field on the way. Structs name their
    //! fields to `deserialize_struct`; a key that holds "a number or a
    //! table" (`NumberOr`) asks for `deserialize_any`, and is probed once
    //! with an unknown key: a struct (they all deny unknown fields) answers
    //! with the list of its fields, anything else with another error (a
    //! leaf). Each probe ends the walk, which then restarts knowing the
    //! answer; the schema has a handful of such keys.

    use std::collections::{BTreeMap, BTreeSet};
    use std::fmt;

    use serde::Deserialize;
    use serde::de::{self, DeserializeSeed, IntoDeserializer, MapAccess, SeqAccess, Visitor};

    /// What a `deserialize_any` key turned out to hold.
    #[derive(Debug, Clone, Copy)]
    enum Shape {
        Table(&'static [&'static str]),
        Leaf,
    }

    #[derive(Debug, Default)]
    struct State {
        keys: BTreeSet<String>,
        shapes: BTreeMap<String, Shape>,
    }

    #[derive(Debug)]
    pub(super) enum TraceError {
        /// A struct rejected the probe key; these are its fields.
        UnknownField(&'static [&'static str]),
        /// A probe found a key's shape: walk again.
        Restart,
        /// A table took the probe key.
        AcceptsUnknownKeys,
        Other(String),
    }

    impl fmt::Display for TraceError {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            match self {
                TraceError::UnknownField(fields) => write!(f, "unknown field, expected {fields:?}"),
                TraceError::Restart => f.write_str("restart"),
                TraceError::AcceptsUnknownKeys => {
                    f.write_str("a table takes unknown keys (deny_unknown_fields is missing)")
                }
                TraceError::Other(message) => f.write_str(message),
            }
        }
    }

    impl std::error::Error for TraceError {}

    impl de::Error for TraceError {
        fn custom<T: fmt::Display>(message: T) -> Self {
            TraceError::Other(message.to_string())
        }
        fn unknown_field(_field: &str, expected: &'static [&'static str]) -> Self {
            TraceError::UnknownField(expected)
        }
    }

    /// A key no struct of the schema has.
    const PROBE: &str = "\u{0}probe";

    pub(super) fn accepted_keys<T: for<'de> Deserialize<'de>>() -> Vec<String> {
        let mut state = State::default();
        // One walk per `deserialize_any` key, plus the last.
        for _ in 0..100 {
            state.keys.clear();
            let tracer = Tracer {
                path: String::new(),
                state: &mut state,
            };
            match T::deserialize(tracer) {
                Ok(_) => return state.keys.into_iter().collect(),
                Err(TraceError::Restart) => {}
                Err(e) => panic!("the atmosphere file schema cannot be traced: {e}"),
            }
        }
        panic!("the atmosphere file schema did not trace in 100 walks");
    }

    struct Tracer<'s> {
        path: String,
        state: &'s mut State,
    }

    impl Tracer<'_> {
        fn visit_fields<'de, V: Visitor<'de>>(
            self,
            fields: &'static [&'static str],
            visitor: V,
        ) -> Result<V::Value, TraceError> {
            visitor.visit_map(Fields {
                fields,
                next: 0,
                path: self.path,
                state: self.state,
            })
        }
    }

    fn child(path: &str, key: &str) -> String {
        if path.is_empty() {
            key.to_string()
        } else {
            format!("{path}.{key}")
        }
    }

    impl<'de> de::Deserializer<'de> for Tracer<'_> {
        type Error = TraceError;

        fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, TraceError> {
            match self.state.shapes.get(&self.path).copied() {
                Some(Shape::Table(fields)) => self.visit_fields(fields, visitor),
                Some(Shape::Leaf) => visitor.visit_f64(1.0),
                None => {
                    let shape = match visitor.visit_map(Probe { asked: false }) {
                        Err(TraceError::UnknownField(fields)) => Shape::Table(fields),
                        Err(TraceError::AcceptsUnknownKeys) | Ok(_) => {
                            return Err(TraceError::Other(format!(
                                "{}: takes unknown keys (deny_unknown_fields is missing)",
                                self.path
                            )));
                        }
                        Err(_) => Shape::Leaf,
                    };
                    self.state.shapes.insert(self.path, shape);
                    Err(TraceError::Restart)
                }
            }
        }

        fn deserialize_struct<V: Visitor<'de>>(
            self,
            _name: &'static str,
            fields: &'static [&'static str],
            visitor: V,
        ) -> Result<V::Value, TraceError> {
            self.visit_fields(fields, visitor)
        }

        fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, TraceError> {
            visitor.visit_some(self)
        }

        /// One element, at the path of the sequence (`species.name`).
        fn deserialize_seq<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, TraceError> {
            visitor.visit_seq(OneElement(Some(self)))
        }

        fn deserialize_f64<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, TraceError> {
            visitor.visit_f64(1.0)
        }

        fn deserialize_bool<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, TraceError> {
            visitor.visit_bool(false)
        }

        fn deserialize_string<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, TraceError> {
            visitor.visit_str("x")
        }

        fn deserialize_str<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, TraceError> {
            visitor.visit_str("x")
        }

        serde::forward_to_deserialize_any! {
            i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 char bytes byte_buf unit
            unit_struct newtype_struct tuple tuple_struct map enum identifier ignored_any
        }
    }

    /// The fields of a struct, each with a traced value.
    struct Fields<'s> {
        fields: &'static [&'static str],
        next: usize,
        path: String,
        state: &'s mut State,
    }

    impl<'de> MapAccess<'de> for Fields<'_> {
        type Error = TraceError;

        fn next_key_seed<K: DeserializeSeed<'de>>(
            &mut self,
            seed: K,
        ) -> Result<Option<K::Value>, TraceError> {
            match self.fields.get(self.next) {
                Some(&key) => seed.deserialize(key.into_deserializer()).map(Some),
                None => Ok(None),
            }
        }

        fn next_value_seed<V: DeserializeSeed<'de>>(
            &mut self,
            seed: V,
        ) -> Result<V::Value, TraceError> {
            let path = child(&self.path, self.fields[self.next]);
            self.next += 1;
            self.state.keys.insert(path.clone());
            seed.deserialize(Tracer {
                path,
                state: self.state,
            })
        }
    }

    /// A table with one key that no struct has.
    struct Probe {
        asked: bool,
    }

    impl<'de> MapAccess<'de> for Probe {
        type Error = TraceError;

        fn next_key_seed<K: DeserializeSeed<'de>>(
            &mut self,
            seed: K,
        ) -> Result<Option<K::Value>, TraceError> {
            if std::mem::replace(&mut self.asked, true) {
                return Ok(None);
            }
            seed.deserialize(PROBE.into_deserializer()).map(Some)
        }

        fn next_value_seed<V: DeserializeSeed<'de>>(
            &mut self,
            _seed: V,
        ) -> Result<V::Value, TraceError> {
            Err(TraceError::AcceptsUnknownKeys)
        }
    }

    struct OneElement<'s>(Option<Tracer<'s>>);

    impl<'de> SeqAccess<'de> for OneElement<'_> {
        type Error = TraceError;

        fn next_element_seed<T: DeserializeSeed<'de>>(
            &mut self,
            seed: T,
        ) -> Result<Option<T::Value>, TraceError> {
            match self.0.take() {
                Some(tracer) => seed.deserialize(tracer).map(Some),
                None => Ok(None),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
name = "minimal"
[planet]
radius_m = 6360e3
atmosphere_height_m = 100e3
[sun]
spectrum = "flat"
irradiance_w_m2_nm = 1.0
"#;

    fn parse(text: &str) -> Result<Atmosphere> {
        Atmosphere::from_toml_str(text)
    }

    #[test]
    fn a_minimal_file_has_defaults() {
        let atmosphere = parse(MINIMAL).unwrap();
        assert_eq!(atmosphere.name, "minimal");
        assert_eq!(atmosphere.planet.ground_albedo(), &Spectrum::Constant(0.0));
        assert_eq!(atmosphere.sun.angular_diameter_deg(), 0.53);
        assert_eq!(atmosphere.sun.irradiance_scale(), 1.0);
        assert!(atmosphere.species.is_empty());
    }

    #[test]
    fn numbers_may_be_integers_and_albedo_a_table() {
        let text = MINIMAL.replace("radius_m = 6360e3", "radius_m = 6360000")
            + "[planet.ground_albedo]\nwavelength_nm = [360, 830]\nalbedo = [0.1, 0.3]\n";
        // The planet table is reopened after [sun]: TOML allows sub-tables anywhere.
        let atmosphere = parse(&text).unwrap();
        assert_eq!(atmosphere.planet.radius_m(), 6.36e6);
        assert!(matches!(
            atmosphere.planet.ground_albedo(),
            Spectrum::Tabulated(_)
        ));
    }

    #[test]
    fn syntax_errors_give_the_line() {
        let e = parse("name = \"x\"\n[planet\nradius_m = 1\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("atmosphere file, line 2:"), "{e}");
        assert!(!e.contains('\n'), "{e}");
        let e = parse(&MINIMAL.replace("atmosphere_height_m", "atmosphere_heigth_m"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 5") && e.contains("unknown field `atmosphere_heigth_m`"),
            "{e}"
        );
    }

    /// A file holding only `path` (dotted, through inline tables; the
    /// species as a one-element array), set to `value`.
    fn file_with(path: &str, value: &str) -> String {
        let mut parts = path.rsplit('.');
        let mut text = format!("{} = {value}", parts.next().unwrap());
        let parents: Vec<&str> = parts.collect();
        for (i, parent) in parents.iter().enumerate() {
            text = if i + 1 == parents.len() && *parent == "species" {
                format!("{parent} = [{{ {text} }}]")
            } else {
                format!("{parent} = {{ {text} }}")
            };
        }
        text
    }

    /// The message of the parser's error for `text` ("" when it parses).
    fn schema_error(text: &str) -> String {
        match toml::from_str::<AtmosphereFile>(text) {
            Ok(_) => String::new(),
            Err(e) => e.message().to_string(),
        }
    }

    #[test]
    fn every_listed_key_is_accepted_and_an_unknown_sibling_rejected() {
        let keys = accepted_keys();
        for key in &keys {
            // The sibling proves the file reaches the key's table ...
            let sibling = match key.rsplit_once('.') {
                Some((parent, _)) => format!("{parent}.not_a_key"),
                None => "not_a_key".to_string(),
            };
            let e = schema_error(&file_with(&sibling, "0"));
            assert!(e.contains("unknown field `not_a_key`"), "{sibling}: {e}");
            // ... where the key itself is known (its value may be of the wrong type).
            let e = schema_error(&file_with(key, "0"));
            assert!(!e.contains("unknown field"), "{key}: {e}");
        }
    }

    #[test]
    fn the_key_list_covers_the_schema() {
        let keys = accepted_keys();
        for key in [
            "name",
            "description",
            "planet",
            "planet.ground_albedo",
            "planet.ground_albedo.albedo",
            "sun.csv_file",
            "species",
            "species.profile.layers.relative_density",
            "species.scattering.parametric.phase.cornette_shanks.g",
            "species.scattering.mie.refractive_index.k",
            "species.scattering.mie.size_distribution.gamma.max_radius_um",
            "species.absorption.cross_section_m2",
        ] {
            assert!(keys.iter().any(|k| k == key), "{key} missing from {keys:?}");
        }
        // A key that holds only a number has no keys under it.
        assert!(
            !keys
                .iter()
                .any(|k| k.starts_with("species.scattering.mie.refractive_index.n."))
        );
        assert!(keys.windows(2).all(|w| w[0] < w[1]), "sorted, no repeats");
        assert!(keys.len() > 60, "{keys:#?}");
    }

    #[test]
    fn builtin_tables_parse() {
        let dust = builtin_refractive_index("mars-dust-wolff2009").unwrap();
        let (lo, hi) = dust.wavelength_range_nm();
        assert!(
            (lo - 263.0).abs() < 1e-9 && (hi - 2480.0).abs() < 1e-9,
            "{lo} {hi}"
        );
        assert!(builtin_refractive_index("unobtainium").is_none());
    }
}
