//! Colour: spectral radiance -> CIE XYZ -> RGB -> display values (the
//! paper's §4, "光強度 → 等色関数 → CIE XYZ → 式6 → RGB").
//!
//! # The pipeline
//! 1. **Spectrum -> XYZ** ([`SpectrumToXyz`], `xyz.rs`): on the computation's
//!    [`crate::spectrum::WavelengthGrid`], X = Σ_i L(λ_i) x̄(λ_i) Δλ_i and
//!    likewise Y, Z, with the CIE 1931 2-degree colour-matching functions
//!    (CIE 015:2018; the paper's, via JIS Z 8701) or optionally the CIE 1964
//!    10-degree ones ([`Observer`], [`ColourMatchingFunctions`],
//!    `colour_matching.rs`). Δλ_i is the grid's quadrature weight: the
//!    paper's 20 nm on its 380-780 nm grid. No 683 lm/W factor: XYZ are in
//!    the radiance's unit × nm, and luminance in cd/m^2 is 683 × Y for
//!    radiance in W m^-2 sr^-1 nm^-1 ([`Xyz::luminance_cd_m2`]). Spectra with
//!    NaN, infinite or negative samples are rejected here, naming the sample.
//! 2. **XYZ -> linear RGB** ([`RgbColourSpace`], `rgb.rs`): sRGB's
//!    IEC 61966-2-1 matrix by default; the paper's eq. 6 SMPTE-C/D65 matrix
//!    as an option. Linear RGB (and XYZ) are scene-referred and unbounded,
//!    for HDR (OpenEXR) output.
//! 3. **Exposure** ([`Exposure`], `exposure.rs`): one factor per image: fixed,
//!    or automatic (the image's log-average luminance over its non-black
//!    pixels maps to the key 0.18).
//! 4. **Gamut and range** ([`GamutMapping`], `gamut.rs`): negative
//!    components (out of gamut) and components above 1 (over range) are
//!    either clipped per channel, or handled hue-preservingly (desaturate at
//!    constant luminance until nothing is negative, then scale down by the
//!    largest component), and by default then moved toward white where they
//!    were brighter than white (the sun's core shows white).
//! 5. **Encoding** ([`DisplayEncoding`], `display.rs`): the transfer curve
//!    (sRGB's, or the paper's k L^(1/γ)) and rounding to 8 or 16 bits,
//!    `round(V × 255)` / `round(V × 65535)`. [`DisplayMapping`] runs steps 2-5
//!    on a whole image.
//!
//! # Conventions
//! Wavelengths in nm; XYZ with Y the luminance-like component, in display
//! units (white Y = 1) from step 3 on; linear RGB with the colour space's
//! white (D65) at R = G = B = 1 when Y = 1. Every name the command line
//! accepts (`cie1931-2deg`, `srgb`, `paper-smpte-c`, `highlights-to-white`, `auto`)
//! parses with [`std::str::FromStr`], and an unknown name gets an error listing
//! the valid ones.
//!
//! # Validation against references (`colour/reference_tests.rs`)
//! - CIE D65 on 380-780 nm every 5 nm (CIE 015's abridged range and step)
//!   gives the CIE white point (95.04, 100, 108.88) with the 2-degree observer
//!   and (94.81, 100, 107.32) with the 10-degree one, and sRGB (1, 1, 1).
//! - The clear-sky case (a) spectra give the XYZ and linear sRGB of an
//!   independent computation to 1e-5 relative.
//!
//! Sources: CIE 015:2018 *Colorimetry*, 4th ed. (colour-matching functions,
//! tristimulus sums); IEC 61966-2-1:1999 (sRGB); SMPTE RP 145 (SMPTE-C
//! primaries); Nakai & Sakai, eq. 6 (see `../shared/paper/NOTES.md`);
//! Reinhard et al. 2002 (log-average exposure).

mod colour_matching;
mod display;
mod exposure;
mod gamut;
#[cfg(test)]
mod reference_tests;
mod rgb;
mod xyz;

pub use colour_matching::{
    CIE_MAX_WAVELENGTH_NM, CIE_MIN_WAVELENGTH_NM, ColourMatchingFunctions, Observer,
};
pub use display::{DisplayEncoding, DisplayMapping};
pub use exposure::{Exposure, NIGHT_FLOOR_CD_M2, apply_night_floor};
pub use gamut::GamutMapping;
pub use rgb::{LinearRgb, Matrix3, RgbColourSpace, ScaledPower, TransferCurve};
pub use xyz::{MAXIMUM_LUMINOUS_EFFICACY_LM_PER_W, SpectrumToXyz, Xyz};
