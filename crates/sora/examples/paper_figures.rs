//! The paper's results, and skies beside them, generated from the library
//! (deterministic; 60-120 s on two cores after the build):
//!
//! ```sh
//! cargo run --release -p sora --example paper_figures -- docs
//! ```
//!
//! Writes into the directory given (default `docs`, created if missing):
//! - `table1_spectrum.csv`, `table1_spectrum.png`,
//!   `table1_spectrum_normalised.png`: the sky spectrum of the paper's
//!   Table 1 geometry (sun 36 deg elevation, azimuth 207; view 17, 347),
//!   single scattering beside all orders, absolute and normalised to each
//!   curve's maximum over 380-780 nm (as the paper normalised its Fig. 2),
//!   checked against the paper's march and the path tracer;
//! - Earth skies (`earth-clear` at noon, sunset and twilight; `paper-earth`
//!   at noon) as fisheyes (512 x 512) and equirectangular panoramas
//!   (1024 x 512), each as `*_single.png` and `*_multiple.png`;
//! - the Mars sunset (`paper-mars`, the paper's Table 2, and `mars-dust`)
//!   as a fisheye and a perspective view toward the sun, single and
//!   multiple, and `mars_sun_glow.csv`: the colour of the sky near the sun
//!   and away from it, the numbers behind `docs/README.md`'s remarks on the
//!   blue glow;
//! - `polarisation_principal_plane.png` and `.csv`: the degree of
//!   polarisation along the sun's vertical of a Rayleigh sky
//!   (`us-standard-1976-rayleigh`, 550 nm) at suns 30 and 5 degrees, single
//!   scattering beside all orders (the polarised path tracer), with the
//!   neutral points where the higher orders put them;
//! - `twilight_sequence.png`: earth-clear panoramas with the sun at 0, -2,
//!   -4, -6, -9 and -12 degrees in the west, each row at its own automatic
//!   exposure (printed), showing the Earth's shadow and the Belt of Venus;
//! - `twilight_brightness.png` and `.csv`: zenith luminance and horizontal
//!   illuminance of earth-clear against sun elevation, +10 to -18 degrees,
//!   with the classic clear-sky illuminances beside them;
//! - `day_strip.png`: a day over Tokyo (June solstice 2026) from before
//!   sunrise to after sunset, fisheyes at one exposure;
//!
//! (The README's two pictures, `readme_sky.png` and `readme_tokyo.png`, are
//! written by the README's own commands, `sora render`, and checked against
//! them by `crates/sora-cli/tests/docs_recipes_cli.rs`.)
//!
//! Every image goes through the same stages as `sora render`:
//! [`Sky::render_xyz`] (fast method, sun disc drawn), then the
//! colour module's [`DisplayMapping`] (sRGB, the preserve-hue gamut
//! mapping, which keeps the hue of over-exposed sky; scalar light)
//! and [`write_png`]. Exposure: each scene's multiple-scattering fisheye
//! gets the default automatic exposure (log-average luminance -> 0.18), and
//! the same factor is used, fixed, for every other picture of the scene
//! (its other views, and single scattering), so they compare directly.
//!
//! The line plots are drawn by the workspace's `sora-plot` crate, which
//! also draws `sora retrieve --plot`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use sora::atmosphere::presets::find_preset;
use sora::atmosphere::{Atmosphere, Sun};
use sora::camera::{Camera, PerspectiveCamera};
use sora::colour::{
    DisplayMapping, Exposure, GamutMapping, Observer, RgbColourSpace, SpectrumToXyz,
};
use sora::geometry::angle_between_deg;
use sora::output::{DisplayImage, write_png};
use sora::spectrum::{SampledSpectrum, SolarSpectrum, WavelengthGrid};
use sora::sun_position::{Location, Refraction, SunPosition, parse_time_utc};
use sora::{
    ImageSettings, Irradiance, Method, Plane, Polarisation, Scattering, Sky, ViewDirection,
};
use sora_plot::{Axis, LinePlot, Series};

/// Image pixels per font pixel of the line plots' text (12-pixel
/// characters, sora-plot's 8 x 8 font).
const TEXT_SCALE: f64 = 1.5;

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

/// The paper's Table 1 geometry: (elevation, azimuth) in degrees.
const TABLE1_SUN: (f64, f64) = (36.0, 207.0);
const TABLE1_VIEW: (f64, f64) = (17.0, 347.0);

/// Sunsets face west.
const SUNSET_AZIMUTH: f64 = 270.0;
/// Sun elevation of the Earth and Mars sunsets, degrees.
const SUNSET_ELEVATION: f64 = 3.0;

fn main() {
    let started = Instant::now();
    let out = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "docs".into()));
    if let Err(e) = run(&out) {
        eprintln!("paper_figures: {e}");
        std::process::exit(1);
    }
    println!("done in {:.1} s", started.elapsed().as_secs_f64());
}

fn run(out: &Path) -> Result<()> {
    std::fs::create_dir_all(out)?;
    let grid = WavelengthGrid::paper();
    table1_spectrum(out, &grid)?;
    for scene in scenes()? {
        render_scene(out, &grid, &scene)?;
    }
    mars_sun_glow(out, &grid)?;
    polarisation_principal_plane(out)?;
    twilight_sequence(out, &grid)?;
    twilight_brightness(out, &grid)?;
    day_strip(out, &grid)?;
    Ok(())
}

/// Tokyo (35.68 N, 139.77 E), the README's time-and-place example.
const TOKYO: (f64, f64) = (35.68, 139.77);

/// The sun over Tokyo at `time` (RFC 3339), refraction at its default, as
/// `sora render --time ... --location 35.68,139.77` computes it.
fn sun_over_tokyo(time: &str) -> Result<(f64, f64)> {
    let place = Location::new(TOKYO.0, TOKYO.1, 0.0)?;
    let sun = SunPosition::at(parse_time_utc(time)?, place, Refraction::default())?;
    Ok((sun.elevation_deg, sun.azimuth_deg))
}

/// `day_strip.png`: a day at one place, Tokyo on the June solstice 2026,
/// as fisheyes (160 px, north up, east left) side by side from before
/// sunrise to after sunset (local times in `DAY_STRIP_TIMES`), all at one
/// exposure: the automatic exposure of the brightest frame, so that the
/// frames compare directly (twilight is as dark as it is).
fn day_strip(out: &Path, grid: &WavelengthGrid) -> Result<()> {
    let started = Instant::now();
    const SIDE: usize = 160;
    let atmosphere = Atmosphere::preset("earth-clear")?;
    let to_xyz = SpectrumToXyz::new(grid, Observer::Cie1931TwoDegree);
    let image = ImageSettings::new(Camera::Fisheye, SIDE as u32, SIDE as u32);
    let frames = DAY_STRIP_TIMES.len();
    let mut strip = vec![sora::colour::Xyz::BLACK; frames * SIDE * SIDE];
    let mut first: Option<Sky> = None;
    let mut frame_scales = Vec::with_capacity(frames);
    for (k, time) in DAY_STRIP_TIMES.iter().enumerate() {
        let (elevation, azimuth) = sun_over_tokyo(&format!("2026-06-21T{time}:00+09:00"))?;
        // Every frame after the first reuses its optics.
        let sky = match &first {
            None => sky(
                &atmosphere,
                grid,
                (elevation, azimuth),
                Scattering::multiple(),
                Method::Fast,
            )?,
            Some(first) => first.with_sun_deg(elevation, azimuth)?,
        };
        let xyz = sky.render_xyz(&image, &to_xyz, &|_| {})?;
        frame_scales.push(Exposure::default().scale_for_image(&xyz)?);
        for row in 0..SIDE {
            let at = (row * frames + k) * SIDE;
            strip[at..at + SIDE].copy_from_slice(&xyz[row * SIDE..(row + 1) * SIDE]);
        }
        println!("day strip: {time} local, sun {elevation:.2} deg up at {azimuth:.2} deg");
        first.get_or_insert(sky);
    }
    // One exposure: the automatic exposure of the brightest frame (the
    // smallest of the frames' own), so that midday is exposed as a camera
    // would and twilight is as dark as it is beside it.
    let scale = frame_scales.iter().copied().fold(f64::INFINITY, f64::min);
    let mapping = DisplayMapping {
        exposure: Exposure::Fixed(scale),
        ..DisplayMapping::default()
    };
    let pixels = mapping.to_u8(&strip)?.concat();
    let path = out.join("day_strip.png");
    write_png(&path, &DisplayImage::new(frames * SIDE, SIDE, pixels)?)?;
    println!(
        "wrote {} ({} frames, one exposure {scale:.4e}, {:.2} s)",
        path.display(),
        frames,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Local times (UTC+9) of the day strip's frames.
const DAY_STRIP_TIMES: [&str; 10] = [
    "04:00", "04:30", "05:30", "08:00", "11:40", "15:00", "18:00", "18:50", "19:15", "19:40",
];

/// The sky of `atmosphere` with the sun at (elevation, azimuth), seen
/// from the ground, with `scattering` by `method`.
fn sky(
    atmosphere: &Atmosphere,
    grid: &WavelengthGrid,
    sun: (f64, f64),
    scattering: Scattering,
    method: Method,
) -> Result<Sky> {
    Ok(Sky::builder(atmosphere)
        .wavelengths(*grid)
        .sun_deg(sun.0, sun.1)
        .scattering(scattering)
        .method(method)
        .polarisation(sora::Polarisation::Scalar)
        .build()?)
}

/// Spectral radiance toward (elevation, azimuth), W m^-2 sr^-1 nm^-1, as
/// `sora spectrum` computes it.
fn radiance(sky: &Sky, view: (f64, f64)) -> Result<SampledSpectrum> {
    Ok(sky
        .radiance(ViewDirection::new(view.0, view.1)?)?
        .radiance_w_m2_sr_nm)
}

/// A preset with one line of its TOML replaced (a variant for comparison).
fn preset_variant(name: &str, from: &str, to: &str) -> Result<Atmosphere> {
    let preset = find_preset(name).ok_or_else(|| format!("no preset {name}"))?;
    if !preset.toml.contains(from) {
        return Err(format!("preset {name} has no line '{from}'").into());
    }
    Ok(Atmosphere::from_toml_str(&preset.toml.replace(from, to))?)
}

fn wrote(path: &Path, what: &str, started: Instant) {
    println!(
        "wrote {} ({what}, {:.2} s)",
        path.display(),
        started.elapsed().as_secs_f64()
    );
}

// ---------------------------------------------------------------------------
// Twilight

/// Sun elevations of the twilight sequence, degrees (the sun in the west).
const TWILIGHT_SUNS: [f64; 6] = [0.0, -2.0, -4.0, -6.0, -9.0, -12.0];

/// `twilight_sequence.png`: earth-clear, all orders, the upper halves (down
/// to 6 degrees below the horizon) of 512 x 256 panoramas (north at the
/// centre, west at a quarter of the width) stacked from sun 0 (top) to -12
/// degrees (bottom); each row at its own automatic exposure of that part,
/// since the sky dims fifty-thousandfold over the sequence.
fn twilight_sequence(out: &Path, grid: &WavelengthGrid) -> Result<()> {
    let started = Instant::now();
    let (width, height) = (512usize, 256usize);
    let atmosphere = Atmosphere::preset("earth-clear")?;
    let to_xyz = SpectrumToXyz::new(grid, Observer::Cie1931TwoDegree);
    let image = ImageSettings::new(Camera::Equirectangular, width as u32, height as u32);
    let first = sky(
        &atmosphere,
        grid,
        (TWILIGHT_SUNS[0], SUNSET_AZIMUTH),
        Scattering::multiple(),
        Method::Fast,
    )?;
    let mut rows = Vec::with_capacity(TWILIGHT_SUNS.len() * width * height);
    // The sky and 6 degrees below the horizon of each panorama (the
    // ground below is lit only by the sky and shows nothing of twilight).
    let kept = height / 2 + height / 30;
    for elevation in TWILIGHT_SUNS {
        let sky = first.with_sun_deg(elevation, SUNSET_AZIMUTH)?;
        let xyz = sky.render_xyz(&image, &to_xyz, &|_| {})?;
        let sky_rows = &xyz[..kept * width];
        let scale = Exposure::default().scale_for_image(sky_rows)?;
        println!("twilight sequence: sun {elevation} deg, automatic exposure {scale:.4e}");
        rows.extend(sky_rows.iter().map(|c| c.scaled(scale)));
    }
    let mapping = DisplayMapping {
        exposure: Exposure::Fixed(1.0),
        gamut_mapping: GamutMapping::PreserveHue,
        ..DisplayMapping::default()
    };
    let pixels = mapping.to_u8(&rows)?.concat();
    let path = out.join("twilight_sequence.png");
    write_png(
        &path,
        &DisplayImage::new(width, kept * TWILIGHT_SUNS.len(), pixels)?,
    )?;
    wrote(&path, "twilight sequence", started);
    Ok(())
}

/// `twilight_brightness.png` and `.csv`: the zenith luminance (cd/m^2) and
/// the global horizontal illuminance (lux) of earth-clear, fast method with
/// all orders, for the sun every degree from +10 to -18 (azimuth 270), as
/// log10 against the sun's elevation, with the classic clear-sky
/// illuminances quoted by issue 11 (400-700 lx at 0, 2-4 lx at -6, about
/// 0.01 lx at -12) as markers.
fn twilight_brightness(out: &Path, grid: &WavelengthGrid) -> Result<()> {
    let started = Instant::now();
    let atmosphere = Atmosphere::preset("earth-clear")?;
    let to_xyz = SpectrumToXyz::new(grid, Observer::Cie1931TwoDegree);
    let first = sky(
        &atmosphere,
        grid,
        (10.0, SUNSET_AZIMUTH),
        Scattering::multiple(),
        Method::Fast,
    )?;
    let horizontal = Plane::new(0.0, 0.0)?;
    let zenith = ViewDirection::new(90.0, 0.0)?;
    let mut csv = String::from(
        "# earth-clear, fast method, all orders, sun azimuth 270: zenith luminance and global horizontal illuminance\nsun_elevation_deg,zenith_luminance_cd_m2,horizontal_illuminance_lx\n",
    );
    let (mut luminance, mut illuminance) = (Vec::new(), Vec::new());
    for k in 0..=28 {
        let elevation = 10.0 - k as f64;
        let sky = first.with_sun_deg(elevation, SUNSET_AZIMUTH)?;
        let l = to_xyz
            .to_xyz(&sky.radiance(zenith)?.radiance_w_m2_sr_nm)?
            .luminance_cd_m2();
        let e = Irradiance::illuminance_lx(&sky.irradiance(horizontal)?.global_w_m2_nm, grid)?;
        writeln!(csv, "{elevation},{l:.6e},{e:.6e}")?;
        for (series, value) in [(&mut luminance, l), (&mut illuminance, e)] {
            if value > 0.0 {
                series.push((elevation, value.log10()));
            }
        }
    }
    let path = out.join("twilight_brightness.csv");
    std::fs::write(&path, csv)?;
    wrote(&path, "twilight brightness", started);
    let classic = |elevation: f64, low: f64, high: f64| {
        vec![(elevation, low.log10()), (elevation, high.log10())]
    };
    let mut series = vec![
        Series::curve(
            "HORIZONTAL ILLUMINANCE (LX)",
            [200, 60, 40],
            false,
            illuminance,
        ),
        Series::curve("ZENITH LUMINANCE (CD/M2)", [40, 90, 200], false, luminance),
    ];
    for (label, elevation, low, high) in [
        ("CLASSIC: 400-700 LX AT 0", 0.0, 400.0, 700.0),
        ("CLASSIC: 2-4 LX AT -6", -6.0, 2.0, 4.0),
        ("CLASSIC: ABOUT 0.01 LX AT -12", -12.0, 0.007, 0.013),
    ] {
        series.push(Series::curve(
            label,
            [0, 0, 0],
            false,
            classic(elevation, low, high),
        ));
    }
    let figure = LinePlot {
        title: "TWILIGHT, EARTH-CLEAR, FAST METHOD, ALL ORDERS".into(),
        x: Axis::linear(
            "SUN ELEVATION (DEG)",
            (-18.5, 10.5),
            (0..7).map(|k| -18.0 + 4.0 * k as f64),
            0,
        ),
        // Room above the curves for the legend.
        y: Axis::linear(
            "LOG10 OF THE VALUE",
            (-6.0, 9.0),
            (0..7).map(|k| -6.0 + 2.0 * k as f64),
            0,
        ),
        series,
        notes: vec!["BELOW -12 DEG THE METHOD IS NOT VALIDATED".into()],
        text_scale: TEXT_SCALE,
    };
    let (w, h, data) = figure.render(900, 640).into_rgb8();
    let path = out.join("twilight_brightness.png");
    write_png(&path, &DisplayImage::new(w, h, data)?)?;
    wrote(&path, "twilight plot", started);
    Ok(())
}

// ---------------------------------------------------------------------------
// Polarisation along the principal plane

/// Paths per direction of the polarisation curves (standard error of the
/// degree of polarisation about 0.004).
const POLARISATION_PATHS: u64 = 10_000;

/// `polarisation_principal_plane.png` and `.csv`: -Q/I along the sun's
/// vertical (where U = 0 by symmetry, so -Q/I is the degree of
/// polarisation with its sign: positive for a field perpendicular to the
/// vertical, the usual skylight polarisation, negative beyond a neutral
/// point), at 550 nm for the U.S. standard Rayleigh sky at suns 30 and 5
/// degrees (azimuth 180): single scattering (fast method, exact) and all
/// orders (the polarised path tracer). The x axis runs from the horizon
/// under the sun (0) over the zenith (90) to the opposite horizon (180).
fn polarisation_principal_plane(out: &Path) -> Result<()> {
    let started = Instant::now();
    let atmosphere = Atmosphere::preset("us-standard-1976-rayleigh")?;
    let grid = WavelengthGrid::new(550.0, 550.0, 20.0)?;
    // Elevations 1..89 toward the sun, the zenith, then 89..1 away from it.
    let along: Vec<f64> = (1..180).map(f64::from).collect();
    let views: Vec<ViewDirection> = along
        .iter()
        .map(|x| {
            if *x <= 90.0 {
                ViewDirection::new(*x, 180.0)
            } else {
                ViewDirection::new(180.0 - x, 0.0)
            }
        })
        .collect::<sora::Result<_>>()?;
    let mut csv = String::from(
        "# -Q/I at 550 nm along the principal plane of us-standard-1976-rayleigh (sun azimuth 180); x: degrees from the horizon under the sun over the zenith\nsun_elevation_deg,x_deg,view_elevation_deg,view_azimuth_deg,scattering,minus_q_over_i,standard_error\n",
    );
    let mut series = Vec::new();
    let mut notes = Vec::new();
    for (sun_elevation, colour) in [(30.0, [200, 60, 40]), (5.0, [40, 90, 200])] {
        for (scattering, method, dashed) in [
            ("single", Method::Fast, true),
            (
                "all orders",
                Method::PathTracing {
                    samples: POLARISATION_PATHS,
                    seed: 1,
                },
                false,
            ),
        ] {
            let sky = Sky::builder(&atmosphere)
                .wavelengths(grid)
                .sun_deg(sun_elevation, 180.0)
                .scattering(if dashed {
                    Scattering::Single
                } else {
                    Scattering::multiple()
                })
                .method(method)
                .polarisation(Polarisation::Vector)
                .build()?;
            let results = sky.radiances(&views)?;
            let mut points = Vec::with_capacity(views.len());
            for ((x, view), result) in along.iter().zip(&views).zip(&results) {
                let stokes = result.stokes.as_ref().ok_or("no Stokes vector")?;
                let (i, q) = (result.radiance_w_m2_sr_nm[0], stokes.q_w_m2_sr_nm[0]);
                let error = stokes
                    .standard_errors_w_m2_sr_nm
                    .as_ref()
                    .map_or(0.0, |e| e[0][0] / i);
                writeln!(
                    csv,
                    "{sun_elevation},{x},{},{},{scattering},{:.6},{error:.6}",
                    view.elevation_deg(),
                    view.azimuth_deg(),
                    -q / i
                )?;
                points.push((*x, -q / i));
            }
            if !dashed {
                // Neutral points: where -Q/I changes sign (linear between
                // the two directions around the change).
                for pair in points.windows(2) {
                    let ((x0, y0), (x1, y1)) = (pair[0], pair[1]);
                    if y0.signum() != y1.signum() {
                        let x = x0 + (x1 - x0) * y0 / (y0 - y1);
                        let (name, from) = if x < 90.0 {
                            (
                                if x > sun_elevation {
                                    "BABINET"
                                } else {
                                    "BREWSTER"
                                },
                                sun_elevation,
                            )
                        } else {
                            ("ARAGO", 180.0 + sun_elevation)
                        };
                        let note = format!(
                            "SUN {sun_elevation}: {name} POINT {:.1} DEG FROM THE {}",
                            (x - from).abs(),
                            if name == "ARAGO" { "ANTISUN" } else { "SUN" }
                        );
                        println!("{}", note.to_lowercase());
                        notes.push(note);
                    }
                }
            }
            series.push(Series::curve(
                format!("SUN {sun_elevation} DEG, {}", scattering.to_uppercase()),
                colour,
                dashed,
                points,
            ));
        }
    }
    let path = out.join("polarisation_principal_plane.csv");
    std::fs::write(&path, csv)?;
    wrote(&path, "polarisation along the principal plane", started);
    notes.push("SOLID: ALL ORDERS (PATH TRACER), DASHED: SINGLE".into());
    let figure = LinePlot {
        title: "DEGREE OF POLARISATION, SUN'S VERTICAL, RAYLEIGH SKY, 550 NM".into(),
        x: Axis::linear(
            "DEGREES FROM THE HORIZON UNDER THE SUN (ZENITH AT 90)",
            (0.0, 180.0),
            (0..7).map(|k| 30.0 * k as f64),
            0,
        ),
        // Room above the curves for the legend.
        y: Axis::linear(
            "-Q / I",
            (-0.2, 2.0),
            (0..7).map(|k| -0.2 + 0.2 * k as f64),
            1,
        ),
        series,
        notes,
        text_scale: TEXT_SCALE,
    };
    let (w, h, data) = figure.render(900, 640).into_rgb8();
    let path = out.join("polarisation_principal_plane.png");
    write_png(&path, &DisplayImage::new(w, h, data)?)?;
    wrote(&path, "polarisation plot", started);
    Ok(())
}

// ---------------------------------------------------------------------------
// 1. The Table 1 spectrum (the paper's Fig. 2 model curve)

fn table1_spectrum(out: &Path, grid: &WavelengthGrid) -> Result<()> {
    let started = Instant::now();
    let paper_earth = Atmosphere::preset("paper-earth")?;
    let mut paper_earth_e490 = paper_earth.clone();
    paper_earth_e490.sun = Sun::new(SolarSpectrum::astm_e490(), 1.0, 0.53)?;
    let earth_clear = Atmosphere::preset("earth-clear")?;
    // (CSV key, legend, atmosphere, colour)
    let curves = [
        (
            "paper_earth",
            "PAPER-EARTH, FLAT SUN (THE PAPER'S)",
            &paper_earth,
            [31, 90, 180],
        ),
        (
            "paper_earth_e490_sun",
            "PAPER-EARTH, ASTM E490 SUN",
            &paper_earth_e490,
            [230, 120, 20],
        ),
        (
            "earth_clear",
            "EARTH-CLEAR (ASTM E490 SUN, OZONE)",
            &earth_clear,
            [40, 150, 60],
        ),
    ];
    let mut columns = Vec::new();
    for (key, _, atmosphere, _) in &curves {
        let sky_by = |scattering, method| sky(atmosphere, grid, TABLE1_SUN, scattering, method);
        let single = radiance(&sky_by(Scattering::Single, Method::Fast)?, TABLE1_VIEW)?;
        let multiple = radiance(&sky_by(Scattering::multiple(), Method::Fast)?, TABLE1_VIEW)?;
        // Checks printed beside the numbers: the paper's uniform double
        // march for single scattering, the path tracer for all orders.
        let reference = radiance(
            &sky_by(
                Scattering::Single,
                Method::Reference {
                    view_steps: 4000,
                    sun_steps: 800,
                },
            )?,
            TABLE1_VIEW,
        )?;
        let traced = sky_by(
            Scattering::multiple(),
            Method::PathTracing {
                samples: PATHS_PER_CHECK,
                seed: 1,
            },
        )?
        .radiance(ViewDirection::new(TABLE1_VIEW.0, TABLE1_VIEW.1)?)?;
        let worst_single = worst_relative_difference(&single, &reference);
        let worst_multiple = worst_relative_difference(&multiple, &traced.radiance_w_m2_sr_nm);
        for (name, spectrum) in [("single", &single), ("multiple", &multiple)] {
            let (peak_nm, peak) = peak_of(grid, spectrum);
            println!(
                "table 1, {key}, {name} scattering: peak {peak:.4e} W m^-2 sr^-1 nm^-1 at {peak_nm} nm, {:.3} of it at 380 nm and {:.3} at 780 nm",
                spectrum[0] / peak,
                spectrum[grid.len() - 1] / peak,
            );
        }
        println!(
            "table 1, {key}: single scattering vs the reference march {worst_single:.1e}; multiple vs the path tracer ({PATHS_PER_CHECK} paths, {:.2}% standard error at worst) {:.2}% at worst",
            100.0 * traced.worst_relative_standard_error(),
            100.0 * worst_multiple
        );
        columns.push((key, single, multiple));
    }
    // CSV: absolute radiances, and each divided by its own maximum (as the
    // paper normalised its Fig. 2).
    let mut csv = String::from("wavelength_nm");
    for (key, _, _) in &columns {
        write!(
            csv,
            ",single_{key}_w_m2_sr_nm,multiple_{key}_w_m2_sr_nm,single_{key}_normalised,multiple_{key}_normalised"
        )?;
    }
    csv.push('\n');
    for (i, wavelength) in grid.wavelengths_nm().enumerate() {
        write!(csv, "{wavelength}")?;
        for (_, single, multiple) in &columns {
            let (s, m) = (single[i], multiple[i]);
            write!(
                csv,
                ",{s:.6e},{m:.6e},{:.6},{:.6}",
                s / single.max_value(),
                m / multiple.max_value()
            )?;
        }
        csv.push('\n');
    }
    let path = out.join("table1_spectrum.csv");
    std::fs::write(&path, csv)?;
    wrote(&path, "Table 1 spectra", started);

    let curve = |spectrum: &SampledSpectrum, scale: f64| -> Vec<(f64, f64)> {
        grid.wavelengths_nm()
            .zip(spectrum.values())
            .map(|(w, v)| (w, v / scale))
            .collect()
    };
    let plot = |series: Vec<Series>, y_label: &str, notes: Vec<String>| LinePlot {
        title: "TABLE 1: SUN 36 DEG / AZ 207, VIEW 17 DEG / AZ 347".into(),
        x: Axis::linear(
            "WAVELENGTH (NM)",
            (370.0, 790.0),
            (0..8).map(|k| 400.0 + 50.0 * k as f64),
            0,
        ),
        // Room above the curves for the legend.
        y: Axis::linear(y_label, (0.0, 1.65), (0..6).map(|k| 0.2 * k as f64), 1),
        series,
        notes,
        text_scale: TEXT_SCALE,
    };
    // 1. Single beside multiple scattering, for the paper's atmosphere and
    // sun and for the physical Earth: each pair divided by the maximum of
    // its multiple-scattering curve, so that both the shape and the light
    // added by the higher orders show.
    let mut series = Vec::new();
    for ((key, label, _, colour), (_, single, multiple)) in curves.iter().zip(&columns) {
        if *key == "paper_earth_e490_sun" {
            continue;
        }
        let scale = multiple.max_value();
        let name = label.split(" (").next().unwrap_or(label);
        for (scattering, spectrum, dashed) in
            [("MULTIPLE", multiple, false), ("SINGLE", single, true)]
        {
            series.push(Series::curve(
                format!("{name}, {scattering} SCATTERING"),
                *colour,
                dashed,
                curve(spectrum, scale),
            ));
        }
    }
    let figure = plot(
        series,
        "RADIANCE / MAXIMUM OF MULTIPLE",
        vec![
            "PAPER-EARTH: FLAT SUN, EARTH-CLEAR: E490 SUN".into(),
            "EACH PAIR DIVIDED BY ITS MULTIPLE-SCATTERING MAXIMUM".into(),
        ],
    );
    let (w, h, data) = figure.render(900, 640).into_rgb8();
    let path = out.join("table1_spectrum.png");
    write_png(&path, &DisplayImage::new(w, h, data)?)?;
    wrote(
        &path,
        "Table 1 plot, single and multiple scattering",
        started,
    );

    // 2. The paper's comparison (each curve divided by its own maximum):
    // which sun, with which orders of scattering.
    let mut series = Vec::new();
    for ((key, label, _, colour), (_, single, multiple)) in curves.iter().zip(&columns) {
        for (scattering, spectrum, dashed) in [("", multiple, false), (", SINGLE", single, true)] {
            if *key == "earth_clear" && dashed {
                continue;
            }
            series.push(Series::curve(
                format!("{label}{scattering}"),
                *colour,
                dashed,
                curve(spectrum, spectrum.max_value()),
            ));
        }
    }
    let figure = plot(
        series,
        "RADIANCE / ITS MAXIMUM",
        vec![
            "SOLID: MULTIPLE SCATTERING, DASHED: SINGLE".into(),
            "EACH CURVE DIVIDED BY ITS MAXIMUM".into(),
        ],
    );
    let (w, h, data) = figure.render(900, 640).into_rgb8();
    let path = out.join("table1_spectrum_normalised.png");
    write_png(&path, &DisplayImage::new(w, h, data)?)?;
    wrote(&path, "Table 1 plot, each curve to its maximum", started);
    Ok(())
}

/// Paths for each path-traced check of the Table 1 spectra (about 0.5%
/// standard error).
const PATHS_PER_CHECK: u64 = 40_000;

/// The wavelength (nm) and value of the largest sample of `spectrum`.
fn peak_of(grid: &WavelengthGrid, spectrum: &SampledSpectrum) -> (f64, f64) {
    let (index, peak) =
        spectrum
            .values()
            .iter()
            .enumerate()
            .fold(
                (0, f64::MIN),
                |best, (i, &v)| if v > best.1 { (i, v) } else { best },
            );
    (grid.wavelength_nm(index), peak)
}

/// The largest |a / b - 1| over the samples.
fn worst_relative_difference(a: &SampledSpectrum, b: &SampledSpectrum) -> f64 {
    a.values()
        .iter()
        .zip(b.values())
        .map(|(a, b)| (a / b - 1.0).abs())
        .fold(0.0, f64::max)
}

// ---------------------------------------------------------------------------
// 2-3. Skies as images

/// How a view's exposure is chosen.
#[derive(Clone, Copy, PartialEq)]
enum ViewExposure {
    /// The scene's: the automatic exposure of its first view, fixed.
    Scene,
    /// The brightest pixel's largest linear sRGB component at full scale,
    /// so that nothing is clipped (with the sun's disc left out).
    Unclipped,
}

/// One image of a scene.
struct View {
    suffix: &'static str,
    camera: Camera,
    width: u32,
    height: u32,
    exposure: ViewExposure,
}

/// One sky; its first view sets the exposure of its other views.
struct Scene {
    name: &'static str,
    atmosphere: Atmosphere,
    sun: (f64, f64),
    /// Draw the sun's disc.
    sun_disc: bool,
    /// Render single scattering beside multiple scattering (`*_single.png`
    /// and `*_multiple.png`); otherwise multiple only.
    single_too: bool,
    views: Vec<View>,
}

fn fisheye() -> View {
    View {
        suffix: "fisheye",
        camera: Camera::Fisheye,
        width: 512,
        height: 512,
        exposure: ViewExposure::Scene,
    }
}

fn panorama() -> View {
    View {
        suffix: "panorama",
        camera: Camera::Equirectangular,
        width: 1024,
        height: 512,
        exposure: ViewExposure::Scene,
    }
}

/// Toward the setting sun: 90 deg across, looking 15 deg up, so the
/// horizon is in the lower part.
fn toward_sunset(exposure: ViewExposure) -> Result<View> {
    Ok(View {
        suffix: match exposure {
            ViewExposure::Scene => "toward_sun",
            ViewExposure::Unclipped => "toward_sun_unclipped",
        },
        camera: Camera::Perspective(PerspectiveCamera::new(15.0, SUNSET_AZIMUTH, 90.0)?),
        width: 768,
        height: 512,
        exposure,
    })
}

fn scenes() -> Result<Vec<Scene>> {
    let preset = Atmosphere::preset;
    let sunset = (SUNSET_ELEVATION, SUNSET_AZIMUTH);
    Ok(vec![
        Scene {
            name: "earth_clear_noon",
            atmosphere: preset("earth-clear")?,
            sun: (60.0, 180.0),
            sun_disc: true,
            single_too: true,
            views: vec![fisheye(), panorama()],
        },
        Scene {
            name: "earth_clear_sunset",
            atmosphere: preset("earth-clear")?,
            sun: sunset,
            sun_disc: true,
            single_too: true,
            views: vec![fisheye(), panorama()],
        },
        Scene {
            name: "earth_clear_twilight",
            atmosphere: preset("earth-clear")?,
            sun: (-2.0, SUNSET_AZIMUTH),
            sun_disc: true,
            single_too: true,
            views: vec![fisheye(), panorama()],
        },
        Scene {
            name: "paper_earth_noon",
            atmosphere: preset("paper-earth")?,
            sun: (60.0, 180.0),
            sun_disc: true,
            single_too: true,
            views: vec![fisheye(), panorama()],
        },
        Scene {
            name: "paper_mars_sunset",
            atmosphere: preset("paper-mars")?,
            sun: sunset,
            sun_disc: true,
            single_too: true,
            views: vec![
                fisheye(),
                toward_sunset(ViewExposure::Scene)?,
                toward_sunset(ViewExposure::Unclipped)?,
            ],
        },
        Scene {
            name: "mars_dust_sunset",
            atmosphere: preset("mars-dust")?,
            sun: sunset,
            sun_disc: true,
            single_too: true,
            views: vec![
                fisheye(),
                toward_sunset(ViewExposure::Scene)?,
                toward_sunset(ViewExposure::Unclipped)?,
            ],
        },
    ])
}

fn render_scene(out: &Path, grid: &WavelengthGrid, scene: &Scene) -> Result<()> {
    let started = Instant::now();
    // One sky per order of scattering, each building its tables once for
    // all the scene's views.
    let multiple_sky = Sky::builder(&scene.atmosphere)
        .wavelengths(*grid)
        .sun_deg(scene.sun.0, scene.sun.1)
        .polarisation(Polarisation::Scalar)
        .build()?;
    let single_sky = sky(
        &scene.atmosphere,
        grid,
        scene.sun,
        Scattering::Single,
        Method::Fast,
    )?;
    let to_xyz = SpectrumToXyz::new(grid, Observer::Cie1931TwoDegree);
    let mut scene_exposure = None;
    for view in &scene.views {
        let settings = ImageSettings {
            camera: view.camera,
            width: view.width,
            height: view.height,
            draw_sun_disc: scene.sun_disc && view.exposure == ViewExposure::Scene,
        };
        // Multiple scattering first: its exposure is the view's, and the
        // single-scattering picture beside it shares it.
        let mut scale = None;
        for sky in [&multiple_sky, &single_sky] {
            let (scattering_name, file_suffix) = match sky.scattering() {
                Scattering::Single if !scene.single_too => continue,
                Scattering::Single => ("single", "_single"),
                Scattering::Multiple(_) if scene.single_too => ("multiple", "_multiple"),
                Scattering::Multiple(_) => ("multiple", ""),
            };
            let xyz = sky.render_xyz(&settings, &to_xyz, &|_| {})?;
            let scale = *match (view.exposure, scene_exposure) {
                (ViewExposure::Scene, Some(scene_scale)) => scale.insert(scene_scale),
                (ViewExposure::Scene, None) => {
                    let auto = Exposure::default().scale_for_image(&xyz)?;
                    scene_exposure = Some(auto);
                    scale.insert(auto)
                }
                (ViewExposure::Unclipped, _) => scale.get_or_insert_with(|| {
                    let peak = xyz
                        .iter()
                        .map(|c| RgbColourSpace::Srgb.linear_rgb_from_xyz(*c).max_component())
                        .fold(0.0, f64::max);
                    1.0 / peak
                }),
            };
            // The scenes compared in docs/README.md keep the hue of
            // over-exposed sky (preserve-hue), so that the glow around a
            // low sun shows its colour.
            let mapping = DisplayMapping {
                exposure: Exposure::Fixed(scale),
                gamut_mapping: GamutMapping::PreserveHue,
                ..DisplayMapping::default()
            };
            let data = mapping.to_u8(&xyz)?.into_iter().flatten().collect();
            let file = if view.suffix.is_empty() {
                format!("{}{file_suffix}.png", scene.name)
            } else {
                format!("{}_{}{file_suffix}.png", scene.name, view.suffix)
            };
            let path = out.join(file);
            write_png(
                &path,
                &DisplayImage::new(view.width as usize, view.height as usize, data)?,
            )?;
            wrote(
                &path,
                &format!(
                    "{}x{}, {scattering_name} scattering, sun {} / {} deg, disc {}, exposure {scale}",
                    view.width,
                    view.height,
                    scene.sun.0,
                    scene.sun.1,
                    if settings.draw_sun_disc {
                        "drawn"
                    } else {
                        "not drawn"
                    }
                ),
                started,
            );
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// 3. The colour of the Mars sky near the setting sun and away from it

fn mars_sun_glow(out: &Path, grid: &WavelengthGrid) -> Result<()> {
    let started = Instant::now();
    let variants = [
        ("paper-mars", Atmosphere::preset("paper-mars")?),
        (
            "paper-mars (mie phase)",
            preset_variant(
                "paper-mars",
                r#"scattering.mie.phase = "paper-hg""#,
                r#"scattering.mie.phase = "mie""#,
            )?,
        ),
        ("mars-dust", Atmosphere::preset("mars-dust")?),
        (
            "mars-dust (paper-hg phase)",
            preset_variant(
                "mars-dust",
                r#"scattering.mie.phase = "mie""#,
                r#"scattering.mie.phase = "paper-hg""#,
            )?,
        ),
    ];
    let (sun_el, sun_az) = (SUNSET_ELEVATION, SUNSET_AZIMUTH);
    // Above the sun (same azimuth), then along its almucantar (same elevation).
    let mut directions: Vec<(String, f64, f64)> = [1.0, 2.0, 5.0, 10.0, 20.0, 45.0]
        .iter()
        .map(|d| (format!("{d} deg above the sun"), sun_el + d, sun_az))
        .collect();
    directions.push(("zenith".into(), 90.0, sun_az));
    for d in [5.0, 10.0, 20.0, 45.0, 90.0, 135.0, 180.0] {
        directions.push((
            format!("{d} deg in azimuth from the sun"),
            sun_el,
            sun_az - d,
        ));
    }
    let to_xyz = SpectrumToXyz::new(grid, Observer::Cie1931TwoDegree);
    let index_of = |nm: f64| ((nm - grid.start_nm()) / grid.step_nm()).round() as usize;
    let (blue, red) = (index_of(440.0), index_of(700.0));
    let mut csv = String::from(
        "atmosphere,scattering,direction,view_elevation_deg,view_azimuth_deg,angle_from_sun_deg,y_luminance,chromaticity_x,chromaticity_y,linear_srgb_r,linear_srgb_g,linear_srgb_b,b_over_r,l440_over_l700_relative_to_sun\n",
    );
    for (name, atmosphere) in &variants {
        let single_sky = sky(
            atmosphere,
            grid,
            (sun_el, sun_az),
            Scattering::Single,
            Method::Fast,
        )?;
        let multiple_sky = sky(
            atmosphere,
            grid,
            (sun_el, sun_az),
            Scattering::multiple(),
            Method::Fast,
        )?;
        let sun = &single_sky.optics().solar_irradiance_w_m2_nm;
        let sun_ratio = sun[blue] / sun[red];
        for (scattering, sky) in [("single", &single_sky), ("multiple", &multiple_sky)] {
            let mut summary = Vec::new();
            for (label, el, az) in &directions {
                let spectrum = radiance(sky, (*el, *az))?;
                let xyz = to_xyz.to_xyz(&spectrum)?;
                let [x, y] = xyz.chromaticity_xy().unwrap_or([f64::NAN, f64::NAN]);
                let rgb = RgbColourSpace::Srgb.linear_rgb_from_xyz(xyz);
                let b_over_r = rgb.b / rgb.r;
                let spectral = spectrum[blue] / spectrum[red] / sun_ratio;
                let angle = angle_between_deg(*el, *az, sun_el, sun_az);
                writeln!(
                    csv,
                    "{name},{scattering},{label},{el},{az},{angle:.2},{:.6e},{x:.4},{y:.4},{:.6e},{:.6e},{:.6e},{b_over_r:.4},{spectral:.4}",
                    xyz.y, rgb.r, rgb.g, rgb.b
                )?;
                if label == "1 deg above the sun" || label == "90 deg in azimuth from the sun" {
                    summary.push(format!(
                        "{label}: Y {:.4e}, B/R {b_over_r:.3}, xy ({x:.3}, {y:.3})",
                        xyz.y
                    ));
                }
            }
            println!(
                "mars glow, {name}, {scattering} scattering: {}",
                summary.join("; ")
            );
        }
    }
    let path = out.join("mars_sun_glow.csv");
    std::fs::write(&path, csv)?;
    wrote(&path, "Mars sky colour near and away from the sun", started);
    Ok(())
}
