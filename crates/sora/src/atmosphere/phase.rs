//! Phase functions: the angular distribution of scattered light.
//!
//! A phase function p(theta) gives the probability per steradian that light
//! scattered once leaves at angle theta from its incoming direction
//! (theta = 0 is straight on). Unit sr^-1, normalised so that
//! `integral over 4 pi of p dOmega = 2 pi * integral_{-1}^{1} p(mu) dmu = 1`
//! with mu = cos(theta). Every function here depends on theta only
//! (randomly oriented particles, unpolarised light).
//!
//! - Rayleigh (air, CO2): `p = 3/(16 pi) (1 + mu^2)` (the paper calls it
//!   "nearly isotropic"; this is the real one), and with the molecular
//!   depolarisation ratio rho (Chandrasekhar 1950; as in the comment of
//!   `us-standard-1976-rayleigh.toml`):
//!   `p = 3/(16 pi) * 2/(2 + rho) * ((1 + rho) + (1 - rho) mu^2)`.
//! - Henyey-Greenstein, the paper's eq. 3:
//!   `p = (1 - g^2) / (4 pi (1 + g^2 - 2 g mu)^{3/2})`, mean cosine g.
//! - Cornette-Shanks (1992), a Henyey-Greenstein with a Rayleigh-like
//!   factor that gives more side and back scattering for the same g:
//!   `p = 3/(8 pi) (1 - g^2)(1 + mu^2) / ((2 + g^2)(1 + g^2 - 2 g mu)^{3/2})`.
//!   Its mean cosine is not g but `3 g (4 + g^2) / (5 (2 + g^2))`.
//! - Tabulated: values at nodes mu_j, linear in mu between them (the exact
//!   Mie phase function of a size distribution), renormalised so that the
//!   interpolant integrates to exactly 1: one `sora_mie`
//!   [`TabulatedPhaseFunction`] per wavelength, on shared nodes.
//!
//! Henyey-Greenstein and the tabulated function are `sora_mie`'s (its
//! `paper_phase` and `ensemble` modules): one implementation of their
//! evaluation, normalisation and sampling serves the Mie engine and the
//! renderer.
//!
//! A species' phase function may change with wavelength (the depolarisation
//! of air, the Mie phase function), so [`PhaseFunction`] holds one set of
//! parameters per sample of the atmosphere's wavelength grid and every
//! method takes the wavelength index. `PhaseFunction::eval_into`
//! evaluates all wavelengths at one angle, the renderer's hot path.
//!
//! Sampling (for a path tracer, as pbrt's `PhaseFunction::Sample_p`): from
//! two uniform numbers u in [0, 1)^2, `PhaseFunction::sample` returns a
//! direction as (cos theta, phi) about the incoming direction, with the
//! value p and the pdf of having chosen it (per steradian). Rayleigh,
//! Henyey-Greenstein and tabulated functions are sampled exactly (pdf = p);
//! Cornette-Shanks is sampled with the Henyey-Greenstein of the same g
//! (pdf != p; the weight is p / pdf).

use super::phase_matrix::{PhaseMatrix, rayleigh_phase_matrix};
use crate::mie::ensemble::{PhaseMatrixRatios, TabulatedPhaseFunction};
use crate::mie::paper_phase::sample_henyey_greenstein_cos_theta;
use std::f64::consts::PI;

/// Henyey-Greenstein phase function with asymmetry parameter `g`, sr^-1
/// (the paper's eq. 3): `sora_mie`'s.
pub use crate::mie::paper_phase::henyey_greenstein_phase_function_per_sr as henyey_greenstein_phase;

/// Isotropic scattering, 1 / (4 pi) sr^-1.
pub const ISOTROPIC_PHASE_PER_SR: f64 = 1.0 / (4.0 * PI);

/// Rayleigh phase function with depolarisation ratio `depolarization_ratio`
/// (0 for the classical 3/(16 pi)(1 + mu^2)), sr^-1.
pub(crate) fn rayleigh_phase(depolarization_ratio: f64, cos_theta: f64) -> f64 {
    let rho = depolarization_ratio;
    3.0 / (16.0 * PI) * 2.0 / (2.0 + rho) * ((1.0 + rho) + (1.0 - rho) * cos_theta * cos_theta)
}

/// Cornette-Shanks phase function with parameter `g`, sr^-1.
pub(crate) fn cornette_shanks_phase(g: f64, cos_theta: f64) -> f64 {
    let denominator = 1.0 + g * g - 2.0 * g * cos_theta;
    3.0 / (8.0 * PI) * (1.0 - g * g) * (1.0 + cos_theta * cos_theta)
        / ((2.0 + g * g) * denominator * denominator.sqrt())
}

/// Mean cosine of the Cornette-Shanks function of parameter `g`.
pub(crate) fn cornette_shanks_asymmetry(g: f64) -> f64 {
    3.0 * g * (4.0 + g * g) / (5.0 * (2.0 + g * g))
}

/// A sampled scattering direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseSample {
    /// Cosine of the angle from the incoming direction.
    pub cos_theta: f64,
    /// Azimuth about the incoming direction, radians in [0, 2 pi).
    pub phi: f64,
    /// The phase function there, sr^-1.
    pub value: f64,
    /// The probability density of having sampled it, sr^-1.
    pub pdf: f64,
}

/// Phase functions at nodes mu_j (increasing, from -1 to 1), one row of
/// values per wavelength, linear in mu between nodes; each row normalised
/// so that its interpolant integrates to 1 over the sphere. Each row is a
/// `sora_mie` [`TabulatedPhaseFunction`] (evaluation, exact cumulative
/// distribution and its inversion, mean cosine); all rows share the nodes,
/// so that evaluating every wavelength at one angle searches them once.
#[derive(Debug, Clone, PartialEq)]
pub struct TabulatedPhase {
    /// One table per wavelength, all on the same nodes.
    rows: Vec<TabulatedPhaseFunction>,
    /// Mean cosine per wavelength, exact for the interpolant.
    asymmetry: Vec<f64>,
    /// F12/F11, F33/F11 and F34/F11 per wavelength on the same nodes, for
    /// polarised computations (`phase_matrix.rs`); None until computed.
    matrix_ratios: Option<Vec<PhaseMatrixRatios>>,
}

impl TabulatedPhase {
    /// A table from nodes (strictly increasing, first -1 and last 1) and one
    /// row of values per wavelength (at least one; finite, >= 0, not all
    /// zero); each row is rescaled to integrate to 1. Returns `None` for an
    /// invalid table (the callers build tables from computed values, so this
    /// is a bug check, not a user error).
    #[cfg(test)]
    pub(crate) fn new(cos_theta_nodes: Vec<f64>, values: Vec<Vec<f64>>) -> Option<TabulatedPhase> {
        let rows = values
            .into_iter()
            .map(|row| TabulatedPhaseFunction::from_nodes(cos_theta_nodes.clone(), row).ok())
            .collect::<Option<Vec<_>>>()?;
        Self::from_tables(rows)
    }

    /// The tables of the wavelengths as they are (no renormalisation), e.g.
    /// the Mie engine's; `None` unless there is at least one and all share
    /// their nodes.
    pub(crate) fn from_tables(rows: Vec<TabulatedPhaseFunction>) -> Option<TabulatedPhase> {
        let nodes = rows.first()?.cos_theta_nodes();
        if rows.iter().any(|row| row.cos_theta_nodes() != nodes) {
            return None;
        }
        let asymmetry = rows.iter().map(|row| row.asymmetry_parameter()).collect();
        Some(TabulatedPhase {
            rows,
            asymmetry,
            matrix_ratios: None,
        })
    }

    /// The table of wavelength sample `wavelength_index`.
    pub(crate) fn row(&self, wavelength_index: usize) -> &TabulatedPhaseFunction {
        &self.rows[wavelength_index]
    }

    /// The cosines of the table's nodes (every wavelength's).
    pub(crate) fn cos_theta_nodes(&self) -> &[f64] {
        self.rows[0].cos_theta_nodes()
    }

    /// Keeps the phase-matrix ratios of each wavelength (computed on
    /// [`Self::cos_theta_nodes`]); false, keeping none, unless there is one
    /// per wavelength on those nodes.
    pub(crate) fn set_matrix_ratios(&mut self, ratios: Vec<PhaseMatrixRatios>) -> bool {
        let nodes = self.cos_theta_nodes();
        if ratios.len() != self.rows.len() || ratios.iter().any(|r| r.cos_theta != nodes) {
            return false;
        }
        self.matrix_ratios = Some(ratios);
        true
    }

    /// Whether the table carries its phase matrix (a Mie species' is
    /// computed for polarised light only; a tabulated one has it always).
    pub fn has_matrix_ratios(&self) -> bool {
        self.matrix_ratios.is_some()
    }

    /// Whether the table carries a phase matrix that polarises (one not
    /// everywhere F12 = F34 = 0, F33 = F11).
    pub(crate) fn has_polarising_matrix(&self) -> bool {
        self.matrix_ratios.as_ref().is_some_and(|all| {
            all.iter().any(|r| {
                r.f12_over_f11.iter().any(|v| *v != 0.0)
                    || r.f34_over_f11.iter().any(|v| *v != 0.0)
                    || r.f33_over_f11.iter().any(|v| *v != 1.0)
            })
        })
    }

    /// The phase matrix of every wavelength at `cos_theta` into `out`: a1
    /// the tabulated phase function, the rest a1 times the ratios, all
    /// linear in cos theta between the nodes (a2 = a1 and a4 = a3 for
    /// spheres). Non-polarising without ratios.
    pub(crate) fn phase_matrix_into(&self, cos_theta: f64, out: &mut [PhaseMatrix]) {
        let location = self.rows[0].locate(cos_theta);
        let (i, t) = location;
        let at = |v: &[f64]| v[i] + t * (v[i + 1] - v[i]);
        for (k, (m, row)) in out.iter_mut().zip(&self.rows).enumerate() {
            let a1 = row.phase_function_at(location);
            *m = match &self.matrix_ratios {
                None => PhaseMatrix::non_polarising(a1),
                Some(ratios) => {
                    let r = &ratios[k];
                    let a3 = a1 * at(&r.f33_over_f11);
                    PhaseMatrix {
                        a1,
                        a2: a1,
                        a3,
                        a4: a3,
                        b1: a1 * at(&r.f12_over_f11),
                        b2: a1 * at(&r.f34_over_f11),
                    }
                }
            };
        }
    }

    /// p(theta) at every wavelength row into `out`, the same values as
    /// [`TabulatedPhase::eval`] row by row.
    fn eval_all(&self, cos_theta: f64, out: &mut [f64]) {
        let location = self.rows[0].locate(cos_theta);
        for (value, row) in out.iter_mut().zip(&self.rows) {
            *value = row.phase_function_at(location);
        }
    }

    fn eval(&self, wavelength_index: usize, cos_theta: f64) -> f64 {
        self.rows[wavelength_index].phase_function_per_sr(cos_theta)
    }

    /// Inverts the cumulative distribution of the linear interpolant.
    fn sample_cos_theta(&self, wavelength_index: usize, u: f64) -> f64 {
        self.rows[wavelength_index].sample_cos_theta(u)
    }
}

/// The phase function of one species, per wavelength of a grid.
#[derive(Debug, Clone, PartialEq)]
pub enum PhaseFunction {
    /// 1 / (4 pi); also the placeholder of species that do not scatter.
    Isotropic,
    /// Rayleigh with a depolarisation ratio per wavelength.
    Rayleigh {
        /// One per wavelength.
        depolarization_ratios: Vec<f64>,
    },
    /// Henyey-Greenstein with g per wavelength.
    HenyeyGreenstein {
        /// One per wavelength.
        asymmetry_g: Vec<f64>,
    },
    /// Cornette-Shanks with parameter g per wavelength.
    CornetteShanks {
        /// One per wavelength.
        g: Vec<f64>,
    },
    /// Tabulated in cos theta, one row per wavelength.
    Tabulated(TabulatedPhase),
}

impl PhaseFunction {
    /// p(theta) at wavelength sample `wavelength_index`, sr^-1.
    pub fn eval(&self, wavelength_index: usize, cos_theta: f64) -> f64 {
        match self {
            PhaseFunction::Isotropic => ISOTROPIC_PHASE_PER_SR,
            PhaseFunction::Rayleigh {
                depolarization_ratios,
            } => rayleigh_phase(depolarization_ratios[wavelength_index], cos_theta),
            PhaseFunction::HenyeyGreenstein { asymmetry_g } => {
                henyey_greenstein_phase(asymmetry_g[wavelength_index], cos_theta)
            }
            PhaseFunction::CornetteShanks { g } => {
                cornette_shanks_phase(g[wavelength_index], cos_theta)
            }
            PhaseFunction::Tabulated(table) => table.eval(wavelength_index, cos_theta),
        }
    }

    /// p(theta) at every wavelength, written into `out` (one value per
    /// wavelength sample; no allocation).
    pub(crate) fn eval_into(&self, cos_theta: f64, out: &mut [f64]) {
        match self {
            // Every wavelength shares the table's cos theta nodes: find the
            // segment once (a binary search per wavelength dominated the
            // renderer's profile).
            PhaseFunction::Tabulated(table) => table.eval_all(cos_theta, out),
            _ => {
                for (i, value) in out.iter_mut().enumerate() {
                    *value = self.eval(i, cos_theta);
                }
            }
        }
    }

    /// The probability density (sr^-1) with which [`PhaseFunction::sample`]
    /// picks a direction at angle theta.
    pub(crate) fn pdf(&self, wavelength_index: usize, cos_theta: f64) -> f64 {
        match self {
            PhaseFunction::CornetteShanks { g } => {
                henyey_greenstein_phase(g[wavelength_index], cos_theta)
            }
            other => other.eval(wavelength_index, cos_theta),
        }
    }

    /// Samples a scattering direction from two uniform numbers in [0, 1).
    pub(crate) fn sample(&self, wavelength_index: usize, u: [f64; 2]) -> PhaseSample {
        let cos_theta = match self {
            PhaseFunction::Isotropic => 1.0 - 2.0 * u[0],
            PhaseFunction::Rayleigh {
                depolarization_ratios,
            } => sample_rayleigh_cos_theta(depolarization_ratios[wavelength_index], u[0]),
            PhaseFunction::HenyeyGreenstein { asymmetry_g } => {
                henyey_greenstein_cos_theta(asymmetry_g[wavelength_index], u[0])
            }
            PhaseFunction::CornetteShanks { g } => {
                henyey_greenstein_cos_theta(g[wavelength_index], u[0])
            }
            PhaseFunction::Tabulated(table) => table.sample_cos_theta(wavelength_index, u[0]),
        };
        PhaseSample {
            cos_theta,
            phi: 2.0 * PI * u[1],
            value: self.eval(wavelength_index, cos_theta),
            pdf: self.pdf(wavelength_index, cos_theta),
        }
    }

    /// Mean cosine of the scattering angle, `<cos theta>` (the asymmetry
    /// parameter g of radiative transfer) at wavelength sample
    /// `wavelength_index`.
    pub fn asymmetry_g(&self, wavelength_index: usize) -> f64 {
        match self {
            // Both are symmetric about 90 degrees.
            PhaseFunction::Isotropic | PhaseFunction::Rayleigh { .. } => 0.0,
            PhaseFunction::HenyeyGreenstein { asymmetry_g } => asymmetry_g[wavelength_index],
            PhaseFunction::CornetteShanks { g } => cornette_shanks_asymmetry(g[wavelength_index]),
            PhaseFunction::Tabulated(table) => table.asymmetry[wavelength_index],
        }
    }

    /// Whether this phase function has a phase matrix that polarises
    /// (Rayleigh, tabulated Mie functions, whose matrix a polarised sky
    /// computes from S1 and S2, and tabulated ones given with a polarising
    /// matrix). The parametric ones (isotropic,
    /// Henyey-Greenstein, Cornette-Shanks) carry no polarisation: a
    /// polarised computation treats them as non-polarising, F12 = F34 = 0,
    /// F33 = F44 = F11 (`phase_matrix.rs`).
    pub fn is_polarising(&self) -> bool {
        match self {
            PhaseFunction::Rayleigh { .. } => true,
            // A Mie table without its matrix yet: computed when needed.
            PhaseFunction::Tabulated(table) => {
                !table.has_matrix_ratios() || table.has_polarising_matrix()
            }
            _ => false,
        }
    }

    /// A short name for listings.
    pub fn kind(&self) -> &'static str {
        match self {
            PhaseFunction::Isotropic => "isotropic",
            PhaseFunction::Rayleigh { .. } => "Rayleigh",
            PhaseFunction::HenyeyGreenstein { .. } => "Henyey-Greenstein",
            PhaseFunction::CornetteShanks { .. } => "Cornette-Shanks",
            PhaseFunction::Tabulated(table) if !table.has_matrix_ratios() => "tabulated (Mie)",
            PhaseFunction::Tabulated(_) => "tabulated",
        }
    }
}

impl PhaseFunction {
    /// Whether a polarised computation can use this phase function: every
    /// kind but a tabulated (Mie) one without its matrix ratios (which
    /// `Atmosphere::add_phase_matrices` computes).
    pub(crate) fn has_phase_matrix(&self) -> bool {
        match self {
            PhaseFunction::Tabulated(table) => table.has_matrix_ratios(),
            _ => true,
        }
    }

    /// The phase matrix at every wavelength at scattering-angle cosine
    /// `cos_theta`, into `out` (one per wavelength sample; no allocation).
    /// A tabulated function without its ratios gets its non-polarising
    /// matrix: callers check [`PhaseFunction::has_phase_matrix`] first.
    pub(crate) fn phase_matrix_into(&self, cos_theta: f64, out: &mut [PhaseMatrix]) {
        match self {
            PhaseFunction::Tabulated(table) => table.phase_matrix_into(cos_theta, out),
            PhaseFunction::Rayleigh {
                depolarization_ratios,
            } => {
                for (m, rho) in out.iter_mut().zip(depolarization_ratios) {
                    *m = rayleigh_phase_matrix(*rho, cos_theta);
                }
            }
            _ => {
                for (i, m) in out.iter_mut().enumerate() {
                    *m = PhaseMatrix::non_polarising(self.eval(i, cos_theta));
                }
            }
        }
    }
}

/// Exact inversion of the Rayleigh distribution in mu: with a = 1 + rho,
/// b = 1 - rho, the cumulative distribution is
/// (a (mu + 1) + b (mu^3 + 1) / 3) / (2 a + 2 b / 3) = u, a depressed cubic
/// in mu with one real root (a, b > 0), found by Cardano's formula.
fn sample_rayleigh_cos_theta(depolarization_ratio: f64, u: f64) -> f64 {
    let (a, b) = (1.0 + depolarization_ratio, 1.0 - depolarization_ratio);
    if b <= 0.0 {
        return 1.0 - 2.0 * u;
    }
    // mu^3 + p mu + q = 0 with p = 3 a / b and
    // q = 3 (a + b/3 - u (2 a + 2 b / 3)) / b.
    let p = 3.0 * a / b;
    let q = 3.0 * (a + b / 3.0 - u * (2.0 * a + 2.0 * b / 3.0)) / b;
    let root = (q * q / 4.0 + p * p * p / 27.0).sqrt();
    let mu = (-q / 2.0 + root).cbrt() + (-q / 2.0 - root).cbrt();
    mu.clamp(-1.0, 1.0)
}

/// Henyey-Greenstein inversion, `sora_mie`'s, fed 1 - u so that u = 0 is
/// the forward direction as in pbrt-v4's `SampleHenyeyGreenstein` (mu
/// measured from the incoming direction: g > 0 favours mu near 1).
fn henyey_greenstein_cos_theta(g: f64, u: f64) -> f64 {
    sample_henyey_greenstein_cos_theta(g, 1.0 - u)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 2 pi * integral_{-1}^{1} f(mu) mu^power dmu by composite Simpson
    /// in theta (dense where forward peaks are).
    fn sphere_integral(f: impl Fn(f64) -> f64, power: i32) -> f64 {
        let n = 200_000;
        let h = PI / n as f64;
        let g = |theta: f64| {
            let mu = theta.cos();
            f(mu) * mu.powi(power) * theta.sin()
        };
        let mut sum = g(0.0) + g(PI);
        for i in 1..n {
            sum += if i % 2 == 1 { 4.0 } else { 2.0 } * g(i as f64 * h);
        }
        2.0 * PI * sum * h / 3.0
    }

    #[test]
    fn analytic_phase_functions_integrate_to_one() {
        for rho in [0.0, 0.0279, 0.08, 0.5] {
            let total = sphere_integral(|mu| rayleigh_phase(rho, mu), 0);
            assert!((total - 1.0).abs() < 1e-10, "rayleigh {rho}: {total}");
        }
        for g in [-0.7, 0.0, 0.5, 0.76, 0.9] {
            let total = sphere_integral(|mu| henyey_greenstein_phase(g, mu), 0);
            assert!((total - 1.0).abs() < 1e-8, "hg {g}: {total}");
            let mean = sphere_integral(|mu| henyey_greenstein_phase(g, mu), 1);
            assert!((mean - g).abs() < 1e-8, "hg mean {g}: {mean}");
            let total = sphere_integral(|mu| cornette_shanks_phase(g, mu), 0);
            assert!((total - 1.0).abs() < 1e-8, "cs {g}: {total}");
            let mean = sphere_integral(|mu| cornette_shanks_phase(g, mu), 1);
            assert!(
                (mean - cornette_shanks_asymmetry(g)).abs() < 1e-8,
                "cs mean {g}: {mean}"
            );
        }
    }

    #[test]
    fn rayleigh_depolarisation_flattens_the_function() {
        // 3/(16 pi)(1 + mu^2) at 0 and 90 degrees, and rho = 1 is isotropic.
        assert!((rayleigh_phase(0.0, 1.0) - 6.0 / (16.0 * PI)).abs() < 1e-15);
        assert!((rayleigh_phase(0.0, 0.0) - 3.0 / (16.0 * PI)).abs() < 1e-15);
        assert!((rayleigh_phase(1.0, 0.3) - ISOTROPIC_PHASE_PER_SR).abs() < 1e-15);
        let ratio = |rho: f64| rayleigh_phase(rho, 1.0) / rayleigh_phase(rho, 0.0);
        assert!(ratio(0.0279) < ratio(0.0));
    }

    #[test]
    fn tabulated_phase_is_normalised_and_has_the_right_mean_cosine() {
        // Tabulate HG(0.7) on nodes dense in the forward direction.
        let nodes: Vec<f64> = (0..=400)
            .map(|j| (PI * (1.0 - j as f64 / 400.0).powi(2)).cos())
            .collect();
        let values = nodes
            .iter()
            .map(|&mu| henyey_greenstein_phase(0.7, mu) * 3.0)
            .collect();
        let table = TabulatedPhase::new(nodes.clone(), vec![values]).unwrap();
        let phase = PhaseFunction::Tabulated(table);
        let total = sphere_integral(|mu| phase.eval(0, mu), 0);
        assert!((total - 1.0).abs() < 1e-6, "{total}");
        // The exact mean cosine of the interpolant agrees with quadrature
        // and, for a fine table, with g.
        let mean = sphere_integral(|mu| phase.eval(0, mu), 1);
        assert!((phase.asymmetry_g(0) - mean).abs() < 1e-6, "{mean}");
        assert!(
            (phase.asymmetry_g(0) - 0.7).abs() < 2e-3,
            "{}",
            phase.asymmetry_g(0)
        );
        assert!(TabulatedPhase::new(vec![-1.0, 0.5], vec![vec![1.0, 1.0]]).is_none());
        assert!(TabulatedPhase::new(vec![-1.0, 1.0], vec![vec![0.0, 0.0]]).is_none());
    }

    /// Histogram of sampled mu against the pdf: each of 20 bins in mu gets
    /// probability 2 pi integral pdf dmu, within 5 standard deviations.
    fn check_sampling(phase: &PhaseFunction) {
        let n = 200_000;
        let bins = 20;
        let mut counts = vec![0usize; bins];
        // A deterministic low-discrepancy sequence (golden ratio).
        let mut u0 = 0.5f64;
        for i in 0..n {
            u0 = (u0 + 0.618_033_988_749_894_9) % 1.0;
            let sample = phase.sample(0, [u0, (i as f64 * 0.754_877_666) % 1.0]);
            assert!((-1.0..=1.0).contains(&sample.cos_theta));
            assert!((sample.pdf - phase.pdf(0, sample.cos_theta)).abs() < 1e-12);
            let bin = (((sample.cos_theta + 1.0) / 2.0 * bins as f64) as usize).min(bins - 1);
            counts[bin] += 1;
        }
        for (b, &count) in counts.iter().enumerate() {
            let lo = -1.0 + 2.0 * b as f64 / bins as f64;
            let hi = lo + 2.0 / bins as f64;
            let m = 2000;
            let expected: f64 = (0..m)
                .map(|k| {
                    let mu = lo + (k as f64 + 0.5) * (hi - lo) / m as f64;
                    2.0 * PI * phase.pdf(0, mu) * (hi - lo) / m as f64
                })
                .sum();
            let observed = count as f64 / n as f64;
            let sigma = (expected * (1.0 - expected) / n as f64).sqrt();
            assert!(
                (observed - expected).abs() < 5.0 * sigma + 1e-4,
                "{}: bin {b}: {observed} vs {expected}",
                phase.kind()
            );
        }
    }

    #[test]
    fn sampling_follows_the_pdf() {
        check_sampling(&PhaseFunction::Isotropic);
        check_sampling(&PhaseFunction::Rayleigh {
            depolarization_ratios: vec![0.0],
        });
        check_sampling(&PhaseFunction::Rayleigh {
            depolarization_ratios: vec![0.08],
        });
        check_sampling(&PhaseFunction::HenyeyGreenstein {
            asymmetry_g: vec![0.7],
        });
        check_sampling(&PhaseFunction::HenyeyGreenstein {
            asymmetry_g: vec![-0.3],
        });
        check_sampling(&PhaseFunction::CornetteShanks { g: vec![0.6] });
        let nodes: Vec<f64> = (0..=50)
            .map(|j| -1.0 + 2.0 * (j as f64 / 50.0).powf(0.5))
            .collect();
        let mut nodes = nodes;
        *nodes.last_mut().unwrap() = 1.0;
        let values = nodes
            .iter()
            .map(|&mu| 1.0 + mu * mu + 4.0 * mu.max(0.0).powi(8))
            .collect();
        check_sampling(&PhaseFunction::Tabulated(
            TabulatedPhase::new(nodes, vec![values]).unwrap(),
        ));
    }

    #[test]
    fn eval_into_fills_every_wavelength() {
        let phase = PhaseFunction::Rayleigh {
            depolarization_ratios: vec![0.0, 0.03, 0.1],
        };
        let mut out = [0.0; 3];
        phase.eval_into(1.0, &mut out);
        for (i, v) in out.iter().enumerate() {
            assert_eq!(*v, phase.eval(i, 1.0));
        }
        assert!(out[0] > out[2]);
    }

    #[test]
    fn tabulated_eval_into_equals_eval_at_every_wavelength() {
        let nodes: Vec<f64> = (0..=40).map(|i| -1.0 + i as f64 / 20.0).collect();
        let rows: Vec<Vec<f64>> = [0.3, 0.6, 0.85]
            .iter()
            .map(|g| {
                nodes
                    .iter()
                    .map(|mu| henyey_greenstein_phase(*g, *mu))
                    .collect()
            })
            .collect();
        let phase = PhaseFunction::Tabulated(TabulatedPhase::new(nodes, rows).unwrap());
        let mut out = [0.0; 3];
        for mu in [-1.0, -0.999, -0.3, 0.0, 0.41, 0.95, 0.9999, 1.0] {
            phase.eval_into(mu, &mut out);
            for (i, v) in out.iter().enumerate() {
                assert_eq!(*v, phase.eval(i, mu), "mu {mu} row {i}");
            }
        }
    }

    #[test]
    fn rayleigh_a1_is_the_scalar_phase_function() {
        for rho in [0.0, 0.0279, 0.1, 0.3] {
            let phase = PhaseFunction::Rayleigh {
                depolarization_ratios: vec![rho],
            };
            for k in 0..=20 {
                let mu = -1.0 + 0.1 * k as f64;
                let m = rayleigh_phase_matrix(rho, mu);
                let p = phase.eval(0, mu);
                assert!((m.a1 - p).abs() <= 1e-15 * p, "rho {rho} mu {mu}");
            }
        }
    }

    #[test]
    fn tabulated_functions_carry_their_ratios() {
        use crate::mie::ensemble::PhaseMatrixRatios;
        let nodes = vec![-1.0, 0.0, 1.0];
        let mut table = TabulatedPhase::new(nodes.clone(), vec![vec![1.0, 0.5, 2.0]]).unwrap();
        assert!(!PhaseFunction::Tabulated(table.clone()).has_phase_matrix());
        let ratios = PhaseMatrixRatios {
            cos_theta: nodes.clone(),
            f12_over_f11: vec![0.0, -0.8, 0.0],
            f33_over_f11: vec![-1.0, 0.1, 1.0],
            f34_over_f11: vec![0.0, 0.2, 0.0],
        };
        // Ratios on other nodes, or for another number of wavelengths, are refused.
        let shifted = PhaseMatrixRatios {
            cos_theta: vec![-1.0, 0.1, 1.0],
            ..ratios.clone()
        };
        assert!(!table.set_matrix_ratios(vec![shifted]));
        assert!(!table.set_matrix_ratios(vec![ratios.clone(), ratios.clone()]));
        assert!(table.set_matrix_ratios(vec![ratios]));
        let phase = PhaseFunction::Tabulated(table);
        assert!(phase.has_phase_matrix());
        // At a node: a1 the table's value, the rest a1 times the ratios;
        // halfway between nodes, linear in cos theta.
        let mut out = [PhaseMatrix::default()];
        phase.phase_matrix_into(0.0, &mut out);
        let a1 = phase.eval(0, 0.0);
        assert!((out[0].a1 - a1).abs() < 1e-15 && (out[0].b1 + 0.8 * a1).abs() < 1e-15);
        assert!((out[0].a3 - 0.1 * a1).abs() < 1e-15 && (out[0].b2 - 0.2 * a1).abs() < 1e-15);
        assert_eq!((out[0].a2, out[0].a4), (out[0].a1, out[0].a3));
        phase.phase_matrix_into(0.5, &mut out);
        let a1 = phase.eval(0, 0.5);
        assert!((out[0].b1 + 0.4 * a1).abs() < 1e-12, "{:?}", out[0]);
    }

    #[test]
    fn parametric_functions_do_not_polarise() {
        let phase = PhaseFunction::HenyeyGreenstein {
            asymmetry_g: vec![0.7, 0.2],
        };
        let mut out = [PhaseMatrix::default(); 2];
        phase.phase_matrix_into(0.3, &mut out);
        for (i, m) in out.iter().enumerate() {
            assert_eq!(m.b1, 0.0);
            assert_eq!(m.normalised_matrix()[1][1], 1.0);
            assert_eq!(m.a1, phase.eval(i, 0.3));
        }
        assert!(phase.has_phase_matrix());
    }
}
