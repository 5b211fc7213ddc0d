//! Where the fast method departs from the path tracer after sunset, order
//! by order (issue 11): an ignored survey that prints, per preset, sun,
//! view and wavelength, the fast method's total, its single scattering
//! and its multiple scattering (total minus single) over the path
//! tracer's same parts (`PathTracedSpectrum::single_scattering` and
//! `multiple_scattering`; the sunlit ground is zero above the horizon),
//! each as fast / traced - 1 with the traced part's relative standard
//! error.
//!
//! Settings by environment (all optional): `SORA_SURVEY_PRESETS`
//! (comma-separated preset names or paths of atmosphere files ending in
//! `.toml`, default earth-clear,earth-hazy, us-standard-1976-rayleigh),
//! `SORA_SURVEY_SUNS` (degrees, default
//! -2,-4,-6), `SORA_SURVEY_SAMPLES` (paths per view, default 800 000),
//! `SORA_SURVEY_VIEWS` (`elevation:azimuth` pairs, azimuth from the sun;
//! default the zenith and elevations 5 and 20 at 0, 90 and 180 degrees).
//! `SORA_SURVEY_VARIANTS` (default `default`): fast settings to compare,
//! each `default` or `+`-joined changes of it: `sN` streams per
//! hemisphere, `lN` layers, `zX` the sunset sun-zenith step in degrees,
//! `pN` view-ray panels, `tN` a sun-column table of N altitude and 2N mu
//! nodes (e.g. `s16+z0.25`).
//! `SORA_SURVEY_ORDERS=N` (N >= 2): the orders up to N alone (the fast
//! field stopped after N - 1 sweeps, the path tracer's paths after N
//! interactions); `multiple` is then the orders 2 to N.
//! `SORA_SURVEY_PLAIN=1`: the path tracer without its draws toward the
//! sunlit air (`PathTracer::without_twilight_sampling`), to check them.
//! Wavelengths 440, 560 and 680 nm.
//!
//! ```text
//! cargo test --release -p sora --lib -- --ignored --nocapture twilight_survey
//! ```

use crate::atmosphere::Atmosphere;
use crate::spectrum::WavelengthGrid;
use crate::transport::multiple_scattering::{FieldRequest, MultipleScatteringField};
use crate::transport::{Observation, PathTracer, SingleScatteringScene, SunColumns};
use crate::{FastTableSize, Method, MultipleScatteringSettings, Scattering, Sky, ViewDirection};

/// The default settings and tables with a variant's changes (module docs).
fn settings(variant: &str) -> (MultipleScatteringSettings, FastTableSize) {
    let mut settings = MultipleScatteringSettings::default();
    let mut table = FastTableSize::default();
    for change in variant.split('+').filter(|c| *c != "default") {
        let (key, value) = change.split_at(1);
        match key {
            "s" => settings.streams_per_hemisphere = value.parse().unwrap(),
            "l" => settings.layers = value.parse().unwrap(),
            "z" => settings.sunset_sun_zenith_step_deg = value.parse().unwrap(),
            "p" => settings.view_ray_panels = value.parse().unwrap(),
            "t" => {
                let n: usize = value.parse().unwrap();
                table.sun_column_nodes = (n, 2 * n);
            }
            _ => panic!("unknown variant {change}"),
        }
    }
    (settings, table)
}

fn list(name: &str, default: &str) -> Vec<String> {
    std::env::var(name)
        .unwrap_or_else(|_| default.to_string())
        .split(',')
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .collect()
}

/// One row per (preset, sun, view, wavelength):
/// `preset,sun,elevation,azimuth,nm,variant,total,total_se,single,single_se,multiple,multiple_se,ms_share`,
/// where each of total/single/multiple is fast / traced - 1 and its `_se`
/// the traced part's relative standard error, and `ms_share` the traced
/// multiple scattering over the traced total.
#[test]
#[ignore]
fn twilight_survey() {
    let presets = list(
        "SORA_SURVEY_PRESETS",
        "earth-clear,earth-hazy,us-standard-1976-rayleigh",
    );
    let suns: Vec<f64> = list("SORA_SURVEY_SUNS", "-2,-4,-6")
        .iter()
        .map(|s| s.parse().unwrap())
        .collect();
    let samples: u64 = std::env::var("SORA_SURVEY_SAMPLES")
        .map(|s| s.parse().unwrap())
        .unwrap_or(800_000);
    let views: Vec<(f64, f64)> = list("SORA_SURVEY_VIEWS", "90:0,5:0,5:90,5:180,20:0,20:90,20:180")
        .iter()
        .map(|v| {
            let (e, a) = v.split_once(':').unwrap();
            (e.parse().unwrap(), a.parse().unwrap())
        })
        .collect();
    let variants = list("SORA_SURVEY_VARIANTS", "default");
    let orders: Option<usize> = std::env::var("SORA_SURVEY_ORDERS")
        .ok()
        .map(|v| v.parse().unwrap())
        .filter(|n| *n >= 2);
    let grid = WavelengthGrid::new(440.0, 680.0, 120.0).unwrap();
    println!(
        "preset,sun,elevation,azimuth,nm,variant,total,total_se,single,single_se,multiple,multiple_se,ms_share"
    );
    for preset in &presets {
        // A preset's name, or the path of an atmosphere file (`.toml`).
        let atmosphere = if preset.ends_with(".toml") {
            Atmosphere::from_toml_str(&std::fs::read_to_string(preset).unwrap()).unwrap()
        } else {
            Atmosphere::preset(preset).unwrap()
        };
        for (n, &sun) in suns.iter().enumerate() {
            let observation = Observation {
                observer_altitude_m: 0.0,
                sun_elevation_deg: sun,
                sun_azimuth_deg: 0.0,
            };
            let scene = SingleScatteringScene::new(&atmosphere, &grid, observation).unwrap();
            let sky = |scattering, table| {
                Sky::from_scene(scene.clone(), scattering, Method::Fast, table).unwrap()
            };
            let directions: Vec<ViewDirection> = views
                .iter()
                .map(|(e, a)| ViewDirection::new(*e, *a).unwrap())
                .collect();
            let single = sky(Scattering::Single, FastTableSize::default())
                .radiances(&directions)
                .unwrap();
            let totals: Vec<Vec<crate::SkyRadiance>> = variants
                .iter()
                .map(|v| {
                    let (settings, table) = settings(v);
                    let Some(orders) = orders else {
                        return sky(Scattering::Multiple(settings), table)
                            .radiances(&directions)
                            .unwrap();
                    };
                    let request = FieldRequest {
                        sweeps: orders - 1,
                        ..FieldRequest::new(settings, table.sun_column_nodes)
                    };
                    let field = MultipleScatteringField::solve(&scene, &request).unwrap();
                    let mut scratch = field.scratch();
                    directions
                        .iter()
                        .zip(&single)
                        .map(|(view, s)| {
                            let mut radiance = vec![0.0; grid.len()];
                            field.compute_radiance(
                                view.to_vector(),
                                SunColumns::Exact,
                                &mut scratch,
                                &mut radiance,
                            );
                            for (r, s) in radiance.iter_mut().zip(s.radiance_w_m2_sr_nm.values()) {
                                *r += s;
                            }
                            crate::SkyRadiance {
                                radiance_w_m2_sr_nm: crate::spectrum::SampledSpectrum::from_values(
                                    radiance,
                                ),
                                standard_error_w_m2_sr_nm: None,
                                stokes: None,
                            }
                        })
                        .collect()
                })
                .collect();
            let tracer = match orders {
                Some(n) => PathTracer::new(&scene).with_max_interactions(n as u32),
                None => PathTracer::new(&scene),
            };
            let tracer = if std::env::var("SORA_SURVEY_PLAIN").is_ok_and(|v| v == "1") {
                tracer.without_twilight_sampling()
            } else {
                tracer
            };
            for (v, view) in directions.iter().enumerate() {
                let traced = tracer
                    .compute_radiance(view.to_vector(), samples, 1000 + n as u64)
                    .unwrap();
                for (i, (variant, total)) in (0..grid.len())
                    .flat_map(|i| variants.iter().zip(&totals).map(move |vt| (i, vt)))
                {
                    let t = total[v].radiance_w_m2_sr_nm.values()[i];
                    let s = single[v].radiance_w_m2_sr_nm.values()[i];
                    let part = |estimate: &crate::transport::path_tracing::SpectralEstimate,
                                fast: f64| {
                        let mean = estimate.mean.values()[i];
                        let error = estimate.standard_error.values()[i];
                        (fast / mean - 1.0, error / mean)
                    };
                    let (te, ts) = part(&traced.total, t);
                    let (se, ss) = part(&traced.single_scattering, s);
                    let (me, ms) = part(&traced.multiple_scattering, t - s);
                    let share =
                        traced.multiple_scattering.mean.values()[i] / traced.total.mean.values()[i];
                    println!(
                        "{preset},{sun},{},{},{},{variant},{:+.4},{:.4},{:+.4},{:.4},{:+.4},{:.4},{:.3}",
                        views[v].0,
                        views[v].1,
                        grid.wavelength_nm(i),
                        te,
                        ts,
                        se,
                        ss,
                        me,
                        ms,
                        share
                    );
                }
            }
        }
    }
}

/// The fast single scattering against the paper's uniform double march at
/// twice and four times `SORA_SURVEY_STEPS` (view steps; a quarter as many
/// toward the sun, default 4000), same presets, suns and views as
/// [`twilight_survey`]: `preset,sun,elevation,azimuth,nm,fast_vs_fine,coarse_vs_fine`
/// (fast / fine - 1, and the coarser march / fine - 1 as its own error).
#[test]
#[ignore]
fn twilight_single_scattering_survey() {
    let presets = list(
        "SORA_SURVEY_PRESETS",
        "earth-clear,earth-hazy,us-standard-1976-rayleigh",
    );
    let suns: Vec<f64> = list("SORA_SURVEY_SUNS", "-2,-4,-6")
        .iter()
        .map(|s| s.parse().unwrap())
        .collect();
    let steps: usize = std::env::var("SORA_SURVEY_STEPS")
        .map(|s| s.parse().unwrap())
        .unwrap_or(4000);
    let views: Vec<ViewDirection> =
        list("SORA_SURVEY_VIEWS", "90:0,5:0,5:90,5:180,20:0,20:90,20:180")
            .iter()
            .map(|v| {
                let (e, a) = v.split_once(':').unwrap();
                ViewDirection::new(e.parse().unwrap(), a.parse().unwrap()).unwrap()
            })
            .collect();
    let grid = WavelengthGrid::new(440.0, 680.0, 120.0).unwrap();
    println!("preset,sun,elevation,azimuth,nm,fast_vs_fine,coarse_vs_fine");
    for preset in &presets {
        let atmosphere = Atmosphere::preset(preset).unwrap();
        for &sun in &suns {
            let observation = Observation {
                observer_altitude_m: 0.0,
                sun_elevation_deg: sun,
                sun_azimuth_deg: 0.0,
            };
            let scene = SingleScatteringScene::new(&atmosphere, &grid, observation).unwrap();
            let radiances = |method| {
                Sky::from_scene(
                    scene.clone(),
                    Scattering::Single,
                    method,
                    FastTableSize::default(),
                )
                .unwrap()
                .radiances(&views)
                .unwrap()
            };
            let fast = radiances(Method::Fast);
            let march = |n: usize| Method::Reference {
                view_steps: n,
                sun_steps: n / 4,
            };
            let coarse = radiances(march(2 * steps));
            let fine = radiances(march(4 * steps));
            for (v, view) in views.iter().enumerate() {
                for i in 0..grid.len() {
                    let value = |r: &[crate::SkyRadiance]| r[v].radiance_w_m2_sr_nm.values()[i];
                    println!(
                        "{preset},{sun},{},{},{},{:+.5},{:+.5}",
                        view.elevation_deg(),
                        view.azimuth_deg(),
                        grid.wavelength_nm(i),
                        value(&fast) / value(&fine) - 1.0,
                        value(&coarse) / value(&fine) - 1.0,
                    );
                }
            }
        }
    }
}
