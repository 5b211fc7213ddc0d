//! The forward model of a retrieval: the sky radiances and optical depths
//! an aerosol state gives at the measured wavelengths and directions.
//!
//! The atmosphere is the user's (air, gases, planet, ground, sun) with its
//! aerosol species removed and the state's aerosol added as one species:
//! the Mie kernels' ensemble (`kernels.rs`) scaled to the state's optical
//! depth at the reference wavelength, spread over an exponential profile
//! of scale height `aerosol_scale_height_m`. Radiances come from the
//! library's own fast method ([`crate::Sky`], all orders of scattering,
//! scalar light, the default tables): one sky per wavelength and sun
//! position, each on a one-wavelength grid, since a photometer's channels
//! (440, 675, 870, 1020 nm) are not a regular grid; the grid's step is the
//! channel's band (`RetrievalSettings::band_nm`), over which the sun's
//! spectrum and the gases' cross-sections are averaged (a box of that
//! width: the aerosol and the air's scattering, smooth in wavelength, are
//! taken at the channel's wavelength). The optics of air and
//! gases are computed once; only the aerosol species changes between
//! evaluations.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

use super::kernels::MieKernels;
use super::measurements::{Measurements, SAME_WAVELENGTH_NM};
use super::state::AerosolState;
use crate::ViewDirection;
use crate::atmosphere::{
    Atmosphere, AtmosphereOptics, DensityProfile, PhaseFunction, SpeciesModel, SpeciesOptics,
    TabulatedPhase,
};
use crate::error::{Error, Result};
use crate::mie::Complex64;
use crate::mie::ensemble::TabulatedPhaseFunction;
use crate::sky::{FastTableSize, Method, MultipleScatteringSettings, Scattering, Sky};
use crate::spectrum::{Filter, SampledSpectrum, WavelengthGrid};
use crate::transport::{Observation, SingleScatteringScene};

/// The multiple-scattering solver of the forward model: the default's 8
/// streams per hemisphere, with 20 layers instead of 40 and 8 panels per
/// view ray instead of 16. Against the default, over almucantars at 440-
/// 1020 nm (suns 8-30 degrees, aerosol optical depth 0.3-0.5): within
/// 1.9e-3, at about half the cost; 6 streams would add 1e-3 more at 0.4
/// times. The measurements' own uncertainty is 3-5 %.
const RETRIEVAL_SOLVER: MultipleScatteringSettings = MultipleScatteringSettings {
    streams_per_hemisphere: 8,
    layers: 20,
    sun_zenith_step_deg: 3.0,
    sunset_sun_zenith_step_deg: 0.75,
    view_ray_panels: 8,
    table_view_zenith_nodes: 37,
    table_azimuth_nodes: 19,
    polarisation_wavelength_stride: 2,
    first_order_panels: 4,
    first_order_fine_nodes: 4,
    twilight_shift_pieces: 1,
};

/// Mie kernels kept per wavelength (the fit's current point, its index
/// columns of the Jacobian and a trial step fit with room to spare).
const KERNEL_CACHE_SIZE: usize = 8;

/// Skies kept per group of measurements: the radiances of a group depend on
/// the aerosol's optics at its wavelength only, and a Jacobian column that
/// moves another wavelength's refractive index leaves them as they were
/// (the fit's point, its Jacobian's columns and trial steps fit).
const SKY_CACHE_SIZE: usize = 32;

/// What one wavelength's aerosol optics depend on: the size distribution
/// and the optical depth at the reference wavelength (the state's first
/// six parameters), the wavelength's refractive index and the reference
/// wavelength's (which scales the optical depth), compared bit for bit.
type OpticsKey = [f64; 10];

/// One group's last skies: the radiances of each, by its optics' key.
type SkyCache = Mutex<Vec<(OpticsKey, Vec<f64>)>>;

/// Where `wavelength_nm` is in `wavelengths_nm` (the measurements'
/// wavelengths, equal to within `SAME_WAVELENGTH_NM` as
/// [`Measurements::wavelengths_nm`] merges them).
pub(crate) fn wavelength_index(wavelengths_nm: &[f64], wavelength_nm: f64) -> Option<usize> {
    wavelengths_nm
        .iter()
        .position(|w| (w - wavelength_nm).abs() < SAME_WAVELENGTH_NM)
}

/// The measured directions of one wavelength and one sun position.
#[derive(Debug, Clone)]
struct SkyGroup {
    wavelength: usize,
    sun_elevation_deg: f64,
    sun_azimuth_deg: f64,
    views: Vec<ViewDirection>,
    /// Indices into the measurements' sky list, in `views`' order.
    measurements: Vec<usize>,
}

/// The aerosol's optics at one wavelength.
#[derive(Debug, Clone)]
pub(crate) struct AerosolOptics {
    /// Extinction optical depth.
    pub optical_depth: f64,
    /// Single-scattering albedo.
    pub single_scattering_albedo: f64,
    /// The phase function (sr^-1).
    pub phase_function: TabulatedPhaseFunction,
}

/// What stays fixed while the aerosol changes.
#[derive(Debug)]
pub(crate) struct ForwardModel {
    /// The measured wavelengths, nm, increasing.
    pub wavelengths_nm: Vec<f64>,
    /// Index of the reference wavelength (the state's optical depth).
    pub reference: usize,
    /// Air and gases on each wavelength's one-point grid.
    base_optics: Vec<AtmosphereOptics>,
    ground_radius_m: f64,
    top_radius_m: f64,
    sun_angular_radius_rad: f64,
    profile: DensityProfile,
    column_m: f64,
    groups: Vec<SkyGroup>,
    sky_measurements: usize,
    /// The multiple-scattering solver's settings.
    pub(crate) scattering: Scattering,
    /// Mie kernels, each of one wavelength (its index) and refractive index.
    kernels: Mutex<Vec<(usize, Arc<MieKernels>)>>,
    /// Per group: the radiances of the last skies computed, by what the
    /// aerosol's optics at the group's wavelength depend on.
    sky_cache: Vec<SkyCache>,
    /// The first sky's scene, whose sun-column tables every later sky
    /// shares: they depend on the profiles, the radii and the eye only,
    /// which no evaluation changes, and at a low sun (where the first
    /// order and the forward peak read them) building one took 70 % of a
    /// retrieval's time when each sky built its own.
    column_tables: OnceLock<SingleScatteringScene>,
    /// How many times the radiances and the kernels were computed.
    pub(crate) evaluations: AtomicUsize,
    pub(crate) kernel_computations: AtomicUsize,
}

impl ForwardModel {
    /// The model of `measurements` in `atmosphere` (whose aerosol species
    /// are set aside), with the aerosol in an exponential profile of
    /// `aerosol_scale_height_m`, and the state's optical depth given at
    /// `reference_wavelength_nm` (one of the measured wavelengths); each
    /// wavelength's sun and gases averaged over a band `band_nm` wide, or,
    /// where `filters` has a filter for it (`filters[i]` for wavelength
    /// index i; an empty list: none), weighted by its response
    /// ([`band_optics`]).
    pub(crate) fn new(
        atmosphere: &Atmosphere,
        measurements: &Measurements,
        aerosol_scale_height_m: f64,
        reference_wavelength_nm: f64,
        band_nm: f64,
        filters: &[Option<Filter>],
    ) -> Result<ForwardModel> {
        let wavelengths_nm = measurements.wavelengths_nm();
        let reference = wavelength_index(&wavelengths_nm, reference_wavelength_nm)
            .ok_or_else(|| {
                Error::Unsupported(format!(
                    "the reference wavelength {reference_wavelength_nm} nm is not one of the measured wavelengths ({wavelengths_nm:?} nm)"
                ))
            })?;
        let mut base = atmosphere.clone();
        base.species.retain(|s| {
            !matches!(
                s.model,
                SpeciesModel::Mie(_) | SpeciesModel::ParametricAerosol(_)
            )
        });
        let base_optics = wavelengths_nm
            .iter()
            .enumerate()
            .map(|(i, &w)| match filters.get(i).and_then(Option::as_ref) {
                Some(filter) => band_optics(&base.compute_optics(&filter.grid()?)?, filter, w),
                None => base.compute_optics(&WavelengthGrid::new(w, w, band_nm)?),
            })
            .collect::<Result<Vec<_>>>()?;
        let profile = DensityProfile::exponential(aerosol_scale_height_m, "aerosol scale height")?;
        let column_m = profile.vertical_column_m(base.planet.atmosphere_height_m());

        let mut groups: Vec<SkyGroup> = Vec::new();
        for (index, m) in measurements.sky.iter().enumerate() {
            let wavelength = wavelength_index(&wavelengths_nm, m.wavelength_nm)
                .expect("every sky wavelength is in the list");
            let view = ViewDirection::new(m.view_elevation_deg, m.view_azimuth_deg)?;
            match groups.iter_mut().find(|g| {
                g.wavelength == wavelength
                    && g.sun_elevation_deg == m.sun_elevation_deg
                    && g.sun_azimuth_deg == m.sun_azimuth_deg
            }) {
                Some(group) => {
                    group.views.push(view);
                    group.measurements.push(index);
                }
                None => groups.push(SkyGroup {
                    wavelength,
                    sun_elevation_deg: m.sun_elevation_deg,
                    sun_azimuth_deg: m.sun_azimuth_deg,
                    views: vec![view],
                    measurements: vec![index],
                }),
            }
        }
        let sky_cache = groups.iter().map(|_| Mutex::new(Vec::new())).collect();
        Ok(ForwardModel {
            wavelengths_nm,
            reference,
            base_optics,
            ground_radius_m: base.planet.radius_m(),
            top_radius_m: base.planet.top_radius_m(),
            sun_angular_radius_rad: base.sun.angular_radius_rad(),
            profile,
            column_m,
            groups,
            sky_measurements: measurements.sky.len(),
            scattering: Scattering::Multiple(RETRIEVAL_SOLVER),
            kernels: Mutex::new(Vec::new()),
            sky_cache,
            column_tables: OnceLock::new(),
            evaluations: AtomicUsize::new(0),
            kernel_computations: AtomicUsize::new(0),
        })
    }

    /// The Mie kernels of `m` at wavelength index `wavelength`, from the
    /// cache or computed (and cached).
    fn kernels(&self, wavelength: usize, m: Complex64) -> Result<Arc<MieKernels>> {
        if let Some((_, k)) = self
            .kernels
            .lock()
            .expect("kernel cache")
            .iter()
            .find(|(w, k)| *w == wavelength && k.refractive_index == m)
        {
            return Ok(Arc::clone(k));
        }
        let computed = Arc::new(MieKernels::compute(
            &self.wavelengths_nm[wavelength..=wavelength],
            m,
        )?);
        self.kernel_computations.fetch_add(1, Ordering::Relaxed);
        let mut cache = self.kernels.lock().expect("kernel cache");
        if cache.iter().filter(|(w, _)| *w == wavelength).count() >= KERNEL_CACHE_SIZE {
            let oldest = cache
                .iter()
                .position(|(w, _)| *w == wavelength)
                .expect("counted above");
            cache.remove(oldest);
        }
        cache.push((wavelength, Arc::clone(&computed)));
        Ok(computed)
    }

    /// The aerosol's optical depth, albedo and phase function at every
    /// measured wavelength, with the size distribution and optical depth of
    /// `state` and the refractive index `indices[i]` at wavelength i (the
    /// state's own index is not used).
    pub(crate) fn aerosol_optics(
        &self,
        state: &AerosolState,
        indices: &[Complex64],
    ) -> Result<Vec<AerosolOptics>> {
        if indices.len() != self.wavelengths_nm.len() {
            return Err(Error::Unsupported(format!(
                "{} refractive indices for {} wavelengths",
                indices.len(),
                self.wavelengths_nm.len()
            )));
        }
        let (radii_um, _) = super::kernels::radius_nodes_um();
        let volume: Vec<f64> = radii_um
            .iter()
            .map(|r| state.volume_per_ln_radius(*r))
            .collect();
        let mut phase = Vec::new();
        let per_wavelength: Vec<(f64, f64, Vec<f64>, Vec<f64>)> = indices
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let kernels = self.kernels(i, *m)?;
                let (e, s) = kernels.ensemble(0, &volume, &mut phase);
                Ok((e, s, phase.clone(), kernels.cos_theta.clone()))
            })
            .collect::<Result<_>>()?;
        let reference_extinction = per_wavelength[self.reference].0;
        per_wavelength
            .into_iter()
            .map(|(e, s, phase, cos_theta)| {
                let phase_function = TabulatedPhaseFunction::from_nodes(cos_theta, phase)
                    .map_err(|error| Error::Unsupported(format!("aerosol phase table: {error}")))?;
                Ok(AerosolOptics {
                    optical_depth: state.optical_depth * e / reference_extinction,
                    single_scattering_albedo: s / e,
                    phase_function,
                })
            })
            .collect()
    }

    /// The sky radiance of every measurement (W m^-2 sr^-1 nm^-1), in the
    /// measurements' order, and the aerosol's optics per wavelength, with
    /// refractive index `indices[i]` at wavelength i.
    pub(crate) fn radiances(
        &self,
        state: &AerosolState,
        indices: &[Complex64],
    ) -> Result<(Vec<f64>, Vec<AerosolOptics>)> {
        self.evaluations.fetch_add(1, Ordering::Relaxed);
        let aerosol = self.aerosol_optics(state, indices)?;
        let shared = state.to_array();
        let reference = indices[self.reference];
        let key = |w: usize| -> OpticsKey {
            [
                shared[0],
                shared[1],
                shared[2],
                shared[3],
                shared[4],
                shared[5],
                indices[w].re,
                indices[w].im,
                reference.re,
                reference.im,
            ]
        };
        // One sky per group, the groups in parallel (a trial step is one
        // evaluation: this is what keeps both cores busy for it); a group
        // whose wavelength's optics are those of a sky already computed
        // takes that sky's radiances (the same numbers: the sky is a
        // function of those optics).
        let mut per_group: Vec<Result<Vec<f64>>> = vec![Ok(Vec::new()); self.groups.len()];
        crate::parallel::for_each_chunk_mut(&mut per_group, 1, |g, out| {
            let group = &self.groups[g];
            let key = key(group.wavelength);
            let cached = {
                let mut cache = self.sky_cache[g].lock().expect("sky cache");
                cache.iter().position(|(k, _)| *k == key).map(|i| {
                    // Most recently used last.
                    let entry = cache.remove(i);
                    let values = entry.1.clone();
                    cache.push(entry);
                    values
                })
            };
            out[0] = match cached {
                Some(values) => Ok(values),
                None => self
                    .group_radiances(group, &aerosol[group.wavelength])
                    .inspect(|values| {
                        let mut cache = self.sky_cache[g].lock().expect("sky cache");
                        if cache.len() == SKY_CACHE_SIZE {
                            cache.remove(0);
                        }
                        cache.push((key, values.clone()));
                    }),
            };
        });
        let mut radiances = vec![0.0; self.sky_measurements];
        for (group, values) in self.groups.iter().zip(per_group) {
            for (value, &index) in values?.iter().zip(&group.measurements) {
                radiances[index] = *value;
            }
        }
        Ok((radiances, aerosol))
    }

    /// The radiances of one group's views.
    fn group_radiances(&self, group: &SkyGroup, aerosol: &AerosolOptics) -> Result<Vec<f64>> {
        let scene = SingleScatteringScene::from_optics(
            self.optics_at(group.wavelength, aerosol),
            self.ground_radius_m,
            self.top_radius_m,
            self.sun_angular_radius_rad,
            Observation {
                observer_altitude_m: 0.0,
                sun_elevation_deg: group.sun_elevation_deg,
                sun_azimuth_deg: group.sun_azimuth_deg,
            },
        )?;
        let first = self.column_tables.get_or_init(|| scene.clone());
        let scene = scene.sharing_sun_column_tables_of(first);
        let sky = Sky::from_scene(
            scene,
            self.scattering,
            Method::Fast,
            FastTableSize::default(),
        )?;
        // The field for these views' rays only: a low sun's is many
        // times cheaper so, and the same to 5e-7.
        let sky = sky.for_views_above(&group.views);
        Ok(sky
            .radiances(&group.views)?
            .iter()
            .map(|radiance| radiance.radiance_w_m2_sr_nm[0])
            .collect())
    }

    /// Air, gases and the aerosol at wavelength index `wavelength`.
    fn optics_at(&self, wavelength: usize, aerosol: &AerosolOptics) -> AtmosphereOptics {
        let mut optics = self.base_optics[wavelength].clone();
        let extinction_per_m = aerosol.optical_depth / self.column_m;
        optics.species.push(SpeciesOptics {
            name: "retrieved aerosol".into(),
            kind: "mie",
            profile: self.profile.clone(),
            vertical_column_m: self.column_m,
            reference_number_density_m3: None,
            extinction_per_m: SampledSpectrum::from_values(vec![extinction_per_m]),
            scattering_per_m: SampledSpectrum::from_values(vec![
                extinction_per_m * aerosol.single_scattering_albedo,
            ]),
            phase_function: PhaseFunction::Tabulated(
                TabulatedPhase::from_tables(vec![aerosol.phase_function.clone()])
                    .expect("one table"),
            ),
        });
        optics
    }
}

/// The optics of air and gases that a channel of spectral response R
/// (`filter`'s, at the wavelengths of `optics.grid`) sees, as one
/// wavelength at `wavelength_nm` (the aerosol's):
///
/// ```text
///     S_F = sum_i R_i S_i / sum_i R_i                 (the sun through the filter)
///     x_F = sum_i R_i S_i x_i / sum_i R_i S_i         (x: every coefficient, the
///                                                      ground albedo, phase parameters)
/// ```
///
/// so that a sky linear in the sun and in each coefficient is the filter's
/// weighted mean of the skies at the grid's wavelengths: the sky's
/// radiance is proportional to S and, for optical depths well below 1 over
/// a channel's width, nearly linear in the coefficients (the Rayleigh
/// optical depth changes by about 9 % across a 10-nm channel at 440 nm;
/// the test `a_filter_weights_the_sky_as_its_mean_over_the_filter`
/// measures what that leaves against the weighted mean of the skies at the
/// filter's wavelengths).
pub(crate) fn band_optics(
    optics: &AtmosphereOptics,
    filter: &Filter,
    wavelength_nm: f64,
) -> Result<AtmosphereOptics> {
    let sun_through_filter =
        filter.weighted_mean(&optics.grid, &optics.solar_irradiance_w_m2_nm)?;
    let sun = optics.solar_irradiance_w_m2_nm.values();
    let weights: Vec<f64> = optics
        .grid
        .wavelengths_nm()
        .zip(sun)
        .map(|(l, s)| filter.response_at(l) * s)
        .collect();
    let total: f64 = weights.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return Err(Error::Unsupported(format!(
            "a filter at {wavelength_nm} nm: its response sees no sunlight on its grid"
        )));
    }
    let mean = |values: &[f64]| -> f64 {
        values.iter().zip(&weights).map(|(v, w)| v * w).sum::<f64>() / total
    };
    let one =
        |spectrum: &SampledSpectrum| SampledSpectrum::from_values(vec![mean(spectrum.values())]);
    let species = optics
        .species
        .iter()
        .map(|s| {
            let phase_function = match &s.phase_function {
                PhaseFunction::Isotropic => PhaseFunction::Isotropic,
                PhaseFunction::Rayleigh {
                    depolarization_ratios,
                } => PhaseFunction::Rayleigh {
                    depolarization_ratios: vec![mean(depolarization_ratios)],
                },
                PhaseFunction::HenyeyGreenstein { asymmetry_g } => {
                    PhaseFunction::HenyeyGreenstein {
                        asymmetry_g: vec![mean(asymmetry_g)],
                    }
                }
                PhaseFunction::CornetteShanks { g } => {
                    PhaseFunction::CornetteShanks { g: vec![mean(g)] }
                }
                PhaseFunction::Tabulated(table) => {
                    // The row at the response's weighted centre (tabulated
                    // phase functions are smooth over a channel).
                    let centre = optics
                        .grid
                        .wavelengths_nm()
                        .zip(&weights)
                        .map(|(l, w)| l * w)
                        .sum::<f64>()
                        / total;
                    let row = optics
                        .grid
                        .wavelengths_nm()
                        .enumerate()
                        .min_by(|a, b| (a.1 - centre).abs().total_cmp(&(b.1 - centre).abs()))
                        .map_or(0, |(i, _)| i);
                    PhaseFunction::Tabulated(
                        TabulatedPhase::from_tables(vec![table.row(row).clone()])
                            .expect("one table"),
                    )
                }
            };
            SpeciesOptics {
                name: s.name.clone(),
                kind: s.kind,
                profile: s.profile.clone(),
                vertical_column_m: s.vertical_column_m,
                reference_number_density_m3: s.reference_number_density_m3,
                extinction_per_m: one(&s.extinction_per_m),
                scattering_per_m: one(&s.scattering_per_m),
                phase_function,
            }
        })
        .collect();
    Ok(AtmosphereOptics {
        grid: WavelengthGrid::new(wavelength_nm, wavelength_nm, optics.grid.step_nm())?,
        solar_irradiance_w_m2_nm: SampledSpectrum::from_values(vec![sun_through_filter]),
        ground_albedo: one(&optics.ground_albedo),
        species,
    })
}
