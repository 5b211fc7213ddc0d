//! Aerial perspective: the light of the air between the eye and a point of
//! a scene, and how much of the point's own light gets through.
//!
//! For the eye at x_0 and a point x_d = x_0 + d w at distance d (m) along
//! the view w, a renderer composites
//!
//! ```text
//! L_eye(lambda) = L_point(lambda) T(lambda) + L_air(lambda)
//! T(lambda)     = exp(-integral_0^d beta_ext(x_0 + s w, lambda) ds)
//! L_air(lambda) = integral_0^d T(0..s) J(x_0 + s w, -w, lambda) ds
//! ```
//!
//! with J the source of light scattered into the view (single scattering
//! of the sun's beam and the higher orders). This is the sky's own
//! composition along a segment instead of the whole ray: the same march
//! ([`crate::transport::optical_column::PanelMarch`]) and the same terms
//! ([`super::composition::ViewTerms`]: single scattering, the scaled field's light, the
//! forward-peak term) with the segment ending at min(d, where the ray
//! leaves the atmosphere or meets the ground), L_seg. The ground's terms
//! (its sunlit and skylit light) are left out of it: the point is the
//! scene's, and a ray that reaches the ground before d ends there.
//!
//! The point is a point (a black target, as the path tracer that checks
//! this has it): it changes no light but that along the view through it,
//! so the eye's sky L_sky is L_air plus T times the light arriving at the
//! point from behind it, exactly:
//!
//! ```text
//! L_air = L_sky - T L_behind
//! ```
//!
//! The terms of L_behind, seen from the point, follow from the whole
//! ray's and the segment's ([`Sky::compute_segment_terms`]): single
//! scattering and the scaled field are integrals along the ray, so the
//! segment keeps its own (S_seg, F_seg) and the light from behind that
//! the segment's forward peaks scatter toward the eye,
//! (1 - T / T*) (F_sky - F_seg + G_sky) (T* the scaled transmittance, G
//! the ground's light);
//! the forward-peak term is taken as the sky's less T times that of the
//! ray from the point on, its integrals counted from the point (the
//! segment's peaks are what spreads the light from behind: toward the sun
//! the aureole behind the point reaches the eye spread over the peaks'
//! width, not at its own peak radiance). The whole ray is marched too, so
//! a segment costs two views. L_air tends to the sky's radiance as d grows
//! (exactly, to the last bit, once d passes the ray's end, for a view that
//! leaves through the top) and to d times the source toward the eye at
//! the eye as d shrinks. T is the exact Beer-Lambert transmittance of the
//! real (not delta-M scaled) extinction, from the columns of the march.
//!
//! What lights the point itself, for shading it: the sun's transmittance
//! from the top of the atmosphere to the point (exact columns; zero in the
//! planet's shadow), and the sky's diffuse irradiance on a horizontal
//! plane at the point: [`Sky::irradiance`] of this sky with the eye moved
//! to the point's altitude and the sun to its elevation there (over a
//! curved planet up to d / R rad from the eye's, 0.45 degrees at 50 km);
//! zero at the top of the atmosphere. Each point with its own altitude and
//! sun costs a sky (its field and image tables, about as much as the
//! eye's); points that share them share it.
//!
//! Units: radiance W m^-2 sr^-1 nm^-1, irradiance W m^-2 nm^-1,
//! transmittances 1, distances m; spectra on the sky's wavelength grid.
//! Methods: [`Method::Fast`] (the field synthesised exactly along the
//! segment) and [`Method::PathTracing`] (a black target at d that ends the
//! paths reaching it, with standard errors); the reference march has no
//! segment and is an error.

use super::composition::{SegmentSky, ViewWork, sky_radiance_from_traced};
use super::{ImageSettings, Method, Polarisation, Sky, SkyRadiance};
use crate::colour::{SpectrumToXyz, Xyz};
use crate::error::{Error, Result};
use crate::geometry::{Vector3, ViewDirection, segment_in_atmosphere};
use crate::spectrum::SampledSpectrum;
use crate::transport::path_tracing::PathTracer;
use crate::transport::stokes::meridian_reference;

/// The air between the eye and a point of a scene
/// ([`Sky::aerial_perspective`]; see the module docs for the compositing
/// and the units).
#[derive(Debug, Clone, PartialEq)]
pub struct AerialPerspective {
    /// The segment's length, m: the distance asked for, or where the view
    /// ray leaves the atmosphere or meets the ground if that is nearer
    /// (zero where the view misses the atmosphere).
    pub distance_m: f64,
    /// L_air: the light scattered into the view between the eye and the
    /// point (single and multiple scattering; the Stokes vector too for a
    /// polarised sky, standard errors when path tracing), W m^-2 sr^-1
    /// nm^-1.
    pub radiance: SkyRadiance,
    /// T: the segment's transmittance, exp(-integral beta_ext ds).
    pub transmittance: SampledSpectrum,
    /// The sun's beam transmittance from the top of the atmosphere to the
    /// point (zero where the planet shades it).
    pub sun_transmittance_at_point: SampledSpectrum,
    /// The sky's diffuse irradiance on a horizontal plane at the point, W
    /// m^-2 nm^-1 (at its altitude and sun elevation; see the module docs).
    pub sky_irradiance_at_point: SampledSpectrum,
}

impl Sky {
    /// The aerial perspective of a point `distance_m` m (> 0; infinity for
    /// the whole ray) along `view` from the eye: the light the air between
    /// them scatters toward the eye, the segment's transmittance and what
    /// lights the point (see [`AerialPerspective`] and the module docs).
    pub fn aerial_perspective(
        &self,
        view: ViewDirection,
        distance_m: f64,
    ) -> Result<AerialPerspective> {
        let mut all = self.aerial_perspectives(&[(view, distance_m)])?;
        Ok(all.remove(0))
    }

    /// The aerial perspective of a point given by its position relative to
    /// the eye, east-north-up, m (not the eye itself).
    pub fn aerial_perspective_to_point(&self, point_m: [f64; 3]) -> Result<AerialPerspective> {
        let offset = Vector3::new(point_m[0], point_m[1], point_m[2]);
        let distance = offset.length();
        if !(distance.is_finite() && distance > 0.0) {
            return Err(Error::out_of_range(
                "the point's distance from the eye",
                distance,
                "m",
                "> 0 and finite",
            ));
        }
        let (elevation, azimuth) =
            crate::geometry::elevation_azimuth_from_direction(offset * (1.0 / distance));
        self.aerial_perspective(ViewDirection::new(elevation, azimuth)?, distance)
    }

    /// [`Sky::aerial_perspective`] for every (view, distance) in
    /// `segments`, in order, in parallel, every table built once.
    pub fn aerial_perspectives(
        &self,
        segments: &[(ViewDirection, f64)],
    ) -> Result<Vec<AerialPerspective>> {
        let wavelengths = self.wavelengths().len();
        super::check_view_count("the views", segments.len() as f64, wavelengths)?;
        for (view, distance) in segments {
            check_distance(*distance)?;
            self.check_within_restricted_field(Some(view.elevation_deg()))?;
        }
        if let Method::Reference { .. } = self.method {
            return Err(Error::Unsupported(
                "aerial perspective: the fast method (the default) or path tracing; the reference march has no segment".into(),
            ));
        }
        if !self.k_terms.is_empty() {
            return self.sum_term_aerial_perspectives(|term| term.aerial_perspectives(segments));
        }
        let wavelengths = self.wavelengths().len();
        let mut scratch = self.scene.scratch();
        let mut irradiances = SkyIrradiances::default();
        let mut all = Vec::with_capacity(segments.len());
        for ((view, distance_m), (radiance, transmittance)) in
            segments.iter().zip(self.compute_segment_light(segments)?)
        {
            let (length, end) = self.segment_end(view.to_vector(), *distance_m);
            let mut sun = vec![0.0; wavelengths];
            self.scene.compute_sun_transmittance_at(
                end,
                crate::transport::single_scattering::SunColumns::Exact,
                &mut scratch,
                &mut sun,
            );
            all.push(AerialPerspective {
                distance_m: length,
                radiance,
                transmittance,
                sun_transmittance_at_point: SampledSpectrum::from_values(sun),
                sky_irradiance_at_point: irradiances.at(self, end)?,
            });
        }
        Ok(all)
    }

    /// The sky's diffuse irradiance on a horizontal plane at `point`
    /// (planet-centred, m), W m^-2 nm^-1: [`Sky::irradiance`] of this sky
    /// with the eye moved to the point's altitude and the sun to its
    /// elevation there (the plane is horizontal and the planet round, so
    /// its azimuth does not matter); zero at the top of the atmosphere
    /// and above it, where no air is above the plane.
    pub(crate) fn compute_sky_irradiance_at(&self, point: Vector3) -> Result<SampledSpectrum> {
        let (ground, top) = self.scene.radii_m();
        let radius = point.length().max(ground);
        if radius >= top {
            return Ok(SampledSpectrum::zeros(self.wavelengths().len()));
        }
        let sun_elevation_deg = self
            .sun_direction()
            .dot(point * (1.0 / point.length()))
            .clamp(-1.0, 1.0)
            .asin()
            .to_degrees();
        let scene = self
            .scene
            .with_observer_and_sun(radius - ground, sun_elevation_deg, 0.0)?;
        let mut sky = Sky::from_scene(scene, self.scattering, self.method, self.table_size)?;
        sky.sun_position_deg = (sun_elevation_deg, 0.0);
        Ok(sky.irradiance(super::Plane::HORIZONTAL)?.diffuse_w_m2_nm)
    }

    /// The light of the air along each checked segment (W m^-2 sr^-1
    /// nm^-1) and the segment's transmittance: what an image needs, and
    /// what [`Sky::aerial_perspectives`] adds the point's light to (and
    /// what the engine tables' aerial-perspective table is baked from).
    pub(crate) fn compute_segment_light(
        &self,
        segments: &[(ViewDirection, f64)],
    ) -> Result<Vec<(SkyRadiance, SampledSpectrum)>> {
        let radiances = match self.method {
            Method::PathTracing { samples, seed } => {
                self.trace_segments(segments, samples, seed)?
            }
            _ => self.compute_segment_radiances(segments)?,
        };
        let mut scratch = self.scene.scratch();
        Ok(segments
            .iter()
            .zip(radiances)
            .map(|((view, distance_m), radiance)| {
                self.scene.compute_segment_integrals(
                    (view.to_vector(), *distance_m),
                    crate::transport::single_scattering::SunColumns::Exact,
                    &mut scratch,
                );
                let transmittance =
                    SampledSpectrum::from_values(scratch.view_transmittance().to_vec());
                (radiance, transmittance)
            })
            .collect())
    }

    /// An image of the aerial perspective: per pixel of `image` (without
    /// the sun's disc), the CIE XYZ (by `to_xyz`, on the sky's grid) of the
    /// light the air scatters into its view between the eye and the point
    /// `depth_m` m along it (one distance for every pixel, or one per
    /// pixel, row-major, top row first; each > 0, infinity for the sky),
    /// and the XYZ of its transmittance spectrum taken as a radiance (a
    /// renderer divides by the XYZ of a spectrum of ones for per-channel
    /// factors). Pixels the camera does not see are black with a
    /// transmittance of zero. Rows of pixels run in parallel.
    pub fn render_aerial_perspective_xyz(
        &self,
        image: &ImageSettings,
        depth_m: &[f64],
        to_xyz: &SpectrumToXyz,
    ) -> Result<(Vec<Xyz>, Vec<Xyz>)> {
        let (width, height) = (image.width, image.height);
        super::check_image_size(width, height)?;
        self.check_colour_conversion(to_xyz)?;
        let pixels = width as usize * height as usize;
        if depth_m.len() != 1 && depth_m.len() != pixels {
            return Err(Error::out_of_range(
                "depth values",
                depth_m.len() as f64,
                "1",
                format!("1 or one per pixel, {width} x {height} = {pixels}"),
            ));
        }
        if let Some(k) = depth_m.iter().position(|d| d.is_nan() || *d <= 0.0) {
            return Err(Error::out_of_range(
                format!(
                    "depth at pixel ({}, {})",
                    k % width as usize,
                    k / width as usize
                ),
                depth_m[k],
                "m",
                "> 0 (infinity: the sky)",
            ));
        }
        if let Method::Reference { .. } | Method::PathTracing { .. } = self.method {
            return Err(Error::Unsupported(
                "an aerial-perspective image: the fast method (the default)".into(),
            ));
        }
        if !self.k_terms.is_empty() {
            let mut parts = Vec::with_capacity(self.k_terms.len());
            for (weights, term) in &self.k_terms {
                let grid = (self.term_offset(term), term.wavelengths());
                let Some((w, to_xyz)) =
                    super::k_terms::term_colour_conversion(to_xyz, grid, weights)
                else {
                    continue;
                };
                parts.push((
                    w,
                    term.render_aerial_perspective_xyz(image, depth_m, &to_xyz)?,
                ));
            }
            let (radiances, transmittances) = parts
                .into_iter()
                .map(|(w, (r, t))| ((w, r), (w, t)))
                .unzip();
            let sum = |images| {
                super::k_terms::weighted_images(images, super::k_terms::add_scaled_xyz, Xyz::BLACK)
            };
            return Ok((sum(radiances), sum(transmittances)));
        }
        let (mut radiance, mut transmittance) =
            (vec![Xyz::BLACK; pixels], vec![Xyz::BLACK; pixels]);
        // A few rows at a time: every pixel's spectra are not kept at once.
        const PIXELS_PER_BATCH: usize = 16_384;
        let mut first = 0;
        while first < pixels {
            let last = (first + PIXELS_PER_BATCH).min(pixels);
            let mut indices = Vec::with_capacity(last - first);
            let mut segments = Vec::with_capacity(last - first);
            for k in first..last {
                let (column, row) = ((k % width as usize) as u32, (k / width as usize) as u32);
                if let Some(view) = image.camera.direction_for_pixel(column, row, width, height) {
                    let (elevation, azimuth) =
                        crate::geometry::elevation_azimuth_from_direction(view);
                    let depth = depth_m[if depth_m.len() == 1 { 0 } else { k }];
                    segments.push((ViewDirection::new(elevation, azimuth)?, depth));
                    indices.push(k);
                }
            }
            for (k, (light, through)) in indices
                .into_iter()
                .zip(self.compute_segment_light(&segments)?)
            {
                radiance[k] = to_xyz.to_xyz(&light.radiance_w_m2_sr_nm)?;
                transmittance[k] = to_xyz.to_xyz(&through)?;
            }
            first = last;
        }
        Ok((radiance, transmittance))
    }

    /// The length (m) of the segment of `view` from the eye toward
    /// `distance_m` inside the atmosphere, and its end (planet-centred,
    /// lifted onto the ground where it ends there).
    fn segment_end(&self, view: Vector3, distance_m: f64) -> (f64, Vector3) {
        let observer = self.scene.observer();
        let (ground, top) = self.scene.radii_m();
        match segment_in_atmosphere(observer, view, ground, top) {
            None => (0.0, observer),
            Some((enter, exit)) => {
                let along = exit.min(distance_m).max(enter);
                let end = observer + view * along;
                let end = if end.length() < ground {
                    end.normalized() * ground
                } else {
                    end
                };
                ((along - enter).max(0.0), end)
            }
        }
    }

    /// The altitude (m) where the segment of `view` to `distance_m` ends,
    /// infinity where it is the whole ray out through the top of the
    /// atmosphere (a segment that ends on the ground ends at 0 m: the
    /// ground's light is the point's).
    fn segment_end_altitude(&self, view: Vector3, distance_m: f64) -> f64 {
        let (ground, top) = self.scene.radii_m();
        let radius = self.segment_end(view, distance_m).1.length();
        if radius >= top * (1.0 - 1e-12) {
            f64::INFINITY
        } else {
            radius - ground
        }
    }

    /// The fast method's light of the air along each segment.
    fn compute_segment_radiances(
        &self,
        segments: &[(ViewDirection, f64)],
    ) -> Result<Vec<SkyRadiance>> {
        self.prepare_field()?;
        const SEGMENTS_PER_TASK: usize = 4;
        let polarised = self.polarisation == Polarisation::Vector;
        // The segment's own air's polarisation, not the whole column's.
        let rows = self.polarisation_rows(segments.iter().map(|(view, distance_m)| {
            (
                view,
                self.segment_end_altitude(view.to_vector(), *distance_m),
            )
        }));
        Ok(self.compute_views_in_parallel(
            segments,
            SEGMENTS_PER_TASK,
            &|_, _| {},
            |(view, distance_m), work, radiance, stokes| {
                self.compute_segment_terms(view.to_vector(), distance_m, work);
                work.terms.add_into(radiance);
                if polarised {
                    let view = (
                        view,
                        self.segment_end_altitude(view.to_vector(), distance_m),
                    );
                    self.compute_view_stokes(view, rows.as_ref(), work, radiance, stokes);
                }
            },
        ))
    }

    /// The terms of the light of the air along the segment of `view` to
    /// `distance_m` into `work` (its terms, the forward-peak integrals the
    /// Stokes vector takes, the segment's single scattering): the eye's
    /// sky radiance less T times the radiance arriving at the point from
    /// behind it, L_air = L_sky - T L_behind (exact for a point: it
    /// changes no light but that along the view through it). With the
    /// sky's terms, for single scattering S, the scaled field F (and the
    /// ground G) and the forward-peak term P, L_behind = (S_sky - S_seg) /
    /// T + (F_sky - F_seg + G_sky) / T* + P_behind, so
    ///
    /// ```text
    /// L_air = S_seg + F_seg + (1 - T / T*) (F_sky - F_seg + G_sky) + P_sky - T P_behind
    /// ```
    ///
    /// with P_behind the forward-peak term of the ray from the point on
    /// (its integrals: the transmittances counted from the point, X of
    /// the view leg from the point). Its first line's rows are linear in
    /// the integrals, P_sky - T P_behind has rows I_seg + (1 - T / T*)
    /// (I*_sky - I*_seg) (I* the scaled part,
    /// [`crate::transport::multiple_scattering::MultipleScatteringScratch::scaled_forward_integrals`]);
    /// its peak-only line's T Q_behind and T Q_behind X-bar_behind are
    /// summed along the ray beyond the point itself
    /// ([`crate::transport::multiple_scattering::MultipleScatteringField::compute_forward_integrals_beyond`]),
    /// and the sky's Q_sky and Q_sky X-bar_sky are composed from them and
    /// the segment's (Q_seg + T Q_behind, Q_seg X-bar_seg + T Q_behind
    /// (X-bar_behind + X_seg), X_seg the segment's peak depth tau - tau*),
    /// not taken from the whole ray's own march. Either difference of two
    /// marches is their quadrature error where the segment adds little
    /// to Q: Q_sky - Q_seg as the light from behind (a view through haze
    /// near the horizon, X-bar of that error over that error anything,
    /// e^X-bar up to e^64), and P_sky - T P_behind as the air's peak-only
    /// light (earth-hazy, the eye at 100 km, sun 0 degrees, a view 10.09
    /// degrees down 20 degrees from the sun's azimuth, 1755 m, 700 nm:
    /// 4.1315e-4 - 4.1317e-4, -1.3e-8 against single scattering's 8.4e-9).
    fn compute_segment_terms(&self, view: Vector3, distance_m: f64, work: &mut ViewWork) {
        let wavelengths = self.wavelengths().len();
        // The whole ray's field, ground and forward-peak integrals, kept
        // for the next segment along the same view.
        let key = [view.x.to_bits(), view.y.to_bits(), view.z.to_bits()];
        let sky = match work.segment_sky.take() {
            Some(sky) if sky.view == key => sky,
            _ => {
                self.compute_view_terms((view, f64::INFINITY), None, work);
                SegmentSky {
                    view: key,
                    field: work.terms.field.clone(),
                    ground: (
                        work.terms.ground_sunlit.clone(),
                        work.terms.ground_skylit.clone(),
                    ),
                    integrals: work
                        .multiple
                        .as_ref()
                        .map(|scratch| scratch.scaled_forward_integrals().to_vec()),
                }
            }
        };
        // The segment's terms; the ground beyond it is the point's.
        self.compute_view_terms((view, distance_m), None, work);
        work.terms.ground_sunlit.fill(0.0);
        work.terms.ground_skylit.fill(0.0);
        let (Some(field), Some(scratch), Some(sky_scaled)) =
            (self.field(), work.multiple.as_ref(), sky.integrals.as_ref())
        else {
            work.segment_sky = Some(sky);
            return;
        };
        let (sky_terms, sky_ground) = (&sky.field, &sky.ground);
        // 1 - T / T* per wavelength.
        let mut scaled = vec![0.0; wavelengths];
        field.scaled_transmittance_of_last_ray(scratch, &mut scaled);
        // The segment's X_seg (its view leg's peak depth).
        let mut peak_depth = vec![0.0; wavelengths];
        field.peak_depth_of_last_ray(scratch, &mut peak_depth);
        let through = work.single.view_transmittance();
        let share: Vec<f64> = through
            .iter()
            .zip(&scaled)
            .map(|(t, t_scaled)| {
                if *t > 0.0 && *t_scaled > 0.0 {
                    1.0 - t / t_scaled
                } else {
                    0.0
                }
            })
            .collect();
        let species = sky_scaled.len() / wavelengths;
        let (forward, segment_scaled) = (
            scratch.forward_integrals(),
            scratch.scaled_forward_integrals(),
        );
        // The air's forward-peak integrals (first line; the segment's
        // peak-only rows, the light from behind's added below), and T
        // times those of the light from behind (peak-only rows only).
        let mut behind = vec![0.0; forward.len()];
        for (row, out) in work.forward.chunks_mut(wavelengths).enumerate() {
            for (i, o) in out.iter_mut().enumerate() {
                let k = row * wavelengths + i;
                *o = if row < species {
                    forward[k] + share[i] * (sky_scaled[k] - segment_scaled[k])
                } else {
                    forward[k]
                };
            }
        }
        // The light from behind's peak-only rows from the ray beyond the
        // point marched on its own (T and X counted from the point), times
        // T: T Q_behind and T Q_behind X-bar_behind. The sky's are the
        // segment's and these, X counted from the eye (X_seg more):
        // Q_sky = Q_seg + T Q_behind, Q_sky X-bar_sky = Q_seg X-bar_seg +
        // T Q_behind (X-bar_behind + X_seg).
        let beyond = work.multiple.as_mut().map(|scratch| {
            field.compute_forward_integrals_beyond(view, distance_m, scratch);
            scratch.forward_integrals().to_vec()
        });
        let through = work.single.view_transmittance();
        if let Some(beyond) = beyond {
            for (i, t) in through.iter().enumerate() {
                let (q, qx) = (species * wavelengths + i, (species + 1) * wavelengths + i);
                behind[q] = t * beyond[q];
                behind[qx] = t * beyond[qx];
                work.forward[q] += behind[q];
                work.forward[qx] += behind[qx] + peak_depth[i] * behind[q];
            }
        }
        let terms = &mut work.terms;
        for i in 0..wavelengths {
            terms.field[i] += share[i] * (sky_terms[i] - terms.field[i]);
            terms.ground_sunlit[i] = share[i] * sky_ground.0[i];
            terms.ground_skylit[i] = share[i] * sky_ground.1[i];
        }
        let cos_theta = view.dot(self.sun_direction());
        field.compute_forward_peak_radiance(
            cos_theta,
            &work.forward,
            &mut work.phase,
            &mut terms.forward_peak,
        );
        let mut hidden = vec![0.0; wavelengths];
        field.compute_forward_peak_radiance(cos_theta, &behind, &mut work.phase, &mut hidden);
        for (p, h) in terms.forward_peak.iter_mut().zip(&hidden) {
            *p -= h;
        }
        work.segment_sky = Some(sky);
    }

    /// The parts of the light of the air along one segment (prototype
    /// measurements, `engine_tables` tests): [single scattering, the
    /// segment's own scaled field, the field with the light from behind
    /// that the segment's peaks scatter forward, the forward-peak term,
    /// the ground's share].
    #[cfg(test)]
    pub(crate) fn segment_term_parts(&self, view: Vector3, distance_m: f64) -> [Vec<f64>; 5] {
        self.prepare_field().unwrap();
        let mut work = self.view_work();
        self.compute_view_terms((view, distance_m), None, &mut work);
        let own = work.terms.field.clone();
        self.compute_segment_terms(view, distance_m, &mut work);
        let t = &work.terms;
        let ground = t
            .ground_sunlit
            .iter()
            .zip(&t.ground_skylit)
            .map(|(a, b)| a + b)
            .collect();
        [
            t.single.clone(),
            own,
            t.field.clone(),
            t.forward_peak.clone(),
            ground,
        ]
    }

    /// The path tracer's light of the air along each segment: a black
    /// target at its end.
    fn trace_segments(
        &self,
        segments: &[(ViewDirection, f64)],
        samples: u64,
        seed: u64,
    ) -> Result<Vec<SkyRadiance>> {
        let tracer = match self.polarisation {
            Polarisation::Scalar => PathTracer::new(&self.scene),
            Polarisation::Vector => PathTracer::new_polarised(&self.scene)?,
        };
        segments
            .iter()
            .map(|(view, distance_m)| {
                let traced = tracer
                    .clone()
                    .with_target_distance(*distance_m)
                    .compute_stokes_with_progress(
                        view.to_vector(),
                        meridian_reference(view.elevation_deg(), view.azimuth_deg()),
                        samples,
                        seed,
                        &|_| {},
                    )?;
                Ok(sky_radiance_from_traced(traced))
            })
            .collect()
    }
}

/// The sky irradiances of the points of one call, computed once for each
/// (altitude, sun elevation) and taken from the sky itself at the eye.
#[derive(Default)]
struct SkyIrradiances {
    /// Irradiances known so far (W m^-2 nm^-1), keyed by the bits of the
    /// point's distance from the planet's centre (m) and the sine of the
    /// sun's elevation there.
    known: Vec<((u64, u64), SampledSpectrum)>,
}

impl SkyIrradiances {
    /// The sky irradiance on a horizontal plane at `point` (see
    /// [`Sky::compute_sky_irradiance_at`]).
    fn at(&mut self, sky: &Sky, point: Vector3) -> Result<SampledSpectrum> {
        let zenith = point * (1.0 / point.length());
        let key = (
            point.length().to_bits(),
            sky.sun_direction().dot(zenith).to_bits(),
        );
        if let Some((_, known)) = self.known.iter().find(|(k, _)| *k == key) {
            return Ok(known.clone());
        }
        let eye = sky.scene.observer();
        let at_eye = (
            eye.length().to_bits(),
            sky.sun_direction()
                .dot(eye * (1.0 / eye.length()))
                .to_bits(),
        );
        let irradiance = if key == at_eye {
            sky.irradiance(super::Plane::HORIZONTAL)?.diffuse_w_m2_nm
        } else {
            sky.compute_sky_irradiance_at(point)?
        };
        self.known.push((key, irradiance.clone()));
        Ok(irradiance)
    }
}

/// A distance along a view must be positive (infinity: the whole ray).
fn check_distance(distance_m: f64) -> Result<()> {
    if distance_m > 0.0 {
        Ok(())
    } else {
        Err(Error::out_of_range(
            "distance_m",
            distance_m,
            "m",
            "> 0 (infinity: the whole view ray)",
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::Atmosphere;
    use crate::sky::Scattering;
    use crate::spectrum::WavelengthGrid;

    fn build_sky(
        preset: &str,
        sun_elevation_deg: f64,
        scattering: Scattering,
        method: Method,
    ) -> Sky {
        Sky::builder(&Atmosphere::preset(preset).unwrap())
            .sun_deg(sun_elevation_deg, 180.0)
            .wavelengths(WavelengthGrid::new(440.0, 680.0, 120.0).unwrap())
            .scattering(scattering)
            .method(method)
            .build()
            .unwrap()
    }

    /// The light of the air along the segment of `view` to `distance_m`
    /// and its transmittance (without the point's own light, which costs
    /// a sky at the point).
    fn air(sky: &Sky, view: ViewDirection, distance_m: f64) -> (SkyRadiance, SampledSpectrum) {
        sky.compute_segment_light(&[(view, distance_m)])
            .unwrap()
            .remove(0)
    }

    /// The settings' `twilight_shift_pieces` reach the field: after sunset
    /// (earth-hazy, eye 3 km up, sun -2 degrees, the 1 km segment 10
    /// degrees down toward the sun, 680 nm) at most 3 pieces of each path
    /// darken the segment by 1-4 % (measured 2.0 %: the whole
    /// paths' shift over-brightens the red; docs/aerial_perspective.md);
    /// with the sun 30 degrees up nothing is shifted in pieces, the same
    /// bits; 0 pieces is refused with the setting's name.
    #[test]
    fn twilight_shift_pieces_darken_the_red_segment_after_sunset_only() {
        use crate::transport::multiple_scattering::MultipleScatteringSettings;
        let atmosphere = Atmosphere::preset("earth-hazy").unwrap();
        let build = |sun: f64, pieces: usize| {
            let settings = MultipleScatteringSettings {
                twilight_shift_pieces: pieces,
                ..MultipleScatteringSettings::default()
            };
            Sky::builder(&atmosphere)
                .sun_deg(sun, 180.0)
                .observer_altitude_m(3000.0)
                .wavelengths(WavelengthGrid::new(680.0, 680.0, 10.0).unwrap())
                .scattering(Scattering::Multiple(settings))
                .build()
        };
        let view = ViewDirection::new(-10.0, 180.0).unwrap();
        let segment = |sun: f64, pieces: usize| {
            air(&build(sun, pieces).unwrap(), view, 1000.0)
                .0
                .radiance_w_m2_sr_nm[0]
        };
        let change = segment(-2.0, 3) / segment(-2.0, 1) - 1.0;
        eprintln!("sun -2, 680 nm: 3 pieces {:+.2} %", 100.0 * change);
        assert!((-0.04..-0.01).contains(&change), "{change}");
        assert_eq!(segment(30.0, 3).to_bits(), segment(30.0, 1).to_bits());
        let error = build(-2.0, 0).err().unwrap().to_string();
        assert!(error.contains("twilight shift pieces"), "{error}");
    }

    /// tau of the segment by the midpoint rule on 1 m steps, straight from
    /// the profiles and coefficients (no panels, no columns).
    fn independent_optical_depth(sky: &Sky, view: Vector3, length_m: f64, i: usize) -> f64 {
        let (ground, _) = sky.scene.radii_m();
        let observer = sky.scene.observer();
        let steps = length_m.ceil() as usize;
        let h = length_m / steps as f64;
        let mut tau = 0.0;
        for k in 0..steps {
            let altitude = (observer + view * ((k as f64 + 0.5) * h)).length() - ground;
            for s in &sky.optics().species {
                tau += s.extinction_per_m[i] * s.profile.relative_density(altitude) * h;
            }
        }
        tau
    }

    /// A view of earth-hazy 1.06 degrees up, 18.4 degrees in azimuth from
    /// a sun 10 degrees up (pixel (16, 46) of a 48 x 48 fisheye): at 50
    /// km almost no light comes from behind the point, and the light from
    /// behind's peak-only rows, once taken as the whole ray's less the
    /// segment's, were their quadratures' difference: the air's light was
    /// 1.4e17 at 500 nm. It is finite, positive and at most the sky's
    /// radiance (which it tends to) at every distance.
    #[test]
    fn the_light_from_behind_a_far_point_near_the_horizon_is_bounded() {
        let sky = Sky::builder(&Atmosphere::preset("earth-hazy").unwrap())
            .sun_deg(10.0, 180.0)
            .polarisation(Polarisation::Scalar)
            .build()
            .unwrap();
        let direction = crate::camera::Camera::Fisheye
            .direction_for_pixel(16, 46, 48, 48)
            .unwrap();
        let (elevation, azimuth) = crate::geometry::elevation_azimuth_from_direction(direction);
        let view = ViewDirection::new(elevation, azimuth).unwrap();
        let distances = [1e3, 10e3, 30e3, 40e3, 50e3, 60e3, 100e3, f64::INFINITY];
        let segments: Vec<_> = distances.iter().map(|d| (view, *d)).collect();
        let lights = sky.compute_segment_light(&segments).unwrap();
        let sky_light = lights
            .last()
            .unwrap()
            .0
            .radiance_w_m2_sr_nm
            .values()
            .to_vec();
        for (d, (light, _)) in distances.iter().zip(&lights) {
            for (i, (l, s)) in light
                .radiance_w_m2_sr_nm
                .values()
                .iter()
                .zip(&sky_light)
                .enumerate()
            {
                assert!(
                    l.is_finite() && *l > 0.0 && *l <= 1.001 * s,
                    "d {d} m, wavelength {i}: the air's light {l:e}, the sky's {s:e}"
                );
            }
        }
    }

    /// A grazing view from the top of the atmosphere (earth-hazy, the eye
    /// at 100 km, the sun on the horizon; the engine tables' aerial
    /// table's view next to the horizon, 20 degrees from the sun's
    /// azimuth, 22.3 from the sun; 700-780 nm) crosses air of almost no
    /// aerosol in its first 18 km: the segment adds nothing to the
    /// forward peaks' Q (2.6e-38 at 1755 m against the whole ray's
    /// 3.1e-2), so its peak-only light is the difference of the sky's and
    /// T times the light from behind's, both 4.13e-4 at 700 nm. With the
    /// sky's Q from the whole ray's own march that difference was the
    /// two marches' quadrature error (-1.3e-8), and the air's light
    /// -4.5e-9 against single scattering's 8.5e-9 (negative from 670 to
    /// 780 nm, 0.1 to 18 km). Now it is the segment's own light, single
    /// scattering and the scaled field's (the light from behind that its
    /// peaks spread is nil), within 0.1 %, and its single scattering is
    /// the path tracer's (which finds no multiply scattered light there in
    /// 20000 paths) within 1 % + 3 standard errors.
    #[test]
    fn a_grazing_segment_from_the_top_of_the_atmosphere_is_its_own_light() {
        use crate::engine_tables::axes;
        let build = |method: Method| {
            Sky::builder(&Atmosphere::preset("earth-hazy").unwrap())
                .sun_deg(0.0, 180.0)
                .observer_altitude_m(100e3)
                .wavelengths(WavelengthGrid::new(700.0, 780.0, 40.0).unwrap())
                .polarisation(Polarisation::Scalar)
                .method(method)
                .build()
                .unwrap()
        };
        let fast = build(Method::Fast);
        let (ground, top) = fast.scene.radii_m();
        // The last node above the horizon of a half of 16 nodes.
        let horizon = axes::horizon_zenith(top, ground);
        let zenith = axes::zenith_of_node(15, 16, (0, 0), horizon);
        let view = ViewDirection::new(90.0 - zenith.to_degrees(), 200.0).unwrap();
        let segments: Vec<_> = [100.0, 1755.0, 17834.0].map(|d| (view, d)).to_vec();
        let lights = fast.compute_segment_light(&segments).unwrap();
        let traced = build(Method::PathTracing {
            samples: 20_000,
            seed: 3,
        })
        .compute_segment_light(&segments)
        .unwrap();
        for (((_, d), (light, _)), (reference, _)) in segments.iter().zip(&lights).zip(&traced) {
            let [single, own, ..] = fast.segment_term_parts(view.to_vector(), *d);
            let errors = reference.standard_error_w_m2_sr_nm.as_ref().unwrap();
            for i in 0..fast.wavelengths().len() {
                let (x, y) = (
                    light.radiance_w_m2_sr_nm[i],
                    reference.radiance_w_m2_sr_nm[i],
                );
                let alone = single[i] + own[i];
                assert!(
                    x > 0.0 && (x - alone).abs() <= 1e-3 * alone,
                    "d {d} m, #{i}: the air's light {x:e}, the segment's own {alone:e}"
                );
                assert!(
                    (single[i] - y).abs() <= 0.01 * y + 3.0 * errors[i],
                    "d {d} m, #{i}: single scattering {:e}, traced {y:e} +- {:e}",
                    single[i],
                    errors[i]
                );
            }
        }
    }

    /// Segments along one view in a row share its whole ray's terms
    /// (`ViewWork::segment_sky`): their light is bit for bit that of each
    /// segment alone, polarised and scalar, with the multiple-scattering
    /// field and without.
    #[test]
    fn segments_along_one_view_are_each_segment_alone() {
        for (scattering, polarisation) in [
            (Scattering::multiple(), Polarisation::Scalar),
            (Scattering::multiple(), Polarisation::Vector),
            (Scattering::Single, Polarisation::Scalar),
        ] {
            let sky = Sky::builder(&Atmosphere::preset("earth-hazy").unwrap())
                .sun_deg(10.0, 180.0)
                .wavelengths(WavelengthGrid::new(440.0, 680.0, 120.0).unwrap())
                .scattering(scattering)
                .polarisation(polarisation)
                .build()
                .unwrap();
            let segments: Vec<(ViewDirection, f64)> = [(5.0, 0.0), (30.0, 90.0)]
                .iter()
                .flat_map(|(e, a)| {
                    let view = ViewDirection::new(*e, 180.0 + a).unwrap();
                    [300.0, 1e3, 10e3, 50e3].map(move |d| (view, d))
                })
                .collect();
            let together = sky.compute_segment_light(&segments).unwrap();
            for (segment, (light, through)) in segments.iter().zip(&together) {
                let (alone, alone_through) = air(&sky, segment.0, segment.1);
                assert_eq!(light, &alone, "{segment:?}");
                assert_eq!(through, &alone_through);
            }
        }
    }

    /// The segment's transmittance is exp(-tau) of an independent
    /// integration of the extinction along it, to 1e-6.
    #[test]
    fn the_transmittance_is_the_segments_beer_lambert() {
        for preset in ["earth-clear", "earth-hazy"] {
            let sky = build_sky(preset, 30.0, Scattering::Single, Method::Fast);
            for (elevation, distance) in [(1.0, 50e3), (0.5, 1e3), (5.0, 10e3), (30.0, 50e3)] {
                let view = ViewDirection::new(elevation, 90.0).unwrap();
                let (_, transmittance) = air(&sky, view, distance);
                assert_eq!(sky.segment_end(view.to_vector(), distance).0, distance);
                for i in 0..sky.wavelengths().len() {
                    let expected =
                        (-independent_optical_depth(&sky, view.to_vector(), distance, i)).exp();
                    let got = transmittance[i];
                    assert!(
                        (got - expected).abs() <= 1e-6,
                        "{preset} elevation {elevation} d {distance} #{i}: {got} vs {expected}"
                    );
                }
            }
        }
    }

    /// Beyond the ray's end the segment is the whole ray: its light is the
    /// sky's radiance (to 1e-6; the same arithmetic, so to the bit, for a
    /// view that leaves through the top: 1000 km reach the top from the
    /// ground 2 degrees up, not 1, whose 1000 km miss 1.9e-6 of the sky).
    /// As d shrinks it goes to zero in proportion to d (a centimetre gives
    /// 1/100 of a metre's, within 2 %), and a metre gives less than 1e-3 of
    /// the sky. (Not less than 1e-4: a metre of air at the ground scatters
    /// J x 1 m toward the eye, J the source there, which is 1.5e-4 to
    /// 5.8e-4 of the sky's radiance over the views of
    /// `a_short_segments_light_is_the_source_at_the_eye`, built from the
    /// sky's own radiances; the test prints the largest share, measured
    /// 4.3e-4 over these views.)
    #[test]
    fn the_segments_light_tends_to_the_sky_and_to_zero() {
        let mut largest = 0.0f64;
        for (preset, sun, polarisation) in [
            ("earth-clear", 10.0, Polarisation::Scalar),
            ("earth-hazy", 2.0, Polarisation::Vector),
        ] {
            let sky = Sky::builder(&Atmosphere::preset(preset).unwrap())
                .sun_deg(sun, 180.0)
                .wavelengths(WavelengthGrid::new(440.0, 680.0, 120.0).unwrap())
                .polarisation(polarisation)
                .build()
                .unwrap();
            for (elevation, azimuth) in [(2.0, 180.0), (5.0, 90.0), (30.0, 0.0), (90.0, 0.0)] {
                let view = ViewDirection::new(elevation, azimuth).unwrap();
                let radiance = sky.radiance(view).unwrap();
                let far = air(&sky, view, 1000e3).0;
                let near = air(&sky, view, 1.0);
                let nearer = air(&sky, view, 0.01).0;
                for i in 0..sky.wavelengths().len() {
                    let l = radiance.radiance_w_m2_sr_nm[i];
                    let f = far.radiance_w_m2_sr_nm[i];
                    assert!(
                        (f / l - 1.0).abs() <= 1e-6,
                        "{preset} {elevation}: {f} vs {l}"
                    );
                    let n = near.0.radiance_w_m2_sr_nm[i];
                    let m = nearer.radiance_w_m2_sr_nm[i];
                    assert!(
                        m > 0.0 && (100.0 * m / n - 1.0).abs() < 0.02,
                        "{preset} {elevation}: 1 cm {m} vs 1 m {n}"
                    );
                    largest = largest.max(n / l);
                    assert!(
                        n > 0.0 && n < 1e-3 * l,
                        "{preset} {elevation}: 1 m {n} vs {l}"
                    );
                    assert!(near.1[i] > 0.999 && near.1[i] < 1.0);
                }
                if let (Some(a), Some(b)) = (&radiance.stokes, &far.stokes) {
                    for i in 0..sky.wavelengths().len() {
                        let scale = 1e-6 * radiance.radiance_w_m2_sr_nm[i];
                        assert!((a.q_w_m2_sr_nm[i] - b.q_w_m2_sr_nm[i]).abs() <= scale);
                        assert!((a.u_w_m2_sr_nm[i] - b.u_w_m2_sr_nm[i]).abs() <= scale);
                    }
                }
            }
        }
        eprintln!("a metre of air: at most {largest:.3e} of the sky");
    }

    /// As d shrinks, L_air / d tends to the source toward the eye at the
    /// eye, J = E T_sun sum_j beta_sca,j p_j(theta_sun) + sum_j beta_sca,j
    /// integral p_j(w' . w) L(w') dw': sunlight scattered once plus the
    /// sky's own light (its views' radiance, the ground's below the
    /// horizon) scattered into the view. The integral is a quadrature of
    /// the sky's radiances about the view (Gauss panels in the angle from
    /// it, crowded toward it where the aerosol's peak is, 36 azimuths): an
    /// independent construction from the sky's views, not the segment's
    /// march. A centimetre's light over a centimetre is J within 3 %
    /// (the image tables' radiances and the quadrature); and J times a
    /// metre over the sky's radiance is what a metre gives (printed).
    #[test]
    fn a_short_segments_light_is_the_source_at_the_eye() {
        let grid = WavelengthGrid::new(440.0, 680.0, 120.0).unwrap();
        let panels: [f64; 16] = [
            0.0, 0.25, 0.5, 1.0, 2.0, 4.0, 6.0, 10.0, 15.0, 25.0, 40.0, 60.0, 90.0, 120.0, 150.0,
            180.0,
        ];
        for (preset, sun, view) in [
            ("earth-clear", 10.0, (30.0, 90.0)),
            ("earth-hazy", 30.0, (10.0, 180.0)),
            ("earth-hazy", 10.0, (90.0, 0.0)),
        ] {
            let sky = Sky::builder(&Atmosphere::preset(preset).unwrap())
                .sun_deg(sun, 180.0)
                .wavelengths(grid)
                .polarisation(Polarisation::Scalar)
                .build()
                .unwrap();
            let w = sky.wavelengths().len();
            let view = ViewDirection::new(view.0, 180.0 + view.1).unwrap();
            let axis = view.to_vector();
            let e1 = if axis.z.abs() < 0.9 {
                axis.cross(Vector3::new(0.0, 0.0, 1.0)).normalized()
            } else {
                axis.cross(Vector3::new(1.0, 0.0, 0.0)).normalized()
            };
            let e2 = axis.cross(e1);
            let (mut directions, mut weights) = (Vec::new(), Vec::new());
            const AZIMUTHS: usize = 36;
            for pair in panels.windows(2) {
                let (a, b) = (pair[0].to_radians(), pair[1].to_radians());
                for (x, g) in crate::transport::quadrature::GAUSS_NODES
                    .iter()
                    .zip(crate::transport::quadrature::GAUSS_WEIGHTS)
                {
                    let alpha = 0.5 * (a + b) + 0.5 * (b - a) * x;
                    let weight =
                        0.5 * (b - a) * g * alpha.sin() * std::f64::consts::TAU / AZIMUTHS as f64;
                    for k in 0..AZIMUTHS {
                        let phi = std::f64::consts::TAU * (k as f64 + 0.5) / AZIMUTHS as f64;
                        let d =
                            axis * alpha.cos() + (e1 * phi.cos() + e2 * phi.sin()) * alpha.sin();
                        let (el, az) = crate::geometry::elevation_azimuth_from_direction(d);
                        directions.push(ViewDirection::new(el, az).unwrap());
                        weights.push((weight, alpha.cos()));
                    }
                }
            }
            let radiances = sky.radiances(&directions).unwrap();
            let mut source = vec![0.0; w];
            let mut phase = vec![0.0; w];
            for s in &sky.optics().species {
                let density = s.profile.relative_density(0.0);
                for ((weight, cos), radiance) in weights.iter().zip(&radiances) {
                    s.phase_function.eval_into(*cos, &mut phase);
                    for i in 0..w {
                        source[i] += s.scattering_per_m[i]
                            * density
                            * phase[i]
                            * weight
                            * radiance.radiance_w_m2_sr_nm[i];
                    }
                }
                s.phase_function
                    .eval_into(axis.dot(sky.sun_direction()), &mut phase);
                for i in 0..w {
                    source[i] += sky.optics().solar_irradiance_w_m2_nm[i]
                        * sky.direct_beam_transmittance()[i]
                        * s.scattering_per_m[i]
                        * density
                        * phase[i];
                }
            }
            let centimetre = air(&sky, view, 0.01).0;
            let whole = sky.radiance(view).unwrap();
            for (i, source) in source.iter().enumerate() {
                let got = centimetre.radiance_w_m2_sr_nm[i] / 0.01;
                eprintln!(
                    "{preset} sun {sun} view ({}, {}) #{i}: L(1 cm) / 1 cm {got:.4e}, J {:.4e} ({:+.2} %); J x 1 m / L_sky {:.2e}",
                    view.elevation_deg(),
                    view.azimuth_deg() - 180.0,
                    source,
                    100.0 * (got / source - 1.0),
                    source / whole.radiance_w_m2_sr_nm[i]
                );
                assert!(
                    (got / source - 1.0).abs() < 0.03,
                    "{preset} sun {sun} #{i}: {got} vs {source}"
                );
            }
        }
    }

    /// Single scattering over a short horizontal path at the ground (the
    /// eye 1 m up, where a horizontal view runs 3.6 km before it meets the
    /// ground): E_sun T_sun(0) beta_sca p(theta) (1 - exp(-beta_ext d)) /
    /// beta_ext, summed over the species, within 0.1 %.
    #[test]
    fn short_horizontal_single_scattering_is_the_closed_form() {
        for (preset, sun) in [("earth-clear", 30.0), ("earth-hazy", 60.0)] {
            let sky = Sky::builder(&Atmosphere::preset(preset).unwrap())
                .sun_deg(sun, 180.0)
                .observer_altitude_m(1.0)
                .wavelengths(WavelengthGrid::new(440.0, 680.0, 120.0).unwrap())
                .scattering(Scattering::Single)
                .build()
                .unwrap();
            let n = sky.wavelengths().len();
            for (azimuth, distance) in [(0.0, 200.0), (90.0, 500.0), (180.0, 100.0)] {
                let view = ViewDirection::new(0.0, azimuth).unwrap();
                let (radiance, _) = air(&sky, view, distance);
                let cos_theta = view.to_vector().dot(sky.sun_direction());
                let mut phase = vec![0.0; n];
                for i in 0..n {
                    let (mut beta_ext, mut source) = (0.0, 0.0);
                    for s in &sky.optics().species {
                        let density = s.profile.relative_density(1.0);
                        s.phase_function.eval_into(cos_theta, &mut phase);
                        beta_ext += s.extinction_per_m[i] * density;
                        source += s.scattering_per_m[i] * density * phase[i];
                    }
                    let expected = sky.optics().solar_irradiance_w_m2_nm[i]
                        * sky.direct_beam_transmittance()[i]
                        * source
                        * (1.0 - (-beta_ext * distance).exp())
                        / beta_ext;
                    let got = radiance.radiance_w_m2_sr_nm[i];
                    assert!(
                        (got / expected - 1.0).abs() <= 1e-3,
                        "{preset} azimuth {azimuth} d {distance} #{i}: {got} vs {expected}"
                    );
                }
            }
        }
    }

    /// The sky's irradiance at the point is taken there: 2 km straight up
    /// (the same sun elevation) it is that of the sky seen from 2 km, less
    /// than at the eye (less air above it); at the top of the atmosphere it
    /// is zero; and the sun's transmittance to the point is larger than to
    /// the eye.
    #[test]
    fn the_points_light_is_taken_at_the_point() {
        let grid = WavelengthGrid::new(440.0, 680.0, 120.0).unwrap();
        let atmosphere = Atmosphere::preset("earth-clear").unwrap();
        let build = |altitude: f64| {
            Sky::builder(&atmosphere)
                .sun_deg(20.0, 180.0)
                .observer_altitude_m(altitude)
                .wavelengths(grid)
                .polarisation(Polarisation::Scalar)
                .build()
                .unwrap()
        };
        let sky = build(0.0);
        let up = ViewDirection::new(90.0, 0.0).unwrap();
        let ap = sky.aerial_perspective(up, 2e3).unwrap();
        let there = build(2e3)
            .irradiance(super::super::Plane::HORIZONTAL)
            .unwrap();
        let here = sky.irradiance(super::super::Plane::HORIZONTAL).unwrap();
        for i in 0..sky.wavelengths().len() {
            let got = ap.sky_irradiance_at_point[i];
            assert!(
                (got / there.diffuse_w_m2_nm[i] - 1.0).abs() < 1e-9,
                "#{i}: {got} vs {}",
                there.diffuse_w_m2_nm[i]
            );
            assert!(got < here.diffuse_w_m2_nm[i]);
            // (The same path's columns by two quadratures.)
            let sun = ap.sun_transmittance_at_point[i];
            assert!(
                sun > here.direct_beam_transmittance[i]
                    && (sun / there.direct_beam_transmittance[i] - 1.0).abs() < 1e-6,
                "#{i}: {sun} vs {}",
                there.direct_beam_transmittance[i]
            );
        }
        let top = sky.aerial_perspective(up, 1e9).unwrap();
        assert!(
            top.sky_irradiance_at_point
                .values()
                .iter()
                .all(|v| *v == 0.0)
        );
    }

    #[test]
    fn bad_distances_and_the_reference_method_are_errors() {
        let sky = build_sky("earth-clear", 30.0, Scattering::Single, Method::Fast);
        let view = ViewDirection::new(5.0, 0.0).unwrap();
        for bad in [0.0, -1.0, f64::NAN, f64::NEG_INFINITY] {
            let message = sky.aerial_perspective(view, bad).unwrap_err().to_string();
            assert!(message.contains("distance_m"), "{message}");
        }
        assert!(sky.aerial_perspective_to_point([0.0, 0.0, 0.0]).is_err());
        let reference = build_sky(
            "earth-clear",
            30.0,
            Scattering::Single,
            Method::Reference {
                view_steps: 10,
                sun_steps: 10,
            },
        );
        assert!(reference.aerial_perspective(view, 1e3).is_err());
        // A point given in 3D is the view toward it at its distance.
        let ap = sky.aerial_perspective_to_point([0.0, 3e3, 4e3]).unwrap();
        let toward = ViewDirection::new(4f64.atan2(3.0).to_degrees(), 0.0).unwrap();
        let same = sky.aerial_perspective(toward, 5e3).unwrap();
        for i in 0..sky.wavelengths().len() {
            let (a, b) = (
                ap.radiance.radiance_w_m2_sr_nm[i],
                same.radiance.radiance_w_m2_sr_nm[i],
            );
            assert!((a / b - 1.0).abs() < 1e-9);
        }
    }

    /// The fast method's aerial perspective against the path tracer's (a
    /// black target at d) for the views at (elevation, azimuth from the
    /// sun) and distances given: the failures of |fast - traced| <= 1 % of
    /// the traced + 3 standard errors, and the worst |difference| / (1 % +
    /// 3 sigma) with where it was.
    fn compare_with_path_tracer(
        preset: &str,
        sun: f64,
        views: &[(f64, f64)],
        distances: &[f64],
        samples: u64,
    ) -> (Vec<String>, f64, String) {
        let fast = build_sky(preset, sun, Scattering::multiple(), Method::Fast);
        let traced = build_sky(
            preset,
            sun,
            Scattering::multiple(),
            Method::PathTracing { samples, seed: 7 },
        );
        let segments: Vec<(ViewDirection, f64)> = views
            .iter()
            .flat_map(|(e, a)| {
                let view = ViewDirection::new(*e, 180.0 + a).unwrap();
                distances.iter().map(move |d| (view, *d))
            })
            .collect();
        // The air's light and transmittance only (the point's own light is
        // not compared).
        let expected = fast.compute_segment_light(&segments).unwrap();
        let got = traced.compute_segment_light(&segments).unwrap();
        let (mut failures, mut worst, mut worst_at) = (Vec::new(), 0.0f64, String::new());
        for (((view, d), e), g) in segments.iter().zip(&expected).zip(&got) {
            let errors = g.0.standard_error_w_m2_sr_nm.as_ref().unwrap();
            for i in 0..fast.wavelengths().len() {
                let (x, y) = (e.0.radiance_w_m2_sr_nm[i], g.0.radiance_w_m2_sr_nm[i]);
                let allowed = 0.01 * y.abs() + 3.0 * errors[i];
                let at = format!(
                    "{preset} sun {sun} view ({}, {}) d {d} #{i}: fast {x:.5e} traced {y:.5e} +- {:.2e} ({:.2} %)",
                    view.elevation_deg(),
                    view.azimuth_deg() - 180.0,
                    errors[i],
                    100.0 * (x / y - 1.0)
                );
                let ratio = (x - y).abs() / allowed;
                if ratio > worst {
                    (worst, worst_at) = (ratio, at.clone());
                }
                if ratio > 1.0 {
                    failures.push(at);
                }
            }
            // The transmittance is the same function of the same segment.
            assert_eq!(e.1, g.1);
        }
        (failures, worst, worst_at)
    }

    /// A representative subset of the comparison with the path tracer
    /// (the full grid is `aerial_perspective_matches_the_path_tracer_everywhere`).
    #[test]
    fn aerial_perspective_matches_the_path_tracer() {
        let mut all = Vec::new();
        for (preset, sun, view, distance) in [
            ("earth-hazy", 10.0, (5.0, 0.0), 10e3),
            ("earth-hazy", 10.0, (5.0, 0.0), 1000e3),
            ("earth-clear", 60.0, (1.0, 90.0), 50e3),
            ("earth-clear", 2.0, (10.0, 180.0), 1e3),
            // Straight at the sun, where the light from behind the point
            // is the aureole (`Sky::compute_segment_terms`).
            ("earth-hazy", 10.0, (10.0, 0.0), 1e3),
        ] {
            let (failures, worst, at) =
                compare_with_path_tracer(preset, sun, &[view], &[distance], 40_000);
            eprintln!("worst {worst:.2} of the tolerance at {at}");
            all.extend(failures);
        }
        assert!(all.is_empty(), "{all:#?}");
    }

    /// A segment's multiply scattered light is polarised as its own air's,
    /// not as the whole column's. With the sun 2 degrees up, 10 degrees up
    /// away from it, the whole column's polarised multiply scattered
    /// intensity is 1.12 times the scalar one at 440 nm, while the vector
    /// and scalar path tracers give the lowest kilometre's 1.07 times; the
    /// whole column's ratio made such segments 5-6 % too bright against
    /// the vector path tracer (1.1 times the tolerance at 160 000 paths).
    /// Each segment now takes its own column's ratio
    /// (`polarisation_correction.rs`, `ViewExtent`).
    #[test]
    fn a_segments_polarisation_is_its_own_airs() {
        let mut all = Vec::new();
        for (sun, view) in [(2.0, (10.0, 180.0)), (-4.0, (10.0, 0.0))] {
            let (failures, worst, at) =
                compare_with_path_tracer("earth-clear", sun, &[view], &[1e3], 160_000);
            eprintln!("worst {worst:.2} of the tolerance at {at}");
            all.extend(failures);
        }
        assert!(all.is_empty(), "{all:#?}");
    }

    /// The issue's grid: earth-clear and earth-hazy, suns 60, 10, 2 and -4
    /// degrees, views 1, 10 and 30 degrees up (a view 0 degrees up from the
    /// ground is the ground's) at azimuths 0, 90 and 180 from the sun, d =
    /// 1, 10 and 50 km, 440, 560 and 680 nm (ignored: 10 minutes on 2
    /// cores). Fails: 2 of its 648 values, earth-clear at sun -4 degrees,
    /// 30 degrees up toward the sun, 1 km, 560 and 680 nm (+9.0 % and +5.7
    /// %, 1.09 and 1.15 times the tolerance): the polarisation of the
    /// twilight column's lowest air (docs/aerial_perspective.md). Until
    /// each segment took its own column's polarisation ratio, 11 failed.
    #[test]
    #[ignore]
    fn aerial_perspective_matches_the_path_tracer_everywhere() {
        let views: Vec<(f64, f64)> = [1.0, 10.0, 30.0]
            .iter()
            .flat_map(|e| [0.0, 90.0, 180.0].map(|a| (*e, a)))
            .collect();
        let mut all = Vec::new();
        for preset in ["earth-clear", "earth-hazy"] {
            for sun in [60.0, 10.0, 2.0, -4.0] {
                let (failures, worst, at) =
                    compare_with_path_tracer(preset, sun, &views, &[1e3, 10e3, 50e3], 40_000);
                eprintln!("{preset} sun {sun}: worst {worst:.2} of the tolerance at {at}");
                all.extend(failures);
            }
        }
        assert!(all.is_empty(), "{all:#?}");
    }

    /// The 48 x 48 fisheye aerial images (CIE XYZ, scalar light) of the
    /// three presets at suns 60, 10, 2 and -4 degrees and 1, 10 and 50 km:
    /// no pixel's Y is more than 100 times its image's 99th percentile
    /// (a lone spike; the brightest real pixels, toward the sun, are
    /// within a few times it). Prints each image's largest ratio.
    #[test]
    #[ignore]
    fn no_aerial_image_has_a_spike() {
        let mut worst: f64 = 0.0;
        for preset in ["earth-clear", "earth-hazy", "mars-dust"] {
            for sun in [60.0, 10.0, 2.0, -4.0] {
                let sky = Sky::builder(&Atmosphere::preset(preset).unwrap())
                    .sun_deg(sun, 180.0)
                    .polarisation(Polarisation::Scalar)
                    .build()
                    .unwrap();
                let to_xyz = SpectrumToXyz::new(
                    sky.wavelengths(),
                    crate::colour::Observer::Cie1931TwoDegree,
                );
                let mut image = ImageSettings::new(crate::camera::Camera::Fisheye, 48, 48);
                image.draw_sun_disc = false;
                for d in [1e3, 10e3, 50e3] {
                    let (radiance, _) = sky
                        .render_aerial_perspective_xyz(&image, &[d], &to_xyz)
                        .unwrap();
                    let mut y: Vec<f64> = radiance.iter().map(|p| p.y).collect();
                    assert!(y.iter().all(|v| v.is_finite() && *v >= 0.0));
                    let top = y.iter().cloned().fold(0.0, f64::max);
                    let mut lit: Vec<f64> = y.drain(..).filter(|v| *v > 0.0).collect();
                    lit.sort_by(f64::total_cmp);
                    let p99 = lit[(0.99 * (lit.len() - 1) as f64) as usize];
                    eprintln!(
                        "{preset} sun {sun} d {d} m: max {top:.4e}, p99 {p99:.4e}, ratio {:.3}",
                        top / p99
                    );
                    worst = worst.max(top / p99);
                }
            }
        }
        assert!(worst < 100.0, "largest ratio {worst}");
    }

    /// A probe, not a check: the parts of the fast method's light of the
    /// air along segments against the path tracer's (a black target at the
    /// segment's end), with the tracer's standard errors. Environment:
    /// `SORA_SET_PRESET` (earth-hazy; or an atmosphere file, `.toml`),
    /// `SORA_SET_ALBEDO` (the ground's albedo, 1, instead of the preset's), `SORA_SET_EYES` (m, "3000"),
    /// `SORA_SET_SUNS` (deg, "-2"), `SORA_SET_VIEWS` ("elevation,azimuth
    /// from the sun;...", "-10,0"), `SORA_SET_DISTANCES` (m, "1000"; inf
    /// for the whole ray), `SORA_SET_NM` ("440,680,120": start, stop,
    /// step), `SORA_SET_POLARISATION` (scalar), `SORA_SET_STREAMS` (8),
    /// `SORA_SET_LAYERS` (40), `SORA_SET_SUN_STEP` (sunset sun-node step,
    /// deg, 0.75), `SORA_SET_FINE_NODES`, `SORA_SET_FIRST_PANELS`,
    /// `SORA_SET_VIEW_PANELS` (the first order's fine nodes and panels, the
    /// view ray's panels; the defaults), `SORA_SET_PATHS` (200000; 0: the library alone),
    /// `SORA_SET_ORDERS` (the tracer's largest number of interactions, 0:
    /// all), `SORA_SET_LIB_ORDERS` (the library's field stopped after
    /// this many orders less one, 0: all), `SORA_SET_SHIFT_PIECES` (the
    /// most pieces of each path the field's after-sunset shift is taken
    /// in, 1) and `SORA_SET_SHIFT_SPREAD` (deg of the path's angle's
    /// spread per piece, `SHIFT_PIECE_SPREAD_DEG`; 0: every path in the
    /// most; `FieldRequest::shift_pieces`), `SORA_SET_SEED` (1).
    #[test]
    #[ignore]
    fn probe_segment_parts_against_the_tracer() {
        use crate::transport::multiple_scattering::MultipleScatteringSettings;
        let env = |name: &str, default: &str| std::env::var(name).unwrap_or(default.into());
        let list = |name: &str, default: &str| -> Vec<f64> {
            env(name, default)
                .split(',')
                .map(|v| {
                    if v == "inf" {
                        f64::INFINITY
                    } else {
                        v.parse().unwrap()
                    }
                })
                .collect()
        };
        let preset = env("SORA_SET_PRESET", "earth-hazy");
        let mut atmosphere = if preset.ends_with(".toml") {
            Atmosphere::from_toml_str(&std::fs::read_to_string(&preset).unwrap()).unwrap()
        } else {
            Atmosphere::preset(&preset).unwrap()
        };
        if let Ok(albedo) = std::env::var("SORA_SET_ALBEDO") {
            let albedo = crate::spectrum::Spectrum::Constant(albedo.parse().unwrap());
            atmosphere.planet = atmosphere.planet.with_ground_albedo(albedo).unwrap();
        }
        let nm = list("SORA_SET_NM", "440,680,120");
        let grid = WavelengthGrid::new(nm[0], nm[1], nm[2]).unwrap();
        let polarisation: Polarisation = env("SORA_SET_POLARISATION", "scalar").parse().unwrap();
        // Each setting from its variable, the default's where it is unset.
        let default = MultipleScatteringSettings::default();
        let setting =
            |name: &str, value: usize| -> usize { env(name, &value.to_string()).parse().unwrap() };
        let settings = MultipleScatteringSettings {
            streams_per_hemisphere: setting("SORA_SET_STREAMS", default.streams_per_hemisphere),
            layers: setting("SORA_SET_LAYERS", default.layers),
            sunset_sun_zenith_step_deg: env(
                "SORA_SET_SUN_STEP",
                &default.sunset_sun_zenith_step_deg.to_string(),
            )
            .parse()
            .unwrap(),
            first_order_fine_nodes: setting("SORA_SET_FINE_NODES", default.first_order_fine_nodes),
            first_order_panels: setting("SORA_SET_FIRST_PANELS", default.first_order_panels),
            view_ray_panels: setting("SORA_SET_VIEW_PANELS", default.view_ray_panels),
            ..default
        };
        let paths: u64 = env("SORA_SET_PATHS", "200000").parse().unwrap();
        let orders: u32 = env("SORA_SET_ORDERS", "0").parse().unwrap();
        let seed: u64 = env("SORA_SET_SEED", "1").parse().unwrap();
        let lib_orders: usize = env("SORA_SET_LIB_ORDERS", "0").parse().unwrap();
        // The pieces' most and spread per piece (deg), as the settings'
        // `twilight_shift_pieces` takes them.
        let spread = crate::transport::multiple_scattering::SHIFT_PIECE_SPREAD_DEG;
        let default_pieces = (1, spread);
        let shift_pieces: (usize, f64) = (
            env("SORA_SET_SHIFT_PIECES", "1").parse().unwrap(),
            env("SORA_SET_SHIFT_SPREAD", &spread.to_string())
                .parse()
                .unwrap(),
        );
        let views: Vec<(f64, f64)> = env("SORA_SET_VIEWS", "-10,0")
            .split(';')
            .map(|p| {
                let n: Vec<f64> = p.split(',').map(|x| x.parse().unwrap()).collect();
                (n[0], n[1])
            })
            .collect();
        for eye in list("SORA_SET_EYES", "3000") {
            for sun in list("SORA_SET_SUNS", "-2") {
                let sky = Sky::builder(&atmosphere)
                    .sun_deg(sun, 180.0)
                    .observer_altitude_m(eye)
                    .wavelengths(grid)
                    .polarisation(polarisation)
                    .scattering(Scattering::Multiple(settings))
                    .build()
                    .unwrap();
                if lib_orders >= 2 || shift_pieces != default_pieces {
                    use crate::transport::multiple_scattering::{
                        FieldRequest, MultipleScatteringField,
                    };
                    let default = FieldRequest::new(settings, sky.table_size.sun_column_nodes);
                    let request = FieldRequest {
                        sweeps: match lib_orders {
                            0 => default.sweeps,
                            n => n - 1,
                        },
                        shift_pieces,
                        polarised: polarisation == Polarisation::Vector,
                        ..default
                    };
                    let field = MultipleScatteringField::solve(&sky.scene, &request).unwrap();
                    let _ = sky.field.set(std::sync::Arc::new(field));
                }
                for (elevation, azimuth) in &views {
                    let view = ViewDirection::new(*elevation, 180.0 + azimuth).unwrap();
                    for d in list("SORA_SET_DISTANCES", "1000") {
                        let (fast, _) = air(&sky, view, d);
                        let [single, own, field, peak, _] =
                            sky.segment_term_parts(view.to_vector(), d);
                        let traced = (paths > 0).then(|| {
                            let tracer = match polarisation {
                                Polarisation::Scalar => PathTracer::new(&sky.scene),
                                Polarisation::Vector => {
                                    PathTracer::new_polarised(&sky.scene).unwrap()
                                }
                            }
                            .with_target_distance(d);
                            let tracer = if orders > 0 {
                                tracer.with_max_interactions(orders)
                            } else {
                                tracer
                            };
                            tracer
                                .compute_stokes_with_progress(
                                    view.to_vector(),
                                    meridian_reference(view.elevation_deg(), view.azimuth_deg()),
                                    paths,
                                    seed,
                                    &|_| {},
                                )
                                .unwrap()
                        });
                        for (i, lambda) in sky.wavelengths().wavelengths_nm().enumerate() {
                            let f = fast.radiance_w_m2_sr_nm[i];
                            let mut line = format!(
                                "eye {eye} sun {sun} view ({elevation},{azimuth}) d {d} {lambda:.0} nm: fast {f:.4e} [single {:.3e} own {:.3e} field {:.3e} peak {:.3e}]",
                                single[i], own[i], field[i], peak[i]
                            );
                            if let Some(t) = &traced {
                                let (total, error) = match &t.stokes {
                                    Some([s, ..]) => (s.mean[i], s.standard_error[i]),
                                    None => (t.total.mean[i], t.total.standard_error[i]),
                                };
                                line += &format!(
                                    " traced {total:.4e} +- {:.2} % [single {:.3e} +- {:.3e} multiple {:.3e} +- {:.3e}] fast/traced - 1 {:+.2} %",
                                    100.0 * error / total,
                                    t.single_scattering.mean[i],
                                    t.single_scattering.standard_error[i],
                                    t.multiple_scattering.mean[i],
                                    t.multiple_scattering.standard_error[i],
                                    100.0 * (f / total - 1.0)
                                );
                            }
                            eprintln!("{line}");
                        }
                    }
                }
            }
        }
    }
}
