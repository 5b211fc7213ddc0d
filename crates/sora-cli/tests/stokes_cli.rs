//! `sora spectrum --stokes`: the columns, their meaning, the polarised
//! intensity of the default method, and the choices that cannot give
//! Stokes vectors.

mod common;

use common::{one_line_error, sora, stdout};

/// The standard output of `sora` with `args`, which must succeed.
fn run(args: &[&str]) -> String {
    stdout(&sora(args))
}

const RAYLEIGH_SUN_30: [&str; 7] = [
    "spectrum",
    "--preset",
    "us-standard-1976-rayleigh",
    "--sun-elevation",
    "30",
    "--sun-azimuth",
    "180",
];

#[test]
fn single_scattering_stokes_columns_follow_the_convention() {
    // 90 degrees from the sun in its vertical: the field is horizontal,
    // so Q < 0, U = 0 and the angle of polarisation is 90 degrees.
    let csv = run(&[
        &RAYLEIGH_SUN_30[..],
        &[
            "--view-elevation",
            "60",
            "--view-azimuth",
            "0",
            "--scattering",
            "single",
            "--stokes",
        ],
    ]
    .concat());
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some(
            "wavelength_nm,radiance_w_m2_sr_nm,q_w_m2_sr_nm,u_w_m2_sr_nm,v_w_m2_sr_nm,degree_of_linear_polarisation,angle_of_polarisation_deg"
        )
    );
    let mut rows = 0;
    for line in lines {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let (i, q, u, degree, angle) = (v[1], v[2], v[3], v[5], v[6]);
        assert!(q < 0.0 && u.abs() < 1e-12 * i, "{line}");
        // The Rayleigh maximum with air's depolarisation (rho ~ 0.028-0.03):
        // (1 - rho) / (1 + rho) ~ 0.94-0.95.
        assert!(degree > 0.93 && degree < 0.96, "{line}");
        assert!((degree - q.hypot(u) / i).abs() < 1e-6, "{line}");
        assert!((angle - 90.0).abs() < 1e-6, "{line}");
        rows += 1;
    }
    assert_eq!(rows, 21);
}

#[test]
fn unpolarised_light_has_an_empty_angle_and_json_null() {
    // Looking straight at the sun, single scattering is forward scattering:
    // b1 = 0, no polarisation, and no angle.
    let view = [
        "--view-elevation",
        "30",
        "--view-azimuth",
        "180",
        "--scattering",
        "single",
        "--stokes",
    ];
    let csv = run(&[&RAYLEIGH_SUN_30[..], &view, &["--wavelengths", "550"]].concat());
    let row = csv.lines().nth(1).unwrap();
    assert!(row.ends_with(",0.000000,"), "{row}");
    let json = common::json(&sora(
        &[
            &RAYLEIGH_SUN_30[..],
            &view,
            &["--wavelengths", "550", "--format", "json"],
        ]
        .concat(),
    ));
    assert_eq!(
        json["angle_of_polarisation_deg"],
        serde_json::json!([null]),
        "{json}"
    );
}

#[test]
fn path_traced_stokes_have_standard_errors_in_json() {
    let json = run(&[
        &RAYLEIGH_SUN_30[..],
        &[
            "--almucantar",
            "90",
            "--method",
            "path-tracing",
            "--samples",
            "500",
        ],
        &[
            "--stokes",
            "--format",
            "json",
            "--wavelengths",
            "450:650:100",
        ],
    ]
    .concat());
    for key in [
        "\"q_w_m2_sr_nm\"",
        "\"standard_error_q_w_m2_sr_nm\"",
        "\"standard_error_v_w_m2_sr_nm\"",
        "\"degree_of_linear_polarisation\"",
    ] {
        assert_eq!(json.matches(key).count(), 4, "{key} in {json}");
    }
    assert!(!json.contains("NaN"));
}

#[test]
fn the_default_method_gives_the_polarised_intensity_of_all_orders() {
    // Sun 30, view 30 degrees up at 90 degrees from it: the polarised
    // intensity is below the scalar one (the scalar field overestimates the
    // light there, most in the blue), and the light is strongly polarised.
    // Polarised light is the default (--stokes adds columns, not physics);
    // --polarisation scalar is the scalar light.
    let view = ["--view-elevation", "30", "--view-azimuth", "90"];
    let scalar = run(&[
        &RAYLEIGH_SUN_30[..],
        &view[..],
        &["--polarisation", "scalar"],
    ]
    .concat());
    let vector = run(&[&RAYLEIGH_SUN_30[..], &view[..], &["--stokes"]].concat());
    let default = run(&[&RAYLEIGH_SUN_30[..], &view[..]].concat());
    for (d, v) in default.lines().skip(1).zip(vector.lines().skip(1)) {
        let d: Vec<&str> = d.split(',').collect();
        assert_eq!(d[..], v.split(',').collect::<Vec<_>>()[..2]);
    }
    let header = vector.lines().next().unwrap();
    let column = |name: &str| header.split(',').position(|c| c == name).unwrap();
    let (radiance, degree) = (
        column("radiance_w_m2_sr_nm"),
        column("degree_of_linear_polarisation"),
    );
    for (s, v) in scalar.lines().skip(1).zip(vector.lines().skip(1)) {
        let (s, v): (Vec<&str>, Vec<&str>) = (s.split(',').collect(), v.split(',').collect());
        let ratio = v[radiance].parse::<f64>().unwrap() / s[radiance].parse::<f64>().unwrap();
        assert!(
            (0.97..0.999).contains(&ratio),
            "{} nm: vector / scalar {ratio}",
            v[0]
        );
        let d: f64 = v[degree].parse().unwrap();
        assert!((0.6..0.9).contains(&d), "{} nm: degree {d}", v[0]);
    }
}

#[test]
fn choices_without_stokes_vectors_are_one_line_errors() {
    // The reference march is scalar, single or multiple scattering.
    for scattering in ["single", "multiple"] {
        let extra = [
            "--view-elevation",
            "60",
            "--view-azimuth",
            "0",
            "--method",
            "reference",
            "--scattering",
            scattering,
            "--stokes",
        ];
        let out = sora(&[&RAYLEIGH_SUN_30[..], &extra[..]].concat());
        assert!(!out.status.success());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(
            stderr.contains("polarisation") && stderr.contains("reference"),
            "{stderr}"
        );
        assert!(out.stdout.is_empty());
    }
    // Mie aerosols polarise with their phase matrix (computed for --stokes).
    let csv = run(&[
        "spectrum",
        "--preset",
        "mars-dust",
        "--sun-elevation",
        "30",
        "--view-elevation",
        "60",
        "--view-azimuth",
        "0",
        "--scattering",
        "single",
        "--stokes",
        "--wavelengths",
        "550",
    ]);
    let row: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
    let degree: f64 = row[5].parse().unwrap();
    assert!(degree > 0.0 && degree < 0.5, "{row:?}");
}

#[test]
fn atmosphere_show_says_what_polarises() {
    let text = run(&["atmosphere", "show", "--preset", "clear-sky-reference"]);
    assert!(text.contains("phase Rayleigh, polarising"), "{text}");
    assert!(
        text.contains("phase Henyey-Greenstein, non-polarising"),
        "{text}"
    );
    let text = run(&["atmosphere", "show", "--preset", "earth-clear"]);
    assert!(
        text.contains(
            "phase tabulated (Mie), polarising (its phase matrix is computed for --stokes)"
        ),
        "{text}"
    );
    // Ozone does not scatter: nothing to say about its polarisation.
    let ozone = text
        .lines()
        .find(|l| l.trim_start().starts_with("ozone"))
        .unwrap();
    assert!(ozone.ends_with("phase isotropic"), "{ozone}");
}

/// One view 30 degrees up toward azimuth 0, single scattering, 550 nm.
const ONE_VIEW: [&str; 8] = [
    "--view-elevation",
    "30",
    "--view-azimuth",
    "0",
    "--scattering",
    "single",
    "--wavelengths",
    "550",
];

#[test]
fn a_non_polarising_species_is_a_printed_warning() {
    // clear-sky-reference's aerosol is Henyey-Greenstein: Stokes vectors
    // treat it as non-polarising, and say so once per species on stderr.
    let args = [
        &[
            "spectrum",
            "--preset",
            "clear-sky-reference",
            "--sun-elevation",
            "30",
        ][..],
        &ONE_VIEW[..],
    ]
    .concat();
    let out = sora(&[&args[..], &["--stokes"]].concat());
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(
        warnings[0].contains("aerosol")
            && warnings[0].contains("Henyey-Greenstein")
            && warnings[0].contains("non-polarising"),
        "{stderr}"
    );
    // Without polarised output nothing to warn about; nor for a sky
    // whose species all polarise.
    let out = sora(&args);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
    let out = sora(&[&RAYLEIGH_SUN_30[..], &ONE_VIEW[..], &["--stokes"]].concat());
    assert!(out.status.success(), "{out:?}");
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
}

#[test]
fn a_depolarisation_ratio_above_one_half_cannot_be_polarised() {
    // A parametric Rayleigh species with rho = 0.7: scalar light takes it,
    // polarised light (Hansen & Travis's matrix needs rho <= 0.5) is a
    // one-line error naming the species, the value and the range.
    let text = include_str!("../../../atmospheres/clear-sky-reference.toml").replace(
        "wavelength_exponent = 4.0 }",
        "wavelength_exponent = 4.0, depolarization_ratio = 0.7 }",
    );
    assert!(text.contains("depolarization_ratio = 0.7"));
    let path = std::env::temp_dir().join(format!("sora-depolarised-{}.toml", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let file = path.to_str().unwrap();
    let args = [
        &["spectrum", "--atmosphere", file, "--sun-elevation", "30"][..],
        &ONE_VIEW[..],
    ]
    .concat();
    let scalar = sora(&[&args[..], &["--polarisation", "scalar"]].concat());
    let vector = sora(&args);
    std::fs::remove_file(&path).unwrap();
    assert!(scalar.status.success());
    let error = one_line_error(&vector);
    assert!(
        error.contains("\"air\"") && error.contains("0.7") && error.contains("0..=0.5"),
        "{error}"
    );
}
