//! # Phase tables interpolated in the refractive index
//!
//! With a tabulated m(lambda) every wavelength has its own index `n + i k`
//! (dimensionless). Rather than one phase computation per index, the
//! tables are computed for all the wavelengths at five reference indices
//! (four Chebyshev-Lobatto points in `ln k` at the middle `n`, one at the
//! largest `n`) and each wavelength's table is their weighted sum: cubic in
//! `ln k`, linear in `n`, then renormalised. [`index_interpolation_applies`]
//! says where that is validated; the module docs ("A tabulated index")
//! give the reasons and the measured errors.

use super::EnsembleError;
use super::phase_table::{PhaseTableWorkspace, TabulatedPhaseFunction};
use crate::Complex64;
use crate::distribution::{RadiusQuadratureSettings, SizeDistribution, SizeDistributionError};
use std::f64::consts::PI;

/// Number of reference values of ln k of the index interpolation (Chebyshev-Lobatto points).
const INTERPOLATION_ABSORPTION_NODES: usize = 4;

/// Widest spread of the real part n over a spectrum that the index
/// interpolation (linear in n) accepts; validated on the Wolff et al.
/// (2009) Mars dust, whose n spans 0.0044 over 380-780 nm.
pub const MAX_INTERPOLATED_REAL_INDEX_SPREAD: f64 = 0.01;

/// Largest ratio k_max / k_min that the index interpolation (cubic in ln k)
/// accepts; validated on the Wolff et al. (2009) Mars dust (ratio 10.5).
pub const MAX_INTERPOLATED_ABSORPTION_RATIO: f64 = 20.0;

/// Whether [`SpectralPhaseMethod::IndexInterpolated`](super::SpectralPhaseMethod::IndexInterpolated) interpolates for
/// these distinct indices, rather than computing each exactly: more distinct
/// indices than the interpolation's reference computations, all absorbing
/// (k > 0, as ln k is the interpolation variable), n spread at most
/// [`MAX_INTERPOLATED_REAL_INDEX_SPREAD`] and k_max / k_min at most
/// [`MAX_INTERPOLATED_ABSORPTION_RATIO`].
pub fn index_interpolation_applies(distinct_indices: &[Complex64]) -> bool {
    let Some(plan) = IndexInterpolationPlan::new(distinct_indices) else {
        return false;
    };
    distinct_indices.len() > plan.reference_indices().len()
}

/// The reference indices of the index interpolation and the weights that
/// combine their tables for one index (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct IndexInterpolationPlan {
    /// ln k of the reference indices at n_mid (Chebyshev-Lobatto in [ln k_min, ln k_max]).
    ln_absorption_nodes: [f64; INTERPOLATION_ABSORPTION_NODES],
    /// n_mid = (n_min + n_max) / 2.
    real_mid: f64,
    /// n_max - n_mid: the step of the n reference (0: n is constant, no n reference).
    real_half_spread: f64,
}

impl IndexInterpolationPlan {
    /// The plan for these indices, or `None` outside the validated range.
    pub(super) fn new(indices: &[Complex64]) -> Option<Self> {
        let first = indices.first()?;
        let (mut k_min, mut k_max, mut n_min, mut n_max) = (first.im, first.im, first.re, first.re);
        for m in indices {
            k_min = k_min.min(m.im);
            k_max = k_max.max(m.im);
            n_min = n_min.min(m.re);
            n_max = n_max.max(m.re);
        }
        let valid = k_min > 0.0
            && k_max.is_finite()
            && k_max <= MAX_INTERPOLATED_ABSORPTION_RATIO * k_min
            && n_max - n_min <= MAX_INTERPOLATED_REAL_INDEX_SPREAD
            // Distinct values of ln k, or the Lagrange basis is singular.
            && k_max > k_min * (1.0 + 1e-6);
        if !valid {
            return None;
        }
        let (lower, upper) = (k_min.ln(), k_max.ln());
        let (centre, half_width) = (0.5 * (lower + upper), 0.5 * (upper - lower));
        let mut ln_absorption_nodes = [0.0; INTERPOLATION_ABSORPTION_NODES];
        for (j, node) in ln_absorption_nodes.iter_mut().enumerate() {
            let angle = PI * j as f64 / (INTERPOLATION_ABSORPTION_NODES - 1) as f64;
            *node = centre - half_width * angle.cos();
        }
        // The end nodes exactly at the ends (cos rounding), so that no weight extrapolates.
        ln_absorption_nodes[0] = lower;
        ln_absorption_nodes[INTERPOLATION_ABSORPTION_NODES - 1] = upper;
        let real_mid = 0.5 * (n_min + n_max);
        Some(Self {
            ln_absorption_nodes,
            real_mid,
            real_half_spread: n_max - real_mid,
        })
    }

    /// Index of the reference that sits beside the n reference (same k, n_mid).
    const REAL_PARTNER: usize = INTERPOLATION_ABSORPTION_NODES / 2;

    /// The reference indices: n_mid + i k_j for each ln k node, then (if n
    /// varies) n_max + i k_{REAL_PARTNER}.
    pub(super) fn reference_indices(&self) -> Vec<Complex64> {
        let mut references: Vec<Complex64> = self
            .ln_absorption_nodes
            .iter()
            .map(|&ln_k| Complex64::new(self.real_mid, ln_k.exp()))
            .collect();
        if self.real_half_spread > 0.0 {
            references.push(Complex64::new(
                self.real_mid + self.real_half_spread,
                self.ln_absorption_nodes[Self::REAL_PARTNER].exp(),
            ));
        }
        references
    }

    /// Weight of each reference table for index `m`: the Lagrange basis in
    /// ln k at n_mid, plus t (P(n_max) - P(n_mid)) at the partner k, t =
    /// (n - n_mid) / (n_max - n_mid).
    pub(super) fn weights(&self, m: Complex64) -> Vec<f64> {
        let ln_k = m.im.ln();
        let nodes = &self.ln_absorption_nodes;
        let mut weights: Vec<f64> = (0..nodes.len())
            .map(|j| {
                nodes
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != j)
                    .map(|(_, &node)| (ln_k - node) / (nodes[j] - node))
                    .product()
            })
            .collect();
        if self.real_half_spread > 0.0 {
            let t = (m.re - self.real_mid) / self.real_half_spread;
            weights[Self::REAL_PARTNER] -= t;
            weights.push(t);
        }
        weights
    }
}

impl PhaseTableWorkspace {
    /// Phase tables at `wavelengths_nm`, where the particles have index
    /// `indices[i]` at `wavelengths_nm[i]`, by interpolation in the index
    /// between tables computed for all the wavelengths at a few reference
    /// indices (see the module docs). `indices` must satisfy
    /// [`index_interpolation_applies`].
    pub(super) fn compute_index_interpolated(
        &mut self,
        wavelengths_nm: &[f64],
        indices: &[Complex64],
        distribution: &SizeDistribution,
        settings: &RadiusQuadratureSettings,
    ) -> Result<Vec<TabulatedPhaseFunction>, EnsembleError> {
        let plan = IndexInterpolationPlan::new(indices)
            .expect("the caller checked index_interpolation_applies");
        let reference_tables = self.compute_for_indices(
            wavelengths_nm,
            &plan.reference_indices(),
            distribution,
            settings,
        )?;
        let angle_count = self.cos_theta.len();
        let mut tables = Vec::with_capacity(wavelengths_nm.len());
        for (wavelength, (&wavelength_nm, &m)) in wavelengths_nm.iter().zip(indices).enumerate() {
            let weights = plan.weights(m);
            let mut phase_per_sr = vec![0.0; angle_count];
            for (weight, reference) in weights.iter().zip(&reference_tables) {
                for (value, &reference_value) in phase_per_sr
                    .iter_mut()
                    .zip(reference[wavelength].phase_per_sr_nodes())
                {
                    *value += weight * reference_value;
                }
            }
            // The weights sum to 1 and each reference is positive; an
            // interpolant below 0 (never seen) would be clipped.
            phase_per_sr.iter_mut().for_each(|p| *p = p.max(0.0));
            tables.push(
                TabulatedPhaseFunction::from_nodes(self.cos_theta.clone(), phase_per_sr).map_err(
                    |error| {
                        EnsembleError::Distribution(
                            SizeDistributionError::InvalidQuadratureSettings {
                                message: format!(
                                    "interpolated phase table at {wavelength_nm} nm: {error}"
                                ),
                            },
                        )
                    },
                )?,
            );
        }
        Ok(tables)
    }
}
