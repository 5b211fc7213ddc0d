//! The page's atmosphere controls, read from and written into an
//! atmosphere file's TOML: the first aerosol's optical depth, log-normal
//! size distribution and absorption, the ozone column. Edited as TOML and
//! parsed again by the library, so that every value a control sets is
//! checked, and its error named, exactly as in a file (`species[2].
//! optical_depth`, with its unit and range).
//!
//! The aerosol is the first species scattering by Mie theory or by a
//! parametric law; the ozone is the first species absorbing as `ozone`.
//! A control is `None` where the atmosphere does not have it in a form a
//! single number can set (Mars has no ozone; a wavelength table or a
//! built-in refractive index has no single imaginary part).

use serde::Serialize;
use sora::atmosphere::ozone::MOLECULES_PER_CM2_PER_DOBSON_UNIT;
use toml::{Table, Value};

use crate::request::AtmosphereSpec;

/// The controls of one atmosphere and their values in it.
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct Controls {
    /// The aerosol species' name.
    pub aerosol_name: Option<String>,
    /// Its column optical depth at `aerosol_reference_wavelength_nm` (from
    /// the file; the engine computes it where the file gives a number
    /// density).
    pub aerosol_optical_depth: Option<f64>,
    /// The wavelength of that optical depth, nm (550 when the file gives
    /// the aerosol as a number density).
    pub aerosol_reference_wavelength_nm: Option<f64>,
    /// Log-normal number median radius, micrometres (from the effective
    /// radius and variance where the file gives those).
    pub aerosol_median_radius_um: Option<f64>,
    /// Log-normal geometric standard deviation.
    pub aerosol_geometric_std_dev: Option<f64>,
    /// Imaginary part of a constant refractive index.
    pub aerosol_imaginary_index: Option<f64>,
    /// Ozone column, Dobson units.
    pub ozone_column_du: Option<f64>,
    /// The planet's ground albedo where it is one constant.
    pub ground_albedo: Option<f64>,
}

/// The reference wavelength an optical-depth control uses for an aerosol
/// that the file gives as a number density, nm.
pub const DEFAULT_REFERENCE_WAVELENGTH_NM: f64 = 550.0;

/// The controls of the atmosphere file `text`.
pub fn read_controls(text: &str) -> Result<Controls, String> {
    let table: Table = text
        .parse()
        .map_err(|e: toml::de::Error| format!("atmosphere file: {}", e.message()))?;
    let mut controls = Controls {
        ground_albedo: table
            .get("planet")
            .and_then(Value::as_table)
            .and_then(|planet| planet.get("ground_albedo"))
            .and_then(number),
        ..Controls::default()
    };
    let Some(species) = table.get("species").and_then(Value::as_array) else {
        return Ok(controls);
    };
    if let Some(aerosol) = species
        .iter()
        .filter_map(Value::as_table)
        .find(|s| is_aerosol(s))
    {
        controls.aerosol_name = aerosol
            .get("name")
            .and_then(Value::as_str)
            .map(String::from);
        if let Some(tau) = aerosol.get("optical_depth").and_then(number) {
            controls.aerosol_optical_depth = Some(tau);
            controls.aerosol_reference_wavelength_nm =
                aerosol.get("reference_wavelength_nm").and_then(number);
        }
        if let Some(mie) = mie_of(aerosol) {
            if let Some((median, sigma)) = lognormal_of(mie) {
                controls.aerosol_median_radius_um = Some(median);
                controls.aerosol_geometric_std_dev = Some(sigma);
            }
            controls.aerosol_imaginary_index = mie
                .get("refractive_index")
                .and_then(Value::as_table)
                .and_then(|index| index.get("k"))
                .and_then(number);
        }
    }
    controls.ozone_column_du = species
        .iter()
        .filter_map(Value::as_table)
        .find(|s| is_ozone(s))
        .and_then(|s| {
            s.get("column_dobson_units").and_then(number).or_else(|| {
                s.get("column_molecules_cm2")
                    .and_then(number)
                    .map(|n| n / MOLECULES_PER_CM2_PER_DOBSON_UNIT)
            })
        });
    Ok(controls)
}

/// `text` with the controls of `spec` written in (the ground albedo is
/// not here: it replaces the planet's after parsing, as `--ground-albedo`
/// does). Fails, naming the control, where the atmosphere lacks what it
/// sets.
pub fn apply_controls(text: &str, spec: &AtmosphereSpec) -> Result<String, String> {
    let wants_aerosol = spec.aerosol_optical_depth.is_some()
        || spec.aerosol_median_radius_um.is_some()
        || spec.aerosol_geometric_std_dev.is_some()
        || spec.aerosol_imaginary_index.is_some();
    if !wants_aerosol && spec.ozone_column_du.is_none() {
        return Ok(text.to_string());
    }
    let mut table: Table = text
        .parse()
        .map_err(|e: toml::de::Error| format!("atmosphere file: {}", e.message()))?;
    let species = table
        .get_mut("species")
        .and_then(Value::as_array_mut)
        .ok_or("atmosphere file: no [[species]]")?;
    if wants_aerosol {
        let aerosol = species
            .iter_mut()
            .filter_map(Value::as_table_mut)
            .find(|s| is_aerosol(s))
            .ok_or("aerosol controls: this atmosphere has no aerosol species")?;
        if let Some(tau) = spec.aerosol_optical_depth {
            if aerosol.remove("number_density_m3").is_some() {
                aerosol.insert(
                    "reference_wavelength_nm".into(),
                    Value::Float(DEFAULT_REFERENCE_WAVELENGTH_NM),
                );
            }
            aerosol.insert("optical_depth".into(), Value::Float(tau));
        }
        if spec.aerosol_median_radius_um.is_some()
            || spec.aerosol_geometric_std_dev.is_some()
            || spec.aerosol_imaginary_index.is_some()
        {
            let mie = aerosol
                .get_mut("scattering")
                .and_then(Value::as_table_mut)
                .and_then(|s| s.get_mut("mie"))
                .and_then(Value::as_table_mut)
                .ok_or("aerosol size and absorption controls: the aerosol is not a Mie species")?;
            set_lognormal(mie, spec)?;
            if let Some(k) = spec.aerosol_imaginary_index {
                let index = mie
                    .get_mut("refractive_index")
                    .and_then(Value::as_table_mut)
                    .filter(|index| index.get("k").and_then(number).is_some())
                    .ok_or(
                        "aerosol imaginary index: the aerosol's refractive index is not one constant n + ik",
                    )?;
                index.insert("k".into(), Value::Float(k));
            }
        }
    }
    if let Some(du) = spec.ozone_column_du {
        let ozone = species
            .iter_mut()
            .filter_map(Value::as_table_mut)
            .find(|s| is_ozone(s))
            .ok_or("ozone column: this atmosphere has no ozone")?;
        ozone.remove("number_density_m3");
        ozone.remove("column_molecules_cm2");
        ozone.insert("column_dobson_units".into(), Value::Float(du));
    }
    toml::to_string(&table).map_err(|e| format!("atmosphere file: {e}"))
}

/// `text` with the planet's ground albedo set to the constant `albedo`
/// (for a downloaded file that reproduces what the page shows).
pub fn set_ground_albedo(text: &str, albedo: f64) -> Result<String, String> {
    let mut table: Table = text
        .parse()
        .map_err(|e: toml::de::Error| format!("atmosphere file: {}", e.message()))?;
    let planet = table
        .get_mut("planet")
        .and_then(Value::as_table_mut)
        .ok_or("atmosphere file: no [planet]")?;
    planet.insert("ground_albedo".into(), Value::Float(albedo));
    toml::to_string(&table).map_err(|e| format!("atmosphere file: {e}"))
}

/// Writes the median radius and width of `spec` into the Mie table's
/// log-normal (converting an effective-radius form to the median form).
fn set_lognormal(mie: &mut Table, spec: &AtmosphereSpec) -> Result<(), String> {
    if spec.aerosol_median_radius_um.is_none() && spec.aerosol_geometric_std_dev.is_none() {
        return Ok(());
    }
    let (median, sigma) = lognormal_of(mie)
        .ok_or("aerosol size controls: the aerosol's size distribution is not log-normal")?;
    let lognormal = mie
        .get_mut("size_distribution")
        .and_then(Value::as_table_mut)
        .and_then(|d| d.get_mut("lognormal"))
        .and_then(Value::as_table_mut)
        .ok_or("aerosol size controls: the aerosol's size distribution is not log-normal")?;
    lognormal.remove("effective_radius_um");
    lognormal.remove("effective_variance");
    let median = spec.aerosol_median_radius_um.unwrap_or(median);
    let sigma = spec.aerosol_geometric_std_dev.unwrap_or(sigma);
    lognormal.insert("median_radius_um".into(), Value::Float(median));
    lognormal.insert("geometric_std_dev".into(), Value::Float(sigma));
    Ok(())
}

/// The log-normal's number median radius (um) and geometric standard
/// deviation, from either form of the file: for a log-normal, the
/// effective variance is v = exp(ln^2 sigma) - 1 and the effective radius
/// r_eff = r_g exp(5/2 ln^2 sigma) (Hansen & Travis 1974, eq. 2.56).
fn lognormal_of(mie: &Table) -> Option<(f64, f64)> {
    let lognormal = mie
        .get("size_distribution")?
        .as_table()?
        .get("lognormal")?
        .as_table()?;
    if let (Some(median), Some(sigma)) = (
        lognormal.get("median_radius_um").and_then(number),
        lognormal.get("geometric_std_dev").and_then(number),
    ) {
        return Some((median, sigma));
    }
    let r_eff = lognormal.get("effective_radius_um").and_then(number)?;
    let v_eff = lognormal.get("effective_variance").and_then(number)?;
    let ln2_sigma = v_eff.ln_1p();
    Some((r_eff * (-2.5 * ln2_sigma).exp(), ln2_sigma.sqrt().exp()))
}

fn mie_of(species: &Table) -> Option<&Table> {
    species
        .get("scattering")?
        .as_table()?
        .get("mie")?
        .as_table()
}

fn is_aerosol(species: &Table) -> bool {
    species
        .get("scattering")
        .and_then(Value::as_table)
        .is_some_and(|s| s.contains_key("mie") || s.contains_key("parametric"))
}

fn is_ozone(species: &Table) -> bool {
    species
        .get("absorption")
        .and_then(Value::as_table)
        .and_then(|a| a.get("gas"))
        .and_then(Value::as_str)
        == Some("ozone")
}

/// A TOML number (integer or float) as f64.
fn number(value: &Value) -> Option<f64> {
    match value {
        Value::Float(x) => Some(*x),
        Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn preset(name: &str) -> &'static str {
        sora::atmosphere::presets::find_preset(name).unwrap().toml
    }

    #[test]
    fn reads_the_presets_controls() {
        let clear = read_controls(preset("earth-clear")).unwrap();
        assert_eq!(clear.aerosol_optical_depth, Some(0.1));
        assert_eq!(clear.aerosol_reference_wavelength_nm, Some(550.0));
        assert_eq!(clear.aerosol_median_radius_um, Some(0.0212));
        assert_eq!(clear.aerosol_geometric_std_dev, Some(2.24));
        assert_eq!(clear.aerosol_imaginary_index, Some(0.006));
        assert_eq!(clear.ozone_column_du, Some(300.0));
        let mars = read_controls(preset("mars-dust")).unwrap();
        assert_eq!(mars.ozone_column_du, None);
        assert_eq!(mars.aerosol_imaginary_index, None, "built-in index table");
        // r_eff 1.5 um, v_eff 0.3: ln^2 sigma = ln 1.3.
        let (median, sigma) = (
            mars.aerosol_median_radius_um.unwrap(),
            mars.aerosol_geometric_std_dev.unwrap(),
        );
        let ln2 = sigma.ln().powi(2);
        assert!((ln2 - 1.3f64.ln()).abs() < 1e-12);
        assert!((median * (2.5 * ln2).exp() - 1.5).abs() < 1e-12);
        let rayleigh = read_controls(preset("us-standard-1976-rayleigh")).unwrap();
        assert_eq!(
            rayleigh,
            Controls {
                ground_albedo: Some(0.0),
                ..Controls::default()
            }
        );
        assert_eq!(clear.ground_albedo, Some(0.1));
    }

    #[test]
    fn written_controls_are_read_back_and_parse() {
        let spec = AtmosphereSpec {
            aerosol_optical_depth: Some(0.4),
            aerosol_median_radius_um: Some(0.05),
            aerosol_geometric_std_dev: Some(1.8),
            aerosol_imaginary_index: Some(0.02),
            ozone_column_du: Some(250.0),
            ..AtmosphereSpec::default()
        };
        let text = apply_controls(preset("earth-clear"), &spec).unwrap();
        let controls = read_controls(&text).unwrap();
        assert_eq!(controls.aerosol_optical_depth, Some(0.4));
        assert_eq!(controls.aerosol_median_radius_um, Some(0.05));
        assert_eq!(controls.aerosol_geometric_std_dev, Some(1.8));
        assert_eq!(controls.aerosol_imaginary_index, Some(0.02));
        assert_eq!(controls.ozone_column_du, Some(250.0));
        sora::Atmosphere::from_toml_str(&text).unwrap();
        // Mars: the effective-radius form becomes the median form.
        let mars = apply_controls(
            preset("mars-dust"),
            &AtmosphereSpec {
                aerosol_geometric_std_dev: Some(1.6),
                ..AtmosphereSpec::default()
            },
        )
        .unwrap();
        assert_eq!(
            read_controls(&mars).unwrap().aerosol_geometric_std_dev,
            Some(1.6)
        );
        sora::Atmosphere::from_toml_str(&mars).unwrap();
        // The paper's Mars gives its dust as a number density.
        let paper = apply_controls(
            preset("paper-mars"),
            &AtmosphereSpec {
                aerosol_optical_depth: Some(1.0),
                ..AtmosphereSpec::default()
            },
        )
        .unwrap();
        assert_eq!(
            read_controls(&paper)
                .unwrap()
                .aerosol_reference_wavelength_nm,
            Some(550.0)
        );
        sora::Atmosphere::from_toml_str(&paper).unwrap();
    }

    /// An ozone column given in molecules cm^-2 reads as Dobson units and
    /// is replaced, not doubled, when the slider writes one.
    #[test]
    fn an_ozone_column_in_molecules_is_read_and_replaced() {
        let du = preset("earth-clear");
        let molecules = du.replace(
            "column_dobson_units = 300",
            "column_molecules_cm2 = 8.0601e18",
        );
        assert_ne!(du, molecules, "the preset gives its ozone in DU");
        let read = read_controls(&molecules).unwrap().ozone_column_du.unwrap();
        assert!((read - 300.0).abs() < 1e-9, "{read}");
        let spec = AtmosphereSpec {
            ozone_column_du: Some(250.0),
            ..AtmosphereSpec::default()
        };
        let text = apply_controls(&molecules, &spec).unwrap();
        assert!(!text.contains("column_molecules_cm2"), "{text}");
        assert_eq!(read_controls(&text).unwrap().ozone_column_du, Some(250.0));
        sora::Atmosphere::from_toml_str(&text).unwrap();
    }

    #[test]
    fn controls_the_atmosphere_lacks_are_errors_that_name_them() {
        let ozone = AtmosphereSpec {
            ozone_column_du: Some(300.0),
            ..AtmosphereSpec::default()
        };
        let error = apply_controls(preset("mars-dust"), &ozone).unwrap_err();
        assert!(error.contains("ozone"), "{error}");
        let k = AtmosphereSpec {
            aerosol_imaginary_index: Some(0.01),
            ..AtmosphereSpec::default()
        };
        let error = apply_controls(preset("mars-dust"), &k).unwrap_err();
        assert!(error.contains("imaginary"), "{error}");
        let error = apply_controls(preset("us-standard-1976-rayleigh"), &k).unwrap_err();
        assert!(error.contains("no aerosol"), "{error}");
    }
}
