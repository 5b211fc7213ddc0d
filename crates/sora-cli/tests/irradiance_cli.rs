//! `sora irradiance` end to end.

mod common;

use common::{one_line_error, sora, stdout};

const BASE: [&str; 5] = [
    "irradiance",
    "--preset",
    "earth-clear",
    "--sun-elevation",
    "30",
];

#[test]
fn csv_rows_add_up_and_json_carries_units_and_the_sun() {
    let csv = stdout(&sora(&[&BASE[..], &["--tilt-deg", "35"]].concat()));
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header,
        [
            "wavelength_nm",
            "direct_normal_irradiance_w_m2_nm",
            "direct_beam_transmittance",
            "direct_horizontal_irradiance_w_m2_nm",
            "diffuse_horizontal_irradiance_w_m2_nm",
            "global_horizontal_irradiance_w_m2_nm",
            "direct_tilted_irradiance_w_m2_nm",
            "diffuse_tilted_irradiance_w_m2_nm",
            "global_tilted_irradiance_w_m2_nm",
        ]
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 21);
    for row in &rows {
        // direct horizontal = direct normal x sin 30; global = direct + diffuse.
        assert!((row[3] / (0.5 * row[1]) - 1.0).abs() < 1e-8, "{row:?}");
        assert!((row[5] / (row[3] + row[4]) - 1.0).abs() < 1e-8, "{row:?}");
        assert!((row[8] / (row[6] + row[7]) - 1.0).abs() < 1e-8, "{row:?}");
        assert!(row[2] > 0.0 && row[2] < 1.0);
        // Tilted 35 degrees toward the sun (south): more direct light.
        assert!(row[6] > row[3]);
    }
    let json = common::json(&sora(&[&BASE[..], &["--format", "json"]].concat()));
    assert_eq!(json["sun_elevation_deg"], 30.0);
    assert_eq!(json["sun_azimuth_deg"], 180.0);
    for key in [
        "global_horizontal_irradiance_w_m2",
        "global_horizontal_illuminance_lx",
        "direct_normal_illuminance_lx",
    ] {
        assert!(json[key].as_f64().unwrap() > 0.0, "{key} in {json}");
    }
    // The CSV's rows, to its ten significant digits.
    let diffuse = common::numbers(&json["diffuse_horizontal_irradiance_w_m2_nm"]);
    assert_eq!(diffuse.len(), rows.len());
    for (value, row) in diffuse.iter().zip(&rows) {
        assert!((value / row[4] - 1.0).abs() < 6e-10, "{value} vs {row:?}");
    }
}

#[test]
fn bad_irradiance_arguments_are_one_line_errors() {
    for (extra, expected) in [
        (&["--tilt-deg", "200"][..], "plane tilt = 200 deg"),
        (&["--samples", "10"][..], "--samples and --seed"),
        (
            &["--method", "path-tracing", "--samples", "1"][..],
            "samples = 1",
        ),
    ] {
        let error = one_line_error(&sora(&[&BASE[..], extra].concat()));
        assert!(error.contains(expected), "{extra:?}: {error}");
    }
}

/// `--method reference` (4,608 marches of 1000 x 250 steps, about 80 s a
/// wavelength) is a one-line error before any work (docs/limits.md), even
/// at one wavelength, in well under a second.
#[test]
fn the_reference_march_over_the_hemisphere_is_refused_before_any_work() {
    let started = std::time::Instant::now();
    let error = one_line_error(&sora(
        &[
            &BASE[..],
            &["--method", "reference", "--wavelengths", "550:550:1"],
        ]
        .concat(),
    ));
    assert!(started.elapsed().as_secs_f64() < 10.0);
    assert!(
        error.contains("reference irradiance march (4608 directions x 1000 view steps x 250 sun steps) = 1.152e9 steps is out of range: allowed <= 1e8")
            && error.contains("use the fast method"),
        "{error}"
    );
}
