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
//! ([`super::ViewTerms`]: single scattering, the scaled field's light, the
//! forward-peak term) with the segment ending at min(d, where the ray
//! leaves the atmosphere or meets the ground), L_seg. The ground's terms
//! (its sunlit and skylit light) are left out of it: the point is the
//! scene's, and a ray that reaches the ground before d ends there.
//!
//! The point is a point (a black target, as the path tracer that checks
//! this has it): light from behind it that the segment's aerosol scatters
//! into its forward peak still reaches the eye around it. The delta-M
//! field counts that light as unscattered, through the scaled
//! transmittance T* > T, so the sky is L_sky = L_seg + T* L_behind, of
//! which the point hides T L_behind:
//!
//! ```text
//! L_air = L_sky - (T / T*) (L_sky - L_seg)
//! ```
//!
//! (the whole view's radiance is marched too, so a segment costs two
//! views). L_behind is taken at the view's own direction: toward the sun,
//! where it is the aureole's peak, that overestimates the light the peak
//! scatters around the point (9.5-11.9 % too bright at 1 km looking
//! straight at a sun 10 degrees up through earth-hazy; docs/aerial_perspective.md). Without it haze toward a low sun is too dark by the halo: 5.6 %
//! at 680 nm for earth-hazy, sun 10 degrees, a view 5 degrees up toward
//! it, 10 km. L_air tends to the sky's radiance as d grows (exactly, to
//! the last bit, once d passes the ray's end) and to zero as d shrinks. T
//! is the exact Beer-Lambert transmittance of the real (not delta-M
//! scaled) extinction, from the columns of the march.
//!
//! What lights the point itself, for shading it: the sun's transmittance
//! from the top of the atmosphere to the point (exact columns; zero in the
//! planet's shadow), and the sky's diffuse irradiance on a horizontal
//! plane. The latter is computed at the eye ([`Sky::irradiance`]) and
//! stands in for the point's: exact for a point at the eye's altitude and
//! sun, while over a curved planet the sun's elevation at a point d away is
//! up to d / R rad different (0.45 degrees at 50 km on Earth).
//!
//! Units: radiance W m^-2 sr^-1 nm^-1, irradiance W m^-2 nm^-1,
//! transmittances 1, distances m; spectra on the sky's wavelength grid.
//! Methods: [`Method::Fast`] (the field synthesised exactly along the
//! segment) and [`Method::PathTracing`] (a black target at d that ends the
//! paths reaching it, with standard errors); the reference march has no
//! segment and is an error.

use super::{
    ImageSettings, Method, Polarisation, Sky, SkyRadiance, meridian_reference,
    sky_radiance_from_values,
};
use crate::colour::{SpectrumToXyz, Xyz};
use crate::error::{Error, Result};
use crate::geometry::{Vector3, ViewDirection, segment_in_atmosphere};
use crate::spectrum::SampledSpectrum;
use crate::transport::multiple_scattering::PolarisationRows;
use crate::transport::path_tracing::PathTracer;

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
    /// The sky's diffuse irradiance on a horizontal plane, W m^-2 nm^-1,
    /// computed at the eye (see the module docs).
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
        let irradiance = self.irradiance(super::Plane::HORIZONTAL)?.diffuse_w_m2_nm;
        self.compute_aerial_perspectives(segments, &irradiance)
    }

    /// [`Sky::aerial_perspectives`] of checked segments, with the sky's
    /// irradiance `irradiance`.
    fn compute_aerial_perspectives(
        &self,
        segments: &[(ViewDirection, f64)],
        irradiance: &SampledSpectrum,
    ) -> Result<Vec<AerialPerspective>> {
        let wavelengths = self.wavelengths().len();
        let mut scratch = self.scene.scratch();
        Ok(segments
            .iter()
            .zip(self.compute_segment_light(segments)?)
            .map(|((view, distance_m), (radiance, transmittance))| {
                let (length, end) = self.segment_end(view.to_vector(), *distance_m);
                let mut sun = vec![0.0; wavelengths];
                self.scene.compute_sun_transmittance_at(
                    end,
                    crate::transport::single_scattering::SunColumns::Exact,
                    &mut scratch,
                    &mut sun,
                );
                AerialPerspective {
                    distance_m: length,
                    radiance,
                    transmittance,
                    sun_transmittance_at_point: SampledSpectrum::from_values(sun),
                    sky_irradiance_at_point: irradiance.clone(),
                }
            })
            .collect())
    }

    /// The light of the air along each checked segment (W m^-2 sr^-1
    /// nm^-1) and the segment's transmittance: what an image needs, and
    /// what [`Sky::compute_aerial_perspectives`] adds the point's light to.
    fn compute_segment_light(
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
            for (w, term) in &self.k_terms {
                parts.push((
                    *w,
                    term.render_aerial_perspective_xyz(image, depth_m, to_xyz)?,
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

    /// The fast method's light of the air along each segment.
    fn compute_segment_radiances(
        &self,
        segments: &[(ViewDirection, f64)],
    ) -> Result<Vec<SkyRadiance>> {
        self.prepare_field()?;
        const SEGMENTS_PER_TASK: usize = 4;
        let wavelengths = self.wavelengths().len();
        let polarised = self.polarisation == Polarisation::Vector;
        let per_view = wavelengths * if polarised { 4 } else { 1 };
        let rows = self.polarisation_rows(segments.iter().map(|(view, _)| view));
        let mut values = vec![0.0; segments.len() * per_view];
        crate::parallel::for_each_chunk_mut(
            &mut values,
            SEGMENTS_PER_TASK * per_view,
            |task, chunk| {
                let mut work = self.view_work();
                let mut whole = vec![0.0; per_view];
                let mut hidden = vec![0.0; wavelengths];
                let mut scaled = vec![0.0; wavelengths];
                for (k, out) in chunk.chunks_mut(per_view).enumerate() {
                    let (view, distance_m) = segments[task * SEGMENTS_PER_TASK + k];
                    // The whole view's light (the sky's radiance), then the
                    // segment's own.
                    self.compute_segment_values(
                        (view, f64::INFINITY),
                        true,
                        rows.as_ref(),
                        &mut work,
                        &mut whole,
                    );
                    self.compute_segment_values(
                        (view, distance_m),
                        false,
                        rows.as_ref(),
                        &mut work,
                        out,
                    );
                    // The light from behind the point that the segment's
                    // forward peaks scatter toward the eye: behind the
                    // point, L_behind = (L_sky - L_segment) / T*, of which
                    // T reaches the eye unscattered (what the point hides)
                    // and T* - T by the peaks (what the scaled field
                    // counts as unscattered).
                    hidden.copy_from_slice(work.single.view_transmittance());
                    if let (Some(field), Some(scratch)) = (self.field(), work.multiple.as_ref()) {
                        field.scaled_transmittance_of_last_ray(scratch, &mut scaled);
                        for (h, t) in hidden.iter_mut().zip(&scaled) {
                            *h = if *t > 0.0 { *h / t } else { 1.0 };
                        }
                    } else {
                        hidden.fill(1.0);
                    }
                    for (c, (o, w)) in out.iter_mut().zip(&whole).enumerate() {
                        *o = w - hidden[c % wavelengths] * (w - *o);
                    }
                }
            },
        );
        Ok(values
            .chunks(per_view)
            .map(|values| sky_radiance_from_values(values, wavelengths))
            .collect())
    }

    /// The light along the segment of `view` to `distance_m` (its
    /// radiance, then with polarisation Q, U, V) into `out`: the sky's
    /// terms, with the ground's only if `with_ground` (the ground is the
    /// point's where the segment ends on it).
    fn compute_segment_values(
        &self,
        (view, distance_m): (ViewDirection, f64),
        with_ground: bool,
        rows: Option<&PolarisationRows>,
        work: &mut super::ViewWork,
        out: &mut [f64],
    ) {
        let wavelengths = self.wavelengths().len();
        let (radiance, stokes) = out.split_at_mut(wavelengths);
        self.compute_view_terms((view.to_vector(), distance_m), None, work);
        if !with_ground {
            work.terms.ground_sunlit.fill(0.0);
            work.terms.ground_skylit.fill(0.0);
        }
        work.terms.add_into(radiance);
        if self.polarisation == Polarisation::Vector {
            self.compute_view_stokes(view, rows, work, radiance, stokes);
        }
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
                Ok(super::sky_radiance_from_traced(traced))
            })
            .collect()
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

    /// The segment's transmittance is exp(-tau) of an independent
    /// integration of the extinction along it, to 1e-6.
    #[test]
    fn the_transmittance_is_the_segments_beer_lambert() {
        for preset in ["earth-clear", "earth-hazy"] {
            let sky = build_sky(preset, 30.0, Scattering::Single, Method::Fast);
            for (elevation, distance) in [(1.0, 50e3), (0.5, 1e3), (5.0, 10e3), (30.0, 50e3)] {
                let view = ViewDirection::new(elevation, 90.0).unwrap();
                let ap = sky.aerial_perspective(view, distance).unwrap();
                assert_eq!(ap.distance_m, distance);
                for i in 0..sky.wavelengths().len() {
                    let expected =
                        (-independent_optical_depth(&sky, view.to_vector(), distance, i)).exp();
                    let got = ap.transmittance[i];
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
    /// the sky. (Not less than 1e-4: near the ground most of it is
    /// the light from behind the point that the aerosol's forward peak
    /// scatters around it, f beta_sca d L_sky; the test prints the largest
    /// share, measured 4.3e-4 over these views (3.3e-4 at the zenith on
    /// earth-clear, sun 10); see
    /// the module docs.)
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
                let far = sky.aerial_perspective(view, 1000e3).unwrap();
                let near = sky.aerial_perspective(view, 1.0).unwrap();
                let nearer = sky.aerial_perspective(view, 0.01).unwrap();
                for i in 0..sky.wavelengths().len() {
                    let l = radiance.radiance_w_m2_sr_nm[i];
                    let f = far.radiance.radiance_w_m2_sr_nm[i];
                    assert!(
                        (f / l - 1.0).abs() <= 1e-6,
                        "{preset} {elevation}: {f} vs {l}"
                    );
                    let n = near.radiance.radiance_w_m2_sr_nm[i];
                    let m = nearer.radiance.radiance_w_m2_sr_nm[i];
                    assert!(
                        m > 0.0 && (100.0 * m / n - 1.0).abs() < 0.02,
                        "{preset} {elevation}: 1 cm {m} vs 1 m {n}"
                    );
                    largest = largest.max(n / l);
                    assert!(
                        n > 0.0 && n < 1e-3 * l,
                        "{preset} {elevation}: 1 m {n} vs {l}"
                    );
                    assert!(near.transmittance[i] > 0.999 && near.transmittance[i] < 1.0);
                }
                if let (Some(a), Some(b)) = (&radiance.stokes, &far.radiance.stokes) {
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
                let ap = sky.aerial_perspective(view, distance).unwrap();
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
                    let got = ap.radiance.radiance_w_m2_sr_nm[i];
                    assert!(
                        (got / expected - 1.0).abs() <= 1e-3,
                        "{preset} azimuth {azimuth} d {distance} #{i}: {got} vs {expected}"
                    );
                }
            }
        }
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
        let expected = fast.aerial_perspectives(&segments).unwrap();
        let got = traced.aerial_perspectives(&segments).unwrap();
        let (mut failures, mut worst, mut worst_at) = (Vec::new(), 0.0f64, String::new());
        for (((view, d), e), g) in segments.iter().zip(&expected).zip(&got) {
            let errors = g.radiance.standard_error_w_m2_sr_nm.as_ref().unwrap();
            for i in 0..fast.wavelengths().len() {
                let (x, y) = (
                    e.radiance.radiance_w_m2_sr_nm[i],
                    g.radiance.radiance_w_m2_sr_nm[i],
                );
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
            assert_eq!(e.transmittance, g.transmittance);
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
        ] {
            let (failures, worst, at) =
                compare_with_path_tracer(preset, sun, &[view], &[distance], 40_000);
            eprintln!("worst {worst:.2} of the tolerance at {at}");
            all.extend(failures);
        }
        assert!(all.is_empty(), "{all:#?}");
    }

    /// The issue's grid (fails: see docs/aerial_perspective.md, the view
    /// straight at the sun is 9.5-11.9 % too bright at 1 km, every other
    /// value passes): earth-clear and earth-hazy, suns 60, 10, 2 and -4
    /// degrees, views 1, 10 and 30 degrees up (a view 0 degrees up from the
    /// ground is the ground's) at azimuths 0, 90 and 180
    /// from the sun, d = 1, 10 and 50 km (ignored: minutes).
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
}
