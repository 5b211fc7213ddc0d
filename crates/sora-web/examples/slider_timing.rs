//! What a sun-slider move costs the explorer's engine on one thread,
//! natively: the preview (128 pixels) and the refinement (256 pixels)
//! skies moved to each sun of the browser test's speed guard in its order
//! (45, 20, 10, 5, 2, -4; `SUNS` to change them, `REPS` to repeat each,
//! `QUALITIES=preview` for one quality, `POLARISATION=scalar` for scalar light), the wall time and the thread's CPU
//! time (on a shared machine the wall time also counts the waits for a
//! core; the browser's times were 1.4-1.7 times the native CPU time), and
//! a hash of the image's XYZ bits, to check that a change to the library
//! leaves the images the same.
//!
//! ```text
//! cargo run --release --manifest-path crates/sora-web/Cargo.toml --example slider_timing
//! ```
use std::time::Instant;

use sora::camera::Camera;
use sora::colour::SpectrumToXyz;
use sora::{Atmosphere, ImageSettings};
use sora_web::engine::build_sky;
use sora_web::request::{AtmosphereSpec, PolarisationChoice, Quality, ScatteringChoice, SkySpec};

fn main() {
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    let suns: Vec<f64> = std::env::var("SUNS")
        .unwrap_or("45,20,10,5,2,-4".into())
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    let reps: usize = std::env::var("REPS")
        .map(|r| r.parse().unwrap())
        .unwrap_or(1);
    let polarisation = std::env::var("POLARISATION").unwrap_or("vector".into());
    let qualities = std::env::var("QUALITIES").unwrap_or("preview,refined".into());
    for (quality, side) in [(Quality::Preview, 128), (Quality::Refined, 256)] {
        if !qualities.contains(&format!("{quality:?}").to_lowercase()) {
            continue;
        }
        let spec = |sun| SkySpec {
            atmosphere: AtmosphereSpec::default(),
            sun_elevation_deg: sun,
            sun_azimuth_deg: 180.0,
            observer_altitude_m: 0.0,
            scattering: ScatteringChoice::Multiple,
            polarisation: PolarisationChoice::try_from(polarisation.clone()).unwrap(),
        };
        let base = build_sky(&atmosphere, &spec(30.0), quality).unwrap();
        for &sun in &suns {
            for _ in 0..reps {
                let started = Instant::now();
                let cpu_started = cpu_seconds();
                let sky = base.with_sun_deg(sun, 180.0).unwrap();
                let built = started.elapsed().as_secs_f64();
                let to_xyz = SpectrumToXyz::new(sky.wavelengths(), Default::default());
                let image = ImageSettings::new(Camera::Fisheye, side, side);
                let xyz = sky.render_xyz(&image, &to_xyz, &|_| {}).unwrap();
                let total = started.elapsed().as_secs_f64();
                let cpu = cpu_seconds().zip(cpu_started).map(|(b, a)| b - a);
                let sum: f64 = xyz.iter().map(|c| c.y).sum();
                let hash = xyz.iter().fold(0u64, |h, c| {
                    [c.x, c.y, c.z]
                        .iter()
                        .fold(h, |h, v| (h ^ v.to_bits()).wrapping_mul(0x100000001b3))
                });
                println!(
                    "{quality:?} {side} sun {sun}: with_sun {built:.3} total {total:.3} cpu {}  (sumY {sum:.6e} hash {hash:016x})",
                    cpu.map_or("-".into(), |c| format!("{c:.3}"))
                );
            }
        }
    }
}

/// The seconds this thread has run on a CPU (Linux's schedstat; None
/// elsewhere): on a shared machine the wall time also counts the waits
/// for a core.
fn cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let nanoseconds: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(nanoseconds * 1e-9)
}
