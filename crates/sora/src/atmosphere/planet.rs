//! The planet: a sphere of radius R_ground under a spherical shell of
//! atmosphere up to R_top = R_ground + atmosphere height, above a
//! Lambertian ground.
//!
//! Geometry follows Bruneton's precomputed atmospheric scattering (2017):
//! a point is described by its distance r from the planet's centre and a
//! direction by mu, the cosine of its angle from the local zenith. A ray
//! from (r, mu) meets the sphere of radius R at distance d where
//! d^2 + 2 r mu d + r^2 - R^2 = 0. Planets from 1e5 m (an asteroid) to
//! 1e10 m work; a huge radius approximates a plane-parallel atmosphere.
//! Everything is f64: at R = 1e10 m a metre is 1e-10 of r, so the
//! quadratic's roots are written in the forms that do not cancel
//! (R_top^2 - r^2 = (R_top - r)(R_top + r); the small root as c / q).
//!
//! The ground reflects as a Lambertian surface of albedo a(lambda) (a
//! constant or a table over wavelength): reflected radiance = a E / pi for
//! an irradiance E.
//!
//! The ground may stand above the sea ([`Planet::with_ground_altitude_m`]:
//! a site at 1 449 m). The file's radius and atmosphere height are then
//! the sea level's and the top's above it, every species' profile keeps
//! its altitudes above sea level, and the sky is the sea-level one with
//! everything below the ground taken away
//! ([`crate::Atmosphere::compute_optics`]): R_ground = R_sea + g, the
//! atmosphere g thinner.

use crate::error::{Error, Result};
use crate::spectrum::{SampledSpectrum, Spectrum, WavelengthGrid};

/// Smallest supported planet radius, m.
pub const MIN_PLANET_RADIUS_M: f64 = 1e5;
/// Largest supported planet radius, m.
pub const MAX_PLANET_RADIUS_M: f64 = 1e10;
/// Smallest supported atmosphere height, m: 1 km, the thinnest shell the
/// reference tests use (a plane-parallel slab); a shell of a nanometre left
/// the tables' steps at zero width and the spectrum NaN.
pub const MIN_ATMOSPHERE_HEIGHT_M: f64 = 1e3;
/// Largest supported atmosphere height, m: 1,000 km, ten times Earth's
/// 100 km top, where one spectrum still takes seconds (at 1.93e7 m a
/// spectrum or a 16 x 16 image took more than a minute).
pub const MAX_ATMOSPHERE_HEIGHT_M: f64 = 1e6;

/// The least air a raised ground leaves below the top of the atmosphere, m.
pub const MIN_AIR_ABOVE_GROUND_M: f64 = 1e3;

/// The lowest ground altitude, m (the Dead Sea's shore is at -430 m).
pub const MIN_GROUND_ALTITUDE_M: f64 = -1e3;

/// A validated planet.
#[derive(Debug, Clone, PartialEq)]
pub struct Planet {
    /// Radius of the sea level (the profiles' zero), m.
    radius_m: f64,
    /// Height of the top of the atmosphere above sea level, m.
    atmosphere_height_m: f64,
    /// Height of the ground above sea level, m.
    ground_altitude_m: f64,
    ground_albedo: Spectrum,
}

impl Planet {
    /// A planet of radius `radius_m` (1e5..=1e10 m) with an atmosphere
    /// `atmosphere_height_m` thick (1e3..=1e6 m) over a Lambertian ground
    /// of albedo `ground_albedo` (values in [0, 1]). Errors name the keys
    /// `planet.radius_m`, `planet.atmosphere_height_m`, `planet.ground_albedo`.
    pub fn new(radius_m: f64, atmosphere_height_m: f64, ground_albedo: Spectrum) -> Result<Planet> {
        if !(MIN_PLANET_RADIUS_M..=MAX_PLANET_RADIUS_M).contains(&radius_m) {
            return Err(Error::out_of_range(
                "planet.radius_m",
                radius_m,
                "m",
                format!("{MIN_PLANET_RADIUS_M:e}..={MAX_PLANET_RADIUS_M:e}"),
            ));
        }
        if !(MIN_ATMOSPHERE_HEIGHT_M..=MAX_ATMOSPHERE_HEIGHT_M).contains(&atmosphere_height_m) {
            return Err(Error::out_of_range(
                "planet.atmosphere_height_m",
                atmosphere_height_m,
                "m",
                format!("{MIN_ATMOSPHERE_HEIGHT_M:e}..={MAX_ATMOSPHERE_HEIGHT_M:e}"),
            ));
        }
        match &ground_albedo {
            Spectrum::Constant(a) => check_albedo("planet.ground_albedo", *a)?,
            Spectrum::Tabulated(table) => {
                for (i, a) in table.values().iter().enumerate() {
                    check_albedo(&format!("planet.ground_albedo.albedo[{i}]"), *a)?;
                }
            }
        }
        Ok(Planet {
            radius_m,
            atmosphere_height_m,
            ground_altitude_m: 0.0,
            ground_albedo,
        })
    }

    /// This planet with its ground `ground_altitude_m` above sea level
    /// (0, or -1000 m up to 1 km below the top of the atmosphere): the sky of a
    /// site on a plateau or a mountain. The radius and the atmosphere
    /// height it was made with stay the sea level's.
    pub fn with_ground_altitude_m(mut self, ground_altitude_m: f64) -> Result<Planet> {
        if ground_altitude_m == 0.0 {
            // Sea level: the planet as made, however thin its air.
            self.ground_altitude_m = 0.0;
            return Ok(self);
        }
        let highest = self.atmosphere_height_m - MIN_AIR_ABOVE_GROUND_M;
        if !(MIN_GROUND_ALTITUDE_M..=highest).contains(&ground_altitude_m) {
            return Err(Error::out_of_range(
                "planet.ground_altitude_m",
                ground_altitude_m,
                "m",
                format!(
                    "{MIN_GROUND_ALTITUDE_M}..={highest} (at least {MIN_AIR_ABOVE_GROUND_M} m below the top of the atmosphere, planet.atmosphere_height_m above sea level)"
                ),
            ));
        }
        self.ground_altitude_m = ground_altitude_m;
        Ok(self)
    }

    /// This planet with another ground albedo (its geometry unchanged).
    pub fn with_ground_albedo(&self, ground_albedo: Spectrum) -> Result<Planet> {
        Planet::new(self.radius_m, self.atmosphere_height_m, ground_albedo)?
            .with_ground_altitude_m(self.ground_altitude_m)
    }

    /// Radius of the ground, m: the sea level's plus the ground altitude.
    pub fn radius_m(&self) -> f64 {
        self.radius_m + self.ground_altitude_m
    }

    /// Height of the top of the atmosphere above the ground, m.
    pub fn atmosphere_height_m(&self) -> f64 {
        self.atmosphere_height_m - self.ground_altitude_m
    }

    /// Height of the ground above sea level, m (0 unless
    /// [`Planet::with_ground_altitude_m`] raised it).
    pub fn ground_altitude_m(&self) -> f64 {
        self.ground_altitude_m
    }

    /// Radius of the sea level, m (the file's `planet.radius_m`).
    pub fn sea_level_radius_m(&self) -> f64 {
        self.radius_m
    }

    /// Height of the top of the atmosphere above sea level, m (the file's
    /// `planet.atmosphere_height_m`).
    pub fn top_above_sea_level_m(&self) -> f64 {
        self.atmosphere_height_m
    }

    /// Radius of the top of the atmosphere, m.
    pub(crate) fn top_radius_m(&self) -> f64 {
        self.radius_m + self.atmosphere_height_m
    }

    /// Ground albedo as a function of wavelength.
    pub fn ground_albedo(&self) -> &Spectrum {
        &self.ground_albedo
    }

    /// Ground albedo at each wavelength of `grid`; a table must cover it.
    pub(crate) fn sample_ground_albedo(&self, grid: &WavelengthGrid) -> Result<SampledSpectrum> {
        self.ground_albedo.sample_at_wavelengths(grid).map_err(|e| {
            Error::InvalidSpectrum(format!("planet.ground_albedo: {}", strip_prefix(&e)))
        })
    }

    /// Distance from a point at radius `r_m` (inside the atmosphere) along
    /// a direction of zenith cosine `mu` to the top of the atmosphere, m.
    #[cfg(test)]
    pub(crate) fn distance_to_top_of_atmosphere(&self, r_m: f64, mu: f64) -> f64 {
        crate::geometry::distance_to_top_boundary(r_m, mu, self.top_radius_m())
    }

    /// True when a ray from radius `r_m` with zenith cosine `mu` hits the
    /// ground.
    #[cfg(test)]
    pub(crate) fn ray_intersects_ground(&self, r_m: f64, mu: f64) -> bool {
        crate::geometry::ray_intersects_ground(r_m, mu, self.radius_m())
    }

    /// Distance to the ground along (r, mu), m, or `None` when the ray
    /// misses it.
    #[cfg(test)]
    pub(crate) fn distance_to_ground(&self, r_m: f64, mu: f64) -> Option<f64> {
        crate::geometry::distance_to_ground_boundary(r_m, mu, self.radius_m())
    }
}

fn check_albedo(name: &str, albedo: f64) -> Result<()> {
    if (0.0..=1.0).contains(&albedo) {
        Ok(())
    } else {
        Err(Error::out_of_range(name, albedo, "1", "0..=1"))
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

    fn earth() -> Planet {
        Planet::new(6360e3, 100e3, Spectrum::Constant(0.3)).unwrap()
    }

    #[test]
    fn vertical_and_horizontal_distances() {
        let planet = earth();
        let r = planet.radius_m();
        assert!((planet.distance_to_top_of_atmosphere(r, 1.0) - 100e3).abs() < 1e-6);
        assert!((planet.distance_to_top_of_atmosphere(r, -1.0) - (2.0 * r + 100e3)).abs() < 1e-3);
        // Horizontal from the ground: sqrt(top^2 - r^2).
        let expected = (planet.top_radius_m().powi(2) - r * r).sqrt();
        assert!((planet.distance_to_top_of_atmosphere(r, 0.0) - expected).abs() < 1e-6);
        // From 1 km up, looking straight down: 1 km to the ground.
        let d = planet.distance_to_ground(r + 1000.0, -1.0).unwrap();
        assert!((d - 1000.0).abs() < 1e-6, "{d}");
        assert!(planet.distance_to_ground(r + 1000.0, 0.5).is_none());
        // A grazing ray from 1 km misses the ground just below the tangent.
        let mu_horizon = -(1.0 - (r / (r + 1000.0)).powi(2)).sqrt();
        assert!(planet.ray_intersects_ground(r + 1000.0, mu_horizon - 1e-6));
        assert!(!planet.ray_intersects_ground(r + 1000.0, mu_horizon + 1e-6));
    }

    #[test]
    fn huge_planet_is_plane_parallel() {
        let planet = Planet::new(1e10, 100e3, Spectrum::Constant(0.0)).unwrap();
        let r = planet.radius_m() + 2000.0;
        for mu in [1.0, 0.5, 0.1] {
            let d = planet.distance_to_top_of_atmosphere(r, mu);
            let flat = 98e3 / mu;
            // Curvature shortens the path by ~ H / (2 R mu^2) relatively.
            let curvature = 98e3 / (2.0 * 1e10 * mu * mu);
            assert!(
                (d / flat - 1.0).abs() < 2.0 * curvature + 1e-12,
                "mu {mu}: {d} vs {flat}"
            );
        }
        for mu in [-1.0, -0.5, -0.1] {
            let d = planet.distance_to_ground(r, mu).unwrap();
            assert!((d / (2000.0 / -mu) - 1.0).abs() < 1e-4, "mu {mu}: {d}");
        }
    }

    #[test]
    fn the_atmosphere_height_bounds_are_inclusive() {
        for height in [MIN_ATMOSPHERE_HEIGHT_M, MAX_ATMOSPHERE_HEIGHT_M] {
            assert!(Planet::new(6e6, height, Spectrum::Constant(0.0)).is_ok());
        }
    }

    #[test]
    fn small_planet_works() {
        let planet = Planet::new(1e5, 1e4, Spectrum::Constant(0.1)).unwrap();
        assert!((planet.distance_to_top_of_atmosphere(1e5, 1.0) - 1e4).abs() < 1e-9);
    }

    #[test]
    fn invalid_planets_name_the_key() {
        let cases = [
            (
                Planet::new(-1.0, 1e5, Spectrum::Constant(0.0)),
                "planet.radius_m = -1 m",
            ),
            (
                Planet::new(1e4, 1e5, Spectrum::Constant(0.0)),
                "planet.radius_m = 10000 m",
            ),
            (
                Planet::new(f64::NAN, 1e5, Spectrum::Constant(0.0)),
                "planet.radius_m = NaN",
            ),
            (
                Planet::new(6e6, -5.0, Spectrum::Constant(0.0)),
                "planet.atmosphere_height_m = -5 m",
            ),
            // A nanometre of air (NaN at the end, once) and 19,300 km (more
            // than a minute a spectrum, once): refused, naming the bounds.
            (
                Planet::new(6e6, 1e-9, Spectrum::Constant(0.0)),
                "planet.atmosphere_height_m = 1e-9 m is out of range: allowed 1e3..=1e6 m",
            ),
            (
                Planet::new(6e6, 1.93e7, Spectrum::Constant(0.0)),
                "planet.atmosphere_height_m = 1.93e7 m is out of range: allowed 1e3..=1e6 m",
            ),
            (
                Planet::new(6e6, 1e5, Spectrum::Constant(1.5)),
                "planet.ground_albedo = 1.5",
            ),
        ];
        for (result, expected) in cases {
            let message = result.unwrap_err().to_string();
            assert!(message.contains(expected), "{message}");
        }
    }
}
