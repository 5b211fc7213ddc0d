//! Rendering benchmarks: the fast method's image tables (the sun-column and
//! sky-view tables, built together by `Sky::prepare_images`), and a whole
//! 256 x 256 and 1024 x 1024 all-sky fisheye at the 21 paper wavelengths,
//! tables included (issue 5). Single scattering; sun 30 degrees.

use criterion::{Criterion, criterion_group, criterion_main};
use sora::colour::{Observer, SpectrumToXyz};
use sora::{Atmosphere, Camera, ImageSettings, Scattering, Sky, WavelengthGrid};

fn sky(atmosphere: &Atmosphere) -> Sky {
    Sky::builder(atmosphere)
        .sun_deg(30.0, 180.0)
        .wavelengths(WavelengthGrid::paper())
        .scattering(Scattering::Single)
        .polarisation(sora::Polarisation::Scalar)
        .build()
        .expect("sky")
}

fn render_benchmarks(c: &mut Criterion) {
    for preset in ["clear-sky-reference", "earth-clear"] {
        let atmosphere = Atmosphere::preset(preset).expect("preset");
        let to_xyz = SpectrumToXyz::new(&WavelengthGrid::paper(), Observer::Cie1931TwoDegree);
        let mut group = c.benchmark_group(preset);
        group.sample_size(10);
        // A new sky per iteration: its tables are built once per sky.
        group.bench_function("image_tables", |b| {
            b.iter(|| sky(&atmosphere).prepare_images().expect("tables"))
        });
        let render = |width: u32| {
            sky(&atmosphere)
                .render_xyz(
                    &ImageSettings::new(Camera::Fisheye, width, width),
                    &to_xyz,
                    &|_| {},
                )
                .expect("render")
        };
        group.bench_function("fisheye_256_fast", |b| b.iter(|| render(256)));
        group.bench_function("fisheye_1024_fast", |b| b.iter(|| render(1024)));
        group.finish();
    }
}

criterion_group!(benches, render_benchmarks);
criterion_main!(benches);
