//! Rayleigh scattering by gas molecules: cross-sections of air and CO2 from
//! their refractive indices, and the parametric lambda^-n law.
//!
//! The paper (§2) takes the Rayleigh cross-section as proportional to
//! lambda^-4. The physical cross-section per molecule of a gas of number
//! density N and refractive index n (both at the same temperature and
//! pressure; sigma does not depend on them, since n - 1 is proportional to N)
//! is (e.g. Bates 1984, Bodhaine et al. 1999 eq. 2)
//!
//! ```text
//!     sigma(lambda) = 24 pi^3 / (lambda^4 N^2) * ((n^2 - 1) / (n^2 + 2))^2 * F_K(lambda)     [m^2]
//! ```
//!
//! where F_K = (6 + 3 rho) / (6 - 7 rho) is the King correction factor for
//! the anisotropy of the molecules, rho their depolarisation ratio. The
//! same rho changes the phase function (see `super::phase::rayleigh_phase`):
//! rho = 6 (F_K - 1) / (3 + 7 F_K).
//!
//! - Air (`air_cross_section_m2`): Bates (1984), the sum over the four
//!   main gases (N2 78.084 %, O2 20.946 %, Ar 0.934 %, CO2 0.036 % by
//!   volume) of each gas's cross-section, from its refractivity at 0 C and
//!   1013.25 hPa and its King factor, as tabulated and fitted in Bates'
//!   paper: N2 after Peck & Khanna (1966) (three wavelength ranges), O2
//!   (four ranges), Ar and CO2 (Bates' eqs.), F(N2) = 1.034 + 3.17e-4 /
//!   lambda^2, F(O2) = 1.096 + 1.385e-3 / lambda^2 + 1.448e-4 / lambda^4,
//!   F(Ar) = 1, F(CO2) = 1.15 (lambda in um). The effective King factor of
//!   the mixture, for the depolarisation of its phase function, is the
//!   scattering-weighted mean. Checked against the Nicolet (1984) fit to
//!   Bates' table (`earth_rayleigh_21wl.csv`, ±0.5 % by its author): within
//!   1 % at the 21 paper wavelengths (see `atmosphere/reference_tests.rs`).
//!   The N2 refractivity has a 0.016 % step at 468 nm where Bates switches
//!   formulas, kept as published. From 300 to 1100 nm
//!   within 0.25 % of Bodhaine et al.'s (1999, eq. 29) fit from Peck &
//!   Reeder's (1972) refractivity of air; 0.9 % below it at 1640 nm, near
//!   the end of Peck & Reeder's data (1.69 um), where the column's optical
//!   depth is about 1.2e-3 (not compared past it).
//! - CO2 (`co2_cross_section_m2`): refractivity of Bideau-Mehu et al.
//!   (1973) in the form of Sneep & Ubachs (2005, eq. 13), at 288.15 K and
//!   1013.25 hPa (N = 2.546899e25 m^-3), and F_K = 1.1364 + 25.3e-12 nu^2
//!   (nu in cm^-1), as in the header of `mars_co2_rayleigh_21wl.csv`.
//!   Mars' atmosphere is ~95 % CO2; the pure-CO2 cross-section is 2-3 %
//!   above that of the real mixture.
//! - Parametric: beta(lambda) = beta_ref (lambda_ref / lambda)^exponent
//!   at the reference density, the form of the clear-sky reference
//!   (1.16e-5 m^-1 at 550 nm, exponent 4).
//!
//! Wavelengths are in nm (vacuum) at the interface, converted to um or
//! cm^-1 inside the formulas that are written in those units.

use std::f64::consts::PI;

/// Loschmidt's number density at 273.15 K and 101 325 Pa (CODATA 2018),
/// m^-3: the density at which Bates' refractivities are given.
pub const LOSCHMIDT_NUMBER_DENSITY_M3: f64 = 2.686_780_111e25;

/// Number density of an ideal gas at 288.15 K and 101 325 Pa, m^-3 (the
/// reference state of Peck & Reeves, Bodhaine et al. and Sneep & Ubachs).
pub const STANDARD_AIR_NUMBER_DENSITY_M3: f64 = 2.546_899e25;

/// A gas with a physical Rayleigh cross-section.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RayleighGas {
    /// Dry Earth air (Bates 1984).
    Air,
    /// Pure carbon dioxide (Bideau-Mehu 1973, Sneep & Ubachs 2005).
    Co2,
}

impl RayleighGas {
    /// Cross-section per molecule, m^2.
    pub(crate) fn cross_section_m2(self, wavelength_nm: f64) -> f64 {
        match self {
            RayleighGas::Air => air_cross_section_m2(wavelength_nm),
            RayleighGas::Co2 => co2_cross_section_m2(wavelength_nm),
        }
    }

    /// King correction factor (dimensionless, >= 1).
    pub(crate) fn king_factor(self, wavelength_nm: f64) -> f64 {
        match self {
            RayleighGas::Air => air_king_factor(wavelength_nm),
            RayleighGas::Co2 => co2_king_factor(wavelength_nm),
        }
    }
}

/// Depolarisation ratio rho that goes with a King factor:
/// F_K = (6 + 3 rho) / (6 - 7 rho)  <=>  rho = 6 (F_K - 1) / (3 + 7 F_K).
pub(crate) fn depolarization_ratio_from_king_factor(king_factor: f64) -> f64 {
    6.0 * (king_factor - 1.0) / (3.0 + 7.0 * king_factor)
}

/// 24 pi^3 / (lambda^4 N^2) ((n^2 - 1)/(n^2 + 2))^2 F_K with lambda in m,
/// N in m^-3: the cross-section of molecules of refractivity `n_minus_1`
/// measured at density `number_density_m3`.
fn lorentz_lorenz_cross_section_m2(
    wavelength_m: f64,
    n_minus_1: f64,
    number_density_m3: f64,
    king_factor: f64,
) -> f64 {
    // n^2 - 1 = (n - 1)(n + 1), computed without cancellation.
    let n = 1.0 + n_minus_1;
    let polarizability_term = n_minus_1 * (n + 1.0) / (n * n + 2.0);
    24.0 * PI.powi(3) / (wavelength_m.powi(4) * number_density_m3 * number_density_m3)
        * polarizability_term
        * polarizability_term
        * king_factor
}

/// The gases of Bates' air and their volume fractions.
const AIR_COMPOSITION: [(AirGas, f64); 4] = [
    (AirGas::N2, 0.78084),
    (AirGas::O2, 0.20946),
    (AirGas::Ar, 0.00934),
    (AirGas::Co2, 0.00036),
];

#[derive(Debug, Clone, Copy)]
enum AirGas {
    N2,
    O2,
    Ar,
    Co2,
}

impl AirGas {
    /// Refractivity n - 1 at 273.15 K, 1013.25 hPa (Bates 1984), lambda in um.
    fn refractivity(self, wavelength_um: f64) -> f64 {
        let inverse_square = 1.0 / (wavelength_um * wavelength_um);
        match self {
            AirGas::N2 => {
                let (a, b) = if wavelength_um <= 0.254 {
                    (6998.749, 3_233_582.0)
                } else if wavelength_um <= 0.468 {
                    (5989.242, 3_363_266.3)
                } else {
                    (6855.200, 3_243_157.0)
                };
                (a + b / (144.0 - inverse_square)) * 1e-8
            }
            AirGas::O2 => {
                let (a, b) = if wavelength_um <= 0.221 {
                    (23796.7, 168_988.4)
                } else if wavelength_um <= 0.288 {
                    (22120.4, 203_187.6)
                } else if wavelength_um <= 0.546 {
                    (20564.8, 248_089.9)
                } else {
                    (21351.1, 218_567.0)
                };
                (a + b / (40.9 - inverse_square)) * 1e-8
            }
            AirGas::Ar => {
                let n_squared_minus_1 = 5.547e-4
                    * (1.0 + 5.15e-3 * inverse_square + 4.19e-5 * inverse_square * inverse_square);
                n_squared_minus_1 / ((1.0 + n_squared_minus_1).sqrt() + 1.0)
            }
            AirGas::Co2 => {
                (22822.1
                    + 117.8 * inverse_square
                    + 2_406_030.0 / (130.0 - inverse_square)
                    + 15997.0 / (38.9 - inverse_square))
                    * 1e-8
            }
        }
    }

    /// King factor (Bates 1984), lambda in um.
    fn king_factor(self, wavelength_um: f64) -> f64 {
        let inverse_square = 1.0 / (wavelength_um * wavelength_um);
        match self {
            AirGas::N2 => 1.034 + 3.17e-4 * inverse_square,
            AirGas::O2 => {
                1.096 + 1.385e-3 * inverse_square + 1.448e-4 * inverse_square * inverse_square
            }
            AirGas::Ar => 1.0,
            AirGas::Co2 => 1.15,
        }
    }
}

/// Rayleigh cross-section of one molecule of dry air (Bates 1984), m^2.
pub(crate) fn air_cross_section_m2(wavelength_nm: f64) -> f64 {
    let wavelength_um = wavelength_nm * 1e-3;
    AIR_COMPOSITION
        .iter()
        .map(|&(gas, fraction)| {
            fraction
                * lorentz_lorenz_cross_section_m2(
                    wavelength_nm * 1e-9,
                    gas.refractivity(wavelength_um),
                    LOSCHMIDT_NUMBER_DENSITY_M3,
                    gas.king_factor(wavelength_um),
                )
        })
        .sum()
}

/// Effective King factor of dry air: each gas's factor weighted by its
/// share of the scattering (the factor the mixture's depolarisation obeys).
pub(crate) fn air_king_factor(wavelength_nm: f64) -> f64 {
    let wavelength_um = wavelength_nm * 1e-3;
    let (weighted, total) =
        AIR_COMPOSITION
            .iter()
            .fold((0.0, 0.0), |(weighted, total), &(gas, fraction)| {
                let weight = fraction * gas.refractivity(wavelength_um).powi(2);
                (
                    weighted + weight * gas.king_factor(wavelength_um),
                    total + weight,
                )
            });
    weighted / total
}

/// Refractivity n - 1 of CO2 at 288.15 K and 1013.25 hPa (Bideau-Mehu et
/// al. 1973 in the form of Sneep & Ubachs 2005 eq. 13), nu in cm^-1.
pub(crate) fn co2_refractivity(wavelength_nm: f64) -> f64 {
    let nu = 1e7 / wavelength_nm;
    let nu2 = nu * nu;
    1.1427e3
        * (5799.25 / (128_908.9f64.powi(2) - nu2)
            + 120.05 / (89_223.8f64.powi(2) - nu2)
            + 5.3334 / (75_037.5f64.powi(2) - nu2)
            - 4.3244 / (67_837.7f64.powi(2) - nu2)
            + 0.121_814_5e-4 / (2_418.136f64.powi(2) - nu2))
}

/// King factor of CO2, F_K = 1.1364 + 25.3e-12 nu^2 (nu in cm^-1;
/// Sneep & Ubachs 2005).
pub(crate) fn co2_king_factor(wavelength_nm: f64) -> f64 {
    let nu = 1e7 / wavelength_nm;
    1.1364 + 25.3e-12 * nu * nu
}

/// Rayleigh cross-section of one CO2 molecule, m^2.
pub(crate) fn co2_cross_section_m2(wavelength_nm: f64) -> f64 {
    lorentz_lorenz_cross_section_m2(
        wavelength_nm * 1e-9,
        co2_refractivity(wavelength_nm),
        STANDARD_AIR_NUMBER_DENSITY_M3,
        co2_king_factor(wavelength_nm),
    )
}

/// Parametric Rayleigh coefficient beta_ref (lambda_ref / lambda)^exponent,
/// m^-1 (at the reference density).
pub(crate) fn parametric_coefficient_per_m(
    coefficient_per_m: f64,
    reference_wavelength_nm: f64,
    wavelength_exponent: f64,
    wavelength_nm: f64,
) -> f64 {
    coefficient_per_m * (reference_wavelength_nm / wavelength_nm).powf(wavelength_exponent)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn air_at_550_nm_matches_the_classical_values() {
        // Bates 1984 / Bucholtz 1995: 4.51e-31 m^2 at 550 nm; times the
        // 15 C sea-level density, 1.149e-5 m^-1 (NOTES: 1.16e-5 within 1 %).
        let sigma = air_cross_section_m2(550.0);
        assert!((sigma / 4.51e-31 - 1.0).abs() < 3e-3, "{sigma}");
        let beta = sigma * STANDARD_AIR_NUMBER_DENSITY_M3;
        assert!((beta / 1.16e-5 - 1.0).abs() < 0.01, "{beta}");
    }

    #[test]
    fn air_king_factor_and_depolarisation() {
        // At 550 nm F(N2) = 1.0350 and F(O2) = 1.1022; weighted by their
        // shares of the scattering (N2 ~81 %, O2 ~18 %, Ar 1 %) the mixture's
        // factor is 1.0469, rho = 0.0272. (Weighting by mole fraction, as
        // Bodhaine et al. 1999 do, gives 1.0485 and 0.0281; the phase
        // functions differ by < 0.1 %.)
        let king = air_king_factor(550.0);
        assert!((king - 1.0469).abs() < 2e-4, "{king}");
        let rho = depolarization_ratio_from_king_factor(king);
        assert!((rho - 0.0272).abs() < 2e-4, "{rho}");
        // F_K = (6 + 3 rho)/(6 - 7 rho) round trip.
        assert!(((6.0 + 3.0 * rho) / (6.0 - 7.0 * rho) - king).abs() < 1e-12);
        // More anisotropic in the blue.
        assert!(air_king_factor(400.0) > air_king_factor(700.0));
    }

    #[test]
    fn co2_refractivity_and_king_factor_match_the_reference_header() {
        // mars_co2_rayleigh_21wl.csv, 380 nm row: n - 1 = 4.34970e-4, F_K = 1.1539.
        assert!((co2_refractivity(380.0) / 4.34970e-4 - 1.0).abs() < 1e-5);
        assert!((co2_king_factor(380.0) - 1.1539).abs() < 1e-4);
        assert!((co2_cross_section_m2(380.0) / 5.3377e-30 - 1.0).abs() < 1e-4);
    }

    #[test]
    fn air_matches_bodhaine_over_the_photometer_range() {
        // Bodhaine et al. (1999) eq. 29, their fit to the cross-section of
        // air with 360 ppm CO2, 1e-28 cm^2 (lambda in um), from an
        // independent set of refractive indices (Peck & Reeder 1972): within
        // 0.25 % from 300 to 1100 nm.
        let bodhaine_m2 = |wavelength_um: f64| {
            let l2 = wavelength_um * wavelength_um;
            1e-32 * (1.045_599_6 - 341.290_61 / l2 - 0.902_308_50 * l2)
                / (1.0 + 0.002_705_988_9 / l2 - 85.968_563 * l2)
        };
        for nm in [300.0, 340.0, 440.0, 500.0, 675.0, 870.0, 1020.0, 1100.0] {
            let ratio = air_cross_section_m2(nm) / bodhaine_m2(nm * 1e-3);
            assert!((ratio - 1.0).abs() < 2.5e-3, "{nm} nm: {ratio}");
        }
        // Past 1100 nm the two part: 0.991 at 1640 nm, near the end of
        // Peck & Reeder's measurements (1.69 um) that Bodhaine's fit
        // follows, where the column's optical depth is about 1.2e-3.
        let ratio = air_cross_section_m2(1640.0) / bodhaine_m2(1.64);
        assert!((ratio - 0.991).abs() < 1e-3, "1640 nm: {ratio}");
    }

    #[test]
    fn cross_sections_fall_roughly_as_lambda_to_the_minus_four() {
        for gas in [RayleighGas::Air, RayleighGas::Co2] {
            let ratio = gas.cross_section_m2(400.0) / gas.cross_section_m2(800.0);
            // Dispersion of n and F_K make it a little steeper than 2^4.
            assert!(ratio > 16.0 && ratio < 18.5, "{gas:?}: {ratio}");
        }
        let co2_to_air = co2_cross_section_m2(550.0) / air_cross_section_m2(550.0);
        assert!((2.4..2.7).contains(&co2_to_air), "{co2_to_air}");
    }

    #[test]
    fn parametric_law() {
        let beta = parametric_coefficient_per_m(1.16e-5, 550.0, 4.0, 380.0);
        assert!((beta - 1.16e-5 * (550.0f64 / 380.0).powi(4)).abs() < 1e-20);
        assert_eq!(parametric_coefficient_per_m(1.0, 550.0, 4.0, 550.0), 1.0);
    }
}
