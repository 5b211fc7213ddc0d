//! One rule for bad input (README, "Errors"): a value out of range exits
//! with status 1 and the library's one-line message, whichever parser saw
//! it first; azimuths are angles, read modulo 360 degrees.

mod common;

use common::{json, numbers, one_line_error, sora};

#[test]
fn bad_image_sizes_are_the_librarys_message_however_written() {
    let directory = tempfile::tempdir().unwrap();
    let output = directory.path().join("sky.png");
    let render = |size: &[&str]| {
        sora(
            &[
                &[
                    "render",
                    "--preset",
                    "earth-clear",
                    "--sun-elevation",
                    "30",
                    "-o",
                    output.to_str().unwrap(),
                ][..],
                size,
            ]
            .concat(),
        )
    };
    for (size, value) in [
        (&["--width", "-5"][..], "-5"),
        (&["--width=-5"][..], "-5"),
        (&["--width", "0"][..], "0"),
        (&["--width", "4294967808"][..], "4.294967808e9"),
    ] {
        let message = one_line_error(&render(size));
        assert_eq!(
            message.trim_end(),
            format!(
                "error: image width = {value} pixels is out of range: allowed 1..=16384 pixels"
            ),
            "{size:?}"
        );
    }
    let message = one_line_error(&render(&["--width", "8", "--height", "-3"]));
    assert!(message.contains("image height = -3 pixels"), "{message}");
    assert!(!output.exists());
}

#[test]
fn out_of_range_values_exit_1_whichever_parser_saw_them() {
    let spectrum = |extra: &[&str]| {
        sora(
            &[
                &[
                    "spectrum",
                    "--preset",
                    "earth-clear",
                    "--view-elevation",
                    "10",
                    "--view-azimuth",
                    "0",
                ][..],
                extra,
            ]
            .concat(),
        )
    };
    // Parsed by clap (the grid) and checked after parsing (the sun).
    let grid = one_line_error(&spectrum(&[
        "--sun-elevation",
        "30",
        "--wavelengths",
        "200:800:10",
    ]));
    assert!(
        grid.contains("--wavelengths: start_nm = 200 nm is out of range"),
        "{grid}"
    );
    let sun = one_line_error(&spectrum(&["--sun-elevation", "95"]));
    assert!(
        sun.contains("sun elevation = 95 deg is out of range"),
        "{sun}"
    );
    // Text that does not parse is clap's usage error, status 2.
    let out = spectrum(&["--sun-elevation", "high"]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
}

/// The radiance `sora spectrum` gives for the sun and the view at these
/// azimuths, and the sun's azimuth its JSON reports.
fn zenith_angle_spectrum(sun_azimuth: &str, view_azimuth: &str) -> (Vec<f64>, f64) {
    let out = json(&sora(&[
        "spectrum",
        "--preset",
        "earth-clear",
        "--sun-elevation",
        "30",
        "--sun-azimuth",
        sun_azimuth,
        "--view-elevation",
        "20",
        "--view-azimuth",
        view_azimuth,
        "--wavelengths",
        "450:650:100",
        "--format",
        "json",
    ]));
    (
        numbers(&out["radiance_w_m2_sr_nm"]),
        out["sun_azimuth_deg"].as_f64().unwrap(),
    )
}

#[test]
fn azimuths_are_read_modulo_360() {
    let (base, sun_azimuth) = zenith_angle_spectrum("320", "40");
    assert_eq!(sun_azimuth, 320.0);
    for (sun, view) in [("-400", "40"), ("320", "400"), ("680", "-320")] {
        let (turned, sun_azimuth) = zenith_angle_spectrum(sun, view);
        // Reported in one turn, as the sky used it.
        assert_eq!(sun_azimuth, 320.0, "{sun}");
        for (a, b) in turned.iter().zip(&base) {
            // The same direction up to the rounding of the sine and cosine.
            assert!((a / b - 1.0).abs() < 1e-9, "{sun} {view}: {a} vs {b}");
        }
    }
    // Not finite is not an angle.
    let out = sora(&[
        "spectrum",
        "--preset",
        "earth-clear",
        "--sun-elevation",
        "30",
        "--view-elevation",
        "20",
        "--view-azimuth",
        "inf",
    ]);
    assert!(one_line_error(&out).contains("azimuth"), "{out:?}");
}
