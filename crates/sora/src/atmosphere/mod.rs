//! # The atmosphere: what the sky is made of
//!
//! An [`Atmosphere`] is a [`Planet`] (radius, atmosphere height, ground
//! albedo), a [`Sun`] (spectrum, scale, disc) and any number of
//! [`Species`], each with a density profile and one optical model. Every
//! species contributes, at altitude h and wavelength lambda,
//!
//! ```text
//!     beta_ext(h, lambda) = relative_density(h) * beta_ext_ref(lambda)
//!     beta_sca(h, lambda) = relative_density(h) * beta_sca_ref(lambda)
//! ```
//!
//! the paper's eq. 1 (beta = rho(h) sigma(lambda)) split into a profile
//! ([`profile`]) and the coefficients at relative density 1, and scatters
//! with its phase function ([`phase`]; for polarised skies its phase
//! matrix, `phase_matrix.rs`). Optical models:
//! - [`rayleigh`]: molecules; physical (number density and a gas, `air`
//!   or `co2`, cross-section from refractive index and King factor) or
//!   parametric (coefficient at a reference wavelength, lambda^-n);
//! - [`mie_species`]: aerosol particles from Mie theory (the paper's
//!   Tables 1-2);
//! - [`aerosol`]: the parametric aerosol (optical depth, Angstrom exponent,
//!   single-scattering albedo, Henyey-Greenstein / Cornette-Shanks);
//! - [`ozone`]: gases that only absorb (ozone, 300 DU on Earth; NO2);
//!   [`o2_o2`]: O2-O2 collision-induced absorption, which follows the
//!   air's density squared; [`gas_bands`]: water vapour and the O2 and CO2
//!   bands as a k-distribution.
//!
//! Atmospheres are read from TOML ([`file`](mod@file), the one place where files
//! become validated model types; [`Atmosphere::from_toml_str`]) or taken
//! from the built-in [`presets`]. [`Atmosphere::compute_optics`] puts all of
//! it on a wavelength grid once ([`optical_depth::AtmosphereOptics`]): the
//! per-wavelength arrays the renderer reads, and the column optical depths;
//! every wavelength table is checked against the grid first
//! (`coverage.rs`).
//!
//! Units: SI (m, m^-1, m^-3, m^2) unless a name says otherwise
//! (`wavelength_nm`, `radius_um`, `angular_diameter_deg`). No I/O: files
//! arrive as text, and files they name are read through a closure the
//! caller supplies.

pub mod aerosol;
mod coverage;
pub mod file;
pub mod gas_bands;
pub mod mie_species;
pub mod o2_a_band;
pub mod o2_o2;
pub mod optical_depth;
pub mod ozone;
pub mod phase;
pub(crate) mod phase_matrix;
pub mod planet;
pub mod presets;
pub mod profile;
pub mod rayleigh;
#[cfg(test)]
mod reference_tests;
mod refractive_index;
pub mod sun;

pub use aerosol::{AerosolPhase, ParametricAerosol};
pub use mie_species::{MieAerosol, ParticleAmount};
pub use optical_depth::{AtmosphereOptics, OpticsSummaryRow, SpeciesOptics};
pub use ozone::{AbsorbingGas, AbsorptionCrossSection, BinnedCrossSection, GasAmount};
pub use phase::{PhaseFunction, PhaseSample, TabulatedPhase};
pub use planet::Planet;
pub use presets::{PRESETS, Preset};
pub use profile::{DensityProfile, ProfileTable};
pub use rayleigh::RayleighGas;
pub use sun::Sun;

use crate::error::{Error, Result};
use crate::spectrum::{SampledSpectrum, WavelengthGrid};

/// A planet, its sun, and what its sky is made of.
#[derive(Debug, Clone, PartialEq)]
pub struct Atmosphere {
    /// Its name (shown by `sora atmosphere list` and in outputs).
    pub name: String,
    /// A one-line description (may be empty).
    pub description: String,
    /// The planet: radius, top of the atmosphere, ground albedo.
    pub planet: Planet,
    /// The sun: its spectrum, scale and angular diameter.
    pub sun: Sun,
    /// In the file's order.
    pub species: Vec<Species>,
}

/// One constituent of the atmosphere.
#[derive(Debug, Clone, PartialEq)]
pub struct Species {
    /// Its name in the atmosphere file.
    pub name: String,
    /// How its density varies with altitude.
    pub profile: DensityProfile,
    /// How it scatters and absorbs light.
    pub model: SpeciesModel,
}

/// How a species interacts with light.
#[derive(Debug, Clone, PartialEq)]
pub enum SpeciesModel {
    /// Molecules much smaller than the wavelength (Rayleigh scattering).
    Rayleigh(RayleighScatterer),
    /// Spherical particles of a size distribution (Mie theory).
    Mie(MieAerosol),
    /// An aerosol given by optical depth, Angstrom exponent, albedo and a
    /// parametric phase function.
    ParametricAerosol(ParametricAerosol),
    /// A gas that only absorbs (ozone).
    AbsorbingGas(AbsorbingGas),
}

/// Rayleigh scattering by molecules.
#[derive(Debug, Clone, PartialEq)]
pub enum RayleighScatterer {
    /// A physical gas at `number_density_m3` (relative density 1).
    Gas {
        /// Which gas (its refractive index and King factor).
        gas: RayleighGas,
        /// Molecules per m^3 at relative density 1.
        number_density_m3: f64,
        /// Use the depolarisation ratio of the gas' King factor in the
        /// phase function (else 3/(16 pi)(1 + cos^2)).
        depolarization: bool,
    },
    /// beta = coefficient_per_m (reference_wavelength_nm / lambda)^exponent.
    Parametric {
        /// Scattering coefficient at the reference wavelength and relative
        /// density 1, m^-1.
        coefficient_per_m: f64,
        /// The wavelength of `coefficient_per_m`, nm.
        reference_wavelength_nm: f64,
        /// The power of lambda (4 for ideal Rayleigh scattering).
        wavelength_exponent: f64,
        /// Depolarisation ratio of the phase function (0 for none).
        depolarization_ratio: f64,
    },
}

/// The kind's name of an absorbing gas ([`SpeciesModel::AbsorbingGas`])
/// in listings and in `SpeciesOptics::kind`.
pub(crate) const ABSORBING_GAS_KIND: &str = "absorbing gas";

impl SpeciesModel {
    /// The kind's name in listings.
    pub(crate) fn kind(&self) -> &'static str {
        match self {
            SpeciesModel::Rayleigh(_) => "rayleigh",
            SpeciesModel::Mie(_) => "mie",
            SpeciesModel::ParametricAerosol(_) => "parametric aerosol",
            SpeciesModel::AbsorbingGas(_) => ABSORBING_GAS_KIND,
        }
    }
}

impl Atmosphere {
    /// Parses and validates an atmosphere file (see [`file`](mod@file) for the
    /// schema). Files it names (a solar spectrum CSV) are refused; use
    /// [`Atmosphere::from_toml_str_with_files`] to supply them.
    pub fn from_toml_str(text: &str) -> Result<Atmosphere> {
        file::parse_atmosphere(text, &mut |path: &str| {
            Err(format!(
                "'{path}': this atmosphere is read from text alone, so it cannot name other files"
            ))
        })
    }

    /// Parses and validates an atmosphere file; `read_file(path)` returns
    /// the text of a file the atmosphere names (the caller decides where
    /// relative paths point), or a one-line reason it could not.
    pub fn from_toml_str_with_files(
        text: &str,
        read_file: &mut dyn FnMut(&str) -> std::result::Result<String, String>,
    ) -> Result<Atmosphere> {
        file::parse_atmosphere(text, read_file)
    }

    /// A built-in preset by name (see [`presets::PRESETS`]).
    pub fn preset(name: &str) -> Result<Atmosphere> {
        presets::load_preset(name)
    }

    /// Adds to `optics` (this atmosphere's, on its grid) the phase matrix
    /// of every Mie species with a tabulated phase function, for polarised
    /// skies (`phase_matrix.rs`): one Mie solution per radius node and
    /// wavelength, the cost of the phase tables again or more; computed at
    /// every `stride` wavelengths (`spectrum/anchors.rs`; 1: every one) and
    /// interpolated in wavelength between them.
    pub(crate) fn add_phase_matrices(
        &self,
        optics: &mut AtmosphereOptics,
        stride: usize,
    ) -> Result<()> {
        let anchors = crate::spectrum::WavelengthAnchors::new(&optics.grid, stride);
        for (index, (species, species_optics)) in
            self.species.iter().zip(&mut optics.species).enumerate()
        {
            if let (SpeciesModel::Mie(mie), PhaseFunction::Tabulated(table)) =
                (&species.model, &mut species_optics.phase_function)
            {
                let path = format!("species[{index}] ({})", species.name);
                mie.compute_phase_matrix(&optics.grid, &anchors, table, &path)?;
            }
        }
        Ok(())
    }

    /// Puts the atmosphere on `grid`: per-wavelength coefficients, phase
    /// functions, solar irradiance and ground albedo (Mie species compute
    /// their ensembles here: the expensive step). Fails when a table does
    /// not cover the grid, naming the species.
    pub fn compute_optics(&self, grid: &WavelengthGrid) -> Result<AtmosphereOptics> {
        // Every table covers the grid, or one line names the table and the grid.
        coverage::check_grid_coverage(self, grid)?;
        // Amounts given as columns (optical depths, Dobson units) are
        // columns above sea level; a raised ground (`Planet::
        // with_ground_altitude_m`) then takes away what lies below it.
        let top_m = self.planet.top_above_sea_level_m();
        let ground_m = self.planet.ground_altitude_m();
        let mut species_optics = Vec::with_capacity(self.species.len());
        for (index, species) in self.species.iter().enumerate() {
            let path = format!("species[{index}] ({})", species.name);
            let sea_level_column_m = species.profile.vertical_column_m(top_m);
            let (
                mut extinction_per_m,
                mut scattering_per_m,
                phase_function,
                mut reference_number_density_m3,
            ) = species_coefficients(&species.model, grid, sea_level_column_m, &path)?;
            let (profile, column_m) = if ground_m == 0.0 {
                (species.profile.clone(), sea_level_column_m)
            } else {
                let (profile, factor) = species.profile.above_ground(ground_m);
                extinction_per_m *= factor;
                scattering_per_m *= factor;
                reference_number_density_m3 = reference_number_density_m3.map(|n| n * factor);
                let column_m = profile.vertical_column_m(top_m - ground_m);
                (profile, column_m)
            };
            // Values that pass their own checks can still combine into an
            // unusable coefficient: an optical depth spread over a column
            // of 1e-308 m is an infinite extinction. Refuse it here, once,
            // rather than let it become NaN radiance downstream.
            if let Some(bad) = extinction_per_m
                .values()
                .iter()
                .chain(scattering_per_m.values())
                .find(|v| !v.is_finite() || **v < 0.0)
            {
                return Err(Error::InvalidSpectrum(format!(
                    "{path}: its extinction or scattering coefficient comes out as {bad} m^-1, not a finite non-negative number (its vertical column is {column_m:e} m); check its amount, its profile and planet.atmosphere_height_m"
                )));
            }
            species_optics.push(SpeciesOptics {
                name: species.name.clone(),
                kind: species.model.kind(),
                profile,
                vertical_column_m: column_m,
                reference_number_density_m3,
                extinction_per_m,
                scattering_per_m,
                phase_function,
            });
        }
        Ok(AtmosphereOptics {
            grid: *grid,
            solar_irradiance_w_m2_nm: self.sun.sample_irradiance_w_m2_nm(grid)?,
            ground_albedo: self.planet.sample_ground_albedo(grid)?,
            species: species_optics,
        })
    }
}

type Coefficients = (SampledSpectrum, SampledSpectrum, PhaseFunction, Option<f64>);

fn species_coefficients(
    model: &SpeciesModel,
    grid: &WavelengthGrid,
    column_m: f64,
    path: &str,
) -> Result<Coefficients> {
    let with_path = |e: Error| match e {
        Error::InvalidSpectrum(message) => Error::InvalidSpectrum(format!("{path}: {message}")),
        other => other,
    };
    Ok(match model {
        SpeciesModel::Rayleigh(RayleighScatterer::Gas {
            gas,
            number_density_m3,
            depolarization,
        }) => {
            let scattering = SampledSpectrum::from_values(
                grid.wavelengths_nm()
                    .map(|w| number_density_m3 * gas.cross_section_m2(w))
                    .collect(),
            );
            let depolarization_ratios = grid
                .wavelengths_nm()
                .map(|w| {
                    if *depolarization {
                        rayleigh::depolarization_ratio_from_king_factor(gas.king_factor(w))
                    } else {
                        0.0
                    }
                })
                .collect();
            (
                scattering.clone(),
                scattering,
                PhaseFunction::Rayleigh {
                    depolarization_ratios,
                },
                Some(*number_density_m3),
            )
        }
        SpeciesModel::Rayleigh(RayleighScatterer::Parametric {
            coefficient_per_m,
            reference_wavelength_nm,
            wavelength_exponent,
            depolarization_ratio,
        }) => {
            let scattering = SampledSpectrum::from_values(
                grid.wavelengths_nm()
                    .map(|w| {
                        rayleigh::parametric_coefficient_per_m(
                            *coefficient_per_m,
                            *reference_wavelength_nm,
                            *wavelength_exponent,
                            w,
                        )
                    })
                    .collect(),
            );
            (
                scattering.clone(),
                scattering,
                PhaseFunction::Rayleigh {
                    depolarization_ratios: vec![*depolarization_ratio; grid.len()],
                },
                None,
            )
        }
        SpeciesModel::ParametricAerosol(aerosol) => {
            let (extinction, scattering, phase) = aerosol.compute_optics(grid, column_m);
            (extinction, scattering, phase, None)
        }
        SpeciesModel::AbsorbingGas(gas) => {
            let (extinction, scattering, phase) =
                gas.compute_optics(grid, column_m).map_err(with_path)?;
            (
                extinction,
                scattering,
                phase,
                Some(gas.reference_number_density_m3(column_m)),
            )
        }
        SpeciesModel::Mie(aerosol) => {
            let optics = aerosol
                .compute_optics(grid, column_m, path)
                .map_err(with_path)?;
            (
                optics.extinction_per_m,
                optics.scattering_per_m,
                optics.phase_function,
                Some(optics.reference_number_density_m3),
            )
        }
    })
}
