//! Bringing linear RGB into the displayable cube [0, 1]^3: out-of-gamut
//! colours (a negative component: more saturated than the primaries allow)
//! and over-range colours (a component above 1: brighter than the display's
//! white).
//!
//! Spectral skies produce both. Any spectrum narrower than the sRGB primaries
//! is out of gamut: per unit of its spectral radiance and nm, a monochromatic
//! 700 nm light is (R, G, B) = (0.0305, -0.0033, -0.0002), 400 nm is
//! (0.0119, -0.0103, 0.0724), both with a negative green; deep twilight blues
//! and sunset reds come close. And a sky exposed
//! for its average is over range near the sun.
//!
//! Three rules ([`GamutMapping`]), applied after exposure, per pixel:
//!
//! - [`GamutMapping::Clip`]: clamp each component to [0, 1] independently.
//!   Simple and what most renderers do, but it changes hue: an over-exposed
//!   blue sky (0.8, 1.1, 1.6) clips to (0.8, 1, 1), a cyan; an over-exposed
//!   sunset (2.0, 1.2, 0.5) to (1, 1, 0.5), a yellow.
//! - [`GamutMapping::PreserveHue`] (the default, because skies are large
//!   smooth gradients in which such hue shifts show as bands):
//!   1. if a component is negative, desaturate: move the colour c along the
//!      straight line toward the grey of the same luminance Y, g = Y / s ×
//!      (1, 1, 1) where s = c_r + c_g + c_b is the luminance of RGB
//!      (1, 1, 1): c' = g + t (c - g) with the largest t in [0, 1] that
//!      leaves no component negative, t = min over negative c_i of
//!      g / (g - c_i). The luminance is kept exactly, and the
//!      chromaticity moves on the straight line toward the white point, so
//!      the dominant wavelength (the CIE's hue) is kept; only the purity drops,
//!      to the gamut boundary. A colour with Y <= 0 has no displayable
//!      version and becomes black.
//!   2. if the largest component m exceeds 1, scale the whole colour by 1/m:
//!      chromaticity kept exactly, luminance reduced to what the display can
//!      show. Over-exposed areas keep their colour instead of turning white
//!      or changing hue.
//!
//! - [`GamutMapping::HighlightsToWhite`] (the default): preserve-hue, and
//!   then what a camera does with light brighter than its white: where
//!   step 2 scaled a colour down, it is moved on the straight line toward
//!   white, c'' = c' + t ((1, 1, 1) - c'), until its luminance is
//!   min(Y, Y_white) again, t = (min(Y, Y_white) - Y') / (Y_white - Y')
//!   (Y the luminance before step 2, Y' after, Y_white that of (1, 1, 1)).
//!   The dominant wavelength is kept and no component leaves [0, 1]; a
//!   colour at or beyond the display's white becomes white. So the sun's
//!   disc, thousands of times brighter than the sky, shows as the brightest
//!   thing in the picture, its core white, instead of a dim orange dot of
//!   luminance Y / m (preserve-hue's step 2 alone), and bright haze near the
//!   sun fades to white as in a photograph.
//!
//! No rule divides by zero: t's denominators g - c_i are > 0 (g >= 0 >
//! c_i), and the scaling only happens when m > 1. Black stays black.

use std::fmt;
use std::str::FromStr;

use crate::colour::rgb::{LinearRgb, RgbColourSpace};
use crate::error::{Error, Result};

/// How colours outside [0, 1]^3 are brought inside (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum GamutMapping {
    /// Clamp each component to [0, 1].
    Clip,
    /// Desaturate toward the grey of equal luminance until no component is
    /// negative, then scale down by the largest component if it exceeds 1.
    PreserveHue,
    /// Preserve-hue, then over-range colours toward white until their
    /// luminance is restored up to the display's white (the default).
    #[default]
    HighlightsToWhite,
}

impl GamutMapping {
    /// Every mapping, in the order of [`GamutMapping::NAMES`].
    pub const ALL: [GamutMapping; 3] = [
        GamutMapping::Clip,
        GamutMapping::PreserveHue,
        GamutMapping::HighlightsToWhite,
    ];

    /// The names accepted by [`FromStr`] (and written by [`fmt::Display`]).
    pub const NAMES: [&'static str; 3] = ["clip", "preserve-hue", "highlights-to-white"];

    /// The name as the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            GamutMapping::Clip => GamutMapping::NAMES[0],
            GamutMapping::PreserveHue => GamutMapping::NAMES[1],
            GamutMapping::HighlightsToWhite => GamutMapping::NAMES[2],
        }
    }

    /// `rgb` (linear, in `colour_space`, finite) brought into [0, 1]^3.
    /// The luminance of the grey that [`GamutMapping::PreserveHue`]
    /// desaturates toward is that of `colour_space`.
    pub(crate) fn apply(self, rgb: LinearRgb, colour_space: RgbColourSpace) -> LinearRgb {
        match self {
            GamutMapping::Clip => LinearRgb::new(
                rgb.r.clamp(0.0, 1.0),
                rgb.g.clamp(0.0, 1.0),
                rgb.b.clamp(0.0, 1.0),
            ),
            GamutMapping::PreserveHue => {
                let in_gamut = desaturate_into_gamut(rgb, colour_space);
                let largest = in_gamut.max_component();
                if largest > 1.0 {
                    in_gamut.scaled(1.0 / largest)
                } else {
                    in_gamut
                }
            }
            GamutMapping::HighlightsToWhite => {
                let in_gamut = desaturate_into_gamut(rgb, colour_space);
                let largest = in_gamut.max_component();
                if largest <= 1.0 {
                    return in_gamut;
                }
                let white: f64 = colour_space.luminance_coefficients().iter().sum();
                let target = colour_space.luminance(in_gamut).min(white);
                let scaled = in_gamut.scaled(1.0 / largest);
                let reduced = colour_space.luminance(scaled);
                let t = if white > reduced {
                    ((target - reduced) / (white - reduced)).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                LinearRgb::new(
                    scaled.r + t * (1.0 - scaled.r),
                    scaled.g + t * (1.0 - scaled.g),
                    scaled.b + t * (1.0 - scaled.b),
                )
            }
        }
    }
}

/// Step 1 of [`GamutMapping::PreserveHue`]: the least desaturation toward the
/// equal-luminance grey that leaves no component negative.
fn desaturate_into_gamut(rgb: LinearRgb, colour_space: RgbColourSpace) -> LinearRgb {
    if rgb.min_component() >= 0.0 {
        return rgb;
    }
    let luminance = colour_space.luminance(rgb);
    if luminance <= 0.0 {
        return LinearRgb::BLACK;
    }
    let white_luminance: f64 = colour_space.luminance_coefficients().iter().sum();
    let grey = luminance / white_luminance;
    let components = rgb.to_array();
    // The most negative component (relative to the grey) limits t; there is
    // one, since min_component < 0.
    let (limiting, t) = components
        .iter()
        .enumerate()
        .filter(|(_, c)| **c < 0.0)
        .map(|(i, c)| (i, grey / (grey - c)))
        .fold((0, 1.0), |best, candidate| {
            if candidate.1 < best.1 {
                candidate
            } else {
                best
            }
        });
    let mut mapped = components.map(|c| (grey + t * (c - grey)).max(0.0));
    // The limiting component lands on 0 up to rounding; make it exactly 0.
    mapped[limiting] = 0.0;
    LinearRgb::from_array(mapped)
}

impl fmt::Display for GamutMapping {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for GamutMapping {
    type Err = Error;

    /// Parses `clip`, `preserve-hue` or `highlights-to-white`; the error
    /// lists them.
    fn from_str(text: &str) -> Result<GamutMapping> {
        let text = text.trim();
        GamutMapping::ALL
            .into_iter()
            .find(|mapping| mapping.name() == text)
            .ok_or_else(|| {
                Error::parse(
                    "gamut mapping",
                    0,
                    format!(
                        "unknown gamut mapping '{text}'; valid names: {}",
                        GamutMapping::NAMES.join(", ")
                    ),
                )
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SRGB: RgbColourSpace = RgbColourSpace::Srgb;

    #[test]
    fn colours_inside_the_cube_are_unchanged() {
        let rgb = LinearRgb::new(0.0, 0.25, 1.0);
        for mapping in GamutMapping::ALL {
            assert_eq!(mapping.apply(rgb, SRGB), rgb);
            assert_eq!(mapping.apply(LinearRgb::BLACK, SRGB), LinearRgb::BLACK);
        }
    }

    #[test]
    fn clip_clamps_each_component() {
        let rgb = LinearRgb::new(-0.2, 0.5, 1.7);
        assert_eq!(
            GamutMapping::Clip.apply(rgb, SRGB),
            LinearRgb::new(0.0, 0.5, 1.0)
        );
    }

    #[test]
    fn preserve_hue_desaturates_at_constant_luminance() {
        for space in RgbColourSpace::ALL {
            let rgb = LinearRgb::new(0.5, -0.05, 0.02);
            let mapped = GamutMapping::PreserveHue.apply(rgb, space);
            assert_eq!(mapped.g, 0.0, "{mapped:?}");
            assert!(mapped.r > 0.0 && mapped.b > 0.0);
            let (before, after) = (space.luminance(rgb), space.luminance(mapped));
            assert!((after - before).abs() < 1e-15, "{before} -> {after}");
            // On the straight line toward grey: the differences between
            // components shrink by one common factor.
            let t = (mapped.r - mapped.b) / (rgb.r - rgb.b);
            assert!(((mapped.r - mapped.g) / (rgb.r - rgb.g) - t).abs() < 1e-12);
            assert!(t > 0.0 && t < 1.0);
        }
    }

    #[test]
    fn preserve_hue_scales_over_range_colours_by_their_maximum() {
        let rgb = LinearRgb::new(0.8, 1.1, 1.6);
        let mapped = GamutMapping::PreserveHue.apply(rgb, SRGB);
        assert_eq!(mapped.b, 1.0);
        assert!((mapped.r - 0.5).abs() < 1e-15 && (mapped.g - 1.1 / 1.6).abs() < 1e-15);
        // Both steps: out of gamut and over range.
        let mapped = GamutMapping::PreserveHue.apply(LinearRgb::new(3.0, -0.1, 0.4), SRGB);
        assert!((mapped.max_component() - 1.0).abs() < 1e-15, "{mapped:?}");
        assert_eq!(mapped.min_component(), 0.0);
    }

    #[test]
    fn colours_without_positive_luminance_become_black() {
        let rgb = LinearRgb::new(0.01, -0.5, 0.01);
        assert_eq!(GamutMapping::PreserveHue.apply(rgb, SRGB), LinearRgb::BLACK);
        assert_eq!(
            GamutMapping::Clip.apply(rgb, SRGB),
            LinearRgb::new(0.01, 0.0, 0.01)
        );
    }

    #[test]
    fn names_round_trip_and_errors_list_them() {
        for mapping in GamutMapping::ALL {
            assert_eq!(
                mapping.to_string().parse::<GamutMapping>().unwrap(),
                mapping
            );
        }
        // The default shows light brighter than white as white (issue 12:
        // the sun is the brightest thing in the picture).
        assert_eq!(GamutMapping::default(), GamutMapping::HighlightsToWhite);
        let message = "soft".parse::<GamutMapping>().unwrap_err().to_string();
        assert!(
            message.contains("clip, preserve-hue, highlights-to-white"),
            "{message}"
        );
    }

    #[test]
    fn highlights_go_to_white_keeping_luminance_up_to_white() {
        let white: f64 = SRGB.luminance_coefficients().iter().sum();
        // The sun: far beyond white, orange: white.
        let sun =
            GamutMapping::HighlightsToWhite.apply(LinearRgb::new(4000.0, 2500.0, 1200.0), SRGB);
        assert!((sun.min_component() - 1.0).abs() < 1e-12, "{sun:?}");
        // Over range but darker than white: its luminance is restored, its
        // components stay in [0, 1], and it is no less bright than
        // preserve-hue's version.
        let rgb = LinearRgb::new(1.6, 0.5, 0.2);
        let y = SRGB.luminance(rgb);
        assert!(y < white);
        let mapped = GamutMapping::HighlightsToWhite.apply(rgb, SRGB);
        assert!(
            (SRGB.luminance(mapped) / y - 1.0).abs() < 1e-12,
            "{mapped:?}"
        );
        assert!(mapped.max_component() <= 1.0 && mapped.min_component() >= 0.0);
        let hue = GamutMapping::PreserveHue.apply(rgb, SRGB);
        assert!(SRGB.luminance(mapped) > SRGB.luminance(hue));
        // Red still dominates: toward white, not across the hue circle.
        assert!(mapped.r >= mapped.g && mapped.g >= mapped.b, "{mapped:?}");
        // Inside the cube nothing changes.
        let inside = LinearRgb::new(0.3, 0.6, 0.9);
        assert_eq!(GamutMapping::HighlightsToWhite.apply(inside, SRGB), inside);
    }
}
