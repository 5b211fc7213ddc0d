//! `sora colour` end to end: the built binary on real spectra.

mod common;

use common::{data, sora};

/// The numbers after `label` on the line that starts with it.
fn numbers_on_line(stdout: &str, label: &str) -> Vec<f64> {
    let line = stdout
        .lines()
        .find(|l| l.starts_with(label))
        .unwrap_or_else(|| panic!("no {label} in {stdout}"));
    line[label.len()..]
        .split_whitespace()
        .map_while(|w| w.parse().ok())
        .collect()
}

#[test]
fn case_a_sky_spectrum_has_the_reference_xyz() {
    let out = sora(&["colour", &data("case_a_multi_albedo0.csv")]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    // sky_case_a_xyz_srgb.csv, row L_multi, albedo 0.
    let expected = [2.50182473, 2.55049991, 4.47045481];
    let xyz = numbers_on_line(&stdout, "XYZ");
    for (got, want) in xyz.iter().zip(expected) {
        assert!((got / want - 1.0).abs() < 1e-8, "{xyz:?}");
    }
    let rgb = numbers_on_line(&stdout, "linear RGB");
    for (got, want) in rgb.iter().zip([1.95781601, 2.54573362, 4.34432039]) {
        assert!((got / want - 1.0).abs() < 1e-8, "{rgb:?}");
    }
}

#[test]
fn swatches_are_written_and_bad_outputs_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("sky.png");
    let out = sora(&[
        "colour",
        &data("case_a_multi_albedo0.csv"),
        "--swatch",
        png.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(&std::fs::read(&png).unwrap()[..8], b"\x89PNG\r\n\x1a\n");

    let tiff = dir.path().join("sky.tiff");
    let out = sora(&[
        "colour",
        &data("case_a_multi_albedo0.csv"),
        "--swatch",
        tiff.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains(".tiff"));
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "only sky.png is there"
    );
}

#[test]
fn bad_spectra_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("wavelength_nm,v\n400,1\n500,NaN\n", "line 3"),
        ("wavelength_nm,v\n380,1\n780,-1\n", "(600 nm) is -0.1"),
        ("wavelength_nm,v\n400,1\n700,1\n", "covers 400-700 nm"),
        ("wavelength_nm\n400\n", "2 columns"),
    ];
    for (i, (text, expected)) in cases.iter().enumerate() {
        let path = dir.path().join(format!("bad{i}.csv"));
        std::fs::write(&path, text).unwrap();
        let out = sora(&["colour", path.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{text}: {stderr}");
        assert!(
            stderr.contains(expected) && stderr.trim().lines().count() == 1,
            "{text}: {stderr}"
        );
    }
    let out = sora(&["colour", "/nonexistent/spectrum.csv"]);
    assert_eq!(out.status.code(), Some(1));
    let out = sora(&[
        "colour",
        &data("case_a_multi_albedo0.csv"),
        "--wavelengths",
        "270:780:20",
    ]);
    // Out of range: status 1 and the library's one line, as every
    // out-of-range value (crates/sora-cli/src/main.rs).
    let error = common::one_line_error(&out);
    assert!(
        error.starts_with("error: --wavelengths: start_nm = 270 nm"),
        "{error}"
    );
}

#[test]
fn help_is_there() {
    for args in [&["--help"][..], &["colour", "--help"], &["mie", "--help"]] {
        let out = sora(args);
        assert!(out.status.success());
        assert!(String::from_utf8_lossy(&out.stdout).contains("Usage: sora"));
    }
}
