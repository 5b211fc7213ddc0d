//! Absorbing gases: ozone, NO2 and any gas given by an absorption cross-section
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
//! path. The embedded cross-section is at 233 K (a typical temperature of
//! the stratospheric ozone layer), bin averages over [lambda, lambda + 10)
//! nm (vacuum) from 270 to 1110 nm, put together from two published data
//! sets of IUP Bremen:
//!
//! - 360-840 nm (`data/ozone_cross_section_233K_10nm.csv`): Serdyuchenko,
//!   Gorshelev et al. 2014 (AMT 7, 625), as averaged and used by Bruneton
//!   2017. These are the only bins that touch colour, and they are unchanged.
//! - 270-360 nm (the long-wave edge of the Hartley band, 270-300 nm, and
//!   the Huggins band) and 840-1066 nm (the Wulf band)
//!   (`data/ozone_cross_section_233K_10nm_bogumil2003.csv`): Bogumil et al.
//!   2003 (J. Photochem. Photobiol. A 157, 167), SCIAMACHY pre-flight
//!   cross-sections, at 233 K from their quadratic temperature fit as
//!   libRadtran distributes it, converted from air to vacuum wavelengths and
//!   averaged over the same bins (the CSV header gives the details and the
//!   file copied; `scripts/gases/make_ozone_bogumil2003.py` writes it). Serdyuchenko's own data reach 1100 nm, but no copy of
//!   them could be obtained; where the two sets overlap Bogumil's bins are
//!   2-7.5 % above Serdyuchenko's (440-810 nm), so the seams at 360 and 840
//!   nm are steps of a few per cent in cross-sections whose 300 DU optical
//!   depth is below 1e-3 there.
//! - 1070-1110 nm: 0. The Bogumil data end at 1066.5 nm; between 1000 and
//!   1066 nm they average 1.8e-28 m^2, a 300 DU optical depth of 1.5e-5,
//!   at the level of their noise. The zeros err by about that much.
//! - 1110-2510 nm: 0, added in code (`ZERO_BINS_END_NM`): ozone has no
//!   band of note there (SPECTRL2's ozone coefficients, Bird & Riordan
//!   1986, are 0 from 780 to 4000 nm), so the grid's whole range is
//!   covered.
//!
//! | 300 DU, vertical | 280 | 290 | 300 | 310 | 320 | 340 | 380 | 440 | 500 | 600 | 675 | 870 | 1020 nm |
//! |---|---|---|---|---|---|---|---|---|---|---|---|---|---|
//! | ozone optical depth | 33 | 13 | 3.9 | 1.0 | 0.24 | 0.012 | 2.0e-5 | 9.8e-4 | 0.0096 | 0.039 | 0.012 | 4.7e-4 | 6.6e-6 |
//!
//! (the mean over the 10 nm band centred on each wavelength, what a sample
//! of a 10 nm grid gets; at 675 nm that is the 670 nm bin.) In the Huggins
//! band (300-350 nm) the cross-section falls by a factor of 4 across one
//! 10 nm bin and depends on temperature
//! (Bogumil's fit: 243 K is 3, 7, 13 and 20 % above 223 K in the 300, 320,
//! 340 and 350 nm bins), so the one temperature is a model error of a few
//! per cent of the ozone optical depth there; Beer's law with a bin's
//! mean cross-section overestimates the absorption of a long path there
//! (the transmittance of the mean is below the mean transmittance), so
//! below 320 nm sora's radiances are a band model's, not a line-by-line
//! code's. On the Hartley band's long-wave edge (270-300 nm) the
//! cross-section falls by 2.3-3.2 times per bin and hardly depends on
//! temperature (243 K is 0.2, 0.8 and 1.7 % above 223 K in the 270, 280
//! and 290 nm bins); 300 DU are 13-34 vertical optical depths there, so
//! the ground receives almost none of the sun's light below 295 nm.
//!
//! sora treats the table as the piecewise-constant function it describes
//! and puts it on a wavelength grid by the band average over each sample's
//! band [lambda - step/2, lambda + step/2] (clipped to the table, the
//! sample's own wavelength inside it), which keeps the absorbed energy of
//! each band whatever the grid; on a 10 nm grid aligned with the bins a
//! sample at 600 nm averages the 590 and 600 nm bins half and half. The
//! band is also clipped at the seams (360 and 840 nm) to the data set that
//! holds the sample: a sample at 360 nm averages Serdyuchenko's 360 nm bin
//! only, not Bogumil's 350 nm bin, so no sample mixes two measurements and
//! every grid inside 360-840 nm (every grid before the range widened) gets
//! exactly the cross-sections it got then. User
//! tables (`absorption.wavelength_nm` / `cross_section_m2`) are point
//! values, linearly interpolated and sampled at each wavelength.
//!
//! # NO2
//! `absorption.gas = "no2"`: nitrogen dioxide, whose structured continuum
//! absorbs from the ultraviolet to the orange (peak 10 nm means of 6e-19
//! cm^2 near 400-420 nm). The embedded cross-section
//! (`data/no2_cross_section_294K_1nm_vandaele1998.csv`, written by
//! `scripts/gases/make_no2_o4.py`; the CSV header names the file and its
//! sha256) is Vandaele et al. (1998, JQSRT 59, 171) at 294 K, converted
//! from air to vacuum wavelengths and averaged over 1 nm bins from 239 to
//! 667 nm: finer than ozone's 10 nm because NO2's vibronic structure
//! (bands ~5 nm apart) is what a 1-5 nm grid should see; on a 10 nm grid
//! the band averages are the 10 nm means all the same. Past 667 nm (the end
//! of the copy read; the paper reaches 1000 nm) the table is 0: there the
//! cross-section is below 1e-20 cm^2, a 1 DU optical depth below 3e-4.
//! One temperature, 294 K, that of the polluted boundary layer where NO2
//! columns are large; at 220 K (stratospheric NO2) Vandaele's 10 nm means
//! are 1-2 % lower at 400-510 nm, 7 % at 340 nm and 10 % at 600 nm (the
//! script prints the ratios): for a background column of 0.2 DU an error
//! below 1e-4 in optical depth. The amount is a column in Dobson units as
//! for ozone (1 DU = 2.6867e16 molecules cm^-2): a clean background has
//! about 0.1-0.2 DU (mostly stratospheric; the AFGL mid-latitude summer
//! atmosphere, Anderson et al. 1986, has 0.22 DU, 5.97e15 cm^-2), a
//! polluted city 1 DU or more. Vertical optical depths per DU (10 nm bands
//! centred there, tested below):
//!
//! | 1 DU NO2, vertical | 340 | 380 | 440 | 500 | 550 | 600 nm |
//! |---|---|---|---|---|---|---|
//! | optical depth | 0.0105 | 0.0161 | 0.0137 | 0.0062 | 0.0030 | 0.00086 |
//!
//! Sun photometers put their channels in windows between gas bands
//! (AERONET: 340, 380, 440, 500, 675, 870, 1020 nm) and still correct
//! ozone, NO2 and water vapour (Giles et al. 2019, AMT 12, 169): NO2 at 440
//! nm is 0.014 per DU against a Rayleigh optical depth of 0.24.
//!
//! Water vapour and the O2 and CO2 bands are `gas_bands.rs` (a band model
//! as a k-distribution, from an atmosphere file's `[gases]`), the O2-O2
//! collision bands `o2_o2.rs` (`[gases] o2_o2 = true`).

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

/// Molecules per cm^2 in one Dobson unit: 0.01 mm of the gas at 273.15 K
/// and 1013.25 hPa, 1e-3 cm times the Loschmidt constant 2.686780e19
/// cm^-3 (CODATA 2018), written 2.6867e16 as the m^-2 value above.
pub const MOLECULES_PER_CM2_PER_DOBSON_UNIT: f64 = 2.6867e16;

const OZONE_233K_CSV: &str = include_str!("../data/ozone_cross_section_233K_10nm.csv");
/// The end of the ozone table's zero bins past the published data, nm
/// (the grid's longest wavelength, 2500 nm, is the middle of its last
/// 10 nm bin's first half).
pub(crate) const ZERO_BINS_END_NM: f64 = 2510.0;

const OZONE_233K_BOGUMIL_CSV: &str =
    include_str!("../data/ozone_cross_section_233K_10nm_bogumil2003.csv");
/// The start of the first zero bin the embedded tables are padded from
/// where their data start later (ozone's first bin; the grid's shortest
/// wavelength is 280 nm).
pub(crate) const ZERO_BINS_START_NM: f64 = 270.0;

const NO2_294K_CSV: &str = include_str!("../data/no2_cross_section_294K_1nm_vandaele1998.csv");
const O2_O2_CSV: &str = include_str!("../data/o2_o2_cia_1nm_thalman2013_hitran2016.csv");

/// Cross-sections averaged over bins [start, start + width) of equal width.
#[derive(Debug, Clone, PartialEq)]
pub struct BinnedCrossSection {
    bin_starts_nm: Vec<f64>,
    bin_width_nm: f64,
    cross_sections_m2: Vec<f64>,
    /// Where the data sets the table joins meet, nm: a sample's band is
    /// clipped to the data set holding the sample (see `sample`). Empty
    /// for a table from one data set.
    seams_nm: Vec<f64>,
}

impl BinnedCrossSection {
    /// Parses a two-column CSV `wavelength_nm,<cross-section m^2>` whose rows
    /// are the starts of equal-width bins; `what` names it in errors.
    pub(crate) fn parse_csv(text: &str, what: &str) -> Result<BinnedCrossSection> {
        let (starts, values) = parse_two_columns(text, what)?;
        BinnedCrossSection::from_columns(starts, values, what)
    }

    /// Bins with these starts and values (see `parse_csv`).
    fn from_columns(starts: Vec<f64>, values: Vec<f64>, what: &str) -> Result<BinnedCrossSection> {
        if starts.len() < 2 {
            return Err(Error::parse(what, 0, "expected at least 2 bins"));
        }
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
            seams_nm: Vec::new(),
        })
    }

    /// Ozone at 233 K, 10 nm bins from 270 to 1110 nm (embedded): the
    /// Serdyuchenko bins (360-840 nm) and the Bogumil bins on either side
    /// (see the module docs), then zeros to [`ZERO_BINS_END_NM`].
    pub(crate) fn ozone_233k() -> BinnedCrossSection {
        Self::ozone_233k_published().padded_with_zeros()
    }

    /// NO2 at 294 K, 1 nm bins from 239 to 667 nm (Vandaele et al. 1998,
    /// embedded; see the module docs), then zeros to [`ZERO_BINS_END_NM`].
    pub(crate) fn no2_294k() -> BinnedCrossSection {
        BinnedCrossSection::parse_csv(NO2_294K_CSV, "embedded NO2 cross-section")
            .expect("the embedded NO2 table is valid")
            .padded_with_zeros()
    }

    /// The O2-O2 binary absorption coefficient k, m^5 per molecule^2, 1 nm
    /// bins from 335 to 1343 nm (Thalman & Volkamer 2013 and HITRAN 2016
    /// CIA, embedded; see
    /// `o2_o2.rs`), zeros on either side from [`ZERO_BINS_START_NM`] to
    /// [`ZERO_BINS_END_NM`]. Its extinction is k n_O2^2.
    pub(crate) fn o2_o2_cia() -> BinnedCrossSection {
        BinnedCrossSection::parse_csv(O2_O2_CSV, "embedded O2-O2 coefficient")
            .expect("the embedded O2-O2 table is valid")
            .padded_with_zeros()
    }

    /// This table with zero bins added (in its own bin width) from
    /// [`ZERO_BINS_START_NM`] to its first bin and from its end to
    /// [`ZERO_BINS_END_NM`], so that every grid sora accepts (280-2500
    /// nm) is covered: the gas absorbs nothing where it has no data.
    fn padded_with_zeros(mut self) -> BinnedCrossSection {
        let step = self.bin_width_nm;
        let (mut first, mut end) = self.range_nm();
        let mut below = Vec::new();
        while first > ZERO_BINS_START_NM + 0.5 * step {
            first -= step;
            below.push(first);
        }
        below.reverse();
        self.cross_sections_m2
            .splice(0..0, std::iter::repeat_n(0.0, below.len()));
        self.bin_starts_nm.splice(0..0, below);
        while end < ZERO_BINS_END_NM - 0.5 * step {
            self.bin_starts_nm.push(end);
            self.cross_sections_m2.push(0.0);
            end += step;
        }
        self
    }

    /// This table times `factor` (>= 0): e.g. a pair coefficient k (m^5)
    /// times one partner's density (m^-3), a cross-section per molecule of
    /// the other.
    pub(crate) fn scaled(mut self, factor: f64) -> BinnedCrossSection {
        for value in &mut self.cross_sections_m2 {
            *value *= factor;
        }
        self
    }

    /// [`BinnedCrossSection::ozone_233k`] as published: 270-1110 nm.
    fn ozone_233k_published() -> BinnedCrossSection {
        let what = "embedded ozone cross-section";
        let serdyuchenko = BinnedCrossSection::parse_csv(OZONE_233K_CSV, what)
            .expect("the embedded ozone table is valid");
        let (serdyuchenko_first, serdyuchenko_end) = serdyuchenko.range_nm();
        let (bogumil_starts, bogumil_values) = parse_two_columns(OZONE_233K_BOGUMIL_CSV, what)
            .expect("the embedded ozone extension is valid");
        // Bogumil's bins below, then Serdyuchenko's, then Bogumil's above:
        // the Serdyuchenko bins as they are.
        let mut rows: Vec<(f64, f64)> = bogumil_starts
            .iter()
            .zip(&bogumil_values)
            .filter(|(start, _)| **start < serdyuchenko_first)
            .map(|(s, v)| (*s, *v))
            .collect();
        rows.extend(
            serdyuchenko
                .bin_starts_nm
                .iter()
                .zip(&serdyuchenko.cross_sections_m2)
                .map(|(s, v)| (*s, *v)),
        );
        rows.extend(
            bogumil_starts
                .iter()
                .zip(&bogumil_values)
                .filter(|(start, _)| **start >= serdyuchenko_end)
                .map(|(s, v)| (*s, *v)),
        );
        let (starts, values) = rows.into_iter().unzip();
        let mut joined = BinnedCrossSection::from_columns(starts, values, what)
            .expect("the embedded ozone tables join into equal bins");
        joined.seams_nm = vec![serdyuchenko_first, serdyuchenko_end];
        joined
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

    /// Band averages on `grid` (see the module docs), m^2. Each sample's
    /// band is clipped to the table and to the data set that holds the
    /// sample's wavelength, between the seams: a sample never averages two
    /// measurements (they differ by a few per cent where they meet), and a
    /// grid inside 360-840 nm samples Serdyuchenko's bins exactly as it did
    /// when they were the whole table.
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
                let lo = self
                    .seams_nm
                    .iter()
                    .copied()
                    .filter(|seam| *seam <= w)
                    .fold(first, f64::max);
                let hi = self
                    .seams_nm
                    .iter()
                    .copied()
                    .filter(|seam| *seam > w)
                    .fold(end, f64::min);
                self.band_average_m2((w - half).max(lo), (w + half).min(hi))
            })
            .collect::<Result<Vec<f64>>>()
            .map(SampledSpectrum::from_values)
    }
}

/// The two columns (bin start nm, cross-section m^2) of a CSV.
fn parse_two_columns(text: &str, what: &str) -> Result<(Vec<f64>, Vec<f64>)> {
    let table = NumericTable::parse(text, what)?;
    if table.column_names.len() != 2 {
        return Err(Error::parse(
            what,
            0,
            "expected 2 columns (bin start wavelength_nm, cross-section m^2)",
        ));
    }
    Ok((table.column(0), table.column(1)))
}

/// An absorption cross-section per molecule as a function of wavelength.
#[derive(Debug, Clone, PartialEq)]
pub enum AbsorptionCrossSection {
    /// Bin averages (the embedded ozone table).
    Binned(BinnedCrossSection),
    /// Point values, linear interpolation (user tables), m^2.
    Tabulated(TabulatedSpectrum),
    /// A banded gas' k-distribution term (`gas_bands.rs`).
    Band(super::gas_bands::GasBand),
}

impl AbsorptionCrossSection {
    /// Cross-section per molecule on `grid`, m^2.
    pub(crate) fn sample(&self, grid: &WavelengthGrid) -> Result<SampledSpectrum> {
        match self {
            AbsorptionCrossSection::Binned(binned) => binned.sample(grid),
            AbsorptionCrossSection::Tabulated(table) => {
                Spectrum::Tabulated(table.clone()).sample_at_wavelengths(grid)
            }
            AbsorptionCrossSection::Band(band) => band.sample(grid),
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
        assert_eq!(ozone.range_nm(), (270.0, ZERO_BINS_END_NM));
        assert_eq!(
            BinnedCrossSection::ozone_233k_published().range_nm(),
            (270.0, 1110.0)
        );
        // A band inside one bin is that bin's value.
        assert_eq!(ozone.band_average_m2(600.0, 609.0).unwrap(), 5.019e-25);
        // Straddling two bins: the mean, weighted by overlap.
        let mixed = ozone.band_average_m2(595.0, 605.0).unwrap();
        assert!((mixed - 0.5 * (4.701e-25 + 5.019e-25)).abs() < 1e-35);
        // Across the seam at 360 nm: Bogumil's 350 nm bin and Serdyuchenko's
        // 360 nm bin.
        let seam = ozone.band_average_m2(350.0, 370.0).unwrap();
        assert!(
            (seam - 0.5 * (7.828e-27 + 1.18e-27)).abs() < 1e-39,
            "{seam}"
        );
        // Past the published data: zeros to 2510 nm.
        assert_eq!(ozone.band_average_m2(1100.0, 2500.0).unwrap(), 0.0);
        // Outside 270-2510 nm: an error naming the range.
        for (lo, hi) in [(260.0, 280.0), (2500.0, 2520.0)] {
            let message = ozone.band_average_m2(lo, hi).unwrap_err().to_string();
            assert!(message.contains("270-2510 nm"), "{message}");
        }
    }

    /// The bins of one embedded CSV, (start nm, m^2).
    fn csv_bins(text: &str) -> Vec<(f64, f64)> {
        let (starts, values) = parse_two_columns(text, "test").unwrap();
        starts.into_iter().zip(values).collect()
    }

    #[test]
    fn the_joined_table_keeps_every_published_bin_unchanged() {
        let ozone = BinnedCrossSection::ozone_233k_published();
        let joined: Vec<(f64, f64)> = ozone
            .bin_starts_nm
            .iter()
            .copied()
            .zip(ozone.cross_sections_m2.iter().copied())
            .collect();
        assert_eq!(joined.len(), 84); // 270, 280, ..., 1100
        // Serdyuchenko's 48 bins (360-830 nm, today's numbers) are the
        // joined table's, bit for bit, and so are Bogumil's 34 outside them.
        let serdyuchenko = csv_bins(OZONE_233K_CSV);
        assert_eq!(serdyuchenko.len(), 48);
        let bogumil = csv_bins(OZONE_233K_BOGUMIL_CSV);
        assert_eq!(bogumil.len(), 36);
        for bin in serdyuchenko.iter().chain(&bogumil) {
            assert!(joined.contains(bin), "{bin:?}");
        }
        assert_eq!(&joined[9..57], &serdyuchenko[..]);
        // The Huggins band: the cross-section rises monotonically towards
        // the ultraviolet, by 3.5 to 6 times per 10 nm, across the seam too.
        for pair in joined[2..11].windows(2) {
            let ratio = pair[0].1 / pair[1].1;
            assert!((3.5..7.0).contains(&ratio), "{pair:?}: {ratio}");
        }
        // Into the Hartley band (its peak is near 255 nm) the rise slows:
        // 3.2 times from 290 to 280 nm, 2.3 times from 280 to 270 nm.
        for (pair, range) in joined[..3].windows(2).zip([2.0..2.6, 3.0..3.5]) {
            let ratio = pair[0].1 / pair[1].1;
            assert!(range.contains(&ratio), "{pair:?}: {ratio}");
        }
        // Past the end of the data (1066.5 nm) the bins are 0.
        assert!(joined[80..].iter().all(|(_, sigma)| *sigma == 0.0));
        assert!(joined[..80].iter().all(|(_, sigma)| *sigma > 0.0));
    }

    #[test]
    fn ozone_optical_depths_at_the_photometer_channels() {
        // 300 DU, vertical, over the 10 nm band centred on each wavelength:
        // the table of the module docs.
        let ozone = BinnedCrossSection::ozone_233k();
        let column_m2 = 300.0 * MOLECULES_PER_M2_PER_DOBSON_UNIT;
        let expected = [
            (280.0, 33.5),
            (290.0, 13.2),
            (300.0, 3.9),
            (310.0, 1.0),
            (320.0, 0.24),
            (340.0, 0.012),
            (380.0, 2.0e-5),
            (440.0, 9.8e-4),
            (500.0, 0.0096),
            (600.0, 0.039),
            (675.0, 0.012),
            (870.0, 4.7e-4),
            (1020.0, 6.6e-6),
        ];
        for (nm, want) in expected {
            let got = column_m2 * ozone.band_average_m2(nm - 5.0, nm + 5.0).unwrap();
            assert!((got / want - 1.0).abs() < 0.03, "{nm} nm: {got} vs {want}");
        }
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
        // Every grid sora accepts is covered: 280-2500 nm at 20, 10 and 1
        // nm.
        for text in ["280:2500:20", "280:2500:10", "280:2500:1", "280", "2500"] {
            let grid: WavelengthGrid = text.parse().unwrap();
            assert_eq!(ozone.sample(&grid).unwrap().len(), grid.len(), "{text}");
        }
        // 300 nm on a 10 nm grid: half of the 290 nm bin, half of the 300 nm.
        let sampled = ozone.sample(&"300:1100:10".parse().unwrap()).unwrap();
        assert!((sampled[0] - 0.5 * (7.751e-23 + 1.978e-23)).abs() < 1e-35);
        assert_eq!(sampled[80], 0.0); // 1100 nm
        // At the seams each sample keeps to its own data set.
        assert_eq!(sampled[6], 1.18e-27); // 360 nm: Serdyuchenko's bin only
        assert_eq!(sampled[54], 8.857e-27); // 840 nm: Bogumil's bin only
        assert!((sampled[5] - 0.5 * (4.59e-26 + 7.828e-27)).abs() < 1e-38); // 350 nm
        assert!((sampled[53] - 0.5 * (1.383e-26 + 7.105e-27)).abs() < 1e-38); // 830 nm
    }

    #[test]
    fn grids_inside_360_to_840_nm_sample_exactly_what_they_did() {
        // Today's grids against the Serdyuchenko table alone (the whole
        // table before the range widened): bit for bit.
        let joined = BinnedCrossSection::ozone_233k();
        let serdyuchenko = BinnedCrossSection::parse_csv(OZONE_233K_CSV, "test").unwrap();
        for text in [
            "360:830:1",
            "360:830:10",
            "360:830:5",
            "380:780:20",
            "365:825:10",
            "360:830:470",
            "829:830:1",
            "360",
            "550",
            "830",
        ] {
            let grid: WavelengthGrid = text.parse().unwrap();
            assert_eq!(
                joined.sample(&grid).unwrap(),
                serdyuchenko.sample(&grid).unwrap(),
                "{text}"
            );
        }
    }

    #[test]
    fn the_no2_table_reproduces_vandaeles_ten_nm_means() {
        // The 10 nm means the script integrated directly from Vandaele's
        // 294 K points (its printout), against the means of the embedded 1
        // nm bins: the same within their 4-digit rounding.
        let no2 = BinnedCrossSection::no2_294k();
        for (lo, direct) in [
            (300.0, 1.5687e-23),
            (340.0, 4.3036e-23),
            (400.0, 6.1559e-23),
            (410.0, 5.9226e-23),
            (430.0, 5.5397e-23),
            (440.0, 4.9094e-23),
            (500.0, 2.2347e-23),
            (600.0, 2.4947e-24),
        ] {
            let mean = no2.band_average_m2(lo, lo + 10.0).unwrap();
            assert!(
                (mean / direct - 1.0).abs() < 2e-4,
                "{lo}: {mean} vs {direct}"
            );
        }
        // The data's range, 1 nm bins, zeros past 667 nm and to 2510 nm.
        assert_eq!(no2.bin_width_nm, 1.0);
        assert_eq!(no2.range_nm(), (239.0, ZERO_BINS_END_NM));
        assert!(no2.band_average_m2(667.0, 2510.0).unwrap() == 0.0);
        assert!(no2.band_average_m2(666.0, 667.0).unwrap() > 0.0);
        // The largest 1 nm bin: 7.3e-19 cm^2 (the 413 nm band's peak).
        let largest = no2.cross_sections_m2.iter().cloned().fold(0.0, f64::max);
        assert!((largest / 7.316e-23 - 1.0).abs() < 1e-9, "{largest}");
    }

    #[test]
    fn no2_optical_depths_per_dobson_unit() {
        // The module docs' table: 1 DU, vertical, 10 nm band centred on each
        // wavelength.
        let no2 = BinnedCrossSection::no2_294k();
        for (nm, want) in [
            (340.0, 0.0105),
            (380.0, 0.0161),
            (440.0, 0.0137),
            (500.0, 0.0062),
            (550.0, 0.0030),
            (600.0, 0.00086),
        ] {
            let got =
                MOLECULES_PER_M2_PER_DOBSON_UNIT * no2.band_average_m2(nm - 5.0, nm + 5.0).unwrap();
            assert!((got / want - 1.0).abs() < 0.03, "{nm} nm: {got} vs {want}");
        }
        // Every grid sora accepts is covered.
        for text in ["280:2500:20", "280:2500:1", "280", "2500"] {
            let grid: WavelengthGrid = text.parse().unwrap();
            assert_eq!(no2.sample(&grid).unwrap().len(), grid.len(), "{text}");
        }
    }

    #[test]
    fn zero_padding_keeps_the_published_bins_and_covers_270_to_2510_nm() {
        let o4 = BinnedCrossSection::o2_o2_cia();
        assert_eq!(o4.range_nm(), (ZERO_BINS_START_NM, ZERO_BINS_END_NM));
        let published = csv_bins(O2_O2_CSV);
        assert_eq!(published.len(), 1008); // 335, 336, ..., 1342
        let first = o4.bin_starts_nm.iter().position(|s| *s == 335.0).unwrap();
        assert_eq!(first, 65);
        for (i, (start, value)) in published.iter().enumerate() {
            assert_eq!(o4.bin_starts_nm[first + i], *start);
            assert_eq!(o4.cross_sections_m2[first + i], *value);
        }
        assert!(o4.cross_sections_m2[..first].iter().all(|v| *v == 0.0));
        assert!(
            o4.cross_sections_m2[first + 1008..]
                .iter()
                .all(|v| *v == 0.0)
        );
        // Scaling multiplies every bin.
        let scaled = o4.clone().scaled(2.0);
        assert_eq!(
            scaled.cross_sections_m2[first + 142],
            2.0 * o4.cross_sections_m2[first + 142]
        );
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

    #[test]
    fn no2_in_a_file_and_its_errors() {
        use crate::atmosphere::{Atmosphere, SpeciesModel};
        let file = |column: &str| {
            format!(
                "name = \"g\"\n[planet]\nradius_m = 6360e3\natmosphere_height_m = 100e3\n[sun]\nspectrum = \"astm-e490\"\n[[species]]\nname = \"NO2\"\ncolumn_dobson_units = {column}\nprofile.exponential.scale_height_m = 1000\nabsorption.gas = \"no2\"\n"
            )
        };
        let atmosphere = Atmosphere::from_toml_str(&file("1")).unwrap();
        let SpeciesModel::AbsorbingGas(gas) = &atmosphere.species[0].model else {
            panic!("not a gas");
        };
        assert_eq!(
            gas.cross_section,
            AbsorptionCrossSection::Binned(BinnedCrossSection::no2_294k())
        );
        // 1 DU: the vertical optical depth of the 440 nm band is 0.0137.
        let grid: WavelengthGrid = "430:450:10".parse().unwrap();
        let optics = atmosphere.compute_optics(&grid).unwrap();
        let tau = optics.species[0].optical_depth_extinction()[1];
        assert!((tau / 0.0137 - 1.0).abs() < 0.01, "{tau}");
        // A negative column names the key, the value and the unit.
        let message = Atmosphere::from_toml_str(&file("-0.5"))
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("species[0].column_dobson_units = -0.5 DU"),
            "{message}"
        );
        // An unknown gas lists the built-in ones.
        let message = Atmosphere::from_toml_str(&file("1").replace("\"no2\"", "\"so2\""))
            .unwrap_err()
            .to_string();
        assert!(message.contains("\"ozone\" or \"no2\""), "{message}");
    }

    #[test]
    fn a_column_in_molecules_per_cm2_is_the_same_column_in_dobson_units() {
        use crate::atmosphere::Atmosphere;
        let file = |amount: &str| {
            Atmosphere::from_toml_str(&format!(
                "name = \"g\"\n[planet]\nradius_m = 6360e3\natmosphere_height_m = 100e3\n[sun]\nspectrum = \"astm-e490\"\n[[species]]\nname = \"NO2\"\n{amount}\nprofile.exponential.scale_height_m = 1000\nabsorption.gas = \"no2\"\n"
            ))
        };
        // 0.22 DU = 0.22 x 2.6867e16 = 5.91074e15 molecules cm^-2.
        let grid: WavelengthGrid = "400:460:10".parse().unwrap();
        let tau = |atmosphere: Atmosphere| {
            atmosphere.compute_optics(&grid).unwrap().species[0]
                .optical_depth_extinction()
                .values()
                .to_vec()
        };
        let du = tau(file("column_dobson_units = 0.22").unwrap());
        let molecules = tau(file("column_molecules_cm2 = 5.91074e15").unwrap());
        for (a, b) in du.iter().zip(&molecules) {
            assert!(*a > 1e-3 && (a / b - 1.0).abs() < 1e-12, "{a} vs {b}");
        }
        // Both, or neither of the three amounts: one line naming the keys.
        for (amount, needle) in [
            (
                "column_dobson_units = 0.22\ncolumn_molecules_cm2 = 5.9e15",
                "species[0]: give the column as column_dobson_units or column_molecules_cm2, not both",
            ),
            (
                "",
                "species[0]: an absorbing gas needs exactly one of column_dobson_units, column_molecules_cm2 or number_density_m3",
            ),
            (
                "column_molecules_cm2 = -1",
                "species[0].column_molecules_cm2 = -1 molecules cm^-2",
            ),
        ] {
            let message = file(amount).unwrap_err().to_string();
            assert!(message.contains(needle), "{message}");
            assert!(!message.contains('\n'), "{message}");
        }
        // A scattering species takes no column, in either unit.
        let message = Atmosphere::from_toml_str(
            "name = \"g\"\n[planet]\nradius_m = 6360e3\natmosphere_height_m = 100e3\n[sun]\nspectrum = \"astm-e490\"\n[[species]]\nname = \"air\"\nnumber_density_m3 = 2.5e25\ncolumn_molecules_cm2 = 1e16\nprofile.exponential.scale_height_m = 8000\nscattering.rayleigh.gas = \"air\"\n",
        )
        .unwrap_err()
        .to_string();
        assert!(
            message
                .contains("species[0].column_molecules_cm2: is not used by a scattering species"),
            "{message}"
        );
    }
}
