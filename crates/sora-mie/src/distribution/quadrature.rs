//! # Quadrature over radius
//!
//! Every ensemble quantity is an integral over the population,
//!
//! ```text
//!     <f> = integral f(r) (dN/d ln r) / N_window d ln r,
//! ```
//!
//! done here as a composite Gauss-Legendre rule in `t = ln r` (or, for a
//! whole spectrum, in `ln x`, below): the range of [`super::SizeDistribution`]
//! (importance density within `exp(-tail_depth)` of its peak, clipped to the
//! window, so window edges are panel edges and the integrand is smooth inside
//! every panel) is cut into panels of `nodes_per_panel` Gauss-Legendre nodes.
//! The node weights include the number density, so `<f> = sum_i w_i f(r_i)`.
//!
//! ## The importance density
//!
//! Where the integral's mass lies is modelled, before any Mie solution, by
//! the importance density `r^2 min(1, x / 4) dN/d ln r` (`x = 2 pi r / lambda`):
//! a cross-section is about the geometric area times an efficiency that is
//! O(1) above `x ~ 4` and falls no faster than `x` below (absorption; scattering
//! falls like `x^4`). Its depth `D(t)` in e-folds below its peak drives both
//! the range and the node density. For the log-normal at large `x` it is
//! `z^2 / 2`, `z` in standard deviations from the area-weighted median.
//!
//! ## Panel widths: what must be resolved
//!
//! The distribution itself is smooth on the scale of its spread `s` in
//! `ln r`: panels at most `max_panel_width_in_spreads * s` and
//! `max_panel_width_ln_radius` wide, both widened by
//! `1 + tail_panel_widening_per_efold * D` in the tails, integrate it to
//! machine precision.
//!
//! The Mie efficiencies are not smooth in `ln r`. Above `x ~ 1` they carry the
//! ripple of the partial-wave resonances: Lorentzian peaks whose width, once
//! absorption limits it, is a fixed fraction of `x`, `Delta x / x ~ 2 k / n`
//! (full width; 0.013 for m = 1.5 + 0.01i), i.e. a fixed width in `ln r`. A
//! rule with node density `rho` per unit `ln r` integrates such a peak with
//! an error falling like `exp(-c rho k / n)`, so the density that reaches a
//! given accuracy is set by the narrowest resonances, and tails need less:
//! in the resonant range (`x >= min_resonant_size_parameter`) panels hold at
//! least
//!
//! ```text
//!     rho(D) = (resonance_nodes_per_unit_ln_radius - resonance_density_decrease_per_efold * D)
//!              * exp(-resonance_density_decay_rate_per_efold * D)
//! ```
//!
//! nodes per unit `ln r`. The linear decrease is the optimal allocation for
//! exponentially convergent errors (a panel carrying `e^-D` of the integral
//! needs `D / c` fewer nodes per unit); the exponential decay is the optimal
//! one for noise-like errors of unresolved oscillations (density
//! proportional to the weight), the phase function's regime.
//!
//! The interference structure (period `Delta x ~ pi / (n - 1)`) is damped
//! like `exp(-4 k x)` and is resolved wherever the resonances are.
//!
//! ## The ripple of weakly absorbing spheres
//!
//! For `k -> 0` absorption no longer bounds the resonance widths: they are
//! radiative, and at large `x` a fixed density per unit `ln r` is a step in
//! `x` that grows like `x` (150 per unit ln r is a step of 0.5 at x = 79)
//! while the ripple's structure does not widen. So the phase rule also
//! holds at least `ripple_nodes_per_unit_size_parameter * x` nodes per unit
//! `ln r` (a fixed step in `x`, relaxed with depth like the resonance
//! density), capped by [`RadiusQuadratureSettings::for_refractive_index`] at
//! [`RIPPLE_NODES_PER_ABSORPTION_WIDTH`] nodes per absorption-limited
//! resonance width, `0.15 n / (2 k)` per unit `ln r`. The cap switches the
//! ripple density off where absorption is strong enough for the resonance
//! density to be what it was: below 150 per unit `ln r` for
//! `k / n >= 5e-4`, so the phase rules of absorbing aerosols (the presets'
//! continental aerosol, k / n = 3.9e-3; Mars dust with the Wolff index,
//! k / n >= 6.3e-4) are unchanged node for node (tested). The price is
//! paid between: the same cloud with k = 1e-4 (1304 nodes) is within
//! 8.7e-3 (P11) and 7.0e-3 (F12/F11) at 120-180 deg, with k = 4e-4 (392
//! nodes, the cap below the resonance density) 3.9e-2 and 4.2e-2, the
//! absorption-limited resonances of the "Panel widths" section being
//! under-resolved as they are for Mars dust at 540-780 nm
//! ([`crate::ensemble`]). 0.6 nodes per absorption width brings both within
//! 4.5e-3 (4776 and 1304 nodes) but grows the Mars dust phase rule at the
//! 21 paper wavelengths from 512 to 1520 nodes.
//!
//! Measured (water, m = 1.329 + 1.25e-7i, 800 nm, modified gamma r_eff
//! 10 um, v_eff 0.1, x_eff = 79; P11 and F12/F11 at 120-180 deg every
//! 0.5 deg against a uniform trapezoid in ln r with 100 times the nodes over
//! the same range; worst relative error of P11, worst absolute of F12/F11):
//!
//! | nodes per unit x | nodes | P11 | F12/F11 |
//! |---|---|---|---|
//! | 0 (150 per unit ln r alone) | 256 | 8.5e-2 | 1.0e-1 |
//! | 4 | 464 | 5.3e-2 | 3.2e-2 |
//! | 8 | 880 | 2.8e-2 | 2.1e-2 |
//! | 16 | 1656 | 1.1e-2 | 1.1e-2 |
//! | 32 | 3152 | 4.5e-3 | 5.6e-3 |
//! | 64 | 6080 | 1.5e-3 | 2.6e-3 |
//! | 96 (the phase rule's) | 8960 | 2.0e-3 | 1.7e-3 |
//!
//! The error falls about like `N^-1.3`, not exponentially: the narrowest
//! resonances (width `2 k x / n ~ 1.5e-5` here) are never resolved, and what
//! converges is their sampling. The log-normal of the same r_eff and v_eff
//! (heavier large-particle tail) needs more: at 64 per unit x (6304 nodes)
//! P11 is within 1.4e-3 except at 180 deg exactly (6.4e-3, the glory); at
//! 96, 9184 nodes, 1.2e-3 and 1.2e-3 (264 nodes before: 9.8e-2 and 6.4e-2).
//! Hence 96 per unit `x`: for this cloud 35 times the nodes of the rule
//! before it, and the ensemble optics at one wavelength (cross-sections and
//! the 406-angle phase table) take 256 ms instead of 7.2 ms
//! (`benches/ensemble.rs`, `water_cloud_800nm`, both rules side by side).
//!
//! ## One quadrature for a whole spectrum
//!
//! A Mie solution depends on `m` and `x` only. For wavelengths at which the
//! particles have the same `m`, [`SharedSizeParameterQuadrature`] lays one
//! rule out in `ln x`: each wavelength needs the rule above at
//! `ln r = ln x - ln k`; a panel is the narrowest any wavelength needs there,
//! the range is the union of their ranges, and every window edge of every
//! wavelength, `ln(k r_min)` and `ln(k r_max)`, is a panel edge, so that each
//! wavelength's integral is an exact sum over whole panels. Each node carries
//! one weight per wavelength, `W_i dN/d ln r (x_i / k) / N_window` (0 outside
//! the window). The 21 paper wavelengths span `ln(780/380) = 0.72` in `ln x`,
//! a fraction of a typical range, so the whole spectrum costs little more than
//! one wavelength.
//!
//! ## Bounded memory
//!
//! The panels are laid out twice: once to count them, then, with the
//! vectors allocated at their final size, to fill them. A rule of more than
//! [`MAX_RADIUS_QUADRATURE_NODES`] nodes (2^20; the validated settings need
//! a few hundred to a few thousand) or a shared rule of more than
//! [`MAX_SHARED_QUADRATURE_WEIGHTS`] weights (nodes x wavelengths, 2^26:
//! 512 MiB) is refused before anything is allocated
//! ([`SizeDistributionError::TooManyQuadratureNodes`]): a narrow population
//! over thousands of wavelengths lays out separate panels for every
//! wavelength, and a panel narrower than the spacing of doubles would never
//! advance (the counting pass stops at the bound instead of running on).
//!
//! Measured errors of [`RadiusQuadratureSettings::cross_sections`] and
//! [`RadiusQuadratureSettings::phase_function`] are in [`crate::ensemble`].
//! [`RadiusQuadrature::trapezoid`] is the slow, obviously correct oracle:
//! a uniform trapezoid in `ln r` over the same range, spectrally accurate for
//! an integrand that vanishes at both ends, free of any panel-width logic.

use super::{SizeDistribution, SizeDistributionError};
use crate::quadrature::gauss_legendre;

/// Most nodes of one radius quadrature (see "Bounded memory" in the module
/// docs): 2^20, 16 MiB of radii and weights.
pub const MAX_RADIUS_QUADRATURE_NODES: usize = 1 << 20;

/// Most weights (nodes x wavelengths) of one [`SharedSizeParameterQuadrature`]:
/// 2^26, 512 MiB.
pub const MAX_SHARED_QUADRATURE_WEIGHTS: usize = 1 << 26;

/// The error for a rule of `node_count` nodes (or more: counting stops past
/// the bound) at `wavelength_count` wavelengths.
fn too_many_nodes(node_count: usize, wavelength_count: usize) -> SizeDistributionError {
    SizeDistributionError::TooManyQuadratureNodes {
        node_count,
        wavelength_count,
        max_nodes: MAX_RADIUS_QUADRATURE_NODES,
        max_weights: MAX_SHARED_QUADRATURE_WEIGHTS,
    }
}

/// Nodes per absorption-limited resonance width at which the ripple
/// density is capped ([`RadiusQuadratureSettings::for_refractive_index`]; see
/// "The ripple of weakly absorbing spheres" in the module docs).
pub const RIPPLE_NODES_PER_ABSORPTION_WIDTH: f64 = 0.15;

/// How the radius quadrature lays out its panels (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RadiusQuadratureSettings {
    /// Gauss-Legendre nodes per panel (>= 1).
    pub nodes_per_panel: usize,
    /// Largest panel width in ln r, whatever the distribution (> 0).
    pub max_panel_width_ln_radius: f64,
    /// Largest panel width in units of the distribution's spread s in ln r (> 0).
    pub max_panel_width_in_spreads: f64,
    /// Node density (nodes per unit of ln r) that resolves the Mie resonance
    /// structure, at the peak of the area-weighted density (>= 0; 0 disables
    /// it, as does building the quadrature without a wavelength).
    pub resonance_nodes_per_unit_ln_radius: f64,
    /// Decrease of that density per e-fold of depth of the importance
    /// density below its peak (>= 0): tails need less resolution.
    pub resonance_density_decrease_per_efold: f64,
    /// Exponential decay rate of that density per e-fold of depth (>= 0):
    /// the optimal allocation when errors are noise-like (unresolved
    /// oscillations, as in the phase function) rather than exponentially
    /// convergent.
    pub resonance_density_decay_rate_per_efold: f64,
    /// Size parameter below which there is no resonance structure to resolve
    /// (>= 0).
    pub min_resonant_size_parameter: f64,
    /// Node density per unit of size parameter that resolves the ripple of
    /// weakly absorbing spheres (>= 0; 0 disables it): nodes per unit ln r
    /// are at least this times x, with the same relaxation with depth as
    /// the resonance density. See "The ripple of weakly absorbing spheres"
    /// in the module docs.
    pub ripple_nodes_per_unit_size_parameter: f64,
    /// Cap on the ripple density, in nodes per unit ln r (> 0, may be
    /// infinite): [`Self::for_refractive_index`] sets it to
    /// [`RIPPLE_NODES_PER_ABSORPTION_WIDTH`] nodes per absorption-limited
    /// resonance width, `RIPPLE_NODES_PER_ABSORPTION_WIDTH * n / (2 k)`.
    pub ripple_max_nodes_per_unit_ln_radius: f64,
    /// Growth of the smoothness limits (the two maximum panel widths) per
    /// e-fold of depth below the peak of the importance density (>= 0): the
    /// tails carry little of the integral and vary smoothly.
    pub tail_panel_widening_per_efold: f64,
    /// The range ends where the importance density is this many e-folds
    /// below its peak (> 0).
    pub tail_depth: f64,
}

impl RadiusQuadratureSettings {
    /// For the ensemble cross-sections, g and single-scattering albedo:
    /// 450 nodes per unit ln r at the peak, 30 fewer per e-fold of depth,
    /// range +-6 s (depth 18). Measured error (against the reference table
    /// and a 4 times denser rule): see [`crate::ensemble`]'s module docs.
    pub fn cross_sections() -> Self {
        Self {
            nodes_per_panel: 8,
            max_panel_width_ln_radius: 0.25,
            max_panel_width_in_spreads: 0.5,
            resonance_nodes_per_unit_ln_radius: 450.0,
            resonance_density_decrease_per_efold: 30.0,
            resonance_density_decay_rate_per_efold: 0.0,
            min_resonant_size_parameter: 1.0,
            ripple_nodes_per_unit_size_parameter: 0.0,
            ripple_max_nodes_per_unit_ln_radius: f64::INFINITY,
            tail_panel_widening_per_efold: 0.25,
            tail_depth: 18.0,
        }
    }

    /// For the ensemble phase-function table, whose per-node cost is a whole
    /// angular table (406 angles): a narrower range and a node density that
    /// decays exponentially with depth, the optimal allocation for the
    /// noise-like error of unresolved oscillations of S11(theta) in x (see
    /// [`crate::ensemble`] for the measured error), and at least 96 nodes per
    /// unit x for the ripple of weakly absorbing spheres (capped by
    /// [`Self::for_refractive_index`]; see the module docs).
    pub fn phase_function() -> Self {
        Self {
            nodes_per_panel: 8,
            max_panel_width_ln_radius: 0.5,
            max_panel_width_in_spreads: 1.0,
            resonance_nodes_per_unit_ln_radius: 150.0,
            resonance_density_decrease_per_efold: 0.0,
            resonance_density_decay_rate_per_efold: 0.5,
            min_resonant_size_parameter: 1.0,
            ripple_nodes_per_unit_size_parameter: 96.0,
            ripple_max_nodes_per_unit_ln_radius: f64::INFINITY,
            tail_panel_widening_per_efold: 0.25,
            tail_depth: 12.0,
        }
    }

    /// For smooth integrands (moments of the distribution, no Mie
    /// structure): panels of at most s/4, 16 nodes each, the full range.
    pub fn smooth() -> Self {
        Self {
            nodes_per_panel: 16,
            max_panel_width_ln_radius: 0.25,
            max_panel_width_in_spreads: 0.25,
            resonance_nodes_per_unit_ln_radius: 0.0,
            resonance_density_decrease_per_efold: 0.0,
            resonance_density_decay_rate_per_efold: 0.0,
            min_resonant_size_parameter: 0.0,
            ripple_nodes_per_unit_size_parameter: 0.0,
            ripple_max_nodes_per_unit_ln_radius: f64::INFINITY,
            tail_panel_widening_per_efold: 0.0,
            tail_depth: 40.0,
        }
    }

    /// These settings for particles of index `m = n + ik`: the ripple
    /// density capped at [`RIPPLE_NODES_PER_ABSORPTION_WIDTH`] nodes per
    /// absorption-limited resonance width (full width `Delta x / x = 2 k / n`),
    /// i.e. at `RIPPLE_NODES_PER_ABSORPTION_WIDTH * n / (2 k)` nodes per unit
    /// ln r (no cap for `k = 0`). For several indices sharing one rule, pass
    /// the one of smallest `k / n`.
    pub fn for_refractive_index(self, refractive_index: crate::Complex64) -> Self {
        let cap =
            RIPPLE_NODES_PER_ABSORPTION_WIDTH * refractive_index.re / (2.0 * refractive_index.im);
        Self {
            ripple_max_nodes_per_unit_ln_radius: if cap > 0.0 { cap } else { f64::INFINITY },
            ..self
        }
    }

    fn validate(&self) -> Result<(), SizeDistributionError> {
        let positive_finite = |value: f64| value > 0.0 && value.is_finite(); // NaN fails
        let nonnegative_finite = |value: f64| value >= 0.0 && value.is_finite();
        let message = if self.nodes_per_panel == 0 {
            Some("nodes_per_panel must be at least 1")
        } else if !positive_finite(self.max_panel_width_ln_radius) {
            Some("max_panel_width_ln_radius must be finite and > 0")
        } else if !positive_finite(self.max_panel_width_in_spreads) {
            Some("max_panel_width_in_spreads must be finite and > 0")
        } else if !(nonnegative_finite(self.resonance_nodes_per_unit_ln_radius)
            && nonnegative_finite(self.resonance_density_decrease_per_efold)
            && nonnegative_finite(self.resonance_density_decay_rate_per_efold)
            && nonnegative_finite(self.min_resonant_size_parameter)
            && nonnegative_finite(self.ripple_nodes_per_unit_size_parameter)
            && nonnegative_finite(self.tail_panel_widening_per_efold))
        {
            Some(
                "the resonance node density, its decrease and the minimum resonant size parameter and the tail widening must be finite and >= 0",
            )
        } else if self.ripple_max_nodes_per_unit_ln_radius.is_nan()
            || self.ripple_max_nodes_per_unit_ln_radius <= 0.0
        {
            Some("ripple_max_nodes_per_unit_ln_radius must be > 0 (infinite for no cap)")
        } else if !positive_finite(self.tail_depth) {
            Some("tail_depth must be finite and > 0")
        } else {
            None
        };
        match message {
            Some(message) => Err(SizeDistributionError::InvalidQuadratureSettings {
                message: message.to_string(),
            }),
            None => Ok(()),
        }
    }
}

/// The widest panel (in ln r) that `settings` allow at t = ln r for a Mie
/// integrand at wavenumber `wavenumber_per_m` (0: no Mie structure): the
/// smoothness limit, widened in the tails, and the resonance-resolving node
/// density where x is above the resonant threshold.
fn panel_width_limit(
    distribution: &SizeDistribution,
    settings: &RadiusQuadratureSettings,
    ln_radius: f64,
    wavenumber_per_m: f64,
) -> f64 {
    let core_smooth_limit = settings
        .max_panel_width_ln_radius
        .min(settings.max_panel_width_in_spreads * distribution.ln_radius_spread());
    let depth = distribution.importance_depth_below_peak(ln_radius, wavenumber_per_m);
    let smooth_limit = core_smooth_limit * (1.0 + settings.tail_panel_widening_per_efold * depth);
    let size_parameter = wavenumber_per_m * ln_radius.exp();
    if wavenumber_per_m <= 0.0 || size_parameter < settings.min_resonant_size_parameter {
        return smooth_limit;
    }
    let ripple_density = (settings.ripple_nodes_per_unit_size_parameter * size_parameter)
        .min(settings.ripple_max_nodes_per_unit_ln_radius);
    let resonance_density = (settings
        .resonance_nodes_per_unit_ln_radius
        .max(ripple_density)
        - settings.resonance_density_decrease_per_efold * depth)
        * (-settings.resonance_density_decay_rate_per_efold * depth).exp();
    let nodes_per_panel = settings.nodes_per_panel as f64;
    if resonance_density * smooth_limit <= nodes_per_panel {
        smooth_limit
    } else {
        nodes_per_panel / resonance_density
    }
}

/// Nodes in size parameter `x = k r` shared by several wavelengths, with
/// one weight per node and wavelength (see the module docs): for particles
/// whose refractive index is the same at all these wavelengths, one Mie
/// solution per node serves every wavelength.
#[derive(Debug, Clone, PartialEq)]
pub struct SharedSizeParameterQuadrature {
    size_parameter: Vec<f64>,
    wavenumber_per_m: Vec<f64>,
    /// Row-major: `weight[node * wavelength_count + wavelength_index]`.
    weight: Vec<f64>,
    panel_count: usize,
}

impl SharedSizeParameterQuadrature {
    /// Composite Gauss-Legendre in t = ln x covering every wavelength's
    /// range (see [`RadiusQuadrature::gauss_legendre`]); a panel is as narrow
    /// as the narrowest that any wavelength needs there, and every edge of a
    /// wavelength's radius window is a panel edge. `wavenumbers_per_m` are
    /// 2 pi / lambda (m^-1, > 0, at least one).
    pub fn gauss_legendre(
        distribution: &SizeDistribution,
        wavenumbers_per_m: &[f64],
        settings: &RadiusQuadratureSettings,
    ) -> Result<Self, SizeDistributionError> {
        settings.validate()?;
        if wavenumbers_per_m.is_empty()
            || wavenumbers_per_m
                .iter()
                .any(|k| !(k.is_finite() && *k > 0.0))
        {
            return Err(SizeDistributionError::InvalidQuadratureSettings {
                message: format!(
                    "a shared size-parameter quadrature needs at least one wavenumber, each finite and > 0 (m^-1), got {wavenumbers_per_m:?}"
                ),
            });
        }
        let ln_wavenumbers: Vec<f64> = wavenumbers_per_m.iter().map(|k| k.ln()).collect();
        // Each wavelength's range in ln x.
        let ranges: Vec<(f64, f64)> = wavenumbers_per_m
            .iter()
            .zip(&ln_wavenumbers)
            .map(|(&k, &ln_k)| {
                let (lower, upper) =
                    distribution.ln_radius_integration_range(settings.tail_depth, k);
                (lower + ln_k, upper + ln_k)
            })
            .collect();
        let mut breakpoints: Vec<f64> = Vec::new();
        let ln_radius_breakpoints = distribution.ln_radius_breakpoints();
        for &ln_k in &ln_wavenumbers {
            breakpoints.extend(ln_radius_breakpoints.iter().map(|t| t + ln_k));
        }
        let union_end = ranges.iter().map(|r| r.1).fold(f64::NEG_INFINITY, f64::max);
        breakpoints.push(union_end);
        breakpoints.sort_by(f64::total_cmp);

        let width_limit_at = |ln_size_parameter: f64| -> Option<f64> {
            let mut limit: Option<f64> = None;
            for ((&k, &ln_k), &(lower, upper)) in
                wavenumbers_per_m.iter().zip(&ln_wavenumbers).zip(&ranges)
            {
                if (lower..upper).contains(&ln_size_parameter) {
                    let width =
                        panel_width_limit(distribution, settings, ln_size_parameter - ln_k, k);
                    limit = Some(limit.map_or(width, |l: f64| l.min(width)));
                }
            }
            limit
        };
        let wavelength_count = wavenumbers_per_m.len();
        let first_start = ranges.iter().map(|r| r.0).fold(f64::INFINITY, f64::min);
        // The panels as (start, width), visited in order; stops (returning
        // false) when `visit` does.
        let lay_out = |visit: &mut dyn FnMut(f64, f64) -> bool| {
            let mut panel_start = first_start;
            while panel_start < union_end {
                let Some(tentative) = width_limit_at(panel_start) else {
                    // A gap that no wavelength's range covers: skip to the next range.
                    panel_start = ranges
                        .iter()
                        .map(|r| r.0)
                        .filter(|&lower| lower > panel_start)
                        .fold(union_end, f64::min);
                    continue;
                };
                let mut width =
                    width_limit_at(panel_start + tentative).map_or(tentative, |w| w.min(tentative));
                // Panels end at window edges, never stride them; no sliver before one.
                let next_stop = breakpoints
                    .iter()
                    .copied()
                    .find(|&b| b > panel_start)
                    .unwrap_or(union_end);
                if panel_start + 1.25 * width >= next_stop {
                    width = next_stop - panel_start;
                }
                if !visit(panel_start, width) {
                    return;
                }
                panel_start += width;
            }
        };
        // Count first (stopping past the bound), allocate once, then fill.
        let nodes_per_panel = settings.nodes_per_panel;
        let fits = |panels: usize| {
            let nodes = panels.saturating_mul(nodes_per_panel);
            nodes <= MAX_RADIUS_QUADRATURE_NODES
                && nodes.saturating_mul(wavelength_count) <= MAX_SHARED_QUADRATURE_WEIGHTS
        };
        let mut panel_count = 0usize;
        lay_out(&mut |_, _| {
            panel_count += 1;
            fits(panel_count)
        });
        if !fits(panel_count) {
            return Err(too_many_nodes(
                panel_count * nodes_per_panel,
                wavelength_count,
            ));
        }
        let (unit_nodes, unit_weights) = gauss_legendre(nodes_per_panel);
        let mut size_parameter = Vec::with_capacity(panel_count * nodes_per_panel);
        let mut weight = Vec::with_capacity(panel_count * nodes_per_panel * wavelength_count);
        lay_out(&mut |panel_start, width| {
            let half_width = 0.5 * width;
            let middle = panel_start + half_width;
            for (&node, &unit_weight) in unit_nodes.iter().zip(&unit_weights) {
                let ln_x = middle + half_width * node;
                size_parameter.push(ln_x.exp());
                for (&k, &ln_k) in wavenumbers_per_m.iter().zip(&ln_wavenumbers) {
                    let ln_radius = ln_x - ln_k;
                    let inside_window = distribution.radius_window().is_none_or(|w| {
                        ln_radius > w.min_radius_m().ln() && ln_radius < w.max_radius_m().ln()
                    });
                    weight.push(if inside_window {
                        unit_weight
                            * half_width
                            * distribution
                                .number_density_per_ln_radius_inside_window(ln_x.exp() / k)
                    } else {
                        0.0
                    });
                }
            }
            true
        });
        debug_assert_eq!(size_parameter.len(), panel_count * nodes_per_panel);
        debug_assert_eq!(weight.len(), size_parameter.len() * wavelength_count);
        Ok(Self {
            size_parameter,
            wavenumber_per_m: wavenumbers_per_m.to_vec(),
            weight,
            panel_count,
        })
    }

    /// Size parameters of the nodes, increasing.
    pub fn size_parameters(&self) -> &[f64] {
        &self.size_parameter
    }

    /// The wavenumbers 2 pi / lambda (m^-1), in the order given.
    pub fn wavenumbers_per_m(&self) -> &[f64] {
        &self.wavenumber_per_m
    }

    /// Per-particle weights of node `node_index`, one per wavelength (0
    /// where the node lies outside that wavelength's radius window).
    pub fn weights_at_node(&self, node_index: usize) -> &[f64] {
        let count = self.wavenumber_per_m.len();
        &self.weight[node_index * count..(node_index + 1) * count]
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.size_parameter.len()
    }

    /// Whether there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.size_parameter.is_empty()
    }

    /// Number of panels.
    pub fn panel_count(&self) -> usize {
        self.panel_count
    }
}

/// Nodes and weights of a quadrature over a population's radii:
/// `<f> = integral f dN / N_window ~ sum_i weight_i f(radius_i)`. The weights
/// carry the number density and the per-particle normalisation.
#[derive(Debug, Clone, PartialEq)]
pub struct RadiusQuadrature {
    radius_m: Vec<f64>,
    weight: Vec<f64>,
    panel_count: usize,
}

impl RadiusQuadrature {
    /// Composite Gauss-Legendre in ln r laid out by `settings` for a Mie
    /// integrand at wavenumber `wavenumber_per_m` = 2 pi / lambda (m^-1;
    /// 0 ignores the size-parameter limit on panel widths).
    pub fn gauss_legendre(
        distribution: &SizeDistribution,
        wavenumber_per_m: f64,
        settings: &RadiusQuadratureSettings,
    ) -> Result<Self, SizeDistributionError> {
        settings.validate()?;
        if !(wavenumber_per_m.is_finite() && wavenumber_per_m >= 0.0) {
            return Err(SizeDistributionError::InvalidQuadratureSettings {
                message: format!("wavenumber {wavenumber_per_m} m^-1 must be finite and >= 0"),
            });
        }
        let (lower, upper) =
            distribution.ln_radius_integration_range(settings.tail_depth, wavenumber_per_m);
        let width_limit_at =
            |ln_radius: f64| panel_width_limit(distribution, settings, ln_radius, wavenumber_per_m);
        // Panels end at a table's points (kinks of the density), never stride them.
        let breakpoints = distribution.ln_radius_breakpoints();
        let lay_out = |visit: &mut dyn FnMut(f64, f64) -> bool| {
            let mut panel_start = lower;
            while panel_start < upper {
                // The limit at both ends of the tentative panel: x grows across it.
                let tentative = width_limit_at(panel_start);
                let mut width = tentative.min(width_limit_at(panel_start + tentative));
                // No sliver panel before a breakpoint or the end: stretch the
                // panel by up to a quarter.
                let next_stop = breakpoints
                    .iter()
                    .copied()
                    .find(|&b| b > panel_start && b < upper)
                    .unwrap_or(upper);
                if panel_start + 1.25 * width >= next_stop {
                    width = next_stop - panel_start;
                }
                if !visit(panel_start, width) {
                    return;
                }
                panel_start += width;
            }
        };
        // Count first (stopping past the bound), allocate once, then fill.
        let nodes_per_panel = settings.nodes_per_panel;
        let fits =
            |panels: usize| panels.saturating_mul(nodes_per_panel) <= MAX_RADIUS_QUADRATURE_NODES;
        let mut panel_count = 0usize;
        lay_out(&mut |_, _| {
            panel_count += 1;
            fits(panel_count)
        });
        if !fits(panel_count) {
            return Err(too_many_nodes(panel_count * nodes_per_panel, 1));
        }
        let (unit_nodes, unit_weights) = gauss_legendre(nodes_per_panel);
        let mut radius_m = Vec::with_capacity(panel_count * nodes_per_panel);
        let mut weight = Vec::with_capacity(panel_count * nodes_per_panel);
        lay_out(&mut |panel_start, width| {
            let half_width = 0.5 * width;
            let middle = panel_start + half_width;
            for (&node, &unit_weight) in unit_nodes.iter().zip(&unit_weights) {
                let r = (middle + half_width * node).exp();
                radius_m.push(r);
                weight.push(
                    unit_weight
                        * half_width
                        * distribution.number_density_per_ln_radius_inside_window(r),
                );
            }
            true
        });
        Ok(Self {
            radius_m,
            weight,
            panel_count,
        })
    }

    /// The slow oracle: uniform trapezoid in ln r with `node_count` (>= 2)
    /// nodes over the range where the importance density at wavenumber
    /// `wavenumber_per_m` (m^-1; 0 for the area-weighted density) is within
    /// `exp(-tail_depth)` of its peak (clipped to the window).
    pub fn trapezoid(
        distribution: &SizeDistribution,
        wavenumber_per_m: f64,
        node_count: usize,
        tail_depth: f64,
    ) -> Result<Self, SizeDistributionError> {
        let valid_wavenumber = wavenumber_per_m.is_finite() && wavenumber_per_m >= 0.0;
        if node_count < 2 || !(tail_depth > 0.0 && tail_depth.is_finite()) || !valid_wavenumber {
            return Err(SizeDistributionError::InvalidQuadratureSettings {
                message: format!(
                    "trapezoid needs at least 2 nodes (got {node_count}), a finite tail depth > 0 (got {tail_depth}) and a finite wavenumber >= 0 (got {wavenumber_per_m} m^-1)"
                ),
            });
        }
        let (lower, upper) = distribution.ln_radius_integration_range(tail_depth, wavenumber_per_m);
        let step = (upper - lower) / (node_count - 1) as f64;
        let mut radius_m = Vec::with_capacity(node_count);
        let mut weight = Vec::with_capacity(node_count);
        for i in 0..node_count {
            // The last node is placed at `upper` exactly: it may be a window edge.
            let ln_radius = if i + 1 == node_count {
                upper
            } else {
                lower + i as f64 * step
            };
            let r = ln_radius.exp();
            let end_factor = if i == 0 || i + 1 == node_count {
                0.5
            } else {
                1.0
            };
            radius_m.push(r);
            weight.push(
                end_factor * step * distribution.number_density_per_ln_radius_inside_window(r),
            );
        }
        Ok(Self {
            radius_m,
            weight,
            panel_count: node_count - 1,
        })
    }

    /// Radii of the nodes (m), increasing.
    pub fn radii_m(&self) -> &[f64] {
        &self.radius_m
    }

    /// Weights of the nodes (per particle, dimensionless).
    pub fn weights(&self) -> &[f64] {
        &self.weight
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.radius_m.len()
    }

    /// Whether there are no nodes (never, for a valid distribution).
    pub fn is_empty(&self) -> bool {
        self.radius_m.is_empty()
    }

    /// Number of panels (intervals, for the trapezoid).
    pub fn panel_count(&self) -> usize {
        self.panel_count
    }

    /// sum_i w_i f(r_i): the per-particle mean of `f` (f takes the radius in m).
    pub fn integrate(&self, mut f: impl FnMut(f64) -> f64) -> f64 {
        self.radius_m
            .iter()
            .zip(&self.weight)
            .map(|(&r, &w)| w * f(r))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distribution::RadiusWindow;

    const MICROMETRE: f64 = 1e-6;

    #[test]
    fn panels_follow_the_size_parameter_and_relax_in_the_tails() {
        let d = SizeDistribution::log_normal(1.5 * MICROMETRE, 2.0).unwrap();
        let settings = RadiusQuadratureSettings::cross_sections();
        let wavenumber = 2.0 * std::f64::consts::PI / 380e-9;
        let q = RadiusQuadrature::gauss_legendre(&d, wavenumber, &settings).unwrap();
        let without_relaxation = RadiusQuadratureSettings {
            resonance_density_decrease_per_efold: 0.0,
            ..settings
        };
        let q_strict =
            RadiusQuadrature::gauss_legendre(&d, wavenumber, &without_relaxation).unwrap();
        let q_no_wavelength = RadiusQuadrature::gauss_legendre(&d, 0.0, &settings).unwrap();
        assert!(q_no_wavelength.panel_count() < q.panel_count());
        assert!(q.panel_count() < q_strict.panel_count());
        assert_eq!(q.len(), 8 * q.panel_count());
        assert!(q.radii_m().windows(2).all(|w| w[0] < w[1]));
        // Each integrates the number of particles in its range, which leaves
        // out only small particles that scatter nothing.
        for (quadrature, k) in [
            (&q, wavenumber),
            (&q_strict, wavenumber),
            (&q_no_wavelength, 0.0),
        ] {
            let (lower, upper) = d.ln_radius_integration_range(settings.tail_depth, k);
            let in_range = d.shape().number_fraction_between(lower.exp(), upper.exp());
            assert!(1.0 - in_range < 1e-4, "{in_range}");
            assert!((quadrature.integrate(|_| 1.0) / in_range - 1.0).abs() < 1e-13);
        }
    }

    #[test]
    fn window_edges_are_panel_edges() {
        let d = SizeDistribution::log_normal(0.5 * MICROMETRE, 1.5)
            .unwrap()
            .truncated_to(RadiusWindow::from_micrometres(0.45, 0.56).unwrap())
            .unwrap();
        let q =
            RadiusQuadrature::gauss_legendre(&d, 1e7, &RadiusQuadratureSettings::cross_sections())
                .unwrap();
        let radii = q.radii_m();
        assert!(radii[0] > 0.45 * MICROMETRE && radii[radii.len() - 1] < 0.56 * MICROMETRE);
        // Per particle of the truncated population.
        assert!((q.integrate(|_| 1.0) - 1.0).abs() < 1e-14);
        let trapezoid = RadiusQuadrature::trapezoid(&d, 1e7, 20_001, 25.0).unwrap();
        assert!((trapezoid.integrate(|_| 1.0) - 1.0).abs() < 1e-8);
        let mean_radius = q.integrate(|r| r);
        assert!((trapezoid.integrate(|r| r) / mean_radius - 1.0).abs() < 1e-8);
    }

    #[test]
    fn invalid_settings_are_rejected() {
        let d = SizeDistribution::log_normal(0.5 * MICROMETRE, 1.5).unwrap();
        let bad = [
            RadiusQuadratureSettings {
                nodes_per_panel: 0,
                ..RadiusQuadratureSettings::cross_sections()
            },
            RadiusQuadratureSettings {
                max_panel_width_ln_radius: f64::NAN,
                ..RadiusQuadratureSettings::cross_sections()
            },
            RadiusQuadratureSettings {
                tail_depth: -1.0,
                ..RadiusQuadratureSettings::cross_sections()
            },
            RadiusQuadratureSettings {
                ripple_nodes_per_unit_size_parameter: f64::NAN,
                ..RadiusQuadratureSettings::phase_function()
            },
            RadiusQuadratureSettings {
                ripple_max_nodes_per_unit_ln_radius: 0.0,
                ..RadiusQuadratureSettings::phase_function()
            },
        ];
        for settings in bad {
            assert!(RadiusQuadrature::gauss_legendre(&d, 1e7, &settings).is_err());
        }
        assert!(
            RadiusQuadrature::gauss_legendre(&d, -1.0, &RadiusQuadratureSettings::cross_sections())
                .is_err()
        );
        assert!(RadiusQuadrature::trapezoid(&d, 1e7, 1, 25.0).is_err());
    }

    /// Issue 35: the phase rule's step in size parameter near the peak is
    /// bounded whatever the size parameter (water, k ~ 0: no cap), by what
    /// its settings promise: panels at most `nodes_per_panel / (96 x)` wide
    /// in ln r at depth 0, widened by `exp(0.5 D)` with depth, and at most
    /// 0.18 of a panel between neighbouring 8-point Gauss-Legendre nodes.
    /// The rule without the ripple density (150 nodes per unit ln r) steps
    /// about `x / 150` instead.
    #[test]
    fn the_ripple_step_in_size_parameter_is_bounded_whatever_the_size_parameter() {
        let water = crate::Complex64::new(1.329, 1.25e-7);
        let settings = RadiusQuadratureSettings::phase_function().for_refractive_index(water);
        let without_ripple = RadiusQuadratureSettings {
            ripple_nodes_per_unit_size_parameter: 0.0,
            ..settings
        };
        let wavenumber = 2.0 * std::f64::consts::PI / 800e-9;
        let (unit_nodes, _) = gauss_legendre(settings.nodes_per_panel);
        // Widest gap between neighbours in a panel, or across its edge, as a
        // fraction of the panel's width.
        let widest_gap_fraction = unit_nodes
            .windows(2)
            .map(|w| 0.5 * (w[1] - w[0]).abs())
            .fold(
                1.0 - unit_nodes.iter().fold(0.0f64, |a, &u| a.max(u.abs())),
                f64::max,
            );
        assert!(widest_gap_fraction < 0.19, "{widest_gap_fraction}");
        // Pairs of neighbours within one e-fold of the peak of the importance
        // density; the panels they lie in reach at most half a panel deeper.
        let max_depth = 1.5;
        let step_bound = widest_gap_fraction * settings.nodes_per_panel as f64
            / settings.ripple_nodes_per_unit_size_parameter
            * (settings.resonance_density_decay_rate_per_efold * max_depth).exp();
        let widest_step = |distribution: &SizeDistribution, settings| {
            let q = RadiusQuadrature::gauss_legendre(distribution, wavenumber, settings).unwrap();
            let near_peak =
                |r: f64| distribution.importance_depth_below_peak(r.ln(), wavenumber) <= 1.0;
            let steps = q
                .radii_m()
                .windows(2)
                .filter(|w| near_peak(w[0]) && near_peak(w[1]))
                .map(|w| wavenumber * (w[1] - w[0]))
                .collect::<Vec<_>>();
            assert!(steps.len() > 10);
            (q.len(), steps.into_iter().fold(0.0, f64::max))
        };
        for effective_radius_um in [2.0, 10.0, 40.0] {
            for distribution in [
                SizeDistribution::modified_gamma(effective_radius_um * MICROMETRE, 0.1).unwrap(),
                SizeDistribution::log_normal_from_effective_radius_and_variance(
                    effective_radius_um * MICROMETRE,
                    0.1,
                )
                .unwrap(),
            ] {
                let (nodes, step) = widest_step(&distribution, &settings);
                let (nodes_before, step_before) = widest_step(&distribution, &without_ripple);
                eprintln!(
                    "r_eff {effective_radius_um} um: {nodes} nodes, widest step in x near the peak {step:.4} (bound {step_bound:.4}); without the ripple density {nodes_before} nodes, {step_before:.3}"
                );
                assert!(step <= step_bound, "{step} > {step_bound}");
                assert!(step_before > 0.1, "{step_before}");
            }
        }
    }

    /// Issue 17: the node count is bounded before anything is allocated. A
    /// panel narrower than the spacing of doubles in ln r (which once made
    /// the rule allocate without end) stops the counting pass at the bound;
    /// a narrow population over 10,000 wavelengths (separate panels for
    /// each) is refused for its weights; each error names the counts and
    /// the limits.
    #[test]
    fn node_counts_are_bounded_before_allocating() {
        let d = SizeDistribution::log_normal(0.5 * MICROMETRE, 1.5).unwrap();
        let never_advancing = RadiusQuadratureSettings {
            max_panel_width_ln_radius: 1e-300,
            ..RadiusQuadratureSettings::smooth()
        };
        for error in [
            RadiusQuadrature::gauss_legendre(&d, 1e7, &never_advancing).unwrap_err(),
            SharedSizeParameterQuadrature::gauss_legendre(&d, &[1e7], &never_advancing)
                .unwrap_err(),
        ] {
            assert!(
                matches!(error, SizeDistributionError::TooManyQuadratureNodes { node_count, .. } if node_count > MAX_RADIUS_QUADRATURE_NODES),
                "{error}"
            );
            let message = error.to_string();
            assert!(message.contains("1048576 nodes"), "{message}");
        }
        let narrow = SizeDistribution::log_normal(0.5 * MICROMETRE, 1.0001).unwrap();
        let wavenumbers: Vec<f64> = (0..10_000)
            .map(|i| 2.0 * std::f64::consts::PI / ((360.0 + 0.047 * i as f64) * 1e-9))
            .collect();
        let settings = RadiusQuadratureSettings::cross_sections();
        let error = SharedSizeParameterQuadrature::gauss_legendre(&narrow, &wavenumbers, &settings)
            .unwrap_err();
        let message = error.to_string();
        assert!(
            message.contains("10000 wavelength(s)") && message.contains("67108864"),
            "{message}"
        );
        // The same population at 21 wavelengths is fine, and so is one wavelength.
        let q =
            SharedSizeParameterQuadrature::gauss_legendre(&narrow, &wavenumbers[..21], &settings)
                .unwrap();
        assert!(q.len() * 21 <= MAX_SHARED_QUADRATURE_WEIGHTS);
        assert!(RadiusQuadrature::gauss_legendre(&narrow, wavenumbers[0], &settings).is_ok());
    }
}
