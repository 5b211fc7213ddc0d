//! Values of a spectral quantity at the wavelengths of a [`WavelengthGrid`]
//! (pbrt's `SampledSpectrum`): radiance, optical depth, transmittance, any
//! per-wavelength number.
//!
//! The values are plain `f64` in a contiguous buffer, index `i` at
//! `grid.wavelength_nm(i)`; the grid itself is not stored (every spectrum of a
//! computation shares one grid). Arithmetic is element-wise. The in-place
//! operators (`+=`, `*=`, [`SampledSpectrum::add_scaled`],
//! [`SampledSpectrum::exp_neg_in_place`]) never allocate, so the renderer's
//! inner loops keep one buffer per quantity and reuse it; the by-value
//! operators allocate a result and are meant for set-up code.

use std::ops::{Add, AddAssign, Index, IndexMut, Mul, MulAssign};

#[cfg(test)]
use crate::error::{Error, Result};

/// Values at the samples of one wavelength grid (unit: that of the quantity).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SampledSpectrum {
    values: Vec<f64>,
}

impl SampledSpectrum {
    /// `len` zeros.
    pub(crate) fn zeros(len: usize) -> SampledSpectrum {
        SampledSpectrum {
            values: vec![0.0; len],
        }
    }

    /// `len` copies of `value`.
    pub(crate) fn constant(len: usize, value: f64) -> SampledSpectrum {
        SampledSpectrum {
            values: vec![value; len],
        }
    }

    /// Wraps values already sampled on a grid.
    pub fn from_values(values: Vec<f64>) -> SampledSpectrum {
        SampledSpectrum { values }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The values, in grid order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The values, in grid order, for writing.
    pub(crate) fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Consumes the spectrum into its values.
    pub fn into_values(self) -> Vec<f64> {
        self.values
    }

    /// Sets every value to `value` (reuse a buffer without allocating).
    pub(crate) fn fill(&mut self, value: f64) {
        self.values.fill(value);
    }

    /// `self += scale * other`, element-wise: the accumulation step of a
    /// quadrature or a ray march.
    pub(crate) fn add_scaled(&mut self, other: &SampledSpectrum, scale: f64) {
        assert_eq!(
            self.len(),
            other.len(),
            "spectra sampled on different grids"
        );
        for (a, b) in self.values.iter_mut().zip(&other.values) {
            *a += scale * b;
        }
    }

    /// sum_j w_j s_j over `parts` (w_j, s_j), sample by sample (w_j has a
    /// weight per sample), all on one grid (no values when there are no
    /// parts): a k-distribution's sum over its terms.
    pub fn weighted_sum<'a>(
        parts: impl IntoIterator<Item = (&'a SampledSpectrum, &'a SampledSpectrum)>,
    ) -> SampledSpectrum {
        let mut total: Option<SampledSpectrum> = None;
        for (weights, spectrum) in parts {
            assert_eq!(
                weights.len(),
                spectrum.len(),
                "weights and spectrum on different grids"
            );
            let total = total.get_or_insert_with(|| SampledSpectrum::zeros(spectrum.len()));
            assert_eq!(
                total.len(),
                spectrum.len(),
                "spectra sampled on different grids"
            );
            for ((t, w), s) in total
                .values
                .iter_mut()
                .zip(&weights.values)
                .zip(&spectrum.values)
            {
                *t += w * s;
            }
        }
        total.unwrap_or_else(|| SampledSpectrum::zeros(0))
    }

    /// Replaces each value v by exp(-v): optical depth -> transmittance
    /// (Beer-Lambert).
    #[cfg(test)]
    pub(crate) fn exp_neg_in_place(&mut self) {
        for v in &mut self.values {
            *v = (-*v).exp();
        }
    }

    /// Largest value (NaN-free input assumed; -inf for an empty spectrum).
    pub fn max_value(&self) -> f64 {
        self.values
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Checks that every value is finite and >= 0, as radiance, irradiance
    /// and reflectance must be; the error names the first bad sample.
    /// `what` names the quantity in the message (`"sky radiance"`).
    #[cfg(test)]
    pub(crate) fn check_finite_non_negative(&self, what: &str) -> Result<()> {
        match self
            .values
            .iter()
            .position(|v| !(v.is_finite() && *v >= 0.0))
        {
            None => Ok(()),
            Some(i) => Err(Error::InvalidSpectrum(format!(
                "{what}: sample {i} is {}; values must be finite and >= 0",
                self.values[i]
            ))),
        }
    }
}

impl Index<usize> for SampledSpectrum {
    type Output = f64;
    fn index(&self, index: usize) -> &f64 {
        &self.values[index]
    }
}

impl IndexMut<usize> for SampledSpectrum {
    fn index_mut(&mut self, index: usize) -> &mut f64 {
        &mut self.values[index]
    }
}

impl AddAssign<&SampledSpectrum> for SampledSpectrum {
    fn add_assign(&mut self, other: &SampledSpectrum) {
        self.add_scaled(other, 1.0);
    }
}

impl MulAssign<&SampledSpectrum> for SampledSpectrum {
    fn mul_assign(&mut self, other: &SampledSpectrum) {
        assert_eq!(
            self.len(),
            other.len(),
            "spectra sampled on different grids"
        );
        for (a, b) in self.values.iter_mut().zip(&other.values) {
            *a *= b;
        }
    }
}

impl MulAssign<f64> for SampledSpectrum {
    fn mul_assign(&mut self, scale: f64) {
        for a in &mut self.values {
            *a *= scale;
        }
    }
}

impl Add for &SampledSpectrum {
    type Output = SampledSpectrum;
    fn add(self, other: &SampledSpectrum) -> SampledSpectrum {
        let mut sum = self.clone();
        sum += other;
        sum
    }
}

impl Mul for &SampledSpectrum {
    type Output = SampledSpectrum;
    fn mul(self, other: &SampledSpectrum) -> SampledSpectrum {
        let mut product = self.clone();
        product *= other;
        product
    }
}

impl Mul<f64> for &SampledSpectrum {
    type Output = SampledSpectrum;
    fn mul(self, scale: f64) -> SampledSpectrum {
        let mut product = self.clone();
        product *= scale;
        product
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn element_wise_arithmetic() {
        let a = SampledSpectrum::from_values(vec![1.0, 2.0, 3.0]);
        let b = SampledSpectrum::from_values(vec![0.5, 0.25, 2.0]);
        assert_eq!((&a + &b).values(), &[1.5, 2.25, 5.0]);
        assert_eq!((&a * &b).values(), &[0.5, 0.5, 6.0]);
        assert_eq!((&a * 2.0).values(), &[2.0, 4.0, 6.0]);
        let mut c = a.clone();
        c.add_scaled(&b, -2.0);
        assert_eq!(c.values(), &[0.0, 1.5, -1.0]);
        assert_eq!(a.max_value(), 3.0);
    }

    #[test]
    fn beer_lambert_transmittance() {
        let mut tau = SampledSpectrum::from_values(vec![0.0, 1.0, 2.0f64.ln()]);
        tau.exp_neg_in_place();
        assert_eq!(tau[0], 1.0);
        assert!((tau[1] - (-1.0f64).exp()).abs() < 1e-16);
        assert!((tau[2] - 0.5).abs() < 1e-16);
    }

    #[test]
    fn nan_and_negative_values_are_named() {
        let ok = SampledSpectrum::from_values(vec![0.0, 1.0]);
        assert!(ok.check_finite_non_negative("radiance").is_ok());
        let nan = SampledSpectrum::from_values(vec![0.0, f64::NAN]);
        let message = nan
            .check_finite_non_negative("radiance")
            .unwrap_err()
            .to_string();
        assert!(message.contains("sample 1 is NaN"), "{message}");
        let negative = SampledSpectrum::from_values(vec![-1e-3]);
        assert!(negative.check_finite_non_negative("radiance").is_err());
        let infinite = SampledSpectrum::from_values(vec![f64::INFINITY]);
        assert!(infinite.check_finite_non_negative("radiance").is_err());
    }

    #[test]
    #[should_panic(expected = "different grids")]
    fn mixing_grids_is_a_programming_error() {
        let mut a = SampledSpectrum::zeros(2);
        a += &SampledSpectrum::zeros(3);
    }
}
