//! Spectral radiance -> CIE XYZ tristimulus values (CIE 015:2018 §7.1; the
//! paper's §4 "等色関数を用いて CIE XYZ に変換").
//!
//! The rule, on a [`WavelengthGrid`] with samples λ_i and quadrature weights
//! w_i (the grid's `step_nm` for every sample, the paper's Riemann sum):
//!
//! ```text
//! X = Σ_i L(λ_i) x̄(λ_i) w_i,   Y = Σ_i L(λ_i) ȳ(λ_i) w_i,   Z = Σ_i L(λ_i) z̄(λ_i) w_i
//! ```
//!
//! with x̄, ȳ, z̄ the observer's colour-matching functions at the sample
//! wavelengths (interpolated linearly between their 1 nm rows), the sum
//! running over the samples inside 360-830 nm, the range of the tables. A
//! grid that reaches beyond it (sora's span 280-2500 nm, for the
//! sun-photometer channels and the solar infrared) gives its ultraviolet and infrared samples
//! weight 0: the CIE defines colorimetric integrals over 360-830 nm, and the
//! functions there fall to 1e-4 (x̄ at 360 nm) and 1e-6 (at 830 nm) of their
//! peaks, so no colour is lost. A grid inside 360-830 nm, as every grid
//! was before the range widened, converts exactly as before. A grid with no
//! sample in 360-830 nm has no colour ([`SpectrumToXyz::colour_sample_count`]
//! is 0, and every XYZ is black): callers that show colour refuse it. There is no
//! normalising constant and no 683 lm/W: X, Y, Z are in the spectrum's unit
//! times nm. For a spectral radiance L in W m^-2 sr^-1 nm^-1, XYZ are in
//! W m^-2 sr^-1 (ȳ-weighted), and the luminance is
//! L_v = 683 lm/W × Y in cd/m^2 ([`Xyz::luminance_cd_m2`]; 683 lm/W is
//! K_m, the maximum luminous efficacy of photopic vision as CIE 015 uses it;
//! the SI fixes K_cd = 683 lm/W exactly at 540 THz, ≈ 555 nm, where
//! V(λ) ≈ 1). This is photometry proper only for the 2-degree observer,
//! whose ȳ is V(λ); with the 10-degree observer 683 × Y10 is the CIE's
//! 10-degree luminance analogue.
//!
//! [`SpectrumToXyz`] precomputes the products w_i x̄(λ_i), w_i ȳ(λ_i),
//! w_i z̄(λ_i) once per grid, so that each conversion is three dot products.
//! Its checked path rejects NaN, infinite and negative samples and spectra of
//! the wrong length: a bad radiance never becomes a pixel.

use crate::colour::colour_matching::{ColourMatchingFunctions, Observer};
use crate::error::{Error, Result};
use crate::spectrum::{SampledSpectrum, WavelengthGrid};

/// K_m, the maximum luminous efficacy of radiation for photopic vision, lm/W
/// (CIE 015; the SI's K_cd at 540 THz): luminance in cd/m^2 is
/// K_m × Y when Y was computed from radiance in W m^-2 sr^-1 nm^-1.
pub const MAXIMUM_LUMINOUS_EFFICACY_LM_PER_W: f64 = 683.0;

/// CIE XYZ tristimulus values. Unit: that of the integrated spectrum times nm
/// (see the module docs); Y is the luminance-like component.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Xyz {
    /// X.
    pub x: f64,
    /// Y (luminance when the spectrum is a radiance).
    pub y: f64,
    /// Z.
    pub z: f64,
}

impl Xyz {
    /// No light.
    pub const BLACK: Xyz = Xyz {
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };

    /// The tristimulus values (X, Y, Z).
    pub(crate) const fn new(x: f64, y: f64, z: f64) -> Xyz {
        Xyz { x, y, z }
    }

    /// `[X, Y, Z]`.
    pub(crate) const fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }

    /// From `[X, Y, Z]`.
    pub(crate) const fn from_array([x, y, z]: [f64; 3]) -> Xyz {
        Xyz { x, y, z }
    }

    /// Every component multiplied by `factor` (an exposure, a normalisation).
    pub fn scaled(self, factor: f64) -> Xyz {
        Xyz::new(self.x * factor, self.y * factor, self.z * factor)
    }

    /// True when X, Y and Z are all finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    /// CIE 1931 chromaticity coordinates (x, y) = (X, Y) / (X + Y + Z),
    /// dimensionless; `None` for black (X + Y + Z = 0), whose chromaticity is
    /// undefined.
    pub fn chromaticity_xy(self) -> Option<[f64; 2]> {
        let sum = self.x + self.y + self.z;
        (sum != 0.0 && sum.is_finite()).then(|| [self.x / sum, self.y / sum])
    }

    /// Luminance in cd/m^2, K_m × Y with K_m = 683 lm/W: valid when these
    /// values were integrated from spectral radiance in W m^-2 sr^-1 nm^-1
    /// with the 2-degree observer.
    pub fn luminance_cd_m2(self) -> f64 {
        MAXIMUM_LUMINOUS_EFFICACY_LM_PER_W * self.y
    }
}

/// Converts spectra sampled on one [`WavelengthGrid`] to XYZ: the
/// colour-matching functions times the quadrature weights, precomputed.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectrumToXyz {
    grid: WavelengthGrid,
    observer: Observer,
    /// `[w_i x̄(λ_i), w_i ȳ(λ_i), w_i z̄(λ_i)]` for sample `i`, nm.
    weighted_cmfs: Vec<[f64; 3]>,
}

impl SpectrumToXyz {
    /// The conversion on `grid` for `observer` (parses the observer's table;
    /// to share one parsed table between grids, use
    /// `SpectrumToXyz::with_colour_matching_functions`).
    pub fn new(grid: &WavelengthGrid, observer: Observer) -> SpectrumToXyz {
        SpectrumToXyz::with_colour_matching_functions(grid, &ColourMatchingFunctions::new(observer))
    }

    /// The conversion on `grid` with already parsed colour-matching functions.
    pub(crate) fn with_colour_matching_functions(
        grid: &WavelengthGrid,
        cmfs: &ColourMatchingFunctions,
    ) -> SpectrumToXyz {
        // Samples inside 360-830 nm (to a rounding error, which the clamped
        // look-up absorbs) get the functions times their weight; the others,
        // none (see the module docs).
        let weighted_cmfs = (0..grid.len())
            .map(|i| {
                let wavelength_nm = grid.wavelength_nm(i);
                if !ColourMatchingFunctions::covers_nm(wavelength_nm) {
                    return [0.0; 3];
                }
                let weight_nm = grid.quadrature_weight_nm(i);
                cmfs.value_at_nm_clamped(wavelength_nm)
                    .map(|value| value * weight_nm)
            })
            .collect();
        SpectrumToXyz {
            grid: *grid,
            observer: cmfs.observer(),
            weighted_cmfs,
        }
    }

    /// The conversion with each sample's colour-matching functions scaled
    /// by `factors` (one per sample): the colour of a spectrum times the
    /// factors (a k-distribution term's colour with its weight per sample).
    pub(crate) fn scaled(&self, factors: &[f64]) -> SpectrumToXyz {
        assert_eq!(factors.len(), self.weighted_cmfs.len(), "wrong grid");
        SpectrumToXyz {
            grid: self.grid,
            observer: self.observer,
            weighted_cmfs: self
                .weighted_cmfs
                .iter()
                .zip(factors)
                .map(|(cmf, f)| cmf.map(|v| v * f))
                .collect(),
        }
    }

    /// The conversion of the samples from `first` on, on `grid` (their
    /// sub-grid, `WavelengthGrid::sub_grid`): the colour of a spectrum
    /// that is zero at every other sample.
    pub(crate) fn restricted(&self, first: usize, grid: &WavelengthGrid) -> SpectrumToXyz {
        SpectrumToXyz {
            grid: *grid,
            observer: self.observer,
            weighted_cmfs: self.weighted_cmfs[first..first + grid.len()].to_vec(),
        }
    }

    /// Per sample, the colour-matching functions times its quadrature
    /// weight, `[w x̄, w ȳ, w z̄]`, nm.
    pub(crate) fn weighted_cmfs(&self) -> &[[f64; 3]] {
        &self.weighted_cmfs
    }

    /// The grid the spectra must be sampled on.
    pub(crate) fn grid(&self) -> &WavelengthGrid {
        &self.grid
    }

    /// How many of the grid's samples lie in 360-830 nm and so count
    /// towards colour: the grid's length for a grid inside that range, 0
    /// for one with no colour (e.g. 900-1100 nm).
    pub fn colour_sample_count(&self) -> usize {
        self.grid
            .wavelengths_nm()
            .filter(|w| ColourMatchingFunctions::covers_nm(*w))
            .count()
    }

    /// XYZ of `spectrum` (unit: the spectrum's times nm; see the module docs).
    ///
    /// Fails, naming the sample and its wavelength, if the spectrum does not
    /// have one value per grid wavelength, or if a value is NaN, infinite or
    /// negative (radiance cannot be, and such a value must not reach a pixel).
    pub fn to_xyz(&self, spectrum: &SampledSpectrum) -> Result<Xyz> {
        let values = spectrum.values();
        self.check_length(values)?;
        if let Some(i) = values.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(Error::InvalidSpectrum(format!(
                "spectrum to XYZ: sample {i} ({} nm) is {}; values must be finite and >= 0",
                self.grid.wavelength_nm(i),
                values[i]
            )));
        }
        Ok(self.to_xyz_unchecked(values))
    }

    /// XYZ of a signed spectrum: a Stokes Q, U or V, which may be negative
    /// (XYZ is linear in the spectrum, so a Stokes vector's four spectra map
    /// component by component). Fails as [`SpectrumToXyz::to_xyz`] does,
    /// but for negative values.
    pub fn to_xyz_signed(&self, spectrum: &SampledSpectrum) -> Result<Xyz> {
        let values = spectrum.values();
        self.check_length(values)?;
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(Error::InvalidSpectrum(format!(
                "spectrum to XYZ: sample {i} ({} nm) is {}; values must be finite",
                self.grid.wavelength_nm(i),
                values[i]
            )));
        }
        Ok(self.weighted_sum(values))
    }

    /// An error unless `values` has one value per grid wavelength.
    fn check_length(&self, values: &[f64]) -> Result<()> {
        if values.len() != self.weighted_cmfs.len() {
            return Err(Error::InvalidSpectrum(format!(
                "spectrum to XYZ: {} samples, but the grid {} has {}",
                values.len(),
                self.grid,
                self.weighted_cmfs.len()
            )));
        }
        Ok(())
    }

    /// XYZ of `values` without validation, for the renderer's inner loop,
    /// where spectra come from physics that cannot produce bad values.
    /// Checks the length and the values only in debug builds; a NaN passed
    /// here in a release build propagates into the result.
    pub(crate) fn to_xyz_unchecked(&self, values: &[f64]) -> Xyz {
        debug_assert_eq!(values.len(), self.weighted_cmfs.len(), "wrong grid");
        debug_assert!(
            values.iter().all(|v| v.is_finite() && *v >= 0.0),
            "spectrum with a NaN, infinite or negative sample"
        );
        self.weighted_sum(values)
    }

    /// The colour-matching integral of a signed spectrum on the grid,
    /// without the checks: a Stokes Q, U or V, whose XYZ is the same linear
    /// map of it as of a radiance (and may be negative).
    pub(crate) fn weighted_sum(&self, values: &[f64]) -> Xyz {
        debug_assert_eq!(values.len(), self.weighted_cmfs.len(), "wrong grid");
        let mut sum = [0.0; 3];
        for (value, weights) in values.iter().zip(&self.weighted_cmfs) {
            sum[0] += value * weights[0];
            sum[1] += value * weights[1];
            sum[2] += value * weights[2];
        }
        Xyz::from_array(sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_single_sample_gives_the_weighted_colour_matching_functions() {
        let grid = WavelengthGrid::paper();
        let to_xyz = SpectrumToXyz::new(&grid, Observer::Cie1931TwoDegree);
        let mut spectrum = SampledSpectrum::zeros(grid.len());
        spectrum[11] = 2.0; // 600 nm
        let xyz = to_xyz.to_xyz(&spectrum).unwrap();
        // 2 × cmf(600 nm) × 20 nm.
        let expected = [1.0622 * 40.0, 0.631 * 40.0, 0.0008 * 40.0];
        for (got, want) in xyz.to_array().iter().zip(expected) {
            assert!((got - want).abs() < 1e-12, "{xyz:?}");
        }
    }

    #[test]
    fn a_wide_grid_has_the_colour_of_its_part_in_360_to_830_nm() {
        // The same smooth spectrum on 300-1100 nm and on 360-830 nm, both
        // every 10 nm: the samples in 360-830 nm are the same wavelengths,
        // and the others add nothing, so the colours are identical.
        let spectrum_on = |grid: &WavelengthGrid| {
            SampledSpectrum::from_values(
                grid.wavelengths_nm()
                    .map(|w| (550.0 / w).powi(4) + 0.001 * w)
                    .collect(),
            )
        };
        let wide: WavelengthGrid = "300:1100:10".parse().unwrap();
        let visible: WavelengthGrid = "360:830:10".parse().unwrap();
        for observer in Observer::ALL {
            let (wide_to_xyz, visible_to_xyz) = (
                SpectrumToXyz::new(&wide, observer),
                SpectrumToXyz::new(&visible, observer),
            );
            assert_eq!(wide_to_xyz.colour_sample_count(), 48);
            assert_eq!(visible_to_xyz.colour_sample_count(), visible.len());
            let wide_xyz = wide_to_xyz.to_xyz(&spectrum_on(&wide)).unwrap();
            let visible_xyz = visible_to_xyz.to_xyz(&spectrum_on(&visible)).unwrap();
            assert_eq!(wide_xyz, visible_xyz, "{observer}");
            assert!(wide_xyz.y > 0.0);
        }
        // Light only outside 360-830 nm has no colour.
        let mut ultraviolet_and_infrared = SampledSpectrum::zeros(wide.len());
        for i in (0..6).chain(54..81) {
            ultraviolet_and_infrared[i] = 1.0;
        }
        let to_xyz = SpectrumToXyz::new(&wide, Observer::Cie1931TwoDegree);
        assert_eq!(
            to_xyz.to_xyz(&ultraviolet_and_infrared).unwrap(),
            Xyz::BLACK
        );
        // A grid wholly outside has none at all.
        let infrared: WavelengthGrid = "900:1100:10".parse().unwrap();
        let to_xyz = SpectrumToXyz::new(&infrared, Observer::Cie1931TwoDegree);
        assert_eq!(to_xyz.colour_sample_count(), 0);
        assert_eq!(
            to_xyz
                .to_xyz(&SampledSpectrum::constant(infrared.len(), 1.0))
                .unwrap(),
            Xyz::BLACK
        );
        // Rounding: 300:1100:0.1 reaches 360 and 830 nm only to a rounding
        // error, and still counts both ends.
        let fine: WavelengthGrid = "300:1100:0.1".parse().unwrap();
        let to_xyz = SpectrumToXyz::new(&fine, Observer::Cie1931TwoDegree);
        assert_eq!(to_xyz.colour_sample_count(), 4701);
    }

    #[test]
    fn equal_energy_spectrum_is_near_the_equal_energy_white() {
        let grid: WavelengthGrid = "360:830:1".parse().unwrap();
        for observer in Observer::ALL {
            let to_xyz = SpectrumToXyz::new(&grid, observer);
            let xyz = to_xyz
                .to_xyz(&SampledSpectrum::constant(grid.len(), 1.0))
                .unwrap();
            let [x, y] = xyz.chromaticity_xy().unwrap();
            assert!((x - 1.0 / 3.0).abs() < 2e-4 && (y - 1.0 / 3.0).abs() < 2e-4);
        }
    }

    #[test]
    fn zero_spectrum_is_black_without_chromaticity() {
        let grid = WavelengthGrid::paper();
        let to_xyz = SpectrumToXyz::new(&grid, Observer::Cie1931TwoDegree);
        let xyz = to_xyz.to_xyz(&SampledSpectrum::zeros(grid.len())).unwrap();
        assert_eq!(xyz, Xyz::BLACK);
        assert_eq!(xyz.chromaticity_xy(), None);
    }

    #[test]
    fn bad_spectra_are_rejected_naming_the_sample() {
        let grid = WavelengthGrid::paper();
        let to_xyz = SpectrumToXyz::new(&grid, Observer::Cie1931TwoDegree);
        let cases = [
            (2, f64::NAN, "sample 2 (420 nm) is NaN"),
            (20, -1e-9, "sample 20 (780 nm) is -0.000000001"),
            (0, f64::INFINITY, "sample 0 (380 nm) is inf"),
        ];
        for (index, value, expected) in cases {
            let mut spectrum = SampledSpectrum::constant(grid.len(), 1.0);
            spectrum[index] = value;
            let message = to_xyz.to_xyz(&spectrum).unwrap_err().to_string();
            assert!(message.contains(expected), "{message}");
        }
        let message = to_xyz
            .to_xyz(&SampledSpectrum::zeros(20))
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("20 samples") && message.contains("has 21"),
            "{message}"
        );
    }

    #[test]
    fn luminance_uses_683_lumens_per_watt() {
        let xyz = Xyz::new(0.5, 2.0, 0.1);
        assert_eq!(xyz.luminance_cd_m2(), 1366.0);
        assert_eq!(xyz.scaled(0.5), Xyz::new(0.25, 1.0, 0.05));
    }
}
