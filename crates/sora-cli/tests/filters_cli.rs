//! `--filter` (issue 35): an instrument channel's value is the
//! response-weighted mean of the spectrum over the channel. A flat filter
//! gives the band mean of the 1-nm grid, a shaped one its weighted mean, a
//! narrow one the point value; the sun photometer's channels are built in;
//! `sora irradiance` takes filters too; bad filters are one-line errors.

mod common;

use common::{one_line_error, sora, spectrum_rows, stdout};

/// Single scattering keeps these runs short; the weighting is the same for
/// every method.
const VIEW: [&str; 12] = [
    "--preset",
    "earth-clear",
    "--sun-elevation",
    "30",
    "--sun-azimuth",
    "180",
    "--view-elevation",
    "20",
    "--view-azimuth",
    "90",
    "--scattering",
    "single",
];

/// A filter CSV in a fresh temporary directory.
fn filter_file(name: &str, rows: &[(f64, f64)]) -> (tempfile::TempDir, String) {
    let directory = tempfile::tempdir().unwrap();
    let path = directory.path().join(name);
    let mut text = String::from("# a test filter\nwavelength_nm,response\n");
    for (w, r) in rows {
        text += &format!("{w},{r}\n");
    }
    std::fs::write(&path, text).unwrap();
    (directory, path.display().to_string())
}

/// The (filter, centre_nm, radiance) rows of a one-direction filtered CSV.
fn filter_rows(csv: &str) -> Vec<(String, f64, f64)> {
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("filter,centre_nm,radiance_w_m2_sr_nm"));
    lines
        .map(|line| {
            let fields: Vec<&str> = line.split(',').collect();
            assert_eq!(fields.len(), 3, "{line}");
            (
                fields[0].to_string(),
                fields[1].parse().unwrap(),
                fields[2].parse().unwrap(),
            )
        })
        .collect()
}

fn spectrum(grid: &str) -> Vec<(f64, f64)> {
    spectrum_rows(&stdout(&sora(
        &[&["spectrum"][..], &VIEW, &["--wavelengths", grid]].concat(),
    )))
}

fn filtered(filters: &[&str]) -> Vec<(String, f64, f64)> {
    let mut args: Vec<&str> = [&["spectrum"][..], &VIEW].concat();
    for filter in filters {
        args.extend(["--filter", filter]);
    }
    filter_rows(&stdout(&sora(&args)))
}

#[test]
fn a_flat_filter_is_the_band_mean_and_a_shaped_one_its_weighted_mean() {
    let grid = spectrum("430:450:1");
    assert_eq!(grid.len(), 21);
    let (_dir, flat) = filter_file("flat.csv", &[(430.0, 1.0), (450.0, 1.0)]);
    // A triangle peaking at 436 nm: zero at 430 and 450, its rows on the
    // 1-nm grid's wavelengths (the filter's grid).
    let triangle = |w: f64| {
        if w <= 436.0 {
            (w - 430.0) / 6.0
        } else {
            (450.0 - w) / 14.0
        }
    };
    let (_dir2, shaped) = filter_file("triangle.csv", &[(430.0, 0.0), (436.0, 1.0), (450.0, 0.0)]);
    let rows = filtered(&[&flat, &shaped]);
    assert_eq!(rows.len(), 2);
    let band_mean = grid.iter().map(|(_, l)| l).sum::<f64>() / grid.len() as f64;
    let (name, centre, value) = &rows[0];
    assert!(name.ends_with("flat.csv"), "{name}");
    assert_eq!(*centre, 440.0);
    assert!(
        (value / band_mean - 1.0).abs() < 1e-8,
        "flat filter {value} against the band mean {band_mean}"
    );
    let weight: f64 = grid.iter().map(|(w, _)| triangle(*w)).sum();
    let weighted = grid.iter().map(|(w, l)| triangle(*w) * l).sum::<f64>() / weight;
    let (_, centre, value) = &rows[1];
    assert!(
        (centre - (430.0 + 436.0 + 450.0) / 3.0).abs() < 1e-4,
        "{centre}"
    );
    assert!(
        (value / weighted - 1.0).abs() < 1e-8,
        "triangle filter {value} against the weighted mean {weighted}"
    );
    // The sky is bluer at 430 than 450 nm (no Fraunhofer accident): a filter
    // leaning to the blue reads more than the flat one.
    assert!(rows[1].2 != rows[0].2);
}

#[test]
fn a_narrow_filter_reads_the_point_value() {
    // 1 nm wide at the base (0.5 nm at half maximum) around 545 nm, against
    // the one-point grid at 545 nm with a band of the filter's grid step
    // (0.05 nm): the spectrum is smooth on that scale (the solar table has
    // a row every nm, the ozone table every 10 nm away from 545).
    let (_dir, narrow) = filter_file("narrow.csv", &[(544.5, 0.0), (545.0, 1.0), (545.5, 0.0)]);
    let rows = filtered(&[&narrow]);
    let point = spectrum("545:545:0.05")[0].1;
    let value = rows[0].2;
    assert!(
        (value / point - 1.0).abs() < 1e-3,
        "narrow filter {value} against the point value {point}"
    );
}

#[test]
fn the_sun_photometer_channels_are_built_in() {
    let rows = filtered(&["cimel"]);
    let names: Vec<&str> = rows.iter().map(|(n, _, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "cimel-340",
            "cimel-380",
            "cimel-440",
            "cimel-500",
            "cimel-675",
            "cimel-870",
            "cimel-1020"
        ]
    );
    let centres: Vec<f64> = rows.iter().map(|(_, c, _)| *c).collect();
    assert_eq!(centres, [340.0, 380.0, 440.0, 500.0, 675.0, 870.0, 1020.0]);
    // The 440 nm channel, 10 nm wide, sees about the band's mean; its
    // Gaussian weighting leans on the middle: within 3 % of the 1-nm
    // grid's mean over 430-450 nm.
    let grid = spectrum("430:450:1");
    let band_mean = grid.iter().map(|(_, l)| l).sum::<f64>() / grid.len() as f64;
    let value = rows[2].2;
    assert!(
        (value / band_mean - 1.0).abs() < 0.03,
        "{value} {band_mean}"
    );
    // Rayleigh's blue sky: the radiance falls from 440 to 1020 nm.
    assert!(rows[2].2 > rows[4].2 && rows[4].2 > rows[5].2 && rows[5].2 > rows[6].2);
}

#[test]
fn irradiance_takes_filters() {
    let (_dir, flat) = filter_file("flat.csv", &[(430.0, 1.0), (450.0, 1.0)]);
    let run = |extra: &[&str]| {
        stdout(&sora(
            &[
                &[
                    "irradiance",
                    "--preset",
                    "earth-clear",
                    "--sun-elevation",
                    "30",
                    "--scattering",
                    "single",
                ][..],
                extra,
            ]
            .concat(),
        ))
    };
    let filtered = run(&["--filter", &flat]);
    let grid = run(&["--wavelengths", "430:450:1"]);
    let mut lines = filtered.lines();
    let header = lines.next().unwrap();
    assert!(
        header.starts_with("filter,centre_nm,direct_normal_irradiance_w_m2_nm,"),
        "{header}"
    );
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(lines.next(), None);
    let mut grid_lines = grid.lines();
    let grid_header: Vec<&str> = grid_lines.next().unwrap().split(',').collect();
    let grid_rows: Vec<Vec<f64>> = grid_lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(grid_rows.len(), 21);
    // Every quantity through the flat filter is its 1-nm grid's mean.
    for (k, name) in grid_header.iter().enumerate().skip(1) {
        let mean = grid_rows.iter().map(|r| r[k]).sum::<f64>() / 21.0;
        let value: f64 = row[k + 1].parse().unwrap();
        assert!((value / mean - 1.0).abs() < 1e-8, "{name}: {value} {mean}");
    }
}

#[test]
fn bad_filters_are_one_line_errors() {
    let run = |extra: &[&str]| one_line_error(&sora(&[&["spectrum"][..], &VIEW, extra].concat()));
    let message = run(&["--filter", "cimel-441"]);
    assert!(
        message.contains("cimel-441") && message.contains("cimel-440"),
        "{message}"
    );
    let (_dir, negative) = filter_file("negative.csv", &[(430.0, 1.0), (450.0, -0.2)]);
    let message = run(&["--filter", &negative]);
    assert!(
        message.contains("450 nm") && message.contains("-0.2"),
        "{message}"
    );
    let message = run(&["--filter", "/no/such/filter.csv"]);
    assert!(message.contains("/no/such/filter.csv"), "{message}");
    // A filter and a grid are two answers to one question.
    let out = sora(
        &[
            &["spectrum"][..],
            &VIEW,
            &["--filter", "cimel-440", "--wavelengths", "400:500:10"],
        ]
        .concat(),
    );
    assert_eq!(out.status.code(), Some(2), "{out:?}");
}

#[test]
fn many_directions_through_a_filter_as_csv_and_json() {
    let base = [
        "spectrum",
        "--preset",
        "earth-clear",
        "--sun-elevation",
        "30",
        "--sun-azimuth",
        "180",
        "--almucantar",
        "90",
        "--scattering",
        "single",
        "--filter",
        "cimel-870",
    ];
    let csv = stdout(&sora(&base));
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("view_elevation_deg,view_azimuth_deg,filter,centre_nm,radiance_w_m2_sr_nm")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4);
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(
            row[1].parse::<f64>().unwrap(),
            (180.0 + 90.0 * k as f64) % 360.0
        );
        assert_eq!((row[2], row[3]), ("cimel-870", "870.0000"));
    }
    let json = common::json(&sora(&[&base[..], &["--format", "json"]].concat()));
    assert_eq!(json["filter"], serde_json::json!(["cimel-870"]));
    let centre = common::numbers(&json["centre_nm"]);
    assert!(
        centre.len() == 1 && (centre[0] - 870.0).abs() < 1e-9,
        "{json}"
    );
    // The same radiances, one per direction, in the same order (the CSV's
    // to its ten significant digits).
    let directions = json["directions"].as_array().unwrap();
    assert_eq!(directions.len(), rows.len());
    for (direction, row) in directions.iter().zip(&rows) {
        let values = common::numbers(&direction["radiance_w_m2_sr_nm"]);
        let from_csv: f64 = row[4].parse().unwrap();
        assert!(values.len() == 1 && (values[0] / from_csv - 1.0).abs() < 6e-10);
    }
}
