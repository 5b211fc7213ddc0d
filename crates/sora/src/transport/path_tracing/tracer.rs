//! The tracer: its parts ([`PathTracer`], the per-chunk [`PathScratch`]),
//! how it is made from a scene, its entry points (radiance, Stokes vector,
//! irradiance) and the loop of one path, vertex after vertex, with Russian
//! roulette (the module docs' steps 1-6 in order).

use std::f64::consts::PI;

use super::estimate::{PARTS, Part, PathTracedSpectrum, STOKES_PARTS, TOTAL};
use super::free_path::{FreePath, SEGMENT_PANELS, SUNLIT_SHARE};
use super::next_event::reflect_depolarised;
use super::scattering::{SUNLIT_DIRECTION_SHARE, cosine_weighted_direction};
use crate::atmosphere::phase_matrix::PhaseMatrix;
use crate::atmosphere::{AtmosphereOptics, DensityProfile, PhaseFunction};
use crate::error::{Error, Result};
use crate::geometry::{
    Vector3, distance_to_ground_boundary, distance_to_top_boundary, perpendicular_basis,
    segment_in_atmosphere,
};
use crate::transport::optical_column::ProfileCorners;
use crate::transport::quadrature::running_integral_matrix;
use crate::transport::random::RandomStream;
use crate::transport::single_scattering::{SUN_RAY_PANELS, SingleScatteringScene};
use crate::transport::stokes::{IDENTITY, Mueller};
use crate::transport::sunlit_directions::SunlitDirections;

/// A path whose largest throughput falls below this value plays Russian
/// roulette (see the module docs). Measured on the clear-sky reference
/// (albedo 0 and 0.3), CPU time times variance at the worst wavelength,
/// relative to 0.5: 1.0 -> 1.1-1.25, 0.5 -> 1, 0.3 -> 1.1, 0.1 -> 1.3.
pub(crate) const RUSSIAN_ROULETTE_THRESHOLD: f64 = 0.5;

/// Russian roulette spares a path at its first this many interactions
/// when they are in the planet's shadow (module docs, step 6). With the
/// directions toward the sunlit air but no path spared, one path's
/// relative standard deviation at sun -10 degrees (earth-clear, the
/// zenith, 560 nm, 200 000 paths) is 112; sparing two, 17.7.
pub(super) const SHADOW_INTERACTIONS_WITHOUT_ROULETTE: u32 = 2;

/// The sky of a [`SingleScatteringScene`] (atmosphere on a grid, planet,
/// eye, sun), ready for path tracing.
#[derive(Debug, Clone)]
pub struct PathTracer<'a> {
    pub(super) optics: &'a AtmosphereOptics,
    pub(super) profiles: Vec<&'a DensityProfile>,
    pub(super) ground_radius_m: f64,
    pub(super) top_radius_m: f64,
    observer: Vector3,
    pub(super) sun_direction: Vector3,
    pub(super) wavelengths: usize,
    /// beta_ext at relative density 1, species-major: [j * wavelengths + i].
    pub(super) extinction_per_m: Vec<f64>,
    /// beta_sca at relative density 1, species-major.
    pub(super) scattering_per_m: Vec<f64>,
    /// Species that scatter at some wavelength.
    pub(super) scatters: Vec<bool>,
    /// True when the ground reflects nothing at any wavelength.
    pub(super) black_ground: bool,
    /// Integrals of the Lagrange basis on the Gauss nodes up to each node
    /// ([`running_integral_matrix`]).
    pub(super) running_integral: [[f64; 4]; 4],
    /// Where a profile has a corner: every ray is cut where it crosses
    /// them.
    pub(super) corners: ProfileCorners,
    /// Whether each path carries the Mueller matrix of its scatterings
    /// (the Stokes vector of the light, `stokes.rs`).
    pub(super) polarised: bool,
    /// The share of free paths drawn from a segment's sunlit part where
    /// the planet's shadow cuts it ([`SUNLIT_SHARE`]; 0 turns it off, for
    /// the tests that compare the two samplers).
    pub(super) sunlit_share: f64,
    /// The share of the directions drawn toward the sunlit air at a vertex
    /// in the planet's shadow ([`SUNLIT_DIRECTION_SHARE`]; 0 turns it off,
    /// for the tests that compare the two samplers).
    pub(super) sunlit_direction_share: f64,
    /// Paths end after this many interactions (scatterings and ground
    /// reflections), so that `multiple_scattering` holds the orders from
    /// 2 to it: for the tests that compare one order (unlimited
    /// otherwise).
    #[cfg(test)]
    max_interactions: u32,
    /// A black target this far along the view from the eye, m (None:
    /// none): a path whose first free path reaches it, or the ground before
    /// it, ends there (aerial perspective,
    /// [`PathTracer::with_target_distance`]).
    target_distance_m: Option<f64>,
}

/// Per-chunk work space (no allocation per path).
#[derive(Debug, Clone)]
pub(super) struct PathScratch {
    /// Distances of the panel ends along the current segment, m.
    pub(super) panel_ends_m: Vec<f64>,
    /// Columns from the segment's start to each panel end,
    /// [panel end * species + j], m (Gauss-Legendre).
    pub(super) panel_columns_m: Vec<f64>,
    /// Distances along the current segment of the points of the sampling
    /// model: every panel end and every Gauss node, m.
    pub(super) sampling_distances_m: Vec<f64>,
    /// The sampling model's columns at those points,
    /// [point * species + j], m (increasing).
    pub(super) sampling_columns_m: Vec<f64>,
    /// Panel ends of a path toward the sun, m.
    pub(super) sun_panel_ends_m: Vec<f64>,
    /// Relative density of each species at the four Gauss nodes of the
    /// current panel.
    pub(super) node_densities: Vec<[f64; 4]>,
    /// Columns from the segment's start to the sampled point, m.
    pub(super) point_columns_m: Vec<f64>,
    /// Columns from a vertex to the top toward the sun, m.
    pub(super) sun_columns_m: Vec<f64>,
    /// Relative density of each species at the current vertex.
    pub(super) densities: Vec<f64>,
    /// tau_lambda of the whole current segment.
    pub(super) segment_optical_depth: Vec<f64>,
    /// Per wavelength: the model's probability of a collision in the
    /// segment's sunlit parts.
    pub(super) sunlit_mass: Vec<f64>,
    /// sigma_s(lambda) at the current vertex, m^-1.
    pub(super) scattering_coefficient: Vec<f64>,
    /// sum_j sigma_s,j p_j at one angle, m^-1 sr^-1.
    pub(super) phase_term: Vec<f64>,
    /// One species' phase function at one angle, per wavelength.
    pub(super) phase_values: Vec<f64>,
    /// The path throughput beta(lambda).
    pub(super) throughput: Vec<f64>,
    /// This path's contributions, [part * wavelengths + i] (and the
    /// Stokes parts after the scalar ones when polarised).
    pub(super) contributions: Vec<f64>,
    /// Polarised paths: the Mueller matrix from the light on the current
    /// segment to the eye, divided by the scalar throughput (one per
    /// wavelength; empty when scalar).
    pub(super) transfer: Vec<Mueller>,
    /// Polarised paths: the reference e_l of the light on the current
    /// segment.
    pub(super) frame_l: Vector3,
    /// sum_j sigma_s,j F_j at one angle, per wavelength.
    pub(super) phase_matrices: Vec<PhaseMatrix>,
    /// One species' phase matrix at one angle, per wavelength.
    pub(super) species_phase_matrices: Vec<PhaseMatrix>,
    /// The scalar estimate of the current next-event, per wavelength.
    pub(super) next_event: Vec<f64>,
}

impl<'a> PathTracer<'a> {
    /// The path tracer of `sky`'s atmosphere, eye and sun.
    pub(crate) fn new(sky: &'a SingleScatteringScene) -> PathTracer<'a> {
        let optics = sky.optics();
        let (ground_radius_m, top_radius_m) = sky.radii_m();
        let wavelengths = optics.grid.len();
        let mut extinction_per_m = Vec::with_capacity(optics.species.len() * wavelengths);
        let mut scattering_per_m = Vec::with_capacity(optics.species.len() * wavelengths);
        for species in &optics.species {
            extinction_per_m.extend_from_slice(species.extinction_per_m.values());
            scattering_per_m.extend_from_slice(species.scattering_per_m.values());
        }
        let profiles: Vec<&DensityProfile> = optics.species.iter().map(|s| &s.profile).collect();
        PathTracer {
            optics,
            corners: ProfileCorners::new(&profiles, ground_radius_m, top_radius_m),
            profiles,
            ground_radius_m,
            top_radius_m,
            observer: Vector3::new(0.0, 0.0, sky.observer_radius_m()),
            sun_direction: sky.sun_direction(),
            wavelengths,
            extinction_per_m,
            scattering_per_m,
            scatters: optics
                .species
                .iter()
                .map(|s| s.scattering_per_m.values().iter().any(|b| *b > 0.0))
                .collect(),
            black_ground: optics.ground_albedo.values().iter().all(|a| *a <= 0.0),
            running_integral: running_integral_matrix(),
            polarised: false,
            sunlit_share: SUNLIT_SHARE,
            sunlit_direction_share: SUNLIT_DIRECTION_SHARE,
            #[cfg(test)]
            max_interactions: u32::MAX,
            target_distance_m: None,
        }
    }

    /// This tracer with a black target `distance_m` m along every view from
    /// the eye (infinity: where the view leaves the atmosphere): the light
    /// the air scatters into the segment between them. The first free path
    /// ends at the target, or at the ground if that is nearer (the ground
    /// is then the scene's point, black too); later ones, scattered off the
    /// view, pass the target as they would a point.
    pub(crate) fn with_target_distance(mut self, distance_m: f64) -> PathTracer<'a> {
        self.target_distance_m = Some(distance_m);
        self
    }

    /// This tracer without its draws toward the sunlit air (free paths and
    /// directions as in daylight): the same expectation, for checking them.
    #[cfg(test)]
    pub(crate) fn without_twilight_sampling(mut self) -> PathTracer<'a> {
        self.sunlit_share = 0.0;
        self.sunlit_direction_share = 0.0;
        self
    }

    /// This tracer ending every path after `interactions` scatterings and
    /// ground reflections (2: its `multiple_scattering` is the second
    /// order alone).
    #[cfg(test)]
    pub(crate) fn with_max_interactions(mut self, interactions: u32) -> PathTracer<'a> {
        self.max_interactions = interactions;
        self
    }

    /// The path tracer of `sky` carrying the polarisation of the light
    /// (Stokes vectors, `stokes.rs`): the same paths and scalar estimates
    /// as [`PathTracer::new`] (the same random numbers decide them), and the
    /// Stokes vector of the total besides. Fails for a species whose phase
    /// matrix is not known (a tabulated Mie phase function).
    pub(crate) fn new_polarised(sky: &'a SingleScatteringScene) -> Result<PathTracer<'a>> {
        let mut tracer = PathTracer::new(sky);
        if let Some(species) = tracer
            .optics
            .species
            .iter()
            .zip(&tracer.scatters)
            .find(|(s, scatters)| **scatters && !s.phase_function.has_phase_matrix())
        {
            return Err(Error::Unsupported(format!(
                "polarisation: species \"{}\" has a Mie phase table without its phase matrix (F12, F33, F34): build the sky with polarisation, which computes it",
                species.0.name
            )));
        }
        // Hansen & Travis's Rayleigh matrix (`phase_matrix.rs`) has
        // D' = (1 - 2 rho) / (1 - rho): above 0.5 its a4 changes sign.
        for species in &tracer.optics.species {
            if let PhaseFunction::Rayleigh {
                depolarization_ratios,
            } = &species.phase_function
                && let Some(rho) = depolarization_ratios.iter().find(|rho| **rho > 0.5)
            {
                return Err(Error::out_of_range(
                    format!(
                        "polarisation: species \"{}\" depolarization_ratio",
                        species.name
                    ),
                    *rho,
                    "1",
                    "0..=0.5 for polarised light (Hansen & Travis 1974, eq. 2.15; scalar light takes up to 1)",
                ));
            }
        }
        tracer.polarised = true;
        Ok(tracer)
    }

    /// Radiance arriving at the eye from the unit direction `view`
    /// (east-north-up), W m^-2 sr^-1 nm^-1, from `samples` paths (at least
    /// 2, for the standard error) drawn with `seed`.
    #[cfg(test)]
    pub(crate) fn compute_radiance(
        &self,
        view: Vector3,
        samples: u64,
        seed: u64,
    ) -> Result<PathTracedSpectrum> {
        let reference = perpendicular_basis(view).0;
        self.compute_stokes_with_progress(view, reference, samples, seed, &|_| {})
    }

    /// Radiance arriving at the eye from the unit direction `view`, as
    /// [`PathTracer::compute_radiance`], calling `progress(samples_done)`
    /// as chunks of samples complete (from worker threads); a polarised
    /// tracer refers the Stokes vector to `reference` at the eye (a unit
    /// vector perpendicular to `view`: e_l of `stokes.rs`, the meridian
    /// plane's [`stokes::meridian_reference`] for the frame sora reports
    /// in).
    pub(crate) fn compute_stokes_with_progress(
        &self,
        view: Vector3,
        reference: Vector3,
        samples: u64,
        seed: u64,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<PathTracedSpectrum> {
        check_unit("view direction", view)?;
        check_unit("polarisation reference", reference)?;
        self.run(samples, seed, progress, |_| (view, reference, 1.0))
    }

    /// Irradiance on a plane facing the unit direction `facing`: the
    /// radiance integrated over the hemisphere it faces, weighted by the
    /// cosine, integral L(w) (w.facing) dw, W m^-2 nm^-1, without the
    /// direct sun. Each sample draws its view direction cosine-weighted
    /// (pdf (w.facing)/pi), so the estimate is pi L(w). Facing down at the
    /// top of the atmosphere it is the upward flux that leaves the planet.
    pub(crate) fn compute_irradiance(
        &self,
        facing: Vector3,
        samples: u64,
        seed: u64,
    ) -> Result<PathTracedSpectrum> {
        check_unit("facing direction", facing)?;
        self.run(samples, seed, &|_| {}, |random| {
            let u = [random.next_f64(), random.next_f64()];
            let view = cosine_weighted_direction(facing, u);
            (view, perpendicular_basis(view).0, PI)
        })
    }

    pub(super) fn scratch(&self) -> PathScratch {
        let (species, n) = (self.profiles.len(), self.wavelengths);
        let most_panels = self.corners.most_panel_ends(SEGMENT_PANELS) - 1;
        PathScratch {
            panel_ends_m: Vec::with_capacity(most_panels + 1),
            panel_columns_m: vec![0.0; (most_panels + 1) * species],
            sampling_distances_m: vec![0.0; 5 * most_panels + 1],
            sampling_columns_m: vec![0.0; (5 * most_panels + 1) * species],
            sun_panel_ends_m: Vec::with_capacity(self.corners.most_panel_ends(SUN_RAY_PANELS)),
            node_densities: vec![[0.0; 4]; species],
            point_columns_m: vec![0.0; species],
            sun_columns_m: vec![0.0; species],
            densities: vec![0.0; species],
            segment_optical_depth: vec![0.0; n],
            sunlit_mass: vec![0.0; n],
            scattering_coefficient: vec![0.0; n],
            phase_term: vec![0.0; n],
            phase_values: vec![0.0; n],
            throughput: vec![0.0; n],
            contributions: vec![0.0; (PARTS + if self.polarised { STOKES_PARTS } else { 0 }) * n],
            transfer: if self.polarised {
                vec![IDENTITY; n]
            } else {
                Vec::new()
            },
            frame_l: Vector3::default(),
            phase_matrices: vec![PhaseMatrix::default(); if self.polarised { n } else { 0 }],
            species_phase_matrices: vec![
                PhaseMatrix::default();
                if self.polarised { n } else { 0 }
            ],
            next_event: vec![0.0; n],
        }
    }

    /// Where the view ray starts in the atmosphere: the eye, or where the
    /// ray enters the top when the eye is above it (None: it misses).
    fn first_point_in_atmosphere(&self, view: Vector3) -> Option<Vector3> {
        if self.observer.length() <= self.top_radius_m {
            return Some(self.observer);
        }
        let (enter, exit) =
            segment_in_atmosphere(self.observer, view, self.ground_radius_m, self.top_radius_m)?;
        if exit <= enter {
            return None;
        }
        Some((self.observer + view * enter).normalized() * self.top_radius_m)
    }

    /// Length (m) of the straight run from `position` along `direction` to
    /// the ground or the top, and whether it ends on the ground.
    fn segment_length(&self, position: Vector3, direction: Vector3) -> (f64, bool) {
        let r = position.length();
        let mu = position.dot(direction) / r;
        let r = r.clamp(self.ground_radius_m, self.top_radius_m);
        match distance_to_ground_boundary(r, mu, self.ground_radius_m) {
            Some(distance) => (distance, true),
            None => (distance_to_top_boundary(r, mu, self.top_radius_m), false),
        }
    }

    /// One path from the eye along `view`, its contributions (times
    /// `weight`) into `scratch.contributions`; a polarised path refers its
    /// Stokes vector at the eye to `reference` (e_l, perpendicular to
    /// `view`).
    pub(super) fn trace_path(
        &self,
        view: Vector3,
        reference: Vector3,
        weight: f64,
        random: &mut RandomStream,
        scratch: &mut PathScratch,
    ) {
        let n = self.wavelengths;
        scratch.contributions.fill(0.0);
        scratch.throughput.fill(weight);
        if self.polarised {
            scratch.transfer.fill(IDENTITY);
            scratch.frame_l = reference;
        }
        if let Some(start) = self.first_point_in_atmosphere(view) {
            let mut position = start;
            let mut direction = view;
            let mut interactions = 0u32;
            loop {
                let mut in_shadow = false;
                let (mut length, mut ends_on_ground) = self.segment_length(position, direction);
                if let (0, Some(target)) = (interactions, self.target_distance_m) {
                    // The target (or the ground before it): the path ends.
                    let target = target - (position - self.observer).length();
                    (length, ends_on_ground) = (length.min(target.max(0.0)), false);
                }
                match self.sample_free_path(
                    position,
                    direction,
                    length,
                    ends_on_ground,
                    random,
                    scratch,
                ) {
                    FreePath::Escapes => break,
                    FreePath::Scatters { distance_m } => {
                        position = position + direction * distance_m;
                        let part = if interactions == 0 {
                            Part::SingleScattering
                        } else {
                            Part::MultipleScattering
                        };
                        self.set_densities(position, scratch);
                        let lit = self.add_scattered_sunlight(position, direction, part, scratch);
                        in_shadow = !lit;
                        let toward_sunlit_air =
                            (!lit && self.sunlit_direction_share > 0.0).then(|| {
                                SunlitDirections::new(
                                    position,
                                    self.sun_direction,
                                    self.ground_radius_m,
                                )
                            });
                        match self.sample_scattering(
                            direction,
                            toward_sunlit_air.as_ref(),
                            random,
                            scratch,
                        ) {
                            Some(next) => direction = next,
                            None => break,
                        }
                    }
                    FreePath::ReachesGround => {
                        let normal = (position + direction * length).normalized();
                        position = normal * self.ground_radius_m;
                        if self.black_ground {
                            break;
                        }
                        let part = if interactions == 0 {
                            Part::SunlitGround
                        } else {
                            Part::MultipleScattering
                        };
                        self.add_sunlit_ground(position, normal, part, scratch);
                        direction = cosine_weighted_direction(
                            normal,
                            [random.next_f64(), random.next_f64()],
                        );
                        if self.polarised {
                            reflect_depolarised(direction, scratch);
                        }
                        for (b, a) in scratch
                            .throughput
                            .iter_mut()
                            .zip(self.optics.ground_albedo.values())
                        {
                            *b *= a;
                        }
                    }
                }
                interactions += 1;
                #[cfg(test)]
                if interactions >= self.max_interactions {
                    break;
                }
                // Russian roulette (unbiased: survivors are reweighted), but
                // not at the first interactions in the planet's shadow.
                let largest = scratch.throughput.iter().copied().fold(0.0, f64::max);
                if largest <= 0.0 {
                    break;
                }
                debug_assert!(largest.is_finite(), "throughput {largest}");
                let spared = in_shadow
                    && self.sunlit_direction_share > 0.0
                    && interactions <= SHADOW_INTERACTIONS_WITHOUT_ROULETTE;
                if largest < RUSSIAN_ROULETTE_THRESHOLD && !spared {
                    let survival = largest / RUSSIAN_ROULETTE_THRESHOLD;
                    if random.next_f64() >= survival {
                        break;
                    }
                    for b in &mut scratch.throughput {
                        *b /= survival;
                    }
                }
            }
        }
        let (parts, rest) = scratch.contributions.split_at_mut(TOTAL * n);
        let total = &mut rest[..n];
        total.fill(0.0);
        for part in parts.chunks_exact(n) {
            for (t, c) in total.iter_mut().zip(part) {
                *t += c;
            }
        }
    }
}

/// A direction argument must be a finite unit vector.
pub(super) fn check_unit(name: &str, direction: Vector3) -> Result<()> {
    let length = direction.length();
    if (length - 1.0).abs() <= 1e-9 {
        Ok(())
    } else {
        Err(Error::out_of_range(
            format!("{name} length"),
            length,
            "1",
            "a unit vector (within 1e-9)",
        ))
    }
}
