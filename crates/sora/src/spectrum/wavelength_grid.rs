//! The wavelengths a computation samples, and the quadrature that turns
//! samples into integrals over wavelength.
//!
//! A grid is `start:stop:step` in nanometres (vacuum wavelength), inside
//! 280-2500 nm: the near ultraviolet (from the long-wave edge of ozone's
//! Hartley band, where the ground's sky goes dark) to the shortwave
//! infrared, the sun's spectrum that reaches the ground (96 % of the ASTM
//! E490 sun's energy, and the range a pyranometer's broadband value mostly
//! holds). Every
//! built-in optical property covers it: the solar spectrum (ASTM E490,
//! 119.5 nm to 1 mm), the Rayleigh cross-sections (refractive-index
//! formulas of Bates 1984 and Bideau-Mehu et al. 1973, both fitted over
//! wider ranges), the ozone cross-section (`atmosphere::ozone`, 270-2510
//! nm, 0 past 1070 nm), the banded gases of `[gases]` (200-4000 nm) and the
//! Mie solver; a
//! user table (refractive index, albedo, spectrum) that does not cover a
//! grid is an error naming the wavelength and the table's range. Colour
//! uses only the part of a grid inside the range of the CIE colour-matching
//! functions, 360-830 nm (`colour::SpectrumToXyz`). The default is the
//! paper's grid (§4): 380 to 780 nm every 20 nm, 21 samples.
//!
//! Quadrature rule: the paper's, a Riemann sum with the same weight `step_nm`
//! at every sample, so that integral f(lambda) d lambda ≈ sum_i f(lambda_i) *
//! step. For integrands that vanish at the ends of the visible range (the
//! colour-matching functions times any radiance) this is the trapezoidal rule
//! in all but the two end samples, whose weights differ by step/2 times
//! values below 2e-3 of the peak.

use std::fmt;
use std::str::FromStr;

use crate::error::{Error, Result};

/// Shortest wavelength a grid may sample, nm (the near ultraviolet: at 280
/// nm 300 DU of ozone have a vertical optical depth of about 20, so the
/// ground's sky is dark below it; the embedded ozone table starts at 270
/// nm, so a 280 nm sample's band is covered for steps up to 20 nm).
pub const MIN_WAVELENGTH_NM: f64 = 280.0;
/// Longest wavelength a grid may sample, nm (the shortwave infrared: the
/// water and CO2 bands at 1.4, 1.9 and 2.0 um included; past 2500 nm the
/// sun holds under 1.5 % of its energy).
pub const MAX_WAVELENGTH_NM: f64 = 2500.0;

/// The most wavelengths a grid may have (checked before anything is
/// allocated or computed: every spectrum, image row and Mie ensemble is
/// per wavelength). 10000 covers 360-830 nm at 0.05 nm, the whole range at
/// 0.09 nm.
pub const MAX_WAVELENGTH_COUNT: usize = 10_000;

/// Evenly spaced wavelengths `start_nm, start_nm + step_nm, ..., stop_nm`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WavelengthGrid {
    start_nm: f64,
    step_nm: f64,
    len: usize,
}

impl WavelengthGrid {
    /// The grid `start_nm:stop_nm:step_nm`. `stop_nm - start_nm` must be a
    /// whole number of steps (to 1e-6 of a step); a single wavelength is
    /// `start == stop` (its quadrature weight is still `step_nm`).
    pub fn new(start_nm: f64, stop_nm: f64, step_nm: f64) -> Result<WavelengthGrid> {
        let range = format!("{MIN_WAVELENGTH_NM}..={MAX_WAVELENGTH_NM}");
        for (name, value) in [("start_nm", start_nm), ("stop_nm", stop_nm)] {
            if !(MIN_WAVELENGTH_NM..=MAX_WAVELENGTH_NM).contains(&value) {
                return Err(Error::out_of_range(name, value, "nm", range));
            }
        }
        if stop_nm < start_nm {
            return Err(Error::out_of_range(
                "stop_nm",
                stop_nm,
                "nm",
                format!(">= start_nm ({start_nm})"),
            ));
        }
        if !(step_nm.is_finite() && step_nm >= 0.01) {
            return Err(Error::out_of_range("step_nm", step_nm, "nm", ">= 0.01"));
        }
        let steps = (stop_nm - start_nm) / step_nm;
        if (steps - steps.round()).abs() > 1e-6 {
            // The unit follows `allowed` in the message: no "nm" here.
            let stop = |steps: f64| ((start_nm + steps * step_nm) * 1e9).round() / 1e9;
            let (below, above) = (stop(steps.floor()), stop(steps.ceil()));
            let suggestion = if above <= MAX_WAVELENGTH_NM {
                format!(
                    "(try {start_nm}:{below}:{step_nm} or {start_nm}:{above}:{step_nm}): the nearest stops are {below} and {above}"
                )
            } else {
                format!("(try {start_nm}:{below}:{step_nm}): the nearest stop is {below}")
            };
            return Err(Error::out_of_range(
                "stop_nm",
                stop_nm,
                "nm",
                format!("start_nm + a whole number of steps of {step_nm} {suggestion}"),
            ));
        }
        let len = steps.round() as usize + 1;
        if len > MAX_WAVELENGTH_COUNT {
            return Err(Error::Unsupported(format!(
                "wavelength grid {start_nm}:{stop_nm}:{step_nm} has {len} wavelengths, more than the limit of {MAX_WAVELENGTH_COUNT}; use a coarser step (at least {} nm here)",
                ((stop_nm - start_nm) / (MAX_WAVELENGTH_COUNT - 1) as f64 * 1e6).ceil() / 1e6
            )));
        }
        Ok(WavelengthGrid {
            start_nm,
            step_nm,
            len,
        })
    }

    /// The paper's grid: 380 to 780 nm every 20 nm (21 samples).
    pub fn paper() -> WavelengthGrid {
        WavelengthGrid {
            start_nm: 380.0,
            step_nm: 20.0,
            len: 21,
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Always false: a grid has at least one wavelength.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// First wavelength, nm.
    pub fn start_nm(&self) -> f64 {
        self.start_nm
    }

    /// Last wavelength, nm.
    pub fn stop_nm(&self) -> f64 {
        self.wavelength_nm(self.len - 1)
    }

    /// Spacing, nm.
    pub fn step_nm(&self) -> f64 {
        self.step_nm
    }

    /// The `index`-th wavelength, nm.
    pub fn wavelength_nm(&self, index: usize) -> f64 {
        self.start_nm + index as f64 * self.step_nm
    }

    /// All wavelengths in increasing order, nm.
    pub fn wavelengths_nm(&self) -> impl ExactSizeIterator<Item = f64> + '_ {
        (0..self.len).map(|i| self.wavelength_nm(i))
    }

    /// The `len` samples from index `first` on, as a grid of their own
    /// (the same step; its wavelengths are this grid's to rounding).
    pub(crate) fn sub_grid(&self, first: usize, len: usize) -> WavelengthGrid {
        assert!(
            len >= 1 && first + len <= self.len,
            "sub-grid outside the grid"
        );
        WavelengthGrid {
            start_nm: self.wavelength_nm(first),
            step_nm: self.step_nm,
            len,
        }
    }

    /// Quadrature weight of sample `index`, nm: the paper's rule, `step_nm`
    /// for every sample (see the module docs).
    pub(crate) fn quadrature_weight_nm(&self, index: usize) -> f64 {
        debug_assert!(index < self.len);
        self.step_nm
    }
}

impl Default for WavelengthGrid {
    fn default() -> WavelengthGrid {
        WavelengthGrid::paper()
    }
}

impl fmt::Display for WavelengthGrid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.start_nm, self.stop_nm(), self.step_nm)
    }
}

impl FromStr for WavelengthGrid {
    type Err = Error;

    /// Parses `start:stop:step` in nm (e.g. `380:780:20`), or a single
    /// wavelength `550` (weight 1 nm).
    fn from_str(text: &str) -> Result<WavelengthGrid> {
        let what = "wavelength grid (start_nm:stop_nm:step_nm, e.g. 380:780:20)";
        let number = |part: &str| {
            part.trim().parse::<f64>().map_err(|_| {
                Error::parse(
                    what,
                    0,
                    format!("'{}' in '{text}' is not a number", part.trim()),
                )
            })
        };
        let parts: Vec<&str> = text.split(':').collect();
        match parts.as_slice() {
            [single] => {
                let nm = number(single)?;
                WavelengthGrid::new(nm, nm, 1.0)
            }
            [start, stop, step] => {
                WavelengthGrid::new(number(start)?, number(stop)?, number(step)?)
            }
            _ => Err(Error::parse(
                what,
                0,
                format!("'{text}' is not of the form start:stop:step"),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_grid_has_21_samples_from_380_to_780() {
        let grid = WavelengthGrid::paper();
        assert_eq!(grid.len(), 21);
        assert_eq!(grid.wavelength_nm(0), 380.0);
        assert_eq!(grid.stop_nm(), 780.0);
        assert_eq!(grid, "380:780:20".parse().unwrap());
        assert_eq!(grid.to_string(), "380:780:20");
        assert_eq!(grid.quadrature_weight_nm(20), 20.0);
    }

    #[test]
    fn fine_grid_spans_the_cie_range() {
        let grid: WavelengthGrid = "360:830:1".parse().unwrap();
        assert_eq!(grid.len(), 471);
        assert_eq!(grid.wavelengths_nm().last(), Some(830.0));
    }

    #[test]
    fn the_range_is_280_to_2500_nm() {
        // The whole range every 10 nm: 223 samples, 280 to 2500 nm.
        let grid: WavelengthGrid = "280:2500:10".parse().unwrap();
        assert_eq!(grid.len(), 223);
        assert_eq!(grid.start_nm(), MIN_WAVELENGTH_NM);
        assert_eq!(grid.stop_nm(), MAX_WAVELENGTH_NM);
        assert_eq!(grid.to_string(), "280:2500:10");
        // Each end alone, and a photometer channel alone.
        for text in ["280", "2500", "1020", "1640"] {
            assert_eq!(text.parse::<WavelengthGrid>().unwrap().len(), 1);
        }
        // Just outside either end: one line naming the value, its unit and
        // the range.
        for (text, expected) in [
            ("279.9:1100:0.1", "start_nm = 279.9 nm"),
            ("280:2500.5:0.5", "stop_nm = 2500.5 nm"),
            ("2501", "start_nm = 2501 nm"),
            ("250", "start_nm = 250 nm"),
        ] {
            let message = text.parse::<WavelengthGrid>().unwrap_err().to_string();
            assert!(message.contains(expected), "{text}: {message}");
            assert!(message.contains("280..=2500"), "{text}: {message}");
            assert!(!message.contains('\n'), "{text}: {message}");
        }
    }

    #[test]
    fn single_wavelength_grid() {
        let grid: WavelengthGrid = "550".parse().unwrap();
        assert_eq!(grid.len(), 1);
        assert_eq!(grid.wavelength_nm(0), 550.0);
    }

    #[test]
    fn bad_grids_are_rejected_with_the_offending_value() {
        let cases = [
            ("270:780:20", "start_nm = 270 nm"),
            ("380:1110:20", "stop_nm = 1110 nm"),
            ("780:380:20", "stop_nm = 380 nm"),
            ("380:780:0", "step_nm = 0 nm"),
            ("380:780:-20", "step_nm = -20 nm"),
            ("380:781:20", "stop_nm = 781 nm"),
            ("380:abc:20", "'abc'"),
            ("380:780", "start:stop:step"),
            ("NaN:780:20", "start_nm = NaN"),
        ];
        for (text, expected) in cases {
            let message = text.parse::<WavelengthGrid>().unwrap_err().to_string();
            assert!(message.contains(expected), "{text}: {message}");
        }
    }

    #[test]
    fn an_off_grid_stop_names_the_nearest_stops_once_in_nm() {
        let message = "380:780:7"
            .parse::<WavelengthGrid>()
            .unwrap_err()
            .to_string();
        assert!(!message.contains("nm nm"), "{message}");
        assert!(message.contains("380:779:7"), "{message}");
        assert!(message.contains("779 and 786 nm"), "{message}");
        // Past the end of the range only the stop below is offered.
        let message = "380:2499:7"
            .parse::<WavelengthGrid>()
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("(try 380:2494:7): the nearest stop is 2494 nm"),
            "{message}"
        );
        assert!(!message.contains("1101"), "{message}");
    }

    #[test]
    fn the_number_of_wavelengths_is_limited() {
        // At the limit: 10000 wavelengths.
        let grid: WavelengthGrid = "380:779.96:0.04".parse().unwrap();
        assert_eq!(grid.len(), MAX_WAVELENGTH_COUNT);
        // One past it, and far past it: errors naming the count, the limit and the fix.
        for text in ["380:780:0.04", "360:830:0.01"] {
            let message = text.parse::<WavelengthGrid>().unwrap_err().to_string();
            assert!(message.contains("limit of 10000"), "{message}");
            assert!(message.contains("coarser step"), "{message}");
        }
        let message = "360:830:0.01"
            .parse::<WavelengthGrid>()
            .unwrap_err()
            .to_string();
        assert!(message.contains("47001 wavelengths"), "{message}");
    }
}
