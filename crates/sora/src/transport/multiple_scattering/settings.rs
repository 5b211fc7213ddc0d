//! The multiple-scattering method's resolution: streams, layers, the
//! sun-node steps, the view ray's panels, the source table's nodes, the
//! twilight first order's quadrature and the wavelengths the polarisation
//! correction is solved at.

use super::spherical_first_order;
use crate::error::{Error, Result};

/// Resolution of the multiple-scattering method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultipleScatteringSettings {
    /// Discrete ordinates per hemisphere (the solver has twice as many
    /// streams, Legendre terms and azimuthal harmonics).
    pub streams_per_hemisphere: usize,
    /// Layers of the vertical grid.
    pub layers: usize,
    /// Step between the sun zenith angles at which the field is solved
    /// for a high sun, degrees.
    pub sun_zenith_step_deg: f64,
    /// The step near and below the horizon (zenith angles from
    /// `SUNSET_STEP_END_DEG`, 85 degrees),
    /// where the field changes fastest, degrees.
    pub sunset_sun_zenith_step_deg: f64,
    /// Gauss panels along each view ray.
    pub view_ray_panels: usize,
    /// Source table: view zenith nodes (0..180 degrees).
    pub table_view_zenith_nodes: usize,
    /// Source table: relative azimuth nodes (0..180 degrees): 19 at the
    /// table's own azimuths (0, 10, 14, 18, 23, 30, then 10-12 degrees
    /// apart), other counts spread the same way (37 halves each cell).
    pub table_azimuth_nodes: usize,
    /// Polarised light (the fast method): the polarisation correction's
    /// columns and the Mie phase-matrix ratios computed at every this many
    /// wavelengths (and the last; at most 60 nm apart) and interpolated in
    /// wavelength between them by cubics; the columns also at every
    /// wavelength where the anchors' cubic would miss the sky's absorbing
    /// optical depth (gas bands, `spectrum/anchors.rs`). The measured error
    /// of the default 3 is in `docs/polarisation.md`: within 5e-4 in I and
    /// 1.4e-3 in the degree of polarisation on Earth (earth-clear-summer's
    /// gas bands, 280-2500 nm, within 1.2e-3), 4.3e-3 in the degree for Mars's
    /// dust (its Mie ratios). 1 computes them at every wavelength, the
    /// exact path.
    pub polarisation_wavelength_stride: usize,
    /// Gauss panels along each path of the twilight first order (the
    /// first order marched through the spherical shell for the sun nodes
    /// from 84 degrees of zenith), besides its cuts at the profiles'
    /// corners and every 20 km of altitude.
    pub first_order_panels: usize,
    /// Gauss nodes on each of the 8 panels of zenith cosine within 0.25 of
    /// each level's horizon over which the twilight first order's moments
    /// are integrated for the sun nodes from 90 degrees of zenith (the two
    /// wide outer panels take at least 4): 40 cosines by default, each
    /// marched at as many azimuths as the solver has harmonics.
    pub first_order_fine_nodes: usize,
    /// After sunset, the most pieces each near-horizontal stream's path is
    /// cut into when its orders are read at the sun angle of where their
    /// light was gathered (one piece per 0.2 degree of the path's angle's
    /// spread; `twilight_shift.rs`), 1..64. The default 1 reads each whole
    /// path at its mean angle, which after sunset in a coarse haze is too
    /// bright in the red (earth-hazy, an eye 3 km up, a 1 km segment toward
    /// the sun at suns -1 to -4 degrees: 2-3 % at 560 and 680 nm); 3 moves
    /// such views 86-91 % of the way to 32 pieces of every path, at 1.19
    /// times the CPU of an after-sunset almucantar
    /// (docs/aerial_perspective.md). It changes nothing while the sun is
    /// more than 6 degrees up.
    pub twilight_shift_pieces: usize,
}

impl Default for MultipleScatteringSettings {
    fn default() -> MultipleScatteringSettings {
        MultipleScatteringSettings {
            streams_per_hemisphere: 8,
            layers: 40,
            sun_zenith_step_deg: 3.0,
            sunset_sun_zenith_step_deg: 0.75,
            view_ray_panels: 16,
            table_view_zenith_nodes: 37,
            table_azimuth_nodes: 19,
            polarisation_wavelength_stride: 3,
            first_order_panels: spherical_first_order::PANELS,
            first_order_fine_nodes: spherical_first_order::FINE_PANEL_NODES,
            twilight_shift_pieces: 1,
        }
    }
}

impl MultipleScatteringSettings {
    /// Checks that every count and step can make a solver: at least one
    /// stream per hemisphere (at most 32), two layers, two view-ray panels,
    /// two nodes per table axis, a first-order panel and node (at most 64
    /// nodes), 1 to 64 twilight shift pieces, and positive steps.
    pub(crate) fn validate(&self) -> Result<()> {
        let counts = [
            ("streams per hemisphere", self.streams_per_hemisphere, 1, 32),
            ("multiple-scattering layers", self.layers, 2, 10_000),
            ("view-ray panels", self.view_ray_panels, 2, 10_000),
            (
                "source-table view zenith nodes",
                self.table_view_zenith_nodes,
                2,
                10_000,
            ),
            (
                "source-table azimuth nodes",
                self.table_azimuth_nodes,
                2,
                10_000,
            ),
            (
                "polarisation wavelength stride",
                self.polarisation_wavelength_stride,
                1,
                10_000,
            ),
            ("first-order panels", self.first_order_panels, 1, 10_000),
            (
                "first-order fine-quadrature nodes",
                self.first_order_fine_nodes,
                1,
                64,
            ),
            ("twilight shift pieces", self.twilight_shift_pieces, 1, 64),
        ];
        for (name, value, low, high) in counts {
            if !(low..=high).contains(&value) {
                return Err(Error::out_of_range(
                    name,
                    value as f64,
                    "",
                    format!("{low}..={high}"),
                ));
            }
        }
        for (name, value) in [
            ("sun zenith step", self.sun_zenith_step_deg),
            ("sunset sun zenith step", self.sunset_sun_zenith_step_deg),
        ] {
            if !(value.is_finite() && value > 0.0 && value <= 90.0) {
                return Err(Error::out_of_range(name, value, "deg", "> 0 and <= 90"));
            }
        }
        Ok(())
    }
}
