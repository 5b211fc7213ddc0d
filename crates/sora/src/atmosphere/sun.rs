//! The sun as seen from the planet: its spectral irradiance at the top of
//! the atmosphere (the `E_sun` of the paper's eq. 4-5) and its disc.
//!
//! Irradiance = the solar spectrum (flat, ASTM E490 or a user table, see
//! [`SolarSpectrum`]) times a scale factor: 1 at Earth's mean distance,
//! 1/d^2 for a planet at d astronomical units (Mars at 1.524 AU: 0.4306).
//! The disc has an angular diameter (0.53 deg from Earth, 0.35 deg from
//! Mars); 0 makes a point sun, as in the reference radiative-transfer
//! cases.

use crate::error::{Error, Result};
use crate::spectrum::{SampledSpectrum, SolarSpectrum, WavelengthGrid};

/// The sun's apparent angular diameter from Earth, degrees.
pub const EARTH_SUN_ANGULAR_DIAMETER_DEG: f64 = 0.53;

/// Largest angular diameter accepted, degrees.
pub const MAX_SUN_ANGULAR_DIAMETER_DEG: f64 = 20.0;

/// A validated sun.
#[derive(Debug, Clone, PartialEq)]
pub struct Sun {
    spectrum: SolarSpectrum,
    irradiance_scale: f64,
    angular_diameter_deg: f64,
}

/// Largest `sun.irradiance_scale`: a sun 20 deg across (the largest disc,
/// [`MAX_SUN_ANGULAR_DIAMETER_DEG`]) is (sin 10 deg / sin 0.2665 deg)^2 = 1400
/// times as bright as at 1 AU; 1e4 leaves room and keeps every irradiance
/// far from overflow (1e308 made it infinite, found by the mutation tests).
pub const MAX_IRRADIANCE_SCALE: f64 = 1e4;

impl Sun {
    /// A sun of spectrum `spectrum` scaled by `irradiance_scale` (> 0,
    /// <= [`MAX_IRRADIANCE_SCALE`]) with an angular diameter
    /// `angular_diameter_deg` (0..=20 deg).
    pub fn new(
        spectrum: SolarSpectrum,
        irradiance_scale: f64,
        angular_diameter_deg: f64,
    ) -> Result<Sun> {
        if !(irradiance_scale > 0.0 && irradiance_scale <= MAX_IRRADIANCE_SCALE) {
            return Err(Error::out_of_range(
                "sun.irradiance_scale",
                irradiance_scale,
                "1",
                format!(
                    "> 0 and <= {MAX_IRRADIANCE_SCALE:e} (a sun 20 deg across is 1400 times as bright as at 1 AU)"
                ),
            ));
        }
        if !(0.0..=MAX_SUN_ANGULAR_DIAMETER_DEG).contains(&angular_diameter_deg) {
            return Err(Error::out_of_range(
                "sun.angular_diameter_deg",
                angular_diameter_deg,
                "deg",
                format!("0 (a point sun) to {MAX_SUN_ANGULAR_DIAMETER_DEG}"),
            ));
        }
        Ok(Sun {
            spectrum,
            irradiance_scale,
            angular_diameter_deg,
        })
    }

    /// The unscaled solar spectrum.
    pub fn spectrum(&self) -> &SolarSpectrum {
        &self.spectrum
    }

    /// The factor applied to the spectrum.
    pub fn irradiance_scale(&self) -> f64 {
        self.irradiance_scale
    }

    /// Apparent angular diameter, degrees.
    pub fn angular_diameter_deg(&self) -> f64 {
        self.angular_diameter_deg
    }

    /// The distance this sun has on the date of `position`: the date's
    /// Earth-Sun distance for a sun at 1 AU (irradiance scale 1: every
    /// Earth preset), none for other suns (Mars' presets keep the distance
    /// their file gives: the date is the Earth's).
    pub fn date_distance_au(&self, position: &crate::SunPosition) -> Option<f64> {
        (self.irradiance_scale == 1.0).then_some(position.earth_sun_distance_au)
    }

    /// This sun seen from `distance_au` astronomical units (0.1..=100)
    /// instead of the distance its scale implies (1 / sqrt(scale): 1 AU for
    /// every Earth preset, 1.524 AU for Mars'): the irradiance scale
    /// becomes 1 / distance^2 and the disc's angular diameter shrinks in
    /// proportion to the distance, so the disc's radiance is unchanged.
    /// With [`crate::SunPosition::earth_sun_distance_au`] this is the
    /// date's sun (3 January: 1/0.98329^2 = 1.0343 of the 1-AU spectrum).
    pub fn at_distance_au(&self, distance_au: f64) -> Result<Sun> {
        if !(0.1..=100.0).contains(&distance_au) {
            return Err(Error::out_of_range(
                "sun distance",
                distance_au,
                "AU",
                "0.1..=100",
            ));
        }
        let implied_au = self.irradiance_scale.sqrt().recip();
        Sun::new(
            self.spectrum.clone(),
            distance_au.powi(-2),
            self.angular_diameter_deg * implied_au / distance_au,
        )
    }

    /// Apparent angular radius, radians.
    pub(crate) fn angular_radius_rad(&self) -> f64 {
        0.5 * self.angular_diameter_deg.to_radians()
    }

    /// Solid angle of the disc, sr: 2 pi (1 - cos(angular radius)).
    #[cfg(test)]
    pub(crate) fn solid_angle_sr(&self) -> f64 {
        // 1 - cos x = 2 sin^2(x/2), without cancellation for tiny discs.
        4.0 * std::f64::consts::PI * (0.5 * self.angular_radius_rad()).sin().powi(2)
    }

    /// Top-of-atmosphere irradiance on a plane normal to the sun's rays at
    /// each wavelength of `grid`, W m^-2 nm^-1 (band averages, scaled).
    pub(crate) fn sample_irradiance_w_m2_nm(
        &self,
        grid: &WavelengthGrid,
    ) -> Result<SampledSpectrum> {
        let mut irradiance = self.spectrum.sample(grid)?;
        irradiance *= self.irradiance_scale;
        Ok(irradiance)
    }

    /// The top-of-atmosphere irradiance (normal to the rays) integrated
    /// over `grid` with its quadrature (each sample its band, `step_nm`
    /// wide), W m^-2: the sun's share of a broadband value on that grid.
    pub fn grid_irradiance_w_m2(&self, grid: &WavelengthGrid) -> Result<f64> {
        let sampled = self.sample_irradiance_w_m2_nm(grid)?;
        Ok((0..grid.len())
            .map(|i| sampled[i] * grid.quadrature_weight_nm(i))
            .sum())
    }

    /// The whole solar table's range, nm, and its irradiance integrated
    /// over it (trapezoids between the rows), scaled, W m^-2; `None` for a
    /// flat sun, which has no ends. ASTM E490: 119.5 nm to 1 mm, 1366.1 W
    /// m^-2 at 1 AU.
    pub fn table_irradiance_w_m2(&self) -> Option<((f64, f64), f64)> {
        match self.spectrum.irradiance_w_m2_nm() {
            crate::spectrum::Spectrum::Constant(_) => None,
            crate::spectrum::Spectrum::Tabulated(table) => {
                let (lo, hi) = table.range_nm();
                let mean = table.band_average(lo, hi).ok()?;
                Some(((lo, hi), mean * (hi - lo) * self.irradiance_scale))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disc_geometry() {
        let sun = Sun::new(SolarSpectrum::flat(1.0).unwrap(), 1.0, 0.53).unwrap();
        // 6.8e-5 sr for the sun seen from Earth.
        assert!(
            (sun.solid_angle_sr() - 6.72e-5).abs() < 1e-6,
            "{}",
            sun.solid_angle_sr()
        );
        let point = Sun::new(SolarSpectrum::flat(1.0).unwrap(), 1.0, 0.0).unwrap();
        assert_eq!(point.solid_angle_sr(), 0.0);
    }

    #[test]
    fn irradiance_is_scaled() {
        let sun = Sun::new(SolarSpectrum::flat(2.0).unwrap(), 0.25, 0.35).unwrap();
        let e = sun
            .sample_irradiance_w_m2_nm(&WavelengthGrid::paper())
            .unwrap();
        assert_eq!(e.values(), &[0.5; 21]);
    }

    #[test]
    fn the_suns_energy_in_a_band_and_in_its_whole_table() {
        // A flat sun has no table; on a grid each sample holds step_nm.
        let flat = Sun::new(SolarSpectrum::flat(2.0).unwrap(), 0.5, 0.53).unwrap();
        assert_eq!(flat.table_irradiance_w_m2(), None);
        let grid = WavelengthGrid::new(400.0, 700.0, 10.0).unwrap();
        assert!((flat.grid_irradiance_w_m2(&grid).unwrap() - 310.0).abs() < 1e-9);
        // ASTM E490: 1366.1 W m^-2 over 119.5 nm to 1 mm (trapezoids within
        // 0.1 %), 95.78 % of it on 300:2500:10 (295-2505 nm; the trapezoids
        // over the table's rows from 300 to 2500 nm hold 1305.46 W m^-2, and
        // 295-300 and 2500-2505 nm add about 3 W m^-2), scaled at 2 AU.
        let e490 = Sun::new(SolarSpectrum::astm_e490(), 1.0, 0.53).unwrap();
        let ((lo, hi), total) = e490.table_irradiance_w_m2().unwrap();
        assert_eq!((lo, hi), (119.5, 1e6));
        assert!((total - 1366.1).abs() < 1.4, "{total}");
        let wide = WavelengthGrid::new(300.0, 2500.0, 10.0).unwrap();
        let in_band = e490.grid_irradiance_w_m2(&wide).unwrap();
        assert!((1306.0..1312.0).contains(&in_band), "{in_band}");
        let far = e490.at_distance_au(2.0).unwrap();
        let ((_, _), quarter) = far.table_irradiance_w_m2().unwrap();
        assert!((quarter / total - 0.25).abs() < 1e-12);
        assert!((far.grid_irradiance_w_m2(&wide).unwrap() / in_band - 0.25).abs() < 1e-12);
    }

    #[test]
    fn a_sun_moved_keeps_its_disc_radiance() {
        // Mars' preset sun: scale 1/1.524^2 (its implied distance), disc
        // 0.35 deg; moved to 1.381 AU (perihelion).
        let mars = Sun::new(SolarSpectrum::flat(1.0).unwrap(), 1.524f64.powi(-2), 0.35).unwrap();
        let perihelion = mars.at_distance_au(1.381).unwrap();
        assert!((perihelion.irradiance_scale() - 1.381f64.powi(-2)).abs() < 1e-15);
        assert!((perihelion.angular_diameter_deg() - 0.35 * 1.524 / 1.381).abs() < 1e-12);
        // Irradiance / solid angle is the disc's radiance: the same.
        let radiance = |sun: &Sun| sun.irradiance_scale() / sun.solid_angle_sr();
        let ratio = radiance(&perihelion) / radiance(&mars);
        assert!((ratio - 1.0).abs() < 1e-5, "{ratio}");
        // At 1 AU an Earth sun is itself.
        let earth = Sun::new(SolarSpectrum::flat(1.0).unwrap(), 1.0, 0.53).unwrap();
        assert_eq!(earth.at_distance_au(1.0).unwrap(), earth);
        let e = earth.at_distance_au(0.0).unwrap_err().to_string();
        assert!(e.contains("sun distance = 0 AU"), "{e}");
        assert!(earth.at_distance_au(f64::NAN).is_err());
    }

    #[test]
    fn invalid_suns_name_the_key() {
        let flat = || SolarSpectrum::flat(1.0).unwrap();
        let e = Sun::new(flat(), -1.0, 0.5).unwrap_err().to_string();
        assert!(e.contains("sun.irradiance_scale = -1"), "{e}");
        let e = Sun::new(flat(), 1.0, 90.0).unwrap_err().to_string();
        assert!(e.contains("sun.angular_diameter_deg = 90 deg"), "{e}");
    }
}
