//! Mutation fuzzing of `sora retrieve`'s inputs: sora's radiance CSV, its
//! optical-depth CSV, and AERONET almucantar, principal-plane and
//! optical-depth files (the repository's samples), mutated by a seeded
//! generator (one to three edits: delete, duplicate or swap lines, repeat
//! a line hundreds of times (one scan many times), replace a number by 0,
//! -1, -999, 1e308, NaN, inf, tiny or huge values, add or drop a cell,
//! truncate the text), then read by the library's readers, with the
//! optical depths attached and every scan validated, as `sora retrieve`
//! does before any fit. Every outcome must be an error of one non-empty
//! line or measurements whose every number is finite, and nothing may
//! panic.
//!
//! The fit itself is not run here (tens of seconds a scan): it takes only
//! measurements that passed these checks. A fixed-seed short campaign runs
//! with the tests; `cargo test --release -p sora --test
//! retrieve_input_mutations -- --ignored --nocapture` runs a long one
//! (`SORA_FUZZ_SEED`, `SORA_FUZZ_FILES`; 2,000 files by default) and
//! prints its counts.

mod common;

use std::panic::{AssertUnwindSafe, catch_unwind};

use sora::inversion::{
    AeronetScan, Measurements, attach_nearest_optical_depths, parse_aeronet_aod, parse_aeronet_sky,
    parse_optical_depth_csv, parse_sky_radiance_csv,
};

const PPL: &str = include_str!("data/aeronet/ppl_arm_graciosa_20190103.ppl");
const ALM: &str = include_str!("data/aeronet/alm_synthetic_karlsruhe_20050321.alm");
const AOD: &str = include_str!("data/aeronet/aod_karlsruhe_20050321.lev15");
const RADIANCES: &str = include_str!("../../../docs/retrieval_case4_radiances.csv");
const OPTICAL_DEPTHS: &str =
    "wavelength_nm,aerosol_optical_depth,uncertainty\n440,0.2,0.01\n870,0.1,0.01\n";

use common::Rng;

const NUMBERS: [&str; 16] = [
    "0", "-1", "-999", "1e308", "-1e308", "nan", "NaN", "inf", "-inf", "5e-324", "1e-300", "1e30",
    "90.5", "-0", "", "abc",
];

/// `text` with one edit.
fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    if lines.is_empty() {
        return String::new();
    }
    let i = rng.below(lines.len());
    match rng.below(8) {
        0 => {
            lines.remove(i);
        }
        1 => {
            let copy = lines[i].clone();
            lines.insert(i, copy);
        }
        2 => {
            let j = rng.below(lines.len());
            lines.swap(i, j);
        }
        3 => {
            // One row (a scan's line) repeated hundreds of times.
            let copy = lines[i].clone();
            for _ in 0..100 + rng.below(400) {
                lines.push(copy.clone());
            }
        }
        4 | 5 => {
            let mut cells: Vec<String> = lines[i].split(',').map(str::to_string).collect();
            let k = rng.below(cells.len());
            cells[k] = NUMBERS[rng.below(NUMBERS.len())].to_string();
            lines[i] = cells.join(",");
        }
        6 => {
            let mut cells: Vec<String> = lines[i].split(',').map(str::to_string).collect();
            if rng.below(2) == 0 {
                cells.push(NUMBERS[rng.below(NUMBERS.len())].to_string());
            } else if cells.len() > 1 {
                cells.pop();
            }
            lines[i] = cells.join(",");
        }
        _ => {
            let joined = lines.join("\n");
            let cut = rng.below(joined.len().max(1));
            let cut = (0..=cut)
                .rev()
                .find(|&c| joined.is_char_boundary(c))
                .unwrap_or(0);
            return joined[..cut].to_string();
        }
    }
    lines.join("\n") + "\n"
}

#[derive(Debug, Default)]
struct Counts {
    files: usize,
    errors: usize,
    ok: usize,
    problems: Vec<String>,
}

/// Every number of `measurements` is finite.
fn finite(measurements: &Measurements) -> bool {
    measurements.sky.iter().all(|s| {
        [
            s.wavelength_nm,
            s.sun_elevation_deg,
            s.sun_azimuth_deg,
            s.view_elevation_deg,
            s.view_azimuth_deg,
            s.radiance_w_m2_sr_nm,
            s.uncertainty_w_m2_sr_nm,
        ]
        .iter()
        .all(|v| v.is_finite())
    }) && measurements.optical_depths.iter().all(|d| {
        [d.wavelength_nm, d.aerosol_optical_depth, d.uncertainty]
            .iter()
            .all(|v| v.is_finite())
    })
}

/// Reads `text` (input kind `kind`) as `sora retrieve` does: the list of
/// scans, each validated, or the first error.
fn read(kind: usize, text: &str) -> sora::Result<Vec<Measurements>> {
    match kind {
        0 => {
            let mut measurements = parse_sky_radiance_csv(text, "radiances.csv")?;
            measurements.optical_depths = parse_optical_depth_csv(OPTICAL_DEPTHS, "depths.csv")?;
            Ok(vec![measurements])
        }
        1 => {
            let mut measurements = parse_sky_radiance_csv(RADIANCES, "radiances.csv")?;
            measurements.optical_depths = parse_optical_depth_csv(text, "depths.csv")?;
            Ok(vec![measurements])
        }
        2 | 3 => {
            let scan = if kind == 2 {
                AeronetScan::Almucantar
            } else {
                AeronetScan::PrincipalPlane
            };
            let mut sky = parse_aeronet_sky(text, scan, "sky.alm", 0.05)?;
            let depths = parse_aeronet_aod(AOD, "aod.lev15")?;
            attach_nearest_optical_depths(&mut sky.scans, &depths);
            Ok(sky.scans.into_iter().map(|s| s.measurements).collect())
        }
        _ => {
            let mut sky = parse_aeronet_sky(ALM, AeronetScan::Almucantar, "sky.alm", 0.05)?;
            let depths = parse_aeronet_aod(text, "aod.lev15")?;
            attach_nearest_optical_depths(&mut sky.scans, &depths);
            Ok(sky.scans.into_iter().map(|s| s.measurements).collect())
        }
    }
    .and_then(|scans: Vec<Measurements>| {
        for scan in &scans {
            scan.validate()?;
        }
        Ok(scans)
    })
}

fn campaign(seed: u64, files: usize) -> Counts {
    let mut rng = Rng(seed);
    let mut counts = Counts::default();
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    for _ in 0..files {
        let kind = rng.below(5);
        let mut text = [RADIANCES, OPTICAL_DEPTHS, ALM, PPL, AOD][kind].to_string();
        for _ in 0..1 + rng.below(3) {
            text = mutate(&text, &mut rng);
        }
        counts.files += 1;
        match catch_unwind(AssertUnwindSafe(|| read(kind, &text))) {
            Err(_) => counts
                .problems
                .push(format!("panic for input kind {kind}:\n{text}")),
            Ok(Err(error)) => {
                let message = error.to_string();
                if message.is_empty() || message.contains('\n') {
                    counts
                        .problems
                        .push(format!("not a one-line error: {message:?}"));
                } else {
                    counts.errors += 1;
                }
            }
            Ok(Ok(scans)) => {
                if scans.iter().all(finite) {
                    counts.ok += 1;
                } else {
                    counts
                        .problems
                        .push(format!("a non-finite measurement for:\n{text}"));
                }
            }
        }
    }
    std::panic::set_hook(hook);
    counts
}

fn report(counts: &Counts) -> String {
    format!(
        "files {}, one-line errors {}, ok {}, problems (panics, multi-line errors, NaN) {}",
        counts.files,
        counts.errors,
        counts.ok,
        counts.problems.len()
    )
}

fn assert_clean(counts: &Counts) {
    assert!(
        counts.problems.is_empty(),
        "{}\nfirst problems:\n{}",
        report(counts),
        counts
            .problems
            .iter()
            .take(3)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n----\n")
    );
}

#[test]
fn mutated_retrieve_inputs_are_read_or_refused_in_one_line() {
    let counts = campaign(39, 300);
    assert_clean(&counts);
    assert!(counts.errors > 0 && counts.ok > 0, "{}", report(&counts));
}

#[test]
#[ignore = "long campaign: run with --ignored --nocapture to print its counts"]
fn mutated_retrieve_inputs_long_campaign() {
    let env = |name: &str, default: u64| {
        std::env::var(name).map_or(default, |v| v.parse().expect("a number"))
    };
    let seed = env("SORA_FUZZ_SEED", 0x39_2026);
    let files = env("SORA_FUZZ_FILES", 2000) as usize;
    let counts = campaign(seed, files);
    println!("long campaign (seed {seed}): {}", report(&counts));
    assert_clean(&counts);
}
