//! The [`Sky`] itself: its parts, how it is made from a scene on its grid,
//! what it tells of itself, and the expensive parts it builds on first use
//! and keeps (the multiple-scattering field, its source table and the fast
//! method's image tables).

use super::options::{
    FastTableSize, MAX_REFERENCE_MARCH_STEPS, MAX_REFERENCE_STEPS, Method, Polarisation, Scattering,
};

use std::sync::{Arc, OnceLock};

use crate::atmosphere::AtmosphereOptics;
use crate::error::{Error, Result};
use crate::geometry::{Vector3, ViewDirection};
use crate::spectrum::{SampledSpectrum, WavelengthGrid};
use crate::transport::multiple_scattering::{
    FieldRequest, MultipleScatteringField, MultipleScatteringTable, PolarisationTable,
};
use crate::transport::sky_view_table::MarchedRows;
use crate::transport::{PathTracer, SingleScatteringScene, SkyViewTable, SunColumns};

/// A sky: an atmosphere on a wavelength grid, the sun, the eye, and the
/// choice of physics and method (see the module docs).
#[derive(Debug)]
pub struct Sky {
    pub(super) scene: SingleScatteringScene,
    /// Sun elevation and azimuth, degrees.
    pub(super) sun_position_deg: (f64, f64),
    pub(super) scattering: Scattering,
    pub(super) method: Method,
    pub(super) table_size: FastTableSize,
    pub(super) polarisation: Polarisation,
    /// The multiple-scattering field over every sun zenith angle the eye's
    /// rays meet (built on first use).
    pub(super) field: OnceLock<Arc<MultipleScatteringField>>,
    /// The field's source table, for images (built on first use).
    pub(super) source_table: OnceLock<MultipleScatteringTable>,
    /// The fast method's image tables (built on first use).
    pub(super) image_tables: OnceLock<ImageTables>,
    /// The tables many views are read from: the image tables' kinds, with
    /// a source table at half the steps (built on first use; see
    /// [`Sky::view_tables`]).
    pub(super) view_tables: OnceLock<ImageTables>,
    /// The polarisation correction's table (built on first use; see
    /// [`Sky::polarisation_table`]).
    pub(super) polarisation_table: OnceLock<Option<Arc<PolarisationTable>>>,
    /// The sky-view table marches multiply scattered light at every this
    /// many nodes of its zenith and azimuth axes ([`IMAGE_MULTIPLE_STRIDE`]
    /// for images).
    pub(super) multiple_stride: (usize, usize),
    /// The zenith rows its sky-view table marches (every one for images).
    pub(super) sky_view_rows: MarchedRows,
    /// Views no lower than this (rad) only: the field is solved for the
    /// sun angles their rays meet (`Sky::for_views_above`), and other
    /// views and images are refused.
    pub(super) lowest_view_elevation_rad: Option<f64>,
    /// The k-distribution's terms, (w_j, the sky of term j), with banded
    /// gases; empty without them (`sky/k_terms.rs`).
    pub(super) k_terms: Vec<(SampledSpectrum, Sky)>,
    /// Per entry of `k_terms`: whether exact views take it as it is (a
    /// term that leaves out its higher orders somewhere is taken from
    /// `view_terms` instead; `sky/k_terms.rs`).
    pub(super) k_terms_for_views: Vec<bool>,
    /// The runs of samples, with and without their higher orders, of the
    /// terms that exact views do not take from `k_terms`.
    pub(super) view_terms: Vec<(SampledSpectrum, Sky)>,
    /// Built for colour images alone (`SkyBuilder::for_colour_images`):
    /// its terms are folded where colour allows, so spectral images are
    /// refused.
    pub(super) colour_only: bool,
}

#[derive(Debug)]
pub(super) struct ImageTables {
    pub(super) sky_view: SkyViewTable,
    /// The polarisation correction's ratios over view directions
    /// (polarised skies with multiple scattering).
    /// One table per sky, shared by the image and the view tables
    /// ([`Sky::polarisation_table`]).
    pub(super) polarisation: Option<Arc<PolarisationTable>>,
}

/// Nodes of the polarisation table (per half of the zenith-cosine axis,
/// azimuth over 0..180 degrees). Images against the per-view Stokes
/// vectors (`tests/polarisation.rs`, luminance-weighted): the degree of
/// polarisation within 3.6e-4 (us-standard, sun 30) and 6.2e-4
/// (earth-clear, sun 8) at 24 x 48 nodes, against 1.2e-3 at 16 x 48 and
/// 3e-4 at 32 x 64; the table costs about a third of a polarised image's
/// precomputation.
const POLARISATION_TABLE_NODES: (usize, usize) = (24, 48);

/// The images' sky-view table marches multiply scattered light at every
/// other node of each axis (`transport/sky_view_table.rs`).
pub(super) const IMAGE_MULTIPLE_STRIDE: (usize, usize) = (2, 2);

impl Sky {
    /// A sky from a scene already on its grid (optics, planet, eye, sun).
    pub(crate) fn from_scene(
        scene: SingleScatteringScene,
        scattering: Scattering,
        method: Method,
        table_size: FastTableSize,
    ) -> Result<Sky> {
        if let Scattering::Multiple(settings) = scattering {
            settings.validate()?;
        }
        match method {
            Method::Fast => {}
            Method::Reference {
                view_steps,
                sun_steps,
            } => {
                for (name, steps) in [("view steps", view_steps), ("sun steps", sun_steps)] {
                    if !(1..=MAX_REFERENCE_STEPS).contains(&steps) {
                        return Err(Error::out_of_range(name, steps as f64, "1", "1..=1e7"));
                    }
                }
                let march = view_steps as f64 * sun_steps as f64;
                if march > MAX_REFERENCE_MARCH_STEPS {
                    return Err(Error::out_of_range(
                        "view steps x sun steps",
                        march,
                        "1",
                        format!(
                            "<= {MAX_REFERENCE_MARCH_STEPS:e} (seconds a view; the default is 1000 x 250)"
                        ),
                    ));
                }
            }
            Method::PathTracing { samples, .. } => {
                if samples < 2 {
                    return Err(Error::out_of_range(
                        "samples",
                        samples as f64,
                        "1",
                        ">= 2 (a standard error needs two paths)",
                    ));
                }
                if scattering == Scattering::Single {
                    return Err(Error::Unsupported(
                        "path tracing computes all orders of scattering: it takes Scattering::Multiple, not Single".into(),
                    ));
                }
            }
        }
        let ((a, m), (z, az)) = (table_size.sun_column_nodes, table_size.sky_view_nodes);
        for (name, nodes) in [
            ("sun-column table altitude nodes", a),
            ("sun-column table mu nodes", m),
            ("sky-view table zenith nodes", z),
            ("sky-view table azimuth nodes", az),
        ] {
            if !(2..=100_000).contains(&nodes) {
                return Err(Error::out_of_range(name, nodes as f64, "1", "2..=100000"));
            }
        }
        Ok(Sky {
            sun_position_deg: crate::geometry::elevation_azimuth_from_direction(
                scene.sun_direction(),
            ),
            scene,
            scattering,
            method,
            table_size,
            polarisation: Polarisation::Scalar,
            field: OnceLock::new(),
            source_table: OnceLock::new(),
            image_tables: OnceLock::new(),
            view_tables: OnceLock::new(),
            polarisation_table: OnceLock::new(),
            multiple_stride: IMAGE_MULTIPLE_STRIDE,
            sky_view_rows: MarchedRows::EVERY,
            lowest_view_elevation_rad: None,
            k_terms: Vec::new(),
            k_terms_for_views: Vec::new(),
            view_terms: Vec::new(),
            colour_only: false,
        })
    }

    /// This sky with the sun at `elevation_deg`, `azimuth_deg`: the optics
    /// (Mie ensembles included) are reused, the sun-dependent tables and
    /// field are built anew on first use (for sequences of frames).
    pub fn with_sun_deg(&self, elevation_deg: f64, azimuth_deg: f64) -> Result<Sky> {
        let scene = self.scene.with_sun(elevation_deg, azimuth_deg)?;
        let mut sky = Sky::from_scene(scene, self.scattering, self.method, self.table_size)?;
        sky.sun_position_deg = (
            elevation_deg,
            crate::geometry::azimuth_in_one_turn_deg(azimuth_deg),
        );
        sky.set_polarisation(self.polarisation)?;
        let at_sun = |terms: &[(SampledSpectrum, Sky)]| {
            terms
                .iter()
                .map(|(w, term)| Ok((w.clone(), term.with_sun_deg(elevation_deg, azimuth_deg)?)))
                .collect::<Result<Vec<_>>>()
        };
        sky.k_terms = at_sun(&self.k_terms)?;
        sky.k_terms_for_views = self.k_terms_for_views.clone();
        sky.view_terms = at_sun(&self.view_terms)?;
        sky.colour_only = self.colour_only;
        Ok(sky)
    }

    /// This sky for views of `views`' elevations and higher only (all at
    /// or above the horizon): the field is solved for the sun angles their
    /// rays meet, not for every point the eye sees, which at a low sun
    /// is many times cheaper (`MultipleScatteringField::compute_for_views_above`).
    /// Lower views and images are then an error. For a retrieval's forward
    /// model, which asks one sky for one set of views.
    pub(crate) fn for_views_above(mut self, views: &[ViewDirection]) -> Sky {
        let lowest = views
            .iter()
            .map(|v| v.elevation_deg())
            .fold(90.0f64, f64::min)
            .max(0.0);
        self.lowest_view_elevation_rad = Some(lowest.to_radians());
        let above = |terms: Vec<(SampledSpectrum, Sky)>| {
            terms
                .into_iter()
                .map(|(w, term)| (w, term.for_views_above(views)))
                .collect()
        };
        self.k_terms = above(std::mem::take(&mut self.k_terms));
        self.view_terms = above(std::mem::take(&mut self.view_terms));
        self
    }

    /// An error if the field was restricted to views above some elevation
    /// and `elevation_deg` (a view's; None for an image) is not one of them.
    pub(super) fn check_within_restricted_field(&self, elevation_deg: Option<f64>) -> Result<()> {
        match (self.lowest_view_elevation_rad, elevation_deg) {
            (None, _) => Ok(()),
            (Some(lowest), Some(e)) if e.to_radians() >= lowest - 1e-12 => Ok(()),
            (Some(lowest), _) => Err(Error::Unsupported(format!(
                "this sky's multiple-scattering field was solved for views {:.4} degrees or more above the horizon only",
                lowest.to_degrees()
            ))),
        }
    }

    /// Checks that the method can follow `polarisation` and keeps it.
    pub(super) fn set_polarisation(&mut self, polarisation: Polarisation) -> Result<()> {
        if polarisation == Polarisation::Vector {
            match (self.method, self.scattering) {
                (Method::PathTracing { .. }, _) | (Method::Fast, _) => {}
                (Method::Reference { .. }, _) => {
                    return Err(Error::Unsupported(
                        "polarisation: Stokes vectors come from the path tracer (method path-tracing) or the fast method; the reference march is scalar".into(),
                    ));
                }
            }
            PathTracer::new_polarised(&self.scene)?;
        }
        self.polarisation = polarisation;
        Ok(())
    }

    /// The scene (optics, planet, eye, sun) this sky is built on.
    pub(crate) fn scene(&self) -> &SingleScatteringScene {
        &self.scene
    }

    /// The resolution of the fast method's image tables.
    pub(crate) fn table_size(&self) -> FastTableSize {
        self.table_size
    }

    /// The wavelengths of every spectrum the sky returns.
    pub fn wavelengths(&self) -> &WavelengthGrid {
        &self.scene.optics().grid
    }

    /// The atmosphere's optics on the grid (per species: coefficients,
    /// phase functions; the sun; the ground albedo).
    pub fn optics(&self) -> &AtmosphereOptics {
        self.scene.optics()
    }

    /// Unit vector toward the sun, east-north-up.
    pub(crate) fn sun_direction(&self) -> Vector3 {
        self.scene.sun_direction()
    }

    /// The transmittance of the direct beam from the top of the atmosphere
    /// to the eye toward the sun's centre (0 where the planet is in the way).
    pub fn direct_beam_transmittance(&self) -> SampledSpectrum {
        if !self.k_terms.is_empty() {
            return self.sum_term_spectra(Sky::direct_beam_transmittance);
        }
        let mut transmittance = SampledSpectrum::zeros(self.wavelengths().len());
        let sun = self.sun_direction();
        if self.scene.sees_sky(sun) {
            let mut scratch = self.scene.scratch();
            self.scene
                .compute_inscattering_integrals(sun, SunColumns::Exact, &mut scratch);
            transmittance
                .values_mut()
                .copy_from_slice(scratch.view_transmittance());
        }
        transmittance
    }

    /// The direct normal irradiance, E_sun T, W m^-2 nm^-1.
    pub fn direct_normal_irradiance(&self) -> SampledSpectrum {
        let mut direct = self.direct_beam_transmittance();
        for (d, e) in direct
            .values_mut()
            .iter_mut()
            .zip(self.optics().solar_irradiance_w_m2_nm.values())
        {
            *d *= e;
        }
        direct
    }

    /// The sun's elevation above the horizon and azimuth clockwise from
    /// north, degrees (as given to the builder, the azimuth read modulo
    /// 360 into `[0, 360)`).
    pub fn sun_position_deg(&self) -> (f64, f64) {
        self.sun_position_deg
    }

    /// The orders of scattering and the method.
    pub fn scattering(&self) -> Scattering {
        self.scattering
    }

    /// The method.
    pub fn method(&self) -> Method {
        self.method
    }

    /// Scalar or vector light.
    pub fn polarisation(&self) -> Polarisation {
        self.polarisation
    }

    /// For a polarised sky, the species that scatter light with a
    /// parametric phase function (isotropic, Henyey-Greenstein,
    /// Cornette-Shanks) as (name, phase function kind): they have no phase
    /// matrix, so the Stokes vectors treat them as non-polarising
    /// (F12 = F34 = 0, F33 = F44 = F11), what front ends warn about.
    /// Empty for a scalar sky.
    pub fn non_polarising_species(&self) -> Vec<(&str, &'static str)> {
        if self.polarisation != Polarisation::Vector {
            return Vec::new();
        }
        self.optics()
            .species
            .iter()
            .filter(|s| {
                s.scattering_per_m.values().iter().any(|b| *b > 0.0)
                    && !s.phase_function.is_polarising()
            })
            .map(|s| (s.name.as_str(), s.phase_function.kind()))
            .collect()
    }

    /// [`Sky::prepare_field`] for images and the image tables, which need
    /// the field of every direction (an error for a field restricted to
    /// views above some elevation).
    pub(super) fn prepare_field_for_images(&self) -> Result<()> {
        self.check_within_restricted_field(None)?;
        self.prepare_field()
    }

    /// Solves the multiple-scattering field if the sky has one and it is
    /// not solved yet. Every entry point calls it before its parallel loop:
    /// a worker that stole work inside the (parallel) solve must not find
    /// the field half-made, and the loops read it with [`Sky::field`].
    pub(super) fn prepare_field(&self) -> Result<()> {
        if let Scattering::Multiple(settings) = self.scattering {
            if self.field.get().is_none() {
                // The first order and the peak beam share the image tables'
                // sun-column table (see `FieldRequest::sun_column_nodes`).
                let request = FieldRequest {
                    polarised: self.polarisation == Polarisation::Vector,
                    lowest_view_elevation_rad: self.lowest_view_elevation_rad,
                    ..FieldRequest::new(settings, self.table_size.sun_column_nodes)
                };
                let field = MultipleScatteringField::solve(&self.scene, &request)?;
                // Another thread may have been first: either field is the same.
                let _ = self.field.set(Arc::new(field));
            }
        }
        Ok(())
    }

    /// The multiple-scattering field ([`Sky::prepare_field`] has run).
    pub(super) fn field(&self) -> Option<&MultipleScatteringField> {
        debug_assert!(self.scattering == Scattering::Single || self.field.get().is_some());
        self.field.get().map(Arc::as_ref)
    }

    /// The field's source table, built on first use.
    pub(super) fn source_table(&self) -> Option<&MultipleScatteringTable> {
        let field = self.field.get()?;
        Some(
            self.source_table
                .get_or_init(|| MultipleScatteringTable::compute(Arc::clone(field))),
        )
    }

    /// The multiple-scattering source table (prototype measurements,
    /// `engine_tables` tests), the field solved first.
    #[cfg(test)]
    pub(crate) fn source_table_for_tests(&self) -> Option<&MultipleScatteringTable> {
        self.prepare_field().unwrap();
        self.source_table()
    }

    /// The fast method's image tables, built on first use.
    pub(super) fn image_tables(&self) -> &ImageTables {
        self.image_tables
            .get_or_init(|| self.compute_tables(self.source_table(), true))
    }

    /// The tables that many views are read from ([`Sky::radiances`] from
    /// [`super::TABLE_VIEW_COUNT`] views), built on first use: the image
    /// tables' kinds and sizes, with the multiply scattered light marched
    /// through a source table at half the steps of the settings' (73 x 37
    /// nodes by default, 2.5 and 5 degrees). The image tables' source
    /// table alone put a view 2.5 degrees up near the sun's azimuth 1.2e-3
    /// below the exact field's light (earth-clear, 440 nm; 4e-5 at half the
    /// steps), and its kinks in azimuth more than doubled the sky-view
    /// table's error between its nodes (`docs/polarisation.md`). It costs
    /// three to five times the image tables' source table (measured at
    /// suns 30 and 5), which images would pay for every frame.
    pub(super) fn view_tables(&self) -> &ImageTables {
        self.view_tables.get_or_init(|| {
            let source = self
                .field
                .get()
                .map(|field| MultipleScatteringTable::compute_at_half_steps(Arc::clone(field)));
            self.compute_tables(source.as_ref(), true)
        })
    }

    /// The sky-view table from `source` (None: single scattering) and the
    /// polarisation table (polarised skies with multiple scattering), at
    /// the sky's table sizes; with `march_multiple` false the sky-view
    /// table's multiply scattered light is left zero (for
    /// `SkyViewTable::blend_multiple_from`).
    pub(super) fn compute_tables(
        &self,
        source: Option<&MultipleScatteringTable>,
        march_multiple: bool,
    ) -> ImageTables {
        let mut tables = Sky::compute_tables_together(&[(self, source)], march_multiple);
        tables.pop().expect("one sky's tables")
    }

    /// [`Sky::compute_tables`] of each of `skies` (a sky and its source
    /// table), which have the same table sizes: their sky-view tables
    /// built node by node together, the skies whose view rays and
    /// sun-column table are the first's reading its columns toward the sun
    /// (`SkyViewTable::compute_sharing_geometry`), bit for bit the tables
    /// each builds alone.
    pub(super) fn compute_tables_together(
        skies: &[(&Sky, Option<&MultipleScatteringTable>)],
        march_multiple: bool,
    ) -> Vec<ImageTables> {
        let Some((first, _)) = skies.first() else {
            return Vec::new();
        };
        let sizes = (first.table_size, first.multiple_stride, first.sky_view_rows);
        assert!(
            skies
                .iter()
                .all(|(sky, _)| (sky.table_size, sky.multiple_stride, sky.sky_view_rows) == sizes),
            "skies built together share their table sizes"
        );
        let (altitude_nodes, mu_nodes) = first.table_size.sun_column_nodes;
        let sun_columns: Vec<_> = skies
            .iter()
            .map(|(sky, _)| sky.scene.sun_column_table(altitude_nodes, mu_nodes))
            .collect();
        let entries: Vec<_> = skies
            .iter()
            .zip(&sun_columns)
            .map(|((sky, source), columns)| (&sky.scene, columns.as_ref(), *source))
            .collect();
        SkyViewTable::compute_sharing_geometry(
            &entries,
            first.table_size.sky_view_nodes,
            (first.multiple_stride, first.sky_view_rows),
            march_multiple,
        )
        .into_iter()
        .zip(skies)
        .map(|(sky_view, (sky, _))| ImageTables {
            sky_view,
            polarisation: sky.polarisation_table(),
        })
        .collect()
    }

    /// The polarisation correction's ratios over view directions (polarised
    /// skies with multiple scattering), built on first use: it depends on
    /// the field only, so images and many views share it.
    fn polarisation_table(&self) -> Option<Arc<PolarisationTable>> {
        self.polarisation_table
            .get_or_init(|| {
                self.field()
                    .and_then(|field| field.compute_polarisation_table(POLARISATION_TABLE_NODES))
                    .map(Arc::new)
            })
            .clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::Atmosphere;

    /// A field solved only for the sun angles an almucantar's rays meet
    /// gives the almucantar of the field solved for everything the eye
    /// sees (its sun nodes are the same near the eye's sun, its tilted
    /// peak beam too where those rays meet it), and refuses
    /// lower views and images.
    #[test]
    fn a_field_for_some_views_gives_their_radiances_and_refuses_others() {
        let atmosphere = Atmosphere::preset("earth-clear").unwrap();
        // 15 degrees: the restricted field needs no tilted peak beam (its
        // rays' points see the sun 12 degrees up or more); 10: a part of
        // the full field's (`PeakBeam::needed_elevations_deg`).
        for sun_elevation_deg in [30.0, 15.0, 10.0] {
            let views: Vec<ViewDirection> = [4.0, 10.0, 30.0, 90.0, 150.0, 180.0]
                .iter()
                .map(|a| ViewDirection::new(sun_elevation_deg, 180.0 + a).unwrap())
                .collect();
            let sky = || {
                Sky::builder(&atmosphere)
                    .sun_deg(sun_elevation_deg, 180.0)
                    .wavelengths(WavelengthGrid::new(440.0, 870.0, 430.0).unwrap())
                    .polarisation(crate::Polarisation::Scalar)
                    .build()
                    .unwrap()
            };
            let full = sky().radiances(&views).unwrap();
            let restricted_sky = sky().for_views_above(&views);
            let restricted = restricted_sky.radiances(&views).unwrap();
            for (f, r) in full.iter().zip(&restricted) {
                for (a, b) in f
                    .radiance_w_m2_sr_nm
                    .values()
                    .iter()
                    .zip(r.radiance_w_m2_sr_nm.values())
                {
                    assert!(
                        (a / b - 1.0).abs() < 1e-6,
                        "sun {sun_elevation_deg}: {a} {b}"
                    );
                }
            }
            let lower = ViewDirection::new(sun_elevation_deg - 1.0, 0.0).unwrap();
            assert!(restricted_sky.radiance(lower).is_err());
            assert!(restricted_sky.prepare_images().is_err());
        }
    }
}
