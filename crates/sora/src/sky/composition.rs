//! The composition of a view's light: single scattering, the light
//! scattered more than once and the lit ground, computed term by term and
//! added in one place ([`SkyRadiance`], [`Stokes`]), for views
//! ([`Sky::radiances`]) and for the pixels of images.

use super::options::{Method, Polarisation, check_view_count};
use super::setup::{ImageTables, Sky};

use crate::atmosphere::phase_matrix::PhaseMatrix;
use crate::error::Result;
use crate::geometry::{Vector3, ViewDirection};
use crate::spectrum::SampledSpectrum;
use crate::transport::multiple_scattering::{
    MultipleScatteringField, MultipleScatteringScratch, MultipleScatteringTable, PolarisationRows,
};
use crate::transport::path_tracing::worst_relative_error;
use crate::transport::stokes::{meridian_reference, rotation_cos_sin_2eta, scattering_plane};
use crate::transport::{PathTracer, SingleScatteringScratch, SunColumns};

/// What a pixel's read of a sky's image tables takes from its direction
/// alone: the direction (unit, east-north-up), its cell in the sky-view
/// table, and for a polarised sky the rotation (cos 2 eta, sin 2 eta) from
/// the scattering plane to its meridian frame and its azimuth from the
/// sun's, rad (`Sky::pixel_geometry`). The k-distribution's term skies
/// share one per pixel (`Sky::has_pixel_geometry_of`).
#[derive(Debug, Clone, Copy)]
pub(super) struct PixelGeometry {
    pub(super) view: Vector3,
    cell: crate::transport::SkyViewCell,
    stokes: Option<((f64, f64), f64)>,
}

/// The radiance of one view, W m^-2 sr^-1 nm^-1 on the sky's grid.
#[derive(Debug, Clone, PartialEq)]
pub struct SkyRadiance {
    /// The radiance, one value per wavelength.
    pub radiance_w_m2_sr_nm: SampledSpectrum,
    /// The standard error of each value (path tracing only).
    pub standard_error_w_m2_sr_nm: Option<SampledSpectrum>,
    /// Q, U and V with [`Polarisation::Vector`] (then
    /// `radiance_w_m2_sr_nm` is the polarised intensity I).
    pub stokes: Option<Stokes>,
}

/// The polarised part of a view's light: Stokes Q, U and V,
/// W m^-2 sr^-1 nm^-1, one value per wavelength, with standard errors
/// when path tracing.
///
/// The reference plane is the view's meridian plane (through the zenith
/// and the view direction): Q > 0 when the electric field is mostly in it
/// (vertical), Q < 0 when mostly horizontal; the angle of polarisation
/// turns from "up" toward the observer's left (counter-clockwise on the sky
/// as the observer sees it), and U > 0 at +45 degrees.
#[derive(Debug, Clone, PartialEq)]
pub struct Stokes {
    /// Q, W m^-2 sr^-1 nm^-1.
    pub q_w_m2_sr_nm: SampledSpectrum,
    /// U, W m^-2 sr^-1 nm^-1.
    pub u_w_m2_sr_nm: SampledSpectrum,
    /// V (circular polarisation), W m^-2 sr^-1 nm^-1.
    pub v_w_m2_sr_nm: SampledSpectrum,
    /// The standard errors of Q, U and V (path tracing).
    pub standard_errors_w_m2_sr_nm: Option<[SampledSpectrum; 3]>,
}

impl Stokes {
    /// The degree of linear polarisation sqrt(Q^2 + U^2) / I per
    /// wavelength, given I (0 where I is 0).
    pub fn degree_of_linear_polarisation(&self, intensity: &SampledSpectrum) -> Vec<f64> {
        (0..intensity.len())
            .map(|i| {
                let (q, u) = (self.q_w_m2_sr_nm[i], self.u_w_m2_sr_nm[i]);
                let total = intensity[i];
                if total > 0.0 { q.hypot(u) / total } else { 0.0 }
            })
            .collect()
    }

    /// The angle of polarisation 0.5 atan2(U, Q), degrees in (-90, 90],
    /// per wavelength: None where the light is wholly unpolarised
    /// (Q = U = 0), whose angle does not exist.
    pub fn angle_of_polarisation_deg(&self) -> Vec<Option<f64>> {
        self.q_w_m2_sr_nm
            .values()
            .iter()
            .zip(self.u_w_m2_sr_nm.values())
            .map(|(q, u)| {
                (*q != 0.0 || *u != 0.0).then(|| {
                    let angle = 0.5 * u.atan2(*q).to_degrees();
                    if angle <= -90.0 { angle + 180.0 } else { angle }
                })
            })
            .collect()
    }
}

impl SkyRadiance {
    /// sum_j w_j times each part, field by field and sample by sample (the
    /// k-distribution's sum over its terms, `atmosphere::gas_bands`, w_j a
    /// weight per sample; the parts of one view on one grid). Standard
    /// errors add as sum_j w_j se_j, the bound for errors that may be
    /// correlated (the terms are traced with one seed).
    pub fn weighted_sum(parts: &[(SampledSpectrum, SkyRadiance)]) -> SkyRadiance {
        let stokes = parts
            .iter()
            .map(|(w, p)| p.stokes.as_ref().map(|s| (w, s)))
            .collect::<Option<Vec<_>>>()
            .map(|stokes| {
                let sum = |field: fn(&Stokes) -> &SampledSpectrum| {
                    SampledSpectrum::weighted_sum(stokes.iter().map(|(w, s)| (*w, field(s))))
                };
                Stokes {
                    q_w_m2_sr_nm: sum(|s| &s.q_w_m2_sr_nm),
                    u_w_m2_sr_nm: sum(|s| &s.u_w_m2_sr_nm),
                    v_w_m2_sr_nm: sum(|s| &s.v_w_m2_sr_nm),
                    standard_errors_w_m2_sr_nm: stokes
                        .iter()
                        .map(|(w, s)| s.standard_errors_w_m2_sr_nm.as_ref().map(|e| (*w, e)))
                        .collect::<Option<Vec<_>>>()
                        .map(|errors| {
                            [0, 1, 2].map(|k| {
                                SampledSpectrum::weighted_sum(
                                    errors.iter().map(|(w, e)| (*w, &e[k])),
                                )
                            })
                        }),
                }
            });
        SkyRadiance {
            radiance_w_m2_sr_nm: SampledSpectrum::weighted_sum(
                parts.iter().map(|(w, p)| (w, &p.radiance_w_m2_sr_nm)),
            ),
            standard_error_w_m2_sr_nm: parts
                .iter()
                .map(|(w, p)| p.standard_error_w_m2_sr_nm.as_ref().map(|e| (w, e)))
                .collect::<Option<Vec<_>>>()
                .map(SampledSpectrum::weighted_sum),
            stokes,
        }
    }

    /// The largest standard error relative to its value over the
    /// wavelengths (0 without standard errors; see
    /// `crate::transport::SpectralEstimate::worst_relative_standard_error`).
    pub fn worst_relative_standard_error(&self) -> f64 {
        self.standard_error_w_m2_sr_nm
            .as_ref()
            .map_or(0.0, |errors| {
                worst_relative_error(self.radiance_w_m2_sr_nm.values(), errors.values())
            })
    }
}

/// From this many views [`Sky::radiances`] (fast method) reads them from
/// tables as an image's pixels are (`Sky::view_tables`) instead of the
/// exact per-view path. Measured (earth-clear, sun 30, 21 wavelengths,
/// CPU time): the image tables cost about as much as 80 exact polarised
/// views of distinct elevations (0.85 s) and 300 scalar ones (0.43 s);
/// 16 384 polarised views through the views' tables cost 1.27 times a
/// 128 x 128 polarised fisheye (`docs/polarisation.md`).
pub const TABLE_VIEW_COUNT: usize = 256;

/// Views a task when many views are read from tables as pixels are.
const PIXEL_VIEWS_PER_TASK: usize = 64;

/// Views a task on the exact per-view path.
const VIEWS_PER_TASK: usize = 4;

/// The zenith cosine of a view (the polarisation correction's axis).
fn view_cosine(view: &ViewDirection) -> f64 {
    view.elevation_deg().to_radians().sin()
}

/// Per-thread buffers of one view's computation (no allocation per view).
pub(super) struct ViewWork {
    pub(super) single: SingleScatteringScratch,
    pub(super) multiple: Option<MultipleScatteringScratch>,
    /// species * wavelengths integrals (m) of the sky-view table and of the
    /// forward-peak term.
    pub(super) integrals: Vec<f64>,
    pub(super) forward: Vec<f64>,
    pub(super) phase: Vec<f64>,
    /// The fast method's terms of the view or pixel.
    pub(super) terms: ViewTerms,
    /// Phase matrices per wavelength (polarised single scattering).
    matrices: Vec<PhaseMatrix>,
    /// The multiply scattered light's I, Q, U, V (polarised skies).
    multiple_stokes: Vec<f64>,
    /// The light the polarisation correction applies to
    /// ([`ViewTerms::polarisation_corrected`]).
    corrected: Vec<f64>,
    /// The whole ray's terms of the last segment's view
    /// ([`Sky::compute_segment_terms`]), kept for the next segment along
    /// the same view.
    pub(super) segment_sky: Option<SegmentSky>,
}

/// The whole ray's terms a segment's light is taken from (see
/// [`ViewWork::segment_sky`]): its view's bits, the scaled field's light,
/// the ground's sunlit and skylit light, and the scaled forward-peak
/// integrals when there is a field.
pub(super) struct SegmentSky {
    pub(super) view: [u64; 3],
    pub(super) field: Vec<f64>,
    pub(super) ground: (Vec<f64>, Vec<f64>),
    pub(super) integrals: Option<Vec<f64>>,
}

/// The fast method's terms of one view or pixel, each computed on its own
/// and added once ([`ViewTerms::add_into`]), the same way for views
/// ([`Sky::compute_view_radiance`]) and pixels
/// ([`Sky::compute_pixel_radiance`]); W m^-2 sr^-1 nm^-1 per wavelength.
///
/// The air's terms are the light scattered into the view between the eye
/// and the ray's end (or a point at a distance, [`Sky::aerial_perspective`]);
/// the ground's are the light the ground reflects where the ray ends on
/// it, times the transmittance to it.
pub(super) struct ViewTerms {
    /// Single scattering by the air (`transport/single_scattering.rs`; the
    /// reference method's march, with its sunlit ground).
    pub(super) single: Vec<f64>,
    /// The scaled field's light scattered by the air: orders >= 2 (zero
    /// for a sky without multiple scattering).
    pub(super) field: Vec<f64>,
    /// The forward-peak term of delta-M (`forward_peak.rs`), polarised as
    /// single scattering.
    pub(super) forward_peak: Vec<f64>,
    /// The directly sunlit ground (A / pi) E mu_s T_sun T_view.
    pub(super) ground_sunlit: Vec<f64>,
    /// The skylight the ground reflects (from the scaled field, with the
    /// sunlight delta-M moved into its beam), through the scaled view
    /// transmittance. The polarisation correction's ratios apply to it and
    /// to `field` (the correction's own radiance holds both).
    pub(super) ground_skylit: Vec<f64>,
}

impl ViewTerms {
    pub(super) fn new(wavelengths: usize) -> ViewTerms {
        ViewTerms {
            single: vec![0.0; wavelengths],
            field: vec![0.0; wavelengths],
            forward_peak: vec![0.0; wavelengths],
            ground_sunlit: vec![0.0; wavelengths],
            ground_skylit: vec![0.0; wavelengths],
        }
    }

    /// The air's light and the ground's light:
    /// (single + sunlit ground) + ((field + skylit ground) + forward peak).
    pub(super) fn add_into(&self, radiance: &mut [f64]) {
        for (i, r) in radiance.iter_mut().enumerate() {
            *r = (self.single[i] + self.ground_sunlit[i])
                + ((self.field[i] + self.ground_skylit[i]) + self.forward_peak[i]);
        }
    }

    /// The light the polarisation correction's ratios apply to: the
    /// field's and the skylit ground's, into `out`.
    fn polarisation_corrected(&self, out: &mut [f64]) {
        for ((o, f), g) in out.iter_mut().zip(&self.field).zip(&self.ground_skylit) {
            *o = f + g;
        }
    }
}

/// Which tables views are read from: an image's
/// ([`Sky::radiance_from_image_tables`]) or those of many views
/// ([`Sky::radiances`] from [`TABLE_VIEW_COUNT`] views; `Sky::view_tables`).
#[derive(Debug, Clone, Copy)]
enum Tables {
    Image,
    Views,
}

/// Where a view's single-scattering integrals are: in
/// [`ViewWork::single`] (a view, [`Sky::compute_view_radiance`]) or in
/// [`ViewWork::integrals`] (a pixel, from the sky-view table).
#[derive(Debug, Clone, Copy)]
enum SingleIntegrals {
    View,
    Pixel,
}

/// Adds the Stokes vector of the light the scaled field scatters two or
/// more times, `scaled` (its scalar radiance, W m^-2 sr^-1 nm^-1), from
/// the polarisation correction's `ratios` ((I, Q, U, V) / I_scalar,
/// [component * wavelengths + i]): `radiance` gets the polarised
/// intensity in place of the scalar one, `stokes` ([(component - 1) *
/// wavelengths + i]) its Q, U and V. The forward-peak term is not the
/// scaled field's and keeps its intensity (its Q and U are single
/// scattering's, [`Sky::compute_single_scattering_stokes`]).
fn add_corrected_multiple_stokes(
    ratios: &[f64],
    scaled: &[f64],
    radiance: &mut [f64],
    stokes: &mut [f64],
) {
    let w = radiance.len();
    for (i, multiple) in scaled.iter().enumerate() {
        radiance[i] += (ratios[i] - 1.0) * multiple;
        for c in 1..4 {
            stokes[(c - 1) * w + i] += ratios[c * w + i] * multiple;
        }
    }
}

/// A view's [`SkyRadiance`] from the path tracer's estimates.
pub(super) fn sky_radiance_from_traced(
    traced: crate::transport::path_tracing::PathTracedSpectrum,
) -> SkyRadiance {
    match traced.stokes {
        None => SkyRadiance {
            radiance_w_m2_sr_nm: traced.total.mean,
            standard_error_w_m2_sr_nm: Some(traced.total.standard_error),
            stokes: None,
        },
        Some([i, q, u, v]) => SkyRadiance {
            radiance_w_m2_sr_nm: i.mean,
            standard_error_w_m2_sr_nm: Some(i.standard_error),
            stokes: Some(Stokes {
                q_w_m2_sr_nm: q.mean,
                u_w_m2_sr_nm: u.mean,
                v_w_m2_sr_nm: v.mean,
                standard_errors_w_m2_sr_nm: Some([
                    q.standard_error,
                    u.standard_error,
                    v.standard_error,
                ]),
            }),
        },
    }
}

/// A view's [`SkyRadiance`] from its values: the radiance (the polarised
/// intensity I of a polarised sky) at `wavelengths` wavelengths, then, if
/// there are four times as many values, its Q, U and V.
fn sky_radiance_from_values(values: &[f64], wavelengths: usize) -> SkyRadiance {
    let spectrum =
        |k: usize| SampledSpectrum::from_values(values[k * wavelengths..][..wavelengths].to_vec());
    SkyRadiance {
        radiance_w_m2_sr_nm: spectrum(0),
        standard_error_w_m2_sr_nm: None,
        stokes: (values.len() == 4 * wavelengths).then(|| Stokes {
            q_w_m2_sr_nm: spectrum(1),
            u_w_m2_sr_nm: spectrum(2),
            v_w_m2_sr_nm: spectrum(3),
            standard_errors_w_m2_sr_nm: None,
        }),
    }
}

impl Sky {
    pub(super) fn view_work(&self) -> ViewWork {
        let wavelengths = self.wavelengths().len();
        let species = self.optics().species.len();
        ViewWork {
            single: self.scene.scratch(),
            multiple: self.field().map(MultipleScatteringField::scratch),
            integrals: vec![0.0; species * wavelengths],
            forward: vec![
                0.0;
                self.field()
                    .map_or(species, MultipleScatteringField::forward_integral_rows)
                    * wavelengths
            ],
            phase: vec![0.0; wavelengths],
            terms: ViewTerms::new(wavelengths),
            matrices: vec![PhaseMatrix::default(); wavelengths],
            multiple_stokes: vec![0.0; 4 * wavelengths],
            corrected: vec![0.0; wavelengths],
            segment_sky: None,
        }
    }

    /// The spectral radiance arriving at the eye from `view`.
    pub fn radiance(&self, view: ViewDirection) -> Result<SkyRadiance> {
        let mut all = self.radiances(&[view])?;
        Ok(all.remove(0))
    }

    /// The spectral radiance of every view in `views`, in order, reusing
    /// every table (see the module docs). With [`Method::Fast`] and at
    /// least [`TABLE_VIEW_COUNT`] views the views are read from tables as
    /// an image's pixels are, with a source table at half the image's steps
    /// (within 0.1 % of the exact path by day: 0.095 % at most over 256
    /// views of earth-clear at suns 30 and 5, the worst near the horizon
    /// close to the sun's azimuth; 1 % in twilight);
    /// [`Sky::radiances_exact`] keeps the exact per-view path for any
    /// number of views.
    pub fn radiances(&self, views: &[ViewDirection]) -> Result<Vec<SkyRadiance>> {
        self.radiances_with_progress(views, &|_, _| {})
    }

    /// The spectral radiance of every view in `views` by the exact
    /// per-view path whatever their number (what [`Sky::radiances`] gives
    /// below [`TABLE_VIEW_COUNT`] views, and [`Sky::radiance`] always).
    pub fn radiances_exact(&self, views: &[ViewDirection]) -> Result<Vec<SkyRadiance>> {
        self.compute_radiances(views, &|_, _| {}, false)
    }

    /// As [`Sky::radiances`], calling `progress(done, total)` as work
    /// completes (from worker threads): paths when path tracing, views
    /// otherwise.
    pub fn radiances_with_progress(
        &self,
        views: &[ViewDirection],
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<Vec<SkyRadiance>> {
        self.compute_radiances(views, progress, true)
    }

    /// [`Sky::radiances_with_progress`]; `tables_allowed`: many views of the
    /// fast method over a field of every direction are read from the image
    /// tables.
    fn compute_radiances(
        &self,
        views: &[ViewDirection],
        progress: &(dyn Fn(u64, u64) + Sync),
        tables_allowed: bool,
    ) -> Result<Vec<SkyRadiance>> {
        if !self.k_terms.is_empty() {
            // Views read from tables take every term whole (a term's tables
            // cost far more than its samples' higher orders); exact views
            // the runs that leave out negligible higher orders.
            let from_tables = tables_allowed
                && self.method == Method::Fast
                && self.lowest_view_elevation_rad.is_none()
                && views.len() >= TABLE_VIEW_COUNT;
            if from_tables {
                // The terms' tables together (`Sky::prepare_term_tables`).
                check_view_count("the views", views.len() as f64, self.wavelengths().len())?;
                self.prepare_term_tables(true)?;
            }
            return self.sum_term_radiances(!from_tables, |k, terms, term| {
                term.compute_radiances(
                    views,
                    &|done, total| {
                        let (done, total) = self.term_progress((k, terms), done, total);
                        progress(done, total)
                    },
                    tables_allowed,
                )
            });
        }
        let wavelengths = self.wavelengths().len();
        check_view_count("the views", views.len() as f64, wavelengths)?;
        if let Method::PathTracing { samples, seed } = self.method {
            let tracer = match self.polarisation {
                Polarisation::Scalar => PathTracer::new(&self.scene),
                Polarisation::Vector => PathTracer::new_polarised(&self.scene)?,
            };
            let total = samples * views.len() as u64;
            let mut out = Vec::with_capacity(views.len());
            for (k, view) in views.iter().enumerate() {
                let before = k as u64 * samples;
                let traced = tracer.compute_stokes_with_progress(
                    view.to_vector(),
                    meridian_reference(view.elevation_deg(), view.azimuth_deg()),
                    samples,
                    seed,
                    &|done| progress(before + done, total),
                )?;
                out.push(sky_radiance_from_traced(traced));
            }
            return Ok(out);
        }
        // Views in groups, each group with its own buffers; each view's
        // values are I, then Q, U and V when polarised (single scattering
        // of unpolarised sunlight has no V: see
        // `SingleScatteringScene::polarised_radiance_from_integrals`).
        for view in views {
            self.check_within_restricted_field(Some(view.elevation_deg()))?;
        }
        self.prepare_field()?;
        if tables_allowed
            && self.method == Method::Fast
            && self.lowest_view_elevation_rad.is_none()
            && views.len() >= TABLE_VIEW_COUNT
        {
            return self.radiances_from_tables(views, progress, Tables::Views);
        }
        let polarised = self.polarisation == Polarisation::Vector;
        let rows = self.polarisation_rows(views.iter().map(|view| (view, f64::INFINITY)));
        Ok(self.compute_views_in_parallel(
            views,
            VIEWS_PER_TASK,
            progress,
            |view, work, radiance, stokes| {
                self.compute_view_radiance(view.to_vector(), None, work, radiance);
                if polarised {
                    let view = (view, f64::INFINITY);
                    self.compute_view_stokes(view, rows.as_ref(), work, radiance, stokes);
                }
            },
        ))
    }

    /// The polarisation correction's rows toward every distinct zenith
    /// cosine and end altitude (m; infinity for the whole ray, see
    /// `polarisation_correction.rs`) of `views`, computed once (an
    /// almucantar's views share one); None for scalar light or a sky
    /// without a field.
    pub(super) fn polarisation_rows<'a>(
        &self,
        views: impl Iterator<Item = (&'a ViewDirection, f64)>,
    ) -> Option<PolarisationRows> {
        if self.polarisation != Polarisation::Vector {
            return None;
        }
        let cosines: Vec<(f64, f64)> = views.map(|(view, end)| (view_cosine(view), end)).collect();
        self.field()?.compute_polarisation_rows(&cosines)
    }

    /// Every view of `views` (a view, or a view and a distance: anything a
    /// view's light is computed from) by `compute(view, work, radiance, stokes)`
    /// (`stokes`: Q, U and V of a polarised sky, empty otherwise), in
    /// parallel, `views_per_task` a task with one [`ViewWork`] each,
    /// calling `progress(done, total)` as views complete.
    pub(super) fn compute_views_in_parallel<V: Copy + Sync>(
        &self,
        views: &[V],
        views_per_task: usize,
        progress: &(dyn Fn(u64, u64) + Sync),
        compute: impl Fn(V, &mut ViewWork, &mut [f64], &mut [f64]) + Sync,
    ) -> Vec<SkyRadiance> {
        let wavelengths = self.wavelengths().len();
        let polarised = self.polarisation == Polarisation::Vector;
        let per_view = wavelengths * if polarised { 4 } else { 1 };
        let mut values = vec![0.0; views.len() * per_view];
        let total = views.len() as u64;
        let done = std::sync::atomic::AtomicU64::new(0);
        crate::parallel::for_each_chunk_mut(
            &mut values,
            views_per_task * per_view,
            |task, chunk| {
                let mut work = self.view_work();
                for (k, out) in chunk.chunks_mut(per_view).enumerate() {
                    let (radiance, stokes) = out.split_at_mut(wavelengths);
                    compute(
                        views[task * views_per_task + k],
                        &mut work,
                        radiance,
                        stokes,
                    );
                    let finished = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                    progress(finished, total);
                }
            },
        );
        // The spectra built in parallel too (thousands of small
        // allocations per image of the engine tables' layers).
        crate::parallel::map_chunks(&values, per_view, |values| {
            sky_radiance_from_values(values, wavelengths)
        })
    }

    /// A polarised view's Stokes Q, U and V into `stokes` and its polarised
    /// intensity in place of the scalar one in `radiance`, from the terms
    /// and integrals [`Sky::compute_view_terms`] left in `work` (the view,
    /// and the altitude its segment ends at, m, infinity for the whole
    /// ray).
    pub(super) fn compute_view_stokes(
        &self,
        (view, end_altitude_m): (ViewDirection, f64),
        rows: Option<&PolarisationRows>,
        work: &mut ViewWork,
        radiance: &mut [f64],
        stokes: &mut [f64],
    ) {
        stokes.fill(0.0);
        let meridian = meridian_reference(view.elevation_deg(), view.azimuth_deg());
        self.compute_single_scattering_stokes(
            (view.to_vector(), meridian),
            SingleIntegrals::View,
            work,
            stokes,
        );
        if let Some(rows) = rows {
            self.add_multiple_scattering_stokes(
                (view, end_altitude_m),
                rows,
                work,
                radiance,
                stokes,
            );
        }
    }

    /// Q and U (W m^-2 sr^-1 nm^-1, referred to the view's meridian plane)
    /// of the light scattered once through the view's scattering angle,
    /// into `stokes` (Q then U), from the integrals `work` holds (`single`:
    /// single scattering's, [`Sky::compute_view_radiance`]'s or the
    /// sky-view table's; `work.forward`: the forward-peak term's): the
    /// scattering-plane Q turned into the meridian frame
    /// (`transport/stokes.rs`). The forward-peak term's first line is
    /// light scattered once through that angle by a smooth phase function
    /// and otherwise only near-forward, so it is polarised as single
    /// scattering is (`forward_peak.rs`), not as the scaled field's
    /// multiply scattered light.
    fn compute_single_scattering_stokes(
        &self,
        (w, meridian): (Vector3, Vector3),
        single: SingleIntegrals,
        work: &mut ViewWork,
        stokes: &mut [f64],
    ) {
        let rotation = self.scattering_plane_rotation(w, meridian);
        self.compute_single_scattering_stokes_rotated((w, rotation), single, work, stokes);
    }

    /// (cos 2 eta, sin 2 eta) of the rotation from the scattering plane of
    /// sunlight scattered into the view `w` to the view's meridian frame
    /// (`meridian`, its reference).
    fn scattering_plane_rotation(&self, w: Vector3, meridian: Vector3) -> (f64, f64) {
        let (k_in, k_out) = (-self.sun_direction(), -w);
        let normal = scattering_plane(k_in, k_out, meridian);
        rotation_cos_sin_2eta(k_out, normal.cross(k_out), meridian)
    }

    /// [`Sky::compute_single_scattering_stokes`] with the rotation to the
    /// meridian frame, (c, s), found already.
    fn compute_single_scattering_stokes_rotated(
        &self,
        (w, (c, s)): (Vector3, (f64, f64)),
        single: SingleIntegrals,
        work: &mut ViewWork,
        stokes: &mut [f64],
    ) {
        let cos_theta = w.dot(self.sun_direction());
        let (q, u) = stokes.split_at_mut(self.wavelengths().len());
        let integrals = match single {
            SingleIntegrals::View => work.single.inscattering_integrals(),
            SingleIntegrals::Pixel => &work.integrals,
        };
        self.scene
            .polarised_radiance_from_integrals(cos_theta, integrals, &mut work.matrices, q);
        if let Some(field) = self.field() {
            // The forward-peak term's Q into u (work space until the end).
            field.compute_forward_peak_polarised_radiance(
                cos_theta,
                &work.forward,
                (&mut work.phase, &mut work.matrices),
                u,
            );
            for (q, f) in q.iter_mut().zip(u.iter()) {
                *q += f;
            }
        }
        for (q, u) in q.iter_mut().zip(u) {
            *u = -s * *q;
            *q *= c;
        }
    }

    /// Turns the multiply scattered radiance [`Sky::compute_view_radiance`]
    /// left in `work` into its Stokes vector: `radiance` gets the polarised
    /// intensity in place of the scalar one, `stokes` (Q, U, V) the
    /// multiply scattered Q, U and V added (see
    /// [`add_corrected_multiple_stokes`]).
    fn add_multiple_scattering_stokes(
        &self,
        (view, end_altitude_m): (ViewDirection, f64),
        rows: &PolarisationRows,
        work: &mut ViewWork,
        radiance: &mut [f64],
        stokes: &mut [f64],
    ) {
        let azimuth_rad = (view.azimuth_deg() - self.sun_position_deg.1).to_radians();
        rows.ratios(
            ((view_cosine(&view), end_altitude_m), azimuth_rad),
            &mut work.multiple_stokes,
        )
        .expect("a row for every view's cosine");
        work.terms.polarisation_corrected(&mut work.corrected);
        add_corrected_multiple_stokes(&work.multiple_stokes, &work.corrected, radiance, stokes);
    }

    /// The radiance a fast-method image shows toward `view` (read from its
    /// tables, without the sun's disc): within 0.1 % of [`Sky::radiance`]
    /// with [`Method::Fast`] by day away from the sun (0.22 % near the
    /// horizon 10 degrees in azimuth from it, earth-clear; [`Sky::radiances`]
    /// of many views reads finer tables) and within 1 % in twilight (measured
    /// 0.7 %, sun 0 to -16 degrees, `tests/twilight.rs`), which is what the
    /// tests hold it to: values that match a rendered image pixel for pixel.
    pub fn radiance_from_image_tables(&self, view: ViewDirection) -> Result<SkyRadiance> {
        let mut all = self.radiances_from_image_tables(&[view], &|_, _| {})?;
        Ok(all.remove(0))
    }

    /// [`Sky::radiance_from_image_tables`] for every view in `views`, in
    /// parallel, calling `progress(done, total)` as views complete.
    pub(crate) fn radiances_from_image_tables(
        &self,
        views: &[ViewDirection],
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<Vec<SkyRadiance>> {
        self.radiances_from_tables(views, progress, Tables::Image)
    }

    /// Every view in `views` read from `tables` as an image's pixels are,
    /// in parallel, calling `progress(done, total)` as views complete.
    fn radiances_from_tables(
        &self,
        views: &[ViewDirection],
        progress: &(dyn Fn(u64, u64) + Sync),
        tables: Tables,
    ) -> Result<Vec<SkyRadiance>> {
        if !self.k_terms.is_empty() {
            self.prepare_term_tables(matches!(tables, Tables::Views))?;
            return self.sum_term_radiances(false, |k, terms, term| {
                term.radiances_from_tables(
                    views,
                    &|done, total| {
                        let (done, total) = self.term_progress((k, terms), done, total);
                        progress(done, total)
                    },
                    tables,
                )
            });
        }
        self.prepare_field_for_images()?;
        let tables = match tables {
            Tables::Image => self.image_tables(),
            Tables::Views => self.view_tables(),
        };
        let polarised = self.polarisation == Polarisation::Vector;
        Ok(self.compute_views_in_parallel(
            views,
            PIXEL_VIEWS_PER_TASK,
            progress,
            |view, work, radiance, stokes| {
                let pixel = self.pixel_geometry(view.to_vector(), tables);
                self.compute_pixel_radiance(&pixel, tables, work, radiance);
                if polarised {
                    self.add_pixel_stokes(&pixel, tables, work, radiance, stokes);
                }
            },
        ))
    }

    /// One view's radiance without image tables (fast or reference method),
    /// into `radiance`, W m^-2 sr^-1 nm^-1: single scattering and the sunlit
    /// ground, plus the higher orders, synthesised exactly from the field or
    /// (`source_table`, for reference images) read from its source table.
    pub(super) fn compute_view_radiance(
        &self,
        view: Vector3,
        source_table: Option<&MultipleScatteringTable>,
        work: &mut ViewWork,
        radiance: &mut [f64],
    ) {
        self.compute_view_terms((view, f64::INFINITY), source_table, work);
        work.terms.add_into(radiance);
    }

    /// The terms ([`ViewTerms`]) of the segment of the view ray `view` from
    /// the eye to `distance_m` m (`f64::INFINITY`: the whole ray) into
    /// `work.terms`; the single-scattering scratch holds the segment's
    /// integrals, columns and transmittance afterwards.
    pub(super) fn compute_view_terms(
        &self,
        (view, distance_m): (Vector3, f64),
        source_table: Option<&MultipleScatteringTable>,
        work: &mut ViewWork,
    ) {
        let terms = &mut work.terms;
        terms.ground_sunlit.fill(0.0);
        match self.method {
            Method::Reference {
                view_steps,
                sun_steps,
            } => {
                let spectrum = self
                    .scene
                    .compute_radiance_reference(view, view_steps, sun_steps);
                terms.single.copy_from_slice(spectrum.values());
            }
            _ => {
                self.scene.compute_segment_integrals(
                    (view, distance_m),
                    SunColumns::Exact,
                    &mut work.single,
                );
                self.scene.radiance_from_integrals(
                    view.dot(self.sun_direction()),
                    work.single.inscattering_integrals(),
                    &mut work.phase,
                    &mut terms.single,
                );
                terms
                    .ground_sunlit
                    .copy_from_slice(work.single.ground_radiance());
            }
        }
        terms.field.fill(0.0);
        terms.forward_peak.fill(0.0);
        terms.ground_skylit.fill(0.0);
        if let (Some(field), Some(scratch)) = (self.field(), work.multiple.as_mut()) {
            let (segment, out) = (
                (view, distance_m),
                (&mut terms.field[..], &mut terms.ground_skylit[..]),
            );
            match source_table {
                Some(table) => {
                    table.compute_radiance_parts(segment, SunColumns::Exact, scratch, out)
                }
                None => field.compute_field_radiance(segment, SunColumns::Exact, scratch, out),
            }
            // The forward-peak term from its integrals along the view
            // (kept for its Stokes vector).
            work.forward.copy_from_slice(scratch.forward_integrals());
            field.compute_forward_peak_radiance(
                view.dot(self.sun_direction()),
                &work.forward,
                &mut work.phase,
                &mut terms.forward_peak,
            );
        }
    }

    /// What reading `tables` toward `view` takes from the direction alone
    /// ([`PixelGeometry`]).
    pub(super) fn pixel_geometry(&self, view: Vector3, tables: &ImageTables) -> PixelGeometry {
        let stokes = (self.polarisation == Polarisation::Vector).then(|| {
            let (elevation_deg, azimuth_deg) =
                crate::geometry::elevation_azimuth_from_direction(view);
            let meridian = meridian_reference(elevation_deg, azimuth_deg);
            (
                self.scattering_plane_rotation(view, meridian),
                (azimuth_deg - self.sun_position_deg.1).to_radians(),
            )
        });
        PixelGeometry {
            view,
            cell: tables.sky_view.cell(view),
            stokes,
        }
    }

    /// Whether `other` (with its `other_tables`) reads the same
    /// [`PixelGeometry`] from a direction as this sky with `tables`: the
    /// same sun, polarisation and sky-view table axes (the
    /// k-distribution's term skies).
    pub(super) fn has_pixel_geometry_of(
        &self,
        tables: &ImageTables,
        (other, other_tables): (&Sky, &ImageTables),
    ) -> bool {
        let bits = |v: Vector3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
        self.polarisation == other.polarisation
            && bits(self.sun_direction()) == bits(other.sun_direction())
            && self.sun_position_deg.1.to_bits() == other.sun_position_deg.1.to_bits()
            && tables.sky_view.has_cells_of(&other_tables.sky_view)
    }

    /// One pixel's radiance from the image tables (fast method), into
    /// `radiance`: the sky-view table's integrals, ground and multiply
    /// scattered light with the exact phase functions (the sun's disc is
    /// added per image, see [`sun_disc`]).
    pub(super) fn compute_pixel_radiance(
        &self,
        pixel: &PixelGeometry,
        tables: &ImageTables,
        work: &mut ViewWork,
        radiance: &mut [f64],
    ) {
        let cos_theta = pixel.view.dot(self.sun_direction());
        let terms = &mut work.terms;
        tables.sky_view.lookup_with_multiple_scattering(
            pixel.cell,
            (&mut work.integrals, &mut terms.ground_sunlit),
            (
                &mut terms.field,
                &mut terms.ground_skylit,
                &mut work.forward,
            ),
        );
        self.scene.radiance_from_integrals(
            cos_theta,
            &work.integrals,
            &mut work.phase,
            &mut terms.single,
        );
        match self.field() {
            Some(field) => field.compute_forward_peak_radiance(
                cos_theta,
                &work.forward,
                &mut work.phase,
                &mut terms.forward_peak,
            ),
            None => terms.forward_peak.fill(0.0),
        }
        terms.add_into(radiance);
    }

    /// A polarised sky's Stokes Q, U and V of one pixel into `stokes`
    /// ([(component - 1) * wavelengths + i], W m^-2 sr^-1 nm^-1, referred
    /// to the pixel's meridian plane) and its polarised intensity in place
    /// of the scalar one in `radiance`, from what
    /// [`Sky::compute_pixel_radiance`] left in `work`: single scattering's
    /// from the sky-view table's integrals (exact, as for views), the
    /// multiply scattered light's from the polarisation table's ratios
    /// (the per-view correction's, tabulated).
    pub(super) fn add_pixel_stokes(
        &self,
        pixel: &PixelGeometry,
        tables: &ImageTables,
        work: &mut ViewWork,
        radiance: &mut [f64],
        stokes: &mut [f64],
    ) {
        let (rotation, azimuth_rad) = pixel.stokes.expect("a polarised sky's pixel geometry");
        stokes.fill(0.0);
        self.compute_single_scattering_stokes_rotated(
            (pixel.view, rotation),
            SingleIntegrals::Pixel,
            work,
            stokes,
        );
        let Some(table) = &tables.polarisation else {
            return;
        };
        let ratios = &mut work.multiple_stokes;
        table.lookup_ratios((pixel.view.z, azimuth_rad), ratios);
        work.terms.polarisation_corrected(&mut work.corrected);
        add_corrected_multiple_stokes(ratios, &work.corrected, radiance, stokes);
    }
}
