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

/// The limits docs/limits.md says are checked before any work are: each
/// run here names an atmosphere file that does not exist, so a check made
/// after loading it would say that instead.
#[test]
fn the_documented_limits_are_checked_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let image = dir.path().join("sky.png");
    let image = image.to_str().unwrap();
    let missing = ["--atmosphere", "/nonexistent/air.toml"];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "render",
                "--sun-elevation",
                "30",
                "--width",
                "16385",
                "-o",
                image,
            ],
            "image width = 16385 pixels is out of range: allowed 1..=16384 pixels",
        ),
        (
            vec![
                "render",
                "--sun-elevation",
                "30",
                "--ev100",
                "1e308",
                "-o",
                image,
            ],
            "--ev100: EV100 = 1e308 is out of range",
        ),
        (
            vec![
                "render",
                "--sun-elevation",
                "-80",
                "--sun-elevation-to",
                "80",
                "--sun-elevation-step",
                "0.016",
                "-o",
                image,
            ],
            "10001 frames from -80 to 80 deg every 0.016 deg: at most 10000",
        ),
        (
            vec![
                "spectrum",
                "--sun-elevation",
                "30",
                "--almucantar",
                "0.01",
                "--wavelengths",
                "300:1100:1",
            ],
            "gives 36000 directions x 801 wavelengths = 2.8836e7 values, more than the limit of 1e7",
        ),
        // 10,000 frames are allowed (refused only for the missing file).
        (
            vec![
                "render",
                "--sun-elevation",
                "-80",
                "--sun-elevation-to",
                "80",
                "--sun-elevation-step",
                "0.016001",
                "--width",
                "8",
                "-o",
                image,
            ],
            "/nonexistent/air.toml",
        ),
    ];
    for (args, expected) in cases {
        let stderr = one_line_error(&sora(&[&args[..], &missing].concat()));
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
}

/// An endless input (`/dev/zero`) and a file past the size limit are
/// "file too large" errors, found one byte past the limit.
#[cfg(unix)]
#[test]
fn endless_and_huge_inputs_are_refused_before_reading_everything() {
    let stderr = one_line_error(&sora(&["mie", "--batch", "/dev/zero"]));
    assert!(stderr.contains("/dev/zero: file too large"), "{stderr}");
    // A sparse file of 300 MB (no disk used) as an atmosphere file.
    let dir = tempfile::tempdir().unwrap();
    let huge = dir.path().join("huge.toml");
    std::fs::File::create(&huge)
        .unwrap()
        .set_len(300_000_000)
        .unwrap();
    let stderr = one_line_error(&sora(&[
        "spectrum",
        "--atmosphere",
        huge.to_str().unwrap(),
        "--sun-elevation",
        "30",
        "--view-elevation",
        "20",
        "--view-azimuth",
        "0",
    ]));
    assert!(stderr.contains("huge.toml: file too large"), "{stderr}");
}

/// The atmosphere's height is bounded (1e3..=1e6 m), named by its key in
/// the file: a nanometre once ran 17 s to a NaN, 19,300 km past a minute.
#[test]
fn the_atmosphere_height_is_bounded_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    for (height, expected) in [
        (
            "1e-9",
            "planet.atmosphere_height_m = 1e-9 m is out of range: allowed 1e3..=1e6 m",
        ),
        (
            "1.93e7",
            "planet.atmosphere_height_m = 1.93e7 m is out of range: allowed 1e3..=1e6 m",
        ),
    ] {
        let file = dir.path().join("air.toml");
        std::fs::write(
            &file,
            format!(
                "name = \"x\"\n[planet]\nradius_m = 6360e3\natmosphere_height_m = {height}\n[sun]\nspectrum = \"flat\"\nirradiance_w_m2_nm = 1.0\n"
            ),
        )
        .unwrap();
        for command in [
            &["spectrum", "--view-elevation", "20", "--view-azimuth", "0"][..],
            &["render", "-o", dir.path().join("a.png").to_str().unwrap()][..],
        ] {
            let stderr = one_line_error(&sora(
                &[
                    command,
                    &[
                        "--atmosphere",
                        file.to_str().unwrap(),
                        "--sun-elevation",
                        "5",
                    ][..],
                ]
                .concat(),
            ));
            assert!(stderr.contains(expected), "{stderr}");
        }
    }
}

/// `sora retrieve` retrieves at most --max-scans scans of an AERONET file
/// (default 100), refused before any work: here three copies of one scan
/// against --max-scans 2.
#[test]
fn retrieve_is_bounded_in_scans_per_run() {
    let sample = std::fs::read_to_string(format!(
        "{}/../sora/tests/data/aeronet/alm_synthetic_karlsruhe_20050321.alm",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let mut lines = sample.lines();
    let mut text = format!("{}\n", lines.next().unwrap());
    let scan: Vec<&str> = lines.filter(|l| l.contains(",16:30:00,")).collect();
    for minute in ["30", "40", "50"] {
        for row in &scan {
            text += &row.replace(",16:30:00,", &format!(",16:{minute}:00,"));
            text += "\n";
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("three.alm");
    std::fs::write(&file, text).unwrap();
    let stderr = one_line_error(&sora(&[
        "retrieve",
        "--aeronet-almucantar",
        file.to_str().unwrap(),
        "--max-scans",
        "2",
    ]));
    assert!(
        stderr.contains("has 3 usable scans, more than --max-scans 2"),
        "{stderr}"
    );
}
