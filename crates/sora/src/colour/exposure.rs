//! Exposure: the factor that scales an image's XYZ (in radiance units × nm)
//! to display units, where Y = 1 is the display's white.
//!
//! Radiative transfer gives absolute numbers, whose scale depends on the sun
//! and the scene: per unit top-of-atmosphere irradiance (1 W m^-2 nm^-1) the
//! clear sky of case (a) has Y ≈ 2.6 W m^-2 sr^-1 (all orders of scattering,
//! `tests/data/sky_case_a_xyz_srgb.csv`), i.e. 1700 cd/m^2; under the real
//! sun (≈ 1.8 W m^-2 nm^-1 in the visible) nearly twice that; a Mars sunset
//! or a twilight sky orders of magnitude less. Something must choose which
//! radiance is "white"; in the paper that is its constant k (eq. 6). Two
//! rules ([`Exposure`]):
//!
//! - [`Exposure::Fixed`]: multiply XYZ by a given factor. For sequences
//!   (a sunset animation) whose brightness must stay comparable frame to
//!   frame, and for reproducing a known result.
//! - [`Exposure::Auto`] (the default): the photographic rule of Reinhard et
//!   al. (2002, "Photographic tone reproduction for digital images", eq. 1-2),
//!   which is what a camera's averaging light meter does: scale the image so
//!   that its log-average luminance maps to the *key* a (default 0.18, the
//!   18 % grey that meters are calibrated to):
//!   ```text
//!   L̄ = exp( (1/N) Σ_{pixels with Y > 0} ln Y ),     scale = a / L̄
//!   ```
//!   Pixels with Y <= 0 (black: below the horizon with a black ground, the
//!   planet's shadow) are left out of both the sum and N, so that a half-black
//!   frame is not over-exposed, and ln 0 never occurs. An image with no
//!   pixel above 0 is black whatever the scale; its scale is 1.
//!
//! Why the log-average and not, say, "the 99th-percentile Y maps to 1": a sky
//! image's dynamic range is dominated by the aureole around the sun. A
//! percentile or maximum rule lets the few pixels near the sun set the
//! exposure, so the rest of the sky turns dark, and jumps when the sun
//! enters the frame. The geometric mean weighs every pixel's brightness
//! ratio equally; a bright aureole covering 2 % of the frame at 100 times the
//! sky's luminance moves it by only 100^0.02 = 1.096 (0.13 stop).
//! What exceeds 1 afterwards is brought into range by
//! [`crate::colour::GamutMapping`] without changing its hue. For a brighter
//! rendering (skies are lighter than mid-grey in most photographs), raise the
//! key: 0.36 is one stop up.
//!
//! The rule is deterministic: a sequential sum in pixel order, no sorting or
//! sampling, so one image always gets the same scale, bit for bit.

use std::fmt;
use std::str::FromStr;

use crate::colour::xyz::Xyz;
use crate::error::{Error, Result};

/// The night floor, cd/m^2: the model has no airglow, zodiacal light or
/// starlight, which give the moonless natural night sky about 2e-4 cd/m^2
/// (22 mag/arcsec^2); a luminance 200 times below that is not a sky
/// anyone sees, and far below it lie only numerical floors (the
/// multiple-scattering tables floor their logarithms at 1e-30). A pixel
/// darker than this is night: [`apply_night_floor`] makes it black.
pub const NIGHT_FLOOR_CD_M2: f64 = 1e-6;

/// Sets every pixel of `image` (XYZ of radiance, Y x 683 lm/W = cd/m^2)
/// whose luminance is below [`NIGHT_FLOOR_CD_M2`] (or negative) to black,
/// and returns the brightest luminance left, cd/m^2 (0 for an image that
/// is all night: auto exposure then leaves it black, see
/// [`Exposure::scale_for_image`]).
pub fn apply_night_floor(image: &mut [Xyz]) -> f64 {
    let floor = NIGHT_FLOOR_CD_M2 / crate::colour::MAXIMUM_LUMINOUS_EFFICACY_LM_PER_W;
    let mut brightest: f64 = 0.0;
    for xyz in image.iter_mut() {
        if xyz.y < floor {
            *xyz = Xyz::BLACK;
        } else {
            brightest = brightest.max(xyz.y);
        }
    }
    brightest * crate::colour::MAXIMUM_LUMINOUS_EFFICACY_LM_PER_W
}

/// How an image's XYZ are scaled before display (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Exposure {
    /// Multiply XYZ by this factor (finite, > 0; unit: 1 / (radiance × nm)).
    Fixed(f64),
    /// Scale so that the log-average Y of the image's non-black pixels
    /// becomes `key` (finite, > 0; dimensionless, display white = 1).
    Auto {
        /// The target log-average Y (0.18 by default).
        key: f64,
    },
}

impl Exposure {
    /// The default key of [`Exposure::Auto`]: 0.18, photographic mid-grey.
    pub const DEFAULT_KEY: f64 = 0.18;

    /// The forms accepted by [`FromStr`].
    pub const FORMS: &'static str =
        "'auto', 'auto:<key>' (e.g. auto:0.18) or a fixed factor (e.g. 0.5)";

    /// A fixed photographic exposure of `ev100` (exposure value at ISO 100):
    /// the saturation-based rule of ISO 12232, as renderers use it (Lagarde
    /// & de Rousiers 2014, "Moving Frostbite to PBR", §5.1): a luminance of
    /// L_max = 1.2 x 2^EV100 cd/m^2 maps to display white, so the factor on
    /// XYZ (in W m^-2 sr^-1, Y x 683 lm/W = cd/m^2) is 683 / L_max. EV100 15
    /// is a sunny day (L_max = 39 000 cd/m^2), 0 a dim interior, -6 deep
    /// twilight. Finite, within -30..=40.
    pub fn from_ev100(ev100: f64) -> Result<Exposure> {
        if !(ev100.is_finite() && (-30.0..=40.0).contains(&ev100)) {
            return Err(Error::out_of_range("EV100", ev100, "1", "-30..=40"));
        }
        Ok(Exposure::Fixed(
            crate::colour::MAXIMUM_LUMINOUS_EFFICACY_LM_PER_W / (1.2 * ev100.exp2()),
        ))
    }

    /// The factor to multiply `image`'s XYZ by (dimensionless display units
    /// per unit of the XYZ).
    ///
    /// Fails if a fixed factor or the key is not finite and > 0, if a pixel
    /// is not finite (the error names its index), or if the image is so
    /// dark that its scale overflows.
    pub fn scale_for_image(self, image: &[Xyz]) -> Result<f64> {
        match self {
            Exposure::Fixed(scale) => {
                if scale.is_finite() && scale > 0.0 {
                    Ok(scale)
                } else {
                    Err(Error::out_of_range(
                        "exposure scale",
                        scale,
                        "1",
                        "> 0 and finite",
                    ))
                }
            }
            Exposure::Auto { key } => {
                if !(key.is_finite() && key > 0.0) {
                    return Err(Error::out_of_range(
                        "exposure key",
                        key,
                        "1",
                        "> 0 and finite",
                    ));
                }
                let Some(log_average) = log_average_luminance(image)? else {
                    return Ok(1.0);
                };
                let scale = key / log_average;
                if scale.is_finite() {
                    Ok(scale)
                } else {
                    Err(Error::out_of_range(
                        "log-average luminance of the image",
                        log_average,
                        "1",
                        format!(
                            "> {key} / f64::MAX, so that auto exposure can scale it to the key"
                        ),
                    ))
                }
            }
        }
    }
}

impl Default for Exposure {
    /// [`Exposure::Auto`] with key 0.18.
    fn default() -> Exposure {
        Exposure::Auto {
            key: Exposure::DEFAULT_KEY,
        }
    }
}

/// The geometric mean of Y over the pixels of `image` with Y > 0, in Y's
/// unit; `None` when no pixel has Y > 0. Fails, naming the pixel, if an X, Y
/// or Z is not finite.
pub(crate) fn log_average_luminance(image: &[Xyz]) -> Result<Option<f64>> {
    let mut sum_of_logs = 0.0;
    let mut count = 0usize;
    for (index, xyz) in image.iter().enumerate() {
        if !xyz.is_finite() {
            return Err(Error::InvalidSpectrum(format!(
                "pixel {index} has XYZ ({}, {}, {}); values must be finite",
                xyz.x, xyz.y, xyz.z
            )));
        }
        if xyz.y > 0.0 {
            sum_of_logs += xyz.y.ln();
            count += 1;
        }
    }
    Ok((count > 0).then(|| (sum_of_logs / count as f64).exp()))
}

impl fmt::Display for Exposure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Exposure::Fixed(scale) => write!(f, "{scale}"),
            Exposure::Auto { key } if *key == Exposure::DEFAULT_KEY => f.write_str("auto"),
            Exposure::Auto { key } => write!(f, "auto:{key}"),
        }
    }
}

impl FromStr for Exposure {
    type Err = Error;

    /// Parses `auto`, `auto:<key>` or a fixed factor (a number); checks that
    /// the number is finite and > 0.
    fn from_str(text: &str) -> Result<Exposure> {
        let text = text.trim();
        let number = |part: &str, name: &'static str| -> Result<f64> {
            let value = part.trim().parse::<f64>().map_err(|_| {
                Error::parse(
                    "exposure",
                    0,
                    format!("'{text}' is not one of {}", Exposure::FORMS),
                )
            })?;
            if value.is_finite() && value > 0.0 {
                Ok(value)
            } else {
                Err(Error::out_of_range(name, value, "1", "> 0 and finite"))
            }
        };
        if text == "auto" {
            Ok(Exposure::default())
        } else if let Some(key) = text.strip_prefix("auto:") {
            Ok(Exposure::Auto {
                key: number(key, "exposure key")?,
            })
        } else {
            Ok(Exposure::Fixed(number(text, "exposure scale")?))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixels_below_the_night_floor_turn_black() {
        let per_cd_m2 = 1.0 / crate::colour::MAXIMUM_LUMINOUS_EFFICACY_LM_PER_W;
        let mut image = vec![
            Xyz::new(1.0, 2e-6 * per_cd_m2, 1.0),
            Xyz::new(1.0, 0.5e-6 * per_cd_m2, 1.0),
            Xyz::new(0.0, -1e-3, 0.0),
        ];
        let brightest = apply_night_floor(&mut image);
        assert!((brightest - 2e-6).abs() < 1e-18, "{brightest}");
        assert_eq!(image[1], Xyz::BLACK);
        assert_eq!(image[2], Xyz::BLACK);
        assert_eq!(image[0].x, 1.0);
        let mut night = vec![Xyz::new(1e-20, 1e-20, 1e-20); 4];
        assert_eq!(apply_night_floor(&mut night), 0.0);
        assert!(night.iter().all(|p| *p == Xyz::BLACK));
        // An all-black image gets scale 1 from auto exposure: it stays black.
        let scale = Exposure::Auto { key: 0.18 }
            .scale_for_image(&night)
            .unwrap();
        assert_eq!(scale, 1.0);
    }

    fn grey(y: f64) -> Xyz {
        Xyz::new(0.95 * y, y, 1.09 * y)
    }

    #[test]
    fn auto_exposure_maps_the_log_average_to_the_key() {
        let image = [grey(0.5), grey(2.0), grey(8.0)];
        // Geometric mean of 0.5, 2, 8 is 2.
        assert!((log_average_luminance(&image).unwrap().unwrap() - 2.0).abs() < 1e-15);
        let scale = Exposure::default().scale_for_image(&image).unwrap();
        assert!((scale - 0.09).abs() < 1e-15, "{scale}");
        let scale = Exposure::Auto { key: 0.5 }.scale_for_image(&image).unwrap();
        assert!((scale - 0.25).abs() < 1e-15, "{scale}");
    }

    #[test]
    fn black_pixels_are_ignored_and_a_black_image_gets_scale_one() {
        let with_black = [grey(2.0), Xyz::BLACK, grey(2.0), Xyz::BLACK];
        let scale = Exposure::default().scale_for_image(&with_black).unwrap();
        assert!((scale - 0.09).abs() < 1e-15, "{scale}");
        let black = [Xyz::BLACK; 4];
        assert_eq!(Exposure::default().scale_for_image(&black).unwrap(), 1.0);
        assert_eq!(Exposure::default().scale_for_image(&[]).unwrap(), 1.0);
    }

    #[test]
    fn a_small_bright_region_barely_moves_the_exposure() {
        // 2 % of the pixels 100 times brighter: the scale drops by 100^0.02.
        let mut image = vec![grey(1.0); 98];
        image.extend([grey(100.0); 2]);
        let scale = Exposure::default().scale_for_image(&image).unwrap();
        assert!((scale - 0.18 / 100f64.powf(0.02)).abs() < 1e-14, "{scale}");
    }

    #[test]
    fn fixed_exposure_is_the_factor() {
        let image = [grey(1e6)];
        assert_eq!(Exposure::Fixed(0.25).scale_for_image(&image).unwrap(), 0.25);
    }

    #[test]
    fn bad_parameters_and_pixels_are_errors() {
        for exposure in [
            Exposure::Fixed(0.0),
            Exposure::Fixed(f64::NAN),
            Exposure::Auto { key: -0.18 },
            Exposure::Auto { key: f64::INFINITY },
        ] {
            assert!(
                exposure.scale_for_image(&[grey(1.0)]).is_err(),
                "{exposure:?}"
            );
        }
        let image = [grey(1.0), Xyz::new(0.0, f64::NAN, 0.0)];
        let message = Exposure::default()
            .scale_for_image(&image)
            .unwrap_err()
            .to_string();
        assert!(message.contains("pixel 1"), "{message}");
        // So dark that key / log-average overflows.
        let message = Exposure::default()
            .scale_for_image(&[grey(1e-320)])
            .unwrap_err()
            .to_string();
        assert!(message.contains("log-average"), "{message}");
    }

    #[test]
    fn parses_and_prints_every_form() {
        assert_eq!("auto".parse::<Exposure>().unwrap(), Exposure::default());
        assert_eq!(
            "auto:0.36".parse::<Exposure>().unwrap(),
            Exposure::Auto { key: 0.36 }
        );
        assert_eq!("2.5".parse::<Exposure>().unwrap(), Exposure::Fixed(2.5));
        for exposure in [
            Exposure::default(),
            Exposure::Auto { key: 0.36 },
            Exposure::Fixed(2.5),
        ] {
            assert_eq!(exposure.to_string().parse::<Exposure>().unwrap(), exposure);
        }
        let message = "bright".parse::<Exposure>().unwrap_err().to_string();
        assert!(message.contains("'auto'"), "{message}");
        let message = "auto:-1".parse::<Exposure>().unwrap_err().to_string();
        assert!(message.contains("exposure key = -1"), "{message}");
        assert!("0".parse::<Exposure>().is_err());
        assert!("inf".parse::<Exposure>().is_err());
    }

    #[test]
    fn ev100_maps_its_saturation_luminance_to_white() {
        let Exposure::Fixed(scale) = Exposure::from_ev100(15.0).unwrap() else {
            panic!("a fixed exposure");
        };
        // Y such that 683 Y = 1.2 x 2^15 cd/m^2 maps to 1.
        let y = 1.2 * 32768.0 / 683.0;
        assert!((scale * y - 1.0).abs() < 1e-12);
        assert_eq!(
            Exposure::from_ev100(14.0).unwrap(),
            Exposure::Fixed(2.0 * scale)
        );
        for bad in [f64::NAN, 41.0, -31.0] {
            assert!(Exposure::from_ev100(bad).is_err());
        }
    }
}
