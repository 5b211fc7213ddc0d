//! The front door: one [`Sky`], built once from an atmosphere, the sun and
//! the eye, a wavelength grid and the choice of physics and method, that
//! answers every question the library can ask of a sky.
//!
//! - [`Sky::radiance`] and [`Sky::radiances`]: the spectral radiance
//!   (W m^-2 sr^-1 nm^-1) of one view or of many views in one call, with
//!   standard errors when path tracing;
//! - [`Sky::render_xyz`] and [`Sky::render_spectral`]: an image for a
//!   camera, as CIE XYZ or as radiance per wavelength, with the sun's disc
//!   energy-true at any resolution (`sky/sun_disc.rs`);
//! - [`Sky::irradiance`]: direct, diffuse and global irradiance on a plane
//!   (`sky/irradiance.rs`);
//! - [`Sky::aerial_perspective`]: the light of the air between the eye and
//!   a point of a scene and the segment's transmittance, the same terms
//!   along a segment (`sky/aerial_perspective.rs`);
//! - with [`Polarisation::Vector`], the Stokes vector of each view
//!   ([`SkyRadiance::stokes`]) and of each pixel
//!   ([`Sky::render_stokes_xyz`]); `docs/polarisation.md` says which
//!   methods follow it.
//!
//! This is the one place where single scattering and the multiply
//! scattered light are added: what [`Scattering`] asks for is composed
//! here and nowhere else. The expensive parts are built once, on first
//! use, and kept: the multiple-scattering field (used by every view, so an
//! almucantar of 72 directions costs about as much as one), and for images
//! the sun-column, source and sky-view tables.
//!
//! # Methods ([`Method`])
//! - [`Method::Fast`]: single scattering by Gauss-Legendre columns
//!   (`crate::transport::single_scattering`) with exact columns toward the
//!   sun for views, a sun-column table and a sky-view table for images
//!   (within 0.1 % of the exact path); the higher orders from the
//!   discrete-ordinate field, synthesised exactly along each view, or read
//!   from its source table for images
//!   (`crate::transport::multiple_scattering`).
//! - [`Method::Reference`]: the paper's uniform double march for single
//!   scattering per view and per pixel (slow: the oracle the fast method
//!   is tested against), plus the field's exact synthesis for views, and
//!   the march of its source table for images (as the fast image's
//!   sky-view table does; a fast 24 x 24 fisheye at sun 36 degrees differs
//!   by up to 4.1e-3 in XYZ from one whose higher orders are synthesised
//!   exactly per pixel, against 1.7e-3 from this reference).
//! - [`Method::PathTracing`]: the Monte Carlo path tracer (all orders,
//!   unbiased, with standard errors; views only).
//!
//! The sun's disc is part of images only (`ImageSettings::draw_sun_disc`);
//! a view's radiance is the sky's, and the direct beam is in
//! [`Sky::irradiance`] and [`Sky::direct_normal_irradiance`].
//!
//! Views and pixels run in parallel with the `parallel` feature; each is
//! computed by the same code whatever the thread count or the number of
//! views asked for together, so `radiances(&[v])[0] == radiance(v)` to the
//! last bit, with one exception: from [`TABLE_VIEW_COUNT`] views on,
//! [`Sky::radiances`] of the fast method reads its views from the image
//! tables, as an image's pixels are (measured over 256 views of
//! earth-clear: within 0.27 % of the exact path in I, the worst near the
//! horizon 10 degrees in azimuth from the sun, and 1.4e-3 in the degree of polarisation; 1 % in
//! twilight; [`Sky::radiances_exact`] keeps the exact path).

mod aerial_perspective;
mod irradiance;
mod k_terms;
mod names;
mod shared_field;
mod sun_disc;

pub(crate) use shared_field::SharedField;

pub use crate::transport::multiple_scattering::MultipleScatteringSettings;
pub use aerial_perspective::AerialPerspective;
pub use irradiance::{Irradiance, MAX_REFERENCE_IRRADIANCE_STEPS, Plane, check_irradiance_work};
pub(crate) use sun_disc::LIMB_DARKENING as SUN_LIMB_DARKENING;

use std::sync::{Arc, OnceLock};

use crate::atmosphere::phase_matrix::PhaseMatrix;
use crate::atmosphere::{Atmosphere, AtmosphereOptics};
use crate::camera::Camera;
use crate::colour::{SpectrumToXyz, Xyz};
use crate::error::{Error, Result};
use crate::geometry::{Vector3, ViewDirection};
use crate::spectrum::{SampledSpectrum, WavelengthGrid};
use crate::transport::multiple_scattering::{
    FieldRequest, MultipleScatteringField, MultipleScatteringScratch, MultipleScatteringTable,
    PolarisationRows, PolarisationTable,
};
use crate::transport::path_tracing::worst_relative_error;
use crate::transport::stokes::{meridian_reference, rotation_cos_sin_2eta, scattering_plane};
use crate::transport::{
    Observation, PathTracer, SingleScatteringScratch, SingleScatteringSky, SkyViewTable, SunColumns,
};

/// Which orders of scattering a sky has.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scattering {
    /// Sunlight scattered once, plus the sunlit ground (the paper's model).
    Single,
    /// All orders, and skylight reflected by the ground, at this resolution.
    Multiple(MultipleScatteringSettings),
}

impl Scattering {
    /// All orders at the default resolution.
    pub fn multiple() -> Scattering {
        Scattering::Multiple(MultipleScatteringSettings::default())
    }

    /// This scattering with the multiple-scattering field's `streams` per
    /// hemisphere and `layers` where given (the CLI's `--streams` and
    /// `--layers`, Python's `streams=` and `layers=`); validated as the
    /// sky's builder does. Giving either for single scattering or for the
    /// path tracer (which have no discrete-ordinate field) is an error.
    pub fn with_resolution(
        self,
        method: Method,
        streams: Option<usize>,
        layers: Option<usize>,
    ) -> Result<Scattering> {
        if streams.is_none() && layers.is_none() {
            return Ok(self);
        }
        if let Method::PathTracing { .. } = method {
            return Err(Error::Unsupported(
                "streams and layers apply to the fast and reference methods (the path tracer has no discrete-ordinate field)".into(),
            ));
        }
        match self {
            Scattering::Single => Err(Error::Unsupported(
                "streams and layers apply to multiple scattering (not single scattering)".into(),
            )),
            Scattering::Multiple(mut settings) => {
                if let Some(streams) = streams {
                    settings.streams_per_hemisphere = streams;
                }
                if let Some(layers) = layers {
                    settings.layers = layers;
                }
                settings.validate()?;
                Ok(Scattering::Multiple(settings))
            }
        }
    }
}

/// How the radiance is computed (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Gauss-Legendre columns for views, tables for images.
    Fast,
    /// The paper's uniform midpoint march with these step counts along the
    /// view ray and toward the sun.
    Reference {
        /// Midpoint steps along the view ray.
        view_steps: usize,
        /// Midpoint steps toward the sun from each view step.
        sun_steps: usize,
    },
    /// Monte Carlo: `samples` paths per view (at least 2), drawn with
    /// `seed` (the same seed gives the same result on any thread count).
    PathTracing {
        /// Paths per view.
        samples: u64,
        /// The random seed.
        seed: u64,
    },
}

impl Method {
    /// The reference method's default step counts. The uniform midpoint
    /// march converges as 1/N^2; measured against the converged radiance
    /// (clear-sky reference and earth-clear, sun 30 deg, five directions
    /// from the zenith to 0.5 deg): 400/100 steps 3.7e-3, 800/200 9.5e-4,
    /// so 1000/250 stays within ~0.1%.
    pub const REFERENCE_DEFAULT: Method = Method::Reference {
        view_steps: 1000,
        sun_steps: 250,
    };
}

/// Whether the polarisation of the light is followed.
///
/// The default of every front end (the library's [`Sky::builder`], the
/// command line, Python) is [`Polarisation::for_method`]: vector light,
/// the more accurate, except with the reference march, which is scalar.
/// Its names, `"scalar"` and `"vector"`, are the one spelling of every
/// front end ([`std::str::FromStr`], [`std::fmt::Display`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Polarisation {
    /// Light as a scalar intensity (what radiative-transfer codes call the
    /// scalar approximation; up to a few per cent off in a clear sky).
    Scalar,
    /// Stokes vectors through every scattering: the polarised intensity and
    /// Q, U and V, referred to the meridian plane of each view (the
    /// convention is in `transport/stokes.rs`, summarised at
    /// [`Stokes`]). From the path tracer (views) and from the fast method
    /// (views and images, all orders; its multiple scattering polarised by
    /// a column solved with Stokes vectors, `docs/polarisation.md`):
    /// [`Sky::render_xyz`] and [`Sky::render_spectral`] give the polarised
    /// intensity, [`Sky::render_stokes_xyz`] all four components. Mie
    /// species get their phase matrix computed when the sky is built.
    Vector,
}

impl Polarisation {
    /// The default light for `method`: [`Polarisation::Vector`], except
    /// [`Polarisation::Scalar`] for the reference march (which has no
    /// Stokes vectors).
    pub fn for_method(method: Method) -> Polarisation {
        match method {
            Method::Reference { .. } => Polarisation::Scalar,
            Method::Fast | Method::PathTracing { .. } => Polarisation::Vector,
        }
    }
}

impl std::fmt::Display for Polarisation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Polarisation::Scalar => "scalar",
            Polarisation::Vector => "vector",
        })
    }
}

impl std::str::FromStr for Polarisation {
    type Err = Error;

    /// `"scalar"` or `"vector"`; anything else is a one-line error naming
    /// the value and the choices.
    fn from_str(name: &str) -> Result<Polarisation> {
        match name {
            "scalar" => Ok(Polarisation::Scalar),
            "vector" => Ok(Polarisation::Vector),
            other => Err(Error::parse(
                "polarisation",
                0,
                format!("'{other}' is unknown: use 'scalar' or 'vector'"),
            )),
        }
    }
}

/// Resolution of the fast method's image tables.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FastTableSize {
    /// Sun-column table: altitude nodes, mu nodes. The multiple-scattering
    /// field's spherical first order and tilted peak beam read their
    /// columns toward the sun from the same table, so this size reaches
    /// the radiance of a view too at a low sun: 32 x 64 nodes move a view
    /// by at most 0.11 % from the default at suns 5 to -8 degrees (measured
    /// on earth-clear, earth-hazy and mars-dust, 440-680 nm), by under 1e-5
    /// at 10 degrees.
    pub sun_column_nodes: (usize, usize),
    /// Sky-view table: nodes per half of the zenith axis, azimuth nodes.
    pub sky_view_nodes: (usize, usize),
}

impl Default for FastTableSize {
    fn default() -> FastTableSize {
        FastTableSize {
            sun_column_nodes: (128, 256),
            sky_view_nodes: (128, 48),
        }
    }
}

/// Largest image side, pixels.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Most paths per view of the path tracer ([`Method::PathTracing`]).
pub use crate::transport::path_tracing::MAX_SAMPLES;

/// Refuses an image side outside 1..=[`MAX_IMAGE_SIDE`] pixels: checked by
/// every render, and by `sora render` before any work.
pub fn check_image_size(width: u32, height: u32) -> Result<()> {
    image_side("image width", width.into())?;
    image_side("image height", height.into())?;
    Ok(())
}

/// One side of an image, `name` ("image width" or "image height"), as a
/// user gave it (any integer: the command line's `--width -5` and
/// Python's `width=-5` reach here), checked against 1..=[`MAX_IMAGE_SIDE`]
/// pixels: the one message for every front end.
pub fn image_side(name: &str, side: i64) -> Result<u32> {
    u32::try_from(side)
        .ok()
        .filter(|side| (1..=MAX_IMAGE_SIDE).contains(side))
        .ok_or_else(|| {
            Error::out_of_range(name, side as f64, "pixels", format!("1..={MAX_IMAGE_SIDE}"))
        })
}

/// Most steps of the reference method's march along a view or toward the
/// sun ([`Method::Reference`]).
pub const MAX_REFERENCE_STEPS: usize = 10_000_000;

/// Most steps of the reference method's march for one view, view steps x
/// sun steps: 1e8, 400 times the default 1000 x 250, about 3.5 s a view at
/// 21 wavelengths by the rate of docs/limits.md (113 views/s at the
/// default); the twilight survey's finest is 16000 x 4000. 1e7 x 1e7 steps
/// would have taken weeks a view.
pub const MAX_REFERENCE_MARCH_STEPS: f64 = 1e8;

/// Most views of one [`Sky::radiances`] call (an almucantar every 0.0036
/// deg); checked before any work, as `sora spectrum` checks its directions
/// before it lists them.
pub const MAX_VIEWS: usize = 100_000;

/// Most views x wavelengths of one [`Sky::radiances`] call: 1e7 values,
/// 160 MB of radiances and standard errors.
pub const MAX_VIEW_VALUES: usize = 10_000_000;

/// Refuses more than [`MAX_VIEWS`] views, or more than [`MAX_VIEW_VALUES`]
/// views x wavelengths, naming `what` asked for them (a count as f64, so
/// that a step's count past any integer is refused too).
pub fn check_view_count(what: &str, views: f64, wavelengths: usize) -> Result<()> {
    if views.is_nan() || views > MAX_VIEWS as f64 {
        return Err(Error::Unsupported(format!(
            "{what} gives {views:e} directions, more than the limit of {MAX_VIEWS}: use a coarser step or fewer directions"
        )));
    }
    let values = views * wavelengths as f64;
    if values > MAX_VIEW_VALUES as f64 {
        return Err(Error::Unsupported(format!(
            "{what} gives {views} directions x {wavelengths} wavelengths = {values:e} values, more than the limit of {MAX_VIEW_VALUES:e}: use fewer directions or a coarser --wavelengths"
        )));
    }
    Ok(())
}

/// Largest image buffer [`Sky::render_xyz`] or [`Sky::render_spectral`]
/// allocates, bytes (4 GiB): width x height x values per pixel (1 XYZ of 24
/// bytes, or one 8-byte radiance per wavelength). Checked before anything
/// is computed; a 16384 x 16384 XYZ image (6 GiB) or a 1024 x 1024 spectral
/// image of 1000 wavelengths (8 GiB) is refused.
pub const MAX_IMAGE_BUFFER_BYTES: u64 = 4 << 30;

/// An image to render: camera, size, and whether the sun's disc is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageSettings {
    /// Which direction each pixel sees.
    pub camera: Camera,
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
    /// Draw the sun's disc (with limb darkening), attenuated by the air.
    pub draw_sun_disc: bool,
}

impl ImageSettings {
    /// `camera` at `width` x `height` pixels, with the sun's disc.
    pub fn new(camera: Camera, width: u32, height: u32) -> ImageSettings {
        ImageSettings {
            camera,
            width,
            height,
            draw_sun_disc: true,
        }
    }
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
    /// sum_j w_j times each part, field by field (the k-distribution's sum
    /// over its terms, `atmosphere::gas_bands`; the parts of one view on
    /// one grid). Standard errors add as sum_j w_j se_j, the bound for
    /// errors that may be correlated (the terms are traced with one seed).
    pub fn weighted_sum(parts: &[(f64, SkyRadiance)]) -> SkyRadiance {
        let stokes = parts
            .iter()
            .map(|(w, p)| p.stokes.as_ref().map(|s| (*w, s)))
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
                parts.iter().map(|(w, p)| (*w, &p.radiance_w_m2_sr_nm)),
            ),
            standard_error_w_m2_sr_nm: parts
                .iter()
                .map(|(w, p)| p.standard_error_w_m2_sr_nm.as_ref().map(|e| (*w, e)))
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

/// The parts of a [`Sky`] (see [`Sky::builder`]).
#[derive(Debug, Clone)]
pub struct SkyBuilder<'a> {
    atmosphere: &'a Atmosphere,
    wavelengths: WavelengthGrid,
    observation: Observation,
    scattering: Scattering,
    method: Method,
    table_size: FastTableSize,
    polarisation: Option<Polarisation>,
}

impl SkyBuilder<'_> {
    /// Sun elevation above the horizon (-90..=90; negative: below it) and
    /// azimuth clockwise from north, degrees. Default: 90 (the zenith), 180.
    pub fn sun_deg(mut self, elevation_deg: f64, azimuth_deg: f64) -> Self {
        self.observation.sun_elevation_deg = elevation_deg;
        self.observation.sun_azimuth_deg = azimuth_deg;
        self
    }

    /// Height of the eye above the ground, m (default 0; may be above the
    /// atmosphere).
    pub fn observer_altitude_m(mut self, altitude_m: f64) -> Self {
        self.observation.observer_altitude_m = altitude_m;
        self
    }

    /// The wavelength grid (default: the paper's 380-780 nm every 20 nm).
    pub fn wavelengths(mut self, grid: WavelengthGrid) -> Self {
        self.wavelengths = grid;
        self
    }

    /// Orders of scattering (default: all, [`Scattering::multiple`]).
    pub fn scattering(mut self, scattering: Scattering) -> Self {
        self.scattering = scattering;
        self
    }

    /// Method (default [`Method::Fast`]).
    pub fn method(mut self, method: Method) -> Self {
        self.method = method;
        self
    }

    /// Resolution of the fast method's image tables.
    pub fn table_size(mut self, table_size: FastTableSize) -> Self {
        self.table_size = table_size;
        self
    }

    /// Scalar or vector (Stokes) light (default
    /// [`Polarisation::for_method`]: vector, scalar for the reference
    /// march).
    pub fn polarisation(mut self, polarisation: Polarisation) -> Self {
        self.polarisation = Some(polarisation);
        self
    }

    /// Checks every choice and puts the atmosphere on the grid (the
    /// expensive tables wait for their first use).
    pub fn build(self) -> Result<Sky> {
        let mut sky = self.build_for(self.atmosphere)?;
        // Banded gases: one sky per k-distribution term (`sky/k_terms.rs`).
        sky.k_terms = k_terms::term_skies(self.atmosphere, |at_term| self.build_for(at_term))?;
        Ok(sky)
    }

    /// [`SkyBuilder::build`] of `atmosphere` as one solve.
    fn build_for(&self, atmosphere: &Atmosphere) -> Result<Sky> {
        let polarisation = self
            .polarisation
            .unwrap_or(Polarisation::for_method(self.method));
        let scene = SingleScatteringSky::new_with_phase_matrices(
            atmosphere,
            &self.wavelengths,
            self.observation,
            polarisation == Polarisation::Vector,
        )?;
        let mut sky = Sky::from_scene(scene, self.scattering, self.method, self.table_size)?;
        // The angles as given (the azimuth in one turn), not as recovered
        // from the unit vector.
        sky.sun_position_deg = (
            self.observation.sun_elevation_deg,
            crate::geometry::azimuth_in_one_turn_deg(self.observation.sun_azimuth_deg),
        );
        sky.set_polarisation(polarisation)?;
        Ok(sky)
    }
}

/// A sky: an atmosphere on a wavelength grid, the sun, the eye, and the
/// choice of physics and method (see the module docs).
#[derive(Debug)]
pub struct Sky {
    scene: SingleScatteringSky,
    /// Sun elevation and azimuth, degrees.
    sun_position_deg: (f64, f64),
    scattering: Scattering,
    method: Method,
    table_size: FastTableSize,
    polarisation: Polarisation,
    /// The multiple-scattering field over every sun zenith angle the eye's
    /// rays meet (built on first use).
    field: OnceLock<Arc<MultipleScatteringField>>,
    /// The field's source table, for images (built on first use).
    source_table: OnceLock<MultipleScatteringTable>,
    /// The fast method's image tables (built on first use).
    image_tables: OnceLock<ImageTables>,
    /// Views no lower than this (rad) only: the field is solved for the
    /// sun angles their rays meet (`Sky::for_views_above`), and other
    /// views and images are refused.
    lowest_view_elevation_rad: Option<f64>,
    /// The k-distribution's terms, (w_j, the sky of term j), with banded
    /// gases; empty without them (`sky/k_terms.rs`).
    k_terms: Vec<(f64, Sky)>,
}

#[derive(Debug)]
struct ImageTables {
    sky_view: SkyViewTable,
    /// The polarisation correction's ratios over view directions
    /// (polarised skies with multiple scattering).
    polarisation: Option<PolarisationTable>,
}

/// Nodes of the polarisation table (per half of the zenith-cosine axis,
/// azimuth over 0..180 degrees). Images against the per-view Stokes
/// vectors (`tests/polarisation.rs`, luminance-weighted): the degree of
/// polarisation within 3.6e-4 (us-standard, sun 30) and 6.2e-4
/// (earth-clear, sun 8) at 24 x 48 nodes, against 1.2e-3 at 16 x 48 and
/// 3e-4 at 32 x 64; the table costs about a third of a polarised image's
/// precomputation.
const POLARISATION_TABLE_NODES: (usize, usize) = (24, 48);

/// From this many views [`Sky::radiances`] (fast method) reads them from
/// the image tables instead of the exact per-view path. Measured
/// (earth-clear, sun 30, 21 wavelengths, CPU time): the tables cost about
/// as much as 80 exact polarised views of distinct elevations (0.85 s)
/// and 300 scalar ones (0.43 s); 16 384 polarised views through them cost
/// 1.1 times a 128 x 128 polarised fisheye (`docs/polarisation.md`).
pub const TABLE_VIEW_COUNT: usize = 256;

/// Views a task when many views are read from the image tables.
const PIXEL_VIEWS_PER_TASK: usize = 64;

/// Views a task on the exact per-view path.
const VIEWS_PER_TASK: usize = 4;

/// The zenith cosine of a view (the polarisation correction's axis).
fn view_cosine(view: &ViewDirection) -> f64 {
    view.elevation_deg().to_radians().sin()
}

/// Per-thread buffers of one view's computation (no allocation per view).
struct ViewWork {
    single: SingleScatteringScratch,
    multiple: Option<MultipleScatteringScratch>,
    /// species * wavelengths integrals (m) of the sky-view table and of the
    /// forward-peak term.
    integrals: Vec<f64>,
    forward: Vec<f64>,
    phase: Vec<f64>,
    /// The fast method's terms of the view or pixel.
    terms: ViewTerms,
    /// Phase matrices per wavelength (polarised single scattering).
    matrices: Vec<PhaseMatrix>,
    /// The multiply scattered light's I, Q, U, V (polarised skies).
    multiple_stokes: Vec<f64>,
    /// The light the polarisation correction applies to
    /// ([`ViewTerms::polarisation_corrected`]).
    corrected: Vec<f64>,
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
struct ViewTerms {
    /// Single scattering by the air (`transport/single_scattering.rs`; the
    /// reference method's march, with its sunlit ground).
    single: Vec<f64>,
    /// The scaled field's light scattered by the air: orders >= 2 (zero
    /// for a sky without multiple scattering).
    field: Vec<f64>,
    /// The forward-peak term of delta-M (`forward_peak.rs`), polarised as
    /// single scattering.
    forward_peak: Vec<f64>,
    /// The directly sunlit ground (A / pi) E mu_s T_sun T_view.
    ground_sunlit: Vec<f64>,
    /// The skylight the ground reflects (from the scaled field, with the
    /// sunlight delta-M moved into its beam), through the scaled view
    /// transmittance. The polarisation correction's ratios apply to it and
    /// to `field` (the correction's own radiance holds both).
    ground_skylit: Vec<f64>,
}

impl ViewTerms {
    fn new(wavelengths: usize) -> ViewTerms {
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
    fn add_into(&self, radiance: &mut [f64]) {
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
fn sky_radiance_from_traced(
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
    /// Starts a sky of `atmosphere`: the sun at the zenith, the eye on the
    /// ground, the paper's wavelengths, all orders of scattering, the fast
    /// method, polarised light ([`Polarisation::for_method`]); change what
    /// differs, then [`SkyBuilder::build`].
    ///
    /// ```
    /// # fn main() -> sora::Result<()> {
    /// use sora::{Atmosphere, Sky, ViewDirection};
    /// let atmosphere = Atmosphere::preset("earth-clear")?;
    /// let sky = Sky::builder(&atmosphere).sun_deg(30.0, 180.0).build()?;
    /// let zenith = sky.radiance(ViewDirection::new(90.0, 0.0)?)?;
    /// assert!(zenith.radiance_w_m2_sr_nm.values().iter().all(|l| *l > 0.0));
    /// # Ok(())
    /// # }
    /// ```
    pub fn builder(atmosphere: &Atmosphere) -> SkyBuilder<'_> {
        SkyBuilder {
            atmosphere,
            wavelengths: WavelengthGrid::paper(),
            observation: Observation {
                observer_altitude_m: 0.0,
                sun_elevation_deg: 90.0,
                sun_azimuth_deg: 180.0,
            },
            scattering: Scattering::multiple(),
            method: Method::Fast,
            table_size: FastTableSize::default(),
            polarisation: None,
        }
    }

    /// A sky from a scene already on its grid (optics, planet, eye, sun).
    pub(crate) fn from_scene(
        scene: SingleScatteringSky,
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
            lowest_view_elevation_rad: None,
            k_terms: Vec::new(),
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
        sky.k_terms = self
            .k_terms
            .iter()
            .map(|(w, term)| Ok((*w, term.with_sun_deg(elevation_deg, azimuth_deg)?)))
            .collect::<Result<_>>()?;
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
        self.k_terms = std::mem::take(&mut self.k_terms)
            .into_iter()
            .map(|(w, term)| (w, term.for_views_above(views)))
            .collect();
        self
    }

    /// An error if the field was restricted to views above some elevation
    /// and `elevation_deg` (a view's; None for an image) is not one of them.
    fn check_within_restricted_field(&self, elevation_deg: Option<f64>) -> Result<()> {
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
    fn set_polarisation(&mut self, polarisation: Polarisation) -> Result<()> {
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
    pub(crate) fn scene(&self) -> &SingleScatteringSky {
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
    fn prepare_field_for_images(&self) -> Result<()> {
        self.check_within_restricted_field(None)?;
        self.prepare_field()
    }

    /// Solves the multiple-scattering field if the sky has one and it is
    /// not solved yet. Every entry point calls it before its parallel loop:
    /// a worker that stole work inside the (parallel) solve must not find
    /// the field half-made, and the loops read it with [`Sky::field`].
    fn prepare_field(&self) -> Result<()> {
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
    fn field(&self) -> Option<&MultipleScatteringField> {
        debug_assert!(self.scattering == Scattering::Single || self.field.get().is_some());
        self.field.get().map(Arc::as_ref)
    }

    /// The field's source table, built on first use.
    fn source_table(&self) -> Option<&MultipleScatteringTable> {
        let field = self.field.get()?;
        Some(
            self.source_table
                .get_or_init(|| MultipleScatteringTable::compute(Arc::clone(field))),
        )
    }

    /// The fast method's image tables, built on first use.
    fn image_tables(&self) -> &ImageTables {
        self.image_tables.get_or_init(|| {
            let (altitude_nodes, mu_nodes) = self.table_size.sun_column_nodes;
            let sun_columns = self.scene.sun_column_table(altitude_nodes, mu_nodes);
            let (half_zenith, azimuth) = self.table_size.sky_view_nodes;
            let sky_view = SkyViewTable::compute_with_multiple_scattering(
                &self.scene,
                &sun_columns,
                self.source_table(),
                half_zenith,
                azimuth,
            );
            let polarisation = self
                .field()
                .and_then(|field| field.compute_polarisation_table(POLARISATION_TABLE_NODES));
            ImageTables {
                sky_view,
                polarisation,
            }
        })
    }

    fn view_work(&self) -> ViewWork {
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
        }
    }

    /// The spectral radiance arriving at the eye from `view`.
    pub fn radiance(&self, view: ViewDirection) -> Result<SkyRadiance> {
        let mut all = self.radiances(&[view])?;
        Ok(all.remove(0))
    }

    /// The spectral radiance of every view in `views`, in order, reusing
    /// every table (see the module docs). With [`Method::Fast`] and at
    /// least [`TABLE_VIEW_COUNT`] views the views are read from the image
    /// tables ([`Sky::radiance_from_image_tables`]; within 0.27 % of the
    /// exact path by day, the worst near the horizon close to the sun's
    /// azimuth, 1 % in twilight);
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
            return self.sum_term_radiances(|k, term| {
                term.compute_radiances(
                    views,
                    &|done, total| {
                        let (done, total) = self.term_progress(k, done, total);
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
        // `SingleScatteringSky::polarised_radiance_from_integrals`).
        for view in views {
            self.check_within_restricted_field(Some(view.elevation_deg()))?;
        }
        self.prepare_field()?;
        if tables_allowed
            && self.method == Method::Fast
            && self.lowest_view_elevation_rad.is_none()
            && views.len() >= TABLE_VIEW_COUNT
        {
            return self.radiances_from_image_tables(views, progress);
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
    fn polarisation_rows<'a>(
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
    fn compute_views_in_parallel<V: Copy + Sync>(
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
        values
            .chunks(per_view)
            .map(|values| sky_radiance_from_values(values, wavelengths))
            .collect()
    }

    /// A polarised view's Stokes Q, U and V into `stokes` and its polarised
    /// intensity in place of the scalar one in `radiance`, from the terms
    /// and integrals [`Sky::compute_view_terms`] left in `work` (the view,
    /// and the altitude its segment ends at, m, infinity for the whole
    /// ray).
    fn compute_view_stokes(
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
        let (k_in, k_out) = (-self.sun_direction(), -w);
        let normal = scattering_plane(k_in, k_out, meridian);
        let (c, s) = rotation_cos_sin_2eta(k_out, normal.cross(k_out), meridian);
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
    /// with [`Method::Fast`] by day away from the sun (0.27 % near the
    /// horizon 10 degrees in azimuth from it, earth-clear) and within 1 % in twilight (measured
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
        if !self.k_terms.is_empty() {
            return self.sum_term_radiances(|k, term| {
                term.radiances_from_image_tables(views, &|done, total| {
                    let (done, total) = self.term_progress(k, done, total);
                    progress(done, total)
                })
            });
        }
        self.prepare_field_for_images()?;
        let tables = self.image_tables();
        let polarised = self.polarisation == Polarisation::Vector;
        Ok(self.compute_views_in_parallel(
            views,
            PIXEL_VIEWS_PER_TASK,
            progress,
            |view, work, radiance, stokes| {
                let view = view.to_vector();
                self.compute_pixel_radiance(view, tables, work, radiance);
                if polarised {
                    self.add_pixel_stokes(view, tables, work, radiance, stokes);
                }
            },
        ))
    }

    /// One view's radiance without image tables (fast or reference method),
    /// into `radiance`, W m^-2 sr^-1 nm^-1: single scattering and the sunlit
    /// ground, plus the higher orders, synthesised exactly from the field or
    /// (`source_table`, for reference images) read from its source table.
    fn compute_view_radiance(
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
    fn compute_view_terms(
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

    /// One pixel's radiance from the image tables (fast method), into
    /// `radiance`: the sky-view table's integrals, ground and multiply
    /// scattered light with the exact phase functions (the sun's disc is
    /// added per image, see [`sun_disc`]).
    fn compute_pixel_radiance(
        &self,
        view: Vector3,
        tables: &ImageTables,
        work: &mut ViewWork,
        radiance: &mut [f64],
    ) {
        let cos_theta = view.dot(self.sun_direction());
        let terms = &mut work.terms;
        tables.sky_view.lookup_with_multiple_scattering(
            view,
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
    fn add_pixel_stokes(
        &self,
        view: Vector3,
        tables: &ImageTables,
        work: &mut ViewWork,
        radiance: &mut [f64],
        stokes: &mut [f64],
    ) {
        let (elevation_deg, azimuth_deg) = crate::geometry::elevation_azimuth_from_direction(view);
        stokes.fill(0.0);
        self.compute_single_scattering_stokes(
            (view, meridian_reference(elevation_deg, azimuth_deg)),
            SingleIntegrals::Pixel,
            work,
            stokes,
        );
        let Some(table) = &tables.polarisation else {
            return;
        };
        let azimuth_rad = (azimuth_deg - self.sun_position_deg.1).to_radians();
        let ratios = &mut work.multiple_stokes;
        table.lookup_ratios((view.z, azimuth_rad), ratios);
        work.terms.polarisation_corrected(&mut work.corrected);
        add_corrected_multiple_stokes(ratios, &work.corrected, radiance, stokes);
    }

    /// Builds everything images of this sky need (the multiple-scattering
    /// field and its source table; for the fast method the sun-column and
    /// sky-view tables), so that a progress display can show it as its
    /// own phase; rendering does it on first use otherwise.
    pub fn prepare_images(&self) -> Result<()> {
        if !self.k_terms.is_empty() {
            for (_, term) in &self.k_terms {
                term.prepare_images()?;
            }
            return Ok(());
        }
        self.prepare_field_for_images()?;
        self.source_table();
        if self.method == Method::Fast {
            self.image_tables();
        }
        Ok(())
    }

    /// `to_xyz` must be on the sky's grid, and the grid must have a
    /// wavelength in 360-830 nm (colour comes from those; see
    /// [`SpectrumToXyz`]).
    fn check_colour_conversion(&self, to_xyz: &SpectrumToXyz) -> Result<()> {
        if to_xyz.grid() != self.wavelengths() {
            return Err(Error::InvalidSpectrum(
                "the colour conversion and the sky use different wavelength grids".into(),
            ));
        }
        if to_xyz.colour_sample_count() == 0 {
            return Err(Error::Unsupported(format!(
                "no wavelength of the grid {} lies in {}-{} nm, the range of the colour-matching functions, so it gives no colour: use a grid that overlaps that range (a spectral image takes any grid)",
                self.wavelengths(),
                crate::colour::CIE_MIN_WAVELENGTH_NM,
                crate::colour::CIE_MAX_WAVELENGTH_NM
            )));
        }
        Ok(())
    }

    /// The image `image` as CIE XYZ per pixel (row-major, top row first;
    /// black where the camera sees nothing), converted by `to_xyz` (which
    /// must be on the sky's grid; colour comes from the grid's wavelengths
    /// in 360-830 nm, and a grid with none there is an error);
    /// `progress(rows)` is called as rows complete (from worker threads).
    pub fn render_xyz(
        &self,
        image: &ImageSettings,
        to_xyz: &SpectrumToXyz,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Vec<Xyz>> {
        self.check_colour_conversion(to_xyz)?;
        if !self.k_terms.is_empty() {
            return self.sum_term_images(
                progress,
                Xyz::BLACK,
                k_terms::add_scaled_xyz,
                |term, p| term.render_xyz(image, to_xyz, p),
            );
        }
        let n = self.wavelengths().len();
        self.render_pixels(image, 1, Xyz::BLACK, progress, |radiance, pixel| {
            pixel[0] = to_xyz.to_xyz_unchecked(&radiance[..n])
        })
    }

    /// The image `image` of a polarised sky ([`Polarisation::Vector`]) as
    /// the CIE XYZ of its Stokes vector per pixel: [S0, S1, S2, S3] = the
    /// XYZ of the spectra I, Q, U and V (XYZ is linear in the spectrum, so
    /// Q, U and V map as I does and may be negative), Q and U referred to
    /// each pixel's meridian plane (the convention of [`Stokes`]); the
    /// sun's disc, unpolarised, adds to S0 only. Row-major, top row first,
    /// black where the camera sees nothing. An error for a scalar sky.
    pub fn render_stokes_xyz(
        &self,
        image: &ImageSettings,
        to_xyz: &SpectrumToXyz,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Vec<[Xyz; 4]>> {
        if self.polarisation != Polarisation::Vector {
            return Err(Error::Unsupported(
                "Stokes images: the sky is scalar; build it with Polarisation::Vector".into(),
            ));
        }
        self.check_colour_conversion(to_xyz)?;
        if !self.k_terms.is_empty() {
            let add = |sum: &mut [Xyz; 4], w: f64, x: &[Xyz; 4]| {
                for (s, x) in sum.iter_mut().zip(x) {
                    k_terms::add_scaled_xyz(s, w, x);
                }
            };
            return self.sum_term_images(progress, [Xyz::BLACK; 4], add, |term, p| {
                term.render_stokes_xyz(image, to_xyz, p)
            });
        }
        let n = self.wavelengths().len();
        self.render_pixels(image, 1, [Xyz::BLACK; 4], progress, |stokes, pixel| {
            pixel[0] = [
                to_xyz.to_xyz_unchecked(&stokes[..n]),
                to_xyz.weighted_sum(&stokes[n..2 * n]),
                to_xyz.weighted_sum(&stokes[2 * n..3 * n]),
                to_xyz.weighted_sum(&stokes[3 * n..]),
            ]
        })
    }

    /// The image `image` as spectral radiance, W m^-2 sr^-1 nm^-1:
    /// `width * height * wavelengths` values, pixel-major (row-major
    /// pixels, top row first, each pixel's wavelengths together).
    pub fn render_spectral(
        &self,
        image: &ImageSettings,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Vec<f64>> {
        if !self.k_terms.is_empty() {
            let add = |sum: &mut f64, w: f64, x: &f64| *sum += w * x;
            return self
                .sum_term_images(progress, 0.0, add, |term, p| term.render_spectral(image, p));
        }
        let wavelengths = self.wavelengths().len();
        self.render_pixels(image, wavelengths, 0.0, progress, |radiance, pixel| {
            pixel.copy_from_slice(&radiance[..wavelengths])
        })
    }

    /// Renders every pixel's radiance and stores it through `store` into
    /// `per_pixel` values of type T: `store` gets the pixel's spectral
    /// radiance (the polarised intensity I of a polarised sky), followed
    /// for a polarised sky by its Q, U and V.
    fn render_pixels<T: Copy + Send>(
        &self,
        image: &ImageSettings,
        per_pixel: usize,
        black: T,
        progress: &(dyn Fn(usize) + Sync),
        store: impl Fn(&[f64], &mut [T]) + Sync,
    ) -> Result<Vec<T>> {
        let (width, height) = (image.width, image.height);
        check_image_size(width, height)?;
        let buffer_bytes = u64::from(width)
            * u64::from(height)
            * per_pixel as u64
            * std::mem::size_of::<T>() as u64;
        if buffer_bytes > MAX_IMAGE_BUFFER_BYTES {
            return Err(Error::out_of_range(
                format!(
                    "image buffer ({width} x {height} pixels x {per_pixel} values of {} bytes)",
                    std::mem::size_of::<T>()
                ),
                buffer_bytes as f64 / f64::from(1u32 << 30),
                "GiB",
                format!(
                    "<= {}: render fewer pixels (or fewer wavelengths for a spectral image)",
                    MAX_IMAGE_BUFFER_BYTES >> 30
                ),
            ));
        }
        if let Method::PathTracing { .. } = self.method {
            return Err(Error::Unsupported(
                "path tracing computes views, not images: render with the fast or reference method"
                    .into(),
            ));
        }
        // Tables first, outside the parallel loop (see `prepare_field`).
        self.prepare_field_for_images()?;
        let source_table = self.source_table();
        let tables = (self.method == Method::Fast).then(|| self.image_tables());
        let wavelengths = self.wavelengths().len();
        let polarised = self.polarisation == Polarisation::Vector;
        let components = if polarised { 4 } else { 1 };
        // The sun's disc: its share of each pixel it touches, per sr.
        let direct_normal = self.direct_normal_irradiance();
        let disc = if image.draw_sun_disc {
            sun_disc::compute_disc_pixels(
                &image.camera,
                width,
                height,
                self.sun_direction(),
                self.scene.sun_angular_radius_rad(),
                |direction| self.scene.sees_sky(direction),
            )
        } else {
            Vec::new()
        };
        let rows_done = std::sync::atomic::AtomicUsize::new(0);
        let row_length = width as usize * per_pixel;
        let mut pixels = vec![black; row_length * height as usize];
        crate::parallel::for_each_chunk_mut(&mut pixels, row_length, |row, values| {
            let mut work = self.view_work();
            let mut spectra = vec![0.0; components * wavelengths];
            for (column, pixel) in values.chunks_mut(per_pixel).enumerate() {
                let Some(view) =
                    image
                        .camera
                        .direction_for_pixel(column as u32, row as u32, width, height)
                else {
                    continue;
                };
                let (radiance, stokes) = spectra.split_at_mut(wavelengths);
                // A polarised sky has the fast method's tables (the
                // reference march is scalar: `Sky::set_polarisation`).
                match tables {
                    Some(tables) => {
                        self.compute_pixel_radiance(view, tables, &mut work, radiance);
                        if polarised {
                            self.add_pixel_stokes(view, tables, &mut work, radiance, stokes);
                        }
                    }
                    None => self.compute_view_radiance(view, source_table, &mut work, radiance),
                }
                let index = row * width as usize + column;
                if let Ok(k) = disc.binary_search_by_key(&index, |(pixel, _)| *pixel) {
                    let per_sr = disc[k].1;
                    for (r, e) in radiance.iter_mut().zip(direct_normal.values()) {
                        *r += e * per_sr;
                    }
                }
                store(&spectra, pixel);
            }
            progress(rows_done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
        });
        Ok(pixels)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
