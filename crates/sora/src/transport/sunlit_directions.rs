//! Directions from a point in the planet's shadow toward the sunlit air:
//! the path tracer's second direction sampler in deep twilight (issue 11).
//!
//! **Why.** With the sun more than about 8 degrees below the horizon every
//! photon the eye receives was scattered at least twice: once in the
//! sunlit air above the Earth's shadow and then, in the shadow, toward the
//! eye. A path traced from the eye collides first in the shadow, where
//! next-event estimation toward the sun scores nothing; by its phase
//! function (nearly isotropic for air) it then leaves in a direction that
//! reaches sunlit air at a usable density only by chance: with the sun 10
//! degrees down, a ray from the ground first meets sunlight about 24 km up
//! when it leaves level toward the sun, and higher the steeper or the
//! further round in azimuth it goes, so the useful directions are a band a
//! few degrees above the horizon and a few tens of degrees either side of
//! the sun's azimuth: a few per cent of the sphere.
//!
//! **The density.** In the vertex's local frame (up the radial direction,
//! azimuth phi from the sun's vertical, mu the cosine of the zenith
//! angle), q(w) = p_mu(mu) p_phi(phi) sr^-1 (d omega = d mu d phi):
//! - p_mu: an exponential in mu above the geometric horizon mu_0 =
//!   -sqrt(1 - (R_ground / r)^2) (below it the ray meets the ground),
//!   truncated at 1: p_mu = exp(-(mu - mu_0) / k) / (k (1 - exp(-(1 - mu_0)
//!   / k))), with k = [`ELEVATION_SCALE`];
//! - p_phi: the wrapped Cauchy distribution about the sun's azimuth,
//!   p_phi = (1 - rho^2) / (2 pi (1 + rho^2 - 2 rho cos phi)), with rho =
//!   [`AZIMUTH_CONCENTRATION`] (half width at half maximum about -ln rho).
//!
//! Both are inverted in closed form. q is positive for every direction
//! above the horizon, so the path tracer's mixture of it with the phase
//! function stays unbiased whatever the shape (only the variance depends
//! on it): the shape is a guess at where the sunlit air is, not a model of
//! it. Written here because it is our sampling design, not a generic
//! distribution a crate provides.

use std::f64::consts::PI;

use crate::geometry::Vector3;

/// k of p_mu (module docs): the mean height of the sampled directions
/// above the horizon is about 0.1 in the cosine of their zenith angle (6
/// degrees).
const ELEVATION_SCALE: f64 = 0.1;

/// rho of p_phi (module docs): half of the directions lie within about 30
/// degrees of the sun's azimuth.
const AZIMUTH_CONCENTRATION: f64 = 0.6;

/// The sampler's frame at one vertex.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SunlitDirections {
    up: Vector3,
    /// Horizontal, toward the sun's azimuth.
    toward_sun: Vector3,
    /// up x toward_sun.
    side: Vector3,
    /// The cosine of the zenith angle of the horizon (the ground's tangent).
    horizon_mu: f64,
    /// 1 - exp(-(1 - horizon_mu) / k), p_mu's normalisation.
    elevation_mass: f64,
}

impl SunlitDirections {
    /// The sampler at `position` (m from the planet's centre, above the
    /// ground of radius `ground_radius_m`) for the unit vector `sun` toward
    /// the sun.
    pub(crate) fn new(position: Vector3, sun: Vector3, ground_radius_m: f64) -> SunlitDirections {
        let r = position.length();
        let up = position * (1.0 / r);
        let horizontal = sun - up * sun.dot(up);
        // The sun straight below (the antipode of the subsolar point): no
        // azimuth is special; any horizontal axis will do.
        let toward_sun = if horizontal.length() > 1e-9 {
            horizontal.normalized()
        } else {
            crate::geometry::perpendicular_basis(up).0
        };
        let ratio = (ground_radius_m / r).min(1.0);
        let horizon_mu = -(1.0 - ratio * ratio).max(0.0).sqrt();
        SunlitDirections {
            up,
            toward_sun,
            side: up.cross(toward_sun),
            horizon_mu,
            elevation_mass: -(-(1.0 - horizon_mu) / ELEVATION_SCALE).exp_m1(),
        }
    }

    /// A direction drawn from q with the uniform numbers `u`.
    pub(crate) fn sample(&self, u: [f64; 2]) -> Vector3 {
        let mu = (self.horizon_mu - ELEVATION_SCALE * (-u[0] * self.elevation_mass).ln_1p())
            .clamp(-1.0, 1.0);
        let rho = AZIMUTH_CONCENTRATION;
        let phi = 2.0 * ((1.0 - rho) / (1.0 + rho) * (PI * (u[1] - 0.5)).tan()).atan();
        let sin_theta = (1.0 - mu * mu).max(0.0).sqrt();
        let (sin_phi, cos_phi) = phi.sin_cos();
        (self.toward_sun * (sin_theta * cos_phi) + self.side * (sin_theta * sin_phi) + self.up * mu)
            .normalized()
    }

    /// q(`direction`), sr^-1 (zero below the horizon).
    pub(crate) fn pdf(&self, direction: Vector3) -> f64 {
        let mu = direction.dot(self.up);
        if mu < self.horizon_mu {
            return 0.0;
        }
        let p_mu = (-(mu - self.horizon_mu) / ELEVATION_SCALE).exp()
            / (ELEVATION_SCALE * self.elevation_mass);
        let (x, y) = (direction.dot(self.toward_sun), direction.dot(self.side));
        let horizontal = x.hypot(y);
        let cos_phi = if horizontal > 0.0 {
            x / horizontal
        } else {
            1.0
        };
        let rho = AZIMUTH_CONCENTRATION;
        let p_phi = (1.0 - rho * rho) / (2.0 * PI * (1.0 + rho * rho - 2.0 * rho * cos_phi));
        p_mu * p_phi
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::random::RandomStream;

    /// q integrates to one over the sphere (a midpoint rule in mu and phi,
    /// fine where p_mu falls fastest), and the sampled directions have q's
    /// moments: the mean cosine with the local vertical and with the
    /// sun's horizontal direction, against the same integrals, within four
    /// standard errors of 200 000 draws.
    #[test]
    fn the_density_is_normalised_and_is_the_one_sampled() {
        let ground = 6_371_000.0;
        let position = Vector3::new(1000.0, -3000.0, ground + 5000.0);
        let sun = Vector3::new(0.3, 0.1, -0.2).normalized();
        let q = SunlitDirections::new(position, sun, ground);
        let (m, p) = (4000, 720);
        let (mut total, mut mean_up, mut mean_sun) = (0.0, 0.0, 0.0);
        for a in 0..m {
            let mu = -1.0 + 2.0 * (a as f64 + 0.5) / m as f64;
            for b in 0..p {
                let phi = 2.0 * PI * (b as f64 + 0.5) / p as f64;
                let s = (1.0 - mu * mu).sqrt();
                let w = q.toward_sun * (s * phi.cos()) + q.side * (s * phi.sin()) + q.up * mu;
                let weight = q.pdf(w) * (2.0 / m as f64) * (2.0 * PI / p as f64);
                total += weight;
                mean_up += weight * w.dot(q.up);
                mean_sun += weight * w.dot(q.toward_sun);
            }
        }
        assert!((total - 1.0).abs() < 1e-3, "integral {total}");
        let mut random = RandomStream::new(5, 0);
        let draws = 200_000;
        let (mut up, mut up2, mut toward, mut toward2) = (0.0, 0.0, 0.0, 0.0);
        for _ in 0..draws {
            let w = q.sample([random.next_f64(), random.next_f64()]);
            assert!(q.pdf(w) > 0.0);
            let (a, b) = (w.dot(q.up), w.dot(q.toward_sun));
            up += a;
            up2 += a * a;
            toward += b;
            toward2 += b * b;
        }
        let n = draws as f64;
        for (name, sum, sum2, expected) in [
            ("up", up, up2, mean_up),
            ("toward the sun", toward, toward2, mean_sun),
        ] {
            let mean = sum / n;
            let error = ((sum2 / n - mean * mean) / n).sqrt();
            assert!(
                (mean - expected).abs() < 4.0 * error,
                "{name}: {mean} against {expected} (+-{error})"
            );
        }
    }

    /// Below the horizon q is zero; just above it, it is largest.
    #[test]
    fn nothing_below_the_horizon() {
        let ground = 6_371_000.0;
        let position = Vector3::new(0.0, 0.0, ground + 2000.0);
        let sun = Vector3::new(1.0, 0.0, -0.17).normalized();
        let q = SunlitDirections::new(position, sun, ground);
        let level = |mu: f64| Vector3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
        assert_eq!(q.pdf(level(q.horizon_mu - 1e-6)), 0.0);
        assert!(q.pdf(level(q.horizon_mu + 1e-6)) > q.pdf(level(0.5)));
        assert!(q.pdf(level(0.5)) > q.pdf(Vector3::new(-0.866, 0.0, 0.5)));
    }
}
