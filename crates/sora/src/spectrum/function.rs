//! A spectral quantity as a function of wavelength (pbrt's `Spectrum`):
//! a constant, or a table with linear interpolation between its rows.
//!
//! Two ways to put a function on a [`WavelengthGrid`]:
//! - [`Spectrum::sample_at_wavelengths`]: the value at each wavelength
//!   (for smooth quantities: cross-sections, refractive indices, reflectance);
//! - [`Spectrum::sample_band_averaged`]: the mean over the band
//!   [lambda - step/2, lambda + step/2] of each sample (clipped to the table),
//!   for spiky quantities such as the solar spectrum, so that a coarse grid
//!   still carries the right energy in each band.
//!
//! Either way a table must cover the wavelengths asked for; there is no
//! silent extrapolation.

use crate::error::{Error, Result};
use crate::spectrum::{SampledSpectrum, WavelengthGrid};
use crate::table::NumericTable;

/// A function of wavelength (unit: that of the quantity; wavelength in nm).
#[derive(Debug, Clone, PartialEq)]
pub enum Spectrum {
    /// The same value at every wavelength.
    Constant(f64),
    /// Linear interpolation in a table.
    Tabulated(TabulatedSpectrum),
}

/// Rows (wavelength_nm, value), wavelengths strictly increasing, at least two
/// rows; linear interpolation between them.
#[derive(Debug, Clone, PartialEq)]
pub struct TabulatedSpectrum {
    wavelengths_nm: Vec<f64>,
    values: Vec<f64>,
}

impl TabulatedSpectrum {
    /// A table from its columns. `what` names it in errors.
    pub(crate) fn new(
        wavelengths_nm: Vec<f64>,
        values: Vec<f64>,
        what: &str,
    ) -> Result<TabulatedSpectrum> {
        if wavelengths_nm.len() != values.len() || wavelengths_nm.len() < 2 {
            return Err(Error::InvalidSpectrum(format!(
                "{what}: needs at least two rows of (wavelength, value), got {} wavelengths and {} values",
                wavelengths_nm.len(),
                values.len()
            )));
        }
        if let Some(i) = wavelengths_nm
            .iter()
            .chain(&values)
            .position(|v| !v.is_finite())
        {
            return Err(Error::InvalidSpectrum(format!(
                "{what}: entry {i} is not finite"
            )));
        }
        if let Some(i) = wavelengths_nm.windows(2).position(|w| w[1] <= w[0]) {
            return Err(Error::InvalidSpectrum(format!(
                "{what}: wavelengths must increase, but {} nm follows {} nm",
                wavelengths_nm[i + 1],
                wavelengths_nm[i]
            )));
        }
        Ok(TabulatedSpectrum {
            wavelengths_nm,
            values,
        })
    }

    /// Parses a two-column CSV (`wavelength_nm,<value>`, `#` comments, one
    /// header line, any column names).
    pub fn parse_csv(text: &str, what: &str) -> Result<TabulatedSpectrum> {
        let table = NumericTable::parse(text, what)?;
        if table.column_names.len() != 2 {
            return Err(Error::parse(
                what,
                0,
                format!(
                    "expected 2 columns (wavelength_nm,value), found {}",
                    table.column_names.len()
                ),
            ));
        }
        TabulatedSpectrum::new(table.column(0), table.column(1), what)
    }

    /// Shortest and longest tabulated wavelengths, nm.
    pub fn range_nm(&self) -> (f64, f64) {
        (self.wavelengths_nm[0], *self.wavelengths_nm.last().unwrap())
    }

    /// The rows' wavelengths, nm.
    pub(crate) fn wavelengths_nm(&self) -> &[f64] {
        &self.wavelengths_nm
    }

    /// The rows' values.
    pub(crate) fn values(&self) -> &[f64] {
        &self.values
    }

    fn check_covers(&self, lo_nm: f64, hi_nm: f64) -> Result<()> {
        let (first, last) = self.range_nm();
        if lo_nm < first || hi_nm > last {
            return Err(Error::InvalidSpectrum(format!(
                "the table covers {first}-{last} nm but {lo_nm}-{hi_nm} nm is needed"
            )));
        }
        Ok(())
    }

    /// Index i of the table interval [w_i, w_{i+1}] containing `wavelength_nm`
    /// (clamped to the first and last interval).
    fn interval(&self, wavelength_nm: f64) -> usize {
        let upper = self.wavelengths_nm.partition_point(|&w| w <= wavelength_nm);
        upper.clamp(1, self.wavelengths_nm.len() - 1) - 1
    }

    /// Linearly interpolated value at `wavelength_nm` (must be inside the table).
    pub(crate) fn value_at_nm(&self, wavelength_nm: f64) -> Result<f64> {
        self.check_covers(wavelength_nm, wavelength_nm)?;
        Ok(self.interpolate(wavelength_nm))
    }

    fn interpolate(&self, wavelength_nm: f64) -> f64 {
        let i = self.interval(wavelength_nm);
        let (w0, w1) = (self.wavelengths_nm[i], self.wavelengths_nm[i + 1]);
        let t = (wavelength_nm - w0) / (w1 - w0);
        self.values[i] + t * (self.values[i + 1] - self.values[i])
    }

    /// Exact integral of the piecewise-linear function over [lo_nm, hi_nm]
    /// (inside the table), unit: value * nm.
    fn integral(&self, lo_nm: f64, hi_nm: f64) -> f64 {
        let mut total = 0.0;
        let mut a = lo_nm;
        let mut i = self.interval(lo_nm);
        while a < hi_nm {
            let b = hi_nm.min(self.wavelengths_nm[i + 1]);
            total += 0.5 * (self.interpolate(a) + self.interpolate(b)) * (b - a);
            a = b;
            i += 1;
            if i + 1 >= self.wavelengths_nm.len() {
                break;
            }
        }
        total
    }

    /// Mean value over [lo_nm, hi_nm] (inside the table); the value at lo_nm
    /// when the band is empty.
    pub(crate) fn band_average(&self, lo_nm: f64, hi_nm: f64) -> Result<f64> {
        self.check_covers(lo_nm, hi_nm)?;
        if hi_nm <= lo_nm {
            return Ok(self.interpolate(lo_nm));
        }
        Ok(self.integral(lo_nm, hi_nm) / (hi_nm - lo_nm))
    }
}

impl Spectrum {
    /// Value at `wavelength_nm`.
    pub(crate) fn value_at_nm(&self, wavelength_nm: f64) -> Result<f64> {
        match self {
            Spectrum::Constant(v) => Ok(*v),
            Spectrum::Tabulated(table) => table.value_at_nm(wavelength_nm),
        }
    }

    /// Point samples at the grid's wavelengths.
    pub fn sample_at_wavelengths(&self, grid: &WavelengthGrid) -> Result<SampledSpectrum> {
        grid.wavelengths_nm()
            .map(|w| self.value_at_nm(w))
            .collect::<Result<Vec<f64>>>()
            .map(SampledSpectrum::from_values)
    }

    /// Band averages over [lambda - step/2, lambda + step/2] of each sample,
    /// the band clipped to the table where the grid's end bands stick out of
    /// it (the sample's own wavelength must still be inside). A single-sample
    /// grid is one band too (`438.7:438.7:10`: an instrument's 10-nm
    /// channel; `550` alone: 1 nm).
    pub(crate) fn sample_band_averaged(&self, grid: &WavelengthGrid) -> Result<SampledSpectrum> {
        let table = match self {
            Spectrum::Constant(v) => return Ok(SampledSpectrum::constant(grid.len(), *v)),
            Spectrum::Tabulated(table) => table,
        };
        let (first, last) = table.range_nm();
        let half = 0.5 * grid.step_nm();
        grid.wavelengths_nm()
            .map(|w| {
                table.check_covers(w, w)?;
                table.band_average((w - half).max(first), (w + half).min(last))
            })
            .collect::<Result<Vec<f64>>>()
            .map(SampledSpectrum::from_values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> TabulatedSpectrum {
        // value = wavelength / 100 on 300..900 nm, with uneven rows.
        let w = vec![300.0, 400.0, 450.0, 700.0, 900.0];
        let v = w.iter().map(|x| x / 100.0).collect();
        TabulatedSpectrum::new(w, v, "ramp").unwrap()
    }

    #[test]
    fn linear_interpolation_is_exact_on_a_line() {
        let table = ramp();
        for w in [300.0, 333.3, 400.0, 449.9, 555.0, 899.0, 900.0] {
            assert!(
                (table.value_at_nm(w).unwrap() - w / 100.0).abs() < 1e-12,
                "{w}"
            );
        }
        assert!(table.value_at_nm(299.0).is_err());
        assert!(table.value_at_nm(901.0).is_err());
    }

    #[test]
    fn band_average_of_a_line_is_its_midpoint_value() {
        let spectrum = Spectrum::Tabulated(ramp());
        let grid = WavelengthGrid::paper();
        let sampled = spectrum.sample_band_averaged(&grid).unwrap();
        for (i, w) in grid.wavelengths_nm().enumerate() {
            assert!(
                (sampled[i] - w / 100.0).abs() < 1e-12,
                "{w}: {}",
                sampled[i]
            );
        }
    }

    #[test]
    fn band_average_of_a_spike_keeps_its_area() {
        // A triangle of area 1 nm (height 1, base 2 nm) at 500 nm in a 20 nm band.
        let table = TabulatedSpectrum::new(
            vec![360.0, 499.0, 500.0, 501.0, 830.0],
            vec![0.0, 0.0, 1.0, 0.0, 0.0],
            "spike",
        )
        .unwrap();
        assert!((table.band_average(490.0, 510.0).unwrap() - 1.0 / 20.0).abs() < 1e-15);
        // Point sampling would miss it entirely at 480 and 520 and see 1.0 at 500.
        let grid = WavelengthGrid::new(480.0, 520.0, 20.0).unwrap();
        let sampled = Spectrum::Tabulated(table)
            .sample_band_averaged(&grid)
            .unwrap();
        assert_eq!(sampled.values(), &[0.0, 0.05, 0.0]);
    }

    #[test]
    fn constant_spectrum_samples_everywhere() {
        let sampled = Spectrum::Constant(2.5)
            .sample_band_averaged(&WavelengthGrid::paper())
            .unwrap();
        assert_eq!(sampled.values(), &[2.5; 21]);
    }

    #[test]
    fn invalid_tables_are_rejected() {
        assert!(TabulatedSpectrum::new(vec![400.0], vec![1.0], "t").is_err());
        assert!(TabulatedSpectrum::new(vec![400.0, 400.0], vec![1.0, 2.0], "t").is_err());
        assert!(TabulatedSpectrum::new(vec![400.0, 500.0], vec![1.0, f64::NAN], "t").is_err());
        let e =
            TabulatedSpectrum::parse_csv("wavelength_nm,value\n400,1\n390,2\n", "t").unwrap_err();
        assert!(e.to_string().contains("390 nm follows 400 nm"), "{e}");
    }

    #[test]
    fn table_must_cover_the_grid() {
        let table = TabulatedSpectrum::new(vec![400.0, 700.0], vec![1.0, 1.0], "narrow").unwrap();
        let e = Spectrum::Tabulated(table)
            .sample_at_wavelengths(&WavelengthGrid::paper())
            .unwrap_err();
        assert!(e.to_string().contains("covers 400-700 nm"), "{e}");
    }
}
