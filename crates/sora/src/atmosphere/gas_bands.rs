//! Banded gases: water vapour and the uniformly mixed gases (O2 A, B and
//! gamma bands; CO2 beyond 1100 nm), from a published band model turned
//! into a k-distribution so that a band's radiance is a weighted sum of a
//! few monochromatic solves.
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
//! atmosphere with term j ([`k_distribution_terms`]). Where both gases
//! absorb (690-710 nm here; 1.4, 1.9 and 2.7 um in the table) the one that
//! absorbs less at air mass 2 takes its effective coefficient (below) in
//! every term, so the two overlap at random rather than fully correlated:
//! the direct beam through the sky's spherical shell then matches
//! T_w T_u within 1.9 % of the absorption there (tested: 0.5 and 3 cm of
//! water, sun at 90 and 30 degrees), and within 1.3 % where one gas
//! absorbs (the A band, the 720, 820, 940 and 1130 nm water bands on a 10
//! nm grid from 700 to 1100 nm).
//!
//! # What the model is and is not
//! The band model scales with the absorber amount only: pressure and
//! temperature enter through M (the column of air above a raised ground or
//! an observer aloft), not through line widths, so the A band seen from 10
//! km is the sea-level band with a quarter of the air above. Its
//! resolution is its coefficients' (a 10 nm grid sample at 760 nm reads
//! a_u = 2.0, half way between 757.5 and 762.5 nm). It has no O2-O2
//! collision bands (`o2_o2.rs`, `[gases] o2_o2 = true`), no NO2 (a
//! cross-section species, `absorption.gas = "no2"`) and no CH4 (its mixed
//! gases are O2 and CO2).
//! When one solve is asked for (a sky built from an atmosphere with gases,
//! not summed over terms), each banded gas acts with one effective
//! coefficient: the one whose Beer-Lambert transmittance equals the band
//! model's for twice the vertical column ([`EFFECTIVE_AIR_MASS`]); that is
//! exact at air mass 2 and errs elsewhere (tested below): the zenith sky
//! in the A band (Rayleigh air, single scattering, sun 60 degrees) keeps
//! 0.827 of its gas-free radiance with one solve, 0.7773 with the five
//! terms, against 0.7773 from the plane-parallel closed form over the
//! terms. A [`crate::Sky`] built from an atmosphere with banded gases sums
//! the terms itself (`sky/k_terms.rs`), so every command, Python and the
//! explorer get the k-distribution; the effective coefficient is the
//! sky's own optics ([`crate::Sky::optics`]).

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
/// the band model.
pub const EFFECTIVE_AIR_MASS: f64 = 2.0;

/// The default scale height of water vapour's profile, m (about the
/// mid-latitude summer atmosphere's, from its precipitable water over its
/// surface density).
pub const WATER_SCALE_HEIGHT_M: f64 = 2000.0;

/// The scale height of the mixed gases' profile, m (the air's, near the
/// ground).
pub const MIXED_GAS_SCALE_HEIGHT_M: f64 = 8000.0;

/// Which banded gas.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BandGas {
    /// Water vapour (amount: precipitable water).
    WaterVapour,
    /// The uniformly mixed gases, O2 and CO2 (amount: air columns).
    MixedGases,
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
    /// The vertical amount the effective coefficient is fitted for: cm of
    /// precipitable water, or air columns (1 at sea level).
    pub vertical_amount: f64,
    /// The other banded gas' vertical amount, when the atmosphere has it:
    /// where the other absorbs more, this one takes its effective
    /// coefficient in every term (see the module docs).
    pub partner_vertical_amount: Option<f64>,
}

/// One term: its weight and the factors of x (water) and y (mixed gases).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KTerm {
    /// w_j (the weights sum to 1).
    pub weight: f64,
    /// c_w,j.
    pub water_factor: f64,
    /// c_u,j.
    pub mixed_factor: f64,
}

/// The band model's transmittance of water vapour for x = a_w u.
pub fn water_band_transmittance(x: f64) -> f64 {
    (-0.2385 * x / (1.0 + 20.07 * x).powf(0.45)).exp()
}

/// The band model's transmittance of the mixed gases for y = a_u M.
pub fn mixed_band_transmittance(y: f64) -> f64 {
    (-1.41 * y / (1.0 + 118.3 * y).powf(0.45)).exp()
}

/// The embedded k-distribution terms (parsed once).
pub fn k_terms() -> &'static [KTerm] {
    static PARSED: std::sync::LazyLock<Vec<KTerm>> = std::sync::LazyLock::new(|| {
        let table = NumericTable::parse(K_TERMS_CSV, "embedded gas k-terms")
            .expect("the embedded k-terms are valid");
        let terms: Vec<KTerm> = table
            .rows
            .iter()
            .map(|row| KTerm {
                weight: row[0],
                water_factor: row[1],
                mixed_factor: row[2],
            })
            .collect();
        assert_eq!(terms.len(), TERMS, "the embedded k-terms have {TERMS} rows");
        terms
    });
    &PARSED
}

/// The band model's coefficient of `gas` against wavelength (a_w per cm,
/// or a_u per air column), 200-4000 nm.
pub fn band_coefficients(gas: BandGas) -> TabulatedSpectrum {
    let table = NumericTable::parse(SPECTRL2_CSV, "embedded gas band table")
        .expect("the embedded gas band table is valid");
    let column = match gas {
        BandGas::WaterVapour => 1,
        BandGas::MixedGases => 2,
    };
    TabulatedSpectrum::new(
        table.column(0),
        table.column(column),
        "embedded gas band table",
    )
    .expect("the embedded gas band table is valid")
}

/// [`band_coefficients`] of `gas` on `grid`, interpolated linearly.
pub fn sampled_band_coefficients(gas: BandGas, grid: &WavelengthGrid) -> Result<SampledSpectrum> {
    Spectrum::Tabulated(band_coefficients(gas)).sample_at_wavelengths(grid)
}

impl GasBand {
    /// Molecules per m^2 in one unit of this gas' amount.
    fn molecules_per_unit(&self) -> f64 {
        match self.gas {
            BandGas::WaterVapour => MOLECULES_PER_M2_PER_CM_PRECIPITABLE_WATER,
            BandGas::MixedGases => AIR_MOLECULES_PER_M2_SEA_LEVEL_COLUMN,
        }
    }

    /// The band model's transmittance of `gas` for a = `a`, slant amount
    /// `amount`.
    fn band_transmittance(gas: BandGas, a: f64, amount: f64) -> f64 {
        match gas {
            BandGas::WaterVapour => water_band_transmittance(a * amount),
            BandGas::MixedGases => mixed_band_transmittance(a * amount),
        }
    }

    fn partner_gas(&self) -> BandGas {
        match self.gas {
            BandGas::WaterVapour => BandGas::MixedGases,
            BandGas::MixedGases => BandGas::WaterVapour,
        }
    }

    /// The effective (single-solve) coefficient per unit amount at band
    /// coefficient `a`: Beer-Lambert matching the band model at
    /// [`EFFECTIVE_AIR_MASS`].
    pub fn effective_coefficient_per_unit_amount(&self, a: f64) -> f64 {
        let slant = EFFECTIVE_AIR_MASS * self.vertical_amount;
        if a <= 0.0 || slant <= 0.0 {
            0.0
        } else {
            -Self::band_transmittance(self.gas, a, slant).ln() / slant
        }
    }

    /// Absorption coefficient per unit amount (per cm of precipitable water,
    /// per air column) at band coefficient `a`, where the partner gas'
    /// coefficient is `a_partner`.
    pub fn coefficient_per_unit_amount(&self, a: f64, a_partner: f64) -> f64 {
        let Some(j) = self.term else {
            return self.effective_coefficient_per_unit_amount(a);
        };
        if let Some(partner_amount) = self.partner_vertical_amount {
            let own = 1.0
                - Self::band_transmittance(self.gas, a, EFFECTIVE_AIR_MASS * self.vertical_amount);
            let partner = 1.0
                - Self::band_transmittance(
                    self.partner_gas(),
                    a_partner,
                    EFFECTIVE_AIR_MASS * partner_amount,
                );
            if partner > own {
                return self.effective_coefficient_per_unit_amount(a);
            }
        }
        let term = k_terms()[j];
        let factor = match self.gas {
            BandGas::WaterVapour => term.water_factor,
            BandGas::MixedGases => term.mixed_factor,
        };
        factor * a
    }

    /// Cross-section per molecule on `grid`, m^2.
    pub(crate) fn sample(&self, grid: &WavelengthGrid) -> Result<SampledSpectrum> {
        let own = sampled_band_coefficients(self.gas, grid)?;
        let partner = sampled_band_coefficients(self.partner_gas(), grid)?;
        let per_molecule = 1.0 / self.molecules_per_unit();
        Ok(SampledSpectrum::from_values(
            own.values()
                .iter()
                .zip(partner.values())
                .map(|(a, a_partner)| {
                    self.coefficient_per_unit_amount(*a, *a_partner) * per_molecule
                })
                .collect(),
        ))
    }

    /// The wavelengths the table covers, nm.
    pub(crate) fn range_nm(&self) -> (f64, f64) {
        band_coefficients(self.gas).range_nm()
    }
}

/// The banded gases as species: water vapour (`water`: precipitable
/// water above sea level, cm, and the scale height of its exponential
/// profile, m), named `water vapour`, and, when `mixed_gases`, the O2 and
/// CO2 of one sea-level air column over an exponential profile of
/// [`MIXED_GAS_SCALE_HEIGHT_M`], named `mixed gases (O2, CO2)`.
pub fn banded_gas_species(water: Option<(f64, f64)>, mixed_gases: bool) -> Vec<Species> {
    let water = water.filter(|(cm, _)| *cm > 0.0);
    let mixed_amount = mixed_gases.then_some(1.0);
    let mut species = Vec::new();
    if let Some((cm, scale_height_m)) = water {
        species.push(Species {
            name: "water vapour".into(),
            profile: DensityProfile::Exponential { scale_height_m },
            model: SpeciesModel::AbsorbingGas(AbsorbingGas {
                cross_section: AbsorptionCrossSection::Band(GasBand {
                    gas: BandGas::WaterVapour,
                    term: None,
                    vertical_amount: cm,
                    partner_vertical_amount: mixed_amount,
                }),
                amount: GasAmount::ColumnDobsonUnits(
                    cm * MOLECULES_PER_M2_PER_CM_PRECIPITABLE_WATER
                        / MOLECULES_PER_M2_PER_DOBSON_UNIT,
                ),
            }),
        });
    }
    if let Some(amount) = mixed_amount {
        species.push(Species {
            name: "mixed gases (O2, CO2)".into(),
            profile: DensityProfile::Exponential {
                scale_height_m: MIXED_GAS_SCALE_HEIGHT_M,
            },
            model: SpeciesModel::AbsorbingGas(AbsorbingGas {
                cross_section: AbsorptionCrossSection::Band(GasBand {
                    gas: BandGas::MixedGases,
                    term: None,
                    vertical_amount: amount,
                    partner_vertical_amount: water.map(|(cm, _)| cm),
                }),
                amount: GasAmount::ColumnDobsonUnits(
                    amount * AIR_MOLECULES_PER_M2_SEA_LEVEL_COLUMN
                        / MOLECULES_PER_M2_PER_DOBSON_UNIT,
                ),
            }),
        });
    }
    species
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

fn band_of(species: &Species) -> Option<&GasBand> {
    match &species.model {
        SpeciesModel::AbsorbingGas(AbsorbingGas {
            cross_section: AbsorptionCrossSection::Band(band),
            ..
        }) => Some(band),
        _ => None,
    }
}

/// The atmospheres whose weighted sum is `atmosphere`'s k-distribution:
/// (w_j, the atmosphere with every banded gas at term j), [`TERMS`] of
/// them; (1, the atmosphere) when it has no banded gas. Any quantity
/// linear in the light (radiance, irradiance, transmittance) of the
/// atmosphere is sum_j w_j times that quantity of atmosphere j.
pub fn k_distribution_terms(atmosphere: &Atmosphere) -> Vec<(f64, Atmosphere)> {
    if !has_gas_bands(atmosphere) {
        return vec![(1.0, atmosphere.clone())];
    }
    k_terms()
        .iter()
        .enumerate()
        .map(|(j, term)| {
            let mut at_term = atmosphere.clone();
            for species in &mut at_term.species {
                if let SpeciesModel::AbsorbingGas(AbsorbingGas {
                    cross_section: AbsorptionCrossSection::Band(band),
                    ..
                }) = &mut species.model
                {
                    band.term = Some(j);
                }
            }
            (term.weight, at_term)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

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
        for (weight, at_term) in k_distribution_terms(atmosphere) {
            let optics = at_term.compute_optics(grid).unwrap();
            let tau: Vec<f64> = optics
                .species
                .iter()
                .filter(|s| s.name == "water vapour" || s.name.starts_with("mixed gases"))
                .fold(vec![0.0; grid.len()], |mut acc, s| {
                    for (a, v) in acc.iter_mut().zip(s.optical_depth_extinction().values()) {
                        *a += v;
                    }
                    acc
                });
            for (ti, tau) in t.iter_mut().zip(tau) {
                *ti += weight * (-air_mass * tau).exp();
            }
        }
        t
    }

    fn gas_atmosphere(water_cm: f64) -> Atmosphere {
        let mut atmosphere = Atmosphere::preset("earth-clear").unwrap();
        atmosphere
            .species
            .extend(banded_gas_species(Some((water_cm, 2000.0)), true));
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
                for i in 0..3 {
                    let want = mixed_band_transmittance(a_u[i] * air_column * air_mass)
                        * water_band_transmittance(a_w[i] * water_cm * air_mass);
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
        let a_u = 2.0; // half way between 0 at 757.5 and 4.0 at 762.5 nm
        let fraction = (-10_000.0 / 8000.0f64).exp();
        let want_sea = mixed_band_transmittance(a_u);
        let want_high = mixed_band_transmittance(a_u * fraction);
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
            vertical_amount: 1.5,
            partner_vertical_amount: Some(1.0),
        };
        let a = 27.0; // 930 nm
        let k = band.coefficient_per_unit_amount(a, 0.0);
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
        let a_u = sampled_band_coefficients(BandGas::MixedGases, &grid).unwrap();
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
                let mut summed = SampledSpectrum::zeros(grid.len());
                for (weight, at_term) in k_distribution_terms(&gases) {
                    summed.add_scaled(&direct(&at_term, elevation), weight);
                }
                for i in 0..grid.len() {
                    let t = summed[i] / reference[i];
                    let t_u = mixed_band_transmittance(a_u[i] * air_mass);
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
        gases.species.extend(banded_gas_species(None, true));
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
        let parts: Vec<(f64, f64)> = k_distribution_terms(&gases)
            .iter()
            .map(|(w, at_term)| (*w, zenith(at_term)))
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
        let a_u = sampled_band_coefficients(BandGas::MixedGases, &grid).unwrap()[0];
        let column = 1.0 - (-100e3 / MIXED_GAS_SCALE_HEIGHT_M).exp();
        let f = |tau: f64| (tau_r / tau) * (-tau).exp() * (1.0 - (-tau * (m - 1.0)).exp());
        let want: f64 = k_terms()
            .iter()
            .map(|t| t.weight * f(tau_r + t.mixed_factor * a_u * column) / f(tau_r))
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
