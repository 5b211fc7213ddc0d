//! `sora spectrum`: the sky's spectral radiance in one direction or many.

use std::io::Write;
use std::time::Instant;

use clap::{Args, ValueEnum};
use serde::Serialize;
use sora::colour::{RgbColourSpace, SpectrumToXyz};
use sora::spectrum::SampledSpectrum;
use sora::{SkyRadiance, ViewDirection};

use crate::arguments::{
    AtmosphereSource, FilterOptions, MethodOptions, Resolution, SunAndObserver,
    parse_directions_csv,
};

/// Spectral radiance of the sky in one direction or many.
///
/// One direction (--view-elevation and --view-azimuth): CSV
/// wavelength_nm,radiance_w_m2_sr_nm on stdout (the colour of the spectrum,
/// CIE XYZ and linear sRGB, goes to stderr), or everything as JSON with
/// --format json. Many directions (--directions FILE.csv, --almucantar,
/// --principal-plane): one long CSV,
/// view_elevation_deg,view_azimuth_deg,wavelength_nm,radiance_w_m2_sr_nm,
/// or JSON with one object per direction; every table is built once for all
/// of them, and from 256 directions the fast method reads them from an
/// image's kinds of tables (within 0.1 % of the exact per-direction
/// path, the worst near the sun; 16,384 polarised directions cost about
/// 1.4 times a 128 x 128 fisheye). Radiance is in W m^-2 sr^-1 nm^-1 for
/// the atmosphere's sun.
///
/// With banded gases (an atmosphere file's [gases]) every radiance is the
/// library's sum of five solves, one per k-distribution term, weighted
/// (five times the time at the samples from the first a band absorbs to
/// the last; one solve elsewhere).
///
/// Methods: fast and reference compute single scattering (plus the sunlit
/// ground) and, with --scattering multiple (the default), add all higher
/// orders and the skylight reflected by the ground (a discrete-ordinate
/// field, synthesised exactly along the view); --scattering single gives
/// the paper's model. path-tracing is the Monte Carlo reference for all
/// orders of scattering and ground reflection, and adds a column,
/// standard_error_w_m2_sr_nm, the standard error of each value (it shrinks
/// as 1/sqrt(--samples); on a terminal a progress bar shows the time left).
///
/// Examples (the paper's Table 1 geometry; an almucantar every 5 degrees):
///   sora spectrum --preset paper-earth --sun-elevation 36 --sun-azimuth 207 \
///       --view-elevation 17 --view-azimuth 347
///   sora spectrum --preset clear-sky-reference --sun-elevation 36 \
///       --view-elevation 17 --view-azimuth 347 --method path-tracing --samples 100000
///   sora spectrum --preset earth-clear --sun-elevation 30 --almucantar 5
///
/// Polarisation (--stokes): the Stokes vector of the light, all orders, by
/// the fast method (its multiple scattering polarised by a column solved
/// with Stokes vectors at the eye's sun; docs/polarisation.md) or the path
/// tracer; adds the columns q_w_m2_sr_nm,u_w_m2_sr_nm,v_w_m2_sr_nm,
/// degree_of_linear_polarisation,angle_of_polarisation_deg, and the
/// radiance column becomes the polarised intensity I. Q and U are referred
/// to the view's meridian plane (the vertical plane through the view): Q > 0
/// for a mostly vertical electric field, Q < 0 for a horizontal one; the
/// angle of polarisation (-90..90 degrees) turns from the vertical toward
/// the observer's left; it is empty (JSON null) for wholly unpolarised
/// light. Mie aerosols polarise by their phase matrix, computed for the run:
///   sora spectrum --preset us-standard-1976-rayleigh --sun-elevation 30 \
///       --principal-plane 10 --method path-tracing --samples 20000 --stokes
///
/// Instrument channels (--filter, repeatable): one value per channel and
/// direction, the response-weighted mean radiance over the channel's own
/// wavelengths, in columns filter,centre_nm,radiance_w_m2_sr_nm (after
/// view_elevation_deg,view_azimuth_deg for many directions); the sun
/// photometer's channels are built in (docs/filters.md):
///   sora spectrum --preset earth-clear --sun-elevation 30 --almucantar 10 \
///       --filter cimel-440 --filter cimel-870
///
/// Aerial perspective (--distance-m D): the light the air scatters into
/// the view between the eye and a point D m away (instead of the whole
/// sky; W m^-2 sr^-1 nm^-1), and a column transmittance, the segment's
/// Beer-Lambert transmittance; a renderer shows the point's own radiance
/// L as L * transmittance + radiance. The fast method or path tracing:
///   sora spectrum --preset earth-hazy --sun-elevation 10 --view-elevation 2 \
///       --view-azimuth 0 --distance-m 20000
///
/// The sun from a date, a time and a place instead (--refraction off for
/// its geometric position; the JSON reports the sun used):
///   sora spectrum --preset earth-clear --time 2026-06-21T05:30:00+09:00 \
///       --location 35.68,139.77,40 --almucantar 10 --format json
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
#[group(id = "views", required = true, multiple = false)]
pub struct SpectrumArgs {
    #[command(flatten)]
    source: AtmosphereSource,

    #[command(flatten)]
    sun: SunAndObserver,

    /// View elevation above the horizon, degrees (-90..90)
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        requires = "view_azimuth",
        group = "views"
    )]
    view_elevation: Option<f64>,

    /// View azimuth clockwise from north, degrees (any finite angle, read
    /// modulo 360: 400 is 40)
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        requires = "view_elevation"
    )]
    view_azimuth: Option<f64>,

    /// Many directions: a CSV file with the header
    /// view_elevation_deg,view_azimuth_deg and one direction per line
    /// (lines starting with # are comments)
    #[arg(long, value_name = "FILE.csv", group = "views")]
    directions: Option<std::path::PathBuf>,

    /// Many directions: the almucantar (the sun's elevation) at azimuths
    /// every STEP degrees, starting at the sun's (5 gives 72 directions)
    #[arg(
        long,
        value_name = "STEP_DEG",
        group = "views",
        allow_hyphen_values = true
    )]
    almucantar: Option<f64>,

    /// Many directions: the principal plane (the sun's vertical) every
    /// STEP degrees of elevation, from the horizon below the sun over the
    /// zenith to the opposite horizon
    #[arg(
        long,
        value_name = "STEP_DEG",
        group = "views",
        allow_hyphen_values = true
    )]
    principal_plane: Option<f64>,

    #[command(flatten)]
    method: MethodOptions,

    #[command(flatten)]
    resolution: Resolution,

    #[command(flatten)]
    filters: FilterOptions,

    /// Aerial perspective: the light scattered into the view between the
    /// eye and a point this far along it (m, > 0), and its transmittance
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    distance_m: Option<f64>,

    /// Polarised light: Stokes Q, U, V, the degree and the angle of
    /// polarisation (the fast method or path tracing; not the reference)
    #[arg(long, conflicts_with = "filter")]
    stokes: bool,

    /// Output format
    #[arg(long, value_enum, default_value_t = Format::Csv)]
    format: Format,
}

/// Paths traced by default: about 1% standard error for a clear sky.
const DEFAULT_SAMPLES: u64 = 10_000;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Format {
    Csv,
    Json,
}

/// Refuses more directions (or directions x wavelengths) than the library
/// computes in one call (`sora::sky::MAX_VIEWS`, `MAX_VIEW_VALUES`), naming
/// what asked: before the directions are listed.
fn check_direction_count(what: &str, directions: f64, wavelengths: usize) -> anyhow::Result<()> {
    Ok(sora::sky::check_view_count(what, directions, wavelengths)?)
}

/// Directions every `step_deg` over a turn of `span_deg`: how many, checked.
fn steps_over(
    option: &str,
    step_deg: f64,
    span_deg: f64,
    wavelengths: usize,
) -> anyhow::Result<usize> {
    if !(step_deg.is_finite() && step_deg > 0.0 && step_deg <= 90.0) {
        anyhow::bail!("{option} = {step_deg} deg is out of range: allowed > 0 and <= 90 deg");
    }
    // The last step ends short of (almucantar) or at (principal plane) the
    // span. Counted in floating point: a subnormal step's count is infinite
    // (5e-324 overflowed the integer, found by the flag mutation tests).
    let steps = (span_deg / step_deg + 1e-9).floor();
    check_direction_count(
        &format!("{option} = {step_deg:e} deg"),
        steps + 1.0,
        wavelengths,
    )?;
    Ok(steps as usize)
}

/// The directions the options ask for, with the sun at these angles.
fn directions(
    args: &SpectrumArgs,
    (sun_elevation, sun_azimuth): (f64, f64),
    wavelengths: usize,
) -> anyhow::Result<Vec<ViewDirection>> {
    if let (Some(elevation), Some(azimuth)) = (args.view_elevation, args.view_azimuth) {
        if !(-90.0..=90.0).contains(&elevation) {
            anyhow::bail!(
                "--view-elevation = {elevation} deg is out of range: allowed -90..=90 deg"
            );
        }
        if !azimuth.is_finite() {
            anyhow::bail!("--view-azimuth = {azimuth} deg is not a finite angle");
        }
        return Ok(vec![ViewDirection::new(elevation, azimuth)?]);
    }
    if let Some(path) = &args.directions {
        let text = sora::input::read_text(path)?;
        let views = parse_directions_csv(&text, &path.display().to_string())?;
        check_direction_count(&path.display().to_string(), views.len() as f64, wavelengths)?;
        return Ok(views);
    }
    let views: Result<Vec<ViewDirection>, sora::Error> = if let Some(step) = args.almucantar {
        let count = steps_over("--almucantar", step, 360.0 - 1e-6, wavelengths)? + 1;
        (0..count)
            .map(|k| {
                ViewDirection::new(
                    sun_elevation,
                    (sun_azimuth + k as f64 * step).rem_euclid(360.0),
                )
            })
            .collect()
    } else {
        let step = args
            .principal_plane
            .expect("clap requires one direction option");
        let count = steps_over("--principal-plane", step, 180.0, wavelengths)? + 1;
        (0..count)
            .map(|k| {
                let e = k as f64 * step;
                if e <= 90.0 {
                    ViewDirection::new(e, sun_azimuth.rem_euclid(360.0))
                } else {
                    ViewDirection::new(180.0 - e, (sun_azimuth + 180.0).rem_euclid(360.0))
                }
            })
            .collect()
    };
    Ok(views?)
}

pub fn run(args: SpectrumArgs) -> anyhow::Result<()> {
    let (scattering, method) = args.method.resolve(
        DEFAULT_SAMPLES,
        sora::Method::Reference {
            view_steps: 4000,
            sun_steps: 800,
        },
    )?;
    let scattering = args.resolution.apply(scattering, method)?;
    let (samples, seed) = match method {
        sora::Method::PathTracing { samples, seed } => (samples, seed),
        _ => (0, 0),
    };
    // The directions (and their limits, docs/limits.md) before any work.
    if let Some(distance) = args.distance_m
        && (distance.is_nan() || distance <= 0.0)
    {
        anyhow::bail!(
            "--distance-m {distance}: the distance to the point must be > 0 m (infinity: the whole sky)"
        );
    }
    let (sun_elevation, sun_azimuth) = args.sun.sun_deg()?;
    let filters = args.filters.filters()?;
    let grids = filters
        .iter()
        .map(|f| {
            f.grid()
                .map_err(|e| anyhow::anyhow!("--filter {}: {e}", f.name()))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let wavelength_count = grids
        .iter()
        .map(sora::spectrum::WavelengthGrid::len)
        .max()
        .unwrap_or(args.sun.wavelengths.len());
    let views = directions(&args, (sun_elevation, sun_azimuth), wavelength_count)?;
    if !filters.is_empty() && args.distance_m.is_some() {
        anyhow::bail!(
            "--distance-m and --filter do not combine: aerial perspective is given per wavelength"
        );
    }
    let mut atmosphere = args.source.load()?;
    // Banded gases: the sky sums its k-distribution terms.
    let solves = sora::atmosphere::gas_bands::solves_per_wavelength(&atmosphere);
    if !filters.is_empty() {
        return run_filtered(
            &args,
            &filters,
            &grids,
            &views,
            atmosphere,
            (scattering, method),
        );
    }
    if args.stokes && args.sun.polarisation(method) == sora::Polarisation::Scalar {
        match method {
            sora::Method::Reference { .. } => anyhow::bail!(
                "--stokes: the reference method's march is scalar (no polarisation); Stokes vectors come from --method fast (the default) or path-tracing"
            ),
            _ => anyhow::bail!("--stokes needs --polarisation vector (the default), not off"),
        }
    }
    let (sky, sun) = &args.sun.sky(&mut atmosphere, scattering, method)?;
    if args.stokes {
        crate::arguments::warn_non_polarising_species(sky);
    }
    let grid = *sky.wavelengths();
    debug_assert_eq!(grid.len(), args.sun.wavelengths.len());
    let started = Instant::now();
    let path_tracing = args.method.is_path_tracing();
    if path_tracing {
        crate::estimate::announce(crate::estimate::path_tracing_estimate(
            samples * solves as u64,
            views.len(),
            grid.len(),
        ));
    }
    let radiances = |compute: &dyn Fn(&sora::Sky) -> anyhow::Result<Vec<SkyRadiance>>| compute(sky);
    let (results, transmittances) = if let Some(distance) = args.distance_m {
        let segments: Vec<(ViewDirection, f64)> = views.iter().map(|v| (*v, distance)).collect();
        let (radiances, transmittances) = sky
            .aerial_perspectives(&segments)?
            .into_iter()
            .map(|ap| (ap.radiance, ap.transmittance))
            .unzip();
        (radiances, Some(transmittances))
    } else if path_tracing {
        let results = radiances(&|sky: &sora::Sky| {
            let bar = crate::progress::bar(
                samples * views.len() as u64,
                "{spinner} path tracing [{bar:40}] {pos}/{len} paths, {eta} left",
            );
            let results = sky.radiances_with_progress(&views, &|done, _| bar.set_position(done))?;
            bar.finish_and_clear();
            Ok(results)
        })?;
        let seconds = started.elapsed().as_secs_f64();
        let worst = results
            .iter()
            .map(SkyRadiance::worst_relative_standard_error)
            .fold(0.0, f64::max);
        eprintln!(
            "path tracing: {samples} paths per direction (seed {seed}) in {seconds:.3} s ({:.0} paths/s); largest relative standard error {:.3}%",
            (solves as u64 * samples * views.len() as u64) as f64 / seconds,
            100.0 * worst
        );
        (results, None)
    } else {
        (
            radiances(&|sky: &sora::Sky| Ok(sky.radiances(&views)?))?,
            None,
        )
    };
    // The transmittance column of a CSV row and member of a direction's
    // JSON (empty without --distance-m).
    let transmittance_csv = |k: usize, i: usize| {
        transmittances
            .as_ref()
            .map_or(String::new(), |t: &Vec<sora::spectrum::SampledSpectrum>| {
                format!(",{:.9e}", t[k][i])
            })
    };
    let transmittance_header = if transmittances.is_some() {
        ",transmittance"
    } else {
        ""
    };
    // Colour comes from the grid's wavelengths in 360-830 nm (all of them
    // for a grid inside that range); a grid with none there has no colour.
    let to_xyz = SpectrumToXyz::new(&grid, sora::colour::Observer::Cie1931TwoDegree);
    let colour_sample_count = to_xyz.colour_sample_count();
    let colour_note = if colour_sample_count == 0 {
        format!(
            "no colour: no wavelength of {grid} lies in {}-{} nm, the range of the colour-matching functions",
            sora::colour::CIE_MIN_WAVELENGTH_NM,
            sora::colour::CIE_MAX_WAVELENGTH_NM
        )
    } else if colour_sample_count < grid.len() {
        format!(
            " (colour from the {colour_sample_count} of {} wavelengths in {}-{} nm)",
            grid.len(),
            sora::colour::CIE_MIN_WAVELENGTH_NM,
            sora::colour::CIE_MAX_WAVELENGTH_NM
        )
    } else {
        String::new()
    };
    let colours = results
        .iter()
        .map(|r| {
            let xyz = to_xyz.to_xyz(&r.radiance_w_m2_sr_nm)?;
            Ok((xyz, RgbColourSpace::Srgb.linear_rgb_from_xyz(xyz)))
        })
        .collect::<sora::Result<Vec<_>>>()?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let wavelengths: Vec<f64> = grid.wavelengths_nm().collect();
    // A direction's JSON: its spectrum (and errors), its colour.
    let json_direction =
        |k: usize,
         view: Option<&ViewDirection>,
         (xyz, rgb): &(sora::colour::Xyz, sora::colour::LinearRgb)| {
            let r = &results[k];
            let stokes = r.stokes.as_ref().filter(|_| args.stokes);
            let stokes_errors = |i: usize| {
                stokes
                    .and_then(|s| s.standard_errors_w_m2_sr_nm.as_ref())
                    .map(|errors| errors[i].values())
            };
            DirectionJson {
                view_elevation_deg: view.map(|v| v.elevation_deg()),
                view_azimuth_deg: view.map(|v| v.azimuth_deg()),
                radiance_w_m2_sr_nm: r.radiance_w_m2_sr_nm.values(),
                standard_error_w_m2_sr_nm: r
                    .standard_error_w_m2_sr_nm
                    .as_ref()
                    .map(SampledSpectrum::values),
                transmittance: transmittances.as_ref().map(|t| t[k].values()),
                stokes: stokes.map(|stokes| StokesJson {
                    q_w_m2_sr_nm: stokes.q_w_m2_sr_nm.values(),
                    u_w_m2_sr_nm: stokes.u_w_m2_sr_nm.values(),
                    v_w_m2_sr_nm: stokes.v_w_m2_sr_nm.values(),
                    standard_error_q_w_m2_sr_nm: stokes_errors(0),
                    standard_error_u_w_m2_sr_nm: stokes_errors(1),
                    standard_error_v_w_m2_sr_nm: stokes_errors(2),
                    degree_of_linear_polarisation: stokes
                        .degree_of_linear_polarisation(&r.radiance_w_m2_sr_nm),
                    angle_of_polarisation_deg: stokes.angle_of_polarisation_deg(),
                }),
                xyz_w_m2_sr: (colour_sample_count > 0).then_some([xyz.x, xyz.y, xyz.z]),
                linear_srgb_w_m2_sr: (colour_sample_count > 0).then_some([rgb.r, rgb.g, rgb.b]),
            }
        };
    let polarisation = sky.polarisation();
    let json = |direction: Option<DirectionJson>, directions: Option<Vec<DirectionJson>>| {
        crate::json::to_string(&SpectrumJson {
            sun: crate::json::Sun::new(sun_elevation, sun_azimuth, sun),
            polarisation: polarisation.to_string(),
            wavelength_nm: &wavelengths,
            samples: path_tracing.then_some(samples),
            seed: path_tracing.then_some(seed),
            distance_m: args.distance_m,
            direction,
            directions,
        })
    };
    // The Stokes columns of a CSV row (empty without --stokes).
    let stokes_header = if args.stokes {
        ",q_w_m2_sr_nm,u_w_m2_sr_nm,v_w_m2_sr_nm,degree_of_linear_polarisation,angle_of_polarisation_deg"
    } else {
        ""
    };
    let stokes_columns: Vec<Vec<String>> = results
        .iter()
        .map(|r| match r.stokes.as_ref().filter(|_| args.stokes) {
            None => vec![String::new(); wavelengths.len()],
            Some(stokes) => {
                let degree = stokes.degree_of_linear_polarisation(&r.radiance_w_m2_sr_nm);
                let angle = stokes.angle_of_polarisation_deg();
                (0..wavelengths.len())
                    .map(|i| {
                        format!(
                            ",{:.9e},{:.9e},{:.9e},{:.6},{}",
                            stokes.q_w_m2_sr_nm[i],
                            stokes.u_w_m2_sr_nm[i],
                            stokes.v_w_m2_sr_nm[i],
                            degree[i],
                            angle[i].map_or(String::new(), |a| format!("{a:.6}"))
                        )
                    })
                    .collect()
            }
        })
        .collect();
    if args.view_elevation.is_some() {
        // One direction: the two- or three-column spectrum.
        let (result, (xyz, rgb)) = (&results[0], &colours[0]);
        match args.format {
            Format::Csv => {
                let header = if path_tracing {
                    "wavelength_nm,radiance_w_m2_sr_nm,standard_error_w_m2_sr_nm"
                } else {
                    "wavelength_nm,radiance_w_m2_sr_nm"
                };
                writeln!(out, "{header}{transmittance_header}{stokes_header}")?;
                for (i, wavelength) in wavelengths.iter().enumerate() {
                    write!(out, "{wavelength},{:.9e}", result.radiance_w_m2_sr_nm[i])?;
                    if let Some(errors) = &result.standard_error_w_m2_sr_nm {
                        write!(out, ",{:.3e}", errors[i])?;
                    }
                    writeln!(out, "{}{}", transmittance_csv(0, i), stokes_columns[0][i])?;
                }
                if colour_sample_count == 0 {
                    eprintln!("{colour_note}");
                } else {
                    eprintln!(
                        "XYZ {:.6e} {:.6e} {:.6e}; linear sRGB {:.6e} {:.6e} {:.6e}{colour_note}",
                        xyz.x, xyz.y, xyz.z, rgb.r, rgb.g, rgb.b
                    );
                }
            }
            Format::Json => {
                out.write_all(json(Some(json_direction(0, None, &colours[0])), None)?.as_bytes())?;
            }
        }
    } else {
        match args.format {
            Format::Csv => {
                let header = if path_tracing {
                    "view_elevation_deg,view_azimuth_deg,wavelength_nm,radiance_w_m2_sr_nm,standard_error_w_m2_sr_nm"
                } else {
                    "view_elevation_deg,view_azimuth_deg,wavelength_nm,radiance_w_m2_sr_nm"
                };
                writeln!(out, "{header}{transmittance_header}{stokes_header}")?;
                for (k, ((view, result), stokes)) in
                    views.iter().zip(&results).zip(&stokes_columns).enumerate()
                {
                    for (i, wavelength) in wavelengths.iter().enumerate() {
                        write!(
                            out,
                            "{},{},{wavelength},{:.9e}",
                            view.elevation_deg(),
                            view.azimuth_deg(),
                            result.radiance_w_m2_sr_nm[i]
                        )?;
                        if let Some(errors) = &result.standard_error_w_m2_sr_nm {
                            write!(out, ",{:.3e}", errors[i])?;
                        }
                        writeln!(out, "{}{}", transmittance_csv(k, i), stokes[i])?;
                    }
                }
            }
            Format::Json => {
                let directions = views
                    .iter()
                    .zip(&colours)
                    .enumerate()
                    .map(|(k, (view, colour))| json_direction(k, Some(view), colour))
                    .collect();
                out.write_all(json(None, Some(directions))?.as_bytes())?;
            }
        }
        eprintln!(
            "{} directions in {:.3} s",
            views.len(),
            started.elapsed().as_secs_f64()
        );
    }
    out.flush()?;
    Ok(())
}

/// `sora spectrum --format json` (docs/json.md): the sun and the light,
/// the wavelengths, how it was computed, and one direction's members or
/// `directions`, a list of them.
#[derive(Serialize)]
struct SpectrumJson<'a> {
    #[serde(flatten)]
    sun: crate::json::Sun,
    /// "vector" or "scalar" ([`sora::Polarisation`]).
    polarisation: String,
    wavelength_nm: &'a [f64],
    /// Paths per direction and the seed (path tracing only).
    #[serde(skip_serializing_if = "Option::is_none")]
    samples: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    seed: Option<u64>,
    /// --distance-m: the aerial perspective of a point this far away.
    #[serde(skip_serializing_if = "Option::is_none")]
    distance_m: Option<f64>,
    /// One direction (--view-elevation and --view-azimuth).
    #[serde(flatten)]
    direction: Option<DirectionJson<'a>>,
    /// Many directions.
    #[serde(skip_serializing_if = "Option::is_none")]
    directions: Option<Vec<DirectionJson<'a>>>,
}

/// One direction's spectra and colour.
#[derive(Serialize)]
struct DirectionJson<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    view_elevation_deg: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    view_azimuth_deg: Option<f64>,
    radiance_w_m2_sr_nm: &'a [f64],
    #[serde(skip_serializing_if = "Option::is_none")]
    standard_error_w_m2_sr_nm: Option<&'a [f64]>,
    /// Of the path to the point (--distance-m), 0-1.
    #[serde(skip_serializing_if = "Option::is_none")]
    transmittance: Option<&'a [f64]>,
    /// --stokes.
    #[serde(flatten)]
    stokes: Option<StokesJson<'a>>,
    /// CIE 1931 XYZ of the radiance, W m^-2 sr^-1 (sum of the colour-matching
    /// functions times the radiance times the step); null when no wavelength
    /// lies in 360-830 nm.
    xyz_w_m2_sr: Option<[f64; 3]>,
    /// Linear sRGB of the XYZ, the same unit; null as the XYZ is.
    linear_srgb_w_m2_sr: Option<[f64; 3]>,
}

/// The Stokes vector's Q, U and V (referred to the view's meridian plane),
/// their standard errors (path tracing), the degree and the angle of
/// linear polarisation (null where the light is unpolarised).
#[derive(Serialize)]
struct StokesJson<'a> {
    q_w_m2_sr_nm: &'a [f64],
    u_w_m2_sr_nm: &'a [f64],
    v_w_m2_sr_nm: &'a [f64],
    #[serde(skip_serializing_if = "Option::is_none")]
    standard_error_q_w_m2_sr_nm: Option<&'a [f64]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    standard_error_u_w_m2_sr_nm: Option<&'a [f64]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    standard_error_v_w_m2_sr_nm: Option<&'a [f64]>,
    degree_of_linear_polarisation: Vec<f64>,
    angle_of_polarisation_deg: Vec<Option<f64>>,
}

/// `sora spectrum --filter --format json`: per filter, the
/// response-weighted mean radiance.
#[derive(Serialize)]
struct FilteredJson<'a> {
    #[serde(flatten)]
    sun: crate::json::Sun,
    polarisation: String,
    filter: &'a [&'a str],
    centre_nm: &'a [f64],
    #[serde(flatten)]
    direction: Option<FilteredDirectionJson>,
    #[serde(skip_serializing_if = "Option::is_none")]
    directions: Option<Vec<FilteredDirectionJson>>,
}

/// One direction's mean radiance per filter.
#[derive(Serialize)]
struct FilteredDirectionJson {
    #[serde(skip_serializing_if = "Option::is_none")]
    view_elevation_deg: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    view_azimuth_deg: Option<f64>,
    radiance_w_m2_sr_nm: Vec<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    standard_error_w_m2_sr_nm: Option<Vec<f64>>,
}

/// `sora spectrum --filter`: per filter, the sky on its grid and the
/// response-weighted mean radiance in every direction.
fn run_filtered(
    args: &SpectrumArgs,
    filters: &[sora::spectrum::Filter],
    grids: &[sora::spectrum::WavelengthGrid],
    views: &[ViewDirection],
    atmosphere: sora::Atmosphere,
    (scattering, method): (sora::Scattering, sora::Method),
) -> anyhow::Result<()> {
    let started = Instant::now();
    let path_tracing = args.method.is_path_tracing();
    // [filter][direction] -> (radiance, standard error bound)
    let mut values = Vec::with_capacity(filters.len());
    // The sun and the light of the first filter's sky (all are alike).
    let mut sun_and_light = None;
    for (filter, grid) in filters.iter().zip(grids) {
        let mut atmosphere = atmosphere.clone();
        let options = args.sun.with_wavelengths(*grid);
        let (sky, sun) = options.sky(&mut atmosphere, scattering, method)?;
        sun_and_light.get_or_insert_with(|| {
            (
                crate::json::Sun::new(sun.elevation_deg, sun.azimuth_deg, &sun),
                sky.polarisation().to_string(),
            )
        });
        if path_tracing {
            let samples = match method {
                sora::Method::PathTracing { samples, .. } => samples,
                _ => 0,
            };
            crate::estimate::announce(crate::estimate::path_tracing_estimate(
                samples,
                views.len(),
                grid.len(),
            ));
        }
        let results = sky.radiances(views)?;
        let per_view = results
            .iter()
            .map(|r| {
                let mean = filter.weighted_mean(grid, &r.radiance_w_m2_sr_nm)?;
                // The response-weighted mean of the errors: a bound on the
                // mean's error however the wavelengths' errors correlate.
                let error = r
                    .standard_error_w_m2_sr_nm
                    .as_ref()
                    .map(|e| filter.weighted_mean(grid, e))
                    .transpose()?;
                Ok((mean, error))
            })
            .collect::<sora::Result<Vec<_>>>()?;
        values.push(per_view);
    }
    let centres = filters
        .iter()
        .map(sora::spectrum::Filter::centre_nm)
        .collect::<sora::Result<Vec<f64>>>()?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let error_header = if path_tracing {
        ",standard_error_w_m2_sr_nm"
    } else {
        ""
    };
    let one_view = args.view_elevation.is_some();
    match args.format {
        Format::Csv => {
            let view_header = if one_view {
                ""
            } else {
                "view_elevation_deg,view_azimuth_deg,"
            };
            writeln!(
                out,
                "{view_header}filter,centre_nm,radiance_w_m2_sr_nm{error_header}"
            )?;
            for (v, view) in views.iter().enumerate() {
                for ((filter, centre), per_view) in filters.iter().zip(&centres).zip(&values) {
                    if !one_view {
                        write!(out, "{},{},", view.elevation_deg(), view.azimuth_deg())?;
                    }
                    let (radiance, error) = per_view[v];
                    write!(out, "{},{centre:.4},{radiance:.9e}", filter.name())?;
                    if let Some(error) = error {
                        write!(out, ",{error:.3e}")?;
                    }
                    writeln!(out)?;
                }
            }
        }
        Format::Json => {
            let (sun, polarisation) = sun_and_light.expect("at least one filter");
            let names: Vec<&str> = filters.iter().map(sora::spectrum::Filter::name).collect();
            let direction = |v: usize, view: Option<&ViewDirection>| FilteredDirectionJson {
                view_elevation_deg: view.map(|v| v.elevation_deg()),
                view_azimuth_deg: view.map(|v| v.azimuth_deg()),
                radiance_w_m2_sr_nm: values.iter().map(|p| p[v].0).collect(),
                standard_error_w_m2_sr_nm: path_tracing
                    .then(|| values.iter().filter_map(|p| p[v].1).collect()),
            };
            let text = crate::json::to_string(&FilteredJson {
                sun,
                polarisation,
                filter: &names,
                centre_nm: &centres,
                direction: one_view.then(|| direction(0, None)),
                directions: (!one_view).then(|| {
                    views
                        .iter()
                        .enumerate()
                        .map(|(v, view)| direction(v, Some(view)))
                        .collect()
                }),
            })?;
            out.write_all(text.as_bytes())?;
        }
    }
    out.flush()?;
    eprintln!(
        "{} directions x {} filters in {:.3} s",
        views.len(),
        filters.len(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
