//! The limits on work and memory of the CLI (issue 17; docs/limits.md):
//! each refused before any work, in one line naming the value, the limit
//! and what to do.

mod common;

use common::{one_line_error, sora};

/// `sora render` refuses image buffers beyond 4 GiB before loading the
/// atmosphere (which here does not even exist); the estimate line of a long
/// legal render is printed on a terminal only, so a piped stderr holds just
/// the error.
#[test]
fn render_memory_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    for (name, width, height, expected) in [
        (
            "big.png",
            "16384",
            "16384",
            "30 bytes a pixel for 8-bit PNG",
        ),
        ("big.exr", "9460", "9460", "48 bytes a pixel for OpenEXR"),
    ] {
        let output = dir.path().join(name);
        let out = sora(&[
            "render",
            "--atmosphere",
            "/nonexistent/air.toml",
            "--sun-elevation",
            "30",
            "--width",
            width,
            "--height",
            height,
            "-o",
            output.to_str().unwrap(),
        ]);
        let stderr = one_line_error(&out);
        assert!(
            stderr.contains(expected) && stderr.contains("more than the limit of 4294967296 bytes"),
            "{stderr}"
        );
        assert!(!output.exists());
    }
    // Just inside the OpenEXR bound (9459 x 9459 pixels): the next check
    // fails (the missing atmosphere), with no estimate on a piped stderr.
    let out = sora(&[
        "render",
        "--atmosphere",
        "/nonexistent/air.toml",
        "--sun-elevation",
        "30",
        "--width",
        "9459",
        "--height",
        "9459",
        "-o",
        dir.path().join("edge.exr").to_str().unwrap(),
    ]);
    let stderr = one_line_error(&out);
    assert!(stderr.contains("air.toml"), "{stderr}");
    assert!(!stderr.contains("estimate"), "{stderr}");
}

/// `sora spectrum` lists at most 100,000 directions and 1e7 directions x
/// wavelengths, refused before any radiance is computed (issue 17:
/// `--almucantar 5e-324` overflowed the count).
#[test]
fn direction_counts_are_bounded() {
    let spectrum = |extra: &[&str]| {
        sora(
            &[
                &[
                    "spectrum",
                    "--preset",
                    "clear-sky-reference",
                    "--sun-elevation",
                    "30",
                    "--scattering",
                    "single",
                ][..],
                extra,
            ]
            .concat(),
        )
    };
    for (extra, expected) in [
        (
            &["--almucantar", "5e-324", "--wavelengths", "550"][..],
            "--almucantar = 5e-324 deg gives inf directions, more than the limit of 100000",
        ),
        (
            &["--almucantar", "0.0035", "--wavelengths", "550"][..],
            "gives 1.02858e5 directions, more than the limit of 100000",
        ),
        (
            &["--principal-plane", "0.002", "--wavelengths", "360:830:1"][..],
            "90001 directions x 471 wavelengths = 4.2390471e7 values, more than the limit of 1e7",
        ),
    ] {
        let stderr = one_line_error(&spectrum(extra));
        assert!(stderr.contains(expected), "{extra:?}: {stderr}");
    }
    // Within both limits: 1801 directions at one wavelength.
    let out = spectrum(&["--principal-plane", "0.1", "--wavelengths", "550"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).lines().count(),
        1 + 1801
    );
}
