//! Banded gases: water vapour, the uniformly mixed gases (O2 A, B and
//! gamma bands; CO2 beyond 1100 nm) and CH4 (1.63-2.43 um), from published
//! band models turned into a k-distribution so that a band's radiance is a
//! weighted sum of a few monochromatic solves; the O2 A band (samples at
//! 749.5-780 nm) from k-terms fitted to its lines instead
//! ([`super::o2_a_band`]).
//!
//! # The band model
//! Bird & Riordan (1986, J. Climate Appl. Meteor. 25, 87; SPECTRL2, after
//! Leckner 1978, Solar Energy 20, 143) give, at 122 wavelengths from 300
//! to 4000 nm, coefficients a_w (water vapour, cm^-1 of precipitable
//! water) and a_u (mixed gases, per unit pressure-corrected air mass) and
//! the band transmittances (their eqs. 2-8 and 2-11)
//!
//! ```text
//!     T_w(x) = exp(-0.2385 x / (1 + 20.07 x)^0.45),   x = a_w u
//!     T_u(y) = exp(-1.41 y / (1 + 118.3 y)^0.45),     y = a_u M
//! ```
//!
//! with u the slant precipitable water (cm) and M the slant air column in
//! units of the vertical sea-level column (the air mass times p/1013.25
//! hPa). These are mean transmittances over each coefficient's band, some
//! 5-50 nm wide (the A band is the 762.5 nm point, the 940 nm water band
//! the 925-948 nm points): their curve of growth (x for weak absorption,
//! x^0.55 for strong) is what a band of many lines does, so a single
//! Beer-Lambert coefficient cannot reproduce them. The table
//! (`data/gas_bands_spectrl2.csv`, written by
//! `scripts/gases/make_gas_bands.py` from pvlib 0.13.1's copy, BSD
//! 3-clause) is interpolated linearly in wavelength at each grid sample;
//! below 593 nm (water) and 687 nm (mixed gases) both are 0.
//!
//! # CO2
//! The band model lumps O2 and CO2 in one coefficient array a_u. Its rows
//! are split by band at [`O2_CO2_SPLIT_NM`]: those below 1300 nm (the O2 B
//! and A bands, 690-767.5 nm, and O2's 1.27 um band, 1240-1290 nm) are O2,
//! those above (1.4, 1.6, 2.0 and 2.7 um, and the weak rows between) CO2;
//! the table has no row near 628 nm (the gamma band is below its
//! resolution). y = a_u M is the absorber's path, so `co2_ppm` scales the
//! CO2 rows by `co2_ppm` / [`CO2_REFERENCE_PPM`] and the same k-terms then
//! apply (term j's optical depth is c_u,j times the scaled a_u M). The
//! reference, 330 ppm, is assumed, not read from Leckner (1978), whose
//! paper was not at hand: it is the CO2 of the AFGL/LOWTRAN model
//! atmospheres of the band model's time (LOWTRAN 7's uniformly mixed
//! gases: 330 ppm at every level) and of the air then (Mauna Loa's annual
//! means 1975-1978: 331-335 ppm). At 330 ppm the table is used as it is,
//! unsplit, so an atmosphere without `co2_ppm` is unchanged bit for bit.
//!
//! # CH4
//! LOWTRAN 7's band model (Kneizys et al. 1988, AFGL-TR-88-0177; Pierluissi
//! & Peng 1985, Opt. Eng. 24, 541): the mean transmittance of a 20 cm^-1
//! band is exp(-(C W)^a), a = [`METHANE_EXPONENT`], C per atm cm every
//! 5 cm^-1 over 4110-4690 and 5865-6135 cm^-1 (2.13-2.43 and 1.63-1.71 um;
//! `data/gas_bands_ch4_lowtran7.csv`, written by
//! `scripts/gases/make_ch4_lowtran7.py` from LOWTRAN 7's source, a U.S.
//! Government work), 0 elsewhere (LOWTRAN 7 has no CH4 band below 1.63 um:
//! the weak 1.33 and 0.89 um bands are left out). W is the CH4 path in atm
//! cm scaled by (p / 1013.25 hPa)^0.7139 (T0 / T)^-0.4185; here c ppm in M
//! air columns is W = c M [`ATM_CM_PER_PPM_AIR_COLUMN`] times
//! [`METHANE_PRESSURE_WEIGHT`] (the pressure scaling over an exponential
//! profile of the air's scale height) and T = T0 = 273.15 K (between 220
//! and 290 K the temperature factor is 0.91-1.03: (C W)^a 5 % less at
//! 220 K, 1.5 % more at 290 K), so
//! the band coefficient is a_m = C [`ATM_CM_PER_PPM_AIR_COLUMN`]
//! [`METHANE_PRESSURE_WEIGHT`] per ppm of one air column and z = a_m c M.
//! exp(-z^a) is a mixture of exponentials; its factors c_m,j for the shared
//! weights (`data/gas_bands_ch4_k_terms.csv`, the same script) reproduce
//! it within 3.0 % of max(1 - T, 0.01) over z in [1e-4, 1e3] and within
//! 7.2e-4 of T below (tested: the weights are fixed by water and the mixed
//! gases, so the fit is coarser than theirs). 1.8 ppm absorbs 1 % of the 1.666 um Q branch's 20 cm^-1
//! band and up to 14 % in the 2.3 um band, vertically.
//!
//! # The k-distribution
//! Both transmittances are fitted by one exponential sum with shared
//! weights (`data/gas_bands_k_terms.csv`, the same script; Wiscombe &
//! Evans 1977):
//!
//! ```text
//!     T_w(x) ~ sum_j w_j exp(-c_w,j x),   T_u(y) ~ sum_j w_j exp(-c_u,j y)
//! ```
//!
//! with [`TERMS`] = 5 terms; the largest error is 1.6 % of the absorption
//! 1 - T over x in [1e-6, 1e5] and y in [1e-6, 1e4] (tested here). Term j
//! is an ordinary absorbing gas of absorption coefficient
//! c_w,j a_w(lambda) per cm of precipitable water (c_u,j a_u per sea-level
//! air column), so its optical depth along any path, through any profile,
//! is c_j times the band model's x (or y) of that path: the k-distribution
//! is exact for inhomogeneous paths wherever the band model's scaling with
//! amount holds (the correlated-k assumption). A radiance, irradiance or
//! transmittance of the atmosphere is sum_j w_j times that of the
//! atmosphere with term j ([`k_distribution_terms`]). Where several gases
//! absorb (690-710 nm here; 1.4, 1.9 and 2.7 um in the table; CH4 with
//! water and CO2 at 1.63-1.71 and 2.13-2.43 um) each one that absorbs less
//! at air mass 2 than another takes its effective coefficient (below) in
//! every term, so the weaker overlap the strongest at random rather than
//! fully correlated:
//! the direct beam through the sky's spherical shell then matches
//! T_w T_u within 1.9 % of the absorption there (tested: 0.5 and 3 cm of
//! water, sun at 90 and 30 degrees), and within 1.3 % where one gas
//! absorbs (the A band, the 720, 820, 940 and 1130 nm water bands on a 10
//! nm grid from 700 to 1100 nm). CH4's curve of growth (z^0.58) is far from
//! Beer-Lambert even where it is weak, so where it overlaps water its
//! effective coefficient errs more: with 2.9 cm of water and 1.8 ppm, sun
//! at 60 degrees, the direct beam is within 12 % of max(1 - T, 0.01) of
//! T_w T_m over 1640-2440 nm, 9.8 % at 2270 nm (tested; from the tables,
//! fully correlated terms would err 25 %).
//!
//! # What the model is and is not
//! The band model scales with the absorber amount only: pressure and
//! temperature enter through M (the column of air above a raised ground or
//! an observer aloft), not through line widths, so the A band seen from 10
//! km is the sea-level band with a quarter of the air above (CH4's
//! pressure and temperature scaling is folded into a_m once, for the
//! column above sea level). Its
//! resolution is its coefficients' (the 940 nm water band is the 925-948 nm
//! points, read by linear interpolation at each sample).
//!
//! # The O2 A band from its lines
//! Samples at 749.5-780 nm ([`super::o2_a_band::A_BAND_RANGE_NM`]) take the
//! mixed gases' absorption not from a_u (whose A band is one strong point,
//! 762.5 nm, and a weak one, 767.5 nm) but from k-terms fitted, per 0.5 nm
//! bin, to HITRAN 2016 O2 lines through the U.S. Standard Atmosphere 1976
//! (`data/o2_a_band_k_terms.csv`, written by
//! `scripts/gases/make_lbl_reference.py`) and re-sorted into each sample's
//! band with the band's own five weights ([`SampleAbsorber::Terms`]; the
//! band model has no CO2 there): where the mixed gases absorb most, the
//! sample's terms are summed with those weights, not the shared ones
//! ([`BandAmounts::term_weights`]).
//! Against line by line (`tests/data/gas_line_by_line_reference.csv`, the
//! same lines through the layered, spherical atmosphere) the direct beam
//! averaged over the 1 nm samples of 755-765, 760-770 and 765-775 nm errs
//! by -0.4 to -0.1 % of the absorption 1 - T, a 10 nm grid's sample at each
//! band's centre by as much, a 20 nm grid's samples at 750-780 nm by -1.0
//! to -0.1 % (suns 60 and 15 degrees; measured in
//! `tests/gas_line_by_line.rs`); the band model erred -43 to +62 %. It has no O2-O2
//! collision bands (`o2_o2.rs`, `[gases] o2_o2 = true`) and no NO2 (a
//! cross-section species, `absorption.gas = "no2"`).
//! When one solve is asked for (a sky built from an atmosphere with gases,
//! not summed over terms), each banded gas acts with one effective
//! coefficient: the one whose Beer-Lambert transmittance equals the band
//! model's for twice the vertical column ([`EFFECTIVE_AIR_MASS`]); that is
//! exact at air mass 2 and errs elsewhere (tested below): the zenith sky
//! in the A band (760 nm on a 10 nm grid; Rayleigh air, single scattering,
//! sun 60 degrees) keeps 0.782 of its gas-free radiance with one solve,
//! 0.7123 with the five terms, against 0.7122 from the plane-parallel
//! closed form over the terms. A [`crate::Sky`] built from an atmosphere with banded gases sums
//! the terms itself (`sky/k_terms.rs`), so every command, Python and the
//! explorer get the k-distribution; the effective coefficient is the
//! sky's own optics ([`crate::Sky::optics`]).

use super::o2_a_band;
use super::ozone::{
    AbsorbingGas, AbsorptionCrossSection, GasAmount, MOLECULES_PER_M2_PER_DOBSON_UNIT,
};
use super::profile::DensityProfile;
use super::{Atmosphere, Species, SpeciesModel};
use crate::error::Result;
use crate::spectrum::{SampledSpectrum, Spectrum, TabulatedSpectrum, WavelengthGrid};
use crate::table::NumericTable;

const SPECTRL2_CSV: &str = include_str!("../data/gas_bands_spectrl2.csv");
const K_TERMS_CSV: &str = include_str!("../data/gas_bands_k_terms.csv");
const CH4_CSV: &str = include_str!("../data/gas_bands_ch4_lowtran7.csv");
const CH4_K_TERMS_CSV: &str = include_str!("../data/gas_bands_ch4_k_terms.csv");

/// Terms of the k-distribution.
pub const TERMS: usize = 5;

/// Water molecules per m^2 in 1 cm of precipitable water (1 g cm^-2 /
/// 18.015 g mol^-1 x 6.02214e23 mol^-1).
pub const MOLECULES_PER_M2_PER_CM_PRECIPITABLE_WATER: f64 = 3.3429e26;

/// Molecules of air per m^2 in the vertical column above sea level at
/// 1013.25 hPa (p N_A / (M_air g) with M_air = 28.964 g mol^-1, g =
/// 9.80665 m s^-2): the band model's unit of mixed-gas amount.
pub const AIR_MOLECULES_PER_M2_SEA_LEVEL_COLUMN: f64 = 2.1484e29;

/// The air mass at which a single solve's effective coefficient matches
/// the banded transmittance (the band model's, or the O2 A band's k-terms).
pub const EFFECTIVE_AIR_MASS: f64 = 2.0;

/// The default scale height of water vapour's profile, m (about the
/// mid-latitude summer atmosphere's, from its precipitable water over its
/// surface density).
pub const WATER_SCALE_HEIGHT_M: f64 = 2000.0;

/// The scale height of the mixed gases' profile, m (the air's, near the
/// ground). CH4's profile is the same.
pub const MIXED_GAS_SCALE_HEIGHT_M: f64 = 8000.0;

/// The CO2 mixing ratio, ppm by volume, the band model's mixed-gas
/// coefficients stand for (see the module docs): `gases.co2_ppm`'s
/// default.
pub const CO2_REFERENCE_PPM: f64 = 330.0;

/// Where the mixed-gas table passes from O2 to CO2, nm: its coefficients
/// below (the O2 B, A and 1.27 um bands, 690-1290 nm) are O2's, those above
/// (1.4, 1.6, 2.0 and 2.7 um and beyond) CO2's.
pub const O2_CO2_SPLIT_NM: f64 = 1300.0;

/// The exponent a of LOWTRAN 7's CH4 band transmittance exp(-(C W)^a).
pub const METHANE_EXPONENT: f64 = 0.5844;

/// Molecules per m^3 of an ideal gas at 273.15 K and 1013.25 hPa (the
/// Loschmidt constant, CODATA 2018): the unit of LOWTRAN's atm cm.
pub const LOSCHMIDT_M3: f64 = 2.686_780e25;

/// LOWTRAN 7's pressure scaling of the CH4 amount, (p / p0)^n with n =
/// 0.7139, over an exponential profile of the air's scale height: the
/// scaled column is 1 / (1 + n) of the column.
pub const METHANE_PRESSURE_WEIGHT: f64 = 1.0 / (1.0 + 0.7139);

/// Atm cm of a gas at 1 ppm in one sea-level air column
/// ([`AIR_MOLECULES_PER_M2_SEA_LEVEL_COLUMN`] / [`LOSCHMIDT_M3`], in cm,
/// times 1e-6): 0.79963.
pub const ATM_CM_PER_PPM_AIR_COLUMN: f64 =
    AIR_MOLECULES_PER_M2_SEA_LEVEL_COLUMN / LOSCHMIDT_M3 * 100.0 * 1e-6;

/// Which banded gas.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BandGas {
    /// Water vapour (amount: precipitable water, cm).
    WaterVapour,
    /// The uniformly mixed gases, O2 and CO2 (amount: air columns).
    MixedGases,
    /// CH4 (amount: ppm of one air column).
    Methane,
}

impl BandGas {
    /// Every banded gas.
    pub const ALL: [BandGas; 3] = [BandGas::WaterVapour, BandGas::MixedGases, BandGas::Methane];
}

/// The banded gases of an atmosphere and their vertical amounts above sea
/// level; every banded species carries them, since where several absorb
/// the one that absorbs most keeps the k-terms (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BandAmounts {
    /// Precipitable water, cm (`None`: no water vapour).
    pub water_cm: Option<f64>,
    /// Air columns of O2 and CO2 (`None`: no mixed gases).
    pub mixed_columns: Option<f64>,
    /// CO2, ppm by volume (scales the CO2 part of the mixed gases' table by
    /// `co2_ppm / CO2_REFERENCE_PPM`).
    pub co2_ppm: f64,
    /// CH4, ppm by volume of one air column (`None`: no CH4).
    pub methane_ppm: Option<f64>,
}

impl BandAmounts {
    /// The vertical amount of `gas`, in its unit, when the atmosphere has
    /// it.
    pub fn vertical(&self, gas: BandGas) -> Option<f64> {
        match gas {
            BandGas::WaterVapour => self.water_cm,
            BandGas::MixedGases => self.mixed_columns,
            BandGas::Methane => self.methane_ppm,
        }
    }

    /// The band coefficient of `gas` on `grid` for these amounts: the
    /// table's, with the mixed gases' CO2 part scaled to `co2_ppm`.
    pub fn sampled_coefficients(
        &self,
        gas: BandGas,
        grid: &WavelengthGrid,
    ) -> Result<SampledSpectrum> {
        if gas == BandGas::MixedGases && self.co2_ppm != CO2_REFERENCE_PPM {
            sampled_mixed_coefficients(grid, self.co2_ppm)
        } else {
            sampled_band_coefficients(gas, grid)
        }
    }
}

impl BandAmounts {
    /// One sea-level air column of the mixed gases at the band model's CO2,
    /// no water, no CH4.
    pub fn one_air_column() -> BandAmounts {
        BandAmounts {
            water_cm: None,
            mixed_columns: Some(1.0),
            co2_ppm: CO2_REFERENCE_PPM,
            methane_ppm: None,
        }
    }

    /// Each sample's absorber of `gas` on `grid`: the band model's
    /// coefficient ([`Self::sampled_coefficients`]), except the mixed gases'
    /// samples in the O2 A band ([`o2_a_band::A_BAND_RANGE_NM`]), which take
    /// the k-terms fitted to its lines over their band (the band model has
    /// no CO2 there).
    pub fn sampled_absorbers(
        &self,
        gas: BandGas,
        grid: &WavelengthGrid,
    ) -> Result<Vec<SampleAbsorber>> {
        let a = self.sampled_coefficients(gas, grid)?;
        let lines = if gas == BandGas::MixedGases {
            o2_a_band::terms_on(grid)
        } else {
            vec![None; grid.len()]
        };
        Ok(a.values()
            .iter()
            .zip(lines)
            .map(|(a, k)| k.map_or(SampleAbsorber::Band(*a), SampleAbsorber::Terms))
            .collect())
    }

    /// The banded transmittance of `gas` at each sample of `grid` for
    /// `air_mass` times this vertical amount (the band model's, or the sum
    /// over the O2 A band's k-terms): what the k-distribution reproduces.
    pub fn sampled_transmittance(
        &self,
        gas: BandGas,
        grid: &WavelengthGrid,
        air_mass: f64,
    ) -> Result<Vec<f64>> {
        let amount = air_mass * self.vertical(gas).unwrap_or(0.0);
        Ok(self
            .sampled_absorbers(gas, grid)?
            .into_iter()
            .map(|absorber| GasBand::absorber_transmittance(gas, absorber, amount))
            .collect())
    }

    /// Each sample's weights of the k-distribution's terms on `grid`: the
    /// shared weights ([`k_terms`]), except where the mixed gases take the
    /// O2 A band's k-terms ([`SampleAbsorber::Terms`]) and no other banded
    /// gas absorbs more at [`EFFECTIVE_AIR_MASS`] (the others then take
    /// their effective coefficients in every term, as
    /// `GasBand::coefficient_of` decides): there the band's own weights.
    pub fn term_weights(&self, grid: &WavelengthGrid) -> Result<Vec<[f64; TERMS]>> {
        let shared: [f64; TERMS] = std::array::from_fn(|j| k_terms()[j].weight);
        let Some(columns) = self.mixed_columns else {
            return Ok(vec![shared; grid.len()]);
        };
        let mixed = self.sampled_absorbers(BandGas::MixedGases, grid)?;
        let mut others = Vec::new();
        for gas in [BandGas::WaterVapour, BandGas::Methane] {
            if let Some(amount) = self.vertical(gas) {
                others.push((gas, amount, self.sampled_absorbers(gas, grid)?));
            }
        }
        let absorption = |gas: BandGas, absorber: SampleAbsorber, vertical: f64| {
            1.0 - GasBand::absorber_transmittance(gas, absorber, EFFECTIVE_AIR_MASS * vertical)
        };
        Ok(mixed
            .iter()
            .enumerate()
            .map(|(i, absorber)| match absorber {
                SampleAbsorber::Terms(terms) => {
                    let mine = absorption(BandGas::MixedGases, *absorber, columns);
                    let outdone = others.iter().any(|(gas, amount, absorbers)| {
                        absorption(*gas, absorbers[i], *amount) > mine
                    });
                    if outdone { shared } else { terms.weights }
                }
                SampleAbsorber::Band(_) => shared,
            })
            .collect())
    }
}

/// One sample's absorption by one banded gas.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SampleAbsorber {
    /// The band model's coefficient (a_w, a_u or a_m).
    Band(f64),
    /// k-terms per unit amount with the sample's own weights (the O2 A
    /// band's, from its lines: [`o2_a_band`]).
    Terms(o2_a_band::BandTerms),
}

/// A banded gas' absorption: the band model's coefficient, per molecule,
/// for one k-distribution term or the single-solve effective term.
#[derive(Debug, Clone, PartialEq)]
pub struct GasBand {
    /// Which gas.
    pub gas: BandGas,
    /// The k-distribution term (0..[`TERMS`]); `None`: the effective
    /// coefficient of a single solve.
    pub term: Option<usize>,
    /// The atmosphere's banded gases: this one's vertical amount (the one
    /// the effective coefficient is fitted for) and the others', for the
    /// overlaps.
    pub amounts: BandAmounts,
    /// With a term: per sample (nm), the term this gas takes there in
    /// place of `term` and a factor on its coefficient (a colour image's
    /// merged terms, `sky/k_terms.rs`: one sky carrying a group of terms
    /// at one coefficient); samples not listed take `term`. Empty: every
    /// sample at `term`.
    pub merged: Vec<MergedSample>,
}

/// One sample of [`GasBand::merged`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MergedSample {
    /// The sample's wavelength, nm.
    pub wavelength_nm: f64,
    /// The k-distribution term taken there.
    pub term: usize,
    /// The factor on that term's coefficient.
    pub factor: f64,
}

/// One term: its weight and the factors of x (water), y (mixed gases) and
/// z (CH4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KTerm {
    /// w_j (the weights sum to 1).
    pub weight: f64,
    /// c_w,j.
    pub water_factor: f64,
    /// c_u,j.
    pub mixed_factor: f64,
    /// c_m,j.
    pub methane_factor: f64,
}

/// The band model's transmittance of water vapour for x = a_w u.
pub fn water_band_transmittance(x: f64) -> f64 {
    (-0.2385 * x / (1.0 + 20.07 * x).powf(0.45)).exp()
}

/// The band model's transmittance of the mixed gases for y = a_u M.
pub fn mixed_band_transmittance(y: f64) -> f64 {
    (-1.41 * y / (1.0 + 118.3 * y).powf(0.45)).exp()
}

/// LOWTRAN 7's transmittance of CH4 for z = a_m c M (c in ppm, M air
/// columns): exp(-z^a).
pub fn methane_band_transmittance(z: f64) -> f64 {
    if z <= 0.0 {
        1.0
    } else {
        (-z.powf(METHANE_EXPONENT)).exp()
    }
}

/// The embedded k-distribution terms (parsed once).
pub fn k_terms() -> &'static [KTerm] {
    static PARSED: std::sync::LazyLock<Vec<KTerm>> = std::sync::LazyLock::new(|| {
        let table = NumericTable::parse(K_TERMS_CSV, "embedded gas k-terms")
            .expect("the embedded k-terms are valid");
        let methane = NumericTable::parse(CH4_K_TERMS_CSV, "embedded CH4 k-terms")
            .expect("the embedded CH4 k-terms are valid");
        let terms: Vec<KTerm> = table
            .rows
            .iter()
            .zip(&methane.rows)
            .map(|(row, methane)| {
                assert_eq!(row[0], methane[0], "the CH4 k-terms share the weights");
                KTerm {
                    weight: row[0],
                    water_factor: row[1],
                    mixed_factor: row[2],
                    methane_factor: methane[1],
                }
            })
            .collect();
        assert_eq!(terms.len(), TERMS, "the embedded k-terms have {TERMS} rows");
        assert_eq!(
            methane.rows.len(),
            TERMS,
            "the CH4 k-terms have {TERMS} rows"
        );
        terms
    });
    &PARSED
}

/// The band model's coefficient of `gas` against wavelength: a_w per cm
/// and a_u per air column (at [`CO2_REFERENCE_PPM`]), a_m per ppm of one
/// air column, 200-4000 nm.
pub fn band_coefficients(gas: BandGas) -> TabulatedSpectrum {
    if gas == BandGas::Methane {
        return methane_coefficients();
    }
    let table = NumericTable::parse(SPECTRL2_CSV, "embedded gas band table")
        .expect("the embedded gas band table is valid");
    let column = match gas {
        BandGas::WaterVapour => 1,
        _ => 2,
    };
    TabulatedSpectrum::new(
        table.column(0),
        table.column(column),
        "embedded gas band table",
    )
    .expect("the embedded gas band table is valid")
}

/// CH4's a_m = C [`ATM_CM_PER_PPM_AIR_COLUMN`] [`METHANE_PRESSURE_WEIGHT`]
/// per ppm of one air column, from LOWTRAN 7's C per atm cm.
fn methane_coefficients() -> TabulatedSpectrum {
    let table = NumericTable::parse(CH4_CSV, "embedded CH4 band table")
        .expect("the embedded CH4 band table is valid");
    let per_ppm_column = ATM_CM_PER_PPM_AIR_COLUMN * METHANE_PRESSURE_WEIGHT;
    TabulatedSpectrum::new(
        table.column(0),
        table.column(1).iter().map(|c| c * per_ppm_column).collect(),
        "embedded CH4 band table",
    )
    .expect("the embedded CH4 band table is valid")
}

/// The O2 (`co2 == false`) or CO2 (`co2 == true`) part of the mixed gases'
/// table: a_u on its side of [`O2_CO2_SPLIT_NM`], 0 on the other.
pub fn mixed_gas_part(co2: bool) -> TabulatedSpectrum {
    let all = band_coefficients(BandGas::MixedGases);
    let values = all
        .wavelengths_nm()
        .iter()
        .zip(all.values())
        .map(|(wavelength, a)| {
            let keep = (*wavelength >= O2_CO2_SPLIT_NM) == co2;
            if keep { *a } else { 0.0 }
        })
        .collect();
    TabulatedSpectrum::new(
        all.wavelengths_nm().to_vec(),
        values,
        "embedded gas band table",
    )
    .expect("the embedded gas band table is valid")
}

/// [`band_coefficients`] of `gas` on `grid`, interpolated linearly.
pub fn sampled_band_coefficients(gas: BandGas, grid: &WavelengthGrid) -> Result<SampledSpectrum> {
    Spectrum::Tabulated(band_coefficients(gas)).sample_at_wavelengths(grid)
}

/// The mixed gases' a_u on `grid` with `co2_ppm` of CO2: the O2 part plus
/// `co2_ppm / CO2_REFERENCE_PPM` times the CO2 part (the band model's y =
/// a_u M is the absorber's path, so a CO2 amount scales its a_u).
pub fn sampled_mixed_coefficients(grid: &WavelengthGrid, co2_ppm: f64) -> Result<SampledSpectrum> {
    let o2 = Spectrum::Tabulated(mixed_gas_part(false)).sample_at_wavelengths(grid)?;
    let co2 = Spectrum::Tabulated(mixed_gas_part(true)).sample_at_wavelengths(grid)?;
    let scale = co2_ppm / CO2_REFERENCE_PPM;
    Ok(SampledSpectrum::from_values(
        o2.values()
            .iter()
            .zip(co2.values())
            .map(|(o2, co2)| o2 + scale * co2)
            .collect(),
    ))
}

impl GasBand {
    /// Molecules per m^2 in one unit of this gas' amount.
    fn molecules_per_unit(&self) -> f64 {
        match self.gas {
            BandGas::WaterVapour => MOLECULES_PER_M2_PER_CM_PRECIPITABLE_WATER,
            BandGas::MixedGases => AIR_MOLECULES_PER_M2_SEA_LEVEL_COLUMN,
            BandGas::Methane => 1e-6 * AIR_MOLECULES_PER_M2_SEA_LEVEL_COLUMN,
        }
    }

    /// The band model's transmittance of `gas` for a = `a`, slant amount
    /// `amount`.
    fn band_transmittance(gas: BandGas, a: f64, amount: f64) -> f64 {
        match gas {
            BandGas::WaterVapour => water_band_transmittance(a * amount),
            BandGas::MixedGases => mixed_band_transmittance(a * amount),
            BandGas::Methane => methane_band_transmittance(a * amount),
        }
    }

    /// This gas' vertical amount (0 if the amounts lack it).
    pub fn vertical_amount(&self) -> f64 {
        self.amounts.vertical(self.gas).unwrap_or(0.0)
    }

    /// The transmittance of `gas` as `absorber` describes it for slant
    /// amount `amount`.
    fn absorber_transmittance(gas: BandGas, absorber: SampleAbsorber, amount: f64) -> f64 {
        match absorber {
            SampleAbsorber::Band(a) => Self::band_transmittance(gas, a, amount),
            SampleAbsorber::Terms(terms) => terms.transmittance(amount),
        }
    }

    /// The effective (single-solve) coefficient per unit amount of
    /// `absorber`: Beer-Lambert matching it at [`EFFECTIVE_AIR_MASS`].
    fn effective_coefficient_of(&self, absorber: SampleAbsorber) -> f64 {
        let slant = EFFECTIVE_AIR_MASS * self.vertical_amount();
        let absorbs = match absorber {
            SampleAbsorber::Band(a) => a > 0.0,
            SampleAbsorber::Terms(terms) => terms.k.iter().any(|k| *k > 0.0),
        };
        if !absorbs || slant <= 0.0 {
            0.0
        } else {
            -Self::absorber_transmittance(self.gas, absorber, slant).ln() / slant
        }
    }

    /// The effective (single-solve) coefficient per unit amount at band
    /// coefficient `a`: Beer-Lambert matching the band model at
    /// [`EFFECTIVE_AIR_MASS`].
    pub fn effective_coefficient_per_unit_amount(&self, a: f64) -> f64 {
        self.effective_coefficient_of(SampleAbsorber::Band(a))
    }

    /// Absorption coefficient per unit amount (per cm of precipitable water,
    /// per air column, per ppm of an air column) at band coefficient `a`,
    /// where the other banded gases of the atmosphere have coefficients
    /// `others` (gas, a): if one of them absorbs more at
    /// [`EFFECTIVE_AIR_MASS`], this gas takes its effective coefficient in
    /// every term.
    pub fn coefficient_per_unit_amount(
        &self,
        a: f64,
        others: impl IntoIterator<Item = (BandGas, f64)>,
    ) -> f64 {
        self.coefficient_of(
            SampleAbsorber::Band(a),
            others
                .into_iter()
                .map(|(gas, a)| (gas, SampleAbsorber::Band(a))),
        )
    }

    /// [`Self::coefficient_per_unit_amount`] for any sample's absorber (the
    /// band model's coefficient or the O2 A band's k-terms).
    fn coefficient_of(
        &self,
        own: SampleAbsorber,
        others: impl IntoIterator<Item = (BandGas, SampleAbsorber)>,
    ) -> f64 {
        let Some(j) = self.term else {
            return self.effective_coefficient_of(own);
        };
        let absorption = |gas: BandGas, absorber: SampleAbsorber, vertical: f64| {
            1.0 - Self::absorber_transmittance(gas, absorber, EFFECTIVE_AIR_MASS * vertical)
        };
        let mine = absorption(self.gas, own, self.vertical_amount());
        for (gas, other) in others {
            let Some(amount) = self.amounts.vertical(gas).filter(|_| gas != self.gas) else {
                continue;
            };
            if absorption(gas, other, amount) > mine {
                return self.effective_coefficient_of(own);
            }
        }
        match own {
            SampleAbsorber::Terms(terms) => terms.k[j],
            SampleAbsorber::Band(a) => {
                let term = k_terms()[j];
                let factor = match self.gas {
                    BandGas::WaterVapour => term.water_factor,
                    BandGas::MixedGases => term.mixed_factor,
                    BandGas::Methane => term.methane_factor,
                };
                factor * a
            }
        }
    }

    /// Cross-section per molecule on `grid`, m^2.
    pub(crate) fn sample(&self, grid: &WavelengthGrid) -> Result<SampledSpectrum> {
        let own = self.amounts.sampled_absorbers(self.gas, grid)?;
        let mut others = Vec::new();
        for gas in BandGas::ALL {
            if gas != self.gas && self.amounts.vertical(gas).is_some() {
                others.push((gas, self.amounts.sampled_absorbers(gas, grid)?));
            }
        }
        let per_molecule = 1.0 / self.molecules_per_unit();
        Ok(SampledSpectrum::from_values(
            own.iter()
                .enumerate()
                .map(|(i, absorber)| {
                    let others = others.iter().map(|(gas, values)| (*gas, values[i]));
                    let wavelength_nm = grid.wavelength_nm(i);
                    let merged = self
                        .merged
                        .iter()
                        .find(|m| (m.wavelength_nm - wavelength_nm).abs() < 1e-6);
                    let coefficient = match merged {
                        Some(m) => {
                            let at = GasBand {
                                gas: self.gas,
                                term: Some(m.term),
                                amounts: self.amounts,
                                merged: Vec::new(),
                            };
                            m.factor * at.coefficient_of(*absorber, others)
                        }
                        None => self.coefficient_of(*absorber, others),
                    };
                    coefficient * per_molecule
                })
                .collect(),
        ))
    }

    /// The wavelengths the table covers, nm.
    pub(crate) fn range_nm(&self) -> (f64, f64) {
        band_coefficients(self.gas).range_nm()
    }
}

/// What an atmosphere file's `[gases]` asks for (`banded_gas_species`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BandedGases {
    /// Precipitable water above sea level, cm, and the scale height of its
    /// exponential profile, m (`None`, or 0 cm: no water vapour).
    pub water: Option<(f64, f64)>,
    /// The O2 and CO2 of one sea-level air column.
    pub mixed_gases: bool,
    /// CO2 in the mixed gases, ppm ([`CO2_REFERENCE_PPM`]: the band model's).
    pub co2_ppm: f64,
    /// CH4, ppm of one sea-level air column (0: none).
    pub ch4_ppm: f64,
}

impl BandedGases {
    /// Water vapour (`water`) and the mixed gases (`mixed_gases`) at the
    /// band model's CO2, no CH4.
    pub fn new(water: Option<(f64, f64)>, mixed_gases: bool) -> BandedGases {
        BandedGases {
            water,
            mixed_gases,
            co2_ppm: CO2_REFERENCE_PPM,
            ch4_ppm: 0.0,
        }
    }
}

/// The banded gases as species: water vapour (precipitable water above
/// sea level, cm, on an exponential profile), named `water vapour`; when
/// `mixed_gases`, the O2 and CO2 of one sea-level air column over an
/// exponential profile of [`MIXED_GAS_SCALE_HEIGHT_M`], named
/// `mixed gases (O2, CO2)`; with `ch4_ppm` > 0, that much CH4 in one air
/// column on the same profile, named `methane (CH4)`.
pub fn banded_gas_species(gases: &BandedGases) -> Vec<Species> {
    let water = gases.water.filter(|(cm, _)| *cm > 0.0);
    let amounts = BandAmounts {
        water_cm: water.map(|(cm, _)| cm),
        mixed_columns: gases.mixed_gases.then_some(1.0),
        co2_ppm: gases.co2_ppm,
        methane_ppm: (gases.ch4_ppm > 0.0).then_some(gases.ch4_ppm),
    };
    let species = |name: &str, gas: BandGas, scale_height_m: f64, molecules_per_m2: f64| Species {
        name: name.into(),
        profile: DensityProfile::Exponential { scale_height_m },
        model: SpeciesModel::AbsorbingGas(AbsorbingGas {
            cross_section: AbsorptionCrossSection::Band(GasBand {
                gas,
                term: None,
                amounts,
                merged: Vec::new(),
            }),
            amount: GasAmount::ColumnDobsonUnits(
                molecules_per_m2 / MOLECULES_PER_M2_PER_DOBSON_UNIT,
            ),
        }),
    };
    let mut out = Vec::new();
    if let Some((cm, scale_height_m)) = water {
        out.push(species(
            "water vapour",
            BandGas::WaterVapour,
            scale_height_m,
            cm * MOLECULES_PER_M2_PER_CM_PRECIPITABLE_WATER,
        ));
    }
    if let Some(columns) = amounts.mixed_columns {
        out.push(species(
            "mixed gases (O2, CO2)",
            BandGas::MixedGases,
            MIXED_GAS_SCALE_HEIGHT_M,
            columns * AIR_MOLECULES_PER_M2_SEA_LEVEL_COLUMN,
        ));
    }
    if let Some(ppm) = amounts.methane_ppm {
        out.push(species(
            "methane (CH4)",
            BandGas::Methane,
            MIXED_GAS_SCALE_HEIGHT_M,
            ppm * 1e-6 * AIR_MOLECULES_PER_M2_SEA_LEVEL_COLUMN,
        ));
    }
    out
}

/// Whether `atmosphere` has a banded gas.
pub fn has_gas_bands(atmosphere: &Atmosphere) -> bool {
    atmosphere.species.iter().any(|s| band_of(s).is_some())
}

/// How many monochromatic solves a [`crate::Sky`] of `atmosphere` makes per
/// wavelength: [`TERMS`] with a banded gas (it sums the k-terms), else 1.
pub fn solves_per_wavelength(atmosphere: &Atmosphere) -> usize {
    if has_gas_bands(atmosphere) { TERMS } else { 1 }
}

/// Whether `atmosphere` has a banded gas at its single solve's effective
/// coefficient (not at a k-term): the atmosphere whose terms a
/// [`crate::Sky`] sums (`sky/k_terms.rs`).
pub fn has_untermed_gas_bands(atmosphere: &Atmosphere) -> bool {
    atmosphere
        .species
        .iter()
        .any(|s| band_of(s).is_some_and(|band| band.term.is_none()))
}

/// The first and last sample of `grid` at which a banded gas of
/// `atmosphere` absorbs differently in different k-distribution terms
/// (its cross-sections at terms 0..[`TERMS`] not all equal); `None` where
/// they are equal everywhere (no band on the grid). Outside that span every
/// term's atmosphere is the same at each sample, so one solve there is
/// the sum over the terms (their weights times the same value).
pub fn term_span(atmosphere: &Atmosphere, grid: &WavelengthGrid) -> Result<Option<(usize, usize)>> {
    let mut differs = vec![false; grid.len()];
    for band in atmosphere.species.iter().filter_map(band_of) {
        let first = GasBand {
            term: Some(0),
            ..band.clone()
        }
        .sample(grid)?;
        for j in 1..TERMS {
            let other = GasBand {
                term: Some(j),
                ..band.clone()
            }
            .sample(grid)?;
            for (d, (a, b)) in differs
                .iter_mut()
                .zip(first.values().iter().zip(other.values()))
            {
                *d |= a != b;
            }
        }
    }
    let first = differs.iter().position(|d| *d);
    let last = differs.iter().rposition(|d| *d);
    Ok(first.zip(last))
}

/// The vertical absorption optical depth of each banded gas of
/// `atmosphere` from `altitude_m` above the ground to the top, at each
/// sample of `grid`, [gas][sample] in the species' order: a lower bound on
/// that gas' optical depth along any path from the top of the atmosphere
/// to a point at that altitude (the path crosses every shell above it,
/// along at least the shell's thickness).
pub(crate) fn banded_depths_above(
    atmosphere: &Atmosphere,
    grid: &WavelengthGrid,
    altitude_m: f64,
) -> Result<Vec<Vec<f64>>> {
    let banded = Atmosphere {
        species: atmosphere
            .species
            .iter()
            .filter(|s| band_of(s).is_some())
            .cloned()
            .collect(),
        name: atmosphere.name.clone(),
        description: String::new(),
        planet: atmosphere.planet.clone(),
        sun: atmosphere.sun.clone(),
    };
    let top_m = atmosphere.planet.top_above_sea_level_m() - atmosphere.planet.ground_altitude_m();
    let optics = banded.compute_optics(grid)?;
    Ok(optics
        .species
        .iter()
        .map(|s| {
            let column_m = s
                .profile
                .column_between_m(altitude_m.clamp(0.0, top_m), top_m);
            s.extinction_per_m
                .values()
                .iter()
                .map(|b| b * column_m)
                .collect()
        })
        .collect())
}

/// The banded gas of a species, to change.
pub(crate) fn band_of_mut(species: &mut Species) -> Option<&mut GasBand> {
    match &mut species.model {
        SpeciesModel::AbsorbingGas(AbsorbingGas {
            cross_section: AbsorptionCrossSection::Band(band),
            ..
        }) => Some(band),
        _ => None,
    }
}

pub(crate) fn band_of(species: &Species) -> Option<&GasBand> {
    match &species.model {
        SpeciesModel::AbsorbingGas(AbsorbingGas {
            cross_section: AbsorptionCrossSection::Band(band),
            ..
        }) => Some(band),
        _ => None,
    }
}

/// The atmospheres whose weighted sum is `atmosphere`'s k-distribution on
/// `grid`: (w_j at each sample, the atmosphere with every banded gas at
/// term j), [`TERMS`] of them; (1, the atmosphere) when it has no banded
/// gas. Any quantity linear in the light (radiance, irradiance,
/// transmittance) of the atmosphere at a sample is sum_j w_j times that
/// quantity of atmosphere j there. The weights are the shared ones
/// ([`k_terms`]) but in the O2 A band, whose samples have their own
/// ([`BandAmounts::term_weights`]).
pub fn k_distribution_terms(
    atmosphere: &Atmosphere,
    grid: &WavelengthGrid,
) -> Result<Vec<(SampledSpectrum, Atmosphere)>> {
    let Some(amounts) = atmosphere
        .species
        .iter()
        .find_map(band_of)
        .map(|b| b.amounts)
    else {
        return Ok(vec![(
            SampledSpectrum::constant(grid.len(), 1.0),
            atmosphere.clone(),
        )]);
    };
    let weights = amounts.term_weights(grid)?;
    Ok((0..TERMS)
        .map(|j| {
            let mut at_term = atmosphere.clone();
            for band in at_term.species.iter_mut().filter_map(band_of_mut) {
                band.term = Some(j);
            }
            (
                SampledSpectrum::from_values(weights.iter().map(|w| w[j]).collect()),
                at_term,
            )
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mixed gases' banded transmittance on `grid` for `columns` air
    /// columns: T_u(a_u columns), or in the O2 A band the sum over its
    /// line-derived k-terms.
    fn mixed_transmittance(grid: &WavelengthGrid, columns: f64) -> Vec<f64> {
        BandAmounts::one_air_column()
            .sampled_transmittance(BandGas::MixedGases, grid, columns)
            .unwrap()
    }

    fn log_points(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f64> {
        (0..n).map(move |i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
    }

    #[test]
    fn the_k_distribution_reproduces_the_band_model_within_two_percent_of_the_absorption() {
        let terms = k_terms();
        let total: f64 = terms.iter().map(|t| t.weight).sum();
        assert!((total - 1.0).abs() < 1e-5, "{total}");
        let sum = |x: f64, water: bool| -> f64 {
            terms
                .iter()
                .map(|t| {
                    let c = if water {
                        t.water_factor
                    } else {
                        t.mixed_factor
                    };
                    t.weight * (-c * x).exp()
                })
                .sum()
        };
        let mut worst: f64 = 0.0;
        for (water, hi) in [(true, 1e5), (false, 1e4)] {
            for x in log_points(1e-6, hi, 1000) {
                let band = if water {
                    water_band_transmittance(x)
                } else {
                    mixed_band_transmittance(x)
                };
                let error = (sum(x, water) - band).abs() / (1.0 - band).max(1e-3);
                worst = worst.max(error);
            }
        }
        // The script's fit reports 0.0157; a denser check finds the same.
        assert!(worst < 0.02, "{worst}");
        assert!(worst > 0.005, "{worst}: not the fit the table says");
    }

    #[test]
    fn weak_absorption_is_beer_lambert_with_the_band_models_slope() {
        // For x -> 0, T_w = 1 - 0.2385 x: sum_j w_j c_w,j = 0.2385 (and
        // 1.41 for the mixed gases) within the fit's error.
        let terms = k_terms();
        let slope_w: f64 = terms.iter().map(|t| t.weight * t.water_factor).sum();
        let slope_u: f64 = terms.iter().map(|t| t.weight * t.mixed_factor).sum();
        assert!((slope_w / 0.2385 - 1.0).abs() < 0.02, "{slope_w}");
        assert!((slope_u / 1.41 - 1.0).abs() < 0.02, "{slope_u}");
    }

    /// sum_j w_j exp(-tau_j) over the vertical optical depths of the k-terms
    /// of `atmosphere` on `grid`, times `air_mass` (a plane-parallel slant
    /// path through every profile).
    fn k_transmittance(atmosphere: &Atmosphere, grid: &WavelengthGrid, air_mass: f64) -> Vec<f64> {
        let mut t = vec![0.0; grid.len()];
        for (weights, at_term) in k_distribution_terms(atmosphere, grid).unwrap() {
            let optics = at_term.compute_optics(grid).unwrap();
            let tau: Vec<f64> = optics
                .species
                .iter()
                .filter(|s| {
                    s.name == "water vapour"
                        || s.name.starts_with("mixed gases")
                        || s.name.starts_with("methane")
                })
                .fold(vec![0.0; grid.len()], |mut acc, s| {
                    for (a, v) in acc.iter_mut().zip(s.optical_depth_extinction().values()) {
                        *a += v;
                    }
                    acc
                });
            for ((ti, tau), weight) in t.iter_mut().zip(tau).zip(weights.values()) {
                *ti += weight * (-air_mass * tau).exp();
            }
        }
        t
    }

    fn gas_atmosphere(water_cm: f64) -> Atmosphere {
        let mut atmosphere = Atmosphere::preset("earth-clear").unwrap();
        atmosphere
            .species
            .extend(banded_gas_species(&BandedGases::new(
                Some((water_cm, 2000.0)),
                true,
            )));
        atmosphere
    }

    #[test]
    fn columns_through_the_optics_give_the_band_models_transmittance() {
        // The species' optical depths, through their profiles and the
        // atmosphere's top, are the band model's amounts: the k-sum of the
        // slant path is T_w(a_w W m) where only water absorbs (850 nm, a
        // weak band, and 940 nm, a strong one) and T_u(a_u m) where (nearly)
        // only the mixed gases do (the A band), for two water columns and
        // air masses 1 and 3 (sun 90 and 19.5 degrees).
        let grid = WavelengthGrid::new(760.0, 940.0, 90.0).unwrap(); // 760, 850, 940
        let a_w = sampled_band_coefficients(BandGas::WaterVapour, &grid).unwrap();
        let a_u = sampled_band_coefficients(BandGas::MixedGases, &grid).unwrap();
        assert!(a_w[0] < 1e-4); // 757.5-762.5 nm: water nearly absent
        assert!(a_u[2] == 0.0 && a_w[2] > 10.0);
        for water_cm in [0.5, 3.0] {
            let atmosphere = gas_atmosphere(water_cm);
            for air_mass in [1.0, 3.0] {
                let k = k_transmittance(&atmosphere, &grid, air_mass);
                // The atmosphere's top (100 km) cuts exp(-100/8) of the mixed
                // gases' column and nothing measurable of water's.
                let air_column = 1.0 - (-atmosphere.planet.top_above_sea_level_m() / 8000.0).exp();
                let t_u = mixed_transmittance(&grid, air_column * air_mass);
                for i in 0..3 {
                    let want = t_u[i] * water_band_transmittance(a_w[i] * water_cm * air_mass);
                    let error = (k[i] - want).abs() / (1.0 - want);
                    assert!(
                        error < 0.02,
                        "W {water_cm} m {air_mass} sample {i}: {} vs {want}",
                        k[i]
                    );
                }
            }
        }
    }

    #[test]
    fn the_a_band_from_10_km_has_a_quarter_of_the_air_above() {
        // From a ground raised to 10 km the mixed gases' column is
        // exp(-10/8) = 0.29 of sea level's, and the A band's absorption
        // (1 - T) at air mass 1 follows the band model's curve of growth,
        // not the column's ratio (a strong band saturates).
        let grid = WavelengthGrid::new(760.0, 760.0, 10.0).unwrap();
        let sea = gas_atmosphere(1.0);
        let mut high = sea.clone();
        high.planet = high.planet.with_ground_altitude_m(10_000.0).unwrap();
        let t_sea = k_transmittance(&sea, &grid, 1.0)[0];
        let t_high = k_transmittance(&high, &grid, 1.0)[0];
        let fraction = (-10_000.0 / 8000.0f64).exp();
        let want_sea = mixed_transmittance(&grid, 1.0)[0];
        let want_high = mixed_transmittance(&grid, fraction)[0];
        for (got, want) in [(t_sea, want_sea), (t_high, want_high)] {
            assert!((got - want).abs() / (1.0 - want) < 0.02, "{got} vs {want}");
        }
        // Saturation: 29 % of the air gives well over 29 % of the absorption.
        let ratio = (1.0 - t_high) / (1.0 - t_sea);
        assert!(ratio > 0.45 && ratio < 0.75, "{ratio}");
    }

    #[test]
    fn one_effective_term_is_exact_at_air_mass_2_and_errs_elsewhere() {
        // The single-solve coefficient reproduces the band model at
        // EFFECTIVE_AIR_MASS and, being Beer-Lambert, overestimates the
        // absorption of longer paths and underestimates shorter ones.
        let band = GasBand {
            gas: BandGas::WaterVapour,
            term: None,
            amounts: BandAmounts {
                water_cm: Some(1.5),
                mixed_columns: Some(1.0),
                co2_ppm: CO2_REFERENCE_PPM,
                methane_ppm: None,
            },
            merged: Vec::new(),
        };
        let a = 27.0; // 930 nm
        let k = band.coefficient_per_unit_amount(a, [(BandGas::MixedGases, 0.0)]);
        let t = |m: f64| (-k * 1.5 * m).exp();
        let exact = |m: f64| water_band_transmittance(a * 1.5 * m);
        assert!((t(2.0) - exact(2.0)).abs() < 1e-12);
        assert!(t(1.0) > exact(1.0) && t(5.0) < exact(5.0));
        let error5 = ((1.0 - t(5.0)) - (1.0 - exact(5.0))) / (1.0 - exact(5.0));
        assert!(error5 > 0.05, "{error5}");
    }

    const FILE: &str = "name = \"g\"\n[planet]\nradius_m = 6360e3\natmosphere_height_m = 100e3\n[sun]\nspectrum = \"astm-e490\"\n";

    #[test]
    fn the_gases_table_adds_the_two_species_and_checks_its_values() {
        let atmosphere =
            Atmosphere::from_toml_str(&format!("{FILE}[gases]\nprecipitable_water_cm = 2.9\n"))
                .unwrap();
        let names: Vec<&str> = atmosphere.species.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["water vapour", "mixed gases (O2, CO2)"]);
        assert!(has_gas_bands(&atmosphere));
        // 2.9 cm of water on the grid: the vertical column of the effective
        // coefficient at 940 nm is -ln T_w(2 a_w W) / 2.
        let grid = WavelengthGrid::new(940.0, 940.0, 10.0).unwrap();
        let optics = atmosphere.compute_optics(&grid).unwrap();
        let tau = optics.species[0].optical_depth_extinction()[0];
        let a = 55.0 + (940.0 - 937.0) * (45.0 - 55.0) / 11.0; // 55 at 937, 45 at 948 nm
        let want = -water_band_transmittance(a * 2.9 * 2.0).ln() / 2.0;
        assert!((tau / want - 1.0).abs() < 1e-3, "{tau} vs {want}");
        let only_water = Atmosphere::from_toml_str(&format!(
            "{FILE}[gases]\nprecipitable_water_cm = 1\nmixed_gases = false\n"
        ))
        .unwrap();
        assert_eq!(only_water.species.len(), 1);
        for (bad, needle) in [
            (
                "precipitable_water_cm = -1",
                "gases.precipitable_water_cm = -1 cm",
            ),
            (
                "precipitable_water_cm = 1\nwater_scale_height_m = 0",
                "gases.water_scale_height_m = 0 m",
            ),
            (
                "precipitable_water_cm = 1\nozone = 3",
                "unknown field `ozone`",
            ),
        ] {
            let message = Atmosphere::from_toml_str(&format!("{FILE}[gases]\n{bad}\n"))
                .unwrap_err()
                .to_string();
            assert!(message.contains(needle), "{message}");
        }
        // A file's own species may not take a name [gases] gives.
        let clash = format!(
            "{FILE}[[species]]\nname = \"water vapour\"\nnumber_density_m3 = 1\nprofile.exponential.scale_height_m = 8000\nabsorption.gas = \"ozone\"\n[gases]\nprecipitable_water_cm = 1\n"
        );
        let message = Atmosphere::from_toml_str(&clash).unwrap_err().to_string();
        assert!(message.contains("species[0].name"), "{message}");
    }

    /// The banded species' vertical optical depths on `grid` for each
    /// k-term and the effective solve.
    fn band_optical_depths(atmosphere: &Atmosphere, grid: &WavelengthGrid) -> Vec<Vec<f64>> {
        let mut terms = k_distribution_terms(atmosphere, grid).unwrap();
        terms.push((
            SampledSpectrum::constant(grid.len(), 1.0),
            atmosphere.clone(),
        ));
        terms
            .iter()
            .flat_map(|(_, at_term)| {
                at_term
                    .compute_optics(grid)
                    .unwrap()
                    .species
                    .iter()
                    .map(|s| s.optical_depth_extinction().values().to_vec())
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    #[test]
    fn co2_at_the_band_models_amount_is_the_key_absent_bit_for_bit() {
        // 1200-2100 nm every 5 nm: the O2 1.27 um band, the O2/CO2 split
        // (1290-1320 nm), water's 1.4 and 1.9 um bands and CO2's.
        let grid = WavelengthGrid::new(1200.0, 2100.0, 5.0).unwrap();
        let absent =
            Atmosphere::from_toml_str(&format!("{FILE}[gases]\nprecipitable_water_cm = 2.9\n"))
                .unwrap();
        let given = Atmosphere::from_toml_str(&format!(
            "{FILE}[gases]\nprecipitable_water_cm = 2.9\nco2_ppm = 330\n"
        ))
        .unwrap();
        assert_eq!(absent, given);
        assert_eq!(
            band_optical_depths(&absent, &grid),
            band_optical_depths(&given, &grid)
        );
        // The split table summed back is the table (its two parts cover
        // every row once): to rounding, on a grid that falls between rows.
        let fine = WavelengthGrid::new(600.0, 2500.0, 1.0).unwrap();
        let whole = sampled_band_coefficients(BandGas::MixedGases, &fine).unwrap();
        let split = sampled_mixed_coefficients(&fine, CO2_REFERENCE_PPM).unwrap();
        for i in 0..fine.len() {
            assert!(
                (whole[i] - split[i]).abs() <= 1e-14 * whole[i].abs(),
                "{} nm: {} vs {}",
                fine.wavelength_nm(i),
                whole[i],
                split[i]
            );
        }
    }

    #[test]
    fn doubling_co2_deepens_the_2_um_band_as_the_band_model_says_and_leaves_o2_alone() {
        // Mixed gases only (no water), 330 and 660 ppm of CO2: at 2005 nm
        // (a_u = 21, CO2's 2.0 um band) the k-sum of the slant column is
        // T_u(s a_u M m) with s = 1 and 2; the A band (760 nm) and the
        // 1.27 um O2 band keep their optical depths bit for bit.
        let grid = WavelengthGrid::new(760.0, 2005.0, 5.0).unwrap();
        let index = |nm: f64| ((nm - 760.0) / 5.0).round() as usize;
        let at = |ppm: f64| {
            Atmosphere::from_toml_str(&format!(
                "{FILE}[gases]\nprecipitable_water_cm = 0\nco2_ppm = {ppm}\n"
            ))
            .unwrap()
        };
        let (single, double) = (at(330.0), at(660.0));
        let a_u = sampled_band_coefficients(BandGas::MixedGases, &grid).unwrap();
        let column = 1.0 - (-100e3 / MIXED_GAS_SCALE_HEIGHT_M).exp();
        let i = index(2005.0);
        assert_eq!(a_u[i], 21.0);
        for air_mass in [1.0, 3.0] {
            let t1 = k_transmittance(&single, &grid, air_mass)[i];
            let t2 = k_transmittance(&double, &grid, air_mass)[i];
            let want1 = mixed_band_transmittance(a_u[i] * column * air_mass);
            let want2 = mixed_band_transmittance(2.0 * a_u[i] * column * air_mass);
            println!(
                "2005 nm, air mass {air_mass}: 1 - T = {} (330 ppm), {} (660 ppm); band model {} and {}",
                1.0 - t1,
                1.0 - t2,
                1.0 - want1,
                1.0 - want2
            );
            for (got, want) in [(t1, want1), (t2, want2)] {
                assert!((got - want).abs() / (1.0 - want) < 0.02, "{got} vs {want}");
            }
            // Deeper, by less than double (the band saturates), and by the
            // band model's ratio within the two 2 % errors.
            let ratio = (1.0 - t2) / (1.0 - t1);
            let want = (1.0 - want2) / (1.0 - want1);
            assert!(ratio > 1.1 && ratio < 2.0, "{ratio}");
            assert!((ratio / want - 1.0).abs() < 0.03, "{ratio} vs {want}");
        }
        let (d1, d2) = (
            band_optical_depths(&single, &grid),
            band_optical_depths(&double, &grid),
        );
        for nm in [760.0, 1270.0] {
            for (one, two) in d1.iter().zip(&d2) {
                assert_eq!(one[index(nm)], two[index(nm)], "{nm} nm");
            }
        }
        assert!(d2[0][i] > 1.5 * d1[0][i]);
        // No CO2: the 2.0 um band is gone, the A band stays.
        let none = band_optical_depths(&at(0.0), &grid);
        assert_eq!(none[0][i], 0.0);
        assert_eq!(none[0][index(760.0)], d1[0][index(760.0)]);
    }

    #[test]
    fn the_ch4_k_distribution_reproduces_lowtran7s_transmittance() {
        // exp(-y^0.5844) against sum_j w_j exp(-c_m,j y): within 3.1 % of
        // max(1 - T, 0.01) over y in [1e-4, 1e3] (the script's fit: 0.0304),
        // and within 7.3e-4 of T below (where 1 - T < 0.0046).
        let k = |y: f64| -> f64 {
            k_terms()
                .iter()
                .map(|term| term.weight * (-term.methane_factor * y).exp())
                .sum()
        };
        let mut worst: f64 = 0.0;
        for y in log_points(1e-4, 1e3, 2000) {
            let t = methane_band_transmittance(y);
            worst = worst.max((k(y) - t).abs() / (1.0 - t).max(0.01));
        }
        let mut worst_weak: f64 = 0.0;
        for y in log_points(1e-9, 1e-4, 2000) {
            worst_weak = worst_weak.max((k(y) - methane_band_transmittance(y)).abs());
        }
        println!(
            "CH4 k-terms: {worst} of max(1 - T, 0.01) above y = 1e-4, {worst_weak} of T below"
        );
        assert!(worst < 0.031 && worst > 0.01, "{worst}");
        assert!(worst_weak < 7.3e-4 && worst_weak > 1e-4, "{worst_weak}");
    }

    #[test]
    fn ch4_columns_follow_lowtran7s_band_model() {
        // 1.8 ppm of CH4 alone (no water, no mixed gases): the k-sum of the
        // slant column at the 1.666 um Q branch and in the 2.3 um band is
        // exp(-(a_m c M m)^0.5844), within the fit's error.
        let atmosphere = Atmosphere::from_toml_str(&format!(
            "{FILE}[gases]\nprecipitable_water_cm = 0\nmixed_gases = false\nch4_ppm = 1.8\n"
        ))
        .unwrap();
        let names: Vec<&str> = atmosphere.species.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["methane (CH4)"]);
        let grid = WavelengthGrid::new(1650.0, 2400.0, 5.0).unwrap();
        let a_m = sampled_band_coefficients(BandGas::Methane, &grid).unwrap();
        let column = 1.0 - (-100e3 / MIXED_GAS_SCALE_HEIGHT_M).exp();
        for air_mass in [1.0, 3.0] {
            let k = k_transmittance(&atmosphere, &grid, air_mass);
            let mut deepest: (f64, f64) = (0.0, 1.0);
            for i in 0..grid.len() {
                let z = a_m[i] * 1.8 * column * air_mass;
                let want = methane_band_transmittance(z);
                let ok = if z >= 1e-4 {
                    (k[i] - want).abs() / (1.0 - want).max(0.01) < 0.031
                } else {
                    (k[i] - want).abs() < 7.3e-4
                };
                assert!(
                    ok,
                    "{} nm, m {air_mass}: {} vs {want}",
                    grid.wavelength_nm(i),
                    k[i]
                );
                if want < deepest.1 {
                    deepest = (grid.wavelength_nm(i), want);
                }
            }
            println!(
                "CH4 1.8 ppm, air mass {air_mass}: deepest T = {} at {} nm",
                deepest.1, deepest.0
            );
        }
        // The 1.666 um Q branch (LOWTRAN 7's C' = -3.3351 at 6005 cm^-1):
        // a_m = 10^C' 0.79963 / 1.7139 per ppm of one air column.
        let q = WavelengthGrid::new(1e7 / 6005.0, 1e7 / 6005.0, 1.0).unwrap();
        let a_q = sampled_band_coefficients(BandGas::Methane, &q).unwrap()[0];
        let want = 10f64.powf(-3.3351) * 0.79963 / 1.7139;
        assert!((a_q / want - 1.0).abs() < 1e-4, "{a_q} vs {want}");
        // Nothing below 1.63 um, nor between the bands.
        let outside = WavelengthGrid::new(700.0, 1620.0, 10.0).unwrap();
        let none = sampled_band_coefficients(BandGas::Methane, &outside).unwrap();
        assert!(none.values().iter().all(|v| *v == 0.0));
        let between = WavelengthGrid::new(1720.0, 2120.0, 10.0).unwrap();
        let none = sampled_band_coefficients(BandGas::Methane, &between).unwrap();
        assert!(none.values().iter().all(|v| *v == 0.0));
    }

    #[test]
    fn where_ch4_and_water_overlap_the_stronger_keeps_the_terms() {
        // 2.9 cm of water and 1.8 ppm of CH4 over CH4's two bands: the
        // direct beam through the sky's slant path, summed over the terms,
        // over the gas-free beam, against T_w T_m (random overlap). The
        // weaker gas takes its Beer-Lambert coefficient exact at air mass
        // 2, and CH4's curve of growth (z^0.58) is far from Beer-Lambert even
        // where it is weak: with the sun at 60 degrees the k-sum is within
        // 12 % of max(1 - T, 0.01) (10 % expected from the tables at 5 nm).
        use crate::sky::Sky;
        let with = |gases: &str| {
            Atmosphere::from_toml_str(&format!(
                "{FILE}[[species]]\nname = \"air\"\nnumber_density_m3 = 2.545e25\nprofile.exponential.scale_height_m = 8000\nscattering.rayleigh.gas = \"air\"\n{gases}"
            ))
            .unwrap()
        };
        let clear = with("");
        let gases =
            with("[gases]\nprecipitable_water_cm = 2.9\nmixed_gases = false\nch4_ppm = 1.8\n");
        let grid = WavelengthGrid::new(1640.0, 2440.0, 10.0).unwrap();
        let a_w = sampled_band_coefficients(BandGas::WaterVapour, &grid).unwrap();
        let a_m = sampled_band_coefficients(BandGas::Methane, &grid).unwrap();
        let direct = |atmosphere: &Atmosphere| {
            Sky::builder(atmosphere)
                .sun_deg(60.0, 180.0)
                .wavelengths(grid)
                .build()
                .unwrap()
                .direct_normal_irradiance()
        };
        let (reference, summed) = (direct(&clear), direct(&gases));
        let air_mass = 1.0 / 60f64.to_radians().sin();
        let (mut worst, mut at): (f64, f64) = (0.0, 0.0);
        for i in 0..grid.len() {
            if a_m[i] == 0.0 {
                continue;
            }
            let t = summed[i] / reference[i];
            let want = water_band_transmittance(a_w[i] * 2.9 * air_mass)
                * methane_band_transmittance(a_m[i] * 1.8 * air_mass);
            let error = (t - want).abs() / (1.0 - want).max(0.01);
            if error > worst {
                (worst, at) = (error, grid.wavelength_nm(i));
            }
            assert!(error < 0.12, "{} nm: {t} vs {want}", grid.wavelength_nm(i));
        }
        println!("water and CH4: worst error {worst} of max(1 - T, 0.01), at {at} nm");
        assert!(worst > 0.02, "{worst}");
    }

    #[test]
    fn the_gases_table_checks_co2_and_ch4() {
        for (bad, needle) in [
            ("co2_ppm = -1", "gases.co2_ppm = -1 ppm"),
            ("co2_ppm = 20000", "gases.co2_ppm = 20000 ppm"),
            ("ch4_ppm = -0.1", "gases.ch4_ppm = -0.1 ppm"),
            (
                "mixed_gases = false\nco2_ppm = 400",
                "gases.co2_ppm: goes with the O2 and CO2 bands, but mixed_gases = false",
            ),
        ] {
            let message = Atmosphere::from_toml_str(&format!(
                "{FILE}[gases]\nprecipitable_water_cm = 1\n{bad}\n"
            ))
            .unwrap_err()
            .to_string();
            assert!(message.contains(needle), "{message}");
        }
        // ch4_ppm = 0 is no CH4 (the default).
        let zero = Atmosphere::from_toml_str(&format!(
            "{FILE}[gases]\nprecipitable_water_cm = 1\nch4_ppm = 0\n"
        ))
        .unwrap();
        assert_eq!(zero.species.len(), 2);
    }

    #[test]
    fn the_direct_beam_summed_over_the_terms_is_the_band_models() {
        // Through the sky's own slant paths (a spherical shell): the direct
        // normal irradiance summed over the k-terms, over that of the same
        // sky without the gases, is T_w(a_w W m) T_u(a_u m) at the sun's
        // air mass m, within 2 % of the absorption, for two water columns
        // and two suns, in the O2 A band and the 820, 940 and 1100 nm water
        // bands.
        use crate::sky::Sky;
        let grid = WavelengthGrid::new(700.0, 1100.0, 10.0).unwrap();
        let a_w = sampled_band_coefficients(BandGas::WaterVapour, &grid).unwrap();
        let direct = |atmosphere: &Atmosphere, elevation: f64| {
            Sky::builder(atmosphere)
                .sun_deg(elevation, 180.0)
                .wavelengths(grid)
                .build()
                .unwrap()
                .direct_normal_irradiance()
        };
        let clear = Atmosphere::preset("earth-clear").unwrap();
        let (mut worst, mut worst_overlap): (f64, f64) = (0.0, 0.0);
        for water_cm in [0.5, 3.0] {
            let gases = gas_atmosphere(water_cm);
            for elevation in [90.0, 30.0] {
                let air_mass = 1.0 / f64::to_radians(elevation).sin();
                let reference = direct(&clear, elevation);
                let mixed = mixed_transmittance(&grid, air_mass);
                let mut summed = SampledSpectrum::zeros(grid.len());
                for (weights, at_term) in k_distribution_terms(&gases, &grid).unwrap() {
                    let part = direct(&at_term, elevation);
                    for (i, s) in summed.values_mut().iter_mut().enumerate() {
                        *s += weights[i] * part[i];
                    }
                }
                for i in 0..grid.len() {
                    let t = summed[i] / reference[i];
                    let t_u = mixed[i];
                    let t_w = water_band_transmittance(a_w[i] * water_cm * air_mass);
                    let want = t_u * t_w;
                    if want > 0.999 {
                        continue;
                    }
                    let what = format!(
                        "{} nm W {water_cm} sun {elevation}: {t} vs {want}",
                        grid.wavelength_nm(i)
                    );
                    if t_u.max(t_w) > 0.999 {
                        // One gas absorbs (the other less than 0.1 %).
                        let error = (t - want).abs() / (1.0 - want);
                        worst = worst.max(error);
                        assert!(error < 0.02, "{what}");
                    } else {
                        // Both absorb (690-710 nm): the weaker one takes its
                        // effective coefficient in every term, so the two
                        // overlap at random, its own path matched at air
                        // mass 2.
                        let error = (t - want).abs() / (1.0 - want);
                        worst_overlap = worst_overlap.max(error);
                        assert!(error < 0.03, "{what}");
                    }
                }
            }
        }
        println!(
            "worst error of 1 - T: {worst} where one gas absorbs, {worst_overlap} where both do"
        );
        assert!(worst > 0.0);
    }

    #[test]
    fn zenith_single_scattering_summed_over_the_terms_is_the_closed_forms() {
        // Rayleigh air and the mixed gases on one 8 km exponential profile,
        // ground albedo 0, single scattering, a zenith view, the sun at 60
        // degrees (air mass m): in a plane-parallel atmosphere each term's
        // radiance is F P (tau_R / tau) integral_0^tau e^{-t m} e^{-(tau - t)} dt
        // = F P (tau_R / tau) e^{-tau} (1 - e^{-tau (m - 1)}) / (m - 1) with
        // tau = tau_R + tau_j (t from the top), so with f(tau) that
        // expression without F P, L / L_0 = sum_j w_j f(tau_R + tau_j) / f(tau_R).
        // sora's k-sum of its spherical-shell radiances, in the A band.
        use crate::geometry::ViewDirection;
        use crate::sky::{Scattering, Sky};
        let mut clear = Atmosphere::preset("clear-sky-reference").unwrap();
        clear.species.retain(|s| s.name == "air");
        let mut gases = clear.clone();
        gases
            .species
            .extend(banded_gas_species(&BandedGases::new(None, true)));
        let grid = WavelengthGrid::new(760.0, 760.0, 10.0).unwrap();
        let elevation = 60.0;
        let zenith = |atmosphere: &Atmosphere| {
            Sky::builder(atmosphere)
                .sun_deg(elevation, 180.0)
                .wavelengths(grid)
                .scattering(Scattering::Single)
                .build()
                .unwrap()
                .radiance(ViewDirection::new(90.0, 0.0).unwrap())
                .unwrap()
                .radiance_w_m2_sr_nm[0]
        };
        // The sky sums its terms itself (`sky/k_terms.rs`): the same as
        // summing skies built from each term's atmosphere.
        let parts: Vec<(f64, f64)> = k_distribution_terms(&gases, &grid)
            .unwrap()
            .iter()
            .map(|(w, at_term)| (w[0], zenith(at_term)))
            .collect();
        let summed: f64 = parts.iter().map(|(w, l)| w * l).sum();
        let by_the_sky = zenith(&gases);
        assert!(
            (by_the_sky / summed - 1.0).abs() < 1e-12,
            "{by_the_sky} vs {summed}"
        );
        let ratio = by_the_sky / zenith(&clear);
        let m = 1.0 / f64::to_radians(elevation).sin();
        let tau_r = clear
            .compute_optics(&grid)
            .unwrap()
            .total_optical_depth_extinction()[0];
        // Term j's optical depth per air column: the A band's k-terms.
        let SampleAbsorber::Terms(terms) = BandAmounts::one_air_column()
            .sampled_absorbers(BandGas::MixedGases, &grid)
            .unwrap()[0]
        else {
            panic!("760 nm is in the A band's line-derived range")
        };
        let column = 1.0 - (-100e3 / MIXED_GAS_SCALE_HEIGHT_M).exp();
        let f = |tau: f64| (tau_r / tau) * (-tau).exp() * (1.0 - (-tau * (m - 1.0)).exp());
        let want: f64 = terms
            .weights
            .iter()
            .zip(terms.k)
            .map(|(w, k)| w * f(tau_r + k * column) / f(tau_r))
            .sum();
        // One solve with the effective coefficient (matched to the band
        // model's direct beam at air mass 2) errs more.
        let single_solve = {
            let scene = crate::transport::SingleScatteringScene::new_with_phase_matrices(
                &gases,
                &grid,
                crate::transport::Observation {
                    observer_altitude_m: 0.0,
                    sun_elevation_deg: elevation,
                    sun_azimuth_deg: 180.0,
                },
                None,
            )
            .unwrap();
            Sky::from_scene(
                scene,
                Scattering::Single,
                crate::sky::Method::Fast,
                crate::sky::FastTableSize::default(),
            )
            .unwrap()
            .radiance(ViewDirection::new(90.0, 0.0).unwrap())
            .unwrap()
            .radiance_w_m2_sr_nm[0]
        };
        let single = single_solve / zenith(&clear);
        println!(
            "zenith A band: {ratio} (k-sum), {want} (closed form), {single} (one effective solve)"
        );
        assert!(
            (ratio - want).abs() / (1.0 - want) < 0.005,
            "{ratio} vs {want}"
        );
        assert!(
            (single - want).abs() > 5.0 * (ratio - want).abs(),
            "{single}"
        );
        // The band takes a good part of the light: not a vacuous check.
        assert!(want < 0.8, "{want}");
    }
}
