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
