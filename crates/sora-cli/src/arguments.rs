//! Command-line text -> validated library values, in one place: every
//! subcommand parses its numbers, ranges and names through these functions,
//! so a bad value gets the same clear message wherever it appears.

use sora::mie::Complex64;

/// Parses a complex refractive index written `n`, `n+ki` or `n-ki` (`j` is
/// accepted for `i`), e.g. `1.5+0.01i`, `1.33`, `10+10i`. The sign of the
/// imaginary part is kept; the Mie solver rejects a negative one (gain).
pub fn parse_refractive_index(text: &str) -> Result<Complex64, String> {
    let compact: String = text.chars().filter(|c| !c.is_whitespace()).collect();
    let bad = || format!("'{text}' is not a refractive index: write n or n+ki, e.g. 1.5+0.01i");
    let Some(body) = compact.strip_suffix(['i', 'j']) else {
        let re: f64 = compact.parse().map_err(|_| bad())?;
        return Ok(Complex64::new(re, 0.0));
    };
    // The sign that separates the parts is the last + or - not following an exponent 'e'.
    let bytes = body.as_bytes();
    let split = (1..bytes.len())
        .rev()
        .find(|&i| (bytes[i] == b'+' || bytes[i] == b'-') && !matches!(bytes[i - 1], b'e' | b'E'))
        .ok_or_else(bad)?;
    let re: f64 = body[..split].parse().map_err(|_| bad())?;
    let im_text = &body[split..];
    let im: f64 = match im_text {
        "+" => 1.0,
        "-" => -1.0,
        _ => im_text.parse().map_err(|_| bad())?,
    };
    Ok(Complex64::new(re, im))
}

/// Parses a comma-separated list of numbers (`0.5,1.8` or `0.5,1.8,0.1,2.5`).
pub fn parse_number_list(text: &str, what: &str) -> Result<Vec<f64>, String> {
    text.split(',')
        .map(|part| {
            part.trim()
                .parse::<f64>()
                .map_err(|_| format!("'{}' in {what} '{text}' is not a number", part.trim()))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refractive_index_forms() {
        assert_eq!(
            parse_refractive_index("1.5+0.01i").unwrap(),
            Complex64::new(1.5, 0.01)
        );
        assert_eq!(
            parse_refractive_index("1.33").unwrap(),
            Complex64::new(1.33, 0.0)
        );
        assert_eq!(
            parse_refractive_index("10+10i").unwrap(),
            Complex64::new(10.0, 10.0)
        );
        assert_eq!(
            parse_refractive_index("1.5 + 1e-3j").unwrap(),
            Complex64::new(1.5, 1e-3)
        );
        assert_eq!(
            parse_refractive_index("1.5e0+1e-3i").unwrap(),
            Complex64::new(1.5, 1e-3)
        );
        assert_eq!(
            parse_refractive_index("1.5-0.1i").unwrap(),
            Complex64::new(1.5, -0.1)
        );
        assert_eq!(
            parse_refractive_index("1+i").unwrap(),
            Complex64::new(1.0, 1.0)
        );
        for bad in ["", "abc", "1.5+0.01", "+0.01i", "1.5+xi", "i"] {
            assert!(parse_refractive_index(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn number_lists() {
        assert_eq!(parse_number_list("0.5, 1.8", "x").unwrap(), vec![0.5, 1.8]);
        assert!(parse_number_list("0.5,,1", "x").unwrap_err().contains("''"));
    }
}

/// How spectra become display colours: shared by every command that shows
/// colour (`sora colour`, and the renderer).
#[derive(Debug, Clone, clap::Args)]
pub struct ColourOptions {
    /// Colour-matching functions: cie1931-2deg (the paper's) or cie1964-10deg
    #[arg(long, value_name = "NAME", default_value = "cie1931-2deg")]
    pub observer: sora::colour::Observer,

    /// Display encoding: srgb (IEC 61966-2-1), or the paper's eq. 6,
    /// paper-smpte-c[:k=K,gamma=G] (SMPTE-C primaries, D65, R = k*255*lin^(1/gamma))
    #[arg(long, value_name = "NAME", default_value = "srgb")]
    pub encoding: sora::colour::DisplayEncoding,

    /// Exposure: auto (log-average luminance -> 0.18), auto:KEY, or a fixed
    /// factor multiplying XYZ
    #[arg(long, value_name = "auto|auto:KEY|FACTOR", default_value = "auto")]
    pub exposure: sora::colour::Exposure,

    /// A photographic exposure instead of --exposure: the exposure value at
    /// ISO 100 (1.2 x 2^EV100 cd/m^2 maps to white; 15 a sunny day, 0 a dim
    /// room, -6 deep twilight), the same for every image
    #[arg(
        long,
        value_name = "EV",
        allow_hyphen_values = true,
        conflicts_with = "exposure"
    )]
    pub ev100: Option<f64>,

    /// Out-of-gamut and over-range colours: highlights-to-white
    /// (preserve-hue, then colours brighter than white toward white, as a
    /// camera shows them: the sun is white), preserve-hue (desaturate
    /// toward the same luminance, then scale down by the largest channel)
    /// or clip (clamp each channel to 0..1)
    #[arg(long, value_name = "NAME", default_value = "highlights-to-white")]
    pub gamut: sora::colour::GamutMapping,
}

impl ColourOptions {
    /// The library's display stage for these options (an error for an
    /// EV100 out of range).
    pub fn display_mapping(&self) -> anyhow::Result<sora::colour::DisplayMapping> {
        let exposure = match self.ev100 {
            Some(ev100) => sora::colour::Exposure::from_ev100(ev100)
                .map_err(|e| anyhow::anyhow!("--ev100: {e}"))?,
            None => self.exposure,
        };
        Ok(sora::colour::DisplayMapping {
            exposure,
            gamut_mapping: self.gamut,
            encoding: self.encoding,
        })
    }
}

/// Where an atmosphere comes from: a built-in preset or a TOML file.
#[derive(Debug, Clone, clap::Args)]
#[group(required = true, multiple = false)]
pub struct AtmosphereSource {
    /// A built-in atmosphere (list them with: sora atmosphere presets)
    #[arg(long, value_name = "NAME")]
    pub preset: Option<String>,

    /// An atmosphere file (TOML; see atmospheres/ in the repository)
    #[arg(long, value_name = "FILE.toml")]
    pub atmosphere: Option<std::path::PathBuf>,
}

impl AtmosphereSource {
    /// Loads and validates the atmosphere. Files that an atmosphere file
    /// names (a solar spectrum CSV) are read relative to its directory.
    pub fn load(&self) -> anyhow::Result<sora::atmosphere::Atmosphere> {
        use anyhow::Context;
        if let Some(name) = &self.preset {
            return Ok(sora::atmosphere::Atmosphere::preset(name)?);
        }
        let path = self
            .atmosphere
            .as_ref()
            .expect("clap requires --preset or --atmosphere");
        let text = sora::input::read_text(path)?;
        let directory = path
            .parent()
            .map(std::path::Path::to_path_buf)
            .unwrap_or_default();
        let mut read_file = |name: &str| {
            let named = directory.join(name);
            sora::input::read_text(&named).map_err(|e| e.to_string())
        };
        sora::atmosphere::Atmosphere::from_toml_str_with_files(&text, &mut read_file)
            .with_context(|| path.display().to_string())
    }
}

/// Instrument channels instead of a wavelength grid (`sora spectrum`,
/// `sora irradiance`).
#[derive(Debug, Clone, clap::Args)]
pub struct FilterOptions {
    /// An instrument channel instead of --wavelengths (repeatable): a CSV
    /// file wavelength_nm,response, or a built-in sun-photometer channel
    /// (cimel-340, cimel-380, cimel-440, cimel-500, cimel-675, cimel-870,
    /// cimel-1020: Gaussians 10 nm wide at half maximum, 2 nm at 340, 4 nm
    /// at 380; cimel: all seven). Each channel's value is the
    /// response-weighted mean over its own wavelengths (docs/filters.md)
    #[arg(long, value_name = "FILE.csv|NAME", conflicts_with = "wavelengths")]
    pub filter: Vec<String>,
}

impl FilterOptions {
    /// The filters asked for, in order (`cimel` expands to its seven
    /// channels); empty without --filter. A name that is neither a
    /// built-in filter nor a readable file is a one-line error.
    pub fn filters(&self) -> anyhow::Result<Vec<sora::spectrum::Filter>> {
        parse_filters(&self.filter)
    }
}

/// The filters `values` name (each a built-in name, `cimel` for its seven
/// channels, or a CSV file), in order; a one-line error for a value that is
/// neither a built-in filter nor a readable file.
pub fn parse_filters(values: &[String]) -> anyhow::Result<Vec<sora::spectrum::Filter>> {
    use sora::spectrum::Filter;
    let mut filters = Vec::new();
    for value in values {
        if value == "cimel" {
            filters.extend(
                Filter::builtin_names()
                    .iter()
                    .filter_map(|name| Filter::named(name)),
            );
        } else if let Some(filter) = Filter::named(value) {
            filters.push(filter);
        } else {
            let path = std::path::Path::new(value);
            if !path.exists() && !value.to_ascii_lowercase().ends_with(".csv") {
                anyhow::bail!(
                    "--filter {value}: no such file, nor a built-in filter (cimel, {})",
                    Filter::builtin_names().join(", ")
                );
            }
            let text = sora::input::read_text(path)?;
            filters.push(
                Filter::parse_csv(&text, value)
                    .map_err(|e| anyhow::anyhow!("--filter {value}: {e}"))?,
            );
        }
    }
    Ok(filters)
}

/// A clap parser for one of the library's choices: its names (`names`, the
/// library's `NAMES`, which its `Display` writes) are the values clap
/// offers and lists in --help, read by its `FromStr` with the library's
/// defaults: one spelling in every front end.
pub fn library_names<T>(
    names: &'static [&'static str],
) -> impl clap::builder::TypedValueParser<Value = T>
where
    T: std::str::FromStr<Err = sora::Error> + Clone + Send + Sync + 'static,
{
    use clap::builder::TypedValueParser as _;
    clap::builder::PossibleValuesParser::new(names).try_map(|name| name.parse::<T>())
}

/// The multiple-scattering field's resolution: shared by `sora spectrum`,
/// `sora render` and `sora irradiance` (the library's
/// `MultipleScatteringSettings`; the other settings keep their defaults).
#[derive(Debug, Clone, Copy, clap::Args)]
pub struct Resolution {
    /// Multiple scattering: discrete ordinates per hemisphere of the
    /// field (1..32; the solver has twice as many streams and harmonics).
    /// The default 8 (with 40 layers) holds the Coulson tables (polarised,
    /// plane-parallel) to 1.1e-4 absolute at their grazing rows;
    /// --streams 10 holds them within 1e-4 (5.6e-5), at 1.5 times the CPU
    /// time of a polarised view and 1.4 times that of an image (12
    /// streams: 2.3 and 1.8 times; docs/polarisation.md) [default: 8]
    #[arg(long, value_name = "N")]
    pub streams: Option<usize>,

    /// Multiple scattering: layers of the field's vertical grid
    /// (2..10000) [default: 40]
    #[arg(long, value_name = "N")]
    pub layers: Option<usize>,

    /// Multiple scattering after sunset: the most pieces each
    /// near-horizontal stream's path is cut into when its light is read at
    /// the sun angle of where it was gathered (1..64; one piece per 0.2
    /// degree of the path's spread). The default 1 reads whole paths, 2-3
    /// % too bright at 560 and 680 nm in earth-hazy's red twilight; 3 takes
    /// most of that away at 1.1-1.2 times the CPU (docs/aerial_perspective.md)
    /// [default: 1]
    #[arg(long, value_name = "N")]
    pub twilight_shift_pieces: Option<usize>,
}

impl Resolution {
    /// `scattering` at this resolution ([`sora::Scattering::with_resolution`]):
    /// an error where it has no field (single scattering, the path tracer).
    pub fn apply(
        &self,
        scattering: sora::Scattering,
        method: sora::Method,
    ) -> anyhow::Result<sora::Scattering> {
        scattering
            .with_resolution(method, self.streams, self.layers)
            .map_err(|e| anyhow::anyhow!("--streams/--layers: {e}"))?
            .with_twilight_shift_pieces(method, self.twilight_shift_pieces)
            .map_err(|e| anyhow::anyhow!("--twilight-shift-pieces: {e}"))
    }
}

/// How the radiance is computed: shared by `sora spectrum` and `sora
/// irradiance` (whose path tracer estimates the irradiance directly).
#[derive(Debug, Clone, clap::Args)]
pub struct MethodOptions {
    /// fast (Gauss-Legendre columns, tables where they serve) or reference
    /// (the paper's uniform double march, slow), each with the orders of
    /// --scattering; or path-tracing (Monte Carlo, all orders of
    /// scattering, with standard errors)
    #[arg(
        long,
        value_parser = library_names::<sora::Method>(&sora::Method::NAMES),
        default_value = "fast"
    )]
    pub method: sora::Method,

    /// fast and reference: multiple (all orders of scattering and skylight
    /// reflected by the ground) or single (sunlight scattered once, the
    /// paper's model) [default: multiple]
    #[arg(long, value_parser = library_names::<sora::Scattering>(&sora::Scattering::NAMES))]
    pub scattering: Option<sora::Scattering>,

    /// Path tracing: number of paths (the standard error falls as
    /// 1/sqrt(N)) [default: 10000 for a radiance, 100000 for an irradiance]
    #[arg(long, value_name = "N")]
    pub samples: Option<u64>,

    /// Path tracing: random seed (the same seed gives the same result on any
    /// number of threads) [default: 1]
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
}

impl MethodOptions {
    /// Whether --method is path-tracing.
    pub fn is_path_tracing(&self) -> bool {
        matches!(self.method, sora::Method::PathTracing { .. })
    }

    /// The library's scattering and method, checked: `default_samples`
    /// paths unless --samples says otherwise, `reference` for the
    /// reference method's step counts.
    pub fn resolve(
        &self,
        default_samples: u64,
        reference: sora::Method,
    ) -> anyhow::Result<(sora::Scattering, sora::Method)> {
        let tracing = self.is_path_tracing();
        if !tracing && (self.samples.is_some() || self.seed.is_some()) {
            anyhow::bail!("--samples and --seed apply to --method path-tracing only");
        }
        if tracing && self.scattering.is_some() {
            anyhow::bail!(
                "--scattering applies to --method fast and reference only (path tracing has all orders)"
            );
        }
        let samples = self.samples.unwrap_or(default_samples);
        if samples < 2 {
            anyhow::bail!(
                "--samples = {samples} is out of range: at least 2 (a standard error needs two paths)"
            );
        }
        let scattering = self.scattering.unwrap_or_else(sora::Scattering::multiple);
        Ok(match self.method {
            sora::Method::Fast => (scattering, sora::Method::Fast),
            sora::Method::Reference { .. } => (scattering, reference),
            sora::Method::PathTracing { .. } => (
                sora::Scattering::multiple(),
                sora::Method::PathTracing {
                    samples,
                    seed: self.seed.unwrap_or(1),
                },
            ),
        })
    }
}

/// The eye and the sun: shared by `sora spectrum` and `sora render`. The
/// sun is given either as angles (--sun-elevation, --sun-azimuth) or as an
/// instant and a place (--time, --location), never both.
#[derive(Debug, Clone, clap::Args)]
#[command(group(
    clap::ArgGroup::new("sun_position")
        .args(["sun_elevation", "time"])
        .required(true)
        .multiple(false)
))]
pub struct SunAndObserver {
    /// Sun elevation above the horizon, degrees (-90..90; negative: twilight);
    /// or give --time and --location
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub sun_elevation: Option<f64>,

    /// Sun azimuth clockwise from north, degrees (0 N, 90 E, 180 S, 270 W;
    /// any finite angle, read modulo 360: -90 is 270)
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 180.0,
        allow_hyphen_values = true,
        conflicts_with = "time"
    )]
    pub sun_azimuth: f64,

    /// The sun at this instant, instead of --sun-elevation: RFC 3339 with Z
    /// or a zone offset, e.g. 2026-06-21T05:30:00+09:00 (needs --location)
    #[arg(long, value_name = "TIME", requires = "location")]
    pub time: Option<String>,

    /// Where the sun is seen from at --time: LAT,LON[,ELEVATION_M] (degrees
    /// north, degrees east, metres above sea level), e.g. 35.68,139.77,40;
    /// the elevation is also the ground's (the atmosphere's air, gases and
    /// aerosols above it; planet.ground_altitude_m)
    #[arg(
        long,
        value_name = "LAT,LON[,ELEV_M]",
        allow_hyphen_values = true,
        requires = "time",
        conflicts_with = "sun_elevation"
    )]
    pub location: Option<String>,

    /// With --time: the sun's apparent position, lifted by refraction
    /// through the air at --location's elevation (standard atmosphere:
    /// 1013.25 hPa and 10 C at sea level, 812 hPa and -1.9 C at 1830 m),
    /// or its geometric one [default: on]
    #[arg(
        long,
        value_enum,
        value_name = "on|off",
        requires = "time",
        conflicts_with = "sun_elevation"
    )]
    pub refraction: Option<OnOff>,

    /// With --time: the air pressure at the site for refraction, hPa
    /// (measured; default: the standard atmosphere's at --location's
    /// elevation)
    #[arg(
        long,
        value_name = "HPA",
        allow_hyphen_values = true,
        requires = "time",
        conflicts_with = "sun_elevation"
    )]
    pub pressure_hpa: Option<f64>,

    /// With --time: the air temperature at the site for refraction, C
    /// (measured; default: 10 C at sea level, 6.5 C cooler per km up)
    #[arg(
        long,
        value_name = "C",
        allow_hyphen_values = true,
        requires = "time",
        conflicts_with = "sun_elevation"
    )]
    pub temperature_c: Option<f64>,

    /// The sun's distance, astronomical units (0.1..=100): its spectrum at
    /// 1 AU divided by the distance squared [default: with --time, the
    /// date's Earth-Sun distance for a sun at 1 AU (every Earth preset);
    /// otherwise the atmosphere file's sun.irradiance_scale]
    #[arg(long, value_name = "AU", allow_hyphen_values = true)]
    pub sun_distance_au: Option<f64>,

    /// Height of the eye above the ground, metres
    #[arg(
        long,
        value_name = "M",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub observer_altitude_m: f64,

    /// Replace the atmosphere's ground albedo by this constant (0..1, Lambertian)
    #[arg(long, value_name = "A")]
    pub ground_albedo: Option<f64>,

    /// Wavelengths, start:stop:step in nm (within 280-2500; colour uses 360-830)
    #[arg(long, value_name = "START:STOP:STEP", default_value = "380:780:20")]
    pub wavelengths: sora::spectrum::WavelengthGrid,

    /// vector: Stokes vectors through every scattering, so that radiances
    /// are the intensity of polarised light (up to 5 % from the scalar
    /// one, docs/polarisation.md); scalar: scalar light (faster; what
    /// scalar radiative-transfer codes compute; `off`, its old spelling, is
    /// still taken, with a note) [default: vector; scalar with --method
    /// reference, whose march is scalar]
    #[arg(long, value_parser = parse_polarisation, value_name = "vector|scalar")]
    pub polarisation: Option<sora::Polarisation>,
}

/// `--polarisation`: the library's names (`sora::Polarisation`'s
/// `FromStr`), and `off`, the old spelling of `scalar`, with a note on
/// stderr.
fn parse_polarisation(value: &str) -> Result<sora::Polarisation, String> {
    if value == "off" {
        eprintln!("note: --polarisation off is now spelled --polarisation scalar");
        return Ok(sora::Polarisation::Scalar);
    }
    value.parse().map_err(|e: sora::Error| e.to_string())
}

impl SunAndObserver {
    /// These options on another wavelength grid (a filter's).
    pub fn with_wavelengths(&self, grid: sora::spectrum::WavelengthGrid) -> SunAndObserver {
        SunAndObserver {
            wavelengths: grid,
            ..self.clone()
        }
    }

    /// The light's polarisation for `method`: as --polarisation says, or
    /// the library's default ([`sora::Polarisation::for_method`]: vector,
    /// scalar for the reference march; an explicit `--polarisation vector`
    /// with it is the library's one-line error).
    pub fn polarisation(&self, method: sora::Method) -> sora::Polarisation {
        self.polarisation
            .unwrap_or(sora::Polarisation::for_method(method))
    }

    /// The sky these options describe, with `scattering` by `method`, its
    /// light polarised as [`SunAndObserver::polarisation`] says, and the
    /// sun it has ([`SunAndObserver::sun_used`]; `atmosphere`'s sun is
    /// moved to its distance).
    pub fn sky(
        &self,
        atmosphere: &mut sora::Atmosphere,
        scattering: sora::Scattering,
        method: sora::Method,
    ) -> anyhow::Result<(sora::Sky, SunUsed)> {
        self.sky_for(atmosphere, (scattering, method), None)
    }

    /// [`SunAndObserver::sky`]; with `colour_images`, a sky for colour
    /// images alone, seen by that observer
    /// (`sora::SkyBuilder::for_colour_images`: banded gases' terms merged
    /// where colour allows).
    pub fn sky_for(
        &self,
        atmosphere: &mut sora::Atmosphere,
        (scattering, method): (sora::Scattering, sora::Method),
        colour_images: Option<sora::colour::Observer>,
    ) -> anyhow::Result<(sora::Sky, SunUsed)> {
        let polarisation = self.polarisation(method);
        if let Some(albedo) = self.ground_albedo {
            atmosphere.planet = atmosphere
                .planet
                .with_ground_albedo(sora::spectrum::Spectrum::Constant(albedo))
                .map_err(|e| anyhow::anyhow!("--ground-albedo: {e}"))?;
        }
        let sun = self.sun_used(Some(&atmosphere.sun))?;
        if let Some(elevation_m) = sun.site_elevation_m {
            atmosphere.planet = atmosphere
                .planet
                .clone()
                .with_ground_altitude_m(elevation_m)
                .map_err(|e| anyhow::anyhow!("--location's elevation: {e}"))?;
        }
        if let Some(distance_au) = sun.distance_au {
            atmosphere.sun = atmosphere.sun.at_distance_au(distance_au).map_err(|e| {
                anyhow::anyhow!(
                    "{}{e}",
                    if self.sun_distance_au.is_some() {
                        "--sun-distance-au: "
                    } else {
                        ""
                    }
                )
            })?;
        }
        let mut builder = sora::Sky::builder(atmosphere)
            .sun_deg(sun.elevation_deg, sun.azimuth_deg)
            .observer_altitude_m(self.observer_altitude_m)
            .wavelengths(self.wavelengths)
            .scattering(scattering)
            .method(method)
            .polarisation(polarisation);
        if let Some(observer) = colour_images {
            builder = builder.for_colour_images(observer);
        }
        let sky = builder.build()?;
        Ok((sky, sun))
    }
}

/// The sun these options give: where it is and, when it was moved from
/// the atmosphere file's distance, how far it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SunUsed {
    /// Elevation above the horizon, degrees.
    pub elevation_deg: f64,
    /// Azimuth clockwise from north, degrees.
    pub azimuth_deg: f64,
    /// The sun's distance, AU, when --sun-distance-au or --time set it
    /// (the file's sun otherwise).
    pub distance_au: Option<f64>,
    /// The Earth-Sun distance at --time, AU (whether or not it was used).
    pub earth_sun_distance_au: Option<f64>,
    /// --location's elevation above sea level, m: the ground's altitude.
    pub site_elevation_m: Option<f64>,
}

impl SunUsed {
    /// `; the sun at d AU` for summaries, or nothing.
    pub fn summary(&self) -> String {
        self.distance_au
            .map_or(String::new(), |d| format!("; the sun at {d:.6} AU"))
    }
}

/// Prints on stderr, for polarised output (Stokes vectors, degree and
/// angle maps) of `sky`, one warning line per species that scatters light
/// with a parametric phase function ([`sora::Sky::non_polarising_species`]:
/// taken as non-polarising; docs/polarisation.md, and `sora atmosphere
/// show` lists it so). The output is still written.
pub fn warn_non_polarising_species(sky: &sora::Sky) {
    for (name, kind) in sky.non_polarising_species() {
        eprintln!(
            "warning: species {name} has a {kind} phase function, which carries no polarisation: the Stokes vectors treat it as non-polarising (F12 = F34 = 0, F33 = F44 = F11; docs/polarisation.md)"
        );
    }
}

impl SunAndObserver {
    /// The sun's elevation and azimuth (degrees) these options give: as
    /// written, or computed for --time at --location.
    pub fn sun_deg(&self) -> anyhow::Result<(f64, f64)> {
        let sun = self.sun_used(None)?;
        Ok((sun.elevation_deg, sun.azimuth_deg))
    }

    /// The sun these options give for an atmosphere whose sun is
    /// `file_sun`: its position as written, or computed for --time at
    /// --location; its distance from --sun-distance-au, or with --time the
    /// date's Earth-Sun distance when `file_sun` is at 1 AU (scale 1;
    /// without a `file_sun`, only --sun-distance-au).
    pub fn sun_used(&self, file_sun: Option<&sora::atmosphere::Sun>) -> anyhow::Result<SunUsed> {
        let (Some(time), Some(location)) = (&self.time, &self.location) else {
            let elevation = self
                .sun_elevation
                .expect("clap requires --sun-elevation or --time");
            return Ok(SunUsed {
                elevation_deg: elevation,
                azimuth_deg: sora::geometry::azimuth_in_one_turn_deg(self.sun_azimuth),
                distance_au: self.sun_distance_au,
                earth_sun_distance_au: None,
                site_elevation_m: None,
            });
        };
        let time = sora::sun_position::parse_time_utc(time).map_err(|e| match e {
            sora::Error::Parse { message, .. } => anyhow::anyhow!("--time: {message}"),
            other => anyhow::anyhow!("--time: {other}"),
        })?;
        let location = parse_location(location).map_err(|e| anyhow::anyhow!("--location: {e}"))?;
        let refraction = match self.refraction.unwrap_or(OnOff::On) {
            OnOff::On => sora::sun_position::Refraction::at_site(
                location.elevation_m(),
                self.pressure_hpa,
                self.temperature_c,
            ),
            OnOff::Off => sora::sun_position::Refraction::Off,
        };
        let sun = sora::SunPosition::at(time, location, refraction)?;
        Ok(SunUsed {
            elevation_deg: sun.elevation_deg,
            azimuth_deg: sun.azimuth_deg,
            distance_au: self
                .sun_distance_au
                .or(file_sun.and_then(|file_sun| file_sun.date_distance_au(&sun))),
            earth_sun_distance_au: Some(sun.earth_sun_distance_au),
            site_elevation_m: Some(location.elevation_m()),
        })
    }
}

/// A yes/no option (`--refraction on|off`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OnOff {
    On,
    Off,
}

/// Parses a place written `LAT,LON[,ELEVATION_M]`: latitude in degrees
/// north (-90..=90), longitude in degrees east (-180..=180), elevation in
/// metres above sea level (default 0), e.g. `35.68,139.77,40`.
pub fn parse_location(text: &str) -> Result<sora::sun_position::Location, String> {
    let values = parse_number_list(text, "location")?;
    let (latitude, longitude, elevation) = match values[..] {
        [latitude, longitude] => (latitude, longitude, 0.0),
        [latitude, longitude, elevation] => (latitude, longitude, elevation),
        _ => {
            return Err(format!(
                "'{text}' has {} values: write LAT,LON or LAT,LON,ELEVATION_M (degrees north, degrees east, metres), e.g. 35.68,139.77,40",
                values.len()
            ));
        }
    };
    sora::sun_position::Location::new(latitude, longitude, elevation).map_err(|e| e.to_string())
}

#[cfg(test)]
mod location_tests {
    use super::*;

    #[test]
    fn locations() {
        let tokyo = parse_location("35.68, 139.77, 40").unwrap();
        assert_eq!(
            (
                tokyo.latitude_deg(),
                tokyo.longitude_deg(),
                tokyo.elevation_m()
            ),
            (35.68, 139.77, 40.0)
        );
        let sydney = parse_location("-33.87,151.21").unwrap();
        assert_eq!(sydney.elevation_m(), 0.0);
        for (text, expected) in [
            ("91,0", "latitude = 91 deg is out of range"),
            ("0,200", "longitude = 200 deg"),
            ("0", "has 1 values"),
            ("0,0,0,0", "has 4 values"),
            ("north,0", "'north' in location"),
            ("", "'' in location"),
        ] {
            let error = parse_location(text).unwrap_err();
            assert!(error.contains(expected), "{text}: {error}");
        }
    }
}

/// Header of a directions file (`sora spectrum --directions`).
pub const DIRECTIONS_HEADER: &str = "view_elevation_deg,view_azimuth_deg";

/// Parses a directions file: a numeric CSV table (the library's dialect,
/// [`sora::table`]: `#` comments, blank lines and a byte-order mark
/// allowed) with the header [`DIRECTIONS_HEADER`], one direction per row
/// (elevation -90..=90 and azimuth clockwise from north, degrees). `what`
/// names the file in errors, which give the line (1-based) and the bad
/// value.
pub fn parse_directions_csv(text: &str, what: &str) -> anyhow::Result<Vec<sora::ViewDirection>> {
    let table = sora::table::NumericTable::parse(text, what)?;
    if table.column_names.join(",") != DIRECTIONS_HEADER {
        anyhow::bail!(
            "{what}, line {}: the header is '{}', expected {DIRECTIONS_HEADER}",
            table.header_line,
            table.column_names.join(",")
        );
    }
    table
        .rows
        .iter()
        .zip(&table.line_numbers)
        .map(|(row, line)| {
            sora::ViewDirection::new(row[0], row[1])
                .map_err(|e| anyhow::anyhow!("{what}, line {line}: {e}"))
        })
        .collect()
}

#[cfg(test)]
mod direction_tests {
    use super::*;

    #[test]
    fn directions_files() {
        let parsed = parse_directions_csv(
            "\u{feff}# measured views\nview_elevation_deg, view_azimuth_deg\n\n10,20\n-5.5 , 359\n",
            "views.csv",
        )
        .unwrap();
        assert_eq!(parsed.len(), 2);
        assert_eq!(
            (parsed[1].elevation_deg(), parsed[1].azimuth_deg()),
            (-5.5, 359.0)
        );
        for (text, expected) in [
            ("", "views.csv: the table is empty"),
            (
                "view_elevation_deg,view_azimuth_deg\n",
                "header but no rows",
            ),
            ("elevation,azimuth\n1,2\n", "views.csv, line 1: the header"),
            (
                "# a comment\nelevation,azimuth\n1,2\n",
                "line 2: the header is 'elevation,azimuth'",
            ),
            (
                "view_elevation_deg,view_azimuth_deg\n1,2\n3\n",
                "views.csv, line 3: 1 fields, expected 2",
            ),
            (
                "view_elevation_deg,view_azimuth_deg\n1,2,3\n",
                "line 2: 3 fields",
            ),
            (
                "view_elevation_deg,view_azimuth_deg\nx,2\n",
                "line 2: view_elevation_deg = 'x' is not a finite number",
            ),
            (
                "view_elevation_deg,view_azimuth_deg\n120,2\n",
                "line 2: view elevation = 120 deg",
            ),
            (
                "view_elevation_deg,view_azimuth_deg\nNaN,2\n",
                "line 2: view_elevation_deg = 'NaN' is not a finite number",
            ),
            (
                "view_elevation_deg,view_azimuth_deg\n1,inf\n",
                "line 2: view_azimuth_deg = 'inf' is not a finite number",
            ),
        ] {
            let error = parse_directions_csv(text, "views.csv")
                .unwrap_err()
                .to_string();
            assert!(error.contains(expected), "{text:?}: {error}");
            assert!(!error.contains('\n'), "{error}");
        }
    }
}
