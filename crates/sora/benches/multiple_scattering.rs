//! Multiple-scattering benchmarks (issue 6): the discrete-ordinate field at
//! every sun zenith angle the view rays meet (timed as a new sky's first
//! view, whose exact synthesis costs little beside the field), all the
//! image tables (the field, its source table, the sun-column and sky-view
//! tables), and a whole 512 x 512 all-sky fisheye at the 21 paper
//! wavelengths with multiple scattering, next to the same image with single
//! scattering only. Sun at 30 degrees (the fewest sun angles) and 5 degrees
//! (the most: the sunset steps). And issue 11's twilight image: earth-clear,
//! sun 6 degrees below the horizon, a 512 x 512 fisheye with every order
//! (scalar light, as the bar of 2 s was set before polarisation;
//! the polarised image is `--bench polarisation`'s business), every table
//! built in each iteration as a `sora render` run does.

use criterion::{Criterion, criterion_group, criterion_main};
use sora::colour::{Observer, SpectrumToXyz};
use sora::{Atmosphere, Camera, ImageSettings, Scattering, Sky, ViewDirection, WavelengthGrid};

fn multiple_scattering_benchmarks(c: &mut Criterion) {
    let atmosphere = Atmosphere::preset("clear-sky-reference").expect("preset");
    let to_xyz = SpectrumToXyz::new(&WavelengthGrid::paper(), Observer::Cie1931TwoDegree);
    let view = ViewDirection::new(45.0, 0.0).expect("view");
    for sun_elevation in [30.0, 5.0] {
        // A new sky per iteration: its field and tables are built once per sky.
        let sky = |scattering: Scattering| {
            Sky::builder(&atmosphere)
                .sun_deg(sun_elevation, 180.0)
                .wavelengths(WavelengthGrid::paper())
                .scattering(scattering)
                .polarisation(sora::Polarisation::Scalar)
                .build()
                .expect("sky")
        };
        let mut group = c.benchmark_group(format!("multiple_scattering_sun_{sun_elevation}"));
        group.sample_size(10);
        group.bench_function("field_and_one_view", |b| {
            b.iter(|| sky(Scattering::multiple()).radiance(view).expect("view"))
        });
        group.bench_function("image_tables", |b| {
            b.iter(|| {
                sky(Scattering::multiple())
                    .prepare_images()
                    .expect("tables")
            })
        });
        let image = ImageSettings::new(Camera::Fisheye, 512, 512);
        for (name, scattering) in [
            ("fisheye_512_single", Scattering::Single),
            ("fisheye_512_multiple", Scattering::multiple()),
        ] {
            group.bench_function(name, |b| {
                b.iter(|| {
                    sky(scattering)
                        .render_xyz(&image, &to_xyz, &|_| {})
                        .expect("render")
                })
            });
        }
        group.finish();
    }
}

fn twilight_benchmarks(c: &mut Criterion) {
    let atmosphere = Atmosphere::preset("earth-clear").expect("preset");
    let to_xyz = SpectrumToXyz::new(&WavelengthGrid::paper(), Observer::Cie1931TwoDegree);
    let image = ImageSettings::new(Camera::Fisheye, 512, 512);
    let mut group = c.benchmark_group("twilight_sun_-6");
    group.sample_size(10);
    group.bench_function("fisheye_512_multiple", |b| {
        b.iter(|| {
            Sky::builder(&atmosphere)
                .sun_deg(-6.0, 270.0)
                .scattering(Scattering::multiple())
                .polarisation(sora::Polarisation::Scalar)
                .build()
                .expect("sky")
                .render_xyz(&image, &to_xyz, &|_| {})
                .expect("render")
        })
    });
    group.finish();
}

criterion_group!(benches, multiple_scattering_benchmarks, twilight_benchmarks);
criterion_main!(benches);
