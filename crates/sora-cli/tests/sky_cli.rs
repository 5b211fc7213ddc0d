//! `sora spectrum` and `sora render` end to end.

mod common;

use common::{sora, spectrum_rows, stdout};

/// Case (a) of ../shared/reference/sky/clear_sky_radiance.csv (sun 36 deg
/// at azimuth 207, view 17 deg at 347): L_single_spherical at 380, 400, 780 nm.
const CASE_A_SPHERICAL: [(f64, f64); 3] = [
    (380.0, 2.319739874e-02),
    (400.0, 2.364897365e-02),
    (780.0, 6.343935200e-03),
];

/// `sora spectrum` for case (a), to which extra arguments are added.
fn case_a_spectrum() -> Vec<&'static str> {
    [
        &["spectrum", "--preset", "clear-sky-reference"][..],
        &common::TABLE1_GEOMETRY,
    ]
    .concat()
}

#[test]
fn spectrum_csv_is_the_reference_single_scattering() {
    let out = sora(&[&case_a_spectrum()[..], &["--scattering", "single"]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows = spectrum_rows(&String::from_utf8(out.stdout).unwrap());
    assert_eq!(rows.len(), 21);
    for (wavelength, expected) in CASE_A_SPHERICAL {
        let (_, got) = rows.iter().find(|(w, _)| *w == wavelength).unwrap();
        assert!(
            (got / expected - 1.0).abs() < 1e-6,
            "{wavelength} nm: {got} vs {expected}"
        );
    }
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("XYZ"),
        "the colour goes to stderr"
    );

    let json = sora(&[
        "spectrum",
        "--preset",
        "clear-sky-reference",
        "--sun-elevation",
        "36",
        "--view-elevation",
        "17",
        "--view-azimuth",
        "347",
        "--format",
        "json",
        "--method",
        "reference",
        "--wavelengths",
        "550",
    ]);
    let json = common::json(&json);
    assert_eq!(common::numbers(&json["wavelength_nm"]), [550.0]);
    assert_eq!(common::numbers(&json["radiance_w_m2_sr_nm"]).len(), 1);
    assert_eq!(common::numbers(&json["xyz_w_m2_sr"]).len(), 3);
    assert_eq!(common::numbers(&json["linear_srgb_w_m2_sr"]).len(), 3);
}

/// The default is all orders of scattering (`--scattering multiple`): at
/// case (a) it agrees with the path tracer (within 1% and 4 standard
/// errors; measured 0.04% at 400 and 700 nm) and is well above single
/// scattering. (It is 1-2% below case (a)'s plane-parallel DISORT column: the
/// spherical planet's own effect, as the path tracer shows.)
#[test]
fn spectrum_defaults_to_multiple_scattering() {
    let wavelengths = ["--wavelengths", "400:700:100"];
    let default = stdout(&sora(&[&case_a_spectrum()[..], &wavelengths].concat()));
    let multiple = stdout(&sora(
        &[
            &case_a_spectrum()[..],
            &wavelengths,
            &["--scattering", "multiple"],
        ]
        .concat(),
    ));
    assert_eq!(default, multiple);
    let single = spectrum_rows(&stdout(&sora(
        &[
            &case_a_spectrum()[..],
            &wavelengths,
            &["--scattering", "single"],
        ]
        .concat(),
    )));
    let traced = stdout(&sora(
        &[
            &case_a_spectrum()[..],
            &wavelengths,
            &["--method", "path-tracing", "--samples", "40000"],
        ]
        .concat(),
    ));
    let traced: Vec<Vec<f64>> = traced
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|f| f.parse().unwrap()).collect())
        .collect();
    let rows = spectrum_rows(&default);
    assert_eq!(rows.len(), 4);
    for (((wavelength, got), (_, once)), traced) in rows.iter().zip(&single).zip(&traced) {
        let (expected, error) = (traced[1], traced[2]);
        assert!(
            (got - expected).abs() < (0.01 * expected).min(4.0 * error),
            "{wavelength} nm: {got} vs path tracing {expected} +- {error}"
        );
        assert!(
            got > &(1.2 * once),
            "{wavelength} nm: {got} vs single {once}"
        );
    }

    let out = sora(
        &[
            &case_a_spectrum()[..],
            &["--method", "path-tracing", "--scattering", "single"],
        ]
        .concat(),
    );
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--scattering"));
}

#[test]
fn bad_spectrum_arguments_are_one_line_errors() {
    let cases: [(&[&str], &str); 4] = [
        (
            &[
                "--preset",
                "nowhere",
                "--sun-elevation",
                "30",
                "--view-elevation",
                "10",
                "--view-azimuth",
                "0",
            ],
            "nowhere",
        ),
        (
            &[
                "--preset",
                "clear-sky-reference",
                "--sun-elevation",
                "95",
                "--view-elevation",
                "10",
                "--view-azimuth",
                "0",
            ],
            "sun elevation = 95 deg",
        ),
        (
            &[
                "--preset",
                "clear-sky-reference",
                "--sun-elevation",
                "30",
                "--view-elevation",
                "-100",
                "--view-azimuth",
                "0",
            ],
            "--view-elevation = -100 deg",
        ),
        (
            &[
                "--preset",
                "clear-sky-reference",
                "--sun-elevation",
                "30",
                "--view-elevation",
                "10",
                "--view-azimuth",
                "0",
                "--ground-albedo",
                "1.5",
            ],
            "1.5",
        ),
    ];
    for (args, expected) in cases {
        let out = sora(&[&["spectrum"], args].concat());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(
            stderr.contains(expected) && stderr.trim().lines().count() == 1,
            "{args:?}: {stderr}"
        );
    }
}

#[test]
fn render_writes_png_and_exr_and_nothing_on_failure() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("sky.png");
    let scene = [
        "render",
        "--preset",
        "clear-sky-reference",
        "--sun-elevation",
        "30",
    ];
    let base = [&scene[..], &["--width", "32"]].concat();
    let out = sora(&[&base[..], &["-o", png.to_str().unwrap()]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(&std::fs::read(&png).unwrap()[..8], b"\x89PNG\r\n\x1a\n");
    assert!(String::from_utf8_lossy(&out.stderr).contains("rendered 32x32"));

    let exr = dir.path().join("sky.exr");
    let out = sora(
        &[
            &base[..],
            &[
                "--camera",
                "equirect",
                "--exr-half",
                "-o",
                exr.to_str().unwrap(),
            ],
        ]
        .concat(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        &std::fs::read(&exr).unwrap()[..4],
        &[0x76, 0x2f, 0x31, 0x01],
        "OpenEXR magic number"
    );

    let reference = dir.path().join("reference.png");
    let out = sora(
        &[
            &scene[..],
            &[
                "--width",
                "8",
                "--method",
                "reference",
                "-o",
                reference.to_str().unwrap(),
            ],
        ]
        .concat(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let before: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    for (extra, expected) in [
        (vec!["-o", "sky.tiff"], ".tiff"),
        (
            vec!["--observer-altitude-m", "-5", "-o", "bad.png"],
            "observer altitude = -5 m",
        ),
        (vec!["--height", "0", "-o", "zero.png"], "image height = 0"),
        (
            vec![
                "--camera",
                "perspective",
                "--fov-deg",
                "200",
                "-o",
                "wide.png",
            ],
            "field of view = 200 deg",
        ),
        (vec!["-o", "missing/sky.png"], "does not exist"),
    ] {
        let extra: Vec<String> = extra
            .iter()
            .map(|a| {
                if a.ends_with(".png") || a.ends_with(".tiff") {
                    dir.path().join(a).display().to_string()
                } else {
                    a.to_string()
                }
            })
            .collect();
        let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
        let out = sora(&[&base[..], &extra[..]].concat());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{extra:?}: {stderr}");
        assert!(stderr.contains(expected), "{extra:?}: {stderr}");
    }
    let after: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(before, after, "failed renders leave no file behind");
}

/// `--method path-tracing`: a third column with the standard error, the
/// same output for the same seed, and a clear error for a bad sample count.
#[test]
fn path_tracing_spectrum_has_standard_errors_and_is_deterministic() {
    let args = [
        &case_a_spectrum()[..],
        &[
            "--wavelengths",
            "400:700:100",
            "--method",
            "path-tracing",
            "--samples",
            "4000",
            "--seed",
            "7",
        ],
    ]
    .concat();
    let first = stdout(&sora(&args));
    assert_eq!(first, stdout(&sora(&args)), "same seed, same output");
    let mut lines = first.lines();
    assert_eq!(
        lines.next(),
        Some("wavelength_nm,radiance_w_m2_sr_nm,standard_error_w_m2_sr_nm")
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|f| f.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 4);
    for row in &rows {
        // Multiple scattering adds to single scattering: above the
        // single-scattering value of the reference file at 400 nm and below
        // twice DISORT's, with a small positive error bar.
        assert!(
            row[1].is_finite() && row[2] > 0.0 && row[2] < 0.1 * row[1],
            "{row:?}"
        );
    }
    assert!(
        rows[0][1] > 2.36e-2 && rows[0][1] < 2.0 * 5.48e-2,
        "{:?}",
        rows[0]
    );

    let out = sora(&[&args[..args.len() - 4], &["--samples", "1"]].concat());
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--samples"));
}

/// `sora spectrum` at earth-clear, sun 30 degrees in the south, with these
/// direction options.
fn earth_clear_spectrum(directions: &[&str]) -> std::process::Output {
    let base = [
        "spectrum",
        "--preset",
        "earth-clear",
        "--sun-elevation",
        "30",
        "--sun-azimuth",
        "180",
    ];
    sora(&[&base[..], directions].concat())
}

/// Many directions in one run give, for every direction, the very numbers
/// of a one-direction run (the issue asks 1e-12 relative; the same code
/// makes them equal to the last printed digit), in the long CSV layout.
#[test]
fn almucantar_rows_equal_one_direction_runs() {
    let long = stdout(&earth_clear_spectrum(&["--almucantar", "5"]));
    let mut lines = long.lines();
    assert_eq!(
        lines.next(),
        Some("view_elevation_deg,view_azimuth_deg,wavelength_nm,radiance_w_m2_sr_nm")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 72 * 21);
    let azimuths: Vec<f64> = rows
        .iter()
        .step_by(21)
        .map(|r| r[1].parse().unwrap())
        .collect();
    assert_eq!(azimuths[0], 180.0);
    assert_eq!(azimuths[1], 185.0);
    assert_eq!(azimuths[71], 175.0);
    assert!(rows.iter().all(|r| r[0] == "30"));
    for azimuth in ["180", "0", "95"] {
        let one = stdout(&earth_clear_spectrum(&[
            "--view-elevation",
            "30",
            "--view-azimuth",
            azimuth,
        ]));
        let expected: Vec<&str> = one.lines().skip(1).collect();
        let found: Vec<String> = rows
            .iter()
            .filter(|r| r[1] == azimuth)
            .map(|r| format!("{},{}", r[2], r[3]))
            .collect();
        assert_eq!(found, expected, "azimuth {azimuth}");
    }
}

#[test]
fn principal_plane_and_directions_files() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("views.csv");
    std::fs::write(&file, "view_elevation_deg,view_azimuth_deg\n90,0\n10,180\n").unwrap();
    let listed = common::json(&earth_clear_spectrum(&[
        "--directions",
        file.to_str().unwrap(),
        "--format",
        "json",
    ]));
    let listed = listed["directions"].as_array().unwrap();
    assert_eq!(listed.len(), 2);
    assert_eq!(listed[0]["view_elevation_deg"], 90.0);
    assert_eq!(listed[0]["view_azimuth_deg"], 0.0);
    assert!(listed.iter().all(|d| d["radiance_w_m2_sr_nm"].is_array()));
    assert!(listed.iter().all(|d| d["xyz_w_m2_sr"].is_array()));
    // Horizon under the sun, over the zenith, to the opposite horizon.
    let plane = stdout(&earth_clear_spectrum(&["--principal-plane", "10"]));
    let directions: Vec<String> = plane
        .lines()
        .skip(1)
        .step_by(21)
        .map(|l| l.split(',').take(2).collect::<Vec<_>>().join(","))
        .collect();
    assert_eq!(directions.len(), 19);
    assert_eq!(directions[0], "0,180");
    assert_eq!(directions[9], "90,180");
    assert_eq!(directions[10], "80,0");
    assert_eq!(directions[18], "0,0");
    // The zenith of both runs is the same number.
    let zenith = |csv: &str, prefix: &str| {
        csv.lines()
            .find(|l| l.starts_with(prefix))
            .map(|l| l.rsplit(',').next().unwrap().parse::<f64>().unwrap())
            .unwrap()
    };
    let listed_csv = stdout(&earth_clear_spectrum(&[
        "--directions",
        file.to_str().unwrap(),
    ]));
    let (a, b) = (
        zenith(&listed_csv, "90,0,540,"),
        zenith(&plane, "90,180,540,"),
    );
    assert!((a / b - 1.0).abs() < 1e-8, "{a} vs {b}");
}

#[test]
fn bad_directions_are_one_line_errors_and_print_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let header = "view_elevation_deg,view_azimuth_deg\n";
    for (content, expected) in [
        (String::new(), "empty"),
        (header.to_string(), "header but no rows"),
        (format!("{header}10,0\n20\n"), "line 3: 1 fields"),
        (
            format!("{header}NaN,0\n"),
            "line 2: view_elevation_deg = 'NaN' is not a finite number",
        ),
        (
            format!("{header}10,0\n120,45\n"),
            "line 3: view elevation = 120 deg",
        ),
        ("elevation,azimuth\n1,2\n".to_string(), "line 1: the header"),
    ] {
        let file = dir.path().join("views.csv");
        std::fs::write(&file, &content).unwrap();
        let out = earth_clear_spectrum(&["--directions", file.to_str().unwrap()]);
        let error = common::one_line_error(&out);
        assert!(
            error.contains(expected) && error.contains("views.csv"),
            "{content:?}: {error}"
        );
        assert!(out.stdout.is_empty(), "{content:?}");
    }
    for (option, value, expected) in [
        ("--almucantar", "0", "--almucantar = 0 deg"),
        ("--principal-plane", "-5", "--principal-plane = -5 deg"),
        ("--almucantar", "NaN", "--almucantar = NaN deg"),
    ] {
        let out = earth_clear_spectrum(&[option, value]);
        let error = common::one_line_error(&out);
        assert!(error.contains(expected), "{error}");
        assert!(out.stdout.is_empty());
    }
    // One way of naming directions at a time.
    let out = earth_clear_spectrum(&["--almucantar", "5", "--principal-plane", "5"]);
    assert_eq!(out.status.code(), Some(2));
}

/// --streams and --layers set the field's resolution: the defaults given
/// explicitly change nothing, 12 streams and 60 layers move the radiance
/// (by well under the method's own error), and where there is no field
/// they are one-line errors, as is a count out of range.
#[test]
fn streams_and_layers_set_the_fields_resolution() {
    let view = [
        "--view-elevation",
        "30",
        "--view-azimuth",
        "90",
        "--polarisation",
        "scalar",
        "--wavelengths",
        "440:680:120",
    ];
    let run = |extra: &[&str]| earth_clear_spectrum(&[&view[..], extra].concat());
    let default = stdout(&run(&[]));
    assert_eq!(default, stdout(&run(&["--streams", "8", "--layers", "40"])));
    let finer = stdout(&run(&["--streams", "12", "--layers", "60"]));
    assert_ne!(default, finer);
    for ((w, a), (v, b)) in spectrum_rows(&default)
        .into_iter()
        .zip(spectrum_rows(&finer))
    {
        assert_eq!(w, v);
        assert!((b / a - 1.0).abs() < 0.01, "{w} nm: {a:e} against {b:e}");
    }
    for (extra, expected) in [
        (&["--streams", "40"][..], "streams per hemisphere = 40"),
        (&["--layers", "1"][..], "multiple-scattering layers = 1"),
        (
            &["--scattering", "single", "--streams", "12"][..],
            "streams and layers apply to multiple scattering",
        ),
        (
            &["--method", "path-tracing", "--layers", "60"][..],
            "streams and layers apply to the fast and reference methods",
        ),
    ] {
        let out = run(extra);
        assert_eq!(out.status.code(), Some(1), "{extra:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(stderr.lines().count(), 1, "{extra:?}: {stderr}");
        assert!(stderr.contains(expected), "{extra:?}: {stderr}");
    }
}
