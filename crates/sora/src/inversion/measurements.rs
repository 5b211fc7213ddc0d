//! What a retrieval is given: measured sky radiances in known directions,
//! and optionally the aerosol optical depths a sun photometer measured
//! from the direct beam at the same time.
//!
//! Directions are the user's (elevation above the horizon, azimuth
//! clockwise from north, degrees), as everywhere in sora; radiances are
//! spectral, W m^-2 sr^-1 nm^-1, for the sun of the atmosphere they are
//! compared with (a measured radiance is divided by nothing: its sun is the
//! real one at that date, see `RadianceScale`). Readers of text formats
//! (the CSV of the issue, AERONET version 3 files) live in `input/` (`csv.rs`, `aeronet.rs`);
//! [`Measurements::validate`] checks what any of them produced.

use crate::error::{Error, Result};
use crate::spectrum::MIN_WAVELENGTH_NM;

/// The longest wavelength a retrieval takes, nm: 1100 (its sun-photometer
/// channels from 340 to 1020 nm and the tests that check them; the sky's
/// grids reach `spectrum::MAX_WAVELENGTH_NM`, but a 1640 nm channel's water
/// and CO2 absorption is not in the retrieval's atmosphere).
pub const MAX_RETRIEVAL_WAVELENGTH_NM: f64 = 1100.0;

/// One measured sky radiance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkyRadianceMeasurement {
    /// Wavelength, nm.
    pub wavelength_nm: f64,
    /// Sun elevation at the time of the measurement, degrees.
    pub sun_elevation_deg: f64,
    /// Sun azimuth, degrees clockwise from north.
    pub sun_azimuth_deg: f64,
    /// View elevation, degrees.
    pub view_elevation_deg: f64,
    /// View azimuth, degrees clockwise from north.
    pub view_azimuth_deg: f64,
    /// Measured radiance, W m^-2 sr^-1 nm^-1 (or relative units when the
    /// set's scale is [`RadianceScale::Relative`]).
    pub radiance_w_m2_sr_nm: f64,
    /// Its 1-sigma uncertainty, same unit.
    pub uncertainty_w_m2_sr_nm: f64,
}

/// One aerosol optical depth measured from the direct sun.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpticalDepthMeasurement {
    /// Wavelength, nm.
    pub wavelength_nm: f64,
    /// Vertical aerosol extinction optical depth (no Rayleigh, no gases).
    pub aerosol_optical_depth: f64,
    /// Its 1-sigma uncertainty (AERONET's: about 0.01).
    pub uncertainty: f64,
}

/// Whether radiances are absolute or known only up to one factor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RadianceScale {
    /// Calibrated radiances, W m^-2 sr^-1 nm^-1.
    #[default]
    Absolute,
    /// Radiances up to one unknown factor for the whole set (a normalised
    /// spectrum, as in the paper's Fig. 2): the retrieval fits the factor
    /// too, so only the shapes (spectral and angular) carry information.
    Relative,
}

/// Everything measured in one scan.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Measurements {
    /// A label for outputs (an AERONET scan's date and time, a file name).
    pub label: String,
    /// Sky radiances, any order.
    pub sky: Vec<SkyRadianceMeasurement>,
    /// Direct-sun aerosol optical depths (may be empty).
    pub optical_depths: Vec<OpticalDepthMeasurement>,
    /// Absolute or relative radiances.
    pub scale: RadianceScale,
}

/// How close to the sun's centre a sky radiance may be, as a scattering
/// angle, degrees. Closer than this a measurement is inside the sun's disc
/// (0.27 deg radius) and the bright aureole around it, where the forward
/// model's finite sun disc and the photometer's field of view (AERONET's
/// Cimel: 1.2 deg full width) make the comparison unusable; AERONET's own
/// inversions use scattering angles from 3.2 deg on.
pub const MIN_SCATTERING_ANGLE_DEG: f64 = 3.0;

/// Two wavelengths closer than this are the same channel, nm.
pub(crate) const SAME_WAVELENGTH_NM: f64 = 1e-6;

impl SkyRadianceMeasurement {
    /// Scattering angle between the sun and the view direction, degrees.
    pub fn scattering_angle_deg(&self) -> f64 {
        scattering_angle_deg(
            self.sun_elevation_deg,
            self.sun_azimuth_deg,
            self.view_elevation_deg,
            self.view_azimuth_deg,
        )
    }

    /// Where this measurement is, for messages: `440 nm, view elevation 30
    /// deg, azimuth 90 deg`.
    pub fn describe(&self) -> String {
        format!(
            "{} nm, view elevation {} deg, azimuth {} deg",
            self.wavelength_nm, self.view_elevation_deg, self.view_azimuth_deg
        )
    }

    /// What is wrong with this one measurement on its own, in one line, or
    /// `None`. Shared by [`Measurements::validate`] and the text readers
    /// (which add the line number).
    pub(crate) fn problem(&self, scale: RadianceScale) -> Option<String> {
        let values = [
            ("wavelength_nm", self.wavelength_nm),
            ("sun_elevation_deg", self.sun_elevation_deg),
            ("sun_azimuth_deg", self.sun_azimuth_deg),
            ("view_elevation_deg", self.view_elevation_deg),
            ("view_azimuth_deg", self.view_azimuth_deg),
            ("radiance", self.radiance_w_m2_sr_nm),
            ("uncertainty", self.uncertainty_w_m2_sr_nm),
        ];
        if let Some((name, value)) = values.iter().find(|(_, v)| !v.is_finite()) {
            return Some(format!("{name} = {value} is not a finite number"));
        }
        let unit = match scale {
            RadianceScale::Absolute => " W m^-2 sr^-1 nm^-1",
            RadianceScale::Relative => " (relative units)",
        };
        let (lo, hi) = (MIN_WAVELENGTH_NM, MAX_RETRIEVAL_WAVELENGTH_NM);
        if !(lo..=hi).contains(&self.wavelength_nm) {
            return Some(format!(
                "wavelength {} nm is outside the model's {lo}..={hi} nm",
                self.wavelength_nm
            ));
        }
        if !(0.0..=90.0).contains(&self.view_elevation_deg) {
            return Some(format!(
                "view elevation {} deg at {} nm is outside 0..=90 deg (below the horizon is the ground)",
                self.view_elevation_deg, self.wavelength_nm
            ));
        }
        if !(-90.0..=90.0).contains(&self.sun_elevation_deg) {
            return Some(format!(
                "sun elevation {} deg at {} nm is outside -90..=90 deg",
                self.sun_elevation_deg, self.wavelength_nm
            ));
        }
        if self.radiance_w_m2_sr_nm < 0.0 {
            return Some(format!(
                "negative radiance {}{unit} at {}",
                self.radiance_w_m2_sr_nm,
                self.describe()
            ));
        }
        if self.uncertainty_w_m2_sr_nm <= 0.0 {
            return Some(format!(
                "uncertainty {}{unit} at {} must be > 0 (it weights the fit)",
                self.uncertainty_w_m2_sr_nm,
                self.describe()
            ));
        }
        let scattering = self.scattering_angle_deg();
        if scattering < MIN_SCATTERING_ANGLE_DEG {
            return Some(format!(
                "the view at {} is {scattering:.2} deg from the sun's centre, \
                 inside the sun's disc and aureole (closer than {MIN_SCATTERING_ANGLE_DEG} deg): \
                 the forward model's sun disc and the photometer's field of view make it unusable",
                self.describe()
            ));
        }
        None
    }
}

impl OpticalDepthMeasurement {
    /// What is wrong with this optical depth on its own, or `None`.
    pub(crate) fn problem(&self) -> Option<String> {
        let values = [
            ("wavelength_nm", self.wavelength_nm),
            ("aerosol_optical_depth", self.aerosol_optical_depth),
            ("uncertainty", self.uncertainty),
        ];
        if let Some((name, value)) = values.iter().find(|(_, v)| !v.is_finite()) {
            return Some(format!(
                "optical depth's {name} = {value} is not a finite number"
            ));
        }
        if self.aerosol_optical_depth < 0.0 {
            return Some(format!(
                "negative aerosol optical depth {} at {} nm",
                self.aerosol_optical_depth, self.wavelength_nm
            ));
        }
        if self.uncertainty <= 0.0 {
            return Some(format!(
                "optical depth uncertainty {} at {} nm must be > 0",
                self.uncertainty, self.wavelength_nm
            ));
        }
        None
    }
}

impl Measurements {
    /// The sky radiances' wavelengths, sorted, each once, nm: the
    /// wavelengths the forward model must compute.
    pub fn wavelengths_nm(&self) -> Vec<f64> {
        let mut wavelengths: Vec<f64> = self.sky.iter().map(|m| m.wavelength_nm).collect();
        wavelengths.sort_by(f64::total_cmp);
        wavelengths.dedup_by(|a, b| (*a - *b).abs() < SAME_WAVELENGTH_NM);
        wavelengths
    }

    /// Checks that the set can be fitted, whatever text it was read from:
    /// at least one sky radiance; every value finite; wavelengths inside
    /// the model's range; views above the horizon; radiances >= 0 with
    /// uncertainties > 0; no view within [`MIN_SCATTERING_ANGLE_DEG`] of
    /// the sun; optical depths >= 0, each at a wavelength that has sky
    /// radiances (an optical depth elsewhere is a mismatched file, not
    /// information the fit could use) and at most one per wavelength. The
    /// error names the set's label, the wavelength and the direction.
    pub fn validate(&self) -> Result<()> {
        let invalid = |message: String| Error::parse(self.label.clone(), 0, message);
        if self.sky.is_empty() {
            return Err(invalid(
                "no sky radiance measurements (no usable angle or wavelength)".to_string(),
            ));
        }
        if let Some(problem) = self.sky.iter().find_map(|m| m.problem(self.scale)) {
            return Err(invalid(problem));
        }
        let wavelengths = self.wavelengths_nm();
        for (i, depth) in self.optical_depths.iter().enumerate() {
            if let Some(problem) = depth.problem() {
                return Err(invalid(problem));
            }
            if !wavelengths
                .iter()
                .any(|w| (w - depth.wavelength_nm).abs() < SAME_WAVELENGTH_NM)
            {
                return Err(invalid(format!(
                    "mismatched wavelengths: an optical depth at {} nm but no sky radiance there \
                     (sky radiances at {} nm)",
                    depth.wavelength_nm,
                    list_nm(&wavelengths)
                )));
            }
            if self.optical_depths[..i]
                .iter()
                .any(|d| (d.wavelength_nm - depth.wavelength_nm).abs() < SAME_WAVELENGTH_NM)
            {
                return Err(invalid(format!(
                    "two optical depths at {} nm",
                    depth.wavelength_nm
                )));
            }
        }
        Ok(())
    }
}

/// `440, 675, 870` for messages.
pub(crate) fn list_nm(wavelengths_nm: &[f64]) -> String {
    wavelengths_nm
        .iter()
        .map(|w| w.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Scattering angle between two directions given as elevation and azimuth,
/// degrees.
pub(crate) fn scattering_angle_deg(
    elevation_a_deg: f64,
    azimuth_a_deg: f64,
    elevation_b_deg: f64,
    azimuth_b_deg: f64,
) -> f64 {
    let (ea, eb) = (elevation_a_deg.to_radians(), elevation_b_deg.to_radians());
    let dphi = (azimuth_a_deg - azimuth_b_deg).to_radians();
    let cosine = ea.sin() * eb.sin() + ea.cos() * eb.cos() * dphi.cos();
    cosine.clamp(-1.0, 1.0).acos().to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn good() -> SkyRadianceMeasurement {
        SkyRadianceMeasurement {
            wavelength_nm: 440.0,
            sun_elevation_deg: 30.0,
            sun_azimuth_deg: 180.0,
            view_elevation_deg: 30.0,
            view_azimuth_deg: 90.0,
            radiance_w_m2_sr_nm: 0.05,
            uncertainty_w_m2_sr_nm: 0.0025,
        }
    }

    fn set(sky: Vec<SkyRadianceMeasurement>, depths: &[(f64, f64)]) -> Measurements {
        Measurements {
            label: "scan 1".to_string(),
            sky,
            optical_depths: depths
                .iter()
                .map(
                    |&(wavelength_nm, aerosol_optical_depth)| OpticalDepthMeasurement {
                        wavelength_nm,
                        aerosol_optical_depth,
                        uncertainty: 0.01,
                    },
                )
                .collect(),
            scale: RadianceScale::Absolute,
        }
    }

    fn error_of(sky: SkyRadianceMeasurement) -> String {
        set(vec![good(), sky], &[])
            .validate()
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn a_good_set_validates_and_lists_its_wavelengths() {
        let red = SkyRadianceMeasurement {
            wavelength_nm: 675.0,
            ..good()
        };
        let m = set(vec![red, good(), good()], &[(440.0, 0.2), (675.0, 0.1)]);
        m.validate().unwrap();
        assert_eq!(m.wavelengths_nm(), [440.0, 675.0]);
    }

    #[test]
    fn each_bad_measurement_is_named() {
        let e = set(vec![], &[]).validate().unwrap_err().to_string();
        assert!(e.starts_with("scan 1: no sky radiance"), "{e}");
        let e = error_of(SkyRadianceMeasurement {
            radiance_w_m2_sr_nm: -0.01,
            view_elevation_deg: 20.0,
            ..good()
        });
        assert!(
            e.contains("scan 1")
                && e.contains("negative radiance -0.01 W m^-2 sr^-1 nm^-1")
                && e.contains("at 440 nm, view elevation 20 deg, azimuth 90 deg"),
            "{e}"
        );
        let e = error_of(SkyRadianceMeasurement {
            uncertainty_w_m2_sr_nm: 0.0,
            ..good()
        });
        assert!(e.contains("uncertainty 0") && e.contains("> 0"), "{e}");
        let e = error_of(SkyRadianceMeasurement {
            radiance_w_m2_sr_nm: f64::NAN,
            ..good()
        });
        assert!(e.contains("radiance = NaN is not a finite number"), "{e}");
        let e = error_of(SkyRadianceMeasurement {
            wavelength_nm: 1640.0,
            ..good()
        });
        assert!(
            e.contains("1640 nm is outside the model's 280..=1100 nm"),
            "{e}"
        );
        let e = error_of(SkyRadianceMeasurement {
            view_elevation_deg: -1.0,
            ..good()
        });
        assert!(
            e.contains("view elevation -1 deg") && e.contains("ground"),
            "{e}"
        );
        let e = error_of(SkyRadianceMeasurement {
            sun_elevation_deg: 95.0,
            ..good()
        });
        assert!(e.contains("sun elevation 95 deg"), "{e}");
        // 2 deg of azimuth at 30 deg elevation: 1.73 deg from the sun.
        let e = error_of(SkyRadianceMeasurement {
            view_azimuth_deg: 182.0,
            ..good()
        });
        assert!(
            e.contains("1.73 deg from the sun's centre") && e.contains("sun's disc and aureole"),
            "{e}"
        );
        // 4 deg of azimuth at the horizon is 4 deg away: usable.
        set(
            vec![SkyRadianceMeasurement {
                sun_elevation_deg: 0.0,
                view_elevation_deg: 0.0,
                view_azimuth_deg: 184.0,
                ..good()
            }],
            &[],
        )
        .validate()
        .unwrap();
    }

    #[test]
    fn optical_depths_must_match_the_sky_wavelengths() {
        let e = set(vec![good()], &[(500.0, 0.1)])
            .validate()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("mismatched wavelengths: an optical depth at 500 nm")
                && e.contains("sky radiances at 440 nm"),
            "{e}"
        );
        let e = set(vec![good()], &[(440.0, -0.1)])
            .validate()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("negative aerosol optical depth -0.1 at 440 nm"),
            "{e}"
        );
        let e = set(vec![good()], &[(440.0, 0.1), (440.0, 0.2)])
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("two optical depths at 440 nm"), "{e}");
    }

    #[test]
    fn scattering_angle_is_the_angle_between_directions() {
        assert!((scattering_angle_deg(0.0, 0.0, 0.0, 90.0) - 90.0).abs() < 1e-12);
        assert!((scattering_angle_deg(30.0, 180.0, 90.0, 0.0) - 60.0).abs() < 1e-12);
        assert!((scattering_angle_deg(10.0, 180.0, 10.0, 0.0) - 160.0).abs() < 1e-9);
    }
}
