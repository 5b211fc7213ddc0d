//! The atmosphere's optics on a wavelength grid, precomputed once: what the
//! renderer's inner loop reads, and the column optical depths that
//! summarise an atmosphere.
//!
//! For each species s, at each wavelength lambda_i of the grid:
//! - `extinction_per_m` and `scattering_per_m` at index i: beta_ext and beta_sca
//!   at relative density 1 (m^-1), so that at altitude h
//!   beta(h, lambda_i) = relative_density_s(h) * beta_i (the paper's eq. 1);
//! - the phase function (sr^-1) at that wavelength;
//! - the vertical column of its profile, column_m = integral_0^top
//!   relative_density dh (m).
//!
//! Derived per wavelength: the column optical depths
//! tau_ext = beta_ext column_m and tau_sca = beta_sca column_m (ground to
//! top, vertical), the single-scattering albedo omega = beta_sca / beta_ext
//! (0 for a pure absorber), and the asymmetry parameter g = `<cos theta>`
//! of the phase function. Slant paths and transmittances are the
//! renderer's business; `AtmosphereOptics::add_extinction_at_altitude`
//! and `AtmosphereOptics::add_scattering_at_altitude` are its per-sample
//! building blocks (no allocation).

use super::phase::PhaseFunction;
use super::profile::DensityProfile;
use crate::spectrum::{SampledSpectrum, WavelengthGrid};

/// One species' optics on a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct SpeciesOptics {
    /// The species' name in the atmosphere file.
    pub name: String,
    /// What kind of species it is ("rayleigh", "mie", "parametric aerosol",
    /// "absorbing gas").
    pub kind: &'static str,
    /// How its density varies with altitude.
    pub profile: DensityProfile,
    /// integral_0^top relative_density(h) dh, m.
    pub vertical_column_m: f64,
    /// Number density at relative density 1, m^-3, where the species is made
    /// of particles or molecules (not for parametric species).
    pub reference_number_density_m3: Option<f64>,
    /// beta_ext at relative density 1, m^-1, per wavelength.
    pub extinction_per_m: SampledSpectrum,
    /// beta_sca at relative density 1, m^-1, per wavelength.
    pub scattering_per_m: SampledSpectrum,
    /// Its phase function per wavelength.
    pub phase_function: PhaseFunction,
}

impl SpeciesOptics {
    /// Vertical column extinction optical depth, ground to top.
    pub fn optical_depth_extinction(&self) -> SampledSpectrum {
        &self.extinction_per_m * self.vertical_column_m
    }

    /// Vertical column scattering optical depth, ground to top.
    pub fn optical_depth_scattering(&self) -> SampledSpectrum {
        &self.scattering_per_m * self.vertical_column_m
    }

    /// beta_sca / beta_ext per wavelength (0 where nothing is extinguished).
    pub fn single_scattering_albedo(&self) -> SampledSpectrum {
        SampledSpectrum::from_values(
            self.extinction_per_m
                .values()
                .iter()
                .zip(self.scattering_per_m.values())
                .map(|(e, s)| if *e > 0.0 { s / e } else { 0.0 })
                .collect(),
        )
    }

    /// Asymmetry parameter `<cos theta>` per wavelength (0 for species that do
    /// not scatter).
    pub fn asymmetry_g(&self) -> SampledSpectrum {
        SampledSpectrum::from_values(
            (0..self.extinction_per_m.len())
                .map(|i| {
                    if self.scattering_per_m[i] > 0.0 {
                        self.phase_function.asymmetry_g(i)
                    } else {
                        0.0
                    }
                })
                .collect(),
        )
    }

    /// Cross-section per particle (extinction, scattering), m^2, where the
    /// species has a number density.
    #[cfg(test)]
    pub(crate) fn cross_sections_m2(&self) -> Option<(SampledSpectrum, SampledSpectrum)> {
        let n = self.reference_number_density_m3.filter(|n| *n > 0.0)?;
        Some((
            &self.extinction_per_m * (1.0 / n),
            &self.scattering_per_m * (1.0 / n),
        ))
    }
}

/// Everything on one grid: the sun, the ground and every species.
#[derive(Debug, Clone, PartialEq)]
pub struct AtmosphereOptics {
    /// The wavelengths every spectrum here is sampled on.
    pub grid: WavelengthGrid,
    /// Top-of-atmosphere solar irradiance (scaled), W m^-2 nm^-1.
    pub solar_irradiance_w_m2_nm: SampledSpectrum,
    /// Lambertian ground albedo.
    pub ground_albedo: SampledSpectrum,
    /// In the atmosphere file's order.
    pub species: Vec<SpeciesOptics>,
}

impl AtmosphereOptics {
    /// Total vertical extinction optical depth of all species.
    pub fn total_optical_depth_extinction(&self) -> SampledSpectrum {
        let mut total = SampledSpectrum::zeros(self.grid.len());
        for species in &self.species {
            total.add_scaled(&species.extinction_per_m, species.vertical_column_m);
        }
        total
    }

    /// Adds the extinction coefficient of all species at `altitude_m` to
    /// `out`, m^-1 (a ray-march step; no allocation).
    pub(crate) fn add_extinction_at_altitude(&self, altitude_m: f64, out: &mut SampledSpectrum) {
        for species in &self.species {
            let density = species.profile.relative_density(altitude_m);
            if density > 0.0 {
                out.add_scaled(&species.extinction_per_m, density);
            }
        }
    }

    /// Adds the scattering coefficient of all species at `altitude_m`,
    /// each weighted by its phase function at `cos_theta`, to `out`:
    /// sum_s beta_sca,s(h) p_s(theta), m^-1 sr^-1 (the in-scattering factor of
    /// the paper's eq. 4). `phase_buffer` is scratch space of the grid's
    /// length.
    pub(crate) fn add_scattering_at_altitude(
        &self,
        altitude_m: f64,
        cos_theta: f64,
        phase_buffer: &mut [f64],
        out: &mut SampledSpectrum,
    ) {
        for species in &self.species {
            let density = species.profile.relative_density(altitude_m);
            if density <= 0.0 {
                continue;
            }
            species.phase_function.eval_into(cos_theta, phase_buffer);
            for ((o, beta), p) in out
                .values_mut()
                .iter_mut()
                .zip(species.scattering_per_m.values())
                .zip(phase_buffer.iter())
            {
                *o += density * beta * p;
            }
        }
    }

    /// One row per wavelength and species (wavelength-major), the table of
    /// `sora atmosphere show`.
    pub fn summary_rows(&self) -> Vec<OpticsSummaryRow<'_>> {
        let per_species: Vec<_> = self
            .species
            .iter()
            .map(|s| {
                (
                    s.optical_depth_extinction(),
                    s.optical_depth_scattering(),
                    s.single_scattering_albedo(),
                    s.asymmetry_g(),
                )
            })
            .collect();
        let mut rows = Vec::with_capacity(self.grid.len() * self.species.len());
        for (i, wavelength_nm) in self.grid.wavelengths_nm().enumerate() {
            for (species, (ext, sca, ssa, g)) in self.species.iter().zip(&per_species) {
                rows.push(OpticsSummaryRow {
                    wavelength_nm,
                    species: &species.name,
                    tau_extinction: ext[i],
                    tau_scattering: sca[i],
                    single_scattering_albedo: ssa[i],
                    asymmetry_g: g[i],
                });
            }
        }
        rows
    }
}

/// Column optics of one species at one wavelength.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpticsSummaryRow<'a> {
    /// The wavelength, nm.
    pub wavelength_nm: f64,
    /// The species' name.
    pub species: &'a str,
    /// Vertical column extinction optical depth, ground to top.
    pub tau_extinction: f64,
    /// Vertical column scattering optical depth, ground to top.
    pub tau_scattering: f64,
    /// tau_scattering / tau_extinction (0 for a species that only absorbs).
    pub single_scattering_albedo: f64,
    /// The phase function's mean scattering cosine.
    pub asymmetry_g: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn optics() -> AtmosphereOptics {
        let grid = WavelengthGrid::new(400.0, 600.0, 100.0).unwrap();
        let air = SpeciesOptics {
            name: "air".into(),
            kind: "rayleigh",
            profile: DensityProfile::exponential(8000.0, "h").unwrap(),
            vertical_column_m: 8000.0,
            reference_number_density_m3: Some(2.5e25),
            extinction_per_m: SampledSpectrum::from_values(vec![4e-5, 2e-5, 1e-5]),
            scattering_per_m: SampledSpectrum::from_values(vec![4e-5, 2e-5, 1e-5]),
            phase_function: PhaseFunction::Rayleigh {
                depolarization_ratios: vec![0.0; 3],
            },
        };
        let ozone = SpeciesOptics {
            name: "ozone".into(),
            kind: "absorbing gas",
            profile: DensityProfile::tent(25e3, 15e3, "t").unwrap(),
            vertical_column_m: 15e3,
            reference_number_density_m3: Some(5e18),
            extinction_per_m: SampledSpectrum::from_values(vec![1e-8, 1e-7, 2e-6]),
            scattering_per_m: SampledSpectrum::zeros(3),
            phase_function: PhaseFunction::Isotropic,
        };
        AtmosphereOptics {
            grid,
            solar_irradiance_w_m2_nm: SampledSpectrum::constant(3, 1.0),
            ground_albedo: SampledSpectrum::zeros(3),
            species: vec![air, ozone],
        }
    }

    #[test]
    fn column_quantities() {
        let optics = optics();
        let air = &optics.species[0];
        assert!((air.optical_depth_extinction()[0] - 0.32).abs() < 1e-15);
        assert_eq!(air.single_scattering_albedo().values(), &[1.0; 3]);
        assert_eq!(air.asymmetry_g().values(), &[0.0; 3]);
        let (ext, _) = air.cross_sections_m2().unwrap();
        assert!((ext[1] - 8e-31).abs() < 1e-45);
        let ozone = &optics.species[1];
        assert_eq!(ozone.single_scattering_albedo().values(), &[0.0; 3]);
        let total = optics.total_optical_depth_extinction();
        assert!((total[2] - (0.08 + 0.03)).abs() < 1e-15);
        let rows = optics.summary_rows();
        assert_eq!(rows.len(), 6);
        assert_eq!((rows[1].wavelength_nm, rows[1].species), (400.0, "ozone"));
        assert_eq!((rows[2].wavelength_nm, rows[2].species), (500.0, "air"));
    }

    #[test]
    fn local_coefficients_follow_the_profiles() {
        let optics = optics();
        let mut out = SampledSpectrum::zeros(3);
        optics.add_extinction_at_altitude(0.0, &mut out);
        assert_eq!(out.values(), &[4e-5, 2e-5, 1e-5]); // no ozone at the ground
        let mut out = SampledSpectrum::zeros(3);
        optics.add_extinction_at_altitude(25e3, &mut out);
        let air = (-25e3f64 / 8000.0).exp();
        assert!((out[2] - (1e-5 * air + 2e-6)).abs() < 1e-18);
        let mut buffer = [0.0; 3];
        let mut out = SampledSpectrum::zeros(3);
        optics.add_scattering_at_altitude(0.0, 1.0, &mut buffer, &mut out);
        let p = 6.0 / (16.0 * std::f64::consts::PI);
        assert!((out[0] - 4e-5 * p).abs() < 1e-18);
    }
}
