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
//!
//! Twilight (issue 11): earth-clear, the run that reaches a 1% standard
//! error at 540 nm at the zenith with the sun 6 degrees below the horizon,
//! and at 5 degrees elevation away from the sun with the sun at -4, path
//! counts from pilot runs of 200 000 paths (twilight errors are heavy-
//! tailed: a pilot's estimate is good to some 10-20 %). Measured on this
//! 2-core machine, with the directions drawn toward the sunlit air from
//! shadowed vertices (`transport/sunlit_directions.rs`): 216 000 paths in
//! 2.85 s at the zenith (sun -6), 310 000 in 4.77 s at 5 degrees away from
//! the sun (sun -4); before them 553 000 in 2.45 s and 462 000 in 2.64 s
//! (fewer paths now, each about three times as long: the roulette spares
//! the first two interactions in shadow). From the spread of 100 runs
//! (the ignored `error_bars_are_calibrated_at_twilight`) the zenith needs
//! about 270 000 paths, 3.5 s (830 000 and 3.7 s before; 4 800 000
//! without the sunlit-part sampling). At sun -10 the gain is what the
//! sampler is for: 50 times fewer paths for the same error at the zenith
//! (`docs/twilight_survey.md`).

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

fn twilight_benchmarks(c: &mut Criterion) {
    let atmosphere = Atmosphere::preset("earth-clear").expect("preset");
    let mut group = c.benchmark_group("path_tracing_twilight");
    group.sample_size(10);
    for (name, sun, view) in [
        (
            "zenith_sun_minus_6_to_one_percent_at_540nm",
            -6.0,
            (90.0, 0.0),
        ),
        (
            "away_5deg_sun_minus_4_to_one_percent_at_540nm",
            -4.0,
            (5.0, 90.0),
        ),
    ] {
        let tracer = |samples: u64| {
            Sky::builder(&atmosphere)
                .sun_deg(sun, 270.0)
                .method(Method::PathTracing { samples, seed: 3 })
                .polarisation(sora::Polarisation::Scalar)
                .build()
                .expect("sky")
        };
        let view = ViewDirection::new(view.0, view.1).expect("view");
        let pilot_paths = 200_000;
        let pilot = tracer(pilot_paths).radiance(view).expect("pilot");
        let i = pilot_index_540(&tracer(2));
        let relative = pilot
            .standard_error_w_m2_sr_nm
            .as_ref()
            .expect("error")
            .values()[i]
            / pilot.radiance_w_m2_sr_nm.values()[i];
        let per_path = relative * (pilot_paths as f64).sqrt();
        let paths = ((per_path / 0.01).powi(2).ceil() as u64).max(2);
        eprintln!(
            "path tracing, {name}: per-path relative standard deviation {per_path:.2} at 540 nm; 1% standard error needs {paths} paths"
        );
        group.throughput(Throughput::Elements(paths));
        let run = tracer(paths);
        group.bench_function(name, |b| b.iter(|| run.radiance(view).expect("radiance")));
    }
    group.finish();
}

/// The index of 540 nm on a sky's grid.
fn pilot_index_540(sky: &Sky) -> usize {
    let grid = sky.wavelengths();
    (0..grid.len())
        .find(|&i| grid.wavelength_nm(i) == 540.0)
        .expect("540 nm on the paper's grid")
}

criterion_group!(benches, path_tracing_benchmarks, twilight_benchmarks);
criterion_main!(benches);
