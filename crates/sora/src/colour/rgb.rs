//! RGB colour spaces (XYZ <-> linear RGB) and transfer curves (linear RGB ->
//! display-encoded values).
//!
//! # Colour spaces
//! A linear RGB space is a 3×3 matrix from XYZ, fixed by three primaries and
//! a white point (the white maps to R = G = B = 1 at Y = 1). Two are offered:
//!
//! - [`RgbColourSpace::Srgb`] (the default): IEC 61966-2-1:1999, Rec. 709
//!   primaries (0.64, 0.33), (0.30, 0.60), (0.15, 0.06), D65 white
//!   (0.3127, 0.3290). The matrix is the standard's published one, to four
//!   decimals:
//!   ```text
//!   R =  3.2406 X - 1.5372 Y - 0.4986 Z
//!   G = -0.9689 X + 1.8758 Y + 0.0415 Z
//!   B =  0.0557 X - 0.2040 Y + 1.0570 Z
//!   ```
//!   Why the published matrix and not the one derived exactly from the
//!   primaries and white: the project's reference (linear sRGB of the
//!   clear-sky case (a) spectra, `tests/data/sky_case_a_xyz_srgb.csv`) was
//!   made with it; it reproduces the reference to 3e-9 relative, whereas the
//!   exactly derived matrix (3.24097, -1.53738, -0.49861, ...) is off by up
//!   to 1.8e-4. The difference is invisible in 8 or 16 bits.
//! - [`RgbColourSpace::PaperSmpteC`]: the paper's eq. 6, SMPTE-C primaries
//!   (SMPTE RP 145: (0.630, 0.340), (0.310, 0.595), (0.155, 0.070)) with a
//!   D65 white:
//!   ```text
//!   R =  3.5064 X - 1.7400 Y - 0.5441 Z
//!   G = -1.0690 X + 1.9777 Y + 0.0352 Z
//!   B =  0.0564 X - 0.1970 Y + 1.0511 Z
//!   ```
//!   kept exactly as printed. It is the SMPTE-C/D65 matrix to about 1e-3
//!   (the exact one has 3.5060 and 1.0500): D65 maps to (1.0001, 1.0000,
//!   1.0013) instead of (1, 1, 1).
//!
//! The inverse matrices (linear RGB -> XYZ) are computed from these at
//! compile time, so XYZ -> RGB -> XYZ round-trips to rounding error, rather
//! than taken from the standard's separately rounded RGB -> XYZ table (which
//! inverts the forward one only to 1e-4). Linear RGB may be negative (outside
//! the gamut) or above 1 (brighter than the white): it is scene-referred,
//! what an HDR (OpenEXR) file stores. Mapping it into [0, 1] is
//! [`crate::colour::GamutMapping`]'s job.
//!
//! # Transfer curves
//! A [`TransferCurve`] maps a linear component L in [0, 1] to the encoded
//! value V in [0, 1] a display expects:
//! - [`TransferCurve::Srgb`], IEC 61966-2-1:
//!   V = 12.92 L for L <= 0.0031308, V = 1.055 L^(1/2.4) - 0.055 above;
//!   inverse L = V / 12.92 for V <= 0.04045, ((V + 0.055) / 1.055)^2.4
//!   above. With the published constants the two pieces miss each other by
//!   2.9e-8 in V at the break, and the thresholds do not quite correspond,
//!   so the round trips are inexact in two tiny windows: decode(encode(L))
//!   is off by up to 2.4e-9 for L in (0.0031308, 0.0031308073], and
//!   encode(decode(V)) by up to 3.0e-8 for V in (0.040449936, 0.04045].
//!   Everywhere else both are exact to rounding. (No 8- or 16-bit level
//!   falls in the V window: 10/255 and 11/255 are 0.0392 and 0.0431.)
//! - [`TransferCurve::ScaledPower`], the paper's eq. 6: V = k L^(1/γ), so
//!   that the paper's 0-255 value is 255 V. The paper names k ("定数") and
//!   γ ("ガンマ補正値") but gives no values; [`ScaledPower::PAPER_DEFAULT`]
//!   is k = 1 (exposure is set by [`crate::colour::Exposure`] instead) and
//!   γ = 2.2, the display gamma of the NTSC / SMPTE-C era (SMPTE 170M
//!   encodes with the exponent 0.45 ≈ 1/2.2).
//!
//! Negative inputs (which gamut mapping removes before encoding) encode to 0,
//! so no curve ever produces a NaN.

use std::fmt;
use std::str::FromStr;

use crate::colour::xyz::Xyz;
use crate::error::{Error, Result};

/// A 3×3 matrix, row-major: `m[row][column]`.
pub type Matrix3 = [[f64; 3]; 3];

/// IEC 61966-2-1 XYZ -> linear sRGB, as published (four decimals).
const SRGB_FROM_XYZ: Matrix3 = [
    [3.2406, -1.5372, -0.4986],
    [-0.9689, 1.8758, 0.0415],
    [0.0557, -0.2040, 1.0570],
];
const XYZ_FROM_SRGB: Matrix3 = inverse(&SRGB_FROM_XYZ);

/// The paper's eq. 6: XYZ -> linear RGB with SMPTE-C primaries, D65 white.
const PAPER_SMPTE_C_FROM_XYZ: Matrix3 = [
    [3.5064, -1.7400, -0.5441],
    [-1.0690, 1.9777, 0.0352],
    [0.0564, -0.1970, 1.0511],
];
const XYZ_FROM_PAPER_SMPTE_C: Matrix3 = inverse(&PAPER_SMPTE_C_FROM_XYZ);

/// `m v`.
const fn multiply(m: &Matrix3, v: [f64; 3]) -> [f64; 3] {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

/// The inverse of `m` by cofactors (adjugate / determinant); used at compile
/// time on the colour-space matrices, which are far from singular.
const fn inverse(m: &Matrix3) -> Matrix3 {
    // The 2×2 determinant of rows r0, r1 and columns c0, c1 (closures
    // cannot be called in a const fn).
    const fn minor(m: &Matrix3, r0: usize, r1: usize, c0: usize, c1: usize) -> f64 {
        m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]
    }
    let c00 = minor(m, 1, 2, 1, 2);
    let c01 = -minor(m, 1, 2, 0, 2);
    let c02 = minor(m, 1, 2, 0, 1);
    let determinant = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
    let inverse_determinant = 1.0 / determinant;
    // The inverse is the transposed cofactor matrix over the determinant.
    [
        [
            c00 * inverse_determinant,
            -minor(m, 0, 2, 1, 2) * inverse_determinant,
            minor(m, 0, 1, 1, 2) * inverse_determinant,
        ],
        [
            c01 * inverse_determinant,
            minor(m, 0, 2, 0, 2) * inverse_determinant,
            -minor(m, 0, 1, 0, 2) * inverse_determinant,
        ],
        [
            c02 * inverse_determinant,
            -minor(m, 0, 2, 0, 1) * inverse_determinant,
            minor(m, 0, 1, 0, 1) * inverse_determinant,
        ],
    ]
}

/// Linear (scene-referred) RGB in some [`RgbColourSpace`]; 1 is the white's
/// value at Y = 1, components may be negative or above 1.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LinearRgb {
    /// Red.
    pub r: f64,
    /// Green.
    pub g: f64,
    /// Blue.
    pub b: f64,
}

impl LinearRgb {
    /// No light.
    pub const BLACK: LinearRgb = LinearRgb {
        r: 0.0,
        g: 0.0,
        b: 0.0,
    };

    /// The components (R, G, B).
    pub(crate) const fn new(r: f64, g: f64, b: f64) -> LinearRgb {
        LinearRgb { r, g, b }
    }

    /// `[R, G, B]`.
    pub(crate) const fn to_array(self) -> [f64; 3] {
        [self.r, self.g, self.b]
    }

    /// From `[R, G, B]`.
    pub(crate) const fn from_array([r, g, b]: [f64; 3]) -> LinearRgb {
        LinearRgb { r, g, b }
    }

    /// Every component multiplied by `factor`.
    pub(crate) fn scaled(self, factor: f64) -> LinearRgb {
        LinearRgb::new(self.r * factor, self.g * factor, self.b * factor)
    }

    /// The largest component.
    pub fn max_component(self) -> f64 {
        self.r.max(self.g).max(self.b)
    }

    /// The smallest component.
    pub(crate) fn min_component(self) -> f64 {
        self.r.min(self.g).min(self.b)
    }

    /// True when R, G and B are all finite.
    pub(crate) fn is_finite(self) -> bool {
        self.r.is_finite() && self.g.is_finite() && self.b.is_finite()
    }
}

/// A linear RGB colour space: primaries, white point, and the matrices to
/// and from XYZ (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum RgbColourSpace {
    /// IEC 61966-2-1 sRGB (Rec. 709 primaries, D65), the default.
    #[default]
    Srgb,
    /// The paper's eq. 6: SMPTE-C primaries, D65 white.
    PaperSmpteC,
}

impl RgbColourSpace {
    /// Every colour space, in the order of [`RgbColourSpace::NAMES`].
    pub const ALL: [RgbColourSpace; 2] = [RgbColourSpace::Srgb, RgbColourSpace::PaperSmpteC];

    /// The names accepted by [`FromStr`] (and written by [`fmt::Display`]).
    pub const NAMES: [&'static str; 2] = ["srgb", "paper-smpte-c"];

    /// The name as the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            RgbColourSpace::Srgb => RgbColourSpace::NAMES[0],
            RgbColourSpace::PaperSmpteC => RgbColourSpace::NAMES[1],
        }
    }

    /// The CIE 1931 chromaticities (x, y) of the red, green and blue
    /// primaries (for file metadata such as OpenEXR's `chromaticities`).
    #[cfg(test)]
    pub(crate) fn primaries_xy(self) -> [[f64; 2]; 3] {
        match self {
            RgbColourSpace::Srgb => [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]],
            RgbColourSpace::PaperSmpteC => [[0.630, 0.340], [0.310, 0.595], [0.155, 0.070]],
        }
    }

    /// The XYZ -> linear RGB matrix.
    pub(crate) fn linear_rgb_from_xyz_matrix(self) -> &'static Matrix3 {
        match self {
            RgbColourSpace::Srgb => &SRGB_FROM_XYZ,
            RgbColourSpace::PaperSmpteC => &PAPER_SMPTE_C_FROM_XYZ,
        }
    }

    /// The linear RGB -> XYZ matrix, the exact inverse of
    /// [`RgbColourSpace::linear_rgb_from_xyz_matrix`].
    pub(crate) fn xyz_from_linear_rgb_matrix(self) -> &'static Matrix3 {
        match self {
            RgbColourSpace::Srgb => &XYZ_FROM_SRGB,
            RgbColourSpace::PaperSmpteC => &XYZ_FROM_PAPER_SMPTE_C,
        }
    }

    /// Linear RGB of `xyz` (same scale: Y = 1 white -> RGB = 1), unclamped.
    pub fn linear_rgb_from_xyz(self, xyz: Xyz) -> LinearRgb {
        LinearRgb::from_array(multiply(self.linear_rgb_from_xyz_matrix(), xyz.to_array()))
    }

    /// XYZ of linear RGB `rgb`.
    #[cfg(test)]
    pub(crate) fn xyz_from_linear_rgb(self, rgb: LinearRgb) -> Xyz {
        Xyz::from_array(multiply(self.xyz_from_linear_rgb_matrix(), rgb.to_array()))
    }

    /// The luminance coefficients: Y = c_r R + c_g G + c_b B (the Y row of
    /// the RGB -> XYZ matrix; for sRGB about 0.2126, 0.7152, 0.0722).
    pub(crate) fn luminance_coefficients(self) -> [f64; 3] {
        self.xyz_from_linear_rgb_matrix()[1]
    }

    /// The luminance Y of linear RGB `rgb`, in the unit of the XYZ it came from.
    pub(crate) fn luminance(self, rgb: LinearRgb) -> f64 {
        let [cr, cg, cb] = self.luminance_coefficients();
        cr * rgb.r + cg * rgb.g + cb * rgb.b
    }
}

impl fmt::Display for RgbColourSpace {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for RgbColourSpace {
    type Err = Error;

    /// Parses `srgb` or `paper-smpte-c`; the error lists both.
    fn from_str(text: &str) -> Result<RgbColourSpace> {
        let text = text.trim();
        RgbColourSpace::ALL
            .into_iter()
            .find(|space| space.name() == text)
            .ok_or_else(|| {
                Error::parse(
                    "RGB colour space",
                    0,
                    format!(
                        "unknown colour space '{text}'; valid names: {}",
                        RgbColourSpace::NAMES.join(", ")
                    ),
                )
            })
    }
}

/// The paper's transfer curve V = k L^(1/γ) (eq. 6), with k > 0 and γ > 0
/// checked on construction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScaledPower {
    k: f64,
    gamma: f64,
}

impl ScaledPower {
    /// k = 1, γ = 2.2 (the paper gives no values; see the module docs).
    pub const PAPER_DEFAULT: ScaledPower = ScaledPower { k: 1.0, gamma: 2.2 };

    /// The curve V = k L^(1/γ). Fails unless k and γ are finite and > 0.
    pub(crate) fn new(k: f64, gamma: f64) -> Result<ScaledPower> {
        if !(k.is_finite() && k > 0.0) {
            return Err(Error::out_of_range("k", k, "1", "> 0 and finite"));
        }
        if !(gamma.is_finite() && gamma > 0.0) {
            return Err(Error::out_of_range("gamma", gamma, "1", "> 0 and finite"));
        }
        Ok(ScaledPower { k, gamma })
    }

    /// The scale k (dimensionless).
    pub(crate) fn k(self) -> f64 {
        self.k
    }

    /// The exponent γ (dimensionless); the curve raises to 1/γ.
    pub(crate) fn gamma(self) -> f64 {
        self.gamma
    }
}

/// A curve from linear light to display-encoded values (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum TransferCurve {
    /// IEC 61966-2-1 sRGB: linear toe, then 1.055 L^(1/2.4) - 0.055.
    #[default]
    Srgb,
    /// The paper's eq. 6: k L^(1/γ).
    ScaledPower(ScaledPower),
}

impl TransferCurve {
    /// The encoded value V of linear component `linear` (both dimensionless,
    /// 1 = white); negative input gives 0. Not clamped above: values over 1
    /// encode over 1.
    pub fn encode(self, linear: f64) -> f64 {
        let linear = linear.max(0.0);
        match self {
            TransferCurve::Srgb => {
                if linear <= 0.0031308 {
                    12.92 * linear
                } else {
                    1.055 * linear.powf(1.0 / 2.4) - 0.055
                }
            }
            TransferCurve::ScaledPower(curve) => curve.k * linear.powf(1.0 / curve.gamma),
        }
    }

    /// The linear component of encoded value `encoded`, the inverse of
    /// [`TransferCurve::encode`] (negative input gives 0).
    #[cfg(test)]
    pub(crate) fn decode(self, encoded: f64) -> f64 {
        let encoded = encoded.max(0.0);
        match self {
            TransferCurve::Srgb => {
                if encoded <= 0.04045 {
                    encoded / 12.92
                } else {
                    ((encoded + 0.055) / 1.055).powf(2.4)
                }
            }
            TransferCurve::ScaledPower(curve) => (encoded / curve.k).powf(curve.gamma),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_close(got: [f64; 3], want: [f64; 3], tolerance: f64) {
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() <= tolerance, "{got:?} vs {want:?}");
        }
    }

    #[test]
    fn inverses_are_inverses() {
        for space in RgbColourSpace::ALL {
            let forward = space.linear_rgb_from_xyz_matrix();
            let backward = space.xyz_from_linear_rgb_matrix();
            for unit in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
                assert_close(multiply(forward, multiply(backward, unit)), unit, 1e-15);
                assert_close(multiply(backward, multiply(forward, unit)), unit, 1e-15);
            }
        }
    }

    #[test]
    fn srgb_inverse_is_close_to_the_published_rgb_to_xyz_matrix() {
        // IEC 61966-2-1's own (four-decimal) linear sRGB -> XYZ matrix.
        let published = [
            [0.4124, 0.3576, 0.1805],
            [0.2126, 0.7152, 0.0722],
            [0.0193, 0.1192, 0.9505],
        ];
        for (row, published_row) in XYZ_FROM_SRGB.iter().zip(published) {
            assert_close(*row, published_row, 6e-5);
        }
    }

    #[test]
    fn d65_white_maps_to_equal_rgb() {
        // D65 at Y = 1 from its chromaticity (0.3127, 0.3290).
        let d65 = Xyz::new(0.3127 / 0.3290, 1.0, (1.0 - 0.3127 - 0.3290) / 0.3290);
        let srgb = RgbColourSpace::Srgb.linear_rgb_from_xyz(d65).to_array();
        assert_close(srgb, [1.0, 1.0, 1.0], 2e-4);
        // The paper's matrix is the SMPTE-C one only to about 1e-3.
        let paper = RgbColourSpace::PaperSmpteC
            .linear_rgb_from_xyz(d65)
            .to_array();
        assert_close(paper, [1.000_122, 0.999_997, 1.001_314], 1e-6);
    }

    #[test]
    fn paper_matrix_matches_smpte_c_primaries_to_the_printed_precision() {
        // Each primary's XYZ (the inverse's columns) has the primary's chromaticity.
        let space = RgbColourSpace::PaperSmpteC;
        for (column, [x, y]) in space.primaries_xy().into_iter().enumerate() {
            let m = space.xyz_from_linear_rgb_matrix();
            let xyz = Xyz::new(m[0][column], m[1][column], m[2][column]);
            let [cx, cy] = xyz.chromaticity_xy().unwrap();
            assert!((cx - x).abs() < 1e-3 && (cy - y).abs() < 1e-3, "{cx} {cy}");
        }
    }

    #[test]
    fn luminance_coefficients_are_the_rec709_ones() {
        let [r, g, b] = RgbColourSpace::Srgb.luminance_coefficients();
        assert_close([r, g, b], [0.2126, 0.7152, 0.0722], 6e-5);
        let rgb = LinearRgb::new(0.2, 0.5, 0.9);
        let xyz = RgbColourSpace::Srgb.xyz_from_linear_rgb(rgb);
        assert!((RgbColourSpace::Srgb.luminance(rgb) - xyz.y).abs() < 1e-15);
    }

    #[test]
    fn srgb_curve_matches_the_iec_formula() {
        let curve = TransferCurve::Srgb;
        assert_eq!(curve.encode(0.0), 0.0);
        assert!((curve.encode(0.001) - 0.01292).abs() < 1e-17);
        assert!((curve.encode(1.0) - 1.0).abs() < 1e-15);
        assert!((curve.encode(0.18) - 0.461_356_129_500_441_6).abs() < 1e-15);
        assert_eq!(curve.encode(-0.5), 0.0);
        assert_eq!(curve.decode(-0.5), 0.0);
        assert!((curve.decode(0.5) - 0.214_041_140_482_232_5).abs() < 1e-15);
    }

    /// The documented windows where the published constants make the sRGB
    /// curve non-invertible.
    const LINEAR_WINDOW: (f64, f64) = (0.0031308, 0.0031308073);
    const ENCODED_WINDOW: (f64, f64) = (0.040449936, 0.04045);

    fn inside(value: f64, (low, high): (f64, f64)) -> bool {
        value > low && value <= high
    }

    #[test]
    fn srgb_curve_round_trips_outside_the_documented_windows() {
        let curve = TransferCurve::Srgb;
        // A dense sweep, plus points straddling both windows' ends.
        let mut values: Vec<f64> = (0..=20_000).map(|i| f64::from(i) / 20_000.0).collect();
        for edge in [
            LINEAR_WINDOW.0,
            LINEAR_WINDOW.1,
            ENCODED_WINDOW.0,
            ENCODED_WINDOW.1,
        ] {
            values.extend([-2e-10, -1e-12, 0.0, 1e-12, 2e-10].map(|d| edge + d));
        }
        for value in values {
            let error = (curve.decode(curve.encode(value)) - value).abs();
            let bound = if inside(value, LINEAR_WINDOW) {
                2.4e-9
            } else {
                2e-16 + 1e-15 * value
            };
            assert!(error <= bound, "L = {value}: {error:e}");
            let error = (curve.encode(curve.decode(value)) - value).abs();
            let bound = if inside(value, ENCODED_WINDOW) {
                3.0e-8
            } else {
                2e-16 + 1e-15 * value
            };
            assert!(error <= bound, "V = {value}: {error:e}");
        }
    }

    #[test]
    fn srgb_curve_windows_are_real() {
        // The documented inexactness is there (the bounds above are not slack).
        let curve = TransferCurve::Srgb;
        let linear = 0.0031308 + 1e-9;
        assert!((curve.decode(curve.encode(linear)) - linear).abs() > 2e-9);
        let encoded = 0.04045;
        assert!((curve.encode(curve.decode(encoded)) - encoded).abs() > 2.9e-8);
    }

    #[test]
    fn paper_curve_is_k_times_a_power() {
        let curve = TransferCurve::ScaledPower(ScaledPower::new(0.8, 2.0).unwrap());
        assert_eq!(curve.encode(0.25), 0.4);
        assert_eq!(curve.encode(-1.0), 0.0);
        assert!((curve.decode(0.4) - 0.25).abs() < 1e-16);
        let default = TransferCurve::ScaledPower(ScaledPower::PAPER_DEFAULT);
        assert!((default.encode(0.5) - 0.5f64.powf(1.0 / 2.2)).abs() < 1e-16);
        assert!(ScaledPower::new(0.0, 2.2).is_err());
        assert!(ScaledPower::new(1.0, f64::NAN).is_err());
        let message = ScaledPower::new(1.0, -2.0).unwrap_err().to_string();
        assert!(message.contains("gamma = -2"), "{message}");
    }

    #[test]
    fn colour_space_names_round_trip_and_errors_list_them() {
        for space in RgbColourSpace::ALL {
            assert_eq!(space.to_string().parse::<RgbColourSpace>().unwrap(), space);
        }
        let message = "adobe-rgb"
            .parse::<RgbColourSpace>()
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("srgb") && message.contains("paper-smpte-c"),
            "{message}"
        );
    }
}
