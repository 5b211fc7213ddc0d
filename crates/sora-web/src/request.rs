//! The requests the page sends, as JSON (`"op"` names the request), and
//! the shapes of their replies. Units are in the key names, as in the
//! library and the CLI's JSON output; unknown keys are errors, so a typo in
//! the page fails loudly instead of being ignored.

use serde::Deserialize;

/// One request (`{"op": "render", ...}`).
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "op", rename_all = "snake_case")]
pub enum Request {
    /// The built-in atmospheres: `{"presets": [{"name", "description",
    /// "toml"}]}`.
    Presets,
    /// The controls an atmosphere offers and their values in it (see
    /// [`crate::atmosphere_controls::Controls`]), `null` where a control
    /// does not apply (no ozone on Mars, a tabulated refractive index).
    Controls {
        /// The atmosphere.
        atmosphere: AtmosphereSpec,
    },
    /// A sky image: JSON `{"width", "height", "wavelengths",
    /// "brightest_cd_m2", "night", "exposure_scale"}`, bytes RGBA8
    /// (sRGB display values, row-major, top row first).
    Render {
        /// The sky.
        sky: SkySpec,
        /// The image.
        image: ImageSpec,
    },
    /// The same image as an OpenEXR file (linear sRGB primaries, radiance
    /// units: 1.0 = the XYZ of 1 W m^-2 sr^-1 nm^-1, as `sora render`).
    Exr {
        /// The sky.
        sky: SkySpec,
        /// The image.
        image: ImageSpec,
    },
    /// Which direction a pixel of an image sees: `{"elevation_deg",
    /// "azimuth_deg"}`, or `null` values outside the fisheye's circle.
    ViewAtPixel {
        /// The image's camera and size.
        image: ImageSpec,
        /// Column, 0 at the left.
        column: u32,
        /// Row, 0 at the top.
        row: u32,
    },
    /// One direction's spectrum at the library's default resolution (what
    /// `sora spectrum` computes): the radiance of the sky's scattering and
    /// of single scattering alone, its XYZ, luminance, chromaticity and
    /// display colour.
    Spectrum {
        /// The sky.
        sky: SkySpec,
        /// Degrees above the horizon.
        view_elevation_deg: f64,
        /// Degrees clockwise from north.
        view_azimuth_deg: f64,
    },
    /// The atmosphere file with the controls written in: `{"toml"}` (what
    /// `sora spectrum --atmosphere FILE` and `sora render --atmosphere FILE`
    /// read to reproduce the page's sky).
    AtmosphereToml {
        /// The atmosphere.
        atmosphere: AtmosphereSpec,
    },
    /// The optical depths per species and wavelength (`sora atmosphere
    /// show`'s numbers).
    Optics {
        /// The atmosphere.
        atmosphere: AtmosphereSpec,
    },
    /// The engine tables of an atmosphere for the page's real-time
    /// (WebGL2) view, baked at [`crate::engine::REALTIME_TABLES`]: JSON
    /// `{"manifest", "settings", "tables": {"sky" | "transmittance" |
    /// "irradiance": {"offset_bytes", "width", "height"}, "march":
    /// {"offset_bytes", "length_bytes"}}, "size_bytes"}`, bytes the three
    /// tables one after the other as 32-bit little-endian floats, four per
    /// texel (X, Y, Z, 0: an RGBA32F texture), in the manifest's layout,
    /// then (multiple scattering) the march's tables as `march.bin` holds
    /// them (the manifest's `tables.march`). Progress is reported while the
    /// sky table's layers bake (see [`crate::report_progress`]).
    Tables {
        /// The atmosphere.
        atmosphere: AtmosphereSpec,
        /// Single or multiple scattering.
        #[serde(default)]
        scattering: ScatteringChoice,
    },
    /// The library's aerial perspective of points at each of
    /// `distances_m` (m) along each of `views` ([elevation, azimuth],
    /// degrees) from the eye, on the sky of `quality` (what the real-time
    /// scene's volume is checked against): JSON `{"wavelengths",
    /// "inscattered_xyz": [[[X, Y, Z]]], "transmittance_xyz": [[[X, Y,
    /// Z]]], "segment_m": [[m]]}` indexed [distance][view], the segment's
    /// length (shorter than the distance where the view meets the ground
    /// or leaves the atmosphere first), the light scattered into each
    /// segment as XYZ (radiance units) and its transmittance as the engine
    /// tables give it (the XYZ of the sun's spectrum through the segment
    /// over the sun's, per channel).
    AerialPerspective {
        /// The sky.
        sky: SkySpec,
        /// The views, [elevation, azimuth] in degrees.
        views: Vec<[f64; 2]>,
        /// Metres from the eye (each > 0).
        distances_m: Vec<f64>,
        /// The sky's resolution.
        #[serde(default)]
        quality: Quality,
    },
    /// A sky image as CIE XYZ (radiance units, as `sora render --exr-xyz
    /// --units radiance`): JSON `{"width", "height", "wavelengths"}`, bytes
    /// three 32-bit little-endian floats per pixel (row-major, top row
    /// first), all zero when the whole sky is below the page's night floor
    /// (as `render` shows it): what the real-time view's difference is
    /// taken against.
    RenderXyz {
        /// The sky.
        sky: SkySpec,
        /// The image (its exposure is not used).
        image: ImageSpec,
    },
}

/// An atmosphere: a preset or a file's text, with the page's controls
/// applied on top (each `None` keeps the atmosphere's own value).
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AtmosphereSpec {
    /// A built-in atmosphere's name.
    #[serde(default)]
    pub preset: Option<String>,
    /// An atmosphere file's text (TOML), instead of a preset.
    #[serde(default)]
    pub toml: Option<String>,
    /// The first aerosol's column optical depth at its reference wavelength.
    #[serde(default)]
    pub aerosol_optical_depth: Option<f64>,
    /// Its log-normal number median radius, micrometres.
    #[serde(default)]
    pub aerosol_median_radius_um: Option<f64>,
    /// Its log-normal geometric standard deviation (> 1).
    #[serde(default)]
    pub aerosol_geometric_std_dev: Option<f64>,
    /// Its refractive index's imaginary part (absorption).
    #[serde(default)]
    pub aerosol_imaginary_index: Option<f64>,
    /// The ozone column, Dobson units.
    #[serde(default)]
    pub ozone_column_du: Option<f64>,
    /// A constant Lambertian ground albedo (0..1), as `--ground-albedo`.
    #[serde(default)]
    pub ground_albedo: Option<f64>,
}

/// Which orders of scattering, by the library's names
/// ([`sora::Scattering::NAMES`], read by its `FromStr`: `"single"`,
/// `"multiple"`); the resolution of the field is the engine's, by quality.
#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(try_from = "String")]
pub enum ScatteringChoice {
    /// The sun's light scattered once (the paper's model).
    Single,
    /// All orders (the default, as in the CLI).
    #[default]
    Multiple,
}

impl TryFrom<String> for ScatteringChoice {
    type Error = String;

    fn try_from(name: String) -> Result<Self, String> {
        match name
            .parse::<sora::Scattering>()
            .map_err(|e| e.to_string())?
        {
            sora::Scattering::Single => Ok(Self::Single),
            sora::Scattering::Multiple(_) => Ok(Self::Multiple),
        }
    }
}

/// A sky: atmosphere, sun, eye and physics.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SkySpec {
    /// The atmosphere.
    pub atmosphere: AtmosphereSpec,
    /// Sun elevation, degrees (-90..90).
    pub sun_elevation_deg: f64,
    /// Sun azimuth clockwise from north, degrees.
    #[serde(default = "default_sun_azimuth_deg")]
    pub sun_azimuth_deg: f64,
    /// Height of the eye above the ground, metres.
    #[serde(default)]
    pub observer_altitude_m: f64,
    /// Single or multiple scattering.
    #[serde(default)]
    pub scattering: ScatteringChoice,
    /// Scalar or polarised light, by the library's names
    /// ([`sora::Polarisation`]'s `FromStr`: `"scalar"`, `"vector"`); the
    /// default is the library's (and the CLI's and Python's): the polarised
    /// intensity.
    #[serde(default)]
    pub polarisation: PolarisationChoice,
}

/// Scalar or polarised light ([`SkySpec::polarisation`]).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(try_from = "String")]
pub struct PolarisationChoice(pub sora::Polarisation);

impl Default for PolarisationChoice {
    /// The library's default for the fast method (the CLI's and Python's).
    fn default() -> Self {
        Self(sora::Polarisation::for_method(sora::Method::Fast))
    }
}

impl TryFrom<String> for PolarisationChoice {
    type Error = String;

    fn try_from(name: String) -> Result<Self, String> {
        name.parse()
            .map(Self)
            .map_err(|e: sora::Error| e.to_string())
    }
}

fn default_sun_azimuth_deg() -> f64 {
    180.0
}

/// A camera projection, by the library's names ([`sora::Camera::NAMES`],
/// read by its `FromStr`: `"fisheye"`, `"equirectangular"` or its older
/// spelling `"equirect"`); the explorer draws no perspective view.
#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(try_from = "String")]
pub enum CameraChoice {
    /// The whole sky in a disc, zenith at the centre, north up, east left.
    #[default]
    Fisheye,
    /// A 360 x 180 degree panorama, north at the centre.
    Equirect,
}

impl TryFrom<String> for CameraChoice {
    type Error = String;

    fn try_from(name: String) -> Result<Self, String> {
        match name.parse::<sora::Camera>().map_err(|e| e.to_string())? {
            sora::Camera::Fisheye => Ok(Self::Fisheye),
            sora::Camera::Equirectangular => Ok(Self::Equirect),
            sora::Camera::Perspective(_) => Err(format!(
                "camera: '{name}' is not drawn by the explorer: use 'fisheye' or 'equirectangular'"
            )),
        }
    }
}

/// How finely an image is computed.
#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq, Hash)]
#[serde(rename_all = "snake_case")]
pub enum Quality {
    /// What a slider drag shows at once: every 40 nm, a coarse
    /// multiple-scattering field and small image tables, in scalar light
    /// (see [`crate::engine::build_sky`]).
    Preview,
    /// What the page refines to: the library's defaults but a sky-view
    /// table half as fine on each axis (enough for images up to 512 pixels
    /// across) and wider sun-zenith steps near sunset (see
    /// [`crate::engine::quality_settings`]).
    Refined,
    /// The library's defaults, as `sora render`.
    #[default]
    Full,
    /// The sky the real-time view's engine tables are baked from: the
    /// preview's wavelengths and image tables with a finer field near
    /// sunset (see [`crate::engine::REALTIME_TABLES`]).
    Realtime,
}

/// An image: camera, size, quality, exposure.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ImageSpec {
    /// The projection.
    #[serde(default)]
    pub camera: CameraChoice,
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
    /// Preview or full.
    #[serde(default)]
    pub quality: Quality,
    /// A fixed exposure value at ISO 100 (`--ev100`); `None`: auto exposure.
    #[serde(default)]
    pub ev100: Option<f64>,
    /// Draw the sun's disc.
    #[serde(default = "default_true")]
    pub sun_disc: bool,
}

fn default_true() -> bool {
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The camera and the scattering are read by the library's names, with
    /// its one-line errors.
    #[test]
    fn choices_are_read_by_the_librarys_names() {
        let camera = |name: &str| {
            serde_json::from_str::<ImageSpec>(&format!(
                r#"{{"camera": "{name}", "width": 4, "height": 4}}"#
            ))
            .map(|image| image.camera)
            .map_err(|e| e.to_string())
        };
        assert_eq!(camera("fisheye"), Ok(CameraChoice::Fisheye));
        assert_eq!(camera("equirect"), Ok(CameraChoice::Equirect));
        assert_eq!(camera("equirectangular"), Ok(CameraChoice::Equirect));
        let error = camera("perspective").unwrap_err();
        assert!(error.contains("not drawn by the explorer"), "{error}");
        let error = camera("sideways").unwrap_err();
        assert!(
            error.contains(
                "'sideways' is unknown: use 'fisheye', 'equirectangular' or 'perspective'"
            ),
            "{error}"
        );
        let scattering = |name: &str| {
            serde_json::from_str::<SkySpec>(&format!(
                r#"{{"atmosphere": {{"preset": "earth-clear"}}, "sun_elevation_deg": 10, "scattering": "{name}"}}"#
            ))
            .map(|sky| sky.scattering)
            .map_err(|e| e.to_string())
        };
        assert_eq!(scattering("single"), Ok(ScatteringChoice::Single));
        assert_eq!(scattering("multiple"), Ok(ScatteringChoice::Multiple));
        let error = scattering("double").unwrap_err();
        assert!(
            error.contains("'double' is unknown: use 'single' or 'multiple'"),
            "{error}"
        );
        let light = |field: &str| {
            serde_json::from_str::<SkySpec>(&format!(
                r#"{{"atmosphere": {{"preset": "earth-clear"}}, "sun_elevation_deg": 10{field}}}"#
            ))
            .map(|sky| sky.polarisation.0)
            .map_err(|e| e.to_string())
        };
        // The default is the library's, the CLI's and Python's.
        assert_eq!(light(""), Ok(sora::Polarisation::Vector));
        assert_eq!(
            light(r#", "polarisation": "scalar""#),
            Ok(sora::Polarisation::Scalar)
        );
        assert_eq!(
            light(r#", "polarisation": "vector""#),
            Ok(sora::Polarisation::Vector)
        );
        let error = light(r#", "polarisation": "off""#).unwrap_err();
        assert!(
            error.contains("'off' is unknown: use 'scalar' or 'vector'"),
            "{error}"
        );
    }
}
