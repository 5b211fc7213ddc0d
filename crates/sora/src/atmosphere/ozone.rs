//! Absorbing gases: ozone and any gas given by an absorption cross-section
//! table. They take light out of the beam and scatter none of it (single-
//! scattering albedo 0); their extinction is absorption,
//!
//! ```text
//!     beta_abs(h, lambda) = n(h) * sigma_abs(lambda)     [m^-1]
//! ```
//!
//! (the paper's eq. 1 with an absorption cross-section; the paper has no
//! absorber, one cause of its too-strong long-wavelength sky, see NOTES).
//!
//! Ozone is what keeps the zenith sky blue at sunset: its Chappuis band
//! (broad, peaking near 600 nm) absorbs orange light along the long slant
//! path. The embedded cross-section (`data/ozone_cross_section_233K_10nm.csv`,
//! Serdyuchenko/Gorshelev et al. 2014 at 233 K, as used by Bruneton 2017)
//! holds bin averages over [lambda, lambda + 10) nm, 360-840 nm. sora
//! treats it as the piecewise-constant function it describes and puts it
//! on a wavelength grid by the band average over each sample's band
//! [lambda - step/2, lambda + step/2] (clipped to the table, the sample's
//! own wavelength inside it), which keeps the absorbed energy of each band
//! whatever the grid; on a 10 nm grid aligned with the bins a sample at
//! 600 nm averages the 590 and 600 nm bins half and half. User tables
//! (`absorption.wavelength_nm` / `cross_section_m2`) are point values,
//! linearly interpolated and sampled at each wavelength.
//!
//! Amount: a column in Dobson units (1 DU = 2.6867e20 molecules m^-2, a
//! 10 um layer of pure gas at 0 C and 1 atm; Earth ~300 DU), spread over
//! the species' profile: the number density at relative density 1 is
//! `DU * 2.6867e20 / column_m`; or that number density directly.

use super::phase::PhaseFunction;
use crate::error::{Error, Result};
use crate::spectrum::{SampledSpectrum, Spectrum, TabulatedSpectrum, WavelengthGrid};
use crate::table::NumericTable;

/// Molecules per m^2 in one Dobson unit.
pub const MOLECULES_PER_M2_PER_DOBSON_UNIT: f64 = 2.6867e20;

const OZONE_233K_CSV: &str = include_str!("../data/ozone_cross_section_233K_10nm.csv");

/// Cross-sections averaged over bins [start, start + width) of equal width.
#[derive(Debug, Clone, PartialEq)]
pub struct BinnedCrossSection {
    bin_starts_nm: Vec<f64>,
    bin_width_nm: f64,
    cross_sections_m2: Vec<f64>,
}

impl BinnedCrossSection {
    /// Parses a two-column CSV `wavelength_nm,<cross-section m^2>` whose rows
    /// are the starts of equal-width bins; `what` names it in errors.
    pub(crate) fn parse_csv(text: &str, what: &str) -> Result<BinnedCrossSection> {
        let table = NumericTable::parse(text, what)?;
        if table.column_names.len() != 2 || table.rows.len() < 2 {
            return Err(Error::parse(
                what,
                0,
                "expected 2 columns (bin start wavelength_nm, cross-section m^2) and at least 2 rows",
            ));
        }
        let starts = table.column(0);
        let values = table.column(1);
        let width = starts[1] - starts[0];
        let uniform = width > 0.0
            && starts
                .windows(2)
                .all(|w| ((w[1] - w[0]) - width).abs() < 1e-9 * width);
        if !uniform {
            return Err(Error::parse(
                what,
                0,
                "bin starts must increase in equal steps",
            ));
        }
        if let Some(i) = values.iter().position(|v| *v < 0.0) {
            return Err(Error::parse(
                what,
                0,
                format!(
                    "cross-section {} m^2 at {} nm is negative",
                    values[i], starts[i]
                ),
            ));
        }
        Ok(BinnedCrossSection {
            bin_starts_nm: starts,
            bin_width_nm: width,
            cross_sections_m2: values,
        })
    }

    /// Ozone at 233 K, 10 nm bins from 360 to 840 nm (embedded).
    pub(crate) fn ozone_233k() -> BinnedCrossSection {
        BinnedCrossSection::parse_csv(OZONE_233K_CSV, "embedded ozone cross-section")
            .expect("the embedded ozone table is valid")
    }

    /// The covered range [first bin start, last bin end), nm.
    pub(crate) fn range_nm(&self) -> (f64, f64) {
        (
            self.bin_starts_nm[0],
            self.bin_starts_nm.last().unwrap() + self.bin_width_nm,
        )
    }

    /// Mean cross-section over [lo_nm, hi_nm] (inside the range), m^2;
    /// the value of the bin holding `lo_nm` when the band is empty.
    pub(crate) fn band_average_m2(&self, lo_nm: f64, hi_nm: f64) -> Result<f64> {
        let (first, end) = self.range_nm();
        if !(lo_nm >= first && hi_nm <= end && lo_nm <= hi_nm) {
            return Err(Error::InvalidSpectrum(format!(
                "the cross-section table covers {first}-{end} nm but {lo_nm}-{hi_nm} nm is needed"
            )));
        }
        let bin_of = |w: f64| {
            (((w - first) / self.bin_width_nm).floor() as usize).min(self.bin_starts_nm.len() - 1)
        };
        if hi_nm <= lo_nm {
            return Ok(self.cross_sections_m2[bin_of(lo_nm)]);
        }
        let mut total = 0.0;
        for bin in bin_of(lo_nm)..=bin_of(hi_nm) {
            let start = self.bin_starts_nm[bin];
            let overlap = hi_nm.min(start + self.bin_width_nm) - lo_nm.max(start);
            if overlap > 0.0 {
                total += overlap * self.cross_sections_m2[bin];
            }
        }
        Ok(total / (hi_nm - lo_nm))
    }

    /// Band averages on `grid` (see the module docs), m^2.
    pub(crate) fn sample(&self, grid: &WavelengthGrid) -> Result<SampledSpectrum> {
        let (first, end) = self.range_nm();
        let half = if grid.len() == 1 {
            0.0
        } else {
            0.5 * grid.step_nm()
        };
        grid.wavelengths_nm()
            .map(|w| {
                if !(first..end).contains(&w) {
                    return Err(Error::InvalidSpectrum(format!(
                        "the cross-section table covers {first}-{end} nm but {w} nm is needed"
                    )));
                }
                self.band_average_m2((w - half).max(first), (w + half).min(end))
            })
            .collect::<Result<Vec<f64>>>()
            .map(SampledSpectrum::from_values)
    }
}

/// An absorption cross-section per molecule as a function of wavelength.
#[derive(Debug, Clone, PartialEq)]
pub enum AbsorptionCrossSection {
    /// Bin averages (the embedded ozone table).
    Binned(BinnedCrossSection),
    /// Point values, linear interpolation (user tables), m^2.
    Tabulated(TabulatedSpectrum),
}

impl AbsorptionCrossSection {
    /// Cross-section per molecule on `grid`, m^2.
    pub(crate) fn sample(&self, grid: &WavelengthGrid) -> Result<SampledSpectrum> {
        match self {
            AbsorptionCrossSection::Binned(binned) => binned.sample(grid),
            AbsorptionCrossSection::Tabulated(table) => {
                Spectrum::Tabulated(table.clone()).sample_at_wavelengths(grid)
            }
        }
    }
}

/// How much of an absorbing gas there is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GasAmount {
    /// Vertical column, Dobson units.
    ColumnDobsonUnits(f64),
    /// Number density at relative density 1, m^-3.
    NumberDensityM3(f64),
}

/// A gas that absorbs and does not scatter.
#[derive(Debug, Clone, PartialEq)]
pub struct AbsorbingGas {
    /// Its absorption cross-section against wavelength.
    pub cross_section: AbsorptionCrossSection,
    /// How much of it there is.
    pub amount: GasAmount,
}

impl AbsorbingGas {
    /// Number density at relative density 1, m^-3, for a profile of
    /// vertical column `column_m` (> 0 when the amount is a column).
    pub(crate) fn reference_number_density_m3(&self, column_m: f64) -> f64 {
        match self.amount {
            GasAmount::ColumnDobsonUnits(du) => du * MOLECULES_PER_M2_PER_DOBSON_UNIT / column_m,
            GasAmount::NumberDensityM3(n) => n,
        }
    }

    /// (extinction, scattering = 0) coefficients at the reference density on
    /// `grid`, m^-1, and a placeholder phase function.
    pub(crate) fn compute_optics(
        &self,
        grid: &WavelengthGrid,
        column_m: f64,
    ) -> Result<(SampledSpectrum, SampledSpectrum, PhaseFunction)> {
        let mut extinction = self.cross_section.sample(grid)?;
        extinction *= self.reference_number_density_m3(column_m);
        Ok((
            extinction,
            SampledSpectrum::zeros(grid.len()),
            PhaseFunction::Isotropic,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_table_is_the_reference_with_ten_nm_bins() {
        let ozone = BinnedCrossSection::ozone_233k();
        assert_eq!(ozone.range_nm(), (360.0, 840.0));
        // A band inside one bin is that bin's value.
        assert_eq!(ozone.band_average_m2(600.0, 609.0).unwrap(), 5.019e-25);
        // Straddling two bins: the mean, weighted by overlap.
        let mixed = ozone.band_average_m2(595.0, 605.0).unwrap();
        assert!((mixed - 0.5 * (4.701e-25 + 5.019e-25)).abs() < 1e-35);
        assert!(ozone.band_average_m2(350.0, 370.0).is_err());
    }

    #[test]
    fn band_averages_on_grids() {
        let ozone = BinnedCrossSection::ozone_233k();
        // A 10 nm grid offset by 5 nm hits bin centres: the bin values.
        let grid = WavelengthGrid::new(365.0, 825.0, 10.0).unwrap();
        let sampled = ozone.sample(&grid).unwrap();
        assert_eq!(sampled[24], 5.019e-25); // 605 nm, bin [600, 610)
        // The paper grid: 380 nm averages [370, 390) = bins 370 and 380.
        let sampled = ozone.sample(&WavelengthGrid::paper()).unwrap();
        assert!((sampled[0] - 0.5 * (2.182e-28 + 2.818e-28)).abs() < 1e-40);
        // The 1 nm grid covers the whole CIE range 360-830.
        assert!(ozone.sample(&"360:830:1".parse().unwrap()).is_ok());
    }

    #[test]
    fn dobson_units_set_the_column() {
        let gas = AbsorbingGas {
            cross_section: AbsorptionCrossSection::Binned(BinnedCrossSection::ozone_233k()),
            amount: GasAmount::ColumnDobsonUnits(300.0),
        };
        let column_m = 15e3;
        let grid: WavelengthGrid = "605".parse().unwrap();
        let (ext, sca, _) = gas.compute_optics(&grid, column_m).unwrap();
        // tau = 300 DU * 2.6867e20 * sigma: ~0.040 at 605 nm (Chappuis band).
        let tau = ext[0] * column_m;
        assert!((tau - 300.0 * 2.6867e20 * 5.019e-25).abs() < 1e-12, "{tau}");
        assert_eq!(sca[0], 0.0);
    }
}
