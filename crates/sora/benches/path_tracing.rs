//! Path-tracing benchmark (issue 6): one direction at the 21 paper
//! wavelengths, the paper's Table 1 geometry (sun 36 deg at azimuth 207,
//! view 17 deg at 347) in the clear-sky reference atmosphere on the
//! spherical Earth, with a ground of albedo 0.3 (the noisier of the
//! reference file's two cases).
//!
//! Measured: a fixed batch of paths (criterion's throughput is paths/s),
//! and the run that reaches a 1% standard error at every wavelength, its
//! path count found by a pilot run (printed before the measurements).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use sora::atmosphere::{Atmosphere, Planet};
use sora::geometry::direction_from_elevation_azimuth;
use sora::spectrum::{Spectrum, WavelengthGrid};
use sora::transport::{Observation, PathTracer, SingleScatteringSky};

const BATCH: u64 = 10_000;

fn path_tracing_benchmarks(c: &mut Criterion) {
    let mut atmosphere = Atmosphere::preset("clear-sky-reference").expect("preset");
    atmosphere.planet = Planet::new(
        atmosphere.planet.radius_m(),
        atmosphere.planet.atmosphere_height_m(),
        Spectrum::Constant(0.3),
    )
    .expect("planet");
    let observation = Observation {
        observer_altitude_m: 0.0,
        sun_elevation_deg: 36.0,
        sun_azimuth_deg: 207.0,
    };
    let sky =
        SingleScatteringSky::new(&atmosphere, &WavelengthGrid::paper(), observation).expect("sky");
    let tracer = PathTracer::new(&sky);
    let view = direction_from_elevation_azimuth(17.0, 347.0);

    // Pilot: the per-path relative standard deviation at the worst
    // wavelength gives the paths needed for a 1% standard error.
    let pilot_paths = 40_000;
    let pilot = tracer
        .compute_radiance(view, pilot_paths, 12345)
        .expect("pilot");
    let per_path = pilot.total.worst_relative_standard_error() * (pilot_paths as f64).sqrt();
    let paths_to_one_percent = ((per_path / 0.01).powi(2).ceil() as u64).max(2);
    eprintln!(
        "path tracing, case (a), albedo 0.3: per-path relative standard deviation {per_path:.3} at the worst wavelength; 1% standard error needs {paths_to_one_percent} paths"
    );

    let mut group = c.benchmark_group("path_tracing");
    group.sample_size(10);
    group.throughput(Throughput::Elements(BATCH));
    group.bench_function("case_a_10000_paths", |b| {
        b.iter(|| tracer.compute_radiance(view, BATCH, 1).expect("radiance"))
    });
    group.throughput(Throughput::Elements(paths_to_one_percent));
    group.bench_function("case_a_to_one_percent", |b| {
        b.iter(|| {
            tracer
                .compute_radiance(view, paths_to_one_percent, 1)
                .expect("radiance")
        })
    });
    group.finish();
}

criterion_group!(benches, path_tracing_benchmarks);
criterion_main!(benches);
