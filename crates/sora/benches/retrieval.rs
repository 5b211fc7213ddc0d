//! The aerosol retrieval's cost (issue 16: one almucantar of 4 wavelengths
//! x about 30 angles in at most 5 s on the 2-core machine, so that a day of
//! about 20 scans takes under 2 minutes): whole retrievals of three cases
//! of the synthetic validation set (`tests/data/retrieval/`), from reading
//! nothing (the measurements are parsed once) to the retrieved state with
//! its uncertainties, with the default settings (two starting points).
//! Each retrieval builds its own forward model and kernel cache, as one
//! scan of `sora retrieve` does.
//!
//! ```sh
//! cargo bench -p sora --bench retrieval
//! ```

use criterion::{Criterion, criterion_group, criterion_main};
use sora::Atmosphere;
use sora::inversion::{
    MIN_SCATTERING_ANGLE_DEG, Measurements, OpticalDepthMeasurement, RetrievalSettings,
    SkyRadianceMeasurement, retrieve,
};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/retrieval/");

fn rows(name: &str) -> Vec<Vec<f64>> {
    std::fs::read_to_string(format!("{DATA}{name}"))
        .expect("the synthetic set")
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().expect("number")).collect())
        .collect()
}

/// Case `case`'s radiances (3 degrees or more from the sun) and the
/// optical depths it was given.
fn measurements(case: usize) -> Measurements {
    let mut measurements = Measurements {
        label: format!("case {case}"),
        ..Measurements::default()
    };
    for r in rows("synthetic_almucantars.csv")
        .into_iter()
        .filter(|r| r[0] as usize == case)
    {
        let m = SkyRadianceMeasurement {
            wavelength_nm: r[1],
            sun_elevation_deg: r[2],
            sun_azimuth_deg: r[3],
            view_elevation_deg: r[4],
            view_azimuth_deg: r[5],
            radiance_w_m2_sr_nm: r[6],
            uncertainty_w_m2_sr_nm: r[7],
        };
        if m.scattering_angle_deg() >= MIN_SCATTERING_ANGLE_DEG {
            measurements.sky.push(m);
        }
    }
    let truth = rows("synthetic_truth.csv").remove(case);
    for (w, wavelength_nm) in [440.0, 675.0, 870.0, 1020.0].into_iter().enumerate() {
        measurements.optical_depths.push(OpticalDepthMeasurement {
            wavelength_nm,
            aerosol_optical_depth: truth[20 + w],
            uncertainty: 0.01,
        });
    }
    measurements
}

fn retrieval_benchmarks(c: &mut Criterion) {
    let mut atmosphere = Atmosphere::preset("earth-clear").expect("preset");
    atmosphere
        .species
        .retain(|s| s.name != "continental aerosol");
    let settings = RetrievalSettings::default();
    let mut group = c.benchmark_group("retrieval");
    group.sample_size(10);
    for case in [0, 1, 2] {
        let measurements = measurements(case);
        group.bench_function(format!("almucantar_case_{case}"), |b| {
            b.iter(|| retrieve(&atmosphere, &measurements, &settings).expect("retrieval"))
        });
    }
    group.finish();
}

criterion_group!(benches, retrieval_benchmarks);
criterion_main!(benches);
