//! The aerosol retrieval's cost (issue 16: one almucantar of 4 wavelengths
//! x about 30 angles in at most 5 s on the 2-core machine, so that a day of
//! about 20 scans takes under 2 minutes; issue 35: also at a 75-degree sun
//! zenith angle): whole retrievals of five cases of the synthetic
//! validation set (`tests/data/retrieval/`), from reading
//! nothing (the measurements are parsed once) to the retrieved state with
//! its uncertainties, with the default settings (two starting points).
//! Each retrieval builds its own forward model and kernel cache, as one
//! scan of `sora retrieve` does.
//!
//! ```sh
//! cargo bench -p sora --bench retrieval
//! ```

#[path = "../tests/synthetic_set/mod.rs"]
mod synthetic_set;

use criterion::{Criterion, criterion_group, criterion_main};
use sora::Atmosphere;
use sora::inversion::{RetrievalSettings, retrieve};

fn retrieval_benchmarks(c: &mut Criterion) {
    let mut atmosphere = Atmosphere::preset("earth-clear").expect("preset");
    atmosphere
        .species
        .retain(|s| s.name != "continental aerosol");
    let settings = RetrievalSettings::default();
    let mut group = c.benchmark_group("retrieval");
    group.sample_size(10);
    let cases = synthetic_set::cases();
    // Cases 0-2 (suns 28-31 degrees high), 41 (56.3 degrees from the
    // zenith) and 33 (74.4: where the field's rays meet a low sun).
    for (measurements, truth) in cases
        .iter()
        .filter(|(_, truth)| [0, 1, 2, 41, 33].contains(&truth.case))
    {
        group.bench_function(format!("almucantar_case_{}", truth.case), |b| {
            b.iter(|| retrieve(&atmosphere, measurements, &settings).expect("retrieval"))
        });
    }
    group.finish();
}

criterion_group!(benches, retrieval_benchmarks);
criterion_main!(benches);
