//! Throughput of the single-sphere solver, single-threaded (issue 3 goals):
//! (a) 100 000 evaluations of Q_ext, Q_sca, g at m = 1.5 + 0.01i, x
//!     log-spaced over 0.1 ..= 100: goal >= 800 000 evaluations/s;
//! (b) 1 000 evaluations at x log-spaced over 100 ..= 10 000:
//!     goal >= 22 000 evaluations/s.
//! Criterion reports the element throughput, i.e. evaluations per second.
//! Also timed: the same sweeps through a reused `SphereWorkspace`, each
//! sweep in one call of `compute_efficiencies_many_with` (eight spheres
//! side by side, still one core), and a 181-angle S11/S12 table.
//!
//! Measured (2-core Xeon @ 2.8 GHz with AVX-512, shared; load average
//! 1.0-1.4): (a) 1.04 M/s one call per sphere, 2.6 M/s in one call;
//! (b) 29 500/s one call per sphere, 83 000/s in one call.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use sora_mie::Complex64;
use sora_mie::sphere::{
    MieSolution, SphereWorkspace, compute_efficiencies, compute_efficiencies_many,
    compute_efficiencies_many_with, compute_efficiencies_with,
};

fn log_spaced(count: usize, low: f64, high: f64) -> Vec<f64> {
    let ratio = (high / low).ln() / (count - 1) as f64;
    (0..count).map(|i| low * (ratio * i as f64).exp()).collect()
}

fn efficiency_sweeps(c: &mut Criterion) {
    let m = Complex64::new(1.5, 0.01);
    let sweeps = [
        (
            "a: 100000 spheres, x 0.1..100",
            log_spaced(100_000, 0.1, 100.0),
        ),
        (
            "b: 1000 spheres, x 100..10000",
            log_spaced(1_000, 100.0, 10_000.0),
        ),
    ];
    let mut group = c.benchmark_group("sphere efficiencies");
    group.sample_size(10);
    for (name, xs) in &sweeps {
        group.throughput(Throughput::Elements(xs.len() as u64));
        group.bench_function(*name, |bencher| {
            bencher.iter(|| {
                let mut total = 0.0;
                for &x in xs {
                    let q = compute_efficiencies(black_box(m), black_box(x)).unwrap();
                    total += q.qext + q.qsca + q.g;
                }
                total
            })
        });
        let mut workspace = SphereWorkspace::new();
        group.bench_function(format!("{name}, reused workspace"), |bencher| {
            bencher.iter(|| {
                let mut total = 0.0;
                for &x in xs {
                    let q = compute_efficiencies_with(&mut workspace, black_box(m), black_box(x))
                        .unwrap();
                    total += q.qext + q.qsca + q.g;
                }
                total
            })
        });
        // The whole sweep in one call: eight spheres side by side.
        let mut efficiencies = compute_efficiencies_many(m, xs).unwrap();
        group.bench_function(format!("{name}, all at once"), |bencher| {
            bencher.iter(|| {
                compute_efficiencies_many_with(
                    &mut workspace,
                    black_box(m),
                    black_box(xs),
                    &mut efficiencies,
                )
                .unwrap();
                efficiencies
                    .iter()
                    .map(|q| q.qext + q.qsca + q.g)
                    .sum::<f64>()
            })
        });
    }
    group.finish();
}

fn phase_table(c: &mut Criterion) {
    let mu: Vec<f64> = (0..=180).map(|d| (d as f64).to_radians().cos()).collect();
    let (mut s11, mut s12) = (vec![0.0; mu.len()], vec![0.0; mu.len()]);
    let mut group = c.benchmark_group("sphere phase table");
    for x in [10.0, 1000.0] {
        let solution = MieSolution::compute(Complex64::new(1.5, 0.01), x).unwrap();
        group.throughput(Throughput::Elements(mu.len() as u64));
        group.bench_function(format!("181 angles, x = {x}"), |bencher| {
            bencher.iter(|| solution.s11_s12_table(black_box(&mu), &mut s11, &mut s12))
        });
    }
    group.finish();
}

criterion_group!(benches, efficiency_sweeps, phase_table);
criterion_main!(benches);
