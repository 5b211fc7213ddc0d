//! The polarisation of the multiply scattered light, first form: the
//! column at the eye solved twice, with Stokes vectors
//! ([`super::vector_successive_orders`]) and scalar
//! ([`super::successive_orders`]), and the ratio of the two columns'
//! multiply scattered light applied to the sky's own (spherical) multiply
//! scattered radiance:
//!
//! ```text
//! (I, Q, U, V)_ms(eye, w) = L_ms(eye, w) (I, Q, U, V)_col(w) / I_col,scalar(w)
//! ```
//!
//! L_ms the scaled field's radiance (every refinement of the sphere:
//! spherical paths, the spherical first order, the view ray through the
//! shell), the column's Stokes vector and scalar intensity those of the
//! light scattered two or more times that reaches the eye's level from
//! w in the plane-parallel column with the eye's sun zenith angle (the
//! sun's beam attenuated along its real path through the shell, as the
//! scalar field's), by source-function integration along w from the
//! top (looking up) or the ground (looking down) to the eye's level.
//!
//! The forward-peak term of delta-M (`forward_peak.rs`) is not the
//! scaled field's: light scattered once through the view's scattering
//! angle by a smooth phase function and otherwise only near-forward, it
//! keeps its intensity and is polarised as single scattering is (the sky
//! adds its Q and U with single scattering's). Until it was, the column's
//! ratios were applied to it too, and mars-dust's degree of polarisation
//! 10 degrees up away from a sun 5 degrees high was 0.049 against the
//! vector path tracer's 0.073 at 440 nm (now 0.076; `docs/polarisation.md`).
//!
//! **Deep twilight**: the column's first order is its own, so once the
//! sun is acos(R_ground / R_top) below the horizon (10.1 degrees on Earth)
//! every level of it is in the planet's shadow and it has no light. Its
//! sun stops `POLARISATION_COLUMN_MARGIN_DEG` above that (`regimes.rs`):
//! a lower eye sun takes that column's ratios, which are flat there and
//! match the vector path tracer's ratio of polarised to scalar intensity
//! at the zenith to 1-2 % down to -12 degrees; from
//! `POLARISATION_FADE_START_DEG` below the last lit sun the ratios are
//! blended toward unpolarised light, (1, 0, 0, 0), the column's share
//! falling as exp(-d / `POLARISATION_FADE_SCALE_DEG`) (d degrees past the
//! start), as the path tracer's vector effect does at -14 to -18.
//!
//! **What it is exact for**: the plane-parallel limit, where the scalar
//! field is the column's and the ratio turns its intensity into the
//! polarised one. **What it assumes on the sphere**: that the sphere
//! changes the polarised and the scalar multiply scattered light in the
//! same proportion (the ratio is a smooth function of direction, a degree
//! of polarisation and a few per cent of intensity); with the sun near or
//! below the horizon the column's first order is its own (not the
//! spherical one), so the ratio is the one of a column whose lower air is
//! in the shadow. The measured accuracy against the vector path tracer is
//! in `docs/polarisation.md`.
//!
//! **Segments** (aerial perspective): the light of the air between the
//! eye and a point is the sources along that segment only, so its ratio
//! is the column's integrated from the altitude where the segment ends
//! (the partial layer with its source interpolated linearly) to the
//! eye's level, without the ground's light; a segment that ends beyond
//! the top of the atmosphere is the whole view. Near the ground at a low
//! sun the two differ: with the sun 2 degrees up, 10 degrees up away
//! from it at 440 nm, the whole column's polarised multiply scattered
//! intensity is 1.12 times the scalar one, the lowest kilometre's 1.07
//! times (the vector and scalar path tracers), and the whole column's
//! ratio made such segments 5-6 % too bright.
//!
//! **Wavelengths**: the columns are solved at the anchors of
//! `MultipleScatteringSettings::polarisation_wavelength_stride` that
//! follow the sky's absorption (every third wavelength by default and the
//! last, at most 60 nm apart, and every wavelength where the anchors'
//! cubic misses the column's absorbing optical depth, scattering optical
//! depth or ground albedo: `spectrum/anchors.rs`; stride 1: every
//! wavelength); at the other wavelengths both columns' fields,
//! per unit of solar irradiance, are the cubic through the four nearest
//! anchors' (the same weights for both, so their ratio is a weighted mean
//! of the anchors'), and the views' source integration is the
//! wavelength's own (its optical depths and albedos). Against every
//! wavelength solved (stride 1, the exact path and the test's oracle,
//! `tests/polarisation_wavelength_stride.rs`; the Mie ratios interpolated
//! alike), over suns 30, 5 and -4, 380-780 nm every 20 nm: within 5e-4 in
//! I and 1.5e-3 in the degree of polarisation for earth-clear and
//! earth-hazy, 7e-5 and 4.3e-3 for mars-dust (its Mie ratios at 760 nm);
//! earth-clear-summer (ozone, NO2, O2-O2, the water and O2 bands) within
//! 5e-4 and 1.2e-3 on 280-360, 680-800 and 880-1000 nm every 5 nm,
//! 380-780 and 280-2500 nm every 20 nm (docs/polarisation.md); a grid of
//! one or two wavelengths, or one coarser than 60 nm, is solved at every
//! wavelength. The scalar column at an anchor is the field's own column
//! at that wavelength when the field has a sun node at the column's sun
//! (below the spherical first order's nodes): the field's solve hands its
//! system and its solution there to the vector solve
//! ([`AnchorSolves::solve_anchor`]), the same values as a solve of its own
//! (`field.rs`'s test), made once.
//!
//! **The truncated phase matrix**: delta-M truncates the phase function
//! (`phase_fourier.rs`); the matrix's other elements are taken in the
//! same proportion to it as in the exact matrix, F*_xy = (F_xy / F_11)
//! F*_11 (exact for Rayleigh, which is not truncated, and for
//! non-polarising species, whose ratios are 0 and 1).

use std::cell::RefCell;
use std::f64::consts::PI;
use std::sync::{Arc, Mutex};

use super::column_optics::{ColumnGeometry, ScaledOptics};
use super::phase_fourier::{MAX_LEGENDRE_TERMS, TruncatedPhase, legendre_polynomials};
use super::phase_matrix_fourier::{COMPONENTS, PhaseMatrixHarmonics, is_even_component};
use super::spherical_paths::linear_source_weights;
use super::successive_orders::{ColumnSystem, ScaledSpecies, Streams};
use super::vector_successive_orders::VectorColumnSystem;
use super::vertical_grid::locate_among;
use crate::atmosphere::phase_matrix::PhaseMatrix;
use crate::atmosphere::{AtmosphereOptics, PhaseFunction};
use crate::spectrum::WavelengthAnchors;

/// The smallest |cosine| of a view's zenith angle the column integrates
/// along (a horizontal view sees the eye level's own source).
const SMALLEST_VIEW_COSINE: f64 = 1e-6;

/// Everything the correction's columns need from the scalar field.
pub(crate) struct CorrectionInputs<'a> {
    pub(crate) optics: &'a AtmosphereOptics,
    pub(crate) scaled: &'a ScaledOptics,
    pub(crate) geometry: &'a ColumnGeometry,
    /// The column's sun zenith cosine: the eye's, or the lowest sun that
    /// still lights the column (see the module docs).
    pub(crate) sun_cosine: f64,
    /// The share of the column's polarisation kept, 0..1 (1 but in deep
    /// twilight, see the module docs).
    pub(crate) polarised_share: f64,
    /// The scaled and exact optical depths toward the sun from each level,
    /// [i * levels + k], None for a level in the planet's shadow (the
    /// eye's sun zenith angle).
    pub(crate) sun_optical_depths: &'a [Option<(f64, f64)>],
    pub(crate) eye_altitude_m: f64,
    /// The sky's store of the image table's and the columns' harmonics
    /// from the streams ([`ViewHarmonicsCache`]), shared by the skies moved
    /// to other suns.
    pub(crate) view_harmonics: Arc<ViewHarmonicsCache>,
    /// The wavelengths the columns are solved at; the others' fields are
    /// interpolated between them (see the module docs, "Wavelengths").
    pub(crate) anchors: &'a WavelengthAnchors,
}

/// Each species' phase-matrix harmonics from the streams into the view
/// zenith cosines of the image table's nodes ([`PolarisationTable`]) and
/// into the streams themselves (the columns' own; what
/// `compute_species_harmonics` gives without the sun), kept once computed:
/// they depend on the scattering species' phase functions and truncated
/// phases (the key: [`HarmonicsKey`]), the streams and those fixed
/// cosines, not on the sun or on what absorbs, so a sky moved to another
/// sun (`SingleScatteringScene::with_sun`, a slider drag) and the
/// k-distribution's term skies (`sky/k_terms.rs`: their atmospheres differ
/// in the banded gases' absorption only;
/// `SingleScatteringScene::sharing_view_harmonics`) read them instead of
/// computing them again, the same numbers bit for bit; only the columns'
/// harmonics from the sun are computed per sun
/// ([`PhaseMatrixHarmonics::with_sun_of`]). The table's were three
/// quarters of the phase-matrix work of a polarised image's field, the
/// columns' the rest. Size: the harmonics stored (all 2N of a Mie or
/// Henyey-Greenstein species, 3 of Rayleigh's, none of an absorber's) x 16
/// x streams x cosines x wavelengths doubles (39 MB at 8 streams per
/// hemisphere, 21 wavelengths, Rayleigh and one aerosol, for the table's
/// 48 cosines, and a third of that for the streams' 16; the explorer's
/// preview is scalar); only the table's nodes and the streams are kept,
/// not a list of directions' cosines.
#[derive(Debug, Default)]
pub(crate) struct ViewHarmonicsCache(Mutex<Vec<ViewHarmonics>>);

/// One entry of [`ViewHarmonicsCache`]: its key and the harmonics.
#[derive(Debug)]
struct ViewHarmonics {
    key: HarmonicsKey,
    harmonics: Arc<Vec<Vec<PhaseMatrixHarmonics>>>,
}

/// Everything [`compute_species_harmonics`] without the sun reads: the
/// streams' and the views' cosines (bits), the wavelengths' indices and
/// their wavelengths (bits, nm), and per species `None` for one that
/// scatters nothing (its harmonics are zero) or its phase function and
/// its truncated phases at those wavelengths (forward fraction and
/// coefficients, bits). What absorbs, and how much, is not in it.
#[derive(Debug, PartialEq)]
struct HarmonicsKey {
    stream_cosines: Vec<u64>,
    view_cosines: Vec<u64>,
    wavelengths: Vec<usize>,
    wavelengths_nm: Vec<u64>,
    species: Vec<Option<(PhaseFunction, Vec<u64>)>>,
}

impl HarmonicsKey {
    fn new(
        (optics, phases): (&AtmosphereOptics, &[TruncatedPhase]),
        (streams, view_cosines, wavelengths): (&Streams, &[f64], &[usize]),
    ) -> HarmonicsKey {
        let bits = |values: &[f64]| values.iter().map(|v| v.to_bits()).collect::<Vec<u64>>();
        let count = optics.species.len();
        let species = optics
            .species
            .iter()
            .enumerate()
            .map(|(j, s)| {
                (!scatters_nothing(s)).then(|| {
                    let truncated = wavelengths
                        .iter()
                        .map(|i| &phases[i * count + j])
                        .flat_map(|p| std::iter::once(&p.forward_fraction).chain(&p.coefficients))
                        .map(|v| v.to_bits())
                        .collect();
                    (s.phase_function.clone(), truncated)
                })
            })
            .collect();
        HarmonicsKey {
            stream_cosines: bits(streams.cosines()),
            view_cosines: bits(view_cosines),
            wavelengths: wavelengths.to_vec(),
            wavelengths_nm: wavelengths
                .iter()
                .map(|i| optics.grid.wavelength_nm(*i).to_bits())
                .collect(),
            species,
        }
    }
}

/// Whether species `s` scatters at no wavelength (an absorber: ozone, a
/// banded gas).
fn scatters_nothing(s: &crate::atmosphere::SpeciesOptics) -> bool {
    s.scattering_per_m.values().iter().all(|b| *b == 0.0)
}

impl ViewHarmonicsCache {
    /// The harmonics of `optics` (truncated phases `phases`) for these
    /// streams, view cosines and wavelengths: the kept ones (of these
    /// optics or of optics that scatter the same, [`HarmonicsKey`]), or
    /// `compute()`'s (computed without the lock, which the thread pool's
    /// other tasks may want; of two threads that race, the first one's are
    /// kept).
    fn get_or_compute(
        &self,
        optics: (&AtmosphereOptics, &[TruncatedPhase]),
        views: (&Streams, &[f64], &[usize]),
        compute: impl FnOnce() -> Vec<Vec<PhaseMatrixHarmonics>>,
    ) -> Arc<Vec<Vec<PhaseMatrixHarmonics>>> {
        let key = HarmonicsKey::new(optics, views);
        // A poisoned lock only means that another thread panicked: the
        // entries in it are whole (each is pushed when complete).
        let lock = || {
            self.0
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
        };
        let find = |entries: &[ViewHarmonics]| {
            entries
                .iter()
                .find(|e| e.key == key)
                .map(|e| Arc::clone(&e.harmonics))
        };
        if let Some(harmonics) = find(&lock()) {
            return harmonics;
        }
        let harmonics = Arc::new(compute());
        let mut entries = lock();
        if let Some(first) = find(&entries) {
            return first;
        }
        entries.push(ViewHarmonics {
            key,
            harmonics: Arc::clone(&harmonics),
        });
        harmonics
    }
}

/// The two columns' fields at the eye's sun zenith angle (see the module
/// docs).
#[derive(Debug, Clone)]
pub struct PolarisationCorrection {
    wavelengths: usize,
    species: usize,
    streams: Streams,
    levels: usize,
    eye_level: usize,
    /// The column's level altitudes, m (where a segment's rows stop).
    level_altitudes_m: Vec<f64>,
    /// Per wavelength the polarised field, the scalar field, and the two
    /// ground radiances (polarised, scalar), W m^-2 sr^-1 nm^-1.
    solutions: Vec<f64>,
    solution_len: usize,
    /// [i * layers + k].
    layer_optical_depths: Vec<f64>,
    /// omega_j per wavelength and level, [(i * levels + k) * species + j].
    level_albedos: Vec<f64>,
    /// The share of the column's polarisation kept ([`CorrectionInputs`]).
    polarised_share: f64,
    /// The image table's harmonics, kept ([`ViewHarmonicsCache`]).
    view_harmonics: Arc<ViewHarmonicsCache>,
}

/// F*(cos theta) of species `j` at the wavelengths of indices
/// `wavelengths` into `out` (one each): the exact matrix scaled to the
/// truncated phase function (see the module docs); `all` is room for the
/// exact matrix at every wavelength.
fn truncated_phase_matrix_into(
    function: &PhaseFunction,
    phases: &[TruncatedPhase],
    (j, species): (usize, usize),
    (wavelengths, cos_theta): (&[usize], f64),
    all: &mut [PhaseMatrix],
    out: &mut [PhaseMatrix],
) {
    function.phase_matrix_into(cos_theta, all);
    // The Legendre polynomials once for every wavelength's series.
    let mut legendre = [0.0; MAX_LEGENDRE_TERMS];
    let terms = wavelengths
        .iter()
        .map(|i| phases[i * species + j].terms())
        .max()
        .unwrap_or(0);
    legendre_polynomials(cos_theta, &mut legendre[..terms]);
    for (m, &i) in out.iter_mut().zip(wavelengths) {
        *m = all[i];
        let truncated = phases[i * species + j].eval_with_legendre(&legendre[..terms]);
        let scale = if m.a1 > 0.0 { truncated / m.a1 } else { 0.0 };
        for value in [
            &mut m.a1, &mut m.a2, &mut m.a3, &mut m.a4, &mut m.b1, &mut m.b2,
        ] {
            *value *= scale;
        }
    }
}

/// The harmonics of the Rayleigh phase matrix that do not vanish, m = 0, 1, 2.
const RAYLEIGH_HARMONICS: usize = 3;

/// Each species' harmonics 0..`harmonics` of its truncated phase matrix
/// from the look directions of zenith cosines and weights `inputs` (the
/// streams, or none) and the sun, if given, into the look directions of
/// zenith cosines `outputs`, at the wavelengths of indices `wavelengths`:
/// [j][n] for the n-th of them. The species are independent and computed
/// in parallel.
fn compute_species_harmonics(
    optics: &AtmosphereOptics,
    (phases, wavelengths): (&[TruncatedPhase], &[usize]),
    (inputs, harmonics): ((&[f64], &[f64]), usize),
    outputs: &[f64],
    sun_cosine: Option<f64>,
) -> Vec<Vec<PhaseMatrixHarmonics>> {
    let species = optics.species.len();
    let mut all: Vec<Vec<PhaseMatrixHarmonics>> = vec![Vec::new(); species];
    crate::parallel::for_each_chunk_mut(&mut all, 1, |j, slot| {
        let s = &optics.species[j];
        // An absorber (ozone) scatters nothing: its harmonics are zero, and
        // none are stored.
        slot[0] = if scatters_nothing(s) {
            PhaseMatrixHarmonics::none(wavelengths.len(), harmonics)
        } else {
            // Rayleigh's harmonics end at m = 2 (its phase matrix is
            // quadratic in the scattering angle's cosine, and not truncated).
            let nonzero = match s.phase_function {
                PhaseFunction::Rayleigh { .. } => RAYLEIGH_HARMONICS,
                _ => harmonics,
            };
            let all = RefCell::new(vec![PhaseMatrix::default(); optics.grid.len()]);
            PhaseMatrixHarmonics::compute_nonzero(
                &|c, out| {
                    truncated_phase_matrix_into(
                        &s.phase_function,
                        phases,
                        (j, species),
                        (wavelengths, c),
                        &mut all.borrow_mut(),
                        out,
                    )
                },
                wavelengths.len(),
                outputs,
                inputs,
                sun_cosine,
                (harmonics, nonzero),
            )
        };
    });
    all
}

/// [`compute_species_harmonics`] from the streams `streams`.
fn compute_species_harmonics_from_streams(
    optics: &AtmosphereOptics,
    phases: (&[TruncatedPhase], &[usize]),
    streams: &Streams,
    outputs: &[f64],
    sun_cosine: Option<f64>,
) -> Vec<Vec<PhaseMatrixHarmonics>> {
    compute_species_harmonics(
        optics,
        phases,
        ((streams.cosines(), streams.weights()), streams.count()),
        outputs,
        sun_cosine,
    )
}

impl PolarisationCorrection {
    /// Solves both columns at every anchor on their own (the field's solve
    /// shares its scalar column with them where it can, the same solves:
    /// the tests compare the two).
    #[cfg(test)]
    pub(crate) fn compute(inputs: &CorrectionInputs) -> PolarisationCorrection {
        AnchorSolves::new(inputs).finish(Vec::new())
    }

    /// Per wavelength, the columns' solutions (vector field, scalar field,
    /// ground values), interpolated between the anchors.
    #[cfg(test)]
    pub(crate) fn solutions(&self) -> &[f64] {
        &self.solutions
    }
}

/// A correction's columns at its anchor wavelengths, prepared
/// ([`AnchorSolves::new`]: each species' phase-matrix harmonics), solved
/// one by one ([`AnchorSolves::solve_anchor`], by the field's solve for
/// the anchors it shares its column with) and then all together into the
/// correction ([`AnchorSolves::finish`]).
pub(crate) struct AnchorSolves<'a> {
    inputs: &'a CorrectionInputs<'a>,
    /// Each species' harmonics at each anchor, [j][n].
    harmonics: Vec<Vec<PhaseMatrixHarmonics>>,
    vector_len: usize,
    scalar_len: usize,
}

impl<'a> AnchorSolves<'a> {
    pub(crate) fn new(inputs: &'a CorrectionInputs<'a>) -> AnchorSolves<'a> {
        let optics = inputs.optics;
        let streams = &inputs.geometry.streams;
        let total = streams.count();
        let levels = inputs.geometry.grid.levels();
        let cosines = streams.cosines();
        // The wavelengths the columns are solved at.
        let anchors = inputs.anchors.anchors();
        // Each species' harmonics between the streams and from the sun, at
        // every anchor: [j][n].
        // (The streams' kept, the sun's computed now.)
        let phases = &inputs.scaled.phases;
        let from_streams = inputs.view_harmonics.get_or_compute(
            (optics, phases),
            (streams, cosines, anchors),
            || {
                compute_species_harmonics_from_streams(
                    optics,
                    (phases, anchors),
                    streams,
                    cosines,
                    None,
                )
            },
        );
        let from_sun = compute_species_harmonics(
            optics,
            (phases, anchors),
            ((&[], &[]), total),
            cosines,
            Some(inputs.sun_cosine),
        );
        let harmonics: Vec<Vec<PhaseMatrixHarmonics>> = from_streams
            .iter()
            .zip(&from_sun)
            .map(|(streams, sun)| {
                streams
                    .iter()
                    .zip(sun)
                    .map(|(h, s)| h.with_sun_of(s))
                    .collect()
            })
            .collect();
        AnchorSolves {
            inputs,
            harmonics,
            vector_len: total * COMPONENTS * levels * total,
            scalar_len: total * levels * total,
        }
    }

    /// The values of one anchor's solution: the vector field, the scalar
    /// field and the ground's two values.
    pub(crate) fn solution_len(&self) -> usize {
        self.vector_len + self.scalar_len + 2
    }

    /// The index among the anchors of wavelength `i`, if it is one.
    pub(crate) fn anchor_of(&self, i: usize) -> Option<usize> {
        self.inputs.anchors.anchors().binary_search(&i).ok()
    }

    /// The scalar system of anchor `n`'s wavelength (the field's, which
    /// [`AnchorSolves::solve_anchor`] may take from the field's solve).
    fn column_system(&self, n: usize) -> ColumnSystem<'a> {
        let inputs = self.inputs;
        let optics = inputs.optics;
        let species = optics.species.len();
        let i = inputs.anchors.anchors()[n];
        let scaled: Vec<ScaledSpecies> = (0..species)
            .map(|j| ScaledSpecies {
                extinction_per_m: inputs.scaled.scaled_extinction[i * species + j],
                scattering_per_m: inputs.scaled.scaled_scattering[i * species + j],
                phase: &inputs.scaled.phases[i * species + j],
            })
            .collect();
        ColumnSystem::new(
            &inputs.geometry.streams,
            &inputs.geometry.grid,
            Some(&inputs.geometry.paths),
            scaled,
            optics.solar_irradiance_w_m2_nm[i],
            optics.ground_albedo[i],
        )
    }

    /// Anchor `n`'s solution ([`AnchorSolves::solution_len`] values) into
    /// `out`, with `work` space, from `scalar`, the scalar system of its
    /// wavelength: with `solved`, the scalar field that `scalar` solved for
    /// the column's sun and transmittances and its diffuse downward
    /// irradiance at the ground (the field's solve at that sun node, the
    /// same solve), else solved here.
    pub(crate) fn solve_anchor(
        &self,
        n: usize,
        scalar: ColumnSystem,
        solved: Option<(&[f64], f64)>,
        work: &mut Vec<f64>,
        out: &mut [f64],
    ) {
        let inputs = self.inputs;
        let optics = inputs.optics;
        let levels = inputs.geometry.grid.levels();
        let i = inputs.anchors.anchors()[n];
        let solar = optics.solar_irradiance_w_m2_nm[i];
        let albedo = optics.ground_albedo[i];
        let lit = inputs.sun_cosine.max(0.0);
        let optical_depths = &inputs.sun_optical_depths[i * levels..(i + 1) * levels];
        let transmittance: Vec<f64> = optical_depths
            .iter()
            .map(|t| t.map_or(0.0, |(scaled, _)| (-scaled).exp()))
            .collect();
        let exact_ground = optical_depths[0].map_or(0.0, |(_, exact)| (-exact).exp());
        let (vector_field, rest) = out.split_at_mut(self.vector_len);
        let (scalar_field, ground) = rest.split_at_mut(self.scalar_len);
        let sun_cosine = inputs.sun_cosine;
        let down_scalar = match solved {
            Some((field, down)) => {
                scalar_field.copy_from_slice(field);
                down
            }
            None => scalar.solve(sun_cosine, &transmittance, scalar_field, work),
        };
        let per_species: Vec<&PhaseMatrixHarmonics> =
            self.harmonics.iter().map(|h| &h[n]).collect();
        let vector = VectorColumnSystem::new(scalar, &per_species);
        debug_assert_eq!(vector.field_len(), self.vector_len);
        let down_vector = vector.solve(sun_cosine, &transmittance, vector_field, work);
        // The ground's diffuse light as the scalar field's ground
        // term takes it (the sunlit ground's single reflection is
        // exact elsewhere; delta-M's share of the beam stays here).
        let beam = solar * lit * (transmittance[0] - exact_ground);
        ground[0] = albedo / PI * (down_vector + beam);
        ground[1] = albedo / PI * (down_scalar + beam);
    }

    /// The correction, from `solved`: per anchor, its solution if the
    /// field's solve gave it (empty: none did); the others are solved
    /// here.
    pub(crate) fn finish(self, solved: Vec<Option<Vec<f64>>>) -> PolarisationCorrection {
        let inputs = self.inputs;
        let optics = inputs.optics;
        let wavelengths = optics.grid.len();
        let species = optics.species.len();
        let streams = &inputs.geometry.streams;
        let grid = &inputs.geometry.grid;
        let levels = grid.levels();
        let anchors = inputs.anchors.anchors();
        let solution_len = self.solution_len();
        let mut anchor_solutions = vec![0.0; anchors.len() * solution_len];
        let mut level_albedos = vec![0.0; wavelengths * levels * species];
        let mut layer_optical_depths = vec![0.0; wavelengths * (levels - 1)];
        for i in 0..wavelengths {
            for k in 0..levels - 1 {
                layer_optical_depths[i * (levels - 1) + k] = (0..species)
                    .map(|j| {
                        inputs.scaled.scaled_extinction[i * species + j]
                            * grid.layer_columns_m(k)[j]
                    })
                    .sum();
            }
        }
        // The solves' work space (1.4 MB at 8 streams per hemisphere and 40
        // layers) is kept from one wavelength to the next a thread takes.
        let init = Vec::new;
        crate::parallel::for_each_chunk_mut_with(
            &mut anchor_solutions,
            solution_len,
            init,
            |work, n, out| match solved.get(n).and_then(Option::as_ref) {
                Some(solution) => out.copy_from_slice(solution),
                None => self.solve_anchor(n, self.column_system(n), None, work, out),
            },
        );
        let solutions = interpolate_solutions(
            inputs.anchors,
            anchor_solutions,
            optics.solar_irradiance_w_m2_nm.values(),
        );
        // The level albedos are the scalar system's (the same for both).
        for i in 0..wavelengths {
            for k in 0..levels {
                let densities = grid.densities_at_level(k);
                let extinction: f64 = (0..species)
                    .map(|j| inputs.scaled.scaled_extinction[i * species + j] * densities[j])
                    .sum();
                if extinction > 0.0 {
                    for j in 0..species {
                        level_albedos[(i * levels + k) * species + j] = densities[j]
                            * inputs.scaled.scaled_scattering[i * species + j]
                            / extinction;
                    }
                }
            }
        }
        let (k, t) = grid.locate(inputs.eye_altitude_m);
        PolarisationCorrection {
            wavelengths,
            species,
            streams: streams.clone(),
            levels,
            eye_level: if t < 0.5 { k } else { (k + 1).min(levels - 1) },
            level_altitudes_m: grid.altitudes_m().to_vec(),
            solutions,
            solution_len,
            layer_optical_depths,
            level_albedos,
            polarised_share: inputs.polarised_share.clamp(0.0, 1.0),
            view_harmonics: Arc::clone(&inputs.view_harmonics),
        }
    }
}

impl PolarisationCorrection {
    /// The column's `ratios` blended by its polarised share ([`blend`]).
    fn blend(&self, ratios: [f64; COMPONENTS]) -> [f64; COMPONENTS] {
        blend(self.polarised_share, ratios)
    }

    /// The azimuthal harmonics of the columns' multiply scattered light
    /// that reaches the eye's level from the views of zenith cosines
    /// `view_cosines` (W m^-2 sr^-1 nm^-1): per view a, wavelength i and
    /// harmonic m, the polarised (I, Q, U, V)_m and the scalar I_m,
    /// [((a * wavelengths + i) * harmonics + m) * ROW_VALUES + n] (cosine
    /// coefficients for I, Q and the scalar I, sine coefficients for U and
    /// V), by source-function integration along each view from the top
    /// (looking up) or the ground (looking down) to the eye's level; for a
    /// view with a finite end altitude (a segment of the view,
    /// [`ViewExtent`]) from that altitude instead, without the ground's
    /// light: the light of the column's air between the eye's level and
    /// the segment's end.
    fn compute_harmonic_rows(
        &self,
        optics: &AtmosphereOptics,
        phases: &[TruncatedPhase],
        extents: &[ViewExtent],
        keep_harmonics: bool,
    ) -> Vec<f64> {
        let view_cosines: Vec<f64> = extents.iter().map(|v| v.0).collect();
        let (w, species, levels) = (self.wavelengths, self.species, self.levels);
        let total = self.streams.count();
        let block = levels * total;
        let views = view_cosines.len();
        // A horizontal view sees the eye level's own source; a view within
        // SMALLEST_VIEW_COSINE of it is taken as looking up.
        let cosines: Vec<f64> = view_cosines
            .iter()
            .map(|&mu| {
                if mu.abs() < SMALLEST_VIEW_COSINE {
                    SMALLEST_VIEW_COSINE
                } else {
                    mu
                }
            })
            .collect();
        // The image table's nodes keep their harmonics for the next sun
        // (`keep_harmonics`); a list of directions' cosines does not.
        let every: Vec<usize> = (0..w).collect();
        let compute = || {
            compute_species_harmonics_from_streams(
                optics,
                (phases, &every),
                &self.streams,
                &cosines,
                None,
            )
        };
        let harmonics = if keep_harmonics {
            self.view_harmonics.get_or_compute(
                (optics, phases),
                (&self.streams, &cosines, &every),
                compute,
            )
        } else {
            Arc::new(compute())
        };
        // Which species' harmonics scatter at all (Rayleigh's end at m = 2).
        let active: Vec<Vec<bool>> = harmonics
            .iter()
            .map(|per_wavelength| {
                (0..w)
                    .flat_map(|i| (0..total).map(move |m| (i, m)))
                    .map(|(i, m)| !per_wavelength[i].harmonic_vanishes(m))
                    .collect()
            })
            .collect();
        // The levels the views' integrations reach: from the eye's up for
        // a view looking up, down for one looking down (an eye on the
        // ground looking down sees only the ground's light).
        let needed = {
            let lowest = if cosines.iter().any(|mu| *mu < 0.0) {
                0
            } else {
                self.eye_level
            };
            let highest = if cosines.iter().any(|mu| *mu > 0.0) {
                levels - 1
            } else {
                self.eye_level
            };
            lowest..=highest
        };
        let mut rows = vec![0.0; views * w * total * ROW_VALUES];
        // The sources at every level toward every view, [(k * views + a) *
        // ROW_VALUES + n]; one species' matrix times the field, [n * views
        // + a] (contiguous in the matrix's own order, so it vectorises).
        let mut sources = vec![0.0; levels * views * ROW_VALUES];
        let mut product = vec![0.0; COMPONENTS * views];
        let mut scalar_product = vec![0.0; views];
        for i in 0..w {
            let solution = &self.solutions[i * self.solution_len..][..self.solution_len];
            let vector_len = total * COMPONENTS * block;
            let (vector_field, rest) = solution.split_at(vector_len);
            let (scalar_field, ground) = rest.split_at(total * block);
            let dtau = &self.layer_optical_depths[i * (levels - 1)..(i + 1) * (levels - 1)];
            for m in 0..total {
                sources.fill(0.0);
                for (k, level_sources) in sources
                    .chunks_exact_mut(views * ROW_VALUES)
                    .enumerate()
                    .filter(|(k, _)| needed.contains(k))
                {
                    for (j, species_harmonics) in harmonics.iter().enumerate() {
                        let omega = self.level_albedos[(i * levels + k) * species + j];
                        if omega == 0.0 || !active[j][i * total + m] {
                            continue;
                        }
                        let matrix = species_harmonics[i].scattering(m);
                        product.fill(0.0);
                        scalar_product.fill(0.0);
                        for c in 0..COMPONENTS {
                            for b in 0..total {
                                let radiance =
                                    vector_field[(m * COMPONENTS + c) * block + k * total + b];
                                let column = &matrix[(c * total + b) * COMPONENTS * views..]
                                    [..COMPONENTS * views];
                                for (p, z) in product.iter_mut().zip(column) {
                                    *p += z * radiance;
                                }
                            }
                        }
                        for b in 0..total {
                            let radiance = scalar_field[m * block + k * total + b];
                            let column = &matrix[b * COMPONENTS * views..][..views];
                            for (p, z) in scalar_product.iter_mut().zip(column) {
                                *p += z * radiance;
                            }
                        }
                        for (a, source) in level_sources.chunks_exact_mut(ROW_VALUES).enumerate() {
                            for n in 0..COMPONENTS {
                                source[n] += omega * product[n * views + a];
                            }
                            source[COMPONENTS] += omega * scalar_product[a];
                        }
                    }
                }
                for (a, &mu) in cosines.iter().enumerate() {
                    let source = |k: usize| &sources[(k * views + a) * ROW_VALUES..][..ROW_VALUES];
                    let mut radiance = [0.0; ROW_VALUES];
                    // Through a layer of optical depth `depth` (vertical)
                    // whose source is linear from `near` (the eye's side)
                    // to `far`.
                    let carry_through = |radiance: &mut [f64; ROW_VALUES],
                                         depth: f64,
                                         near: &[f64],
                                         far: &[f64]| {
                        let (one_minus_e, c) = linear_source_weights(depth / mu.abs());
                        for (n, r) in radiance.iter_mut().enumerate() {
                            *r =
                                (1.0 - one_minus_e) * *r + (one_minus_e - c) * near[n] + c * far[n];
                        }
                    };
                    let carry =
                        |radiance: &mut [f64; ROW_VALUES], k: usize, near: usize, far: usize| {
                            carry_through(radiance, dtau[k], source(near), source(far));
                        };
                    // The source at a fraction t up layer k.
                    let source_within = |k: usize, t: f64| -> [f64; ROW_VALUES] {
                        let (lower, upper) = (source(k), source(k + 1));
                        std::array::from_fn(|n| lower[n] + t * (upper[n] - lower[n]))
                    };
                    let end = views_end_altitude(extents[a]);
                    match end {
                        None if mu > 0.0 => {
                            for k in (self.eye_level..levels - 1).rev() {
                                carry(&mut radiance, k, k, k + 1);
                            }
                        }
                        None => {
                            if m == 0 {
                                radiance[0] = ground[0];
                                radiance[COMPONENTS] = ground[1];
                            }
                            for k in 0..self.eye_level {
                                carry(&mut radiance, k, k + 1, k);
                            }
                        }
                        Some(end) => {
                            let (k_end, t) = locate_among(&self.level_altitudes_m, end);
                            if mu > 0.0 && k_end >= self.eye_level {
                                // The part of layer k_end below the end,
                                // then the whole layers down to the eye.
                                let far = source_within(k_end, t);
                                carry_through(&mut radiance, t * dtau[k_end], source(k_end), &far);
                                for k in (self.eye_level..k_end).rev() {
                                    carry(&mut radiance, k, k, k + 1);
                                }
                            } else if mu < 0.0 && k_end < self.eye_level {
                                let far = source_within(k_end, t);
                                carry_through(
                                    &mut radiance,
                                    (1.0 - t) * dtau[k_end],
                                    source(k_end + 1),
                                    &far,
                                );
                                for k in k_end + 1..self.eye_level {
                                    carry(&mut radiance, k, k + 1, k);
                                }
                            } else {
                                // The segment ends on the eye's side of
                                // its level: the level's own source.
                                let eye = source(self.eye_level);
                                carry_through(
                                    &mut radiance,
                                    dtau[0].max(f64::MIN_POSITIVE),
                                    eye,
                                    eye,
                                );
                            }
                        }
                    }
                    rows[((a * w + i) * total + m) * ROW_VALUES..][..ROW_VALUES]
                        .copy_from_slice(&radiance);
                }
            }
        }
        rows
    }
}

/// Every wavelength's solution (the two fields and the two ground
/// radiances, `anchor_solutions`' layout) from those at the anchors: an
/// anchor's its own, another's per unit of its solar irradiance (`solar`)
/// the anchors' per unit of theirs, blended by the anchors' weights
/// ([`WavelengthAnchors::blend`]). The polarised and the scalar field take
/// the same weights, so the ratio of the two, which the correction
/// applies, is a weighted mean of the anchors' ratios.
fn interpolate_solutions(
    anchors: &WavelengthAnchors,
    mut anchor_solutions: Vec<f64>,
    solar: &[f64],
) -> Vec<f64> {
    let solution_len = anchor_solutions.len() / anchors.anchors().len();
    if anchors.anchors().len() == solar.len() {
        // Every wavelength is an anchor (each its own blend, weight 1):
        // the same sums from zero, made in place.
        for (i, out) in anchor_solutions.chunks_exact_mut(solution_len).enumerate() {
            let &[(n, weight)] = anchors.blend(i) else {
                unreachable!("an anchor's blend is itself alone")
            };
            debug_assert_eq!(n, i);
            let e = solar[anchors.anchors()[n]];
            let scale = if e > 0.0 { weight * solar[i] / e } else { 0.0 };
            for o in out {
                *o = 0.0 + scale * *o;
            }
        }
        return anchor_solutions;
    }
    blend_solutions(anchors, &anchor_solutions, solar)
}

/// [`interpolate_solutions`] as sums over each wavelength's blend (also
/// where every wavelength is an anchor: the tests compare the two).
fn blend_solutions(
    anchors: &WavelengthAnchors,
    anchor_solutions: &[f64],
    solar: &[f64],
) -> Vec<f64> {
    let solution_len = anchor_solutions.len() / anchors.anchors().len();
    let mut solutions = vec![0.0; solar.len() * solution_len];
    for (i, out) in solutions.chunks_exact_mut(solution_len).enumerate() {
        for &(n, weight) in anchors.blend(i) {
            let e = solar[anchors.anchors()[n]];
            let scale = if e > 0.0 { weight * solar[i] / e } else { 0.0 };
            let anchor = &anchor_solutions[n * solution_len..][..solution_len];
            for (o, x) in out.iter_mut().zip(anchor) {
                *o += scale * x;
            }
        }
    }
    solutions
}

/// The column's `ratios` (I, Q, U, V) / I_scalar blended with
/// unpolarised light, (1, 0, 0, 0), by `share`, the share of the
/// column's polarisation kept.
fn blend(share: f64, ratios: [f64; COMPONENTS]) -> [f64; COMPONENTS] {
    [
        1.0 + share * (ratios[0] - 1.0),
        share * ratios[1],
        share * ratios[2],
        share * ratios[3],
    ]
}

/// A view the correction's rows are computed toward: its zenith cosine at
/// the eye and the altitude (m) where its segment ends, `f64::INFINITY`
/// for the whole ray (to the top, or to the ground with the ground's
/// light). A segment's multiply scattered light is its own air's, whose
/// polarisation is that of the sources along it, not the whole column's
/// (see the module docs, "Segments").
pub(crate) type ViewExtent = (f64, f64);

/// The end altitude of `view`, None for the whole ray.
fn views_end_altitude(view: ViewExtent) -> Option<f64> {
    view.1.is_finite().then_some(view.1)
}

/// Values per harmonic in the correction's rows: the polarised I, Q, U,
/// V, then the scalar I.
const ROW_VALUES: usize = COMPONENTS + 1;

/// The ratios (I, Q, U, V) / I_scalar at azimuth `azimuth_rad` from the
/// sun's of one view's harmonics at one wavelength (`row`, [m * ROW_VALUES
/// + n], see [`PolarisationCorrection::compute_harmonic_rows`]); (1, 0, 0,
/// 0) where the column has no multiply scattered light.
fn synthesise_ratios(row: &[f64], azimuth_rad: f64) -> [f64; COMPONENTS] {
    let mut stokes = [0.0; ROW_VALUES];
    for (m, harmonic) in row.chunks_exact(ROW_VALUES).enumerate() {
        let (sin_m, cos_m) = (m as f64 * azimuth_rad).sin_cos();
        for (n, (s, r)) in stokes.iter_mut().zip(harmonic).enumerate() {
            let even = n == COMPONENTS || is_even_component(n);
            *s += r * if even { cos_m } else { sin_m };
        }
    }
    let scalar = stokes[COMPONENTS];
    let mut ratios = [1.0, 0.0, 0.0, 0.0];
    if scalar > 0.0 {
        for (ratio, s) in ratios.iter_mut().zip(stokes) {
            *ratio = s / scalar;
        }
    }
    ratios
}

/// The correction's ratios (I, Q, U, V) / I_scalar tabulated over view
/// directions, for images: what [`PolarisationRows::ratios`]
/// gives per view, read per pixel by bilinear interpolation.
///
/// Axes: the view's zenith cosine in two halves that meet at the column's
/// horizon (mu = 0: looking up above it, down below it, the two sides of
/// the source-function integration), each with nodes mu = +-sin^2(pi s / 2)
/// for s uniform on [0, 1]: crowded toward the horizon, where the slant
/// paths change fastest, and toward the zenith and nadir, where the
/// meridian plane that Q and U are referred to turns fastest with the
/// view (with mu = s^2 instead, the zenith's first cell spans 21 degrees
/// and the ratios were 0.7 % off in I there); and the azimuth from the sun's over 0..180 degrees (I
/// and Q are even in it, U and V odd: the other half is their mirror with
/// U and V negated). Bilinear in (s, azimuth). `tests/polarisation.rs`
/// holds the table to the per-view ratios.
#[derive(Debug, Clone)]
pub(crate) struct PolarisationTable {
    half_nodes: usize,
    azimuth_nodes: usize,
    wavelengths: usize,
    /// [((half * half_nodes + z) * azimuth_nodes + k) * COMPONENTS + c) * wavelengths + i].
    values: Vec<f32>,
}

/// View cosines per task when the table's rows are computed.
const COSINES_PER_TASK: usize = 4;

/// The correction's harmonic rows at a list of view zenith cosines
/// ([`PolarisationCorrection::compute_rows`]): a view whose cosine is one
/// of them gets its ratios (I, Q, U, V)_col / I_col,scalar, its harmonics
/// summed at its own azimuth, at the cost of a sum over the harmonics (an
/// almucantar's views share one row).
#[derive(Debug, Clone)]
pub(crate) struct PolarisationRows {
    /// The views, ascending in cosine then end, without repeats.
    cosines: Vec<ViewExtent>,
    wavelengths: usize,
    harmonics: usize,
    /// [((a * wavelengths + i) * harmonics + m) * ROW_VALUES + n].
    rows: Vec<f64>,
    polarised_share: f64,
}

impl PolarisationCorrection {
    /// The harmonic rows toward every distinct view of `views` (its zenith
    /// cosine and where it ends, [`ViewExtent`]; in parallel, a few views
    /// a task; the result independent of the thread count).
    pub(crate) fn compute_rows(
        &self,
        optics: &AtmosphereOptics,
        phases: &[TruncatedPhase],
        views: &[ViewExtent],
    ) -> PolarisationRows {
        let mut cosines = views.to_vec();
        cosines.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        cosines.dedup();
        let per_cosine = self.wavelengths * self.streams.count() * ROW_VALUES;
        let mut rows = vec![0.0; cosines.len() * per_cosine];
        crate::parallel::for_each_chunk_mut(
            &mut rows,
            COSINES_PER_TASK * per_cosine,
            |task, chunk| {
                let first = task * COSINES_PER_TASK;
                let nodes = &cosines[first..first + chunk.len() / per_cosine];
                chunk.copy_from_slice(&self.compute_harmonic_rows(optics, phases, nodes, false));
            },
        );
        PolarisationRows {
            cosines,
            wavelengths: self.wavelengths,
            harmonics: self.streams.count(),
            rows,
            polarised_share: self.polarised_share,
        }
    }
}

impl PolarisationRows {
    /// The ratios (I, Q, U, V)_col / I_col,scalar toward the view of zenith
    /// cosine `view_cosine` (one of the rows' cosines) at azimuth
    /// `view_azimuth_rad` from the sun's (clockwise, the sky's convention)
    /// at every wavelength, into `out` ([component * wavelengths + i]);
    /// (1, 0, 0, 0) where the column has no multiply scattered light. None
    /// for a cosine without a row.
    pub(crate) fn ratios(
        &self,
        (view, view_azimuth_rad): (ViewExtent, f64),
        out: &mut [f64],
    ) -> Option<()> {
        let a = self
            .cosines
            .binary_search_by(|c| c.0.total_cmp(&view.0).then(c.1.total_cmp(&view.1)))
            .ok()?;
        let (w, harmonics) = (self.wavelengths, self.harmonics);
        for i in 0..w {
            let row = &self.rows[(a * w + i) * harmonics * ROW_VALUES..][..harmonics * ROW_VALUES];
            let ratios = blend(
                self.polarised_share,
                synthesise_ratios(row, view_azimuth_rad),
            );
            for (c, ratio) in ratios.into_iter().enumerate() {
                out[c * w + i] = ratio;
            }
        }
        Some(())
    }
}

impl PolarisationCorrection {
    /// The ratios tabulated on `half_nodes` zenith-cosine nodes per half
    /// and `azimuth_nodes` azimuths (see [`PolarisationTable`]); nodes in
    /// parallel, the result independent of the thread count.
    pub(crate) fn tabulate(
        &self,
        optics: &AtmosphereOptics,
        phases: &[TruncatedPhase],
        (half_nodes, azimuth_nodes): (usize, usize),
    ) -> PolarisationTable {
        assert!(half_nodes >= 2 && azimuth_nodes >= 2);
        let (w, harmonics) = (self.wavelengths, self.streams.count());
        let cosines: Vec<f64> = (0..2 * half_nodes)
            .map(|node| {
                let (half, z) = (node / half_nodes, node % half_nodes);
                let s = z as f64 / (half_nodes - 1) as f64;
                // The horizon node of each half keeps its side.
                let mu = (0.5 * PI * s).sin().powi(2).max(SMALLEST_VIEW_COSINE);
                if half == 0 { mu } else { -mu }
            })
            .collect();
        let per_node = azimuth_nodes * COMPONENTS * w;
        let mut values = vec![0.0f32; cosines.len() * per_node];
        crate::parallel::for_each_chunk_mut(
            &mut values,
            COSINES_PER_TASK * per_node,
            |task, chunk| {
                let first = task * COSINES_PER_TASK;
                let nodes: Vec<ViewExtent> = cosines[first..first + chunk.len() / per_node]
                    .iter()
                    .map(|mu| (*mu, f64::INFINITY))
                    .collect();
                let rows = self.compute_harmonic_rows(optics, phases, &nodes, true);
                for (a, node_values) in chunk.chunks_exact_mut(per_node).enumerate() {
                    for (k, out) in node_values.chunks_exact_mut(COMPONENTS * w).enumerate() {
                        let azimuth = PI * k as f64 / (azimuth_nodes - 1) as f64;
                        for i in 0..w {
                            let row = &rows[(a * w + i) * harmonics * ROW_VALUES..]
                                [..harmonics * ROW_VALUES];
                            for (c, ratio) in self
                                .blend(synthesise_ratios(row, azimuth))
                                .into_iter()
                                .enumerate()
                            {
                                out[c * w + i] = ratio as f32;
                            }
                        }
                    }
                }
            },
        );
        PolarisationTable {
            half_nodes,
            azimuth_nodes,
            wavelengths: w,
            values,
        }
    }
}

impl PolarisationTable {
    /// The ratios toward the view of zenith cosine `view_cosine` at azimuth
    /// `view_azimuth_rad` from the sun's (clockwise, any value), into `out`
    /// ([component * wavelengths + i]), bilinear in the table's axes.
    pub(crate) fn lookup_ratios(
        &self,
        (view_cosine, view_azimuth_rad): (f64, f64),
        out: &mut [f64],
    ) {
        let w = self.wavelengths;
        // The azimuth folded onto 0..pi: U and V change sign in the mirror.
        let mut azimuth = view_azimuth_rad.rem_euclid(2.0 * PI);
        let mirror = azimuth > PI;
        if mirror {
            azimuth = 2.0 * PI - azimuth;
        }
        let half = if view_cosine >= 0.0 || view_cosine.abs() < SMALLEST_VIEW_COSINE {
            0
        } else {
            1
        };
        let s = view_cosine.abs().min(1.0).sqrt().asin() / (0.5 * PI);
        let locate = |x: f64, nodes: usize| {
            let position = (x * (nodes - 1) as f64).clamp(0.0, (nodes - 1) as f64);
            let index = (position as usize).min(nodes - 2);
            (index, position - index as f64)
        };
        let (z, tz) = locate(s, self.half_nodes);
        let (k, tk) = locate(azimuth / PI, self.azimuth_nodes);
        let node = |z: usize, k: usize| {
            let start = ((half * self.half_nodes + z) * self.azimuth_nodes + k) * COMPONENTS * w;
            &self.values[start..start + COMPONENTS * w]
        };
        let (a, b, c, d) = (
            node(z, k),
            node(z, k + 1),
            node(z + 1, k),
            node(z + 1, k + 1),
        );
        let weights = [
            (1.0 - tz) * (1.0 - tk),
            (1.0 - tz) * tk,
            tz * (1.0 - tk),
            tz * tk,
        ];
        // One loop over the four corners' slices; the sum from -0.0 in
        // corner order, as `Iterator::sum` of f64 takes it.
        for (n, value) in out[..COMPONENTS * w].iter_mut().enumerate() {
            *value = -0.0
                + weights[0] * f64::from(a[n])
                + weights[1] * f64::from(b[n])
                + weights[2] * f64::from(c[n])
                + weights[3] * f64::from(d[n]);
        }
        if mirror {
            out[2 * w..4 * w].iter_mut().for_each(|v| *v = -*v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where every wavelength is an anchor, the solutions scaled in place
    /// are the blends' sums, bit for bit (zeros' signs included).
    #[test]
    fn solutions_of_every_anchor_in_place_are_the_blends() {
        let grid = crate::spectrum::WavelengthGrid::new(900.0, 940.0, 10.0).unwrap();
        let anchors = WavelengthAnchors::new(&grid, 1);
        assert_eq!(anchors.anchors().len(), grid.len());
        let solar = [1.7, 0.0, 0.93, 1.1e-3, 2.0];
        let solutions: Vec<f64> = (0..grid.len() * 3)
            .map(|n| [-0.0, 0.0, 1.0 / 3.0, -2.5e-7, 7.1][n % 5] * (n + 1) as f64)
            .collect();
        let blended = blend_solutions(&anchors, &solutions, &solar);
        let in_place = interpolate_solutions(&anchors, solutions, &solar);
        assert_eq!(blended.len(), in_place.len());
        for (a, b) in blended.iter().zip(&in_place) {
            assert_eq!(a.to_bits(), b.to_bits(), "{a} {b}");
        }
    }

    /// The k-distribution's term atmospheres (the banded gases at each
    /// term: what absorbs differs, what scatters does not) share one
    /// entry of the harmonics from the streams: computed for the first
    /// term, read by the others, and bit for bit what each term's optics
    /// give alone; truncated phases that differ get their own.
    #[test]
    fn harmonics_shared_between_term_skies_are_those_computed_alone() {
        use crate::atmosphere::gas_bands::k_distribution_terms;
        use crate::sky::k_terms::tests::earth_clear_with_gases;
        use crate::spectrum::WavelengthGrid;
        use crate::transport::multiple_scattering::phase_fourier::compute_truncated_phases;
        let atmosphere = earth_clear_with_gases();
        let grid = WavelengthGrid::new(900.0, 1000.0, 20.0).unwrap();
        let terms = k_distribution_terms(&atmosphere, &grid).unwrap();
        assert!(terms.len() > 1);
        let streams = Streams::new(4);
        let every: Vec<usize> = (0..grid.len()).collect();
        let cosines = streams.cosines();
        let bits = |h: &[Vec<PhaseMatrixHarmonics>]| -> Vec<Vec<u64>> {
            h.iter().flatten().map(PhaseMatrixHarmonics::bits).collect()
        };
        let cache = ViewHarmonicsCache::default();
        let mut shared = Vec::new();
        let mut optics_of_terms = Vec::new();
        for (term, (_, at_term)) in terms.iter().enumerate() {
            let optics = at_term.compute_optics(&grid).unwrap();
            let phases = compute_truncated_phases(&optics, streams.count());
            let alone = compute_species_harmonics_from_streams(
                &optics,
                (&phases, &every),
                &streams,
                cosines,
                None,
            );
            // The terms' absorption differs.
            if let Some(first) = optics_of_terms.first() {
                assert_ne!(&optics, first, "term {term}");
            }
            let mut computed = false;
            let got = cache.get_or_compute((&optics, &phases), (&streams, cosines, &every), || {
                computed = true;
                alone.clone()
            });
            assert_eq!(computed, term == 0, "term {term}");
            assert_eq!(bits(&got), bits(&alone), "term {term}");
            shared.push(got);
            optics_of_terms.push(optics);
        }
        assert!(shared.iter().all(|h| Arc::ptr_eq(h, &shared[0])));
        // Other truncated phases (more degrees): their own harmonics.
        let optics = &optics_of_terms[1];
        let phases = compute_truncated_phases(optics, 2 * streams.count());
        let mut computed = false;
        let other = cache.get_or_compute((optics, &phases), (&streams, cosines, &every), || {
            computed = true;
            compute_species_harmonics_from_streams(
                optics,
                (&phases, &every),
                &streams,
                cosines,
                None,
            )
        });
        assert!(computed);
        assert_ne!(bits(&other), bits(&shared[0]));
    }
}
