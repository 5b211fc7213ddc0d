//! The display stage: an image of XYZ -> 8- or 16-bit display values, and
//! the named encodings the image writer and the command line choose from.
//!
//! Per image, in this order ([`DisplayMapping`]):
//! 1. exposure: one scale for the whole image ([`Exposure`]) multiplies XYZ;
//! 2. XYZ -> linear RGB with the encoding's matrix ([`RgbColourSpace`]);
//! 3. gamut and range mapping into [0, 1]^3 ([`GamutMapping`]);
//! 4. the encoding's transfer curve ([`TransferCurve`]), V in [0, 1];
//! 5. quantisation: `round(V × 255)` to `u8`, `round(V × 65535)` to `u16`,
//!    V first clamped to [0, 1] (the paper's k > 1 can push V above 1);
//!    `round` is round-half-away-from-zero (`f64::round`), so the levels are
//!    the nearest ones, equally spaced, 0 and 1 exactly reachable.
//!
//! The encodings ([`DisplayEncoding`], by name):
//! - `srgb` (the default): IEC 61966-2-1 matrix and transfer curve;
//! - `paper-smpte-c`: the paper's eq. 6, R = k × 255 × (linear R)^(1/γ) with
//!   its SMPTE-C/D65 matrix; k = 1, γ = 2.2 unless given as
//!   `paper-smpte-c:k=<k>,gamma=<γ>` (either or both, any order).
//!
//! HDR output skips steps 3-5: linear RGB (from
//! [`RgbColourSpace::linear_rgb_from_xyz`], possibly after an exposure scale)
//! or XYZ itself goes to OpenEXR unclamped.

use std::fmt;
use std::str::FromStr;

use crate::colour::exposure::Exposure;
use crate::colour::gamut::GamutMapping;
use crate::colour::rgb::{LinearRgb, RgbColourSpace, ScaledPower, TransferCurve};
use crate::colour::xyz::Xyz;
use crate::error::{Error, Result, format_number};

/// A display encoding: an RGB colour space and its transfer curve.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum DisplayEncoding {
    /// IEC 61966-2-1 sRGB: its matrix and its transfer curve (the default).
    #[default]
    Srgb,
    /// The paper's eq. 6: SMPTE-C/D65 matrix, then k × L^(1/γ).
    PaperSmpteC(ScaledPower),
}

impl DisplayEncoding {
    /// The names accepted by [`FromStr`] (`paper-smpte-c` also with
    /// `:k=<k>,gamma=<γ>`).
    pub const NAMES: [&'static str; 2] = ["srgb", "paper-smpte-c"];

    /// The paper's encoding with k = 1 and γ = 2.2.
    pub const PAPER_DEFAULT: DisplayEncoding =
        DisplayEncoding::PaperSmpteC(ScaledPower::PAPER_DEFAULT);

    /// The paper's encoding with scale `k` and gamma `gamma` (both > 0).
    pub(crate) fn paper_smpte_c(k: f64, gamma: f64) -> Result<DisplayEncoding> {
        Ok(DisplayEncoding::PaperSmpteC(ScaledPower::new(k, gamma)?))
    }

    /// The encoding's name, without parameters.
    pub(crate) fn name(self) -> &'static str {
        match self {
            DisplayEncoding::Srgb => DisplayEncoding::NAMES[0],
            DisplayEncoding::PaperSmpteC(_) => DisplayEncoding::NAMES[1],
        }
    }

    /// The colour space whose linear RGB is encoded.
    pub fn colour_space(self) -> RgbColourSpace {
        match self {
            DisplayEncoding::Srgb => RgbColourSpace::Srgb,
            DisplayEncoding::PaperSmpteC(_) => RgbColourSpace::PaperSmpteC,
        }
    }

    /// The transfer curve from linear components to encoded values.
    pub(crate) fn transfer_curve(self) -> TransferCurve {
        match self {
            DisplayEncoding::Srgb => TransferCurve::Srgb,
            DisplayEncoding::PaperSmpteC(curve) => TransferCurve::ScaledPower(curve),
        }
    }

    /// The encoded value in [0, 1] of linear component `linear` (clamped
    /// after the curve).
    fn encoded_unit(self, linear: f64) -> f64 {
        self.transfer_curve().encode(linear).clamp(0.0, 1.0)
    }

    /// 8-bit display values of `rgb` (linear, normally already in [0, 1]^3
    /// after gamut mapping): round(255 × V) per component.
    pub(crate) fn encode_u8(self, rgb: LinearRgb) -> [u8; 3] {
        // The clamp keeps the product in 0..=255, so the cast is exact.
        rgb.to_array()
            .map(|linear| (self.encoded_unit(linear) * 255.0).round() as u8)
    }

    /// 16-bit display values of `rgb`: round(65535 × V) per component.
    pub(crate) fn encode_u16(self, rgb: LinearRgb) -> [u16; 3] {
        rgb.to_array()
            .map(|linear| (self.encoded_unit(linear) * 65535.0).round() as u16)
    }
}

impl fmt::Display for DisplayEncoding {
    /// The name, with `:k=..,gamma=..` when the paper's parameters are not
    /// the defaults; parses back to the same encoding.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DisplayEncoding::PaperSmpteC(curve) if *curve != ScaledPower::PAPER_DEFAULT => {
                write!(f, "{}:k={},gamma={}", self.name(), curve.k(), curve.gamma())
            }
            _ => f.write_str(self.name()),
        }
    }
}

impl FromStr for DisplayEncoding {
    type Err = Error;

    /// Parses `srgb`, `paper-smpte-c` or `paper-smpte-c:k=<k>,gamma=<γ>`;
    /// an unknown name gives an error listing the valid ones.
    fn from_str(text: &str) -> Result<DisplayEncoding> {
        let what = "display encoding";
        let text = text.trim();
        let (name, parameters) = match text.split_once(':') {
            Some((name, parameters)) => (name.trim(), Some(parameters)),
            None => (text, None),
        };
        match (name, parameters) {
            ("srgb", None) => Ok(DisplayEncoding::Srgb),
            ("srgb", Some(_)) => Err(Error::parse(
                what,
                0,
                format!("'{text}': srgb takes no parameters"),
            )),
            ("paper-smpte-c", parameters) => {
                let (mut k, mut gamma) = (1.0, 2.2);
                for assignment in parameters.into_iter().flat_map(|p| p.split(',')) {
                    let value_of = |value: &str| {
                        value.trim().parse::<f64>().map_err(|_| {
                            Error::parse(
                                what,
                                0,
                                format!("'{text}': '{}' is not a number", value.trim()),
                            )
                        })
                    };
                    match assignment.split_once('=').map(|(n, v)| (n.trim(), v)) {
                        Some(("k", value)) => k = value_of(value)?,
                        Some(("gamma", value)) => gamma = value_of(value)?,
                        _ => {
                            return Err(Error::parse(
                                what,
                                0,
                                format!(
                                    "'{text}': expected parameters k=<number>,gamma=<number>, found '{}'",
                                    assignment.trim()
                                ),
                            ));
                        }
                    }
                }
                DisplayEncoding::paper_smpte_c(k, gamma)
            }
            _ => Err(Error::parse(
                what,
                0,
                format!(
                    "unknown display encoding '{text}'; valid names: {} (paper-smpte-c:k=<k>,gamma=<gamma> to set the paper's k and gamma)",
                    DisplayEncoding::NAMES.join(", ")
                ),
            )),
        }
    }
}

/// The whole display stage: exposure, gamut mapping and encoding (see the
/// module docs). The default is automatic exposure (key 0.18), the
/// highlights-to-white gamut mapping and sRGB.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DisplayMapping {
    /// How bright the picture is.
    pub exposure: Exposure,
    /// What happens to colours outside the display's gamut.
    pub gamut_mapping: GamutMapping,
    /// The RGB space and transfer curve of the file.
    pub encoding: DisplayEncoding,
}

impl DisplayMapping {
    /// Linear RGB in [0, 1]^3 of every pixel of `image` (XYZ, any scale), in
    /// the encoding's colour space, after exposure and gamut mapping: the
    /// values the transfer curve is applied to.
    ///
    /// Fails if the exposure is invalid, or if a pixel is not finite before
    /// or after exposure (the error names the pixel's index).
    pub(crate) fn display_linear_rgb(&self, image: &[Xyz]) -> Result<Vec<LinearRgb>> {
        let scale = self.exposure.scale_for_image(image)?;
        let colour_space = self.encoding.colour_space();
        image
            .iter()
            .enumerate()
            .map(|(index, xyz)| {
                let rgb = colour_space.linear_rgb_from_xyz(xyz.scaled(scale));
                if !rgb.is_finite() {
                    return Err(Error::InvalidSpectrum(format!(
                        "pixel {index}: XYZ ({}, {}, {}) times exposure {} is not finite in RGB; give a smaller --exposure",
                        format_number(xyz.x),
                        format_number(xyz.y),
                        format_number(xyz.z),
                        format_number(scale)
                    )));
                }
                Ok(self.gamut_mapping.apply(rgb, colour_space))
            })
            .collect()
    }

    /// 8-bit display values of every pixel of `image`, `[R, G, B]` per pixel.
    pub fn to_u8(&self, image: &[Xyz]) -> Result<Vec<[u8; 3]>> {
        let encoding = self.encoding;
        Ok(self
            .display_linear_rgb(image)?
            .into_iter()
            .map(|rgb| encoding.encode_u8(rgb))
            .collect())
    }

    /// 16-bit display values of every pixel of `image`, `[R, G, B]` per pixel.
    pub fn to_u16(&self, image: &[Xyz]) -> Result<Vec<[u16; 3]>> {
        let encoding = self.encoding;
        Ok(self
            .display_linear_rgb(image)?
            .into_iter()
            .map(|rgb| encoding.encode_u16(rgb))
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_bytes_of_the_iec_curve() {
        // V = 12.92 × 0.0031308 = 0.04045 -> 10.31; 0.18 -> 0.46136 -> 117.65;
        // 0.5 -> 0.73536 -> 187.52 (IEC 61966-2-1 eq. 5-6).
        let srgb = DisplayEncoding::Srgb;
        let bytes: Vec<u8> = [0.0, 0.0031308, 0.18, 0.5, 1.0]
            .into_iter()
            .map(|v| srgb.encode_u8(LinearRgb::new(v, v, v))[0])
            .collect();
        assert_eq!(bytes, [0, 10, 118, 188, 255]);
        let words: Vec<u16> = [0.0, 0.0031308, 0.18, 0.5, 1.0]
            .into_iter()
            .map(|v| srgb.encode_u16(LinearRgb::new(v, v, v))[0])
            .collect();
        assert_eq!(words, [0, 2651, 30235, 48192, 65535]);
        // Out-of-range input saturates instead of wrapping.
        assert_eq!(srgb.encode_u8(LinearRgb::new(-1.0, 2.0, 0.0)), [0, 255, 0]);
    }

    #[test]
    fn paper_bytes_are_k_255_lin_to_one_over_gamma() {
        let paper = DisplayEncoding::paper_smpte_c(0.9, 2.0).unwrap();
        // 0.9 × 255 × 0.25^(1/2) = 114.75 -> 115.
        assert_eq!(
            paper.encode_u8(LinearRgb::new(0.25, 0.0, 1.0)),
            [115, 0, 230]
        );
        let bright = DisplayEncoding::paper_smpte_c(2.0, 2.2).unwrap();
        assert_eq!(
            bright.encode_u8(LinearRgb::new(1.0, 0.5, 0.0))[..2],
            [255, 255]
        );
    }

    #[test]
    fn encoding_names_parse_print_and_list() {
        assert_eq!(
            "srgb".parse::<DisplayEncoding>().unwrap(),
            DisplayEncoding::Srgb
        );
        assert_eq!(
            "paper-smpte-c".parse::<DisplayEncoding>().unwrap(),
            DisplayEncoding::PAPER_DEFAULT
        );
        let custom: DisplayEncoding = "paper-smpte-c:gamma=1.8, k=0.5".parse().unwrap();
        assert_eq!(custom, DisplayEncoding::paper_smpte_c(0.5, 1.8).unwrap());
        for encoding in [
            DisplayEncoding::Srgb,
            DisplayEncoding::PAPER_DEFAULT,
            custom,
        ] {
            assert_eq!(
                encoding.to_string().parse::<DisplayEncoding>().unwrap(),
                encoding
            );
        }
        assert_eq!(custom.to_string(), "paper-smpte-c:k=0.5,gamma=1.8");
        assert_eq!(custom.colour_space(), RgbColourSpace::PaperSmpteC);
        let message = "rec2020"
            .parse::<DisplayEncoding>()
            .unwrap_err()
            .to_string();
        assert!(message.contains("srgb, paper-smpte-c"), "{message}");
        for (text, expected) in [
            ("paper-smpte-c:gamma=x", "'x' is not a number"),
            ("paper-smpte-c:exposure=2", "found 'exposure=2'"),
            ("paper-smpte-c:gamma=0", "gamma = 0"),
            ("srgb:k=1", "no parameters"),
        ] {
            let message = text.parse::<DisplayEncoding>().unwrap_err().to_string();
            assert!(message.contains(expected), "{text}: {message}");
        }
    }

    #[test]
    fn pipeline_exposes_maps_and_encodes() {
        // Pixels of the sRGB matrix's own white (R = G = B at Y = 1; D65 to
        // 1e-4) at Y = 2 and 8: fixed exposure 1/8 puts the brighter one at
        // white and the other at a quarter.
        let d65 = RgbColourSpace::Srgb.xyz_from_linear_rgb(LinearRgb::new(1.0, 1.0, 1.0));
        let image = [d65.scaled(2.0), d65.scaled(8.0), Xyz::BLACK];
        let mapping = DisplayMapping {
            exposure: Exposure::Fixed(0.125),
            ..DisplayMapping::default()
        };
        let bytes = mapping.to_u8(&image).unwrap();
        // Linear 0.25 -> sRGB 0.5371 -> 136.96.
        assert_eq!(bytes, [[137, 137, 137], [255, 255, 255], [0, 0, 0]]);
        let words = mapping.to_u16(&image).unwrap();
        assert_eq!(words[1], [65535; 3]);
        assert_eq!(words[2], [0; 3]);
    }

    #[test]
    fn pipeline_rejects_non_finite_pixels() {
        let image = [Xyz::new(1.0, 1.0, 1.0), Xyz::new(f64::INFINITY, 1.0, 1.0)];
        for exposure in [Exposure::default(), Exposure::Fixed(1.0)] {
            let mapping = DisplayMapping {
                exposure,
                ..DisplayMapping::default()
            };
            let message = mapping.to_u8(&image).unwrap_err().to_string();
            assert!(message.contains("pixel 1"), "{message}");
        }
        // Finite XYZ that overflow once exposed.
        let mapping = DisplayMapping {
            exposure: Exposure::Fixed(1e300),
            ..DisplayMapping::default()
        };
        let message = mapping
            .to_u8(&[Xyz::new(1e10, 1e10, 1e10)])
            .unwrap_err()
            .to_string();
        assert!(message.contains("pixel 0"), "{message}");
        // Huge numbers in scientific notation, not 301 digits (issue 17).
        assert!(message.contains("exposure 1e300"), "{message}");
        assert!(message.contains("XYZ (1e10, 1e10, 1e10)"), "{message}");
        assert!(!message.contains("0000000000"), "{message}");
    }
}
