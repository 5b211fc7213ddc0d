//! Phase functions in the form the discrete-ordinate solver needs: Legendre
//! moments, delta-M truncation, and the azimuthal Fourier components
//! p_m(mu, mu') between two directions.
//!
//! A phase function of the scattering angle alone expands in Legendre
//! polynomials, p(cos Theta) = sum_l (2l + 1) / (4 pi) chi_l P_l(cos Theta),
//! with moments chi_l = 2 pi integral_{-1}^{1} p(mu) P_l(mu) dmu (chi_0 = 1,
//! chi_1 = g). The addition theorem splits P_l(cos Theta) between two
//! directions (mu, phi), (mu', phi') into azimuthal harmonics, which gives
//!
//! ```text
//! p(cos Theta) = sum_m (2 - delta_m0) p_m(mu, mu') cos(m (phi - phi'))
//! p_m(mu, mu') = sum_{l >= m} (2l + 1) / (4 pi) chi_l Lambda_l^m(mu) Lambda_l^m(mu')
//! ```
//!
//! with the normalised associated Legendre functions
//! Lambda_l^m = sqrt((l - m)! / (l + m)!) P_l^m (Chandrasekhar 1950; the
//! form DISORT uses, Stamnes et al. 1988).
//!
//! **Delta-M** (Wiscombe 1977): a solver with N streams represents moments
//! up to l = N - 1 only. A forward-peaked function (an aerosol, and far
//! more a Mie table with its diffraction spike) has large moments beyond
//! that; cutting them off leaves an oscillating, partly negative function.
//! Delta-M instead writes p = f delta(forward) + (1 - f) p*, with
//! f = chi_N, and p* the truncated function with moments
//! chi*_l = (chi_l - f) / (1 - f). Light scattered into the delta peak is
//! treated as not scattered: beta_sca* = (1 - f) beta_sca,
//! beta_ext* = beta_ext - f beta_sca. The diffuse field of the scaled
//! problem is accurate away from the sun's aureole; the aureole itself
//! comes from the exact single scattering (Nakajima & Tanaka 1988's TMS
//! idea: the scaled problem supplies only the orders >= 2).
//!
//! Moments are integrated numerically for every phase function kind (the
//! tabulated Mie functions have no closed form), on 4-point Gauss panels
//! in the scattering angle crowded toward 0 where forward peaks are.

use std::f64::consts::PI;

use super::super::quadrature::{GAUSS_NODES, GAUSS_WEIGHTS};
use crate::atmosphere::PhaseFunction;

/// Panels of the moment quadrature in the scattering angle.
const MOMENT_PANELS: usize = 160;

/// Gauss-Legendre nodes and weights of order `n` (>= 1) on [0, 1], nodes
/// increasing, weights summing to 1: the [-1, 1] rule of
/// [`sora_mie::quadrature::gauss_legendre`](crate::mie::quadrature::gauss_legendre) mapped to mu = (t + 1) / 2.
pub(crate) fn gauss_legendre_unit_interval(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 1);
    let (nodes, weights) = crate::mie::quadrature::gauss_legendre(n);
    (
        nodes.iter().map(|t| 0.5 * (t + 1.0)).collect(),
        weights.iter().map(|w| 0.5 * w).collect(),
    )
}

/// Normalised associated Legendre functions Lambda_l^m(mu) for
/// 0 <= m <= l < `degrees`, written to `out[m * degrees + l]` (entries with
/// l < m are left alone). Stable upward recurrences in l for each m.
pub(crate) fn normalized_associated_legendre(mu: f64, degrees: usize, out: &mut [f64]) {
    debug_assert!(out.len() >= degrees * degrees);
    let sine = (1.0 - mu * mu).max(0.0).sqrt();
    let mut diagonal = 1.0;
    for m in 0..degrees {
        if m > 0 {
            diagonal *= sine * ((2 * m - 1) as f64 / (2 * m) as f64).sqrt();
        }
        let row = &mut out[m * degrees..(m + 1) * degrees];
        row[m] = diagonal;
        if m + 1 < degrees {
            row[m + 1] = mu * ((2 * m + 1) as f64).sqrt() * diagonal;
        }
        for l in m + 2..degrees {
            let (lf, mf) = (l as f64, m as f64);
            row[l] = ((2.0 * lf - 1.0) * mu * row[l - 1]
                - ((lf - 1.0) * (lf - 1.0) - mf * mf).sqrt() * row[l - 2])
                / (lf * lf - mf * mf).sqrt();
        }
    }
}

/// Every species' phase function at every wavelength delta-M truncated
/// to `degrees` terms, [i * species + j] (wavelength i, species j).
pub(crate) fn compute_truncated_phases(
    optics: &crate::atmosphere::AtmosphereOptics,
    degrees: usize,
) -> Vec<TruncatedPhase> {
    let wavelengths = optics.grid.len();
    let mut moments = vec![0.0; wavelengths * (degrees + 1)];
    let per_species: Vec<Vec<TruncatedPhase>> = optics
        .species
        .iter()
        .map(|species| {
            compute_legendre_moments(&species.phase_function, wavelengths, degrees, &mut moments);
            moments
                .chunks_exact(degrees + 1)
                .map(|row| TruncatedPhase::from_moments(row, degrees))
                .collect()
        })
        .collect();
    (0..wavelengths)
        .flat_map(|i| per_species.iter().map(move |row| row[i].clone()))
        .collect()
}

/// Legendre moments chi_0..=chi_`highest` of `phase` at every wavelength:
/// `out[wavelength * (highest + 1) + l]`, normalised so that chi_0 = 1
/// exactly (the quadrature's own normalisation error is divided out).
pub(crate) fn compute_legendre_moments(
    phase: &PhaseFunction,
    wavelengths: usize,
    highest: usize,
    out: &mut [f64],
) {
    let count = highest + 1;
    debug_assert!(out.len() >= wavelengths * count);
    out[..wavelengths * count].fill(0.0);
    let mut values = vec![0.0; wavelengths];
    let mut legendre = vec![0.0; count];
    for panel in 0..MOMENT_PANELS {
        // Edges pi (k / n)^2: widths ~ pi / n^2 at the forward peak.
        let edge = |k: usize| PI * (k as f64 / MOMENT_PANELS as f64).powi(2);
        let (a, b) = (edge(panel), edge(panel + 1));
        let (centre, half) = (0.5 * (a + b), 0.5 * (b - a));
        for (x, w) in GAUSS_NODES.iter().zip(GAUSS_WEIGHTS) {
            let theta = centre + half * x;
            let mu = theta.cos();
            let weight = 2.0 * PI * half * w * theta.sin();
            phase.eval_into(mu, &mut values);
            legendre[0] = 1.0;
            if count > 1 {
                legendre[1] = mu;
            }
            for l in 2..count {
                legendre[l] = ((2 * l - 1) as f64 * mu * legendre[l - 1]
                    - (l - 1) as f64 * legendre[l - 2])
                    / l as f64;
            }
            for (i, value) in values.iter().enumerate() {
                let row = &mut out[i * count..(i + 1) * count];
                for (moment, p_l) in row.iter_mut().zip(&legendre) {
                    *moment += weight * value * p_l;
                }
            }
        }
    }
    for i in 0..wavelengths {
        let row = &mut out[i * count..(i + 1) * count];
        let norm = row[0];
        if norm > 0.0 {
            for moment in row.iter_mut() {
                *moment /= norm;
            }
        }
    }
}

/// The delta-M truncation of one phase function at one wavelength for a
/// solver of `streams` streams: the fraction f in the forward delta peak
/// and the expansion coefficients c_l = (2l + 1) / (4 pi) chi*_l,
/// l < streams, of the truncated function p*.
#[derive(Debug, Clone, PartialEq)]
pub struct TruncatedPhase {
    pub forward_fraction: f64,
    pub coefficients: Vec<f64>,
}

impl TruncatedPhase {
    /// From moments chi_0..=chi_streams (chi_0 = 1).
    pub(crate) fn from_moments(moments: &[f64], streams: usize) -> TruncatedPhase {
        debug_assert!(moments.len() > streams);
        // A negative chi_N (a backscattering function) is not a forward
        // peak: leave such functions alone.
        let f = moments[streams].clamp(0.0, 0.99);
        let coefficients = (0..streams)
            .map(|l| (2 * l + 1) as f64 / (4.0 * PI) * (moments[l] - f) / (1.0 - f))
            .collect();
        TruncatedPhase {
            forward_fraction: f,
            coefficients,
        }
    }

    /// True when p*_m vanishes (all coefficients from l = m on are zero):
    /// Rayleigh scattering has no harmonics above m = 2.
    pub(crate) fn harmonic_vanishes(&self, m: usize) -> bool {
        self.coefficients.iter().skip(m).all(|c| *c == 0.0)
    }

    /// p*_m(mu, mu') from the two directions' Lambda tables (each laid out
    /// as [m * degrees + l], degrees = the number of coefficients).
    pub(crate) fn harmonic(&self, m: usize, lambda_a: &[f64], lambda_b: &[f64]) -> f64 {
        let n = self.coefficients.len();
        let (a, b) = (&lambda_a[m * n..(m + 1) * n], &lambda_b[m * n..(m + 1) * n]);
        (m..n).map(|l| self.coefficients[l] * a[l] * b[l]).sum()
    }

    /// p*(cos Theta), sr^-1, summed from the Legendre series (the tests';
    /// tables take [`Self::eval_with_legendre`]).
    #[cfg(test)]
    pub(crate) fn eval(&self, cos_theta: f64) -> f64 {
        let mut legendre = [0.0; MAX_LEGENDRE_TERMS];
        let legendre = &mut legendre[..self.coefficients.len()];
        legendre_polynomials(cos_theta, legendre);
        self.eval_with_legendre(legendre)
    }

    /// p*(cos Theta), sr^-1, from the Legendre polynomials P_l(cos Theta)
    /// of [`legendre_polynomials`] (at least as many as the series has
    /// terms): for several wavelengths at one angle, the polynomials made
    /// once.
    pub(crate) fn eval_with_legendre(&self, legendre: &[f64]) -> f64 {
        let mut sum = 0.0;
        for (c, p) in self.coefficients.iter().zip(legendre) {
            sum += c * p;
        }
        sum
    }

    /// The number of terms of the series.
    pub(crate) fn terms(&self) -> usize {
        self.coefficients.len()
    }
}

/// The most terms a truncated phase function's series has (two per
/// stream, 32 streams per hemisphere at most).
pub(crate) const MAX_LEGENDRE_TERMS: usize = 64;

/// P_l(x) for l = 0..out.len() into `out`, by Bonnet's recurrence
/// l P_l = (2l - 1) x P_(l-1) - (l - 1) P_(l-2).
pub(crate) fn legendre_polynomials(x: f64, out: &mut [f64]) {
    let (mut p0, mut p1) = (1.0, x);
    for (l, value) in out.iter_mut().enumerate() {
        *value = match l {
            0 => 1.0,
            1 => x,
            _ => {
                let p2 = ((2 * l - 1) as f64 * x * p1 - (l - 1) as f64 * p0) / l as f64;
                p0 = p1;
                p1 = p2;
                p2
            }
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::phase::henyey_greenstein_phase;

    #[test]
    fn gauss_rule_is_exact_to_degree_2n_minus_1() {
        for n in [1, 2, 5, 8, 16] {
            let (x, w) = gauss_legendre_unit_interval(n);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            assert!(x.windows(2).all(|p| p[1] > p[0]));
            let degree = 2 * n - 1;
            let integral: f64 = x
                .iter()
                .zip(&w)
                .map(|(x, w)| w * x.powi(degree as i32))
                .sum();
            assert!(
                (integral - 1.0 / (degree + 1) as f64).abs() < 1e-14,
                "{n}: {integral}"
            );
        }
    }

    #[test]
    fn legendre_addition_theorem_holds() {
        // P_l(cos Theta) = sum_m (2 - delta) Lambda_l^m Lambda_l^m cos(m dphi).
        let degrees = 12;
        let (mu_a, mu_b, dphi) = (0.3f64, -0.77f64, 1.1f64);
        let mut a = vec![0.0; degrees * degrees];
        let mut b = vec![0.0; degrees * degrees];
        normalized_associated_legendre(mu_a, degrees, &mut a);
        normalized_associated_legendre(mu_b, degrees, &mut b);
        let cos_theta =
            mu_a * mu_b + (1.0 - mu_a * mu_a).sqrt() * (1.0 - mu_b * mu_b).sqrt() * dphi.cos();
        let (mut p0, mut p1) = (1.0, cos_theta);
        for l in 0..degrees {
            let p_l = match l {
                0 => 1.0,
                1 => cos_theta,
                _ => {
                    let p2 = ((2 * l - 1) as f64 * cos_theta * p1 - (l - 1) as f64 * p0) / l as f64;
                    p0 = p1;
                    p1 = p2;
                    p2
                }
            };
            let sum: f64 = (0..=l)
                .map(|m| {
                    let factor = if m == 0 { 1.0 } else { 2.0 };
                    factor * a[m * degrees + l] * b[m * degrees + l] * (m as f64 * dphi).cos()
                })
                .sum();
            assert!((sum - p_l).abs() < 1e-12, "l = {l}: {sum} vs {p_l}");
        }
    }

    #[test]
    fn henyey_greenstein_moments_are_powers_of_g() {
        let phase = PhaseFunction::HenyeyGreenstein {
            asymmetry_g: vec![0.7, 0.0, 0.9],
        };
        let highest = 32;
        let mut moments = vec![0.0; 3 * (highest + 1)];
        compute_legendre_moments(&phase, 3, highest, &mut moments);
        for (i, g) in [0.7f64, 0.0, 0.9].iter().enumerate() {
            for l in 0..=highest {
                let got = moments[i * (highest + 1) + l];
                assert!((got - g.powi(l as i32)).abs() < 1e-9, "g {g} l {l}: {got}");
            }
        }
        // Rayleigh: chi_2 = 1/10 without depolarisation, zero beyond.
        let rayleigh = PhaseFunction::Rayleigh {
            depolarization_ratios: vec![0.0],
        };
        let mut moments = vec![0.0; 9];
        compute_legendre_moments(&rayleigh, 1, 8, &mut moments);
        assert!((moments[2] - 0.1).abs() < 1e-12 && moments[1].abs() < 1e-12);
        assert!(moments[3..].iter().all(|m| m.abs() < 1e-12));
    }

    #[test]
    fn truncation_keeps_normalisation_and_removes_the_forward_peak() {
        let g: f64 = 0.85;
        let streams = 8;
        let moments: Vec<f64> = (0..=streams).map(|l| g.powi(l as i32)).collect();
        let truncated = TruncatedPhase::from_moments(&moments, streams);
        assert!((truncated.forward_fraction - g.powi(8)).abs() < 1e-15);
        // Normalised over the sphere, and much lower than HG at 0 degrees.
        let n = 20_000;
        let total: f64 = (0..n)
            .map(|k| {
                let mu = -1.0 + (k as f64 + 0.5) * 2.0 / n as f64;
                2.0 * PI * truncated.eval(mu) * 2.0 / n as f64
            })
            .sum();
        assert!((total - 1.0).abs() < 1e-6, "{total}");
        assert!(truncated.eval(1.0) < 0.5 * henyey_greenstein_phase(g, 1.0));
    }
}
