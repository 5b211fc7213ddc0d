//! Rendering benchmarks: the fast method's two tables, and a whole
//! 256 x 256 all-sky fisheye at the 21 paper wavelengths (issue 5).

use criterion::{Criterion, criterion_group, criterion_main};
use sora::atmosphere::Atmosphere;
use sora::camera::Camera;
use sora::colour::{Observer, SpectrumToXyz};
use sora::spectrum::WavelengthGrid;
use sora::transport::{Observation, SingleScatteringSky, SkyViewTable};
use sora::{FastTableSize, ImageSettings, Method, Scattering, Sky};

fn sky(preset: &str) -> SingleScatteringSky {
    let atmosphere = Atmosphere::preset(preset).expect("preset");
    let observation = Observation {
        observer_altitude_m: 0.0,
        sun_elevation_deg: 30.0,
        sun_azimuth_deg: 180.0,
    };
    SingleScatteringSky::new(&atmosphere, &WavelengthGrid::paper(), observation).expect("sky")
}

fn render_benchmarks(c: &mut Criterion) {
    let size = FastTableSize::default();
    for preset in ["clear-sky-reference", "earth-clear"] {
        let sky = sky(preset);
        let to_xyz = SpectrumToXyz::new(&WavelengthGrid::paper(), Observer::Cie1931TwoDegree);
        let mut group = c.benchmark_group(preset);
        group.sample_size(10);
        group.bench_function("sun_column_table", |b| {
            b.iter(|| {
                sky.compute_sun_column_table(size.sun_column_nodes.0, size.sun_column_nodes.1)
            })
        });
        let sun_columns =
            sky.compute_sun_column_table(size.sun_column_nodes.0, size.sun_column_nodes.1);
        group.bench_function("sky_view_table", |b| {
            b.iter(|| {
                SkyViewTable::compute(
                    &sky,
                    &sun_columns,
                    size.sky_view_nodes.0,
                    size.sky_view_nodes.1,
                )
            })
        });
        // Every image builds its tables: a new sky per iteration.
        let render = |width: u32| {
            Sky::from_scene(sky.clone(), Scattering::Single, Method::Fast, size)
                .expect("sky")
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
