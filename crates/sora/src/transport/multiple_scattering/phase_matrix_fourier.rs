//! Phase matrices in the form the polarised discrete-ordinate solver
//! needs: the azimuthal Fourier components of the phase matrix between two
//! directions, with both Stokes vectors referred to their meridian planes.
//!
//! Light seen in the look direction w' (travelling along -w') and
//! scattered into the look direction w changes its Stokes vector, each
//! referred to its meridian plane (`transport/stokes.rs`), by
//!
//! ```text
//! Z(w <- w') = L(eta_out) F(Theta) L(eta_in),     cos Theta = w . w'
//! ```
//!
//! F the phase matrix in the scattering plane (`atmosphere/phase_matrix.rs`),
//! L(eta_in) turning the incoming meridian frame into the scattering plane
//! and L(eta_out) the scattering plane into the outgoing meridian frame:
//! the rotations the path tracer makes, computed by the same functions.
//! Z depends on the azimuths only through Delta = phi - phi'. With the sun
//! in the plane phi = 0, the field is mirror-symmetric about it: I and Q
//! are even in phi, U and V odd, and
//!
//! ```text
//! I(phi) = sum_m I_m cos(m phi),  Q likewise;  U(phi) = sum_m U_m sin(m phi),  V likewise.
//! ```
//!
//! Z's (I, Q) x (I, Q) and (U, V) x (U, V) blocks are even in Delta, the
//! cross blocks odd, so the scattering integral over the incoming
//! azimuth, integral Z(phi - phi') S(phi') dphi', maps the harmonics
//! (I_m, Q_m, U_m, V_m) of the incoming direction to those of the outgoing
//! one through
//!
//! ```text
//! Z^m_ic(mu, mu') = integral_0^{2 pi} Z_ic(mu, mu', Delta) g_ic(m Delta) dDelta,
//! g_ic = cos   (i, c both in {I, Q} or both in {U, V})
//!      = -sin  (i in {I, Q}, c in {U, V})
//!      = +sin  (i in {U, V}, c in {I, Q})
//! ```
//!
//! (cos(m (phi - Delta)) = cos m phi cos m Delta + sin m phi sin m Delta and
//! so on; the odd parts integrate to zero). For the element I <- I this is
//! 2 pi p_m(mu, mu') of the scalar solver (`phase_fourier.rs`). The sun's
//! unpolarised beam from (mu_s, phi = 0) scatters into harmonic m of
//! component i as
//!
//! ```text
//! B^m_i(mu) = 1 / (pi (1 + delta_m0)) integral_0^{2 pi} Z_i1(mu, mu_s, Delta) {cos, sin}(m Delta) dDelta
//! ```
//!
//! ((2 - delta_m0) p_m(mu, mu_s) for I, as in the scalar solver).
//!
//! # Why a quadrature in azimuth and not generalised spherical functions
//! Vector discrete-ordinate codes (Siewert 2000; de Haan, Bosma & Hovenier
//! 1987; VLIDORT) expand F in generalised spherical functions and build
//! Z^m from an addition theorem. For a phase matrix whose elements expand
//! to degree L (as a truncated one does, L < the streams), every element
//! of Z is a trigonometric polynomial of degree L in Delta, so the
//! integrals above are exact with the (2L + 2)-point trapezoidal rule;
//! this module uses 4N + 1 points for N streams (odd, so that the exact
//! backward direction Delta = pi, where the scattering plane is undefined,
//! is never a node). That needs nothing but F(Theta) and the exact
//! rotations: no generalised spherical functions to derive and test, and
//! the same rotation code as the path tracer the solver is tested
//! against. The mirror symmetry about the sun's vertical halves the
//! nodes (2N + 1 of them are computed), and the mirror symmetry through
//! the horizontal plane, Z(-mu, -mu') = D Z(mu, mu') D with D =
//! diag(1, 1, -1, -1), the pairs of streams; the cost, streams^2 (2N + 1)
//! / 2 rotations per species for all wavelengths and the transforms per
//! wavelength (only harmonics 0..3 of Rayleigh's, whose others vanish), is
//! small beside a solve.

use std::f64::consts::PI;
use std::sync::Arc;

use crate::atmosphere::phase_matrix::PhaseMatrix;
use crate::geometry::{Vector3, direction_from_elevation_azimuth};
use crate::transport::stokes::{
    IDENTITY, Mueller, meridian_reference, multiply_rotated, rotation_cos_sin_2eta,
    scattering_plane,
};

/// Stokes components carried: I, Q, U, V.
pub(crate) const COMPONENTS: usize = 4;

/// Whether component `i` (0..4) is even in azimuth (I, Q: cosine series)
/// or odd (U, V: sine series).
pub(crate) fn is_even_component(i: usize) -> bool {
    i < 2
}

/// The Fourier components of one species' phase matrix at one
/// wavelength, from a set of input directions (the streams, with their
/// quadrature weights) and the sun into a set of output directions (the
/// streams themselves, or view directions).
#[derive(Debug, Clone)]
pub struct PhaseMatrixHarmonics {
    harmonics: usize,
    /// The harmonics kept, 0..stored; those from `stored` on are zero (a
    /// phase matrix whose harmonics end there, Rayleigh's at m = 2) and
    /// not stored.
    stored: usize,
    outputs: usize,
    inputs: usize,
    /// w_b Z^m_ic(mu_a, mu_b), by columns (c, b) of each harmonic's
    /// (4 outputs) x (4 inputs) matrix:
    /// [((m * 4 + c) * inputs + b) * 4 * outputs + i * outputs + a];
    /// shared by the harmonics that differ in their sun only
    /// ([`PhaseMatrixHarmonics::with_sun_of`]).
    scattering: Arc<Vec<f64>>,
    /// B^m_i(mu_a): [(m * 4 + i) * outputs + a].
    sun: Vec<f64>,
}

impl PhaseMatrixHarmonics {
    /// Every number of these harmonics, bits (the tests' bit equality).
    #[cfg(test)]
    pub(crate) fn bits(&self) -> Vec<u64> {
        [self.harmonics, self.stored, self.outputs, self.inputs]
            .iter()
            .map(|n| *n as u64)
            .chain(self.scattering.iter().chain(&self.sun).map(|v| v.to_bits()))
            .collect()
    }

    /// Harmonics 0..`harmonics` at each of `wavelengths` wavelengths of
    /// `phase` (which writes the phase matrix in the scattering plane at a
    /// scattering-angle cosine for every wavelength, sr^-1) from the look
    /// directions of zenith cosines `input_cosines` (weights
    /// `input_weights`, each hemisphere's summing to 1), and from the sun
    /// at zenith cosine `sun_cosine` if given (zeros if not), into those of
    /// `output_cosines`. The rotations are computed once for all
    /// wavelengths.
    #[cfg(test)]
    pub(crate) fn compute(
        phase: &dyn Fn(f64, &mut [PhaseMatrix]),
        wavelengths: usize,
        output_cosines: &[f64],
        inputs: (&[f64], &[f64]),
        sun_cosine: Option<f64>,
        harmonics: usize,
    ) -> Vec<PhaseMatrixHarmonics> {
        PhaseMatrixHarmonics::compute_nonzero(
            phase,
            wavelengths,
            output_cosines,
            inputs,
            sun_cosine,
            (harmonics, harmonics),
        )
    }

    /// [`PhaseMatrixHarmonics::compute`] for a phase matrix whose
    /// harmonics from `nonzero` on vanish (Rayleigh's, from 3: its elements
    /// are quadratic in the scattering angle's cosine, so Z's are
    /// trigonometric polynomials of degree 2 in the azimuth): harmonics
    /// 0..`harmonics`, only 0..`nonzero` computed and stored, the same
    /// numbers as [`PhaseMatrixHarmonics::compute`]'s to the bit (the same
    /// azimuth rule and sums); the others are zero where
    /// [`PhaseMatrixHarmonics::compute`] gives rounding (below 1e-14 of
    /// the largest element).
    pub(crate) fn compute_nonzero(
        phase: &dyn Fn(f64, &mut [PhaseMatrix]),
        wavelengths: usize,
        output_cosines: &[f64],
        (input_cosines, input_weights): (&[f64], &[f64]),
        sun_cosine: Option<f64>,
        (harmonics, nonzero): (usize, usize),
    ) -> Vec<PhaseMatrixHarmonics> {
        const ELEMENTS: usize = COMPONENTS * COMPONENTS;
        let (outputs, inputs) = (output_cosines.len(), input_cosines.len());
        let AzimuthRule { nodes, step, trig } = AzimuthRule::new(harmonics);
        let stored = nonzero.min(harmonics);
        let mut all =
            PhaseMatrixHarmonics::zeros(wavelengths, (harmonics, stored), outputs, inputs);
        let mut matrices = vec![PhaseMatrix::default(); wavelengths];
        let inputs_and_sun = inputs_and_sun((input_cosines, input_weights), sun_cosine);
        // The mirror symmetry about the sun's vertical, Z(-Delta) =
        // D Z(Delta) D with D = diag(1, 1, -1, -1): the even elements are
        // even in Delta and the odd ones odd, so the nodes k and nodes - k
        // add the same to the transform each element keeps. Only the nodes
        // 0..=half are computed, the others counted twice.
        let half = (nodes - 1) / 2;
        let nodes = half + 1;
        // The mirror symmetry through the horizontal plane, Z(-mu, -mu',
        // Delta) = D Z(mu, mu', Delta) D (the mirror keeps I and Q and
        // changes the sign of U and V): of two pairs of directions that
        // are each other's image (streams are symmetric about the
        // horizon), the second takes the first's harmonics.
        let mirrors = Mirrors::new(output_cosines, (input_cosines, input_weights));
        let node_weight = |k: usize| if k == 0 { 1.0 } else { 2.0 };
        // Z at every node for one pair of directions, [i * nodes + k][e]
        // (e = row * 4 + column), and its transforms, [m][e]: whole
        // 16-element rows, so the transforms vectorise. Each element keeps
        // one transform only (the cosine transform of the even elements,
        // the sine transform of the odd ones, see the module docs), so each
        // node's factor is the node weight times cos(m Delta_k) or
        // sin(m Delta_k) by element, [m * nodes + k][e]. Each harmonic's
        // sum over the nodes runs in k's order in one accumulator.
        let mut z_nodes = vec![[0.0; ELEMENTS]; wavelengths * nodes];
        let mut transforms = vec![[0.0; ELEMENTS]; stored];
        let factors: Vec<[f64; ELEMENTS]> = (0..stored)
            .flat_map(|m| (0..nodes).map(move |k| (k, m)))
            .map(|(k, m)| {
                let (cos_m, sin_m) = trig[k * harmonics + m];
                let (cos_m, sin_m) = (node_weight(k) * cos_m, node_weight(k) * sin_m);
                std::array::from_fn(|e| if is_even_element(e) { cos_m } else { sin_m })
            })
            .collect();
        for (a, &mu_out) in output_cosines.iter().enumerate() {
            let outs: Vec<LookDirection> = (0..nodes)
                .map(|k| LookDirection::new(mu_out, k as f64 * step))
                .collect();
            for (b, &(mu_in, weight)) in inputs_and_sun.iter().enumerate() {
                // The mirror image through the horizontal plane of a pair
                // already computed: its harmonics with D's signs.
                if let Some((a_mirror, b_mirror)) = mirrors.pair(a, b)
                    && (a_mirror, b_mirror) < (a, b)
                {
                    for h in all.iter_mut() {
                        h.store_mirror((a, b), (a_mirror, b_mirror));
                    }
                    continue;
                }
                let incoming = LookDirection::new(mu_in, 0.0);
                for (k, out) in outs.iter().enumerate() {
                    let geometry = ScatteringGeometry::new(*out, incoming);
                    phase(geometry.cos_theta, &mut matrices);
                    for (i, f) in matrices.iter().enumerate() {
                        let z = geometry.rotate(f);
                        let target = &mut z_nodes[i * nodes + k];
                        for (t, v) in target.iter_mut().zip(z.iter().flatten()) {
                            *t = *v;
                        }
                    }
                }
                for (i, h) in all.iter_mut().enumerate() {
                    let values = &z_nodes[i * nodes..(i + 1) * nodes];
                    for (transform, node_factors) in
                        transforms.iter_mut().zip(factors.chunks_exact(nodes))
                    {
                        let mut sum = [0.0; ELEMENTS];
                        for (z, f) in values.iter().zip(node_factors) {
                            for e in 0..ELEMENTS {
                                sum[e] += z[e] * f[e];
                            }
                        }
                        *transform = sum;
                    }
                    h.store_transforms(&transforms, (a, b), weight, step);
                }
            }
        }
        all
    }

    /// Stores the transforms over the azimuth nodes of the rotated matrix
    /// from input (or sun) `b` into output `a`, [m][e] (the cosine
    /// transform of the even elements, the sine transform of the odd ones:
    /// [`is_even_element`]), as this wavelength's harmonics: the scattering
    /// blocks with the input's quadrature weight `weight`, or (None) the
    /// sun's.
    fn store_transforms(
        &mut self,
        transforms: &[[f64; COMPONENTS * COMPONENTS]],
        (a, b): (usize, usize),
        weight: Option<f64>,
        step: f64,
    ) {
        let (stored, inputs, outputs) = (self.stored, self.inputs, self.outputs);
        let block = COMPONENTS * outputs;
        let scattering = Arc::make_mut(&mut self.scattering);
        for (m, transform) in transforms[..stored].iter().enumerate() {
            for row in 0..COMPONENTS {
                match weight {
                    Some(weight) => {
                        for column in 0..COMPONENTS {
                            let e = row * COMPONENTS + column;
                            let projected =
                                match (is_even_component(row), is_even_component(column)) {
                                    (true, true) | (false, false) | (false, true) => transform[e],
                                    (true, false) => -transform[e],
                                };
                            scattering[((m * COMPONENTS + column) * inputs + b) * block
                                + row * outputs
                                + a] = weight * step * projected;
                        }
                    }
                    None => {
                        let projected = transform[row * COMPONENTS];
                        let norm = if m == 0 { 2.0 * PI } else { PI };
                        self.sun[(m * COMPONENTS + row) * outputs + a] = step / norm * projected;
                    }
                }
            }
        }
    }

    /// Stores as the harmonics from input `b` into output `a` those from
    /// their mirror images `b_mirror` into `a_mirror` (already stored):
    /// D Z^m D, the (I, Q) x (U, V) and (U, V) x (I, Q) blocks negated.
    fn store_mirror(&mut self, (a, b): (usize, usize), (a_mirror, b_mirror): (usize, usize)) {
        let (inputs, outputs) = (self.inputs, self.outputs);
        let block = COMPONENTS * outputs;
        let scattering = Arc::make_mut(&mut self.scattering);
        for m in 0..self.stored {
            for column in 0..COMPONENTS {
                for row in 0..COMPONENTS {
                    let at = |a: usize, b: usize| {
                        ((m * COMPONENTS + column) * inputs + b) * block + row * outputs + a
                    };
                    let value = scattering[at(a_mirror, b_mirror)];
                    scattering[at(a, b)] = if is_even_component(row) == is_even_component(column) {
                        value
                    } else {
                        -value
                    };
                }
            }
        }
    }

    /// [`PhaseMatrixHarmonics::compute`] element by element, node by node:
    /// the obvious sums the fast one is tested against.
    #[cfg(test)]
    pub(crate) fn compute_reference(
        phase: &dyn Fn(f64, &mut [PhaseMatrix]),
        wavelengths: usize,
        output_cosines: &[f64],
        (input_cosines, input_weights): (&[f64], &[f64]),
        sun_cosine: Option<f64>,
        harmonics: usize,
    ) -> Vec<PhaseMatrixHarmonics> {
        let (outputs, inputs) = (output_cosines.len(), input_cosines.len());
        let AzimuthRule { nodes, step, trig } = AzimuthRule::new(harmonics);
        let block = COMPONENTS * outputs;
        let mut all =
            PhaseMatrixHarmonics::zeros(wavelengths, (harmonics, harmonics), outputs, inputs);
        let mut matrices = vec![PhaseMatrix::default(); wavelengths];
        let inputs_and_sun = inputs_and_sun((input_cosines, input_weights), sun_cosine);
        for (a, &mu_out) in output_cosines.iter().enumerate() {
            for k in 0..nodes {
                let out = LookDirection::new(mu_out, k as f64 * step);
                for (b, &(mu_in, weight)) in inputs_and_sun.iter().enumerate() {
                    let geometry = ScatteringGeometry::new(out, LookDirection::new(mu_in, 0.0));
                    phase(geometry.cos_theta, &mut matrices);
                    for (h, f) in all.iter_mut().zip(&matrices) {
                        let z = geometry.rotate(f);
                        for m in 0..harmonics {
                            let (cos_m, sin_m) = trig[k * harmonics + m];
                            for (i, row) in z.iter().enumerate() {
                                match weight {
                                    Some(weight) => {
                                        let column = |c: usize| {
                                            ((m * COMPONENTS + c) * inputs + b) * block
                                                + i * outputs
                                                + a
                                        };
                                        for (c, value) in row.iter().enumerate() {
                                            let g = match (
                                                is_even_component(i),
                                                is_even_component(c),
                                            ) {
                                                (true, true) | (false, false) => cos_m,
                                                (true, false) => -sin_m,
                                                (false, true) => sin_m,
                                            };
                                            Arc::make_mut(&mut h.scattering)[column(c)] +=
                                                weight * step * value * g;
                                        }
                                    }
                                    None => {
                                        let g = if is_even_component(i) { cos_m } else { sin_m };
                                        let norm = if m == 0 { 2.0 * PI } else { PI };
                                        h.sun[(m * COMPONENTS + i) * outputs + a] +=
                                            step / norm * row[0] * g;
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
        all
    }

    /// Zero harmonics 0..`harmonics` at each of `wavelengths` wavelengths,
    /// of which 0..`stored` are stored.
    pub(crate) fn zeros(
        wavelengths: usize,
        (harmonics, stored): (usize, usize),
        outputs: usize,
        inputs: usize,
    ) -> Vec<PhaseMatrixHarmonics> {
        let block = COMPONENTS * outputs;
        (0..wavelengths)
            .map(|_| PhaseMatrixHarmonics {
                harmonics,
                stored,
                outputs,
                inputs,
                scattering: Arc::new(vec![0.0; stored * COMPONENTS * inputs * block]),
                sun: vec![0.0; stored * block],
            })
            .collect()
    }

    /// The harmonics of a species that scatters nothing, at each of
    /// `wavelengths` wavelengths: none stored (every harmonic vanishes).
    pub(crate) fn none(wavelengths: usize, harmonics: usize) -> Vec<PhaseMatrixHarmonics> {
        PhaseMatrixHarmonics::zeros(wavelengths, (harmonics, 0), 0, 0)
    }

    pub(crate) fn harmonics(&self) -> usize {
        self.harmonics
    }

    /// These harmonics from the inputs (shared, not copied) with the sun's
    /// of `sun`, computed for the same outputs and harmonics (with any
    /// inputs): the two parts are computed apart
    /// ([`PhaseMatrixHarmonics::compute`] takes each pair of directions on
    /// its own), so this is bit for bit what one computation with this sun
    /// gives.
    pub(crate) fn with_sun_of(&self, sun: &PhaseMatrixHarmonics) -> PhaseMatrixHarmonics {
        assert_eq!(
            (self.harmonics, self.stored, self.outputs),
            (sun.harmonics, sun.stored, sun.outputs),
            "harmonics for other outputs"
        );
        PhaseMatrixHarmonics {
            scattering: Arc::clone(&self.scattering),
            sun: sun.sun.clone(),
            ..*self
        }
    }

    /// Harmonic m's matrix by columns: [(c * inputs + b) * 4 * outputs + i * outputs + a];
    /// empty for a harmonic not stored (zero, [`PhaseMatrixHarmonics::compute_nonzero`]).
    pub(crate) fn scattering(&self, m: usize) -> &[f64] {
        if m >= self.stored {
            return &[];
        }
        let size = COMPONENTS * self.inputs * COMPONENTS * self.outputs;
        &self.scattering[m * size..(m + 1) * size]
    }

    /// B^m: [i * outputs + a]; empty for a harmonic not stored.
    pub(crate) fn sun(&self, m: usize) -> &[f64] {
        if m >= self.stored {
            return &[];
        }
        let size = COMPONENTS * self.outputs;
        &self.sun[m * size..(m + 1) * size]
    }

    /// True when harmonic m vanishes (to rounding) for every element (and
    /// for every harmonic not stored).
    pub(crate) fn harmonic_vanishes(&self, m: usize) -> bool {
        if m >= self.stored {
            return true;
        }
        // Harmonic 0's I <- I block holds the largest values (w_b times the
        // phase function's mean over azimuth, 2 pi p_0 > 0).
        let largest = self
            .scattering(0)
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()));
        self.scattering(m)
            .iter()
            .chain(self.sun(m))
            .all(|v| v.abs() <= 1e-14 * largest)
    }
}

/// Whether element `e` (row * 4 + column) of Z is even in the azimuth
/// difference (its two components both even or both odd: it keeps its
/// cosine transform) or odd (its sine transform).
fn is_even_element(e: usize) -> bool {
    is_even_component(e / COMPONENTS) == is_even_component(e % COMPONENTS)
}

/// The azimuth rule of the transforms: `nodes` = 4 harmonics + 1 points
/// `step` apart on [0, 2 pi), and cos(m Delta_k), sin(m Delta_k) at each,
/// [k * harmonics + m].
struct AzimuthRule {
    nodes: usize,
    step: f64,
    trig: Vec<(f64, f64)>,
}

impl AzimuthRule {
    fn new(harmonics: usize) -> AzimuthRule {
        let nodes = 4 * harmonics.max(1) + 1;
        let step = 2.0 * PI / nodes as f64;
        let trig = (0..nodes)
            .flat_map(|k| (0..harmonics).map(move |m| (m as f64 * k as f64 * step).sin_cos()))
            .map(|(s, c)| (c, s))
            .collect();
        AzimuthRule { nodes, step, trig }
    }
}

/// Each output's and input's mirror image through the horizontal plane
/// among the outputs and the inputs (the cosine negated, an input's weight
/// the same), if there is one.
struct Mirrors {
    outputs: Vec<Option<usize>>,
    inputs: Vec<Option<usize>>,
}

impl Mirrors {
    fn new(output_cosines: &[f64], (input_cosines, input_weights): (&[f64], &[f64])) -> Mirrors {
        let find = |values: &[f64], mu: f64| values.iter().position(|v| *v == -mu);
        Mirrors {
            outputs: output_cosines
                .iter()
                .map(|mu| find(output_cosines, *mu))
                .collect(),
            inputs: input_cosines
                .iter()
                .enumerate()
                .map(|(b, mu)| {
                    find(input_cosines, *mu).filter(|m| input_weights[*m] == input_weights[b])
                })
                .collect(),
        }
    }

    /// The mirror image of the pair (output `a`, input `b`); None for the
    /// sun (input `inputs`, not mirrored) or a direction without one.
    fn pair(&self, a: usize, b: usize) -> Option<(usize, usize)> {
        Some((self.outputs[a]?, (*self.inputs.get(b)?)?))
    }
}

/// The input directions' cosines with their weights, then the sun's
/// cosine (weight None) if given.
fn inputs_and_sun(
    (cosines, weights): (&[f64], &[f64]),
    sun_cosine: Option<f64>,
) -> Vec<(f64, Option<f64>)> {
    cosines
        .iter()
        .zip(weights)
        .map(|(mu, w)| (*mu, Some(*w)))
        .chain(sun_cosine.map(|mu| (mu, None)))
        .collect()
}

/// A look direction of zenith cosine mu at azimuth phi (radians) from the
/// sun's, with its meridian reference e_l, in the east-north-up frame of
/// `transport/stokes.rs` (azimuth clockwise from north).
#[derive(Debug, Clone, Copy)]
struct LookDirection {
    w: Vector3,
    e_l: Vector3,
}

impl LookDirection {
    fn new(mu: f64, phi_rad: f64) -> LookDirection {
        let (elevation_deg, azimuth_deg) = (
            mu.clamp(-1.0, 1.0).asin().to_degrees(),
            phi_rad.to_degrees(),
        );
        LookDirection {
            w: direction_from_elevation_azimuth(elevation_deg, azimuth_deg),
            e_l: meridian_reference(elevation_deg, azimuth_deg),
        }
    }
}

/// The geometry of one scattering from the look direction `incoming`
/// into `out`: the scattering angle and the two rotations of
/// Z(out <- in) = L(eta_out) F(Theta) L(eta_in) (see the module docs).
#[derive(Debug, Clone, Copy)]
struct ScatteringGeometry {
    cos_theta: f64,
    /// (cos 2 eta, sin 2 eta) re-referring the incoming light from its
    /// meridian frame to the scattering plane's (e_l = n x k_in).
    rotation_in: (f64, f64),
    /// The scattering plane's frame (e_l = n x k_out) to the outgoing
    /// meridian frame.
    rotation_out: (f64, f64),
}

impl ScatteringGeometry {
    fn new(out: LookDirection, incoming: LookDirection) -> ScatteringGeometry {
        let (k_in, k_out) = (-incoming.w, -out.w);
        let normal = scattering_plane(k_in, k_out, incoming.e_l);
        ScatteringGeometry {
            cos_theta: k_in.dot(k_out).clamp(-1.0, 1.0),
            rotation_in: rotation_cos_sin_2eta(k_in, incoming.e_l, normal.cross(k_in)),
            rotation_out: rotation_cos_sin_2eta(k_out, normal.cross(k_out), out.e_l),
        }
    }

    /// L(eta_out) F L(eta_in) for the phase matrix `f` at this angle.
    fn rotate(&self, f: &PhaseMatrix) -> Mueller {
        let (c1, s1) = self.rotation_in;
        // F L(eta_in), column by column (L's columns 1 and 2 are
        // (0, c, -s, 0) and (0, s, c, 0)).
        let f_l: Mueller = [
            [f.a1, c1 * f.b1, s1 * f.b1, 0.0],
            [f.b1, c1 * f.a2, s1 * f.a2, 0.0],
            [0.0, -s1 * f.a3, c1 * f.a3, f.b2],
            [0.0, s1 * f.b2, -c1 * f.b2, f.a4],
        ];
        let mut z = IDENTITY;
        multiply_rotated(&mut z, self.rotation_out, &f_l);
        z
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::phase_matrix::rayleigh_phase_matrix;
    use crate::transport::multiple_scattering::phase_fourier::{
        TruncatedPhase, gauss_legendre_unit_interval, normalized_associated_legendre,
    };

    fn double_gauss(n: usize) -> (Vec<f64>, Vec<f64>) {
        let (x, w) = gauss_legendre_unit_interval(n);
        (
            x.iter().copied().chain(x.iter().map(|v| -v)).collect(),
            w.iter().chain(w.iter()).copied().collect(),
        )
    }

    #[test]
    fn the_intensity_element_is_the_scalar_harmonic() {
        // Rayleigh with depolarisation: Z^m_11 = 2 pi p_m, B^m_1 = (2 - delta) p_m.
        let (mu, w) = double_gauss(4);
        let total = mu.len();
        let rho = 0.03;
        let d = (1.0 - rho) / (1.0 + 0.5 * rho);
        let moments: Vec<f64> = (0..=total)
            .map(|l| match l {
                0 => 1.0,
                2 => 0.1 * d,
                _ => 0.0,
            })
            .collect();
        let scalar = TruncatedPhase::from_moments(&moments, total);
        let sun_cosine = 0.37;
        let harmonics = PhaseMatrixHarmonics::compute(
            &|c, out| out[0] = rayleigh_phase_matrix(rho, c),
            1,
            &mu,
            (&mu, &w),
            Some(sun_cosine),
            total,
        )
        .remove(0);
        let mut lambda = vec![vec![0.0; total * total]; total];
        for (a, m) in mu.iter().enumerate() {
            normalized_associated_legendre(*m, total, &mut lambda[a]);
        }
        let mut sun_lambda = vec![0.0; total * total];
        normalized_associated_legendre(sun_cosine, total, &mut sun_lambda);
        for m in 0..total {
            let matrix = harmonics.scattering(m);
            for a in 0..total {
                for b in 0..total {
                    let expected = 2.0 * PI * w[b] * scalar.harmonic(m, &lambda[a], &lambda[b]);
                    let got = matrix[b * COMPONENTS * total + a];
                    assert!(
                        (got - expected).abs() < 1e-14,
                        "m {m} a {a} b {b}: {got} vs {expected}"
                    );
                }
                let factor = if m == 0 { 1.0 } else { 2.0 };
                let expected = factor * scalar.harmonic(m, &lambda[a], &sun_lambda);
                let got = harmonics.sun(m)[a];
                assert!(
                    (got - expected).abs() < 1e-14,
                    "sun m {m} a {a}: {got} vs {expected}"
                );
            }
            assert_eq!(harmonics.harmonic_vanishes(m), m > 2, "m {m}");
        }
    }

    #[test]
    fn rayleigh_harmonics_from_three_on_vanish_and_are_not_stored() {
        // compute_nonzero's harmonics 0..3 are compute's to the bit; the
        // ones it does not store are rounding in compute's.
        let phase = |c: f64, out: &mut [PhaseMatrix]| {
            for (i, m) in out.iter_mut().enumerate() {
                *m = rayleigh_phase_matrix(0.01 * i as f64, c);
            }
        };
        let (mu, w) = double_gauss(4);
        let outputs = [0.8, -0.3, 0.02];
        let full = PhaseMatrixHarmonics::compute(&phase, 2, &outputs, (&mu, &w), Some(0.4), 8);
        let kept = PhaseMatrixHarmonics::compute_nonzero(
            &phase,
            2,
            &outputs,
            (&mu, &w),
            Some(0.4),
            (8, 3),
        );
        for (f, k) in full.iter().zip(&kept) {
            for m in 0..8 {
                assert!(f.harmonic_vanishes(m) == (m >= 3) && k.harmonic_vanishes(m) == (m >= 3));
                if m < 3 {
                    assert_eq!(f.scattering(m), k.scattering(m), "m {m}");
                    assert_eq!(f.sun(m), k.sun(m), "m {m}");
                } else {
                    assert!(k.scattering(m).is_empty() && k.sun(m).is_empty());
                }
            }
        }
    }

    #[test]
    fn the_sun_term_synthesises_the_rotated_single_scattering() {
        // sum_m B^m_i(mu) {cos, sin}(m phi) is Z_i1(mu, phi; sun) itself.
        let rho = 0.0;
        let phase = |c: f64| rayleigh_phase_matrix(rho, c);
        let (mu, w) = double_gauss(3);
        let sun_cosine = 0.5;
        let harmonics = PhaseMatrixHarmonics::compute(
            &|c, out| out[0] = phase(c),
            1,
            &mu,
            (&mu, &w),
            Some(sun_cosine),
            6,
        )
        .remove(0);
        for (a, &m_a) in mu.iter().enumerate() {
            for phi in [0.3f64, 1.2, 2.9, 4.4] {
                let geometry = ScatteringGeometry::new(
                    LookDirection::new(m_a, phi),
                    LookDirection::new(sun_cosine, 0.0),
                );
                let z = geometry.rotate(&phase(geometry.cos_theta));
                for (i, row) in z.iter().enumerate() {
                    let synthesised: f64 = (0..6)
                        .map(|m| {
                            let g = if is_even_component(i) {
                                (m as f64 * phi).cos()
                            } else {
                                (m as f64 * phi).sin()
                            };
                            harmonics.sun(m)[i * mu.len() + a] * g
                        })
                        .sum();
                    assert!(
                        (synthesised - row[0]).abs() < 1e-14,
                        "mu {m_a} phi {phi} i {i}: {synthesised} vs {}",
                        row[0]
                    );
                }
            }
        }
    }

    #[test]
    fn the_rotated_matrix_is_the_product_of_the_three_matrices() {
        // ScatteringGeometry::rotate's expanded F L(eta_in) against the
        // plain product L(eta_out) F L(eta_in), with a Mie-like matrix
        // (every element non-zero).
        let f = PhaseMatrix {
            a1: 0.9,
            a2: 0.7,
            a3: 0.5,
            a4: 0.4,
            b1: -0.3,
            b2: 0.2,
        };
        let f_matrix: Mueller = [
            [f.a1, f.b1, 0.0, 0.0],
            [f.b1, f.a2, 0.0, 0.0],
            [0.0, 0.0, f.a3, f.b2],
            [0.0, 0.0, -f.b2, f.a4],
        ];
        for (mu_out, phi, mu_in) in [(0.3, 1.0, 0.8), (-0.6, 2.5, 0.2), (0.9, 4.0, -0.4)] {
            let geometry = ScatteringGeometry::new(
                LookDirection::new(mu_out, phi),
                LookDirection::new(mu_in, 0.0),
            );
            let mut rotate_in = IDENTITY;
            multiply_rotated(&mut rotate_in, geometry.rotation_in, &IDENTITY);
            let mut left = IDENTITY;
            multiply_rotated(&mut left, geometry.rotation_out, &f_matrix);
            let z = geometry.rotate(&f);
            for r in 0..4 {
                for c in 0..4 {
                    let expected: f64 = (0..4).map(|k| left[r][k] * rotate_in[k][c]).sum();
                    assert!((z[r][c] - expected).abs() < 1e-15, "{r} {c}");
                }
            }
        }
    }

    /// A Mie-like matrix at each of `out`'s "wavelengths" (different
    /// shapes) at scattering-angle cosine `c`.
    fn mie_like_phase(c: f64, out: &mut [PhaseMatrix]) {
        for (i, m) in out.iter_mut().enumerate() {
            let g = 0.2 * i as f64;
            let a1 = (1.0 - g * g) / (1.0 + g * g - 2.0 * g * c).powf(1.5) / (4.0 * PI);
            *m = PhaseMatrix {
                a1,
                a2: 0.9 * a1,
                a3: a1 * c,
                a4: 0.8 * a1 * c,
                b1: -0.4 * a1 * (1.0 - c * c),
                b2: 0.1 * a1 * (1.0 - c * c),
            };
        }
    }

    #[test]
    fn the_fast_transform_is_the_reference_sum() {
        // Three "wavelengths", from streams and the sun into other
        // directions.
        let phase = mie_like_phase;
        let (mu, w) = double_gauss(3);
        // Outputs with and without mirror images (those with take their
        // mirror's harmonics with D's signs), and the streams themselves.
        let outputs = [0.7, -0.2, 0.05, -0.7, 0.2, mu[1], mu[4]];
        let fast = PhaseMatrixHarmonics::compute(&phase, 3, &outputs, (&mu, &w), Some(0.3), 6);
        let reference =
            PhaseMatrixHarmonics::compute_reference(&phase, 3, &outputs, (&mu, &w), Some(0.3), 6);
        for (f, r) in fast.iter().zip(&reference) {
            for (a, b) in f
                .scattering
                .iter()
                .zip(r.scattering.iter())
                .chain(f.sun.iter().zip(&r.sun))
            {
                assert!((a - b).abs() <= 1e-14 * (1.0 + b.abs()), "{a} vs {b}");
            }
        }
    }

    /// The harmonics from the streams with those from the sun alone
    /// (computed apart, joined by `with_sun_of`) are one computation's
    /// with the sun, bit for bit.
    #[test]
    fn harmonics_joined_with_the_suns_are_those_computed_with_it() {
        let phase = mie_like_phase;
        let (mu, w) = double_gauss(3);
        let outputs = mu.clone();
        for sun in [0.9, 0.3, -0.05] {
            let whole = PhaseMatrixHarmonics::compute(&phase, 3, &outputs, (&mu, &w), Some(sun), 6);
            let streams = PhaseMatrixHarmonics::compute(&phase, 3, &outputs, (&mu, &w), None, 6);
            let sun_only =
                PhaseMatrixHarmonics::compute(&phase, 3, &outputs, (&[], &[]), Some(sun), 6);
            for ((whole, streams), sun_only) in whole.iter().zip(&streams).zip(&sun_only) {
                let joined = streams.with_sun_of(sun_only);
                assert!(Arc::ptr_eq(&joined.scattering, &streams.scattering));
                for m in 0..6 {
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(joined.scattering(m)), bits(whole.scattering(m)));
                    assert_eq!(bits(joined.sun(m)), bits(whole.sun(m)));
                    assert!(whole.sun(m).iter().any(|v| *v != 0.0) || m > 0);
                }
            }
        }
    }
}
