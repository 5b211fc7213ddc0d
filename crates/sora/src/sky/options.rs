//! What a [`Sky`] is built from: the choice of physics and method
//! ([`Scattering`], [`Method`], [`Polarisation`]), the fast method's table
//! sizes, images ([`ImageSettings`]), the limits every front end checks
//! before any work, and the [`SkyBuilder`].

use super::k_terms;
use super::setup::Sky;

use crate::atmosphere::Atmosphere;
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::spectrum::WavelengthGrid;
use crate::transport::multiple_scattering::MultipleScatteringSettings;
use crate::transport::multiple_scattering::ViewHarmonicsCache;
use crate::transport::single_scattering::ExactSunColumns;
use crate::transport::{Observation, SingleScatteringScene};
use std::sync::Arc;

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

    /// This scattering with the field's
    /// [`MultipleScatteringSettings::twilight_shift_pieces`] where given
    /// (the CLI's `--twilight-shift-pieces`, Python's
    /// `twilight_shift_pieces=`); validated as the sky's builder does, and
    /// an error for single scattering or the path tracer.
    pub fn with_twilight_shift_pieces(
        self,
        method: Method,
        pieces: Option<usize>,
    ) -> Result<Scattering> {
        let Some(pieces) = pieces else {
            return Ok(self);
        };
        match (self, method) {
            (Scattering::Multiple(settings), Method::Fast | Method::Reference { .. }) => {
                let settings = MultipleScatteringSettings {
                    twilight_shift_pieces: pieces,
                    ..settings
                };
                settings.validate()?;
                Ok(Scattering::Multiple(settings))
            }
            _ => Err(Error::Unsupported(
                "twilight shift pieces apply to the fast and reference methods' multiple scattering".into(),
            )),
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
    /// [`Stokes`](super::Stokes)). From the path tracer (views) and from the fast method
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
    colour_images: Option<crate::colour::Observer>,
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

    /// A sky for colour images (XYZ, seen by `observer`) alone: with
    /// banded gases, each sample's k-distribution terms are merged into as
    /// few skies (runs of terms, weights summed, one depth each) as keep
    /// an image's X, Y and Z within `COLOUR_BOUND` (1e-3, relative; summed
    /// over the samples, for any sun; `sky/k_terms.rs`), which costs less
    /// (four skies in place of five for a fisheye with 2.92 cm of water
    /// over 380-780 nm). Its spectral images are refused, and its views,
    /// irradiance and aerial perspective take the merged terms: ask a sky
    /// built without this (the default, every term) for those.
    pub fn for_colour_images(mut self, observer: crate::colour::Observer) -> Self {
        self.colour_images = Some(observer);
        self
    }

    /// Checks every choice and puts the atmosphere on the grid (the
    /// expensive tables wait for their first use).
    pub fn build(self) -> Result<Sky> {
        self.build_with_terms(false)
    }

    /// [`SkyBuilder::build`]; `whole_grid`: every k-distribution term's sky
    /// on the whole grid, also where the terms' atmospheres are the same
    /// (the slow path, the oracle of the tests; `sky/k_terms.rs`).
    pub(crate) fn build_with_terms(self, whole_grid: bool) -> Result<Sky> {
        let mut sky = self.build_for(self.atmosphere, &self.wavelengths, None)?;
        // Banded gases: one sky per k-distribution term (`sky/k_terms.rs`).
        // Terms may leave out negligible higher orders where a sky has them
        // as an addition to single scattering (not the path tracer's).
        // The terms' skies share one store of sun-column tables: the
        // tables hold the species' profile columns alone (no coefficient),
        // the same for every term, so the first term's is every term's
        // (bit for bit; a term that carries fewer species builds its own).
        let leave_out = matches!(self.scattering, Scattering::Multiple(_))
            && !matches!(self.method, Method::PathTracing { .. });
        // The terms' skies march the same view rays toward the same sun
        // through the same profiles: each view's exact columns toward the
        // sun are computed once for all of them (`ExactSunColumns`).
        let sun_columns = Arc::new(ExactSunColumns::default());
        // Their scattering species are the same (the banded gases only
        // absorb): the polarisation correction's phase-matrix harmonics
        // from the streams are computed once for all of them
        // (`ViewHarmonicsCache`, keyed by the scattering species' optics).
        let view_harmonics = Arc::new(ViewHarmonicsCache::default());
        let terms = k_terms::term_skies(
            self.atmosphere,
            &self.wavelengths,
            whole_grid,
            leave_out.then_some(self.observation.observer_altitude_m),
            self.colour_images
                .filter(|_| !whole_grid)
                .map(|observer| (observer, self.observation.observer_altitude_m)),
            |at_term, grid, higher_orders| {
                let mut builder = self.clone();
                if !higher_orders {
                    builder.scattering = Scattering::Single;
                }
                let mut term_sky = builder.build_for(at_term, grid, Some(&sky.scene))?;
                term_sky.scene = term_sky
                    .scene
                    .sharing_exact_sun_columns(&sun_columns)
                    .sharing_view_harmonics(&view_harmonics);
                Ok(term_sky)
            },
        )?;
        sky.k_terms = terms.all;
        sky.k_terms_for_views = terms.for_views;
        sky.view_terms = terms.view_runs;
        sky.colour_only = self.colour_images.is_some() && !sky.k_terms.is_empty();
        Ok(sky)
    }

    /// [`SkyBuilder::build`] of `atmosphere` on `grid` as one solve; with
    /// `tables_of`, sharing that scene's sun-column tables where they are
    /// the same (`SingleScatteringScene::sharing_sun_column_tables_of`).
    fn build_for(
        &self,
        atmosphere: &Atmosphere,
        grid: &WavelengthGrid,
        tables_of: Option<&SingleScatteringScene>,
    ) -> Result<Sky> {
        let polarisation = self
            .polarisation
            .unwrap_or(Polarisation::for_method(self.method));
        // The fast method's multiple scattering takes the Mie phase
        // matrices at its polarisation stride; the rest at every wavelength.
        let stride = match (self.method, self.scattering) {
            (Method::Fast, Scattering::Multiple(settings)) => {
                settings.polarisation_wavelength_stride
            }
            _ => 1,
        };
        let scene = SingleScatteringScene::new_with_phase_matrices(
            atmosphere,
            grid,
            self.observation,
            (polarisation == Polarisation::Vector).then_some(stride),
        )?;
        let scene = match tables_of {
            Some(other) => scene.sharing_sun_column_tables_of(other),
            None => scene,
        };
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
            colour_images: None,
        }
    }
}
