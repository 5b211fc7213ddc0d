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

/// Every broadband value says its band and the sun's share in it: the
/// sun's irradiance on the grid (its samples' direct normal irradiance over
/// the transmittance toward the sun, summed over their bands) and in its
/// whole table (ASTM E490, 1366.1 W m^-2 over 119.5 nm to 1 mm).
#[test]
fn broadband_values_name_their_band_and_the_suns_share_in_it() {
    let grid = ["--wavelengths", "450:650:100"];
    let json = common::json(&sora(&[&BASE[..], &grid, &["--format", "json"]].concat()));
    assert_eq!(common::numbers(&json["broadband_range_nm"]), [450.0, 650.0]);
    assert_eq!(
        common::numbers(&json["sun_table_range_nm"]),
        [119.5, 1_000_000.0]
    );
    let total = json["sun_table_irradiance_w_m2"].as_f64().unwrap();
    assert!((total - 1366.1).abs() < 1.4, "{total}");
    let direct = common::numbers(&json["direct_normal_irradiance_w_m2_nm"]);
    let transmittance = common::numbers(&json["direct_beam_transmittance"]);
    let sun: f64 = direct
        .iter()
        .zip(&transmittance)
        .map(|(e, t)| e / t * 100.0)
        .sum();
    let in_band = json["extraterrestrial_in_band_w_m2"].as_f64().unwrap();
    assert!((in_band / sun - 1.0).abs() < 1e-9, "{in_band} vs {sun}");
    // The table and the CSV's stderr say the same.
    let table = stdout(&sora(&[&BASE[..], &grid, &["--format", "table"]].concat()));
    let share = format!(
        "extraterrestrial irradiance over 450-650 nm: {in_band:.4} W m^-2 ({:.2} % of the sun's {total:.1} W m^-2 over 119.5-1000000 nm)",
        100.0 * in_band / total
    );
    assert!(table.contains(&share), "{table}");
    let csv = sora(&[&BASE[..], &grid].concat());
    let stderr = String::from_utf8(csv.stderr).unwrap();
    assert!(
        stderr.contains("global_horizontal_irradiance_w_m2 ")
            && stderr.contains("; over 450-650 nm")
            && stderr.contains(&share),
        "{stderr}"
    );
    // --broadband takes the widest grid itself: with --wavelengths or
    // --filter it is clap's argument error (status 2, its first line says
    // why) before any work.
    for extra in [&["--wavelengths", "300:2500:5"][..], &["--filter", "cimel"]] {
        let out = sora(&[&BASE[..], &["--broadband"], extra].concat());
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {out:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        let first = stderr.lines().next().unwrap_or_default();
        assert!(
            first.contains("the argument '--broadband' cannot be used with"),
            "{extra:?}: {stderr}"
        );
        assert!(out.stdout.is_empty());
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
