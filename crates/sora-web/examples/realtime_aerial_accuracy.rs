//! How far the real-time view's march (the engine tables of
//! [`REALTIME_TABLES`], `EngineTables::aerial_perspective_xyz`, which
//! `soraAerialPerspectiveMarch` follows step by step) is from the
//! library's aerial perspective on the sky the tables are baked from, at
//! the browser test's views (`web/tests/realtime.test.mjs`, `AERIAL`: the
//! scene camera's 6 x 4 cell centres above the horizon, suns 10 / 2 / -4,
//! 1 / 10 / 50 km): the largest relative error of the in-scattered
//! luminance per case and distance, and the bake's time on one thread.
//! `SUNSET_STEP` (degrees) bakes from a field with other sunset steps than
//! [`Quality::Realtime`]'s (the library's reference keeps them); `CASES`
//! ("sun,sun azimuth,look azimuth;..." in degrees) other cases; `SLICES`
//! ("count,nearest m,farthest m") adds the volume's distance axis alone
//! (linear in d, or `MODE=cubic`: `web/realtime.js`'s Catmull-Rom) against
//! the march; `BAKE_ONLY` stops after the bake (to time it).
//!
//! ```text
//! cargo run --release --manifest-path crates/sora-web/Cargo.toml --example realtime_aerial_accuracy
//! ```

use std::time::Instant;

use sora::colour::SpectrumToXyz;
use sora::engine_tables::EngineTables;
use sora::geometry::ViewDirection;
use sora::{Atmosphere, Scattering, Sky};
use sora_web::engine::{REALTIME_TABLES, quality_settings};
use sora_web::request::Quality;

/// The browser test's cases: sun elevation, sun azimuth, look azimuth.
const CASES: [(f64, f64, f64); 3] = [
    (10.0, 180.0, 180.0),
    (2.0, 240.0, 150.0),
    (-4.0, 180.0, 0.0),
];
const DISTANCES_M: [f64; 3] = [1000.0, 10000.0, 50000.0];
/// The scene camera (`web/realtime.js`, `SCENE`) and the test's grid.
const HALF_ANGLE_X_DEG: f64 = 40.0;
const PITCH_DEG: f64 = 12.0;
const ASPECT: f64 = 0.5;
const GRID: (usize, usize) = (6, 4);

/// `sceneView` of `web/realtime.js`: elevation and azimuth (degrees) of
/// the view through screen point (sx, sy).
fn scene_view(look_deg: f64, sx: f64, sy: f64) -> (f64, f64) {
    let (yaw, pitch) = (look_deg.to_radians(), PITCH_DEG.to_radians());
    let f = [
        yaw.sin() * pitch.cos(),
        yaw.cos() * pitch.cos(),
        pitch.sin(),
    ];
    let r = [yaw.cos(), -yaw.sin(), 0.0];
    let u = [
        r[1] * f[2] - r[2] * f[1],
        r[2] * f[0] - r[0] * f[2],
        r[0] * f[1] - r[1] * f[0],
    ];
    let tan_x = HALF_ANGLE_X_DEG.to_radians().tan();
    let tan_y = tan_x * ASPECT;
    let v: Vec<f64> = (0..3)
        .map(|i| f[i] + sx * tan_x * r[i] + sy * tan_y * u[i])
        .collect();
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let (x, y, z) = (v[0] / n, v[1] / n, v[2] / n);
    (
        z.asin().to_degrees(),
        (x.atan2(y).to_degrees() + 360.0) % 360.0,
    )
}

/// The unit vector (east-north-up) of an elevation and an azimuth
/// clockwise from north, degrees.
fn unit(elevation_deg: f64, azimuth_deg: f64) -> [f64; 3] {
    let (e, a) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    [a.sin() * e.cos(), a.cos() * e.cos(), e.sin()]
}

fn sky(atmosphere: &Atmosphere, sun_deg: f64, sun_azimuth_deg: f64, step: Option<f64>) -> Sky {
    let (grid, mut settings, tables) = quality_settings(Quality::Realtime);
    if let Some(step) = step {
        settings.sunset_sun_zenith_step_deg = step;
    }
    Sky::builder(atmosphere)
        .sun_deg(sun_deg, sun_azimuth_deg)
        .wavelengths(grid)
        .scattering(Scattering::Multiple(settings))
        .table_size(tables)
        .polarisation(sora::Polarisation::Scalar)
        .build()
        .expect("a sky")
}

fn main() {
    let preset = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "earth-clear".into());
    let atmosphere = Atmosphere::preset(&preset).expect("a preset");
    let step: Option<f64> = std::env::var("SUNSET_STEP")
        .ok()
        .map(|s| s.parse().expect("degrees"));
    let started = Instant::now();
    let baked = sky(&atmosphere, 45.0, 180.0, step);
    let tables = EngineTables::bake(&baked, &REALTIME_TABLES.settings, &|_| {}).expect("tables");
    println!(
        "{preset}, sunset step {:?}: bake {:.2} s, {:.2} MB",
        step,
        started.elapsed().as_secs_f64(),
        tables.size_bytes() as f64 / 1e6
    );
    if std::env::var("BAKE_ONLY").is_ok() {
        return;
    }
    let cases: Vec<(f64, f64, f64)> = std::env::var("CASES").map_or(CASES.to_vec(), |v| {
        v.split(';')
            .map(|c| {
                let n: Vec<f64> = c.split(',').map(|n| n.parse().expect("degrees")).collect();
                (n[0], n[1], n[2])
            })
            .collect()
    });
    for (sun_deg, sun_azimuth_deg, look_deg) in cases {
        let reference = sky(&atmosphere, sun_deg, sun_azimuth_deg, None);
        let to_xyz = SpectrumToXyz::new(reference.wavelengths(), Default::default());
        let sun = unit(sun_deg, sun_azimuth_deg);
        let mut views = Vec::new();
        for row in 0..GRID.1 {
            for column in 0..GRID.0 {
                let sx = (2.0 * (column as f64 + 0.5) - GRID.0 as f64) / GRID.0 as f64;
                let sy = (2.0 * (row as f64 + 0.5) - GRID.1 as f64) / GRID.1 as f64;
                let (e, a) = scene_view(look_deg, sx, sy);
                if e > 0.05 {
                    views.push(ViewDirection::new(e, a).unwrap());
                }
            }
        }
        let segments: Vec<(ViewDirection, f64)> = DISTANCES_M
            .iter()
            .flat_map(|d| views.iter().map(move |v| (*v, *d)))
            .collect();
        let library = reference.aerial_perspectives(&segments).expect("segments");
        let mut line = Vec::new();
        for (n, d) in DISTANCES_M.iter().enumerate() {
            let (mut worst, mut at) = (0.0f64, (0.0, 0.0));
            for (i, view) in views.iter().enumerate() {
                let air = &library[n * views.len() + i];
                let want = to_xyz.to_xyz(&air.radiance.radiance_w_m2_sr_nm).unwrap().y;
                let v = unit(view.elevation_deg(), view.azimuth_deg());
                let (got, _) = tables.aerial_perspective_xyz(0.0, v, sun, *d);
                let e = (got[1] / want - 1.0).abs();
                if e > worst {
                    (worst, at) = (e, (view.elevation_deg(), view.azimuth_deg()));
                }
            }
            line.push(format!(
                "{} km {:.2} % (at {:.1}, {:.0})",
                d / 1e3,
                100.0 * worst,
                at.0,
                at.1
            ));
        }
        if std::env::var("SLICES").is_ok() {
            slices(&reference, &tables, &views, sun);
        }
        println!(
            "sun {sun_deg} (azimuth {sun_azimuth_deg}), looking {look_deg}, {} views: {}",
            views.len(),
            line.join("; ")
        );
    }
}

/// The volume's distance axis alone (`web/realtime.js`: 16 slices
/// geometric from 250 m to 200 km, S = L / (1 - T) and tau linear in d
/// between them) at each view and distance: the march at the two slices
/// around d, interpolated, against the march at d and the library's.
fn slices(reference: &Sky, tables: &EngineTables, views: &[ViewDirection], sun: [f64; 3]) {
    let spec: Vec<f64> = std::env::var("SLICES")
        .unwrap()
        .split(',')
        .map(|n| n.parse().unwrap())
        .collect();
    let (n, near, far) = (spec[0] as usize, spec[1], spec[2]);
    let slice = |k: usize| near * (far / near).powf(k as f64 / (n - 1) as f64);
    let mut worst = [0.0f64; 3];
    let to_xyz = SpectrumToXyz::new(reference.wavelengths(), Default::default());
    for view in views {
        let v = unit(view.elevation_deg(), view.azimuth_deg());
        let march = |d: f64| tables.aerial_perspective_xyz(0.0, v, sun, d);
        for (j, d) in [1000.0, 10000.0, 50000.0].into_iter().enumerate() {
            let x = (d / near).ln() / (far / near).ln() * (n - 1) as f64;
            let k = (x.floor() as usize).min(n - 2);
            let (d0, d1) = (slice(k), slice(k + 1));
            let t = (d - d0) / (d1 - d0);
            let (l0, t0) = march(d0);
            let (l1, t1) = march(d1);
            let s = [l0[1] / (1.0 - t0[1]), l1[1] / (1.0 - t1[1])];
            let tau = [-t0[1].ln(), -t1[1].ln()];
            let tau_d = tau[0] + t * (tau[1] - tau[0]);
            let volume = (s[0] + t * (s[1] - s[0])) * (1.0 - (-tau_d).exp());
            // L itself linear in ln d, for comparison.
            let tl = (d / d0).ln() / (d1 / d0).ln();
            let log_linear = l0[1] + tl * (l1[1] - l0[1]);
            // Catmull-Rom in x through slices k - 1..k + 2 of S and tau / d.
            let node = |i: isize| {
                let i = i.clamp(0, n as isize - 1) as usize;
                let di = slice(i);
                let (l, t) = march(di);
                (l[1] / (1.0 - t[1]), -t[1].ln() / di)
            };
            let u = x - k as f64;
            let p: Vec<(f64, f64)> = (-1..=2).map(|i| node(k as isize + i)).collect();
            let cr = |a: f64, b: f64, c: f64, e: f64| {
                0.5 * (2.0 * b
                    + (c - a) * u
                    + (2.0 * a - 5.0 * b + 4.0 * c - e) * u * u
                    + (3.0 * b - a - 3.0 * c + e) * u * u * u)
            };
            let s_c = cr(p[0].0, p[1].0, p[2].0, p[3].0);
            let b_c = cr(p[0].1, p[1].1, p[2].1, p[3].1);
            let cubic = s_c * (1.0 - (-b_c * d).exp());
            let (m, _) = march(d);
            let mode = std::env::var("MODE").unwrap_or_default();
            let value = if mode == "cubic" { cubic } else { volume };
            worst[j] = worst[j].max((value / m[1] - 1.0).abs());
            if std::env::var("SLICES_QUIET").is_ok() {
                continue;
            }
            let lib = reference
                .aerial_perspectives(&[(*view, d0), (*view, d1), (*view, d)])
                .unwrap();
            let y = |i: usize| {
                to_xyz
                    .to_xyz(&lib[i].radiance.radiance_w_m2_sr_nm)
                    .unwrap()
                    .y
            };
            println!(
                "  view ({:.1}, {:.0}) d {:.0} km between {:.1} and {:.1}: volume/march {:+.2} %, L lin-in-ln-d/march {:+.2} %, march/library at d0 {:+.2} %, d1 {:+.2} %, d {:+.2} %",
                view.elevation_deg(),
                view.azimuth_deg(),
                d / 1e3,
                d0 / 1e3,
                d1 / 1e3,
                100.0 * (volume / m[1] - 1.0),
                100.0 * (log_linear / m[1] - 1.0),
                100.0 * (l0[1] / y(0) - 1.0),
                100.0 * (l1[1] / y(1) - 1.0),
                100.0 * (m[1] / y(2) - 1.0),
            );
        }
    }
    println!(
        "  slices {n} from {near} to {far} m: distance axis alone against the march at 1 / 10 / 50 km {:.2} / {:.2} / {:.2} %",
        100.0 * worst[0],
        100.0 * worst[1],
        100.0 * worst[2]
    );
}
