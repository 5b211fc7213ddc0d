//! Polarisation benchmarks (issue 13): a whole 512 x 512 all-sky fisheye
//! with multiple scattering at the 21 paper wavelengths, scalar beside
//! vector (every table, and for the vector sky the Mie phase matrices, the
//! polarised column and its ratio table, built in each iteration, as a
//! `sora render` run does), for a Rayleigh sky, the clear Earth and the
//! Martian dust, sun 30 degrees up. The bound is 3x the scalar time.

use criterion::{Criterion, criterion_group, criterion_main};
use sora::colour::{Observer, SpectrumToXyz};
use sora::{Atmosphere, Camera, ImageSettings, Polarisation, Sky, WavelengthGrid};

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

criterion_group!(benches, polarisation_benchmarks);
criterion_main!(benches);
