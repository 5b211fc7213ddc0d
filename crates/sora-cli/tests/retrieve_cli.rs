//! `sora retrieve` end to end: sora's CSV (radiances made by `sora
//! spectrum` itself), the AERONET sample files, and bad inputs. Each
//! retrieval here is short (--starting-points 1, few iterations): these
//! tests check the command, not the fit (`crates/sora/tests/retrieval.rs`
//! does that).

mod common;

use std::path::Path;

use common::{one_line_error, sora, stdout};

/// A sample file of the library's tests.
fn aeronet(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../sora/tests/data/aeronet")
        .join(name)
        .display()
        .to_string()
}

const ALMUCANTAR: &str = "alm_synthetic_karlsruhe_20050321.alm";
const AOD: &str = "aod_karlsruhe_20050321.lev15";
const PRINCIPAL_PLANE: &str = "ppl_arm_graciosa_20190103.ppl";

/// Short fits: the command is tested, not the fit.
const QUICK: [&str; 4] = ["--starting-points", "1", "--max-iterations", "8"];

/// 2 wavelengths x 8 almucantar azimuths of `sora spectrum` at the
/// earth-clear preset (sun at 30 deg elevation, azimuth 180), scalar
/// light, as sora's radiance CSV with 5 % uncertainties.
fn synthetic_radiances_csv() -> String {
    let out = sora(&[
        "spectrum",
        "--preset",
        "earth-clear",
        "--sun-elevation",
        "30",
        "--sun-azimuth",
        "180",
        "--wavelengths",
        "440:680:240",
        "--almucantar",
        "20",
        "--polarisation",
        "scalar",
    ]);
    let text = stdout(&out);
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("view_elevation_deg,view_azimuth_deg,wavelength_nm,radiance_w_m2_sr_nm")
    );
    let mut csv = String::from(
        "wavelength_nm,sun_elevation_deg,sun_azimuth_deg,view_elevation_deg,view_azimuth_deg,radiance_w_m2_sr_nm,uncertainty_w_m2_sr_nm\n",
    );
    let mut rows = 0;
    for line in lines {
        let v: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        let relative = v[1] - 180.0;
        if (20.0..=160.0).contains(&relative) {
            csv.push_str(&format!(
                "{},30,180,{},{},{},{}\n",
                v[2],
                v[0],
                v[1],
                v[3],
                0.05 * v[3]
            ));
            rows += 1;
        }
    }
    assert_eq!(rows, 16, "{text}");
    csv
}

#[test]
fn csv_radiances_give_json_residuals_and_a_plot() {
    let directory = tempfile::tempdir().unwrap();
    let input = directory.path().join("sky.csv");
    std::fs::write(&input, synthetic_radiances_csv()).unwrap();
    let residuals = directory.path().join("residuals.csv");
    let plot = directory.path().join("fit.png");
    let out = sora(
        &[
            &[
                "retrieve",
                "--radiances",
                input.to_str().unwrap(),
                "--format",
                "json",
                "--residuals",
                residuals.to_str().unwrap(),
                "--plot",
                plot.to_str().unwrap(),
            ][..],
            &QUICK,
        ]
        .concat(),
    );
    let json = common::json(&out);
    let scans = json.as_array().expect("one object per scan");
    assert_eq!(scans.len(), 1);
    let scan = &scans[0];
    assert_eq!(scan["scan"], 1);
    assert!(scan["label"].is_string());
    assert_eq!(scan["reference_wavelength_nm"], 440.0);
    let parameters = scan["parameters"].as_object().unwrap();
    // (serde_json's map sorts its keys.)
    let mut names: Vec<&str> = parameters.keys().map(String::as_str).collect();
    let mut expected = sora::inversion::PARAMETER_NAMES;
    names.sort_unstable();
    expected.sort_unstable();
    assert_eq!(names, expected);
    for estimate in parameters.values() {
        assert!(estimate["value"].is_f64() && estimate["sigma"].is_number());
    }
    assert_eq!(
        scan["correlations"]["parameters"],
        serde_json::json!(sora::inversion::PARAMETER_NAMES)
    );
    let matrix = scan["correlations"]["matrix"].as_array().unwrap();
    assert_eq!(matrix.len(), names.len());
    for (i, row) in matrix.iter().enumerate() {
        let row = common::numbers(row);
        assert_eq!(row.len(), names.len());
        assert!((row[i] - 1.0).abs() < 1e-9, "{row:?}");
    }
    let spectral = scan["spectral"].as_array().unwrap();
    assert_eq!(spectral[0]["wavelength_nm"], 440.0);
    for key in [
        "aerosol_optical_depth",
        "single_scattering_albedo",
        "asymmetry_parameter",
        "refractive_index_real",
        "refractive_index_imaginary",
    ] {
        assert!(spectral[0][key]["value"].is_f64(), "{key}");
    }
    for key in [
        "angstrom_exponent",
        "fine_effective_radius_um",
        "coarse_effective_radius_um",
    ] {
        assert!(scan[key]["value"].is_f64(), "{key}");
    }
    assert!(scan["radiance_scale"].is_null());
    assert!(scan["chi_square"].as_f64().unwrap() >= 0.0);
    assert!(scan["converged"].is_boolean() && scan["warnings"].is_array());
    let radiances = scan["residuals"]["radiances"].as_array().unwrap();
    assert_eq!(
        radiances.len() as u64
            + scan["residuals"]["optical_depths"]
                .as_array()
                .unwrap()
                .len() as u64,
        scan["measurement_count"].as_u64().unwrap()
    );
    assert!(radiances[0]["normalised_residual"].is_f64());
    let residual_text = std::fs::read_to_string(&residuals).unwrap();
    let mut lines = residual_text.lines();
    assert_eq!(
        lines.next(),
        Some(
            "scan,wavelength_nm,sun_elevation_deg,sun_azimuth_deg,view_elevation_deg,view_azimuth_deg,scattering_angle_deg,measured_w_m2_sr_nm,uncertainty_w_m2_sr_nm,fitted_w_m2_sr_nm,normalised_residual"
        )
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 16);
    for row in &rows {
        assert_eq!(row.len(), 11);
        assert!(row[9] > 0.0, "{row:?}");
        assert!(
            ((row[7] - row[9]) / row[8] - row[10]).abs() < 1e-6,
            "{row:?}"
        );
    }
    let png = std::fs::read(&plot).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
}

#[test]
fn aeronet_almucantar_with_optical_depths_as_a_table() {
    // 115 radiances at 4 wavelengths: one iteration (the slowest test).
    let out = sora(&[
        "retrieve",
        "--aeronet-almucantar",
        &aeronet(ALMUCANTAR),
        "--aeronet-aod",
        &aeronet(AOD),
        "--scan",
        "1",
        "--starting-points",
        "1",
        "--max-iterations",
        "1",
    ]);
    let table = stdout(&out);
    for text in [
        "scan 1: Karlsruhe",
        "4 optical depth(s)",
        "aerosol optical depth at 440 nm",
        "fine mode volume median radius",
        " um\n",
        "refractive index, imaginary part",
        "wavelength nm",
        "Angstrom exponent",
        "fine mode effective radius",
        "chi^2 ",
        "per measurement",
        "1 iterations, converged: no",
        "warnings:\n    - the fit did not converge",
    ] {
        assert!(table.contains(text), "{text} not in {table}");
    }
    assert_eq!(table.matches("scan ").count(), 1, "{table}");
    for wavelength in ["440", "675", "870", "1020"] {
        assert!(
            table
                .lines()
                .any(|l| l.trim_start().starts_with(wavelength)),
            "{table}"
        );
    }
    // The reader's notes (a 1640 nm row left out, ...) go to stderr.
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.contains("note: "), "{stderr}");
    assert!(stderr.contains("1640"), "{stderr}");
}

#[test]
fn every_scan_of_a_file_one_row_each_and_a_fit_that_does_not_converge_is_a_warning() {
    // The real principal-plane row (1020 nm), and the same row half an
    // hour later (a second scan); one iteration each: exit 0, the warning
    // on stderr and in the CSV, one CSV row and one residual block per scan.
    let directory = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(aeronet(PRINCIPAL_PLANE)).unwrap();
    let row = text.lines().nth(1).unwrap();
    assert!(row.contains(",11:11:49,"), "{row}");
    let two_scans = directory.path().join("two.ppl");
    std::fs::write(
        &two_scans,
        format!("{text}\n{}\n", row.replace(",11:11:49,", ",11:41:49,")).replace("\n\n", "\n"),
    )
    .unwrap();
    let residuals = directory.path().join("residuals.csv");
    let out = sora(&[
        "retrieve",
        "--aeronet-principal-plane",
        two_scans.to_str().unwrap(),
        "--format",
        "csv",
        "--residuals",
        residuals.to_str().unwrap(),
        "--starting-points",
        "1",
        "--max-iterations",
        "1",
    ]);
    let csv = stdout(&out);
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for column in [
        "scan",
        "label",
        "aerosol_optical_depth_1020nm",
        "aerosol_optical_depth_1020nm_sigma",
        "fine_volume_median_radius_um",
        "fine_volume_median_radius_um_sigma",
        "single_scattering_albedo_1020nm",
        "asymmetry_parameter_1020nm",
        "refractive_index_real_1020nm",
        "refractive_index_imaginary_1020nm_sigma",
        "angstrom_exponent",
        "fine_effective_radius_um",
        "chi_square",
        "converged",
        "warnings",
    ] {
        assert!(header.contains(&column), "{column} not in {header:?}");
    }
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 2, "{csv}");
    for (k, row) in rows.iter().enumerate() {
        assert!(
            row.starts_with(&format!("{},ARM_Graciosa ", k + 1)),
            "{row}"
        );
        assert!(row.contains(",false,\""), "{row}");
        assert!(row.contains("did not converge"), "{row}");
    }
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr
            .lines()
            .any(|l| l.starts_with("warning: ") && l.contains("did not converge")),
        "{stderr}"
    );
    let residual_text = std::fs::read_to_string(&residuals).unwrap();
    let scans: Vec<&str> = residual_text
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert!(
        scans.contains(&"1") && scans.contains(&"2"),
        "{residual_text}"
    );
    assert_eq!(scans.iter().filter(|s| **s == "1").count(), scans.len() / 2);
}

#[test]
fn bad_inputs_give_one_line_errors_and_write_nothing() {
    let directory = tempfile::tempdir().unwrap();
    let path = |name: &str| directory.path().join(name).display().to_string();
    let outputs = |extra: &[&str]| -> Vec<String> {
        let mut args = vec![
            "--residuals".to_string(),
            path("residuals.csv"),
            "--plot".to_string(),
            path("fit.png"),
        ];
        args.extend(extra.iter().map(|s| s.to_string()));
        args
    };
    let run = |args: &[String]| {
        let mut all = vec!["retrieve"];
        all.extend(args.iter().map(String::as_str));
        one_line_error(&sora(&all))
    };

    let missing = run(&[&["--radiances".into(), path("none.csv")][..], &outputs(&[])].concat());
    assert!(
        missing.contains("cannot read") && missing.contains("none.csv"),
        "{missing}"
    );

    let negative = path("negative.csv");
    std::fs::write(
        &negative,
        "wavelength_nm,sun_elevation_deg,sun_azimuth_deg,view_elevation_deg,view_azimuth_deg,radiance_w_m2_sr_nm,uncertainty_w_m2_sr_nm\n\
         440,30,180,30,240,0.05,0.0025\n\
         440,30,180,30,300,-0.01,0.0025\n",
    )
    .unwrap();
    let error = run(&[&["--radiances".into(), negative.clone()][..], &outputs(&[])].concat());
    assert!(error.contains("negative.csv, line 3"), "{error}");

    let scan = run(&[
        &["--aeronet-almucantar".into(), aeronet(ALMUCANTAR)][..],
        &outputs(&["--scan", "99"]),
    ]
    .concat());
    assert!(
        scan.contains("--scan 99") && scan.contains("1..=1"),
        "{scan}"
    );

    let band = run(&[
        &["--aeronet-almucantar".into(), aeronet(ALMUCANTAR)][..],
        &outputs(&["--band-nm", "0"]),
    ]
    .concat());
    assert!(
        band.contains("--band-nm 0 nm") && band.contains("0.01..=50"),
        "{band}"
    );

    // A spectroradiometer's 1-nm spectrum is refused before any work
    // (a retrieval computes a sky per wavelength at every step).
    let dense = path("dense.csv");
    let mut text = String::from("wavelength_nm,relative_radiance\n");
    for w in 400..=480 {
        text += &format!("{w},{}\n", (550.0 / w as f64).powi(3));
    }
    std::fs::write(&dense, text).unwrap();
    let too_many = run(&[
        &["--normalised-spectrum".into(), dense.clone()][..],
        &outputs(
            &[
                &common::TABLE1_GEOMETRY[..],
                &["--max-iterations", "2", "--starting-points", "1"],
            ]
            .concat(),
        ),
    ]
    .concat());
    assert!(
        too_many.contains("81 wavelengths") && too_many.contains("41"),
        "{too_many}"
    );

    let jpeg = run(&[
        "--radiances".into(),
        negative.clone(),
        "--plot".into(),
        path("fit.jpg"),
    ]);
    assert!(jpeg.contains("--plot") && jpeg.contains(".png"), "{jpeg}");

    let no_directory = run(&[
        "--radiances".into(),
        negative.clone(),
        "--residuals".into(),
        path("missing/residuals.csv"),
    ]);
    assert!(no_directory.contains("--residuals"), "{no_directory}");

    // Nothing but the inputs were written.
    let mut names: Vec<String> = std::fs::read_dir(directory.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["dense.csv", "negative.csv"]);
}

#[test]
fn filters_and_the_index_per_wavelength_are_taken_and_a_filter_off_the_channels_is_an_error() {
    let directory = tempfile::tempdir().unwrap();
    let input = directory.path().join("sky.csv");
    std::fs::write(&input, synthetic_radiances_csv()).unwrap();
    let input = input.to_str().unwrap();
    let spectral = |extra: &[&str]| -> Vec<(f64, f64, f64)> {
        let out = sora(
            &[
                &["retrieve", "--radiances", input, "--format", "json"][..],
                &QUICK,
                extra,
            ]
            .concat(),
        );
        let json = common::json(&out);
        json[0]["spectral"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| {
                (
                    s["wavelength_nm"].as_f64().unwrap(),
                    s["refractive_index_real"]["value"].as_f64().unwrap(),
                    s["refractive_index_imaginary"]["value"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    // `cimel` takes its channels that cover the measured 440 and 680 nm
    // (cimel-440, cimel-675); one index (--one-index): the same n and k at
    // both.
    let filtered = spectral(&["--filter", "cimel", "--one-index"]);
    assert_eq!(filtered.len(), 2);
    assert_eq!((filtered[0].0, filtered[1].0), (440.0, 680.0));
    assert_eq!(
        (filtered[0].1, filtered[0].2),
        (filtered[1].1, filtered[1].2)
    );
    // An index per wavelength (the default): each its own (two channels:
    // only n's slope has a prior, no curvature under three).
    let per_wavelength = spectral(&[]);
    assert_ne!(
        (per_wavelength[0].1, per_wavelength[0].2),
        (per_wavelength[1].1, per_wavelength[1].2)
    );
    // The table shows the index's columns only when it varies.
    let header = |extra: &[&str]| -> bool {
        let out = sora(&[&["retrieve", "--radiances", input][..], &QUICK, extra].concat());
        let table = String::from_utf8(out.stdout).unwrap();
        let header = table.lines().find(|l| l.contains("wavelength nm")).unwrap();
        header.ends_with("refr. index, real part    refr. index, imag. part")
    };
    assert!(header(&[]));
    assert!(header(&["--index-per-wavelength"]));
    assert!(!header(&["--one-index"]));
    // Both at once: clap's argument error (status 2) before any work.
    let both = sora(&[
        "retrieve",
        "--radiances",
        input,
        "--one-index",
        "--index-per-wavelength",
    ]);
    assert_eq!(both.status.code(), Some(2), "{both:?}");
    let stderr = String::from_utf8_lossy(&both.stderr);
    assert!(
        stderr
            .lines()
            .next()
            .unwrap_or_default()
            .contains("the argument '--one-index' cannot be used with"),
        "{stderr}"
    );
    assert!(both.stdout.is_empty());

    let error = one_line_error(&sora(&[
        "retrieve",
        "--radiances",
        input,
        "--filter",
        "cimel-870",
    ]));
    assert!(
        error.contains("cimel-870") && error.contains("covers none of the measured wavelengths"),
        "{error}"
    );
    let error = one_line_error(&sora(&[
        "retrieve",
        "--radiances",
        input,
        "--filter",
        "cimel-440",
        "--filter",
        "cimel-440",
    ]));
    assert!(
        error.contains("both cover the measured wavelength 440 nm"),
        "{error}"
    );
}
