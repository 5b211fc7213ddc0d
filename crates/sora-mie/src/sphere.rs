//! One homogeneous sphere. (Stub: the interface the rest of the crate is
//! written against; the implementation replaces every `todo!()`.)

use crate::Complex64;

/// Why a sphere could not be solved: the input is outside the supported domain.
#[derive(Debug, Clone, PartialEq)]
pub enum MieError {
    /// `x` must be finite and > 0 (supported 1e-6 ..= 2e4 guaranteed; larger allowed but slow).
    InvalidSizeParameter(f64),
    /// `m` must be finite, Re(m) > 0, Im(m) >= 0.
    InvalidRefractiveIndex(Complex64),
}

impl std::fmt::Display for MieError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MieError::InvalidSizeParameter(x) => {
                write!(f, "size parameter x = {x} is invalid: it must be finite and greater than 0")
            }
            MieError::InvalidRefractiveIndex(m) => write!(
                f,
                "refractive index m = {}{:+}i is invalid: the real part must be > 0 and the imaginary part >= 0 (absorption), both finite",
                m.re, m.im
            ),
        }
    }
}

impl std::error::Error for MieError {}

/// Efficiencies (dimensionless, cross-section / (pi r^2)) and asymmetry parameter of one sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Efficiencies {
    pub qext: f64,
    pub qsca: f64,
    /// Computed directly (not as qext - qsca) so it keeps its relative accuracy when tiny.
    pub qabs: f64,
    /// Backscattering efficiency, B&H eq. 4.82 convention: |sum (2n+1)(-1)^n (a_n - b_n)|^2 / x^2.
    pub qback: f64,
    /// Asymmetry parameter <cos theta>, weighted by scattered intensity.
    pub g: f64,
}

/// Fast path: efficiencies and g of a sphere, no allocation.
pub fn compute_efficiencies(m: Complex64, x: f64) -> Result<Efficiencies, MieError> {
    let _ = (m, x);
    todo!()
}

/// The full solution of one sphere: series coefficients kept, so that amplitude
/// functions can be evaluated at any angle.
#[derive(Debug, Clone)]
pub struct MieSolution {
    // private fields: a_n, b_n (n = 1..=n_terms), x, efficiencies
}

impl MieSolution {
    /// Solve the sphere (allocates the coefficient vectors once).
    pub fn compute(m: Complex64, x: f64) -> Result<MieSolution, MieError> {
        let _ = (m, x);
        todo!()
    }
    pub fn efficiencies(&self) -> Efficiencies {
        todo!()
    }
    pub fn size_parameter(&self) -> f64 {
        todo!()
    }
    /// Number of series terms kept.
    pub fn n_terms(&self) -> usize {
        todo!()
    }
    /// a_n, b_n for n = 1..=n_terms (index 0 is n = 1).
    pub fn coefficients(&self) -> (&[Complex64], &[Complex64]) {
        todo!()
    }
    /// Amplitude functions (S1, S2) at scattering angle theta with mu = cos(theta), B&H eq. 4.74.
    pub fn amplitudes(&self, cos_theta: f64) -> (Complex64, Complex64) {
        let _ = cos_theta;
        todo!()
    }
    /// (S11, S12) at mu = cos(theta): S11 = (|S1|^2 + |S2|^2)/2, S12 = (|S2|^2 - |S1|^2)/2.
    pub fn s11_s12(&self, cos_theta: f64) -> (f64, f64) {
        let _ = cos_theta;
        todo!()
    }
    /// Unpolarised phase function, normalised to 1 over 4 pi sr (unit: sr^-1):
    /// S11 / (pi x^2 Qsca).
    pub fn phase_function_per_sr(&self, cos_theta: f64) -> f64 {
        let _ = cos_theta;
        todo!()
    }
    /// Fill `s11` and `s12` at each mu of `cos_theta` (one pass of the angular
    /// recurrences per angle, no allocation). Slices must have equal lengths.
    pub fn s11_s12_table(&self, cos_theta: &[f64], s11: &mut [f64], s12: &mut [f64]) {
        let _ = (cos_theta, s11, s12);
        todo!()
    }
}
