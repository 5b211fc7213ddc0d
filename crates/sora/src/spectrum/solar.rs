//! The sun's spectral irradiance at the top of the atmosphere, on a plane
//! normal to its rays, in W m^-2 nm^-1 (the `E_sun` of the paper's eq. 4-5).
//!
//! - [`SolarSpectrum::flat`]: the paper's equal-energy sun (§4, "※": the same
//!   value at every wavelength); 1 W m^-2 nm^-1 is the unit irradiance of the
//!   reference radiative-transfer cases.
//! - [`SolarSpectrum::astm_e490`]: ASTM E490-00a, air mass zero, embedded
//!   (`data/astm_e490_extraterrestrial.csv`, 1366.1 W m^-2 in total).
//! - [`SolarSpectrum::parse_csv`]: a user table `wavelength_nm,irradiance_w_m2_nm`.
//!
//! Tables are put on a wavelength grid by band averaging (see
//! [`Spectrum::sample_band_averaged`]): the solar spectrum is full of
//! Fraunhofer lines, and a point sample every 20 nm would land on or between
//! lines by chance; the band mean carries each band's energy.

use crate::error::{Error, Result};
use crate::spectrum::{SampledSpectrum, Spectrum, TabulatedSpectrum, WavelengthGrid};

const ASTM_E490_CSV: &str = include_str!("../data/astm_e490_extraterrestrial.csv");

/// Spectral irradiance of the sun, W m^-2 nm^-1, at the top of the atmosphere.
#[derive(Debug, Clone, PartialEq)]
pub struct SolarSpectrum {
    name: String,
    irradiance_w_m2_nm: Spectrum,
}

impl SolarSpectrum {
    /// The paper's equal-energy sun with `irradiance_w_m2_nm` at every wavelength.
    pub(crate) fn flat(irradiance_w_m2_nm: f64) -> Result<SolarSpectrum> {
        if !(irradiance_w_m2_nm.is_finite() && irradiance_w_m2_nm > 0.0) {
            return Err(Error::out_of_range(
                "solar irradiance",
                irradiance_w_m2_nm,
                "W m^-2 nm^-1",
                "> 0 and finite",
            ));
        }
        Ok(SolarSpectrum {
            name: format!("flat {irradiance_w_m2_nm} W m^-2 nm^-1"),
            irradiance_w_m2_nm: Spectrum::Constant(irradiance_w_m2_nm),
        })
    }

    /// ASTM E490-00a extraterrestrial spectrum (embedded).
    pub fn astm_e490() -> SolarSpectrum {
        SolarSpectrum::parse_csv(ASTM_E490_CSV, "ASTM E490")
            .expect("the embedded ASTM E490 table is valid")
    }

    /// A user table: two columns `wavelength_nm,irradiance_w_m2_nm` (header
    /// line, `#` comments). `name` identifies it in errors. Irradiances must
    /// be finite and >= 0.
    pub(crate) fn parse_csv(text: &str, name: &str) -> Result<SolarSpectrum> {
        let what = format!("solar spectrum {name}");
        let table = TabulatedSpectrum::parse_csv(text, &what)?;
        if let Some(i) = table.values().iter().position(|v| *v < 0.0) {
            return Err(Error::InvalidSpectrum(format!(
                "{what}: irradiance {} W m^-2 nm^-1 at {} nm is negative",
                table.values()[i],
                table.wavelengths_nm()[i]
            )));
        }
        Ok(SolarSpectrum {
            name: name.to_string(),
            irradiance_w_m2_nm: Spectrum::Tabulated(table),
        })
    }

    /// A short human-readable name ("ASTM E490", "flat 1 W m^-2 nm^-1", a file name).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The irradiance as a function of wavelength, W m^-2 nm^-1.
    pub(crate) fn irradiance_w_m2_nm(&self) -> &Spectrum {
        &self.irradiance_w_m2_nm
    }

    /// Band-averaged irradiance at each wavelength of `grid`, W m^-2 nm^-1.
    /// Fails, naming the table's range, when the table does not cover the grid.
    pub(crate) fn sample(&self, grid: &WavelengthGrid) -> Result<SampledSpectrum> {
        self.irradiance_w_m2_nm
            .sample_band_averaged(grid)
            .map_err(|e| {
                Error::InvalidSpectrum(format!(
                    "solar spectrum {}: {}",
                    self.name,
                    strip_prefix(&e)
                ))
            })
    }
}

fn strip_prefix(e: &Error) -> String {
    match e {
        Error::InvalidSpectrum(message) => message.clone(),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn astm_e490_integrates_to_the_solar_constant() {
        let sun = SolarSpectrum::astm_e490();
        let Spectrum::Tabulated(table) = sun.irradiance_w_m2_nm() else {
            panic!("tabulated")
        };
        let (lo, hi) = table.range_nm();
        let total_w_m2 = table.band_average(lo, hi).unwrap() * (hi - lo);
        // The standard's own total is 1366.1 W m^-2; the trapezoid over its rows agrees to 0.1%.
        assert!((total_w_m2 - 1366.1).abs() < 1.4, "{total_w_m2}");
    }

    #[test]
    fn astm_e490_on_the_paper_grid_is_visible_sunlight() {
        let sampled = SolarSpectrum::astm_e490()
            .sample(&WavelengthGrid::paper())
            .unwrap();
        // Band means near the visible peak are ~1.9-2.0 W m^-2 nm^-1; the violet end is lower.
        let peak = sampled.max_value();
        assert!((1.8..2.2).contains(&peak), "{peak}");
        assert!(sampled[0] < 0.7 * peak, "380 nm band {}", sampled[0]);
        sampled.check_finite_non_negative("E490").unwrap();
    }

    #[test]
    fn flat_sun_is_the_same_everywhere() {
        let sampled = SolarSpectrum::flat(1.0)
            .unwrap()
            .sample(&WavelengthGrid::paper())
            .unwrap();
        assert_eq!(sampled.values(), &[1.0; 21]);
        assert!(SolarSpectrum::flat(0.0).is_err());
        assert!(SolarSpectrum::flat(f64::NAN).is_err());
    }

    #[test]
    fn user_tables_are_checked() {
        let sun = SolarSpectrum::parse_csv(
            "wavelength_nm,irradiance_w_m2_nm\n400,1\n700,2\n",
            "mine.csv",
        )
        .unwrap();
        let e = sun
            .sample(&WavelengthGrid::paper())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("mine.csv") && e.contains("covers 400-700 nm"),
            "{e}"
        );
        let e = SolarSpectrum::parse_csv(
            "wavelength_nm,irradiance_w_m2_nm\n400,1\n700,-2\n",
            "neg.csv",
        )
        .unwrap_err();
        assert!(e.to_string().contains("negative"), "{e}");
    }
}
