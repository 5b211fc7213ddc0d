//! Engine tables: what a real-time shader needs to draw a sora sky, the
//! sun's disc, aerial perspective and the irradiance on the ground for any
//! sun elevation from -12 to 90 degrees and any eye altitude inside the
//! atmosphere, by table reads only (`docs/engine-tables.md`, the reference
//! shaders in `web/shaders/`). Within 2 % of the library for an eye on
//! the ground and at the lowest altitude nodes; the diffuse irradiance
//! at a raised point below 20 km within 2.7 % (suns -4 to 60 degrees;
//! `docs/engine-tables.md`); the sky
//! table's own read between the altitude nodes not (the ignored test
//! `the_sky_between_the_altitude_nodes_matches_the_library` measures 6-65 %
//! on earth-hazy above the eye's horizon).
//!
//! Four tables in CIE XYZ (1.0 = the XYZ of a flat spectrum of 1 in the
//! quantity's unit, as `sora render --units radiance` writes; the shader
//! converts to linear sRGB with the manifest's matrix), and the
//! aerial-perspective march's spectral tables:
//! - **sky**: the sky radiance (W m^-2 sr^-1 nm^-1 XYZ) seen by an eye at
//!   altitude h toward zenith angle z and azimuth phi from the sun's, with
//!   the sun at elevation e: 4D, as layers (e, h) of 2D images (z, phi).
//!   Each layer is the library's own image path
//!   ([`Sky::radiance_from_image_tables`]: single scattering with the exact
//!   phase functions, the multiple-scattering field solved once for every
//!   sun and aimed at the layer's eye and sun, the sunlit ground) at the
//!   layer's sun and eye, without the sun's disc, with a sky-view table on
//!   the layer's own grid: its zenith rows are the layer's (half the
//!   images' at the defaults, and the layer's views on them), and its
//!   multiply scattered light marched in 8 view-ray panels, not the
//!   field's 16 (`LAYER_MULTIPLE_PANELS`), and at every other sun node
//!   from -6 to 70 degrees (-4.4 to 53 degrees, 19 of the default
//!   48 nodes) not marched but blended in its logarithm from the nodes
//!   either side (the cubic through them and the nodes beyond)
//!   (`multiple_from_neighbours`; `docs/engine-tables.md` gives the bake's
//!   time and what each of these changes).
//! - **transmittance**: the transmittance of sunlight from altitude h to
//!   the top of the atmosphere along view cosine mu (2D), as XYZ of the
//!   transmitted solar spectrum over XYZ of the solar spectrum, per
//!   channel (so the sun's disc and direct light are right for the sun's
//!   own spectrum).
//! - **irradiance**: the diffuse (sky) irradiance on a horizontal plane at
//!   altitude h with the sun at e (W m^-2 nm^-1 XYZ) on an altitude axis
//!   of its own (the sky table's mapping, 28 nodes at the default 4
//!   altitude nodes, which are among them;
//!   `EngineTableSettings::irradiance_altitude_nodes`): at the sky
//!   table's altitude nodes integrated from the sky table over the upper
//!   hemisphere (cosine-weighted midpoint rule, 64 x 64 directions),
//!   between them that value scaled by the multiple-scattering field's
//!   own downward diffuse flux at its levels (`raised_irradiance`; linear
//!   between the nodes without a field); the shader adds the direct beam
//!   from the transmittance table.
//! - **aerial**: the aerial perspective, the light scattered into the
//!   segment from the eye to a point at distance d, as a ratio R to
//!   `S w` per channel (S the sky table's read at the eye, w = (1 - T) /
//!   (1 - T_end) the segment's share of the whole ray's extinction, from
//!   the transmittance table): the library's own light of each segment
//!   (`Sky::compute_segment_light`) at every sun and altitude layer of the
//!   sky table, on a coarser view grid (e.g. 8 x 8 per half) and a few
//!   distances spaced in ln d from the thickness / 1000 to the ray's end
//!   (none by default: not yet within 2 % of the library, and it triples
//!   the bake; `docs/engine-tables.md`). Dividing by S w takes out what changes fast (the aureole, the
//!   horizon, the saturation with d), so the ratio interpolates smoothly;
//!   a view out through the top ends (R = 1) as the sky table draws it.
//!   The sky table's difference `S(x, v) - T(x, p) S(p, v)` (Bruneton's)
//!   cancels for short segments (11-124 % off at 1 km against 9-11 % from
//!   the table; `docs/engine-tables.md`); it is what tables baked without
//!   the aerial table (`aerial_nodes` (0, 0, 0), the default) give.
//! - **march** (multiple scattering, `march` in the settings; `march.rs`):
//!   what a per-pixel march of
//!   the segment reads to give the library's light of the air within 2 %
//!   at 1-50 km: the field's source R per wavelength over its altitude
//!   levels, sun zenith nodes and the view's zenith and azimuth, the
//!   species' optics and densities, their columns toward the sun, the
//!   phase functions, the forward-peak term's tables and the ground's
//!   light, from the field solved once for every sun.
//!   `EngineTables::aerial_perspective_xyz` marches them when present
//!   (`lookup.rs`), and so do the reference shaders
//!   (`soraAerialPerspectiveMarch`, `sora_aerial_perspective_march`);
//!   without them the shaders read the aerial table or the difference.
//!
//! Why not Bruneton's parametrisation: his 4D scattering table is indexed
//! by (r, mu, mu_s, nu) with a single mu axis over the ground and the sky
//! and an mu_s mapping that is coarse below the horizon, which is where it
//! breaks (the horizon band, the twilight staircase: ebruneton/
//! precomputed_atmospheric_scattering #6, #26, #30). Here the view's zenith
//! axis is split at the eye's own horizon with nodes crowding toward it
//! from both sides (no cell straddles the horizon, so there is no seam),
//! and the sun axis is an asinh mapping that puts nodes 0.4 degrees apart
//! at sunset; along it the radiance is interpolated in its logarithm,
//! which is what keeps the zenith's brightness smooth through twilight
//! (the sky dims about tenfold per 3 degrees there). The scattering angle
//! is not an axis, so the aureole near a high sun (whose sun layers are up
//! to 10 degrees apart) would be blended between two places; instead each
//! sun layer is read at the view turned with the sun to the layer's
//! elevation, which keeps the view's angle to the sun, near the sun and
//! away from the horizon (`lookup.rs`, the docs page).
//!
//! The multiple-scattering field of every layer is solved once, for every
//! sun zenith angle, and aimed at each layer's eye and sun
//! (`sky::shared_field`); the per-layer solve, the images' own sky-view
//! tables, the field's panels and the multiply scattered light marched at
//! every sun node and every azimuth node are kept as the tests' oracles
//! (`bake_with`). The
//! marches' exponentials, forward-peak integrals and source-table reads
//! run in AVX2's registers where the CPU has them, chosen at run time
//! (`transport/vector_exp.rs`): the same tables bit for bit, 12-15 % less
//! CPU (`docs/engine-tables.md`, "Bake time"). Each row of a layer's
//! sky-view table (one zenith angle, every azimuth) marches its rays'
//! densities and columns once and replays them, with the nodes' located
//! table cells, for its other azimuths (`PanelMarch::reuse_nodes`): the
//! sky values within one f32 rounding of every ray marched alone, which
//! the tests keep as the oracle (`the_rows_marched_once_are_every_ray_marched`).
//!
//! The lookup formulas (`lookup.rs`) are those the shaders run; the
//! manifest (`files.rs`) states them for any other reader.

pub mod axes;
mod files;
mod lookup;
mod march;

pub use files::{MANIFEST_FILE, TABLE_FORMAT, check_output_directory};

use crate::colour::{Observer, SpectrumToXyz};
use crate::error::{Error, Result};
use crate::geometry::{Vector3, ViewDirection};
use crate::sky::{Method, SharedField, Sky, SkyViewGrid};
use crate::spectrum::SampledSpectrum;
use crate::transport::sky_view_table::MarchedRows;

/// Resolution of the engine tables.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngineTableSettings {
    /// Sun elevation nodes over -12..90 degrees.
    pub sun_nodes: usize,
    /// Eye altitude nodes of the sky table (and nodes of the irradiance
    /// table's own altitude axis, `irradiance_altitude_nodes`).
    pub altitude_nodes: usize,
    /// View zenith nodes per half (above and below the horizon).
    pub zenith_nodes_per_half: usize,
    /// Fine cells of the zenith axis next to the horizon, per half
    /// (`axes::zenith_of_node`): the half's nodes lie on a grid of
    /// 2 (zenith_nodes_per_half - 1) - fine + wide cells, at every other
    /// grid node from the zenith (and the nadir), every third over the
    /// `zenith_wide_cells_per_half` wide cells after those, and every one
    /// in the last `fine` cells. With 128 grid nodes per half (the images'
    /// sky-view table's) the nodes there are the library's own rows.
    pub zenith_fine_cells_per_half: usize,
    /// Wide cells of the zenith axis (3 grid cells each) between the
    /// coarse cells from the zenith and the fine cells next to the
    /// horizon, per half; fine + wide at most zenith_nodes_per_half - 1.
    pub zenith_wide_cells_per_half: usize,
    /// Relative azimuth nodes over 0..180 degrees.
    pub azimuth_nodes: usize,
    /// Transmittance table: altitude nodes, view cosine nodes.
    pub transmittance_nodes: (usize, usize),
    /// Aerial-perspective table: view zenith nodes per half, relative
    /// azimuth nodes, distance nodes (its sun and altitude nodes are the
    /// sky table's); (0, 0, 0) for none (the aerial perspective is then
    /// the sky table's difference, see `lookup.rs`).
    pub aerial_nodes: (usize, usize, usize),
    /// Whether to bake the aerial-perspective march's tables (`march.rs`;
    /// multiple scattering only). On by default: the aerial perspective
    /// within 2 % of the library at 1-50 km, 29-34 MB (48-53 MB with the
    /// sky table's 19 MB, under the 64 MB a GPU should hold; no bake time
    /// measurable: the field's source is copied); the reference shaders
    /// march them (`soraAerialPerspectiveMarch`, `docs/engine-tables.md`).
    pub march: bool,
}

impl Default for EngineTableSettings {
    fn default() -> EngineTableSettings {
        EngineTableSettings {
            sun_nodes: 48,
            // 4 altitude nodes (0, 5.4, 25.5 and 100 km for Earth): the
            // raised eye's sky is read from the march's tables
            // (`lookup.rs`, `raised_sky_xyz`), which hold it about as well
            // as 6 nodes did (docs/engine-tables.md, "How many altitude
            // nodes"), at two thirds of the layers and of the bake; the
            // table's read alone (the shaders' `soraSkyView`) is worse.
            // The irradiance table has an altitude axis of its own
            // (`irradiance_altitude_nodes`).
            altitude_nodes: 4,
            zenith_nodes_per_half: 64,
            // 21 fine and 22 wide cells: the nodes of the last 21 cells
            // next to the horizon are the images' sky-view rows (up to 2.5
            // degrees above it for an eye on the ground), which puts
            // paper-mars' horizon band after sunset within 2 % (1.06-1.70
            // % from 2.33-5.63 % with the plain axis) at the same size and
            // bake (docs/engine-tables.md).
            zenith_fine_cells_per_half: 21,
            zenith_wide_cells_per_half: 22,
            azimuth_nodes: 64,
            transmittance_nodes: (32, 128),
            // No aerial table by default: at (8, 8, 6) it is not yet
            // within 2 % of the library and triples the bake
            // (`docs/engine-tables.md`); `sora tables --aerial-*-nodes`.
            aerial_nodes: (0, 0, 0),
            march: true,
        }
    }
}

impl EngineTableSettings {
    /// Checks every count: at least 2 (3 zenith nodes per half), and the
    /// sky table within [`MAX_SKY_TEXELS`].
    pub fn validate(&self) -> Result<()> {
        for (name, nodes, least) in [
            ("sun nodes", self.sun_nodes, 2),
            ("altitude nodes", self.altitude_nodes, 2),
            ("zenith nodes per half", self.zenith_nodes_per_half, 3),
            ("azimuth nodes", self.azimuth_nodes, 2),
            (
                "transmittance altitude nodes",
                self.transmittance_nodes.0,
                2,
            ),
            ("transmittance mu nodes", self.transmittance_nodes.1, 2),
            ("aerial zenith nodes per half", self.aerial_nodes.0, 3),
            ("aerial azimuth nodes", self.aerial_nodes.1, 2),
            ("aerial distance nodes", self.aerial_nodes.2, 2),
        ] {
            let no_aerial = self.aerial_nodes == (0, 0, 0) && name.starts_with("aerial");
            if !(least..=4096).contains(&nodes) && !no_aerial {
                return Err(Error::out_of_range(
                    name,
                    nodes as f64,
                    "1",
                    format!("{least}..=4096"),
                ));
            }
        }
        let (fine, wide) = self.zenith_cells();
        if fine >= self.zenith_nodes_per_half {
            return Err(Error::out_of_range(
                "zenith fine cells per half",
                fine as f64,
                "1",
                format!("0..={}", self.zenith_nodes_per_half - 1),
            ));
        }
        if fine + wide >= self.zenith_nodes_per_half {
            return Err(Error::out_of_range(
                "zenith wide cells per half",
                wide as f64,
                "1",
                format!(
                    "0..={} (zenith nodes per half - 1 - fine cells)",
                    self.zenith_nodes_per_half - 1 - fine
                ),
            ));
        }
        let texels = (self.sky_texels() + self.aerial_texels()) as f64;
        if texels > MAX_SKY_TEXELS as f64 {
            return Err(Error::out_of_range(
                "sky and aerial-perspective tables' texels (sun x altitude x 2 zenith x azimuth (x distance) nodes)",
                texels,
                "1",
                format!("<= {MAX_SKY_TEXELS} (64 MB of 32-bit XYZ)"),
            ));
        }
        Ok(())
    }

    /// The zenith axis's fine and wide cells per half
    /// (`axes::zenith_of_node`).
    pub fn zenith_cells(&self) -> (usize, usize) {
        (
            self.zenith_fine_cells_per_half,
            self.zenith_wide_cells_per_half,
        )
    }

    /// Altitude nodes of the irradiance table: on the sky table's
    /// mapping (`axes::altitude_of_node`) with every cell of the sky
    /// table's altitude axis cut into the same number of cells, at least
    /// [`IRRADIANCE_ALTITUDE_CELLS`] in all, so that the sky table's
    /// nodes are among them (28 for the default 4: 9 cells per sky cell).
    pub fn irradiance_altitude_nodes(&self) -> usize {
        let cells = self.altitude_nodes.max(2) - 1;
        cells * IRRADIANCE_ALTITUDE_CELLS.div_ceil(cells) + 1
    }

    /// The irradiance table's altitude nodes per cell of the sky table's
    /// altitude axis.
    fn irradiance_cells_per_altitude_cell(&self) -> usize {
        (self.irradiance_altitude_nodes() - 1) / (self.altitude_nodes.max(2) - 1)
    }

    /// Layers of the sky table (sun nodes x altitude nodes).
    pub fn sky_layers(&self) -> usize {
        self.sun_nodes * self.altitude_nodes
    }

    fn sky_texels(&self) -> usize {
        self.sky_layers() * 2 * self.zenith_nodes_per_half * self.azimuth_nodes
    }

    /// Texels of one slice (one distance node of one layer) of the
    /// aerial-perspective table.
    fn aerial_slice_texels(&self) -> usize {
        2 * self.aerial_nodes.0 * self.aerial_nodes.1
    }

    fn aerial_texels(&self) -> usize {
        self.sky_layers() * self.aerial_nodes.2 * self.aerial_slice_texels()
    }
}

/// Cells of the irradiance table's altitude axis, at least
/// (`EngineTableSettings::irradiance_altitude_nodes`): the diffuse
/// irradiance between the sky table's altitude nodes follows the
/// multiple-scattering field's own downward flux
/// (`EngineTables::raised_irradiance`), read linearly between these
/// nodes; 27 cells (28 nodes, 16 kB) put the nodes at most 1.2 km apart
/// below 5 km on Earth.
pub const IRRADIANCE_ALTITUDE_CELLS: usize = 27;

/// The tests' choice of the irradiance table's altitude shape between
/// the sky table's nodes: 0 the field's flux with the sunlight delta-M
/// moved into the beam (the bake's), 1 without it, 2 linear between the
/// nodes.
#[cfg(test)]
pub(crate) static IRRADIANCE_SHAPE_OVERRIDE: std::sync::atomic::AtomicUsize =
    std::sync::atomic::AtomicUsize::new(0);

/// Most texels of the sky and aerial-perspective tables together: 64 MB
/// of three 32-bit floats.
pub const MAX_SKY_TEXELS: usize = 64 * 1024 * 1024 / 12;

/// The engine tables of one atmosphere (see the module docs).
#[derive(Debug, Clone)]
pub struct EngineTables {
    settings: EngineTableSettings,
    ground_radius_m: f64,
    top_radius_m: f64,
    sun_angular_radius_rad: f64,
    /// XYZ of the top-of-atmosphere solar irradiance, W m^-2 nm^-1.
    solar_xyz: [f64; 3],
    /// [((s * A + a) * 2 Z + row) * K + k].
    sky: Vec<[f32; 3]>,
    /// [altitude row * M + mu node].
    transmittance: Vec<[f32; 3]>,
    /// The aerial-perspective ratio R, [(((s * A + a) * D + j) * 2 Z + row)
    /// * K + k] (the aerial nodes' Z, K, D).
    aerial: Vec<[f32; 3]>,
    /// Diffuse horizontal irradiance, [a * S + s], a the irradiance
    /// table's own altitude node
    /// (`EngineTableSettings::irradiance_altitude_nodes`).
    irradiance: Vec<[f32; 3]>,
    /// What the aerial-perspective march reads (`march.rs`; None for
    /// single scattering, whose tables have no field).
    march: Option<march::MarchTables>,
    /// What the tables were baked from (for the manifest).
    provenance: Provenance,
}

/// What the tables were baked from.
#[derive(Debug, Clone)]
struct Provenance {
    wavelengths_nm: Vec<f64>,
    scattering: String,
}

impl EngineTables {
    /// Bakes the tables of `sky`'s atmosphere, wavelengths, physics and
    /// fast-method table size (its sun and eye are not used; the sky must
    /// use [`Method::Fast`]). `progress(fraction)` is called as layers of
    /// the sky table complete and with 1 once every table is done. The
    /// multiple-scattering field is solved once for all layers
    /// (`sky/shared_field.rs`).
    pub fn bake(
        sky: &Sky,
        settings: &EngineTableSettings,
        progress: &(dyn Fn(f64) + Sync),
    ) -> Result<EngineTables> {
        EngineTables::bake_with(sky, settings, (Field::Shared, Layers::Grid), progress)
    }

    /// [`EngineTables::bake`] with the multiple-scattering field solved
    /// once for every layer or (`Field::PerLayer`, the slow path the tests
    /// hold the fast one to) anew for each layer's own sun and eye, and
    /// each layer drawn from a sky-view table on its own grid or
    /// (`Layers::Image`, the slow path) from the library's image tables.
    fn bake_with(
        sky: &Sky,
        settings: &EngineTableSettings,
        (field, layers): (Field, Layers),
        progress: &(dyn Fn(f64) + Sync),
    ) -> Result<EngineTables> {
        settings.validate()?;
        if sky.method() != Method::Fast {
            return Err(Error::Unsupported(
                "engine tables are baked with the fast method (its image tables)".into(),
            ));
        }
        let scene = sky.scene();
        let (ground_radius_m, top_radius_m) = scene.radii_m();
        let thickness = top_radius_m - ground_radius_m;
        let to_xyz = SpectrumToXyz::new(sky.wavelengths(), Observer::default());
        let xyz = |values: &[f64]| -> Result<[f64; 3]> {
            let c = to_xyz.to_xyz(&SampledSpectrum::from_values(values.to_vec()))?;
            Ok([c.x, c.y, c.z])
        };
        // XYZ of a view's or a segment's light, negative light counted as
        // none. A grazing ray from the very top of the atmosphere
        // (earth-hazy, the sun at the horizon) gave a segment's light
        // negative values (-4.5e-9 W m^-2 sr^-1 nm^-1 at 1755 m, 700 nm,
        // single scattering 8.5e-9): its peak-only term P_sky - T
        // P_behind with the sky's Q from the whole ray's own march, the
        // two marches' quadrature error where the segment adds nothing
        // to Q; the sky's Q is now composed from the segment's and the
        // light from behind's (`sky/aerial_perspective.rs`), and no
        // segment of that layer (16 x 16 views, 8 distances, 380-780 nm)
        // is negative. The clamp stays: a difference of terms, it is not
        // shown non-negative everywhere. A
        // sky layer's view 0.32 degrees below the horizon at 100 km
        // (earth-hazy, the sun at -9.1 degrees, 420 nm) read -0.039 W m^-2
        // sr^-1 nm^-1 from the sky-view table's forward-peak X-bar filled
        // apart from its Q (`transport/sky_view_table.rs`, fill_unmarched;
        // the same fill put 3.6e11 in a texel of the plain axis's table):
        // since that fix no layer of earth-hazy's (fine cells, 6
        // altitudes), paper-mars', mars-dust's, earth-clear's or
        // paper-earth's bake (2 altitudes) has negative light.
        let light_xyz = |light: &SampledSpectrum| -> Result<[f64; 3]> {
            // (A NaN stays, and is refused.)
            let clean: Vec<f64> = light
                .values()
                .iter()
                .map(|v| if *v < 0.0 { 0.0 } else { *v })
                .collect();
            xyz(&clean)
        };
        let solar = scene.optics().solar_irradiance_w_m2_nm.values().to_vec();
        let solar_xyz = xyz(&solar)?;
        let EngineTableSettings {
            sun_nodes,
            altitude_nodes,
            zenith_nodes_per_half: half,
            azimuth_nodes,
            transmittance_nodes,
            ..
        } = *settings;
        let layer_texels = 2 * half * azimuth_nodes;
        let mut sky_values = vec![[0.0f32; 3]; settings.sky_texels()];
        // The segments' light (XYZ) first; the ratio once the sky and
        // transmittance tables are there.
        let mut aerial_light = vec![[0.0f64; 3]; settings.aerial_texels()];
        let aerial_slice = settings.aerial_slice_texels();
        let (aerial_half, aerial_azimuth, aerial_distances) = settings.aerial_nodes;
        let layer_count = settings.sky_layers();
        // What `progress` is told: the share of the layers drawn, up to
        // the layers' part of the whole bake, and 1 once every table is
        // done. The march's tables (the field's source exported, the small
        // tables computed) took about a sixth of the real-time explorer's
        // bake in WebAssembly (2 of 12.6 s), the transmittance and
        // irradiance tables little.
        let layers_share = if settings.march { 0.85 } else { 0.98 };
        let layers_done = |done: usize| layers_share * done as f64 / layer_count as f64;
        // The field of every layer, solved once (see `sky::shared_field`).
        let shared: Option<SharedField> = match field {
            Field::Shared => sky.solve_shared_field()?,
            Field::PerLayer => None,
        };
        let sky_view = match layers {
            Layers::Grid | Layers::GridLinearBlend | Layers::GridEverySun => {
                Some(layer_sky_view(sky, settings, (false, false)))
            }
            Layers::GridEveryAzimuth => Some(layer_sky_view(sky, settings, (false, true))),
            Layers::GridFieldPanels => Some(layer_sky_view(sky, settings, (true, false))),
            Layers::Image => None,
        };
        let mut done = 0usize;
        for a in 0..altitude_nodes {
            let altitude = axes::altitude_of_node(a, altitude_nodes, thickness);
            // One scene per altitude, moved to each sun: the sun-column
            // tables are shared by its suns.
            let base = scene.with_observer_and_sun(altitude, 90.0, 180.0)?;
            let horizon = axes::horizon_zenith(ground_radius_m + altitude, ground_radius_m);
            let mut views = Vec::with_capacity(layer_texels);
            for row in 0..2 * half {
                let zenith = axes::zenith_of_node(row, half, settings.zenith_cells(), horizon);
                for k in 0..azimuth_nodes {
                    let phi = axes::azimuth_of_node(k, azimuth_nodes);
                    views.push(ViewDirection::new(
                        90.0 - zenith.to_degrees(),
                        180.0 + phi.to_degrees(),
                    )?);
                }
            }
            // View by view, each view's distances in a row (the library
            // marches a view's whole ray once for its segments), and where
            // each goes in the table's layout (distance slice by slice).
            let mut segments = Vec::with_capacity(aerial_distances * aerial_slice);
            let mut places = Vec::with_capacity(aerial_distances * aerial_slice);
            for row in 0..2 * aerial_half {
                let zenith = axes::zenith_of_node(row, aerial_half, (0, 0), horizon);
                let range = axes::distance_range(
                    thickness,
                    axes::ray_length(
                        ground_radius_m + altitude,
                        zenith.cos(),
                        ground_radius_m,
                        top_radius_m,
                    ),
                );
                for k in 0..aerial_azimuth {
                    let phi = axes::azimuth_of_node(k, aerial_azimuth);
                    let view =
                        ViewDirection::new(90.0 - zenith.to_degrees(), 180.0 + phi.to_degrees())?;
                    // A view out through the top ends as the sky table
                    // draws it (`aerial_ratios`): its last node is not
                    // marched.
                    let marched = aerial_distances - usize::from(row < aerial_half);
                    for j in 0..marched {
                        segments.push((view, axes::distance_of_node(j, aerial_distances, range)));
                        places.push(j * aerial_slice + row * aerial_azimuth + k);
                    }
                }
            }
            // The sky of sun node `s` at this altitude, its multiply
            // scattered light marched or (`neighbours`) blended halfway
            // between the skies of the nodes either side (by the cubic
            // through them and the nodes beyond, where given).
            type Neighbours<'a> = ((&'a Sky, &'a Sky), Option<(&'a Sky, &'a Sky)>);
            let layer_at = |s: usize, neighbours: Option<Neighbours>| -> Result<Sky> {
                let elevation = axes::sun_elevation_of_node(s, sun_nodes);
                // In deep twilight the field's own panels
                // (`LAYER_MULTIPLE_PANELS_ABOVE_DEG`).
                let layer_view = sky_view.map(|grid| SkyViewGrid {
                    multiple_panels: grid
                        .multiple_panels
                        .filter(|_| elevation >= LAYER_MULTIPLE_PANELS_ABOVE_DEG),
                    ..grid
                });
                let layer_sky = sky.with_shared_field(
                    base.with_sun(elevation, 180.0)?,
                    shared.as_ref(),
                    layer_view,
                )?;
                if let Some((neighbours, outer)) = neighbours {
                    // The nodes are evenly spaced in the sun axis's
                    // parameter: halfway.
                    layer_sky.blend_multiple_scattering_from(neighbours, outer, 0.5)?;
                }
                Ok(layer_sky)
            };
            let mut draw_layer = |s: usize, layer_sky: &Sky| -> Result<()> {
                let radiances = layer_sky.radiances_from_image_tables(&views, &|_, _| {})?;
                let layer = s * altitude_nodes + a;
                let out = &mut sky_values[layer * layer_texels..][..layer_texels];
                // The texels' XYZ in parallel (on one thread it left the
                // other idle); the first failing texel's error.
                let failed = std::sync::Mutex::new(None);
                crate::parallel::for_each_chunk_mut(out, XYZ_TEXELS_PER_TASK, |task, chunk| {
                    let first = task * XYZ_TEXELS_PER_TASK;
                    for (i, (o, radiance)) in chunk.iter_mut().zip(&radiances[first..]).enumerate()
                    {
                        match light_xyz(&radiance.radiance_w_m2_sr_nm) {
                            Ok(c) => *o = c.map(|v| v.max(0.0) as f32),
                            Err(error) => {
                                let mut failed = failed.lock().expect("no thread panicked");
                                if failed.as_ref().is_none_or(|(at, _)| first + i < *at) {
                                    *failed = Some((first + i, error));
                                }
                                return;
                            }
                        }
                    }
                });
                if let Some((_, error)) = failed.into_inner().expect("no thread panicked") {
                    return Err(error);
                }
                if segments.is_empty() {
                    done += 1;
                    progress(layers_done(done));
                    return Ok(());
                }
                let out = &mut aerial_light[layer * aerial_distances * aerial_slice..]
                    [..aerial_distances * aerial_slice];
                for (place, (light, _)) in places
                    .iter()
                    .zip(layer_sky.compute_segment_light(&segments)?)
                {
                    out[*place] = light_xyz(&light.radiance_w_m2_sr_nm)?;
                }
                done += 1;
                progress(layers_done(done));
                Ok(())
            };
            // The sun nodes in the order their layers are drawn: a node
            // whose multiply scattered light is blended from its
            // neighbours' (`multiple_from_neighbours`) once the node three
            // above it is drawn (the cubic through the marching nodes s -
            // 3, s - 1, s + 1 and s + 3; with `Layers::GridLinearBlend`,
            // or where there is no node s - 3 or s + 3 below 70 degrees,
            // the nodes either side alone, right after the node above
            // it), the last marched skies kept for the next.
            let blended =
                |s: usize| layers.blends_multiple() && multiple_from_neighbours(s, sun_nodes);
            let cubic = layers != Layers::GridLinearBlend;
            let mut marched: Vec<(usize, Sky)> = Vec::new();
            let mut pending: Vec<usize> = Vec::new();
            for s in 0..sun_nodes {
                if blended(s) {
                    pending.push(s);
                    continue;
                }
                let layer_sky = layer_at(s, None)?;
                draw_layer(s, &layer_sky)?;
                marched.push((s, layer_sky));
                if marched.len() > 6 {
                    marched.remove(0);
                }
                let sky_of = |n: Option<usize>| {
                    marched
                        .iter()
                        .find(|(m, _)| Some(*m) == n)
                        .map(|(_, sky)| sky)
                };
                let mut waiting = Vec::new();
                for p in pending.drain(..) {
                    let (below, above) = (sky_of(Some(p - 1)), sky_of(Some(p + 1)));
                    let outer = sky_of(p.checked_sub(3)).zip(sky_of(Some(p + 3)));
                    // The nodes beyond stay below 70 degrees: through the
                    // node at 78.9 degrees, mars-dust's node at 53.1 went
                    // from 1.78 % to 1.92 % in the browser test (bound 2
                    // %), the nodes either side alone.
                    let beyond = cubic
                        && p >= 3
                        && p + 3 < sun_nodes
                        && axes::sun_elevation_of_node(p + 3, sun_nodes)
                            <= MULTIPLE_FROM_NEIGHBOURS_DEG.1;
                    match (below.zip(above), outer) {
                        (Some(either), Some(outer)) if beyond => {
                            draw_layer(p, &layer_at(p, Some((either, Some(outer))))?)?;
                        }
                        (Some(either), _) if !beyond => {
                            draw_layer(p, &layer_at(p, Some((either, None)))?)?;
                        }
                        _ => waiting.push(p),
                    }
                }
                pending = waiting;
            }
            assert!(pending.is_empty(), "every blended node is drawn");
        }
        let transmittance = bake_transmittance(
            sky,
            transmittance_nodes,
            thickness,
            &solar,
            &solar_xyz,
            &xyz,
        )?;
        let mut tables = EngineTables {
            settings: *settings,
            ground_radius_m,
            top_radius_m,
            sun_angular_radius_rad: scene.sun_angular_radius_rad(),
            solar_xyz,
            sky: sky_values,
            transmittance,
            aerial: Vec::new(),
            irradiance: Vec::new(),
            march: match &shared {
                Some(shared) if settings.march => Some(march::MarchTables::bake(sky, shared)?),
                _ => None,
            },
            provenance: Provenance {
                wavelengths_nm: sky.wavelengths().wavelengths_nm().collect(),
                scattering: match sky.scattering() {
                    crate::sky::Scattering::Single => "single".into(),
                    crate::sky::Scattering::Multiple(_) => "multiple".into(),
                },
            },
        };
        let at_nodes = tables.integrate_diffuse_irradiance();
        let field_flux = match &shared {
            #[cfg(test)]
            Some(_)
                if IRRADIANCE_SHAPE_OVERRIDE.load(std::sync::atomic::Ordering::Relaxed) == 2 =>
            {
                None
            }
            Some(shared) => Some(tables.field_flux_xyz(shared, &xyz)?),
            None => None,
        };
        tables.irradiance = tables.raised_irradiance(&at_nodes, field_flux.as_ref());
        if !aerial_light.is_empty() {
            tables.aerial = tables.aerial_ratios(&aerial_light);
        }
        progress(1.0);
        Ok(tables)
    }

    /// The settings the tables were baked with.
    pub fn settings(&self) -> &EngineTableSettings {
        &self.settings
    }

    /// The sky table's texels (XYZ, W m^-2 sr^-1 nm^-1) in the manifest's
    /// layout: texel (k, row) of layer `s * altitude_nodes + a` at index
    /// `(layer * 2 * zenith_nodes_per_half + row) * azimuth_nodes + k`
    /// (what `sky.exr` holds, top scan line first).
    pub fn sky_table(&self) -> &[[f32; 3]] {
        &self.sky
    }

    /// The transmittance table's texels (XYZ ratios), mu node m of
    /// altitude node a at index `a * mu_nodes + m` (`transmittance.exr`).
    pub fn transmittance_table(&self) -> &[[f32; 3]] {
        &self.transmittance
    }

    /// The diffuse horizontal irradiance table's texels (XYZ, W m^-2
    /// nm^-1), sun node s of altitude node a of the irradiance table's own
    /// axis (`EngineTableSettings::irradiance_altitude_nodes`) at index
    /// `a * sun_nodes + s` (`irradiance.exr`).
    pub fn irradiance_table(&self) -> &[[f32; 3]] {
        &self.irradiance
    }

    /// The aerial-perspective table's texels (XYZ ratios R, see the module
    /// docs): texel (k, row) of distance node j of layer `s *
    /// altitude_nodes + a` at index `((layer * distance_nodes + j) * 2
    /// zenith_nodes + row) * azimuth_nodes + k` with the aerial nodes'
    /// counts (what `aerial.exr` holds, top scan line first).
    pub fn aerial_table(&self) -> &[[f32; 3]] {
        &self.aerial
    }

    /// Bytes of the tables as 32-bit floats (what a GPU holds): the four
    /// XYZ tables and the aerial-perspective march's.
    pub fn size_bytes(&self) -> usize {
        12 * (self.sky.len() + self.aerial.len() + self.transmittance.len() + self.irradiance.len())
            + self.march.as_ref().map_or(0, |m| m.size_bytes())
    }

    /// The aerial-perspective table from the segments' light `light`
    /// (XYZ, in its layout): R = L / (S w) per channel, S the sky table's
    /// read at the eye and w = (1 - T) / (1 - T_end) the segment's share
    /// of the whole ray's extinction as the lookup takes them, so that at
    /// every node the lookup returns L. A view out through the top ends
    /// as the sky table draws it: its last node (the ray's end, w = 1) is
    /// R = 1. Where S w vanishes (no air, or no light) R is 1; it is at
    /// most [`MAX_AERIAL_RATIO`].
    fn aerial_ratios(&self, light: &[[f64; 3]]) -> Vec<[f32; 3]> {
        let (half, azimuth, distances) = self.settings.aerial_nodes;
        let slice = self.settings.aerial_slice_texels();
        let mut out = vec![[0.0f32; 3]; light.len()];
        for s in 0..self.settings.sun_nodes {
            let elevation = axes::sun_elevation_of_node(s, self.settings.sun_nodes);
            for a in 0..self.settings.altitude_nodes {
                let altitude =
                    axes::altitude_of_node(a, self.settings.altitude_nodes, self.thickness_m());
                let horizon =
                    axes::horizon_zenith(self.ground_radius_m + altitude, self.ground_radius_m);
                let layer = s * self.settings.altitude_nodes + a;
                for j in 0..distances {
                    for row in 0..2 * half {
                        let zenith = axes::zenith_of_node(row, half, (0, 0), horizon);
                        let range = self.aerial_distance_range(altitude, zenith.cos());
                        let d = axes::distance_of_node(j, distances, range);
                        let view = [zenith.sin(), 0.0, zenith.cos()];
                        let (_, share) = self.aerial_share_xyz(altitude, view, d);
                        for k in 0..azimuth {
                            let local = lookup::LocalView {
                                zenith_rad: zenith,
                                relative_azimuth_rad: axes::azimuth_of_node(k, azimuth),
                            };
                            let sky = self.table_sky_xyz(altitude, local, elevation);
                            let index = ((layer * distances + j) * slice) + row * azimuth + k;
                            // A view out through the top ends as the sky
                            // table draws it.
                            let light = if j + 1 == distances && row < half {
                                sky
                            } else {
                                light[index]
                            };
                            out[index] = std::array::from_fn(|c| {
                                let below = sky[c] * share[c];
                                if below > 1e-30 {
                                    (light[c] / below).clamp(0.0, MAX_AERIAL_RATIO) as f32
                                } else {
                                    1.0
                                }
                            });
                        }
                    }
                }
            }
        }
        out
    }

    /// The atmosphere's thickness (top minus ground radius), m.
    fn thickness_m(&self) -> f64 {
        self.top_radius_m - self.ground_radius_m
    }

    /// The shared field's diffuse irradiance
    /// (`SharedField::downward_diffuse_flux`) in XYZ at each of the
    /// tables' sun nodes (linear between the field's sun nodes in the sun
    /// zenith angle), at the field's levels.
    fn field_flux_xyz(
        &self,
        shared: &SharedField,
        xyz: &dyn Fn(&[f64]) -> Result<[f64; 3]>,
    ) -> Result<FieldFlux> {
        let (altitudes_m, angles, flux, moved) = shared.downward_diffuse_flux();
        #[cfg(test)]
        let flux: Vec<f64> =
            if IRRADIANCE_SHAPE_OVERRIDE.load(std::sync::atomic::Ordering::Relaxed) == 1 {
                flux.iter().zip(&moved).map(|(f, m)| f - m).collect()
            } else {
                flux
            };
        #[cfg(not(test))]
        let _ = moved;
        let levels = altitudes_m.len();
        let wavelengths = flux.len() / (levels * angles.len());
        let s_count = self.settings.sun_nodes;
        let mut values = Vec::with_capacity(s_count * levels);
        let mut spectrum = vec![0.0; wavelengths];
        for s in 0..s_count {
            let theta = (90.0 - axes::sun_elevation_of_node(s, s_count)).to_radians();
            let upper = angles.partition_point(|a| *a <= theta);
            let n = upper.clamp(1, angles.len() - 1) - 1;
            let t = ((theta - angles[n]) / (angles[n + 1] - angles[n])).clamp(0.0, 1.0);
            for k in 0..levels {
                let below = &flux[(n * levels + k) * wavelengths..][..wavelengths];
                let above = &flux[((n + 1) * levels + k) * wavelengths..][..wavelengths];
                for ((o, b), a) in spectrum.iter_mut().zip(below).zip(above) {
                    *o = (b + t * (a - b)).max(0.0);
                }
                values.push(xyz(&spectrum)?);
            }
        }
        Ok(FieldFlux {
            altitudes_m,
            values,
        })
    }

    /// The irradiance table on its own altitude axis
    /// (`EngineTableSettings::irradiance_altitude_nodes`) from the
    /// irradiance at the sky table's nodes `at_nodes` ([a * S + s], the
    /// layers' integral): at those nodes the same values; between two of
    /// them, a and a + 1 with the point f of the way from a in the
    /// altitude coordinate, per channel F(h) ((1 - f) E_a / F(h_a) + f
    /// E_(a+1) / F(h_(a+1))), F the field's diffuse irradiance at h
    /// (`field_flux`, linear between its levels): the field's altitude
    /// shape, scaled to the layers' values at the nodes. Where F is zero
    /// at the upper node (the top of the atmosphere: nothing above it)
    /// F(h) E_a / F(h_a); where it is zero at the lower node too, or
    /// without a field (single scattering), E linear between the nodes
    /// (what the table read before it had an axis of its own).
    fn raised_irradiance(
        &self,
        at_nodes: &[[f32; 3]],
        field_flux: Option<&FieldFlux>,
    ) -> Vec<[f32; 3]> {
        let s_count = self.settings.sun_nodes;
        let a_count = self.settings.altitude_nodes;
        let n_count = self.settings.irradiance_altitude_nodes();
        let per_cell = self.settings.irradiance_cells_per_altitude_cell();
        let thickness = self.thickness_m();
        let mut out = vec![[0.0f32; 3]; n_count * s_count];
        for j in 0..n_count {
            let a = (j / per_cell).min(a_count - 2);
            let step = j - a * per_cell;
            let f = step as f64 / per_cell as f64;
            let h = axes::altitude_of_node(j, n_count, thickness);
            let (h_low, h_high) = (
                axes::altitude_of_node(a, a_count, thickness),
                axes::altitude_of_node(a + 1, a_count, thickness),
            );
            for s in 0..s_count {
                let (low, high) = (at_nodes[a * s_count + s], at_nodes[(a + 1) * s_count + s]);
                let shape =
                    field_flux.map(|flux| [flux.at(s, h), flux.at(s, h_low), flux.at(s, h_high)]);
                out[j * s_count + s] = std::array::from_fn(|c| {
                    let (e_low, e_high) = (low[c] as f64, high[c] as f64);
                    if step == 0 {
                        return low[c];
                    }
                    if step == per_cell {
                        return high[c];
                    }
                    let linear = e_low + f * (e_high - e_low);
                    let lit = |v: f64| v > 1e-30;
                    match shape {
                        Some([here, below, above]) if lit(below[c]) && lit(above[c]) => {
                            (here[c] * ((1.0 - f) * e_low / below[c] + f * e_high / above[c]))
                                as f32
                        }
                        // The top of the atmosphere, where the field has no
                        // downward flux: the node below's ratio alone.
                        Some([here, below, _]) if lit(below[c]) => {
                            (here[c] * e_low / below[c]) as f32
                        }
                        _ => linear as f32,
                    }
                });
            }
        }
        out
    }

    /// Diffuse horizontal irradiance of every (sun, altitude) node from the
    /// sky table: 2 * sum over a 64 x 64 midpoint grid in (mu, phi) of
    /// L mu dmu dphi over mu in 0..1, phi in 0..pi.
    fn integrate_diffuse_irradiance(&self) -> Vec<[f32; 3]> {
        const N: usize = 64;
        let s_count = self.settings.sun_nodes;
        let a_count = self.settings.altitude_nodes;
        let mut out = vec![[0.0f32; 3]; s_count * a_count];
        let weight = 2.0 * (1.0 / N as f64) * (std::f64::consts::PI / N as f64);
        // One (altitude, sun) node per task.
        crate::parallel::for_each_chunk_mut(&mut out, 1, |node, out| {
            let (a, s) = (node / s_count, node % s_count);
            let altitude = axes::altitude_of_node(a, a_count, self.thickness_m());
            let horizon =
                axes::horizon_zenith(self.ground_radius_m + altitude, self.ground_radius_m);
            {
                let layer = s * a_count + a;
                let mut sum = [0.0; 3];
                for i in 0..N {
                    let mu = (i as f64 + 0.5) / N as f64;
                    let zenith = mu.acos();
                    for j in 0..N {
                        let phi = (j as f64 + 0.5) / N as f64 * std::f64::consts::PI;
                        let l = self.layer_value(layer, zenith, horizon, phi);
                        for c in 0..3 {
                            sum[c] += l[c] * mu * weight;
                        }
                    }
                }
                out[0] = sum.map(|v| v as f32);
            }
        });
        out
    }
}

/// The multiple-scattering field's diffuse irradiance (XYZ) at each of
/// the tables' sun nodes and the field's levels
/// (`EngineTables::field_flux_xyz`).
struct FieldFlux {
    /// The levels' altitudes, m, increasing from 0.
    altitudes_m: Vec<f64>,
    /// [s * levels + k].
    values: Vec<[f64; 3]>,
}

impl FieldFlux {
    /// The irradiance at sun node `s` and altitude `h` (m), linear
    /// between the levels.
    fn at(&self, s: usize, h: f64) -> [f64; 3] {
        let levels = self.altitudes_m.len();
        let upper = self.altitudes_m.partition_point(|z| *z <= h);
        let k = upper.clamp(1, levels - 1) - 1;
        let (z0, z1) = (self.altitudes_m[k], self.altitudes_m[k + 1]);
        let t = ((h - z0) / (z1 - z0)).clamp(0.0, 1.0);
        let (v0, v1) = (self.values[s * levels + k], self.values[s * levels + k + 1]);
        std::array::from_fn(|c| v0[c] + t * (v1[c] - v0[c]))
    }
}

/// Texels of a sky layer converted to XYZ per parallel task.
const XYZ_TEXELS_PER_TASK: usize = 256;

/// The aerial-perspective table's ratios are at most this (a segment's
/// light is of the order of S (1 - T); the bound keeps a near-zero
/// denominator from making a node that interpolation would spread).
pub const MAX_AERIAL_RATIO: f64 = 100.0;

/// Where a bake's layers take their multiple-scattering field from.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Field {
    /// One field for every sun and eye ([`Sky::solve_shared_field`]).
    Shared,
    /// Each layer's own, solved for its sun and eye (the slow path).
    #[cfg_attr(not(test), allow(dead_code))]
    PerLayer,
}

/// How a bake draws its layers.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Layers {
    /// From a sky-view table on the layer's own grid
    /// ([`layer_sky_view`]), the multiply scattered light of every other
    /// sun node from -6 to 70 degrees blended from its neighbours'
    /// ([`multiple_from_neighbours`]).
    Grid,
    /// As `Grid`, with the blended nodes' multiply scattered light
    /// halfway between the nodes either side in the logarithm (not the
    /// cubic through them and the nodes beyond; what the tests hold the
    /// cubic against).
    #[cfg_attr(not(test), allow(dead_code))]
    GridLinearBlend,
    /// As `Grid`, with the multiply scattered light marched at every sun
    /// node (the slow path the tests hold `Grid` to).
    #[cfg_attr(not(test), allow(dead_code))]
    GridEverySun,
    /// As `GridEverySun`, with the multiply scattered light marched in the
    /// field's own view-ray panels, not [`layer_multiple_panels`] (the slow
    /// path the tests hold `GridEverySun` to).
    #[cfg_attr(not(test), allow(dead_code))]
    GridFieldPanels,
    /// As `GridEverySun`, with the multiply scattered light marched at
    /// every azimuth node of the layer's sky-view table, not every
    /// [`LAYER_MULTIPLE_STRIDE`]-th (the slow path the tests hold
    /// `GridEverySun`'s azimuth fill to).
    #[cfg_attr(not(test), allow(dead_code))]
    GridEveryAzimuth,
    /// From the library's image tables, as `sora render` draws (the slow
    /// path).
    #[cfg_attr(not(test), allow(dead_code))]
    Image,
}

impl Layers {
    /// Whether some layers take their multiply scattered light from their
    /// neighbours' ([`multiple_from_neighbours`]).
    fn blends_multiple(self) -> bool {
        matches!(self, Layers::Grid | Layers::GridLinearBlend)
    }
}

/// Whether sun node `s` of `nodes` takes its layers' multiply scattered
/// light blended from the nodes either side (in the logarithm, halfway:
/// the nodes are evenly spaced in the sun axis's parameter; by the cubic
/// through s - 3, s - 1, s + 1 and s + 3 where that lies between the two
/// either side and s + 3 lies below 70 degrees,
/// `SkyViewTable::blend_multiple_from`) instead of
/// marching it: every other node whose two neighbours lie within
/// [`MULTIPLE_FROM_NEIGHBOURS_DEG`]. The neighbours are never blended
/// themselves.
fn multiple_from_neighbours(s: usize, nodes: usize) -> bool {
    let (low, high) = MULTIPLE_FROM_NEIGHBOURS_DEG;
    s % 2 == 1
        && s + 1 < nodes
        && [s - 1, s + 1].iter().all(|n| {
            let e = axes::sun_elevation_of_node(*n, nodes);
            (low..=high).contains(&e)
        })
}

/// The sun elevations (degrees) within which every other sun node's
/// multiply scattered light is blended from its neighbours': from -6
/// degrees to 70, where the default 48 nodes are 0.4-8.5 degrees
/// apart (-5.12 to 60.6 degrees; the odd nodes -4.38 to 53.1 degrees, 19
/// of the 48, are blended). Above 12.5 degrees (the odd nodes 14.1 to 53.1,
/// 1.8-8.5 degrees from their neighbours) the multiply scattered light
/// is smooth in the sun's elevation: the browser test's luminance p99
/// on the blended nodes rose by at most 0.5 points (earth-hazy at 14.1
/// degrees 0.37 % to 0.88 %, its horizon band 0.38 % to 0.91 %; mars-dust
/// 0.95 % to 1.25 %, horizon band 0.57 % to 1.27 %; the bound is 2 %).
/// The nodes from 70 degrees up (69.2, 78.9, 90) all march: the read near
/// a high sun is the tables' tightest there. From -6 degrees to the
/// horizon (the odd nodes -4.38 to -0.36 degrees, 0.4-0.7 degrees from
/// their neighbours, 5 more of the 48) the cubic through the four marching
/// nodes around each follows the planet's shadow closely enough: the
/// browser test's measure (`the_sky_between_the_sun_nodes_about_the_sunset_matches_the_library`)
/// on the blended nodes rose by at most 0.63 points (earth-hazy at -2.08
/// degrees 0.30 % to 0.93 %, its horizon band 0.32 % to 0.96 %;
/// earth-clear at most 0.62 %, horizon band 0.79 %; the tightest,
/// paper-mars' horizon band at -3.12 degrees, 1.33 % to 1.52 %; the bound
/// is 2 %), and the bake took 4.5 % less CPU. The halfway blend there (before the
/// cubic and the four-layer read) took earth-clear at -4 degrees from
/// 1.82 % to 3.40 %. Below -6 degrees (the nodes 0.9-1.5 degrees apart,
/// the field's 16 panels) every node marches (`docs/engine-tables.md`).
const MULTIPLE_FROM_NEIGHBOURS_DEG: (f64, f64) = (-6.0, 70.0);

/// The sky-view table a layer needs: its nodes (per half of the zenith
/// axis, azimuth) and multiple-scattering strides. Its zenith rows are the
/// layer's own (the same mapping, `axes::zenith_of_node`, so each of the
/// layer's views lies on a row and its single scattering is marched there,
/// not interpolated between rows), with no more of them than the layer
/// has, and no more azimuth nodes than the layer's or the sky's images'.
/// With the plain axis (no fine or wide cells) at 64 nodes per half this
/// is 64 x 48 nodes instead of the images' 128 x 48: half the
/// single-scattering marches, and the multiply scattered light marched at
/// as many rows as the images' ([`LAYER_MULTIPLE_STRIDE`]) in fewer
/// view-ray panels than the field's (`field_panels` false;
/// [`layer_multiple_panels`]).
///
/// With fine or wide cells (`zenith_fine_cells_per_half`,
/// `zenith_wide_cells_per_half`; the defaults' 21 and 22) the table's
/// rows are the zenith axis's grid (`axes::zenith_of_node`; 128 per half,
/// the images' own, at 64 nodes with 21 fine and 22 wide cells, or 78
/// nodes and 27 fine cells), and only the rows that are the layer's nodes
/// are marched (single and multiply scattered light, [`MarchedRows`]): as
/// many marches as the layer has rows.
fn layer_sky_view(
    sky: &Sky,
    settings: &EngineTableSettings,
    (field_panels, every_azimuth): (bool, bool),
) -> SkyViewGrid {
    let (image_half, image_azimuth) = sky.table_size().sky_view_nodes;
    let half = settings.zenith_nodes_per_half;
    let (fine, wide) = settings.zenith_cells();
    let (rows, marched) = if (fine, wide) == (0, 0) {
        (image_half.min(half), MarchedRows::EVERY)
    } else {
        let (by_two, by_three) = axes::coarse_and_wide(half, fine, wide);
        (
            axes::fine_grid_rows(half, fine, wide),
            MarchedRows { by_two, by_three },
        )
    };
    SkyViewGrid {
        nodes: (rows, image_azimuth.min(settings.azimuth_nodes)),
        multiple_stride: if every_azimuth {
            (LAYER_MULTIPLE_STRIDE.0, 1)
        } else {
            LAYER_MULTIPLE_STRIDE
        },
        rows: marched,
        multiple_panels: if field_panels {
            None
        } else {
            layer_multiple_panels(sky)
        },
    }
}

/// The Gauss panels of a layer's multiply-scattered-light marches along
/// each view ray: [`LAYER_MULTIPLE_PANELS`], or the field's own
/// `view_ray_panels` if fewer. None for single scattering.
fn layer_multiple_panels(sky: &Sky) -> Option<usize> {
    match sky.scattering() {
        crate::sky::Scattering::Multiple(settings) => {
            Some(settings.view_ray_panels.min(LAYER_MULTIPLE_PANELS))
        }
        crate::sky::Scattering::Single => None,
    }
}

/// A layer's multiply scattered light is marched in 8 Gauss panels (of 4
/// nodes, cut at the profiles' corners) along each view ray, half the
/// field's default 16: the source along a view ray is smooth (a
/// scattering integral of a diffuse field). Measured on earth-clear's
/// sky table (`--altitude-nodes 2`) against 32 panels: 1.5e-4 (p99) and
/// 2.2e-3 at most (just above the horizon at 100 km, the sun at -12
/// degrees) where 16 panels are within 6.1e-5 and 3.1e-4; the layers'
/// sky-view tables took 18 % less time (`docs/engine-tables.md`).
/// Single scattering's marches keep their 16 panels: at 8 the sky table
/// moved by 0.21 % (p99) and 12 % at most. Below
/// [`LAYER_MULTIPLE_PANELS_ABOVE_DEG`] the layers keep the field's panels.
const LAYER_MULTIPLE_PANELS: usize = 8;

/// Sun elevation (degrees) from which the layers march their multiply
/// scattered light in [`LAYER_MULTIPLE_PANELS`]; below it (5 of the
/// default 48 sun nodes, -12 to -6.9 degrees) in the field's own. In deep
/// twilight the source along a ray falls by orders of magnitude where the
/// ray crosses the planet's shadow, and 8 panels missed it: earth-hazy's
/// layers at the sun nodes -12 to -9.1 degrees moved by 1.3-1.5 % just
/// above the horizon (2.4 and 100 km) and, at 100 km just below the
/// horizon, one texel (the layer's brightest) by 41 %, 47 % from 32
/// panels' where 16 are 3.9 % from them. From -6.9 degrees up no texel
/// of earth-clear's, earth-hazy's or mars-dust's tables moved by more
/// than 1 % (`docs/engine-tables.md`).
const LAYER_MULTIPLE_PANELS_ABOVE_DEG: f64 = -6.0;

/// A layer's sky-view table marches multiply scattered light at every
/// zenith row (the images' table, with twice the rows, at every other one)
/// and every other azimuth node. At every other row the bake took 68 CPU-s
/// instead of 97 but moved the browser test's horizon band (earth-clear
/// at -12 degrees: 1.97 % against the bound of 2 %). Every 4th azimuth
/// node, filled between by the cubic in the logarithm (mirrored about
/// the solar meridian at the axis's ends; measured on a branch, not
/// kept), saved about 9 % of the CPU at
/// `--altitude-nodes 2` and moved earth-clear, earth-hazy and paper-mars
/// by 0.10-0.13 % (p99), but mars-dust by 0.87 % (2.3 % at most): its
/// multiply scattered light has a wave of about 15 degrees in azimuth
/// (every other node is 0.46 % p99 from every node marched, every 4th
/// 1.0 %), and the browser test's mars-dust went to 1.99 % p99 at -12
/// degrees (from 0.65 %; bound 2 %); set aside (`docs/engine-tables.md`).
const LAYER_MULTIPLE_STRIDE: (usize, usize) = (1, 2);

/// The transmittance table: for each altitude node and view cosine node
/// above the horizon, XYZ(E_sun T) / XYZ(E_sun) per channel.
fn bake_transmittance(
    sky: &Sky,
    (altitude_nodes, mu_nodes): (usize, usize),
    thickness_m: f64,
    solar: &[f64],
    solar_xyz: &[f64; 3],
    xyz: &dyn Fn(&[f64]) -> Result<[f64; 3]>,
) -> Result<Vec<[f32; 3]>> {
    let scene = sky.scene();
    let (ground, _) = scene.radii_m();
    let mut out = vec![[0.0f32; 3]; altitude_nodes * mu_nodes];
    let mut transmittance = vec![0.0; solar.len()];
    let mut transmitted = vec![0.0; solar.len()];
    for a in 0..altitude_nodes {
        let r = ground + axes::altitude_of_node(a, altitude_nodes, thickness_m);
        for m in 0..mu_nodes {
            // The horizon node a hair above the horizon (a grazing ray).
            let mu = axes::transmittance_mu_of_node(m, mu_nodes, r, ground)
                .max(axes::horizon_cosine(r, ground) + 1e-9);
            let direction = Vector3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
            if scene.compute_transmittance_to_top(
                Vector3::new(0.0, 0.0, r),
                direction,
                &mut transmittance,
            ) {
                for ((o, t), e) in transmitted.iter_mut().zip(&transmittance).zip(solar) {
                    *o = t * e;
                }
                let c = xyz(&transmitted)?;
                out[a * mu_nodes + m] = std::array::from_fn(|i| {
                    (c[i] / solar_xyz[i].max(1e-300)).clamp(0.0, 1.0) as f32
                });
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
pub(crate) mod tests;
