//! Multiple-scattering benchmarks (issue 6): the per-image precomputation
//! (the discrete-ordinate field at every sun zenith angle the view rays
//! meet, then its source table), and a whole 512 x 512 all-sky fisheye at
//! the 21 paper wavelengths with multiple scattering, next to the same
//! image with single scattering only. Sun at 30 degrees (the fewest sun
//! angles) and 5 degrees (the most: the sunset steps).

use criterion::{Criterion, criterion_group, criterion_main};
use sora::atmosphere::Atmosphere;
use sora::camera::Camera;
use sora::colour::{Observer, SpectrumToXyz};
use sora::spectrum::WavelengthGrid;
use sora::transport::multiple_scattering::{
    MultipleScatteringField, MultipleScatteringSettings, MultipleScatteringTable,
};
use sora::transport::{Observation, SingleScatteringSky};
use sora::{FastTableSize, ImageSettings, Method, Scattering, Sky};

fn sky(sun_elevation_deg: f64) -> SingleScatteringSky {
    let atmosphere = Atmosphere::preset("clear-sky-reference").expect("preset");
    let observation = Observation {
        observer_altitude_m: 0.0,
        sun_elevation_deg,
        sun_azimuth_deg: 180.0,
    };
    SingleScatteringSky::new(&atmosphere, &WavelengthGrid::paper(), observation).expect("sky")
}

fn multiple_scattering_benchmarks(c: &mut Criterion) {
    let settings = MultipleScatteringSettings::default();
    let to_xyz = SpectrumToXyz::new(&WavelengthGrid::paper(), Observer::Cie1931TwoDegree);
    for sun_elevation in [30.0, 5.0] {
        let sky = sky(sun_elevation);
        let mut group = c.benchmark_group(format!("multiple_scattering_sun_{sun_elevation}"));
        group.sample_size(10);
        group.bench_function("field", |b| {
            b.iter(|| MultipleScatteringField::compute(&sky, settings).expect("field"))
        });
        let field = MultipleScatteringField::compute(&sky, settings).expect("field");
        group.bench_function("source_table", |b| {
            b.iter(|| MultipleScatteringTable::compute(field.clone()))
        });
        let image = ImageSettings::new(Camera::Fisheye, 512, 512);
        for (name, scattering) in [
            ("fisheye_512_single", Scattering::Single),
            ("fisheye_512_multiple", Scattering::Multiple(settings)),
        ] {
            // Every image builds its field and tables: a new sky per iteration.
            group.bench_function(name, |b| {
                b.iter(|| {
                    Sky::from_scene(
                        sky.clone(),
                        scattering,
                        Method::Fast,
                        FastTableSize::default(),
                    )
                    .expect("sky")
                    .render_xyz(&image, &to_xyz, &|_| {})
                    .expect("render")
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, multiple_scattering_benchmarks);
criterion_main!(benches);
