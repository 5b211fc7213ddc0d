//! The forward-peak term of delta-M: light that the scaled problem counts
//! as unscattered because it was scattered into a phase function's
//! truncated forward peak, and that then reaches the eye. Radiance in
//! W m^-2 sr^-1 nm^-1.
//!
//! # The model
//! Delta-M (`phase_fourier.rs`) writes each phase function as
//! p = (1 - f) p* + r: p* the smooth function of N = 2n Legendre terms the
//! solver uses, r the **peak** (moments r_l = f for l <= N, chi_l beyond,
//! so r / f is a normalised bump about as wide as the diffraction peak).
//! The scaled problem treats r as a delta function: the sun's beam and
//! the view ray are attenuated by T* (extinction beta_ext - f beta_sca)
//! instead of T. Single scattering ([`crate::transport::single_scattering`])
//! is exact, with p and T. What remains, along the view ray
//! (a point x at s, sun and view legs through x, X(s) = the peak
//! scattering optical depth sum_j f_j beta_sca,j of both legs), is light
//! scattered k >= 1 times in the peaks plus once more:
//!
//! ```text
//! L_fp(theta) = E sum_j beta_sca,j (1 - f_j) p*_j(theta) integral rho_j (T* T*_sun - T T_sun) ds
//!             + E integral (sum_j f_j beta_sca,j rho_j) T T_sun G(theta; X(s)) ds
//! G(theta; X) = sum_{k >= 2} X^(k-1) / k! rhat^(*k)(theta)
//!             = sum_l (2l + 1) / (4 pi) [(e^(X rhat_l) - 1 - X rhat_l) / X] P_l(cos theta)
//! ```
//!
//! The first line is one scattering by the smooth part p* after or
//! before any number of peak scatterings (the peaks taken as exactly
//! forward: p* has no structure on their scale). The second is light
//! scattered only in the peaks, k >= 2 times (k = 1 is single
//! scattering): the path with k peak scatterings, each of which may be
//! the one at x, weighs X^(k-1) / (k-1)! / k, and its direction is spread
//! by the k-fold convolution of the peak, rhat^(*k), whose Legendre moments
//! are rhat_l^k (rhat = the peaks' mixture normalised to 1, weighted by
//! each species' f beta_sca column). In the small-angle limit of a
//! homogeneous path the two lines with the scaled field give every
//! Legendre moment of the exact solution, e^(-tau) (e^(tau omega chi_l) - 1).
//!
//! Far from the sun the peak-only light is the peak's wide tail (what p
//! has there beyond p*: r's moments sum to f (p - (1 - f) p*) / f there),
//! and the two lines together are E sum_j beta_sca,j p_j(theta) integral
//! rho_j (T* T*_sun - T T_sun) ds: one scattering by the whole p after or
//! before the peak scatterings. That form is used from 30 degrees from
//! the sun on (passing to it linearly from 20 degrees), where the peaks'
//! k-fold spread has no light left; the tables of G stop there.
//!
//! The earlier term, E sum_j beta_sca,j p_j(theta) integral rho_j
//! (T* T*_sun - T T_sun) ds with theta kept out of a 4.3 degree cone
//! around the sun, counted a path with k peak scatterings k times and
//! gave it the peak's full sharpness: near a low sun (X of 1 to 5) Mars
//! dust was 9-29 % too bright 2-5 degrees from it in its orders >= 2 and
//! hazy Earth 8-25 % too dark 2 degrees from it (inside the cone).
//!
//! Near a low sun (the sun within 12 degrees of a view node's horizon)
//! both lines take the peaks' light arriving at x, T*_sun - T_sun, from
//! [`super::peak_beam`] instead: the last peak scattering before x at its
//! real angle in the spherical shell, so that light scattered a few
//! degrees down from higher, less attenuated air counts. The first line's
//! integrand becomes T* B + T_sun (T* - T), the peak-only light's is
//! scaled by (T_sun + B) / T*_sun (see there).
//!
//! With Stokes vectors the first line is polarised as single scattering
//! through theta ([`ForwardPeak::polarised_radiance`]: the peaks'
//! near-forward scatterings keep the state of polarisation) and the
//! peak-only light is taken as unpolarised.
//!
//! # Numerics
//! - rhat_l for l > N from the phase functions' moments integrated over
//!   0..60 degrees (4-point Gauss panels crowded toward the sun, at most
//!   pi / L wide), the integrand tapered by cos^2 over 30..60 degrees: the
//!   high moments are the peak's; the smooth rest contributes little there.
//!   The series stops where |rhat_l| < 1e-3 for every wavelength (at most
//!   L = [`MAX_DEGREE`]).
//! - G is tabulated per wavelength over theta in 0..30 degrees (nodes
//!   crowded toward the sun, theta = 30 (t / 95)^2) and over X (25 nodes,
//!   0..64) as e^(-X) G, read bilinearly (beyond 30 degrees the wide-angle
//!   form above). Along a view ray X(s) is replaced by its mean weighted by the
//!   integrand (near the sun, where G matters, both legs together are
//!   about the sun's slant path, so X hardly changes along the ray).
//! - (1 - f) p* is tabulated over theta (721 nodes, 0.25 degrees apart) for
//!   the species with a peak; the others take p (p* = p for them).

use std::f64::consts::PI;

use super::super::quadrature::{GAUSS_NODES, GAUSS_WEIGHTS};
use super::phase_fourier::TruncatedPhase;
use super::regimes::{PEAK_KERNEL_BLEND_START_RAD, PEAK_KERNEL_RADIUS_RAD};
use crate::atmosphere::phase_matrix::PhaseMatrix;
use crate::atmosphere::{AtmosphereOptics, DensityProfile};

/// The forward-peak integrals hold, after the species' rows, this many
/// rows per wavelength: Q = integral (sum_j f_j beta_sca,j rho_j) T T_sun ds
/// (m^-1 m = 1) and Q times the mean X.
pub(crate) const EXTRA_ROWS: usize = 2;

/// Highest Legendre degree of the peak's series.
const MAX_DEGREE: usize = 768;

/// The peak's moments are integrated up to this angle, rad (tapered
/// from half of it).
const MOMENT_WINDOW_RAD: f64 = 60.0 * PI / 180.0;

/// Nodes of G's angle axis.
const KERNEL_ANGLES: usize = 96;

/// Nodes of G's X axis.
const KERNEL_X: [f64; 25] = [
    0.0, 0.0625, 0.125, 0.25, 0.375, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0,
    10.0, 12.0, 16.0, 20.0, 24.0, 32.0, 48.0, 64.0,
];

/// Nodes of the (1 - f) p* tables, uniform in theta over 0..pi.
const TRUNCATED_ANGLES: usize = 721;

/// |rhat_l| below which the peak's series stops.
const SERIES_FLOOR: f64 = 1e-3;

/// The tables of the forward-peak term (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct ForwardPeak {
    wavelengths: usize,
    species: usize,
    /// [i * species + j]: the species' delta-M fraction f.
    fractions: Vec<f64>,
    /// Per species, whether any wavelength has a peak.
    peaked: Vec<bool>,
    /// (1 - f) p*(theta) of the peaked species, [(j * TRUNCATED_ANGLES + t) * w + i].
    truncated: Vec<f64>,
    /// e^(-X) G(theta; X), [(x * KERNEL_ANGLES + t) * w + i], sr^-1.
    kernel: Vec<f64>,
}

impl ForwardPeak {
    /// The tables for `optics` with delta-M phases `phases` ([i * species + j])
    /// of `degrees` terms and the species' density profiles.
    pub(crate) fn new(
        optics: &AtmosphereOptics,
        phases: &[TruncatedPhase],
        degrees: usize,
        profiles: &[DensityProfile],
        atmosphere_height_m: f64,
    ) -> ForwardPeak {
        let w = optics.grid.len();
        let s = optics.species.len();
        let fractions: Vec<f64> = phases.iter().map(|p| p.forward_fraction).collect();
        let peaked: Vec<bool> = (0..s)
            .map(|j| (0..w).any(|i| fractions[i * s + j] > 0.0))
            .collect();
        let mut table = ForwardPeak {
            wavelengths: w,
            species: s,
            fractions,
            peaked,
            truncated: vec![0.0; s * TRUNCATED_ANGLES * w],
            kernel: Vec::new(),
        };
        if !table.peaked.iter().any(|p| *p) {
            return table;
        }
        // (1 - f) p*: the delta-M coefficients times (1 - f).
        let mut legendre = vec![0.0; degrees];
        for t in 0..TRUNCATED_ANGLES {
            let theta = PI * t as f64 / (TRUNCATED_ANGLES - 1) as f64;
            legendre_into(theta.cos(), &mut legendre);
            for j in (0..s).filter(|j| table.peaked[*j]) {
                for i in 0..w {
                    let phase = &phases[i * s + j];
                    table.truncated[(j * TRUNCATED_ANGLES + t) * w + i] =
                        (1.0 - phase.forward_fraction) * phase.eval_with_legendre(&legendre);
                }
            }
        }
        // The peaks' mixture: weights f_j beta_sca,j times the species'
        // vertical column (relative density integrated over altitude).
        let columns: Vec<f64> = profiles
            .iter()
            .map(|p| vertical_column_m(p, atmosphere_height_m))
            .collect();
        let mut high = vec![0.0; w * (MAX_DEGREE + 1)];
        let mut mixed = vec![0.0; w * (MAX_DEGREE + 1)];
        let mut norm = vec![0.0; w];
        for j in (0..s).filter(|j| table.peaked[*j]) {
            let species = &optics.species[j];
            compute_windowed_moments(&species.phase_function, w, MAX_DEGREE, &mut high);
            for i in 0..w {
                let f = table.fractions[i * s + j];
                if f <= 0.0 {
                    continue;
                }
                let weight = species.scattering_per_m[i] * columns[j];
                norm[i] += f * weight;
                for l in degrees + 1..=MAX_DEGREE {
                    mixed[i * (MAX_DEGREE + 1) + l] += weight * high[i * (MAX_DEGREE + 1) + l];
                }
            }
        }
        // rhat_l: 1 up to N (r_l = f there), the mixture's chi_l / f beyond.
        let mut highest = degrees;
        for i in 0..w {
            let row = &mut mixed[i * (MAX_DEGREE + 1)..(i + 1) * (MAX_DEGREE + 1)];
            for (l, value) in row.iter_mut().enumerate() {
                *value = if l <= degrees {
                    1.0
                } else if norm[i] > 0.0 {
                    (*value / norm[i]).clamp(-1.0, 1.0)
                } else {
                    0.0
                };
            }
            if norm[i] > 0.0 {
                let last = (0..=MAX_DEGREE)
                    .rev()
                    .find(|l| row[*l].abs() >= SERIES_FLOOR)
                    .unwrap_or(degrees);
                highest = highest.max(last);
            }
        }
        // P_l(cos theta_t) for the kernel's angles.
        let count = highest + 1;
        let mut polynomials = vec![0.0; KERNEL_ANGLES * count];
        for t in 0..KERNEL_ANGLES {
            legendre_into(
                kernel_angle(t).cos(),
                &mut polynomials[t * count..(t + 1) * count],
            );
        }
        table.kernel = vec![0.0; KERNEL_X.len() * KERNEL_ANGLES * w];
        let mut series = vec![0.0; count];
        for i in (0..w).filter(|i| norm[*i] > 0.0) {
            let rhat = &mixed[i * (MAX_DEGREE + 1)..][..count];
            for (x, &big_x) in KERNEL_X.iter().enumerate().skip(1) {
                for (l, c) in series.iter_mut().enumerate() {
                    *c = (2 * l + 1) as f64 / (4.0 * PI) * scaled_series_term(rhat[l], big_x);
                }
                for t in 0..KERNEL_ANGLES {
                    let p = &polynomials[t * count..(t + 1) * count];
                    let value = dot(&series, p);
                    table.kernel[(x * KERNEL_ANGLES + t) * w + i] = value;
                }
            }
        }
        table
    }

    /// The peak-only light's table as the engine tables' march reads it:
    /// its X nodes, its angle node count (theta = R (t / (n - 1))^2, R =
    /// [`PEAK_KERNEL_RADIUS_RAD`]), the angle from which the wide-angle form
    /// takes over ([`PEAK_KERNEL_BLEND_START_RAD`]), and e^(-X) G
    /// [(x * angles + t) * wavelengths + i], sr^-1 (empty: no peak).
    pub(crate) fn exported_kernel(&self) -> (Vec<f64>, usize, (f64, f64), Vec<f64>) {
        (
            KERNEL_X.to_vec(),
            KERNEL_ANGLES,
            (PEAK_KERNEL_BLEND_START_RAD, PEAK_KERNEL_RADIUS_RAD),
            self.kernel.clone(),
        )
    }

    /// Whether any species has a peak (otherwise the term is zero).
    pub(crate) fn any(&self) -> bool {
        self.peaked.iter().any(|p| *p)
    }

    /// L_fp toward a view at cos(theta) = `cos_theta` from the sun, into
    /// `out`, from the view ray's integrals (`integrals`: species rows of
    /// integral rho_j (T* T*_sun - T T_sun) ds, then Q and Q X-bar, see
    /// [`EXTRA_ROWS`]); `phase` is work space of one value per wavelength.
    pub(crate) fn radiance(
        &self,
        optics: &AtmosphereOptics,
        cos_theta: f64,
        integrals: &[f64],
        phase: &mut [f64],
        out: &mut [f64],
    ) {
        let w = self.wavelengths;
        out.fill(0.0);
        let theta = cos_theta.clamp(-1.0, 1.0).acos();
        let wide = wide_angle_share(theta);
        for (j, species) in optics.species.iter().enumerate() {
            let row = &integrals[j * w..(j + 1) * w];
            if row.iter().all(|v| *v == 0.0) {
                continue;
            }
            self.smooth_phase_into(j, &species.phase_function, cos_theta, phase);
            for i in 0..w {
                out[i] += optics.solar_irradiance_w_m2_nm[i]
                    * species.scattering_per_m[i]
                    * phase[i]
                    * row[i];
            }
        }
        if self.kernel.is_empty() || theta >= PEAK_KERNEL_RADIUS_RAD {
            return;
        }
        let s = self.species;
        let position = (theta / PEAK_KERNEL_RADIUS_RAD).sqrt() * (KERNEL_ANGLES - 1) as f64;
        let t = (position as usize).min(KERNEL_ANGLES - 2);
        let ft = position - t as f64;
        let (q, qx) = (
            &integrals[s * w..(s + 1) * w],
            &integrals[(s + 1) * w..(s + 2) * w],
        );
        for i in 0..w {
            if q[i] <= 0.0 {
                continue;
            }
            let x_mean = (qx[i] / q[i]).clamp(0.0, KERNEL_X[KERNEL_X.len() - 1]);
            let upper = KERNEL_X
                .partition_point(|x| *x <= x_mean)
                .clamp(1, KERNEL_X.len() - 1);
            let fx = (x_mean - KERNEL_X[upper - 1]) / (KERNEL_X[upper] - KERNEL_X[upper - 1]);
            let at = |x: usize, t: usize| self.kernel[(x * KERNEL_ANGLES + t) * w + i];
            let scaled = (1.0 - fx) * ((1.0 - ft) * at(upper - 1, t) + ft * at(upper - 1, t + 1))
                + fx * ((1.0 - ft) * at(upper, t) + ft * at(upper, t + 1));
            out[i] +=
                (1.0 - wide) * optics.solar_irradiance_w_m2_nm[i] * q[i] * scaled * x_mean.exp();
        }
    }

    /// The scattering-plane Q (W m^-2 sr^-1 nm^-1, the sense of the phase
    /// matrix's b1: Q = b1 for unpolarised light) of the forward-peak
    /// term's first line toward a view at cos(theta) = `cos_theta` from
    /// the sun, into `out`, from the same integrals as
    /// [`ForwardPeak::radiance`]; `phase` and `matrices` are work space of
    /// one value per wavelength. That light was scattered once through
    /// theta by a smooth phase function and otherwise only in the peaks,
    /// near-forward scatterings that keep its state of polarisation
    /// (a1 = a2 = a3, b1 = 0 there): so it is polarised as single
    /// scattering through theta is, Q / I = b1 / a1 of each species. The
    /// light scattered only in the peaks (k >= 2, within 30 degrees of the
    /// sun) is taken as unpolarised: each of its scatterings turns it by a
    /// few degrees, where |b1| / a1 is small (mars-dust's dust: below
    /// 0.002 within 3 degrees of forward, 0.004 within 5).
    pub(crate) fn polarised_radiance(
        &self,
        optics: &AtmosphereOptics,
        cos_theta: f64,
        integrals: &[f64],
        (phase, matrices): (&mut [f64], &mut [PhaseMatrix]),
        out: &mut [f64],
    ) {
        let w = self.wavelengths;
        out.fill(0.0);
        for (j, species) in optics.species.iter().enumerate() {
            let row = &integrals[j * w..(j + 1) * w];
            if row.iter().all(|v| *v == 0.0) {
                continue;
            }
            self.smooth_phase_into(j, &species.phase_function, cos_theta, phase);
            species
                .phase_function
                .phase_matrix_into(cos_theta, matrices);
            for i in 0..w {
                let m = &matrices[i];
                if m.a1 > 0.0 {
                    out[i] += optics.solar_irradiance_w_m2_nm[i]
                        * species.scattering_per_m[i]
                        * phase[i]
                        * (m.b1 / m.a1)
                        * row[i];
                }
            }
        }
    }

    /// The phase function of the first line of L_fp for species `j`
    /// (`function` its phase function) at cos(theta) = `cos_theta`, into
    /// `phase`, sr^-1: (1 - f) p* near the sun, passing to p from
    /// [`PEAK_KERNEL_BLEND_START_RAD`] to [`PEAK_KERNEL_RADIUS_RAD`] (see the module docs),
    /// p itself at wavelengths where the species has no peak.
    pub(crate) fn smooth_phase_into(
        &self,
        j: usize,
        function: &crate::atmosphere::PhaseFunction,
        cos_theta: f64,
        phase: &mut [f64],
    ) {
        let (w, s) = (self.wavelengths, self.species);
        function.eval_into(cos_theta, phase);
        let theta = cos_theta.clamp(-1.0, 1.0).acos();
        let wide = wide_angle_share(theta);
        if !self.peaked[j] || wide >= 1.0 {
            return;
        }
        let position = theta / PI * (TRUNCATED_ANGLES - 1) as f64;
        let t = (position as usize).min(TRUNCATED_ANGLES - 2);
        let ft = position - t as f64;
        let low = &self.truncated[(j * TRUNCATED_ANGLES + t) * w..][..w];
        let high = &self.truncated[(j * TRUNCATED_ANGLES + t + 1) * w..][..w];
        for i in (0..w).filter(|i| self.fractions[i * s + j] > 0.0) {
            let truncated = (1.0 - ft) * low[i] + ft * high[i];
            phase[i] = (1.0 - wide) * truncated + wide * phase[i];
        }
    }
}

/// How much of the forward-peak term takes its wide-angle form at
/// `theta` rad from the sun: 0 up to [`PEAK_KERNEL_BLEND_START_RAD`], 1 from
/// [`PEAK_KERNEL_RADIUS_RAD`] on, linear between.
fn wide_angle_share(theta: f64) -> f64 {
    ((theta - PEAK_KERNEL_BLEND_START_RAD) / (PEAK_KERNEL_RADIUS_RAD - PEAK_KERNEL_BLEND_START_RAD))
        .clamp(0.0, 1.0)
}

/// The angle of G's node t, rad: crowded toward the sun.
fn kernel_angle(t: usize) -> f64 {
    let u = t as f64 / (KERNEL_ANGLES - 1) as f64;
    PEAK_KERNEL_RADIUS_RAD * u * u
}

/// e^(-X) (e^(X r) - 1 - X r) / X, for X > 0 (its series for small X r).
fn scaled_series_term(r: f64, x: f64) -> f64 {
    let xr = x * r;
    let bracket = if xr.abs() < 1e-4 {
        xr * xr * (0.5 + xr / 6.0)
    } else {
        xr.exp_m1() - xr
    };
    (-x).exp() * bracket / x
}

/// sum_l a_l b_l, in four partial sums (one chain of additions over
/// hundreds of terms waited on each addition's latency).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let (a4, b4) = (a.chunks_exact(4), b[..a.len()].chunks_exact(4));
    let rest: f64 = a4
        .remainder()
        .iter()
        .zip(b4.remainder())
        .map(|(x, y)| x * y)
        .sum();
    let mut sums = [0.0; 4];
    for (x, y) in a4.zip(b4) {
        for k in 0..4 {
            sums[k] += x[k] * y[k];
        }
    }
    (sums[0] + sums[1]) + (sums[2] + sums[3]) + rest
}

/// P_0..P_{len-1}(mu) into `out`.
pub(super) fn legendre_into(mu: f64, out: &mut [f64]) {
    if out.is_empty() {
        return;
    }
    out[0] = 1.0;
    if out.len() > 1 {
        out[1] = mu;
    }
    for l in 2..out.len() {
        let (a, b) = ((2 * l - 1) as f64 / l as f64, (l - 1) as f64 / l as f64);
        out[l] = a * mu * out[l - 1] - b * out[l - 2];
    }
}

/// P_0..P_{len-1} at each of the `K` cosines `mu` into `out[l][k]`, by
/// Bonnet's recurrence P_l = ((2l - 1) mu P_{l-1} - (l - 1) P_{l-2}) / l
/// with its two ratios taken out of the dependency chain (a chain of
/// divisions was a third of a retrieval's time) and `K` chains run side
/// by side.
fn legendre_into_many<const K: usize>(mu: [f64; K], out: &mut [[f64; K]]) {
    if out.is_empty() {
        return;
    }
    out[0] = [1.0; K];
    if out.len() > 1 {
        out[1] = mu;
    }
    for l in 2..out.len() {
        let (a, b) = ((2 * l - 1) as f64 / l as f64, (l - 1) as f64 / l as f64);
        let (previous, before) = (out[l - 1], out[l - 2]);
        out[l] = std::array::from_fn(|k| a * mu[k] * previous[k] - b * before[k]);
    }
}

/// The relative density integrated from the ground to the top, m
/// (midpoint rule, 10 m steps in the lowest 2 km, 100 m above).
pub(super) fn vertical_column_m(profile: &DensityProfile, height_m: f64) -> f64 {
    let mut column = 0.0;
    let mut z = 0.0;
    while z < height_m {
        let step: f64 = if z < 2000.0 { 10.0 } else { 100.0 };
        let step = step.min(height_m - z);
        column += step * profile.relative_density(z + 0.5 * step);
        z += step;
    }
    column
}

/// Legendre moments chi_0..=`highest` of `phase` (normalised by its full
/// integral) over the forward window only (see the module docs), into
/// `out[i * (highest + 1) + l]`: for the high degrees, where only the peak
/// contributes.
fn compute_windowed_moments(
    phase: &crate::atmosphere::PhaseFunction,
    wavelengths: usize,
    highest: usize,
    out: &mut [f64],
) {
    let count = highest + 1;
    out[..wavelengths * count].fill(0.0);
    // Panels with edges window (k / n)^2: at most 2 window / n wide, which
    // is pi / highest or less (half a period of P_highest per 4-point panel).
    let panels = ((2.0 * MOMENT_WINDOW_RAD * highest as f64 / PI).ceil() as usize).max(64);
    let mut values = vec![0.0; wavelengths];
    let mut legendre = vec![[0.0; GAUSS_NODES.len()]; count];
    for panel in 0..panels {
        let edge = |k: usize| MOMENT_WINDOW_RAD * (k as f64 / panels as f64).powi(2);
        let (a, b) = (edge(panel), edge(panel + 1));
        let (centre, half) = (0.5 * (a + b), 0.5 * (b - a));
        let theta: [f64; GAUSS_NODES.len()] =
            std::array::from_fn(|k| centre + half * GAUSS_NODES[k]);
        legendre_into_many(theta.map(f64::cos), &mut legendre);
        for (k, theta) in theta.into_iter().enumerate() {
            let taper = if theta <= 0.5 * MOMENT_WINDOW_RAD {
                1.0
            } else {
                let u = (theta - 0.5 * MOMENT_WINDOW_RAD) / (0.5 * MOMENT_WINDOW_RAD);
                (0.5 * PI * u).cos().powi(2)
            };
            let weight = 2.0 * PI * half * GAUSS_WEIGHTS[k] * theta.sin() * taper;
            phase.eval_into(theta.cos(), &mut values);
            for (i, value) in values.iter().enumerate() {
                let row = &mut out[i * count..(i + 1) * count];
                let scale = weight * value;
                for (moment, p_l) in row.iter_mut().zip(&legendre) {
                    *moment += scale * p_l[k];
                }
            }
        }
    }
}
