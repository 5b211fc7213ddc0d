//! One multiple-scattering field for the skies of every sun and eye
//! altitude of an atmosphere (the engine tables' bake, which draws
//! hundreds of them).
//!
//! A sky's field is solved at the sun zenith angles that its own view rays
//! meet, around its eye's (`FieldRequest::reach`). The columns of the
//! field do not depend on the eye or the sun, only on the sun zenith angle
//! they are solved at: solved once at every angle from 0 to where the
//! field is dark (`FieldRequest::every_sun`), with its source table, it is
//! aimed at each sky's eye and sun by moving the view march's eye and sun
//! only (`MultipleScatteringField::aimed`). The radiances differ from the
//! sky's own field by the interpolation between sun nodes that are not
//! placed at the sky's sun (measured in `engine_tables::tests`).

use std::sync::Arc;

use super::{Scattering, Sky};
use crate::error::Result;
use crate::transport::multiple_scattering::{
    FieldRequest, MultipleScatteringField, MultipleScatteringTable,
};
use crate::transport::single_scattering::SingleScatteringScene;
use crate::transport::sky_view_table::MarchedRows;

/// The layout of a sky's sky-view table (`transport/sky_view_table.rs`)
/// when it is not the images' own.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SkyViewGrid {
    /// Nodes per half of the zenith axis, and azimuth nodes.
    pub(crate) nodes: (usize, usize),
    /// The multiply scattered light is marched at every this many nodes of
    /// the zenith and azimuth axes, and filled in between.
    pub(crate) multiple_stride: (usize, usize),
    /// The zenith rows it marches (the others left zero and never read).
    pub(crate) rows: MarchedRows,
    /// Gauss panels of those marches along each view ray (None: the
    /// field's settings', `view_ray_panels`).
    pub(crate) multiple_panels: Option<usize>,
}

/// A field solved for every sun zenith angle, with its source table.
#[derive(Debug, Clone)]
pub(crate) struct SharedField {
    field: Arc<MultipleScatteringField>,
    table: MultipleScatteringTable,
}

impl SharedField {
    /// The field's diffuse irradiance on a horizontal plane at its levels
    /// and sun nodes (`MultipleScatteringField::downward_diffuse_flux`):
    /// the levels' altitudes (m), the sun nodes' zenith angles (rad) and
    /// the flux and (in it) the sunlight delta-M moved into the beam (W
    /// m^-2 nm^-1), each at [(s * levels + k) * wavelengths + i].
    pub(crate) fn downward_diffuse_flux(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        self.field.downward_diffuse_flux()
    }

    /// The source table of the field, for every sun.
    pub(crate) fn table(&self) -> &MultipleScatteringTable {
        &self.table
    }
}

impl Sky {
    /// The field of this sky's atmosphere, physics and image tables' size
    /// for every sun and eye (None for single scattering).
    pub(crate) fn solve_shared_field(&self) -> Result<Option<SharedField>> {
        let Scattering::Multiple(settings) = self.scattering else {
            return Ok(None);
        };
        let request = FieldRequest {
            every_sun: true,
            ..FieldRequest::new(settings, self.table_size.sun_column_nodes)
        };
        let field = Arc::new(MultipleScatteringField::solve(&self.scene, &request)?);
        let table = MultipleScatteringTable::compute(Arc::clone(&field));
        Ok(Some(SharedField { field, table }))
    }

    /// A scalar sky of this sky's physics and image tables' size on
    /// `scene` (the same atmosphere at another sun and eye) whose field is
    /// `shared` (from this atmosphere's [`Sky::solve_shared_field`]) aimed
    /// at its eye and sun, not solved anew; its sky-view table is laid out
    /// as `sky_view` says (None: this sky's own table, as its images have).
    pub(crate) fn with_shared_field(
        &self,
        scene: SingleScatteringScene,
        shared: Option<&SharedField>,
        sky_view: Option<SkyViewGrid>,
    ) -> Result<Sky> {
        let mut table_size = self.table_size();
        if let Some(grid) = sky_view {
            table_size.sky_view_nodes = grid.nodes;
        }
        let mut sky = Sky::from_scene(scene, self.scattering, self.method, table_size)?;
        if let Some(grid) = sky_view {
            sky.multiple_stride = grid.multiple_stride;
            sky.sky_view_rows = grid.rows;
        }
        if let Some(shared) = shared {
            let aimed = shared
                .field
                .aimed(sky.scene.observer_radius_m(), sky.scene.sun_direction());
            let field = Arc::new(match sky_view.and_then(|grid| grid.multiple_panels) {
                Some(panels) => aimed.with_view_ray_panels(panels),
                None => aimed,
            });
            let table = shared.table.aimed(Arc::clone(&field));
            // Fresh cells: neither can be set already.
            let _ = sky.field.set(field);
            let _ = sky.source_table.set(table);
        }
        Ok(sky)
    }

    /// Builds this scalar sky's image tables (from [`Sky::with_shared_field`])
    /// with the multiply scattered light of its sky-view table not marched
    /// but blended from two skies of the same atmosphere, eye and table
    /// layout with the sun at neighbouring elevations, `t` of the way from
    /// `neighbours.0` to `neighbours.1` (in the logarithm, or with
    /// `outer`, the skies one sun step beyond them, by the cubic through
    /// the four: `SkyViewTable::blend_multiple_from`; its single
    /// scattering and sunlit ground are its own). What the engine tables
    /// do at every other sun node from -6 to 70 degrees
    /// (`engine_tables`).
    pub(crate) fn blend_multiple_scattering_from(
        &self,
        neighbours: (&Sky, &Sky),
        outer: Option<(&Sky, &Sky)>,
        t: f64,
    ) -> Result<()> {
        debug_assert!(self.polarisation == super::Polarisation::Scalar);
        self.prepare_field_for_images()?;
        let (below, above) = (neighbours.0.image_tables(), neighbours.1.image_tables());
        let outer = outer.map(|(lowest, highest)| (lowest.image_tables(), highest.image_tables()));
        let mut tables = self.compute_tables(self.source_table(), false);
        tables.sky_view.blend_multiple_from(
            (&below.sky_view, &above.sky_view),
            outer.map(|(lowest, highest)| (&lowest.sky_view, &highest.sky_view)),
            t,
        );
        let fresh = self.image_tables.set(tables).is_ok();
        assert!(fresh, "the sky's image tables were built already");
        Ok(())
    }
}
