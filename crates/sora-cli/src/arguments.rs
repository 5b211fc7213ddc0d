//! Command-line text -> validated library values, in one place: every
//! subcommand parses its numbers, ranges and names through these functions,
//! so a bad value gets the same clear message wherever it appears.

use sora::mie::Complex64;

/// Parses a complex refractive index written `n`, `n+ki` or `n-ki` (`j` is
/// accepted for `i`), e.g. `1.5+0.01i`, `1.33`, `10+10i`. The sign of the
/// imaginary part is kept; the Mie solver rejects a negative one (gain).
pub fn parse_refractive_index(text: &str) -> Result<Complex64, String> {
    let compact: String = text.chars().filter(|c| !c.is_whitespace()).collect();
    let bad = || format!("'{text}' is not a refractive index: write n or n+ki, e.g. 1.5+0.01i");
    let Some(body) = compact.strip_suffix(['i', 'j']) else {
        let re: f64 = compact.parse().map_err(|_| bad())?;
        return Ok(Complex64::new(re, 0.0));
    };
    // The sign that separates the parts is the last + or - not following an exponent 'e'.
    let bytes = body.as_bytes();
    let split = (1..bytes.len())
        .rev()
        .find(|&i| (bytes[i] == b'+' || bytes[i] == b'-') && !matches!(bytes[i - 1], b'e' | b'E'))
        .ok_or_else(bad)?;
    let re: f64 = body[..split].parse().map_err(|_| bad())?;
    let im_text = &body[split..];
    let im: f64 = match im_text {
        "+" => 1.0,
        "-" => -1.0,
        _ => im_text.parse().map_err(|_| bad())?,
    };
    Ok(Complex64::new(re, im))
}

/// Parses a comma-separated list of numbers (`0.5,1.8` or `0.5,1.8,0.1,2.5`).
pub fn parse_number_list(text: &str, what: &str) -> Result<Vec<f64>, String> {
    text.split(',')
        .map(|part| {
            part.trim()
                .parse::<f64>()
                .map_err(|_| format!("'{}' in {what} '{text}' is not a number", part.trim()))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refractive_index_forms() {
        assert_eq!(
            parse_refractive_index("1.5+0.01i").unwrap(),
            Complex64::new(1.5, 0.01)
        );
        assert_eq!(
            parse_refractive_index("1.33").unwrap(),
            Complex64::new(1.33, 0.0)
        );
        assert_eq!(
            parse_refractive_index("10+10i").unwrap(),
            Complex64::new(10.0, 10.0)
        );
        assert_eq!(
            parse_refractive_index("1.5 + 1e-3j").unwrap(),
            Complex64::new(1.5, 1e-3)
        );
        assert_eq!(
            parse_refractive_index("1.5e0+1e-3i").unwrap(),
            Complex64::new(1.5, 1e-3)
        );
        assert_eq!(
            parse_refractive_index("1.5-0.1i").unwrap(),
            Complex64::new(1.5, -0.1)
        );
        assert_eq!(
            parse_refractive_index("1+i").unwrap(),
            Complex64::new(1.0, 1.0)
        );
        for bad in ["", "abc", "1.5+0.01", "+0.01i", "1.5+xi", "i"] {
            assert!(parse_refractive_index(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn number_lists() {
        assert_eq!(parse_number_list("0.5, 1.8", "x").unwrap(), vec![0.5, 1.8]);
        assert!(parse_number_list("0.5,,1", "x").unwrap_err().contains("''"));
    }
}

/// How spectra become display colours: shared by every command that shows
/// colour (`sora colour`, and the renderer).
#[derive(Debug, Clone, clap::Args)]
pub struct ColourOptions {
    /// Colour-matching functions: cie1931-2deg (the paper's) or cie1964-10deg
    #[arg(long, value_name = "NAME", default_value = "cie1931-2deg")]
    pub observer: sora::colour::Observer,

    /// Display encoding: srgb (IEC 61966-2-1), or the paper's eq. 6,
    /// paper-smpte-c[:k=K,gamma=G] (SMPTE-C primaries, D65, R = k*255*lin^(1/gamma))
    #[arg(long, value_name = "NAME", default_value = "srgb")]
    pub encoding: sora::colour::DisplayEncoding,

    /// Exposure: auto (log-average luminance -> 0.18), auto:KEY, or a fixed
    /// factor multiplying XYZ
    #[arg(long, value_name = "auto|auto:KEY|FACTOR", default_value = "auto")]
    pub exposure: sora::colour::Exposure,

    /// Out-of-gamut and over-range colours: preserve-hue (desaturate toward
    /// the same luminance, then scale down by the largest channel) or clip
    /// (clamp each channel to 0..1)
    #[arg(long, value_name = "NAME", default_value = "preserve-hue")]
    pub gamut: sora::colour::GamutMapping,
}

impl ColourOptions {
    /// The library's display stage for these options.
    pub fn display_mapping(&self) -> sora::colour::DisplayMapping {
        sora::colour::DisplayMapping {
            exposure: self.exposure,
            gamut_mapping: self.gamut,
            encoding: self.encoding,
        }
    }
}
