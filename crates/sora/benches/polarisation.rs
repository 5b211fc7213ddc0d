//! Polarisation benchmarks (issue 13): a whole 512 x 512 all-sky fisheye
//! with multiple scattering at the 21 paper wavelengths, scalar beside
//! vector (every table, and for the vector sky the Mie phase matrices, the
//! polarised column and its ratio table, built in each iteration, as a
//! `sora render` run does), for a Rayleigh sky, the clear Earth and the
//! Martian dust, sun 30 degrees up. The bound is 3x the scalar time.
//! Then views against images (`direction_benchmarks`).

use criterion::{Criterion, criterion_group, criterion_main};
use sora::colour::{Observer, SpectrumToXyz};
use sora::{Atmosphere, Camera, ImageSettings, Polarisation, Sky, ViewDirection, WavelengthGrid};

fn polarisation_benchmarks(c: &mut Criterion) {
    let to_xyz = SpectrumToXyz::new(&WavelengthGrid::paper(), Observer::Cie1931TwoDegree);
    let image = ImageSettings::new(Camera::Fisheye, 512, 512);
    for preset in ["us-standard-1976-rayleigh", "earth-clear", "mars-dust"] {
        let atmosphere = Atmosphere::preset(preset).expect("preset");
        let mut group = c.benchmark_group(format!("fisheye_512_multiple_{preset}"));
        group.sample_size(10);
        for (name, polarisation) in [
            ("scalar", Polarisation::Scalar),
            ("vector", Polarisation::Vector),
        ] {
            group.bench_function(name, |b| {
                b.iter(|| {
                    Sky::builder(&atmosphere)
                        .sun_deg(30.0, 180.0)
                        .polarisation(polarisation)
                        .build()
                        .expect("sky")
                        .render_xyz(&image, &to_xyz, &|_| {})
                        .expect("render")
                })
            });
        }
        group.finish();
    }
}

/// Views against images (issue 38), earth-clear, sun 30, 21 wavelengths,
/// polarised, the sky built in each iteration: 16 384 directions (read
/// from tables as pixels are, `Sky::radiances`) beside a 128 x 128 fisheye
/// (bound 2x), and an almucantar of 72 directions (the exact path, one
/// polarisation row for all) beside one direction (bound 2x).
fn direction_benchmarks(c: &mut Criterion) {
    let to_xyz = SpectrumToXyz::new(&WavelengthGrid::paper(), Observer::Cie1931TwoDegree);
    let image = ImageSettings::new(Camera::Fisheye, 128, 128);
    let atmosphere = Atmosphere::preset("earth-clear").expect("preset");
    let sky = || {
        Sky::builder(&atmosphere)
            .sun_deg(30.0, 180.0)
            .polarisation(Polarisation::Vector)
            .build()
            .expect("sky")
    };
    let view = |elevation: f64, azimuth: f64| ViewDirection::new(elevation, azimuth).expect("view");
    let many: Vec<ViewDirection> = (0..16_384)
        .map(|k| {
            view(
                0.5 + 89.0 * (k as f64 + 0.5) / 16_384.0,
                (137.507_764 * k as f64) % 360.0,
            )
        })
        .collect();
    let almucantar: Vec<ViewDirection> = (0..72).map(|k| view(30.0, 5.0 * k as f64)).collect();
    let mut group = c.benchmark_group("directions_earth-clear_vector");
    group.sample_size(10);
    group.bench_function("fisheye_128", |b| {
        b.iter(|| sky().render_xyz(&image, &to_xyz, &|_| {}).expect("render"))
    });
    group.bench_function("directions_16384", |b| {
        b.iter(|| sky().radiances(&many).expect("radiances"))
    });
    group.bench_function("direction_1", |b| {
        b.iter(|| sky().radiance(view(30.0, 90.0)).expect("radiance"))
    });
    group.bench_function("almucantar_72", |b| {
        b.iter(|| sky().radiances(&almucantar).expect("radiances"))
    });
    group.finish();
}

criterion_group!(benches, polarisation_benchmarks, direction_benchmarks);
criterion_main!(benches);
