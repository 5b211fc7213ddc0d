//! Directions in the observer's local frame, as users give them.
//!
//! Frame: x points east, y north, z up (the local zenith), right-handed.
//! Angles (the paper's Table 1 convention): elevation above the horizon in
//! degrees (-90 nadir .. 90 zenith), azimuth clockwise from north as seen
//! from above (0 north, 90 east, 180 south, 270 west).

use std::ops::{Add, Mul, Neg, Sub};

use crate::error::{Error, Result};

/// A 3-vector of f64 (positions in metres or unit directions).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl Vector3 {
    pub(crate) const fn new(x: f64, y: f64, z: f64) -> Vector3 {
        Vector3 { x, y, z }
    }

    pub(crate) fn dot(self, other: Vector3) -> f64 {
        self.x * other.x + self.y * other.y + self.z * other.z
    }

    pub(crate) fn cross(self, other: Vector3) -> Vector3 {
        Vector3::new(
            self.y * other.z - self.z * other.y,
            self.z * other.x - self.x * other.z,
            self.x * other.y - self.y * other.x,
        )
    }

    pub(crate) fn length(self) -> f64 {
        self.dot(self).sqrt()
    }

    /// The unit vector along `self` (self must be non-zero).
    pub(crate) fn normalized(self) -> Vector3 {
        self * (1.0 / self.length())
    }
}

impl Add for Vector3 {
    type Output = Vector3;
    fn add(self, o: Vector3) -> Vector3 {
        Vector3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl Sub for Vector3 {
    type Output = Vector3;
    fn sub(self, o: Vector3) -> Vector3 {
        Vector3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl Mul<f64> for Vector3 {
    type Output = Vector3;
    fn mul(self, s: f64) -> Vector3 {
        Vector3::new(self.x * s, self.y * s, self.z * s)
    }
}

impl Neg for Vector3 {
    type Output = Vector3;
    fn neg(self) -> Vector3 {
        Vector3::new(-self.x, -self.y, -self.z)
    }
}

/// A view direction as users give it: elevation above the horizon and
/// azimuth clockwise from north, degrees, checked once where it is made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewDirection {
    elevation_deg: f64,
    azimuth_deg: f64,
}

impl ViewDirection {
    /// `elevation_deg` in -90..=90 (negative: below the horizon) and a
    /// finite `azimuth_deg` (0 N, 90 E, 180 S, 270 W; any turn is accepted).
    pub fn new(elevation_deg: f64, azimuth_deg: f64) -> Result<ViewDirection> {
        check_elevation_azimuth("view", elevation_deg, azimuth_deg)?;
        Ok(ViewDirection {
            elevation_deg,
            azimuth_deg,
        })
    }

    /// Elevation above the horizon, degrees.
    pub fn elevation_deg(self) -> f64 {
        self.elevation_deg
    }

    /// Azimuth clockwise from north, degrees, as given.
    pub fn azimuth_deg(self) -> f64 {
        self.azimuth_deg
    }

    /// The unit vector in the east-north-up frame.
    pub(crate) fn to_vector(self) -> Vector3 {
        direction_from_elevation_azimuth(self.elevation_deg, self.azimuth_deg)
    }
}

/// Checks a direction as users give it: `elevation_deg` in -90..=90 and a
/// finite `azimuth_deg`; errors name `what` ("view elevation", "sun
/// azimuth").
pub(crate) fn check_elevation_azimuth(
    what: &str,
    elevation_deg: f64,
    azimuth_deg: f64,
) -> Result<()> {
    if !(-90.0..=90.0).contains(&elevation_deg) {
        return Err(Error::out_of_range(
            format!("{what} elevation"),
            elevation_deg,
            "deg",
            "-90..=90",
        ));
    }
    if !azimuth_deg.is_finite() {
        return Err(Error::out_of_range(
            format!("{what} azimuth"),
            azimuth_deg,
            "deg",
            "a finite angle",
        ));
    }
    Ok(())
}

/// Unit direction toward `elevation_deg` above the horizon at
/// `azimuth_deg` clockwise from north, in the east-north-up frame.
pub(crate) fn direction_from_elevation_azimuth(elevation_deg: f64, azimuth_deg: f64) -> Vector3 {
    let (sin_el, cos_el) = elevation_deg.to_radians().sin_cos();
    let (sin_az, cos_az) = azimuth_deg.to_radians().sin_cos();
    Vector3::new(cos_el * sin_az, cos_el * cos_az, sin_el)
}

/// `azimuth_deg` read modulo 360 into `[0, 360)`, degrees (-400 is 320,
/// 400 is 40; -0 and a negative angle too small to move off 360 are 0); a
/// value that is not finite is returned as it is, for the checks that
/// refuse it to name it.
pub fn azimuth_in_one_turn_deg(azimuth_deg: f64) -> f64 {
    if !azimuth_deg.is_finite() {
        return azimuth_deg;
    }
    let turned = azimuth_deg.rem_euclid(360.0) + 0.0;
    if turned >= 360.0 { 0.0 } else { turned }
}

/// Elevation above the horizon and azimuth clockwise from north (0..360),
/// both in degrees, of a unit direction in the east-north-up frame.
pub(crate) fn elevation_azimuth_from_direction(direction: Vector3) -> (f64, f64) {
    let elevation_deg = direction.z.clamp(-1.0, 1.0).asin().to_degrees();
    let azimuth_deg = direction
        .x
        .atan2(direction.y)
        .to_degrees()
        .rem_euclid(360.0);
    (elevation_deg, azimuth_deg)
}

/// Angle between two directions given as (elevation, azimuth) in degrees:
/// the scattering angle when one is the view and the other the sun
/// (0 = looking at the sun). Returns degrees.
pub fn angle_between_deg(
    elevation_a_deg: f64,
    azimuth_a_deg: f64,
    elevation_b_deg: f64,
    azimuth_b_deg: f64,
) -> f64 {
    let a = direction_from_elevation_azimuth(elevation_a_deg, azimuth_a_deg);
    let b = direction_from_elevation_azimuth(elevation_b_deg, azimuth_b_deg);
    // atan2 of |a x b| and a.b keeps full precision near 0 and 180 degrees.
    a.cross(b).length().atan2(a.dot(b)).to_degrees()
}

/// An orthonormal basis (t1, t2) perpendicular to the unit vector `n`
/// (Duff et al. 2017, "Building an orthonormal basis, revisited").
pub(crate) fn perpendicular_basis(n: Vector3) -> (Vector3, Vector3) {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vector3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vector3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The unit vector at angle acos(`cos_theta`) from the unit `axis`, at
/// azimuth `phi` about it.
pub(crate) fn direction_about(axis: Vector3, cos_theta: f64, phi: f64) -> Vector3 {
    let (t1, t2) = perpendicular_basis(axis);
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let (sin_phi, cos_phi) = phi.sin_cos();
    (t1 * (sin_theta * cos_phi) + t2 * (sin_theta * sin_phi) + axis * cos_theta).normalized()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perpendicular_basis_is_orthonormal() {
        for n in [
            Vector3::new(0.0, 0.0, 1.0),
            Vector3::new(0.0, 0.0, -1.0),
            Vector3::new(0.6, 0.0, 0.8),
            Vector3::new(-0.48, 0.6, -0.64),
            Vector3::new(1.0, 0.0, 0.0),
        ] {
            let (a, b) = perpendicular_basis(n);
            for (x, y) in [(a, a), (b, b), (n, n)] {
                assert!((x.dot(y) - 1.0).abs() < 1e-14);
            }
            for (x, y) in [(a, b), (a, n), (b, n)] {
                assert!(x.dot(y).abs() < 1e-14);
            }
            let d = direction_about(n, 0.3, 1.0);
            assert!((d.dot(n) - 0.3).abs() < 1e-14);
        }
    }

    #[test]
    fn azimuths_are_read_into_one_turn() {
        for (given, turned) in [
            (-400.0, 320.0),
            (400.0, 40.0),
            (360.0, 0.0),
            (720.0, 0.0),
            (-90.0, 270.0),
            (180.0, 180.0),
            (-0.0, 0.0),
            (-1e-20, 0.0),
        ] {
            let got = azimuth_in_one_turn_deg(given);
            assert_eq!(got, turned, "{given}");
            assert!(got.is_sign_positive() && got < 360.0, "{given}: {got}");
        }
        assert_eq!(azimuth_in_one_turn_deg(f64::INFINITY), f64::INFINITY);
        assert!(azimuth_in_one_turn_deg(f64::NAN).is_nan());
    }

    #[test]
    fn compass_directions() {
        let close = |a: Vector3, b: Vector3| (a - b).length() < 1e-15;
        assert!(close(
            direction_from_elevation_azimuth(0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0)
        ));
        assert!(close(
            direction_from_elevation_azimuth(0.0, 90.0),
            Vector3::new(1.0, 0.0, 0.0)
        ));
        assert!(close(
            direction_from_elevation_azimuth(90.0, 123.0),
            Vector3::new(0.0, 0.0, 1.0)
        ));
        assert!(close(
            direction_from_elevation_azimuth(0.0, 180.0),
            Vector3::new(0.0, -1.0, 0.0)
        ));
    }

    #[test]
    fn elevation_azimuth_round_trip() {
        for (el, az) in [
            (17.0, 347.0),
            (36.0, 207.0),
            (-10.0, 90.0),
            (0.0, 0.0),
            (89.0, 271.5),
        ] {
            let (el2, az2) =
                elevation_azimuth_from_direction(direction_from_elevation_azimuth(el, az));
            assert!(
                (el - el2).abs() < 1e-12 && (az - az2).abs() < 1e-10,
                "{el} {az} -> {el2} {az2}"
            );
        }
    }

    #[test]
    fn paper_table_1_scattering_angle() {
        // Sun (36, 207), view (17, 347): 114.885824 deg in the reference radiance file.
        let angle = angle_between_deg(17.0, 347.0, 36.0, 207.0);
        assert!((angle - 114.885824).abs() < 1e-6, "{angle}");
    }
}
