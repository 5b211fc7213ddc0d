//! How far the explorer's preview and refined images are from the
//! library's default resolution (what `sora render` computes), per sun
//! elevation: the luminance's median and 99th-percentile relative
//! difference over the sky's pixels (the sun's disc left out) and the
//! largest chromaticity difference, and the time each takes on one thread.
//! `SUNS` to change the suns; `POLARISATION=scalar` for scalar light (the
//! preview is scalar whatever the light, so against the polarised default
//! its error includes the polarisation's).
//!
//! ```text
//! cargo run --release --manifest-path crates/sora-web/Cargo.toml --example quality_accuracy
//! ```

use std::time::Instant;

use sora::camera::Camera;
use sora::colour::{SpectrumToXyz, Xyz};
use sora::{Atmosphere, ImageSettings};
use sora_web::engine::build_sky;
use sora_web::request::{AtmosphereSpec, PolarisationChoice, Quality, ScatteringChoice, SkySpec};

const SIDE: u32 = 128;

fn render(atmosphere: &Atmosphere, sun_elevation_deg: f64, quality: Quality) -> (Vec<Xyz>, f64) {
    let spec = SkySpec {
        atmosphere: AtmosphereSpec::default(),
        sun_elevation_deg,
        sun_azimuth_deg: 180.0,
        observer_altitude_m: 0.0,
        scattering: ScatteringChoice::Multiple,
        polarisation: std::env::var("POLARISATION")
            .map(|p| PolarisationChoice::try_from(p).expect("vector or scalar"))
            .unwrap_or_default(),
    };
    let started = Instant::now();
    let sky = build_sky(atmosphere, &spec, quality).expect("a valid sky");
    let to_xyz = SpectrumToXyz::new(sky.wavelengths(), Default::default());
    let image = ImageSettings {
        draw_sun_disc: false,
        ..ImageSettings::new(Camera::Fisheye, SIDE, SIDE)
    };
    let xyz = sky.render_xyz(&image, &to_xyz, &|_| {}).expect("an image");
    (xyz, started.elapsed().as_secs_f64())
}

fn main() {
    let preset = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "earth-clear".into());
    let atmosphere = Atmosphere::preset(&preset).expect("a preset");
    println!("{preset}, {SIDE}x{SIDE} fisheye, against the default resolution:");
    println!("sun_deg quality   median_dY  p99_dY   max_dxy  seconds(full {{}})");
    for sun in std::env::var("SUNS")
        .map(|s| {
            s.split(",")
                .map(|x| x.parse().unwrap())
                .collect::<Vec<f64>>()
        })
        .unwrap_or(vec![
            45.0, 20.0, 10.0, 5.0, 2.0, 0.0, -2.0, -4.0, -6.0, -9.0, -12.0,
        ])
    {
        let (full, full_seconds) = render(&atmosphere, sun, Quality::Full);
        for quality in [Quality::Refined, Quality::Preview] {
            let (image, seconds) = render(&atmosphere, sun, quality);
            let mut dy: Vec<f64> = Vec::new();
            let mut worst_xy: f64 = 0.0;
            for (a, f) in image.iter().zip(&full) {
                if f.y <= 0.0 {
                    continue;
                }
                dy.push((a.y - f.y).abs() / f.y);
                if let (Some(p), Some(q)) = (a.chromaticity_xy(), f.chromaticity_xy()) {
                    worst_xy = worst_xy.max((p[0] - q[0]).hypot(p[1] - q[1]));
                }
            }
            dy.sort_by(f64::total_cmp);
            let at = |q: f64| dy[((dy.len() - 1) as f64 * q) as usize];
            println!(
                "{sun:>6} {:<9} {:>9.2e} {:>8.2e} {:>8.1e}  {seconds:.3} (full {full_seconds:.3})",
                format!("{quality:?}"),
                at(0.5),
                at(0.99),
                worst_xy
            );
        }
    }
}
