//! `sora mie` end to end: the built binary, its CSV contract and its errors.

mod common;

use common::{sora, stdout};

#[test]
fn batch_keeps_the_header_order_and_precision() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("spheres.csv");
    // Rows from the 100-digit reference (../shared/reference/mie/efficiencies.csv).
    std::fs::write(&input, "m_re,m_im,x\n1.33,0.0,10.0\n1.5,0.01,1.0\n").unwrap();
    let text = stdout(&sora(&["mie", "--batch", input.to_str().unwrap()]));
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("m_re,m_im,x,qext,qsca,qabs,qback,g"));
    let first: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(&first[..3], ["1.33", "0", "10"]);
    // 12+ significant digits: the mantissa of qext alone has 17.
    let qext = first[3];
    assert!(
        qext.split('e')
            .next()
            .unwrap()
            .replace(['.', '-'], "")
            .len()
            >= 12,
        "{qext}"
    );
    let qext: f64 = qext.parse().unwrap();
    assert!((qext / 2.2065487101846184 - 1.0).abs() < 1e-9, "{qext}");
    assert_eq!(lines.count(), 1, "one output row per input row");
}

#[test]
fn batch_errors_name_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("m_re,m_im,x\n1.5,0.01,1\n1.5,abc,1\n", "line 3"),
        ("m_re,m_im,x\n1.5,0.01\n", "line 2"),
        ("m_re,m_im,x\n1.5,-0.01,1\n", "line 2"),
        ("m_re,m_im,x\n1.5,0.01,0\n", "line 2"),
        ("re,im,x\n1.5,0.01,1\n", "header"),
    ];
    for (i, (text, expected)) in cases.iter().enumerate() {
        let path = dir.path().join(format!("bad{i}.csv"));
        std::fs::write(&path, text).unwrap();
        let out = sora(&["mie", "--batch", path.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{text}: {stderr}");
        assert!(stderr.contains(expected), "{text}: {stderr}");
    }
}

#[test]
fn single_sphere_forms_agree() {
    // x = 2 pi r / lambda: r = 0.5 um at 550 nm is x = 5.711986642890533.
    let by_x = stdout(&sora(&[
        "mie",
        "--m",
        "1.5+0.01i",
        "--x",
        "5.711986642890533",
    ]));
    let by_radius = stdout(&sora(&[
        "mie",
        "--m",
        "1.5+0.01i",
        "--radius-um",
        "0.5",
        "--wavelength-nm",
        "550",
    ]));
    let qext = |text: &str| -> f64 {
        text.lines()
            .find(|l| l.starts_with("qext"))
            .unwrap()
            .split('=')
            .nth(1)
            .unwrap()
            .trim()
            .parse()
            .unwrap()
    };
    assert!((qext(&by_x) / qext(&by_radius) - 1.0).abs() < 1e-11);
}

#[test]
fn phase_table_is_normalised() {
    let text = stdout(&sora(&[
        "mie",
        "--m",
        "1.33",
        "--x",
        "10",
        "--phase",
        "--angle-step-deg",
        "0.5",
    ]));
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("angle_deg,phase_function_per_sr,s12_over_s11")
    );
    let rows: Vec<[f64; 3]> = lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|f| f.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert_eq!(rows.len(), 361);
    // Trapezoid of p(theta) 2 pi sin(theta) dtheta over 0..180 deg.
    let integral: f64 = rows
        .windows(2)
        .map(|w| {
            let f = |r: &[f64; 3]| r[1] * 2.0 * std::f64::consts::PI * r[0].to_radians().sin();
            0.5 * (f(&w[0]) + f(&w[1])) * (w[1][0] - w[0][0]).to_radians()
        })
        .sum();
    assert!((integral - 1.0).abs() < 2e-3, "{integral}");
    // Reference: p = 5.155690196871175 sr^-1 at 0 deg (phase.csv, case 0).
    assert!(
        (rows[0][1] / 5.155690196871175 - 1.0).abs() < 1e-9,
        "{}",
        rows[0][1]
    );
}

#[test]
fn distribution_form_matches_the_reference_ensemble() {
    let text = stdout(&sora(&[
        "mie",
        "--m",
        "1.5+0.01i",
        "--lognormal",
        "0.1,2.0,0.1,2.5",
        "--wavelengths",
        "380",
    ]));
    let row: Vec<f64> = text
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|f| f.parse().unwrap())
        .collect();
    // lognormal.csv: r_m 0.1 um, sigma_g 2, 380 nm, window 0.1-2.5 um.
    assert!((row[1] / 4.390748392042728e-13 - 1.0).abs() < 1e-6);
    assert!((row[2] / 4.008738708590066e-13 - 1.0).abs() < 1e-6);
    assert!((row[5] / 0.7194400763233445 - 1.0).abs() < 1e-6);
    let out = sora(&["mie", "--m", "1.5", "--lognormal", "0.1,0.5"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("sigma_g = 0.5"));
}

/// Issue 17: the degenerate corners (m = 1, x down to 1e-300, k -> 0, a zero
/// optical depth) print finite numbers or fail with a one-line error; never
/// NaN or infinity with exit status 0.
#[test]
fn degenerate_corners_print_no_nan() {
    fn check(args: &[&str]) -> Option<String> {
        let out = sora(args);
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        if !out.status.success() {
            assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
            assert_eq!(
                stderr.lines().count(),
                1,
                "{args:?}: not one line: {stderr}"
            );
            assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
            return None;
        }
        let text = String::from_utf8(out.stdout).unwrap();
        let lower = text.to_lowercase();
        assert!(!lower.contains("nan"), "{args:?}:\n{text}");
        assert!(!lower.contains("inf"), "{args:?}:\n{text}");
        Some(text)
    }
    let indices = [
        "1+0i",
        "1.33",
        "1.33+0.01i",
        "1.5+1e-300i",
        "1+1e-300i",
        "2+1i",
    ];
    let size_parameters = ["1e-300", "1e-100", "1e-20", "1e-8", "1e-3", "1"];
    for m in indices {
        for x in size_parameters {
            let text = check(&["mie", "--m", m, "--x", x]).expect("efficiencies always print");
            if m == "1+0i" {
                assert!(text.contains("single_scattering_albedo = 0.0"), "{text}");
            }
            let phase = check(&[
                "mie",
                "--m",
                m,
                "--x",
                x,
                "--phase",
                "--angle-step-deg",
                "30",
            ]);
            if m == "1+0i" {
                assert!(phase.is_none(), "m = 1 has no phase function");
            }
        }
        check(&[
            "mie",
            "--m",
            m,
            "--lognormal",
            "0.1,2.0",
            "--wavelengths",
            "550:550:1",
        ])
        .expect("the ensemble prints");
    }
    // x -> 0: the Rayleigh limit, 3 (1 + mu^2) / (16 pi).
    let text = check(&[
        "mie",
        "--m",
        "1.33",
        "--x",
        "1e-300",
        "--phase",
        "--angle-step-deg",
        "90",
    ])
    .unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let rayleigh = |mu: f64| 3.0 * (1.0 + mu * mu) / (16.0 * std::f64::consts::PI);
    assert_eq!(rows.len(), 3);
    for (row, mu) in rows.iter().zip([1.0, 0.0, -1.0]) {
        assert!((row[1] - rayleigh(mu)).abs() < 1e-12, "{row:?}");
    }
    assert_eq!(rows[1][2], -1.0);
    // ... continuous with the Mie series just above the switch.
    let series = check(&[
        "mie",
        "--m",
        "1.33",
        "--x",
        "1e-6",
        "--phase",
        "--angle-step-deg",
        "90",
    ])
    .unwrap();
    for (line, mu) in series.lines().skip(1).zip([1.0, 0.0, -1.0]) {
        let p: f64 = line.split(',').nth(1).unwrap().parse().unwrap();
        assert!((p / rayleigh(mu) - 1.0).abs() < 1e-9, "{line}");
    }
    // The non-scattering ensemble: albedo and g 0, not NaN.
    let text = check(&[
        "mie",
        "--m",
        "1+0i",
        "--lognormal",
        "0.1,2.0",
        "--wavelengths",
        "550:550:1",
    ])
    .unwrap();
    let values: Vec<f64> = text
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(&values[1..7], &[0.0; 6]);
    // Batch rows at m = 1 and tiny x.
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("corners.csv");
    std::fs::write(
        &input,
        "m_re,m_im,x\n1,0,1\n1.33,0,1e-300\n1.5,1e-300,1e-300\n",
    )
    .unwrap();
    check(&["mie", "--batch", input.to_str().unwrap()]).unwrap();
    // A zero optical depth: the aerosol is absent, the sky is finite.
    let paper = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../atmospheres/paper-earth.toml"),
    )
    .unwrap();
    let zero = paper.replace("optical_depth = 0.15", "optical_depth = 0");
    assert_ne!(zero, paper);
    let path = dir.path().join("zero.toml");
    std::fs::write(&path, zero).unwrap();
    let path = path.to_str().unwrap();
    for format in ["table", "csv", "json"] {
        check(&[
            "atmosphere",
            "show",
            "--atmosphere",
            path,
            "--format",
            format,
        ])
        .unwrap();
    }
    check(&[
        "spectrum",
        "--atmosphere",
        path,
        "--sun-elevation",
        "30",
        "--view-elevation",
        "10",
        "--view-azimuth",
        "0",
        "--wavelengths",
        "400:700:100",
        "--format",
        "csv",
    ])
    .unwrap();
}

/// A batch CSV that starts with a UTF-8 byte-order mark (as spreadsheets
/// write) is read as without it.
#[test]
fn batch_accepts_a_byte_order_mark() {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain.csv");
    let marked = dir.path().join("marked.csv");
    let rows = "m_re,m_im,x\n1.33,0.0,10.0\n";
    std::fs::write(&plain, rows).unwrap();
    std::fs::write(&marked, format!("\u{feff}{rows}")).unwrap();
    let expected = stdout(&sora(&["mie", "--batch", plain.to_str().unwrap()]));
    let got = stdout(&sora(&["mie", "--batch", marked.to_str().unwrap()]));
    assert_eq!(got, expected);
}

/// `--phase --angle-step-deg` is bounded: at most 1800001 rows (a step of
/// 1e-4 deg), refused before anything is computed.
#[test]
fn phase_table_rows_are_limited() {
    // 5e-324: 180 / step is infinite (it overflowed the row count).
    for step in ["1e-6", "9.9e-5", "5e-324"] {
        let out = sora(&[
            "mie",
            "--m",
            "1.33",
            "--x",
            "1",
            "--phase",
            "--angle-step-deg",
            step,
        ]);
        let message = common::one_line_error(&out);
        assert!(message.contains("limit of 1800001"), "{message}");
        assert!(message.contains("at least 1e-4 deg"), "{message}");
    }
    let text = stdout(&sora(&[
        "mie",
        "--m",
        "1.33",
        "--x",
        "1",
        "--phase",
        "--angle-step-deg",
        "0.01",
    ]));
    assert_eq!(text.lines().count(), 18_002);
}

/// A distribution whose effective size parameter exceeds 1e5 is refused at
/// once (it would compute for hours); one below it runs.
#[test]
fn huge_distributions_are_refused_at_once() {
    let start = std::time::Instant::now();
    let out = sora(&[
        "mie",
        "--m",
        "2+1i",
        "--gamma",
        "1e6,0.3",
        "--wavelengths",
        "550:550:1",
    ]);
    let message = common::one_line_error(&out);
    assert!(message.contains("limit of 1e5"), "{message}");
    assert!(start.elapsed().as_secs() < 30);
    stdout(&sora(&[
        "mie",
        "--m",
        "2+1i",
        "--gamma",
        "10,0.3",
        "--wavelengths",
        "550:550:1",
    ]));
}

/// `sora mie --batch` echoes its inputs in the shortest form that reads
/// back as the same double (issue 17: 5e-324 came back as 324 digits).
#[test]
fn batch_echoes_inputs_in_shortest_round_trip_form() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("echo.csv");
    let inputs = [
        ("1.5", "5e-324", "1e-300", ["1.5", "5e-324", "1e-300"]),
        ("1.33", "0.0", "10.0", ["1.33", "0", "10"]),
        ("1.5", "0.001", "12345.678", ["1.5", "0.001", "12345.678"]),
        ("1.5", "1e-5", "2.5e-8", ["1.5", "1e-5", "2.5e-8"]),
    ];
    let mut text = String::from("m_re,m_im,x\n");
    for (re, im, x, _) in &inputs {
        text += &format!("{re},{im},{x}\n");
    }
    std::fs::write(&input, text).unwrap();
    let out = stdout(&sora(&["mie", "--batch", input.to_str().unwrap()]));
    for (line, (re, im, x, expected)) in out.lines().skip(1).zip(&inputs) {
        let fields: Vec<&str> = line.split(',').collect();
        assert_eq!(&fields[..3], expected, "{line}");
        // Each echo reads back as the input's double.
        for (echo, given) in fields[..3].iter().zip([re, im, x]) {
            assert_eq!(echo.parse::<f64>().unwrap(), given.parse::<f64>().unwrap());
        }
        assert!(line.len() < 150, "{line}");
    }
    assert_eq!(out.lines().count(), 1 + inputs.len());
}

/// Q_abs is never negative, even where k is subnormal and the absorption
/// is far below rounding of Q_ext (issue 17: the batch campaign found
/// Q_abs < 0 at k = 5e-324), and stays the reference value where k is
/// normal.
#[test]
fn absorption_is_never_negative_at_tiny_k() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("tiny_k.csv");
    let mut text = String::from("m_re,m_im,x\n");
    for k in [
        "5e-324",
        "1e-320",
        "1e-310",
        "2.2250738585072014e-308",
        "1e-300",
        "1e-30",
    ] {
        for x in ["0.001", "0.5", "1", "10", "100", "1000", "5000"] {
            for n in ["1.0001", "1.33", "1.5", "2", "5"] {
                text += &format!("{n},{k},{x}\n");
            }
        }
    }
    std::fs::write(&input, &text).unwrap();
    let out = stdout(&sora(&["mie", "--batch", input.to_str().unwrap()]));
    let mut rows = 0;
    for line in out.lines().skip(1) {
        let values: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
        let (qext, qsca, qabs) = (values[3], values[4], values[5]);
        assert!(qabs >= 0.0 && qabs.is_sign_positive(), "{line}");
        assert!(qext >= qsca && qsca >= 0.0, "{line}");
        rows += 1;
    }
    assert_eq!(rows, text.lines().count() - 1);
    // Where k is normal: the 100-digit reference
    // (shared/reference/mie/efficiencies.csv), m = 1.5 + 0.01i, x = 1.
    let single = stdout(&sora(&["mie", "--m", "1.5+0.01i", "--x", "1"]));
    let qabs: f64 = single
        .lines()
        .find_map(|l| l.strip_prefix("qabs  = "))
        .unwrap()
        .parse()
        .unwrap();
    assert!((qabs / 0.028840763900684192 - 1.0).abs() < 1e-11, "{qabs}");
}
