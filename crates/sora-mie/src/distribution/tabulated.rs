//! # A size distribution as measured: tabulated dV/d ln r
//!
//! Sun-photometer inversions (AERONET publishes 22 log-spaced radii from
//! 0.05 to 15 um) give the column volume size distribution
//! `v(t) = dV/d ln r` (um^3 um^-2) at radii `r_1 < ... < r_N`, `t = ln r`.
//! Between the radii `v` is linear in `t` (the trapezoids in ln r that the
//! inversion's own volume integrals assume) and it is zero outside
//! `[r_1, r_N]`. The number distribution is
//!
//! ```text
//!     dN/d ln r = v(ln r) / (4/3 pi r^3)
//! ```
//!
//! and every moment of it is a sum over segments of integrals of a linear
//! function times `exp(c t)`, in closed form: on `[t_0, t_0 + h]` with end
//! values `v_0`, `v_1` and `z = c h`,
//!
//! ```text
//!     integral v e^{ct} dt = e^{c t_0} h (v_0 E(z) + (v_1 - v_0) G(z)),
//!     E(z) = (e^z - 1) / z,   G(z) = ((z - 1) e^z + 1) / z^2 = sum_n (n + 1) z^n / (n + 2)!
//! ```
//!
//! (`G` by its series for `|z| < 0.5`, where the closed form cancels). So the
//! column volume is `sum h (v_0 + v_1) / 2` (`c = 0`), the column number
//! `integral v e^{-3t} dt / (4/3 pi)`, and the effective radius
//! `r_eff = <r^3>/<r^2> = integral v dt / integral v e^{-t} dt`.
//!
//! The radius quadrature ([`super::quadrature`]) integrates over the table's
//! support clipped to any window, with every table radius a panel edge (the
//! density has a kink there), at the node density of the importance peak
//! everywhere (the importance depth is taken as 0: a table need not be
//! log-concave, so no tail is relaxed), with panels no wider than the spread
//! of the volume distribution in ln r.

use super::Number;
use std::f64::consts::PI;

/// Most points of a table (a bound on memory and on quadrature panels).
pub const MAX_TABULATED_POINTS: usize = 100_000;

/// A volume size distribution dV/d ln r tabulated at increasing radii
/// (see the module docs). Radii in metres; the values in the unit they were
/// given in (conventionally um^3 um^-2, AERONET's).
#[derive(Debug, Clone, PartialEq)]
pub struct TabulatedVolumeDistribution {
    ln_radius_m: Vec<f64>,
    volume_per_ln_radius: Vec<f64>,
    /// integral v e^{-3 t} dt (t = ln r, r in m): the number normalisation.
    number_integral: f64,
}

/// Why a table was refused (the caller names the key).
#[derive(Debug, Clone, PartialEq)]
pub enum TabulatedDistributionError {
    /// Fewer than 2 points, more than [`MAX_TABULATED_POINTS`], or radii and
    /// values of different lengths.
    BadLength { radii: usize, values: usize },
    /// A radius that is not finite and > 0.
    BadRadius { index: usize, radius_um: f64 },
    /// Radii that do not increase strictly.
    NotIncreasing {
        index: usize,
        previous_um: f64,
        radius_um: f64,
    },
    /// A value that is not finite and >= 0.
    BadValue { index: usize, value: f64 },
    /// Every value 0: no particles.
    AllZero,
}

impl std::fmt::Display for TabulatedDistributionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::BadLength { radii, values } => write!(
                f,
                "a tabulated size distribution needs radii and values of the same length, between 2 and {MAX_TABULATED_POINTS} points (got {radii} radii and {values} values)"
            ),
            Self::BadRadius { index, radius_um } => write!(
                f,
                "radius {index} = {} um is invalid: it must be finite and greater than 0",
                Number(*radius_um)
            ),
            Self::NotIncreasing {
                index,
                previous_um,
                radius_um,
            } => write!(
                f,
                "radius {index} = {} um is not greater than the one before it ({} um): radii must increase strictly",
                Number(*radius_um),
                Number(*previous_um)
            ),
            Self::BadValue { index, value } => write!(
                f,
                "value {index} = {value} um^3/um^2 is invalid: dV/dlnr must be finite and >= 0"
            ),
            Self::AllZero => write!(f, "every value is 0: the distribution holds no particles"),
        }
    }
}

impl std::error::Error for TabulatedDistributionError {}

/// E(z) = (e^z - 1)/z, 1 at z = 0.
fn exprel(z: f64) -> f64 {
    if z == 0.0 { 1.0 } else { z.exp_m1() / z }
}

/// G(z) = ((z - 1) e^z + 1)/z^2 = integral_0^1 u e^{zu} du, 1/2 at z = 0.
fn first_moment_kernel(z: f64) -> f64 {
    if z.abs() < 0.5 {
        // sum_n (n + 1) z^n / (n + 2)!: 20 terms leave < 0.5^20 / 20! of it.
        let (mut sum, mut z_power, mut factorial) = (0.0, 1.0, 2.0);
        for n in 0..20 {
            sum += (n as f64 + 1.0) * z_power / factorial;
            z_power *= z;
            factorial *= n as f64 + 3.0;
        }
        sum
    } else {
        ((z - 1.0) * z.exp() + 1.0) / (z * z)
    }
}

/// integral over [t0, t1] of the linear v (v0 at t0, v1 at t1) times e^{ct}.
fn segment_integral(t0: f64, t1: f64, v0: f64, v1: f64, c: f64) -> f64 {
    let h = t1 - t0;
    let z = c * h;
    (c * t0).exp() * h * (v0 * exprel(z) + (v1 - v0) * first_moment_kernel(z))
}

impl TabulatedVolumeDistribution {
    /// From radii (um, > 0, strictly increasing) and dV/d ln r values (>= 0,
    /// not all 0), at least 2 points. Errors quote the radii in um, as given.
    pub fn from_micrometres(
        radii_um: &[f64],
        volume_per_ln_radius: &[f64],
    ) -> Result<Self, TabulatedDistributionError> {
        let n = radii_um.len();
        if n != volume_per_ln_radius.len() || !(2..=MAX_TABULATED_POINTS).contains(&n) {
            return Err(TabulatedDistributionError::BadLength {
                radii: n,
                values: volume_per_ln_radius.len(),
            });
        }
        for (index, &radius_um) in radii_um.iter().enumerate() {
            if !(radius_um.is_finite() && radius_um > 0.0) {
                return Err(TabulatedDistributionError::BadRadius { index, radius_um });
            }
            if index > 0 && radius_um <= radii_um[index - 1] {
                return Err(TabulatedDistributionError::NotIncreasing {
                    index,
                    previous_um: radii_um[index - 1],
                    radius_um,
                });
            }
        }
        for (index, &value) in volume_per_ln_radius.iter().enumerate() {
            if !(value.is_finite() && value >= 0.0) {
                return Err(TabulatedDistributionError::BadValue { index, value });
            }
        }
        if volume_per_ln_radius.iter().all(|&v| v == 0.0) {
            return Err(TabulatedDistributionError::AllZero);
        }
        let mut table = Self {
            ln_radius_m: radii_um.iter().map(|r| (r * 1e-6).ln()).collect(),
            volume_per_ln_radius: volume_per_ln_radius.to_vec(),
            number_integral: 0.0,
        };
        table.number_integral = table.moment_integral(-3.0);
        Ok(table)
    }

    /// The table's radii (m), increasing.
    pub fn radii_m(&self) -> impl Iterator<Item = f64> + '_ {
        self.ln_radius_m.iter().map(|t| t.exp())
    }

    /// ln of the first and last radius (m).
    pub fn ln_radius_support(&self) -> (f64, f64) {
        (
            self.ln_radius_m[0],
            self.ln_radius_m[self.ln_radius_m.len() - 1],
        )
    }

    /// ln r (m) of every table point.
    pub fn ln_radii(&self) -> &[f64] {
        &self.ln_radius_m
    }

    /// integral v(t) e^{c t} dt over [t_a, t_b] ∩ support (t = ln r, r in m).
    fn moment_integral_between(&self, c: f64, t_a: f64, t_b: f64) -> f64 {
        let mut sum = 0.0;
        for i in 0..self.ln_radius_m.len() - 1 {
            let (t0, t1) = (self.ln_radius_m[i], self.ln_radius_m[i + 1]);
            let (lo, hi) = (t0.max(t_a), t1.min(t_b));
            if lo >= hi {
                continue;
            }
            sum += segment_integral(lo, hi, self.value_at(lo), self.value_at(hi), c);
        }
        sum
    }

    fn moment_integral(&self, c: f64) -> f64 {
        let (lo, hi) = self.ln_radius_support();
        self.moment_integral_between(c, lo, hi)
    }

    /// dV/d ln r at t = ln r (r in m), linear between the points, 0 outside.
    pub fn value_at(&self, ln_radius: f64) -> f64 {
        let t = &self.ln_radius_m;
        let (lo, hi) = self.ln_radius_support();
        if !(lo..=hi).contains(&ln_radius) {
            return 0.0;
        }
        // The segment [t_i, t_{i+1}] holding ln_radius.
        let i = t.partition_point(|&x| x <= ln_radius).clamp(1, t.len() - 1) - 1;
        let fraction = (ln_radius - t[i]) / (t[i + 1] - t[i]);
        let (v0, v1) = (
            self.volume_per_ln_radius[i],
            self.volume_per_ln_radius[i + 1],
        );
        v0 + fraction * (v1 - v0)
    }

    /// Column volume integral dV/d ln r d ln r, in the values' unit
    /// (um^3 um^-2 for AERONET's): the trapezoid sum, exact for the table.
    pub fn column_volume(&self) -> f64 {
        self.moment_integral(0.0)
    }

    /// Column number integral dV/d ln r / (4/3 pi r^3) d ln r, per m^2 when the
    /// values are in um^3 um^-2 (1 um^3 um^-2 = 1e-6 m^3 m^-2).
    pub fn column_number_per_m2_from_um3_per_um2(&self) -> f64 {
        1e-6 * self.number_integral / (4.0 / 3.0 * PI)
    }

    /// dN/d ln r per particle at `radius_m` (dimensionless; 0 outside the table).
    pub fn number_density_per_ln_radius(&self, radius_m: f64) -> f64 {
        let t = radius_m.ln();
        self.value_at(t) * (-3.0 * t).exp() / self.number_integral
    }

    /// Fraction of the particles with radius in [min_radius_m, max_radius_m].
    pub fn number_fraction_between(&self, min_radius_m: f64, max_radius_m: f64) -> f64 {
        self.moment_integral_between(-3.0, min_radius_m.ln(), max_radius_m.ln())
            / self.number_integral
    }

    /// Effective radius `<r^3>/<r^2> = integral v dt / integral v e^{-t} dt` (m), closed form.
    pub fn effective_radius_m(&self) -> f64 {
        self.moment_integral(0.0) / self.moment_integral(-1.0)
    }

    /// Effective variance `<r^4><r^2>/<r^3>^2 - 1`, closed form.
    pub fn effective_variance(&self) -> f64 {
        let v = self.moment_integral(0.0);
        self.moment_integral(1.0) * self.moment_integral(-1.0) / (v * v) - 1.0
    }

    /// Standard deviation of ln r under the volume distribution: the scale
    /// of the quadrature's panels (s for a sampled log-normal). Each segment's
    /// `integral t^p v dt` (p <= 2, a cubic) by Simpson's rule, exact.
    pub fn ln_radius_spread(&self) -> f64 {
        let (mut m0, mut m1, mut m2) = (0.0, 0.0, 0.0);
        for i in 0..self.ln_radius_m.len() - 1 {
            let (t0, t1) = (self.ln_radius_m[i], self.ln_radius_m[i + 1]);
            let (v0, v1) = (
                self.volume_per_ln_radius[i],
                self.volume_per_ln_radius[i + 1],
            );
            let (tm, vm) = (0.5 * (t0 + t1), 0.5 * (v0 + v1));
            let h6 = (t1 - t0) / 6.0;
            m0 += h6 * (v0 + 4.0 * vm + v1);
            m1 += h6 * (t0 * v0 + 4.0 * tm * vm + t1 * v1);
            m2 += h6 * (t0 * t0 * v0 + 4.0 * tm * tm * vm + t1 * t1 * v1);
        }
        let mean = m1 / m0;
        (m2 / m0 - mean * mean).max(0.0).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Complex64;
    use crate::distribution::{RadiusQuadratureSettings, SizeDistribution};
    use crate::ensemble::compute_ensemble_cross_sections;

    const MICROMETRE: f64 = 1e-6;

    /// dV/d ln r of a volume log-normal: total V, volume median r_v (m), s = ln sigma_g.
    fn volume_log_normal(volume: f64, r_v: f64, s: f64, radius_m: f64) -> f64 {
        let z = (radius_m / r_v).ln() / s;
        volume / ((2.0 * PI).sqrt() * s) * (-0.5 * z * z).exp()
    }

    /// `count` radii log-spaced over r_v exp(+-half_width_in_s s) and the
    /// log-normal sampled there.
    fn sampled_log_normal(
        volume: f64,
        r_v: f64,
        s: f64,
        half_width_in_s: f64,
        count: usize,
    ) -> (Vec<f64>, Vec<f64>) {
        let radii: Vec<f64> = (0..count)
            .map(|i| {
                let z = -half_width_in_s + 2.0 * half_width_in_s * i as f64 / (count - 1) as f64;
                r_v * (z * s).exp()
            })
            .collect();
        let values = radii
            .iter()
            .map(|&r| volume_log_normal(volume, r_v, s, r))
            .collect();
        (radii, values)
    }

    fn um(radii_m: &[f64]) -> Vec<f64> {
        radii_m.iter().map(|r| r / MICROMETRE).collect()
    }

    /// AERONET's 22 radii, 0.05-15 um log-spaced (m).
    fn aeronet_radii() -> Vec<f64> {
        (0..22)
            .map(|i| 0.05 * MICROMETRE * (15.0f64 / 0.05).powf(i as f64 / 21.0))
            .collect()
    }

    #[test]
    fn bad_tables_are_refused_with_the_offending_value() {
        let r = [0.1, 0.2, 0.3];
        let message = |radii: &[f64], values: &[f64]| {
            TabulatedVolumeDistribution::from_micrometres(radii, values)
                .unwrap_err()
                .to_string()
        };
        assert!(message(&r[..1], &[1.0]).contains("got 1 radii and 1 values"));
        assert!(message(&r, &[1.0, 2.0]).contains("got 3 radii and 2 values"));
        let m = message(&[0.1, 0.3, 0.2], &[1.0, 1.0, 1.0]);
        assert!(
            m.contains("radius 2 = 0.2 um") && m.contains("increase strictly"),
            "{m}"
        );
        assert!(message(&[0.1, 0.1], &[1.0, 1.0]).contains("increase strictly"));
        assert!(message(&[-0.1, 0.1], &[1.0, 1.0]).contains("radius 0 = -0.1 um is invalid"));
        assert!(message(&[f64::NAN, 0.1], &[1.0, 1.0]).contains("radius 0 = NaN"));
        assert!(message(&r, &[1.0, -0.5, 1.0]).contains("value 1 = -0.5 um^3/um^2"));
        assert!(message(&r, &[1.0, f64::NAN, 1.0]).contains("value 1 = NaN"));
        assert!(message(&r, &[0.0, 0.0, 0.0]).contains("no particles"));
    }

    /// The closed-form moments against a brute-force Simpson integral of the
    /// interpolated table (an independent path), and a finely sampled
    /// log-normal's column volume, number and r_eff against the log-normal's
    /// own closed forms: V; N = V / (4/3 pi r_v^3 exp(-9 s^2 / 2)) (r_v the
    /// volume median); r_eff = r_v exp(-s^2 / 2). The table's error is the
    /// linear interpolation's, h^2/12 times the second derivative's weight
    /// (h = s/40 in ln r here, (c h)^2 / 12 < 1e-4 for the e^{-3t} weight).
    #[test]
    fn column_volume_number_and_effective_radius_match_closed_forms() {
        let (volume, r_v, s) = (0.03, 0.15 * MICROMETRE, 0.45);
        let (radii, values) = sampled_log_normal(volume, r_v, s, 8.0, 641);
        let table = TabulatedVolumeDistribution::from_micrometres(&um(&radii), &values).unwrap();
        // Simpson over each table segment of the interpolated v(t) e^{ct}.
        let brute = |c: f64| {
            let mut sum = 0.0;
            for w in table.ln_radii().windows(2) {
                let n = 64;
                let h = (w[1] - w[0]) / n as f64;
                let f = |t: f64| table.value_at(t) * (c * t).exp();
                let mut s = f(w[0]) + f(w[1]);
                for i in 1..n {
                    s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(w[0] + i as f64 * h);
                }
                sum += s * h / 3.0;
            }
            sum
        };
        for c in [-3.0, -1.0, 0.0, 1.0] {
            let closed = table.moment_integral(c);
            assert!(
                (closed / brute(c) - 1.0).abs() < 1e-10,
                "c {c}: {closed} vs {}",
                brute(c)
            );
        }
        let column_volume = table.column_volume();
        assert!(
            (column_volume / volume - 1.0).abs() < 1e-4,
            "{column_volume}"
        );
        let number = 1e-6 * volume / (4.0 / 3.0 * PI * r_v.powi(3) * (-4.5 * s * s).exp());
        let table_number = table.column_number_per_m2_from_um3_per_um2();
        assert!(
            (table_number / number - 1.0).abs() < 1e-4,
            "{table_number:e} vs {number:e}"
        );
        let r_eff = r_v * (-0.5 * s * s).exp();
        assert!((table.effective_radius_m() / r_eff - 1.0).abs() < 1e-4);
        assert!((table.effective_variance() / (s * s).exp_m1() - 1.0).abs() < 1e-3);
        // Per particle, the quadrature integrates to one particle.
        let distribution = SizeDistribution::tabulated_volume(table);
        let total = crate::distribution::RadiusQuadrature::gauss_legendre(
            &distribution,
            0.0,
            &RadiusQuadratureSettings::smooth(),
        )
        .unwrap()
        .integrate(|_| 1.0);
        assert!((total - 1.0).abs() < 1e-12, "{total}");
    }

    /// A table sampled finely (h = s/40 in ln r over +-8 s) from a volume
    /// log-normal has the log-normal species' optics: per-particle extinction
    /// within twice (3 h)^2 / 12 (relative; 1.9e-4 for s = 0.45, 3.4e-4 for
    /// s = 0.6), single-scattering albedo and asymmetry within 2e-4
    /// (absolute). The table differs from the log-normal by the linear
    /// interpolation, of relative size (c h)^2 / 12 for a weight e^{ct}, the
    /// steepest being the number normalisation's e^{-3t}, and the two
    /// quadratures by their own errors (~1e-5, see [`crate::ensemble`]).
    #[test]
    fn a_finely_sampled_log_normal_has_the_log_normal_optics() {
        let m = Complex64::new(1.45, 0.005);
        for (r_v_um, s, wavelength_nm) in
            [(0.15, 0.45, 550.0), (0.15, 0.45, 1020.0), (2.5, 0.6, 550.0)]
        {
            let r_v = r_v_um * MICROMETRE;
            let (radii, values) = sampled_log_normal(1.0, r_v, s, 8.0, 641);
            let table = SizeDistribution::tabulated_volume(
                TabulatedVolumeDistribution::from_micrometres(&um(&radii), &values).unwrap(),
            );
            // The number distribution of a volume log-normal: median r_v exp(-3 s^2).
            let log_normal =
                SizeDistribution::log_normal(r_v * (-3.0 * s * s).exp(), s.exp()).unwrap();
            let settings = RadiusQuadratureSettings::cross_sections();
            let a = compute_ensemble_cross_sections(wavelength_nm, m, &table, &settings).unwrap();
            let b =
                compute_ensemble_cross_sections(wavelength_nm, m, &log_normal, &settings).unwrap();
            let ext = a.extinction_cross_section_m2 / b.extinction_cross_section_m2 - 1.0;
            let ssa = a.single_scattering_albedo - b.single_scattering_albedo;
            let g = a.asymmetry_parameter - b.asymmetry_parameter;
            println!(
                "r_v {r_v_um} um s {s} {wavelength_nm} nm: ext {ext:.2e} ssa {ssa:.2e} g {g:.2e} (nodes {} vs {}; ssa {:.5} g {:.5})",
                a.radius_node_count,
                b.radius_node_count,
                b.single_scattering_albedo,
                b.asymmetry_parameter
            );
            let h = 16.0 * s / 640.0;
            let interpolation = (3.0 * h).powi(2) / 12.0;
            assert!(ext.abs() < 2.0 * interpolation, "{ext} vs {interpolation}");
            assert!(ssa.abs() < 2e-4 && g.abs() < 2e-4);
        }
    }

    /// A bimodal AERONET-style table (22 radii 0.05-15 um; fine mode r_v
    /// 0.15 um s 0.45 V 0.03, coarse r_v 2.8 um s 0.65 V 0.05 um^3/um^2):
    /// its effective radius in closed form and by quadrature agree to 1e-9,
    /// and lie within 3 % of the continuous bimodal log-normal's,
    /// r_eff = V / sum(V_i exp(s_i^2/2) / r_v,i) (the 22-bin table is coarse,
    /// h = 0.27 in ln r).
    #[test]
    fn an_aeronet_table_has_a_sane_effective_radius() {
        let modes = [
            (0.03, 0.15 * MICROMETRE, 0.45),
            (0.05, 2.8 * MICROMETRE, 0.65),
        ];
        let radii = aeronet_radii();
        let values: Vec<f64> = radii
            .iter()
            .map(|&r| {
                modes
                    .iter()
                    .map(|&(v, r_v, s)| volume_log_normal(v, r_v, s, r))
                    .sum()
            })
            .collect();
        let table = TabulatedVolumeDistribution::from_micrometres(&um(&radii), &values).unwrap();
        let closed = table.effective_radius_m();
        let distribution = SizeDistribution::tabulated_volume(table.clone());
        let (by_quadrature, v_eff) = distribution.effective_radius_and_variance_by_quadrature();
        let continuous = 0.08
            / modes
                .iter()
                .map(|&(v, r_v, s)| v * (0.5 * s * s).exp() / r_v)
                .sum::<f64>();
        println!(
            "r_eff closed {:.6} um, quadrature {:.6} um, continuous {:.6} um; v_eff {v_eff:.4} vs {:.4}; V {:.5}",
            closed / MICROMETRE,
            by_quadrature / MICROMETRE,
            continuous / MICROMETRE,
            table.effective_variance(),
            table.column_volume()
        );
        assert!((by_quadrature / closed - 1.0).abs() < 1e-9);
        assert!((v_eff / table.effective_variance() - 1.0).abs() < 1e-9);
        assert!((closed / continuous - 1.0).abs() < 0.03);
        assert!((table.column_volume() / 0.08 - 1.0).abs() < 0.03);
    }
}
