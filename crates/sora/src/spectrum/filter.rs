//! An instrument's spectral response: what one channel of a sun photometer
//! or a filtered camera sees of a spectrum.
//!
//! A channel with response R(lambda) (any scale: only its shape matters)
//! measures the response-weighted mean of a spectral quantity L(lambda),
//!
//!   L_filter = integral R L d lambda / integral R d lambda,
//!
//! in the unit of L (W m^-2 sr^-1 nm^-1 for a radiance). sora evaluates it
//! on the filter's own wavelength grid ([`Filter::grid`]) by the grid's
//! quadrature (equal weights, `wavelength_grid`): sum_i R(lambda_i) L_i /
//! sum_i R(lambda_i), with L_i the value the engine computes at lambda_i
//! (the sun and other spiky tables there are band averages over the grid
//! step, `Spectrum::sample_band_averaged`).
//!
//! Two kinds of response:
//! - a table read from CSV (`wavelength_nm,response`, linear between rows,
//!   zero outside them; [`Filter::parse_csv`]);
//! - a Gaussian of a stated centre and full width at half maximum, cut at
//!   two widths from the centre (where it is 2^-16 of its peak;
//!   [`Filter::gaussian`]). The built-in channels of the AERONET Cimel
//!   CE318 sun photometer ([`CIMEL_CHANNELS`], [`Filter::named`]) are such
//!   Gaussians at the nominal wavelengths, 10 nm wide except 340 nm (2 nm)
//!   and 380 nm (4 nm): the interference filters' bandwidths stated by
//!   Holben et al. (1998, Remote Sens. Environ. 66, 1-16) and Eck et al.
//!   (1999, J. Geophys. Res. 104, 31333). A real filter's measured response
//!   differs in shape and by a nanometre or two in centre; give its table
//!   with a CSV file where that matters.

use crate::error::{Error, Result};
use crate::spectrum::{
    MAX_WAVELENGTH_NM, MIN_WAVELENGTH_NM, SampledSpectrum, TabulatedSpectrum, WavelengthGrid,
};

/// The Cimel CE318 (AERONET) aerosol channels: nominal centre and full
/// width at half maximum, nm (see the module docs for the source).
pub const CIMEL_CHANNELS: [(f64, f64); 7] = [
    (340.0, 2.0),
    (380.0, 4.0),
    (440.0, 10.0),
    (500.0, 10.0),
    (675.0, 10.0),
    (870.0, 10.0),
    (1020.0, 10.0),
];

/// Half-widths of a Gaussian filter's support, in FWHM.
const GAUSSIAN_CUT_FWHM: f64 = 2.0;
/// Grid steps per FWHM of a Gaussian filter (10 over its 2 x 2 widths:
/// 21 wavelengths).
const GAUSSIAN_STEPS_PER_FWHM: f64 = 5.0;

#[derive(Debug, Clone, PartialEq)]
enum Response {
    Gaussian { centre_nm: f64, fwhm_nm: f64 },
    Tabulated(TabulatedSpectrum),
}

/// One channel's spectral response (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Filter {
    name: String,
    response: Response,
}

impl Filter {
    /// A Gaussian response centred at `centre_nm` with full width at half
    /// maximum `fwhm_nm` (0.01 nm or more), cut at two widths from the
    /// centre; its support must lie within 280-2500 nm.
    pub fn gaussian(name: &str, centre_nm: f64, fwhm_nm: f64) -> Result<Filter> {
        if !(fwhm_nm.is_finite() && fwhm_nm >= 0.01) {
            return Err(Error::out_of_range(
                format!("filter {name}'s width"),
                fwhm_nm,
                "nm",
                ">= 0.01",
            ));
        }
        let half = GAUSSIAN_CUT_FWHM * fwhm_nm;
        let allowed = format!(
            "{}..={} (its support, centre +- {GAUSSIAN_CUT_FWHM} widths, inside {MIN_WAVELENGTH_NM}-{MAX_WAVELENGTH_NM} nm)",
            MIN_WAVELENGTH_NM + half,
            MAX_WAVELENGTH_NM - half
        );
        if !(MIN_WAVELENGTH_NM + half..=MAX_WAVELENGTH_NM - half).contains(&centre_nm) {
            return Err(Error::out_of_range(
                format!("filter {name}'s centre"),
                centre_nm,
                "nm",
                allowed,
            ));
        }
        Ok(Filter {
            name: name.to_string(),
            response: Response::Gaussian { centre_nm, fwhm_nm },
        })
    }

    /// A built-in filter by name: `cimel-340`, `cimel-380`, `cimel-440`,
    /// `cimel-500`, `cimel-675`, `cimel-870`, `cimel-1020` (see
    /// [`CIMEL_CHANNELS`]); `None` for any other name.
    pub fn named(name: &str) -> Option<Filter> {
        let channel: f64 = name.strip_prefix("cimel-")?.parse().ok()?;
        let &(centre, fwhm) = CIMEL_CHANNELS.iter().find(|(c, _)| *c == channel)?;
        Filter::gaussian(name, centre, fwhm).ok()
    }

    /// The names [`Filter::named`] knows, in wavelength order.
    pub fn builtin_names() -> Vec<String> {
        CIMEL_CHANNELS
            .iter()
            .map(|(c, _)| format!("cimel-{c}"))
            .collect()
    }

    /// A tabulated response from CSV text: a header (`wavelength_nm,
    /// response`, any names), `#` comments, rows with increasing
    /// wavelengths inside 280-2500 nm and responses >= 0, at least one of
    /// them > 0. `name` names the filter in output and errors.
    pub fn parse_csv(text: &str, name: &str) -> Result<Filter> {
        let table = TabulatedSpectrum::parse_csv(text, name)?;
        let (first, last) = table.range_nm();
        for (what, value) in [("first", first), ("last", last)] {
            if !(MIN_WAVELENGTH_NM..=MAX_WAVELENGTH_NM).contains(&value) {
                return Err(Error::out_of_range(
                    format!("{name}: the {what} wavelength"),
                    value,
                    "nm",
                    format!("{MIN_WAVELENGTH_NM}..={MAX_WAVELENGTH_NM}"),
                ));
            }
        }
        if let Some(i) = table.values().iter().position(|&r| r < 0.0) {
            return Err(Error::out_of_range(
                format!("{name}: the response at {} nm", table.wavelengths_nm()[i]),
                table.values()[i],
                "1",
                ">= 0",
            ));
        }
        if table.values().iter().all(|&r| r == 0.0) {
            return Err(Error::InvalidSpectrum(format!(
                "{name}: the response is zero at every wavelength"
            )));
        }
        Ok(Filter {
            name: name.to_string(),
            response: Response::Tabulated(table),
        })
    }

    /// The filter's name (a built-in's, or the one it was read with).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The response at `wavelength_nm` (zero outside the support).
    pub fn response_at(&self, wavelength_nm: f64) -> f64 {
        match &self.response {
            Response::Gaussian { centre_nm, fwhm_nm } => {
                let x = (wavelength_nm - centre_nm) / fwhm_nm;
                if x.abs() > GAUSSIAN_CUT_FWHM {
                    0.0
                } else {
                    (-4.0 * std::f64::consts::LN_2 * x * x).exp()
                }
            }
            Response::Tabulated(table) => {
                let (first, last) = table.range_nm();
                if (first..=last).contains(&wavelength_nm) {
                    table.value_at_nm(wavelength_nm).unwrap_or(0.0)
                } else {
                    0.0
                }
            }
        }
    }

    /// The wavelengths where the response can be non-zero, nm: a
    /// Gaussian's cut, or a table from the row before its first non-zero
    /// response to the row after its last.
    pub fn support_nm(&self) -> (f64, f64) {
        match &self.response {
            Response::Gaussian { centre_nm, fwhm_nm } => (
                centre_nm - GAUSSIAN_CUT_FWHM * fwhm_nm,
                centre_nm + GAUSSIAN_CUT_FWHM * fwhm_nm,
            ),
            Response::Tabulated(table) => {
                let (w, r) = (table.wavelengths_nm(), table.values());
                let first = r.iter().position(|&v| v > 0.0).unwrap_or(0);
                let last = r.iter().rposition(|&v| v > 0.0).unwrap_or(w.len() - 1);
                (w[first.saturating_sub(1)], w[(last + 1).min(w.len() - 1)])
            }
        }
    }

    /// The response-weighted mean wavelength, nm, on [`Filter::grid`].
    pub fn centre_nm(&self) -> Result<f64> {
        let grid = self.grid()?;
        let values: Vec<f64> = grid.wavelengths_nm().collect();
        self.weighted_mean(&grid, &SampledSpectrum::from_values(values))
    }

    /// The wavelengths sora computes for this filter: its support, every
    /// FWHM/5 for a Gaussian (21 wavelengths); a table's support every 1
    /// nm (every 1/20 of it when narrower than 20 nm, at most 2001
    /// wavelengths), starting at the support's first wavelength.
    pub fn grid(&self) -> Result<WavelengthGrid> {
        let (lo, hi) = self.support_nm();
        let step = match &self.response {
            Response::Gaussian { fwhm_nm, .. } => fwhm_nm / GAUSSIAN_STEPS_PER_FWHM,
            Response::Tabulated(_) => ((hi - lo) / 20.0).min(1.0).max((hi - lo) / 2000.0),
        };
        let steps = ((hi - lo) / step).round();
        if steps == 0.0 {
            return WavelengthGrid::new(lo, lo, 0.01);
        }
        let stop = (lo + steps * step).min(MAX_WAVELENGTH_NM);
        WavelengthGrid::new(lo, stop, step)
    }

    /// The response-weighted mean of `values` sampled on `grid` (the grid's
    /// equal quadrature weights): sum R_i v_i / sum R_i. An error when the
    /// grid misses the response (every R_i zero) or `values` has another
    /// length.
    pub fn weighted_mean(&self, grid: &WavelengthGrid, values: &SampledSpectrum) -> Result<f64> {
        if values.len() != grid.len() {
            return Err(Error::Unsupported(format!(
                "filter {}: {} values for {} wavelengths",
                self.name,
                values.len(),
                grid.len()
            )));
        }
        let (mut sum, mut weight) = (0.0, 0.0);
        for (w, v) in grid.wavelengths_nm().zip(values.values()) {
            let r = self.response_at(w);
            sum += r * v;
            weight += r;
        }
        if weight <= 0.0 {
            let (lo, hi) = self.support_nm();
            return Err(Error::Unsupported(format!(
                "filter {}: its response ({lo}-{hi} nm) is zero at every wavelength of the grid {grid}",
                self.name
            )));
        }
        Ok(sum / weight)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn csv(rows: &[(f64, f64)]) -> String {
        let mut text = String::from("# test filter\nwavelength_nm,response\n");
        for (w, r) in rows {
            text += &format!("{w},{r}\n");
        }
        text
    }

    #[test]
    fn a_flat_filter_gives_the_band_mean() {
        let filter = Filter::parse_csv(&csv(&[(430.0, 1.0), (450.0, 1.0)]), "flat").unwrap();
        let grid = filter.grid().unwrap();
        assert_eq!(
            (grid.start_nm(), grid.stop_nm(), grid.len()),
            (430.0, 450.0, 21)
        );
        let values: Vec<f64> = grid.wavelengths_nm().map(|w| (w / 100.0).sin()).collect();
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        let got = filter
            .weighted_mean(&grid, &SampledSpectrum::from_values(values))
            .unwrap();
        assert!((got - mean).abs() < 1e-15, "{got} {mean}");
        assert!((filter.centre_nm().unwrap() - 440.0).abs() < 1e-12);
    }

    #[test]
    fn a_narrow_filter_tends_to_the_point_value() {
        // A curved spectrum: the Gaussian mean of sin(a + x / 7) is
        // sin(a) exp(-sigma^2 / 98), off the centre's value by about
        // sin(a) sigma^2 / 98, shrinking as the width squared.
        let f = |w: f64| 1.0 + ((w - 500.0) / 7.0).sin();
        let point = f(503.0);
        let mut previous = f64::INFINITY;
        for fwhm in [8.0, 4.0, 2.0, 1.0, 0.5] {
            let filter = Filter::gaussian("g", 503.0, fwhm).unwrap();
            let grid = filter.grid().unwrap();
            assert_eq!(grid.len(), 21);
            let values = SampledSpectrum::from_values(grid.wavelengths_nm().map(f).collect());
            let error = (filter.weighted_mean(&grid, &values).unwrap() - point).abs();
            let sigma = fwhm / (8.0 * std::f64::consts::LN_2).sqrt();
            let expected = (3.0f64 / 7.0).sin() * (1.0 - (-sigma * sigma / 98.0).exp());
            assert!(
                (error - expected).abs() < 1e-3 * expected,
                "fwhm {fwhm}: {error} against {expected}"
            );
            assert!(error < previous / 3.5);
            previous = error;
        }
    }

    #[test]
    fn the_cimel_channels_are_built_in() {
        let names = Filter::builtin_names();
        assert_eq!(names.len(), 7);
        for (name, (centre, fwhm)) in names.iter().zip(CIMEL_CHANNELS) {
            let filter = Filter::named(name).unwrap();
            assert!((filter.centre_nm().unwrap() - centre).abs() < 1e-9);
            // Half maximum at centre +- fwhm/2.
            assert!((filter.response_at(centre + 0.5 * fwhm) - 0.5).abs() < 1e-12);
            assert_eq!(filter.response_at(centre + 2.01 * fwhm), 0.0);
        }
        assert!(Filter::named("cimel-441").is_none());
        assert!(Filter::named("kodak").is_none());
    }

    #[test]
    fn a_table_is_zero_outside_its_rows_and_its_grid_covers_the_support() {
        let filter = Filter::parse_csv(
            &csv(&[
                (400.0, 0.0),
                (500.0, 0.0),
                (510.0, 1.0),
                (520.0, 0.0),
                (700.0, 0.0),
            ]),
            "triangle",
        )
        .unwrap();
        assert_eq!(filter.support_nm(), (500.0, 520.0));
        assert_eq!(filter.response_at(390.0), 0.0);
        assert_eq!(filter.response_at(505.0), 0.5);
        let grid = filter.grid().unwrap();
        assert_eq!(
            (grid.start_nm(), grid.stop_nm(), grid.step_nm()),
            (500.0, 520.0, 1.0)
        );
        assert!((filter.centre_nm().unwrap() - 510.0).abs() < 1e-12);
    }

    #[test]
    fn bad_filters_are_one_line_errors() {
        let message = |r: Result<Filter>| r.unwrap_err().to_string();
        let m = message(Filter::parse_csv(
            &csv(&[(400.0, 1.0), (410.0, -0.5)]),
            "f.csv",
        ));
        assert!(m.contains("410 nm") && m.contains("-0.5"), "{m}");
        let m = message(Filter::parse_csv(
            &csv(&[(400.0, 0.0), (410.0, 0.0)]),
            "f.csv",
        ));
        assert!(m.contains("zero at every wavelength"), "{m}");
        let m = message(Filter::parse_csv(
            &csv(&[(250.0, 1.0), (410.0, 1.0)]),
            "f.csv",
        ));
        assert!(m.contains("250") && m.contains("nm"), "{m}");
        let m = message(Filter::gaussian("g", 2495.0, 10.0));
        assert!(m.contains("2495") && m.contains("centre"), "{m}");
        let m = message(Filter::gaussian("g", 500.0, 0.0));
        assert!(m.contains("width"), "{m}");
        let filter = Filter::named("cimel-440").unwrap();
        let far = WavelengthGrid::new(600.0, 610.0, 1.0).unwrap();
        let m = message(
            filter
                .weighted_mean(&far, &SampledSpectrum::constant(far.len(), 1.0))
                .map(|_| filter.clone()),
        );
        assert!(m.contains("zero at every wavelength of the grid"), "{m}");
    }
}
