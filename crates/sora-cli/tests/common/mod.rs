//! What every CLI test needs: run the built `sora` binary and read what it
//! printed. Each test file uses a subset.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// Runs `sora` with `args` and collects its exit status and output.
pub fn sora(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sora"))
        .args(args)
        .output()
        .expect("the sora binary runs")
}

/// `sora spectrum` of the zenith under `atmosphere` (a file) with the sun
/// 60 degrees high on `wavelengths`, and `extra` arguments.
pub fn zenith_spectrum(atmosphere: &str, wavelengths: &str, extra: &[&str]) -> Output {
    let mut args = vec![
        "spectrum",
        "--atmosphere",
        atmosphere,
        "--sun-elevation",
        "60",
        "--view-elevation",
        "90",
        "--view-azimuth",
        "0",
        "--wavelengths",
        wavelengths,
    ];
    args.extend_from_slice(extra);
    sora(&args)
}

/// The standard output of a run that must have succeeded.
pub fn stdout(out: &Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout.clone()).unwrap()
}

/// The JSON a run that must have succeeded printed, parsed.
pub fn json(out: &Output) -> serde_json::Value {
    let text = stdout(out);
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("not JSON ({e}): {text}"))
}

/// The numbers of a JSON array.
pub fn numbers(value: &serde_json::Value) -> Vec<f64> {
    value
        .as_array()
        .unwrap_or_else(|| panic!("not an array: {value}"))
        .iter()
        .map(|v| v.as_f64().unwrap_or_else(|| panic!("not a number: {v}")))
        .collect()
}

/// The one-line error of a failed run (exit status 1).
pub fn one_line_error(out: &Output) -> String {
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    let stderr = String::from_utf8(out.stderr.clone()).unwrap();
    assert_eq!(stderr.lines().count(), 1, "not one line: {stderr}");
    stderr
}

/// Every sample of channel `name` of an OpenEXR file, as f32.
pub fn exr_channel(path: &Path, name: &str) -> Vec<f32> {
    let image = exr::prelude::read_first_flat_layer_from_file(path).unwrap();
    let channel = image
        .layer_data
        .channel_data
        .list
        .iter()
        .find(|c| c.name.to_string() == name)
        .unwrap_or_else(|| panic!("no channel {name}"));
    channel.sample_data.values_as_f32().collect()
}

/// The sun and the view of the paper's Table 1 (sun 36 deg up at azimuth
/// 207, view 17 deg up at azimuth 347), as `sora spectrum` options.
pub const TABLE1_GEOMETRY: [&str; 8] = [
    "--sun-elevation",
    "36",
    "--sun-azimuth",
    "207",
    "--view-elevation",
    "17",
    "--view-azimuth",
    "347",
];

/// The (wavelength, radiance) rows of a one-direction `sora spectrum` CSV.
pub fn spectrum_rows(csv: &str) -> Vec<(f64, f64)> {
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("wavelength_nm,radiance_w_m2_sr_nm"));
    lines
        .map(|line| {
            let (w, l) = line.split_once(',').unwrap();
            (w.parse().unwrap(), l.parse().unwrap())
        })
        .collect()
}

/// Path of a file in `tests/data/`.
pub fn data(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
        .display()
        .to_string()
}

/// Fails with a mutation campaign's `report` and its first five problems
/// unless there are none.
pub fn assert_no_problems(report: &str, problems: &[String]) {
    assert!(
        problems.is_empty(),
        "{report}\nfirst problems:\n{}",
        problems
            .iter()
            .take(5)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n----\n")
    );
}

/// The mutation campaigns' random numbers: splitmix64, seeded and
/// portable, so a seed names the same campaign on every machine (the
/// library's tests use the same generator).
#[path = "../../../sora/tests/common/mod.rs"]
mod rng;
#[allow(unused_imports)] // not every test file runs a campaign
pub use rng::Rng;
