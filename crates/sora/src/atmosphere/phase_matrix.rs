//! Phase matrices: how scattering changes the polarisation of light.
//!
//! For randomly oriented particles with a plane of symmetry (molecules,
//! spheres), the 4 x 4 matrix that turns the Stokes vector (I, Q, U, V) of
//! the incident light into that of the scattered light, both referred to
//! the scattering plane, has six independent elements (Hansen & Travis
//! 1974, eq. 2.13; Hovenier, van der Mee & Domke 2004):
//!
//! ```text
//!         | a1  b1   0   0 |
//! F(th) = | b1  a2   0   0 |      sr^-1, normalised as the phase function:
//!         |  0   0  a3  b2 |      a1 = p(th), integral of a1 over 4 pi = 1.
//!         |  0   0 -b2  a4 |
//! ```
//!
//! Unpolarised light (1, 0, 0, 0) scattered by it becomes (a1, b1, 0, 0):
//! a1 is the phase function and -b1 / a1 the degree of linear polarisation,
//! positive when the light is polarised perpendicular to the scattering
//! plane (Q < 0 with respect to it).
//!
//! - **Rayleigh** with depolarisation ratio rho (Hansen & Travis 1974,
//!   eq. 2.15; Chandrasekhar 1950): with
//!   `D = (1 - rho) / (1 + rho / 2)` and `D' = (1 - 2 rho) / (1 - rho)`,
//!   `a1 = 3/4 D (1 + mu^2) + (1 - D)`, `b1 = -3/4 D (1 - mu^2)`,
//!   `a2 = 3/4 D (1 + mu^2)`, `a3 = 3/2 D mu`, `a4 = 3/2 D D' mu`,
//!   `b2 = 0`, all over 4 pi. Its a1 is exactly the scalar Rayleigh phase
//!   function of `phase.rs`, and without depolarisation the degree of
//!   polarisation of single scattering is `(1 - mu^2) / (1 + mu^2)`, 1 at
//!   90 degrees.
//! - **Parametric phase functions** (isotropic, Henyey-Greenstein,
//!   Cornette-Shanks, the paper's HG of g(r)) carry no polarisation: they
//!   are treated as non-polarising, `a1 = a2 = a3 = a4 = p`, `b1 = b2 = 0`
//!   (the light keeps its state of polarisation).
//! - **Tabulated (Mie)** phase functions: the ensemble's F12, F33 and F34
//!   relative to F11, from S1 and S2 over the size distribution
//!   (`sora_mie::ensemble::compute_ensemble_phase_matrix_ratios`, B&H
//!   eq. 4.77), on the table's nodes, with F22 = F11 and F44 = F33 for
//!   spheres. They are computed only for a polarised sky
//!   (`Atmosphere::add_phase_matrices`: a Mie solution per radius node,
//!   angle and wavelength, seconds for large particles).

use std::f64::consts::PI;

/// The six independent elements of a phase matrix at one angle, sr^-1
/// (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct PhaseMatrix {
    pub(crate) a1: f64,
    pub(crate) a2: f64,
    pub(crate) a3: f64,
    pub(crate) a4: f64,
    pub(crate) b1: f64,
    pub(crate) b2: f64,
}

impl PhaseMatrix {
    /// The non-polarising matrix of a phase function value `p`, sr^-1.
    pub(crate) fn non_polarising(p: f64) -> PhaseMatrix {
        PhaseMatrix {
            a1: p,
            a2: p,
            a3: p,
            a4: p,
            b1: 0.0,
            b2: 0.0,
        }
    }

    /// `self + weight * other`, element by element (a mixture of species is
    /// the sum of their scattering coefficients times their matrices).
    pub(crate) fn add_scaled(&mut self, weight: f64, other: &PhaseMatrix) {
        self.a1 += weight * other.a1;
        self.a2 += weight * other.a2;
        self.a3 += weight * other.a3;
        self.a4 += weight * other.a4;
        self.b1 += weight * other.b1;
        self.b2 += weight * other.b2;
    }

    /// The full 4 x 4 matrix divided by `a1` (zero when `a1` is not
    /// positive: nothing scatters).
    pub(crate) fn normalised_matrix(&self) -> [[f64; 4]; 4] {
        if self.a1 <= 0.0 {
            return [[0.0; 4]; 4];
        }
        let s = 1.0 / self.a1;
        [
            [1.0, self.b1 * s, 0.0, 0.0],
            [self.b1 * s, self.a2 * s, 0.0, 0.0],
            [0.0, 0.0, self.a3 * s, self.b2 * s],
            [0.0, 0.0, -self.b2 * s, self.a4 * s],
        ]
    }
}

/// The Rayleigh phase matrix with depolarisation ratio `rho` (0 <= rho <
/// 0.5) at scattering-angle cosine `mu`, sr^-1 (Hansen & Travis 1974,
/// eq. 2.15).
pub(crate) fn rayleigh_phase_matrix(rho: f64, mu: f64) -> PhaseMatrix {
    let d = (1.0 - rho) / (1.0 + 0.5 * rho);
    let d_prime = (1.0 - 2.0 * rho) / (1.0 - rho);
    let per_sr = 1.0 / (4.0 * PI);
    let mu2 = mu * mu;
    PhaseMatrix {
        a1: (0.75 * d * (1.0 + mu2) + (1.0 - d)) * per_sr,
        a2: 0.75 * d * (1.0 + mu2) * per_sr,
        a3: 1.5 * d * mu * per_sr,
        a4: 1.5 * d * d_prime * mu * per_sr,
        b1: -0.75 * d * (1.0 - mu2) * per_sr,
        b2: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rayleigh_degree_of_polarisation_has_its_closed_forms() {
        // Without depolarisation: (1 - mu^2) / (1 + mu^2), 1 at 90 degrees.
        for k in 0..=20 {
            let mu = -1.0 + 0.1 * k as f64;
            let m = rayleigh_phase_matrix(0.0, mu);
            let expected = (1.0 - mu * mu) / (1.0 + mu * mu);
            assert!((-m.b1 / m.a1 - expected).abs() < 1e-12, "mu {mu}");
        }
        // With depolarisation the maximum, at 90 degrees, is
        // (1 - rho) / (1 + rho) (e.g. Hansen & Travis 1974, sec. 2.7).
        for rho in [0.0279, 0.1, 0.3] {
            let m = rayleigh_phase_matrix(rho, 0.0);
            let expected = (1.0 - rho) / (1.0 + rho);
            assert!((-m.b1 / m.a1 - expected).abs() < 1e-12, "rho {rho}");
        }
    }

    #[test]
    fn phase_matrices_conserve_the_degree_bound() {
        // A physical phase matrix never makes light more than fully
        // polarised: a1^2 >= b1^2 + ... for unpolarised light, and the
        // normalised matrix keeps (1, 0, 0, 0) within the Poincare sphere.
        for rho in [0.0, 0.0279, 0.3] {
            for k in 0..=40 {
                let mu = -1.0 + 0.05 * k as f64;
                let f = rayleigh_phase_matrix(rho, mu).normalised_matrix();
                for s in [
                    [1.0, 0.0, 0.0, 0.0],
                    [1.0, 1.0, 0.0, 0.0],
                    [1.0, 0.0, 1.0, 0.0],
                    [1.0, -0.6, 0.0, 0.8],
                ] {
                    let out: Vec<f64> = (0..4)
                        .map(|r| (0..4).map(|c| f[r][c] * s[c]).sum())
                        .collect();
                    let polarised = (out[1] * out[1] + out[2] * out[2] + out[3] * out[3]).sqrt();
                    assert!(
                        polarised <= out[0] * (1.0 + 1e-12),
                        "rho {rho} mu {mu} {s:?}"
                    );
                }
            }
        }
    }
}
