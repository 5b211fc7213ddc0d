//! Path-tracing benchmark (issue 6): one direction at the 21 paper
//! wavelengths, the paper's Table 1 geometry (sun 36 deg at azimuth 207,
//! view 17 deg at 347) in the clear-sky reference atmosphere on the
//! spherical Earth, with a ground of albedo 0.3 (the noisier of the
//! reference file's two cases).
//!
//! Measured: a fixed batch of paths (criterion's throughput is paths/s),
//! the same batch with polarisation (Stokes vectors),
//! and the run that reaches a 1% standard error at every wavelength, its
//! path count found by a pilot run (printed before the measurements).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use sora::atmosphere::Planet;
use sora::spectrum::Spectrum;
use sora::{Atmosphere, Method, Polarisation, Sky, ViewDirection, WavelengthGrid};

const BATCH: u64 = 10_000;

fn path_tracing_benchmarks(c: &mut Criterion) {
    let mut atmosphere = Atmosphere::preset("clear-sky-reference").expect("preset");
    atmosphere.planet = Planet::new(
        atmosphere.planet.radius_m(),
        atmosphere.planet.atmosphere_height_m(),
        Spectrum::Constant(0.3),
    )
    .expect("planet");
    let polarised_tracer = |samples: u64, polarisation: Polarisation| {
        Sky::builder(&atmosphere)
            .sun_deg(36.0, 207.0)
            .wavelengths(WavelengthGrid::paper())
            .method(Method::PathTracing { samples, seed: 1 })
            .polarisation(polarisation)
            .build()
            .expect("sky")
    };
    let tracer = |samples: u64| polarised_tracer(samples, Polarisation::Scalar);
    let view = ViewDirection::new(17.0, 347.0).expect("view");

    // Pilot: the per-path relative standard deviation at the worst
    // wavelength gives the paths needed for a 1% standard error.
    let pilot_paths = 40_000;
    let pilot = tracer(pilot_paths).radiance(view).expect("pilot");
    let per_path = pilot.worst_relative_standard_error() * (pilot_paths as f64).sqrt();
    let paths_to_one_percent = ((per_path / 0.01).powi(2).ceil() as u64).max(2);
    eprintln!(
        "path tracing, case (a), albedo 0.3: per-path relative standard deviation {per_path:.3} at the worst wavelength; 1% standard error needs {paths_to_one_percent} paths"
    );

    let mut group = c.benchmark_group("path_tracing");
    group.sample_size(10);
    group.throughput(Throughput::Elements(BATCH));
    let batch = tracer(BATCH);
    group.bench_function("case_a_10000_paths", |b| {
        b.iter(|| batch.radiance(view).expect("radiance"))
    });
    // The same paths carrying Stokes vectors (the aerosol's
    // Henyey-Greenstein phase function is non-polarising, the air's
    // Rayleigh matrix polarises).
    let polarised = polarised_tracer(BATCH, Polarisation::Vector);
    group.bench_function("case_a_10000_paths_polarised", |b| {
        b.iter(|| polarised.radiance(view).expect("radiance"))
    });
    group.throughput(Throughput::Elements(paths_to_one_percent));
    let to_one_percent = tracer(paths_to_one_percent);
    group.bench_function("case_a_to_one_percent", |b| {
        b.iter(|| to_one_percent.radiance(view).expect("radiance"))
    });
    group.finish();
}

criterion_group!(benches, path_tracing_benchmarks);
criterion_main!(benches);
