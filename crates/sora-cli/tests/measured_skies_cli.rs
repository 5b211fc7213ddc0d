//! docs/measured-skies.md: sora against Kider et al. (2014)'s clear skies
//! measured at Cornell (81 directions, 10-nm means; the data and their
//! provenance in `tests/data/measured/`). The page's recipe is found word
//! for word in the page, run, and its quoted numbers (sora / measured over
//! the 81 directions per wavelength, and over 360-1100 nm per direction)
//! recomputed from what `sora spectrum` prints and the shipped
//! measurements, to the digits the page gives.
//!
//! The test run by `cargo test` computes the table per wavelength as the
//! page does, one run per wavelength on a one-point grid (`W:W:10`, the
//! same 10-nm band as the grid point W of `360:1100:10`, whose values differ
//! from it by up to 0.3 %), for the preset and the page's aerosol-free
//! atmosphere; the table per direction needs the whole recipe, 75
//! wavelengths, and is the ignored test (about 5 CPU-minutes a capture in a
//! debug build):
//! `cargo test --release -p sora-cli --test measured_skies_cli -- --ignored`.
//! When the sky's numbers change on purpose, rerun the page's recipe and
//! update its tables and pictures.

mod common;

use common::{sora, stdout};

/// (the page's label, the data file's stem, `--time`).
const CAPTURES: [(&str, &str, &str); 2] = [
    (
        "2013-05-27 12:00 EDT",
        "2013-05-27_120000",
        "2013-05-27T12:00:00-04:00",
    ),
    (
        "2013-09-24 13:10 EDT",
        "2013-09-24_131000",
        "2013-09-24T13:10:00-04:00",
    ),
];

const DIRECTIONS: &str = "crates/sora-cli/tests/data/measured/kider2014_directions.csv";

fn repository_file(path: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path)
}

fn page() -> String {
    std::fs::read_to_string(repository_file("docs/measured-skies.md")).unwrap()
}

/// One shipped scan: per direction (the archive's order) its elevation,
/// sora's azimuth, and the radiance at each of `wavelengths_nm`.
struct Scan {
    elevation_deg: Vec<f64>,
    azimuth_deg: Vec<f64>,
    wavelengths_nm: Vec<f64>,
    radiance: Vec<Vec<f64>>,
}

fn measured(stem: &str) -> Scan {
    let text = std::fs::read_to_string(common::data(&format!("measured/{stem}.csv"))).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header[..4],
        [
            "index",
            "view_elevation_deg",
            "file_azimuth_deg",
            "view_azimuth_deg"
        ]
    );
    let wavelengths_nm: Vec<f64> = header[4..]
        .iter()
        .map(|h| h.strip_prefix('L').unwrap().parse().unwrap())
        .collect();
    let expected: Vec<f64> = (0..75).map(|i| 360.0 + 10.0 * f64::from(i)).collect();
    assert_eq!(wavelengths_nm, expected, "{stem}: 360-1100 nm every 10 nm");
    let mut scan = Scan {
        elevation_deg: vec![],
        azimuth_deg: vec![],
        wavelengths_nm,
        radiance: vec![],
    };
    for (index, line) in lines.enumerate() {
        let row: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
        assert_eq!(row.len(), 4 + scan.wavelengths_nm.len(), "{stem}: {line}");
        assert_eq!(row[0], index as f64, "{stem}: the archive's order");
        // sora's azimuth is the archive's, mirrored (the data's README).
        assert_eq!(row[3], (360.0 - row[2]).rem_euclid(360.0), "{stem}: {line}");
        assert!(
            row[4..].iter().all(|&l| l > 0.0 && l < 1.0),
            "{stem}: {line}"
        );
        scan.elevation_deg.push(row[1]);
        scan.azimuth_deg.push(row[3]);
        scan.radiance.push(row[4..].to_vec());
    }
    assert_eq!(scan.elevation_deg.len(), 81, "{stem}: 81 directions");
    scan
}

/// The page's command for the capture at `time`, found in the page.
fn page_command(time: &str) -> String {
    let command = format!(
        "sora spectrum --preset earth-clear-summer --location 42.443449,-76.481962,325 \
         --time {time} --directions {DIRECTIONS} --wavelengths 360:1100:10"
    );
    let page = page();
    let flat = page.replace("\\\n", " ");
    let flat = flat.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        flat.contains(&command),
        "docs/measured-skies.md does not give: {command}"
    );
    command
}

const NO_AEROSOL: &str = "crates/sora-cli/tests/data/measured/earth-clear-summer-no-aerosol.toml";

/// Runs the page's command with `grid` as its `--wavelengths` (and, with
/// `no_aerosol`, the page's aerosol-free atmosphere instead of the preset)
/// and returns sora's radiances in the directions file's order, per
/// wavelength of `wavelengths_nm`, checking the directions.
fn modelled(
    time: &str,
    grid: &str,
    no_aerosol: bool,
    scan: &Scan,
    wavelengths_nm: &[f64],
) -> Vec<Vec<f64>> {
    let mut command = page_command(time).replace("360:1100:10", grid);
    if no_aerosol {
        let with = format!("--atmosphere {NO_AEROSOL}");
        assert!(
            page().contains(&with),
            "docs/measured-skies.md does not give {with}"
        );
        command = command.replace("--preset earth-clear-summer", &with);
    }
    let args: Vec<String> = command
        .split_whitespace()
        .skip(1)
        .map(|a| {
            if a == DIRECTIONS || a == NO_AEROSOL {
                repository_file(a).display().to_string()
            } else {
                a.to_string()
            }
        })
        .collect();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let csv = stdout(&sora(&args));
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("view_elevation_deg,view_azimuth_deg,wavelength_nm,radiance_w_m2_sr_nm")
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 81 * wavelengths_nm.len(), "{command}");
    rows.chunks(wavelengths_nm.len())
        .enumerate()
        .map(|(d, chunk)| {
            for (row, w) in chunk.iter().zip(wavelengths_nm) {
                assert!((row[0] - scan.elevation_deg[d]).abs() < 1e-9, "{row:?}");
                assert!((row[1] - scan.azimuth_deg[d]).abs() < 1e-9, "{row:?}");
                assert!((row[2] - w).abs() < 1e-9, "{row:?}");
            }
            chunk.iter().map(|row| row[3]).collect()
        })
        .collect()
}

/// Mean of the ratios, rms of (ratio - 1) and rms of (ratio / mean - 1).
fn statistics(ratios: &[f64]) -> [f64; 3] {
    let n = ratios.len() as f64;
    let mean = ratios.iter().sum::<f64>() / n;
    let rms =
        |f: &dyn Fn(f64) -> f64| (ratios.iter().map(|&r| f(r).powi(2)).sum::<f64>() / n).sqrt();
    [mean, rms(&|r| r - 1.0), rms(&|r| r / mean - 1.0)]
}

/// The rows of the page's tables for `label` with `cells` cells: the cells
/// after the label as numbers (a trailing " %" dropped) with each one's
/// number of decimals.
fn quoted_rows(label: &str, cells: usize) -> Vec<Vec<(f64, usize)>> {
    page()
        .lines()
        .filter(|l| l.starts_with(&format!("| {label} |")))
        .map(|l| {
            l.trim_matches('|')
                .split('|')
                .map(str::trim)
                .collect::<Vec<_>>()
        })
        .filter(|c| c.len() == cells)
        .map(|c| {
            c[1..]
                .iter()
                .map(|cell| {
                    let number = cell.trim_end_matches('%').trim();
                    let decimals = number.split_once('.').map_or(0, |(_, d)| d.len());
                    (number.parse().unwrap(), decimals)
                })
                .collect()
        })
        .collect()
}

/// Asserts `computed` rounds to the page's `quoted` number (a fraction
/// quoted in % when `percent`).
fn assert_quoted(computed: f64, (quoted, decimals): (f64, usize), percent: bool, what: &str) {
    let value = if percent { 100.0 * computed } else { computed };
    let half_digit = 0.5 * 10f64.powi(-(decimals as i32));
    assert!(
        (value - quoted).abs() <= half_digit + 1e-9,
        "{what}: sora and the measurement give {value:.5}, the page says {quoted}"
    );
}

/// Checks the page's rows per wavelength for `label` (wavelength, mean of
/// sora / measured, rms, rms after the mean, and in the preset's table the
/// number of directions whose measured radiance lies between the two skies)
/// against `model` and `no_aerosol` (the aerosol-free sky) at
/// `wavelengths_nm`.
fn check_wavelength_table(
    label: &str,
    scan: &Scan,
    wavelengths_nm: &[f64],
    model: &[Vec<f64>],
    no_aerosol: &[Vec<f64>],
) {
    let rows = quoted_rows(label, 6);
    assert_eq!(rows.len(), 4, "{label}: four wavelengths on the page");
    let free_label = format!("{label}, no aerosol");
    let free_rows = quoted_rows(&free_label, 5);
    assert_eq!(
        free_rows.len(),
        4,
        "{free_label}: four wavelengths on the page"
    );
    for (row, free_row) in rows.iter().zip(&free_rows) {
        let w = row[0].0;
        assert_eq!(free_row[0].0, w, "{label}: the two tables' wavelengths");
        let k = wavelengths_nm.iter().position(|&x| x == w).unwrap();
        let j = scan.wavelengths_nm.iter().position(|&x| x == w).unwrap();
        let what = format!("{label}, {w} nm");
        let check = |sky: &[Vec<f64>], row: &[(f64, usize)], what: &str| {
            let ratios: Vec<f64> = (0..81).map(|d| sky[d][k] / scan.radiance[d][j]).collect();
            let [mean, rms, shape] = statistics(&ratios);
            assert_quoted(mean, row[1], false, &format!("{what}, mean"));
            assert_quoted(rms, row[2], true, &format!("{what}, rms"));
            assert_quoted(shape, row[3], true, &format!("{what}, rms after the mean"));
        };
        check(model, row, &what);
        check(no_aerosol, free_row, &format!("{what}, no aerosol"));
        let between = (0..81)
            .filter(|&d| {
                let (a, b) = (model[d][k], no_aerosol[d][k]);
                let l = scan.radiance[d][j];
                a.min(b) <= l && l <= a.max(b)
            })
            .count();
        assert_quoted(between as f64, row[4], false, &format!("{what}, between"));
    }
}

#[test]
fn the_pages_numbers_per_wavelength_are_what_sora_and_the_measurements_give() {
    for (label, stem, time) in CAPTURES {
        let scan = measured(stem);
        let wavelengths: Vec<f64> = quoted_rows(label, 6).iter().map(|r| r[0].0).collect();
        assert_eq!(
            wavelengths.len(),
            4,
            "{label}: four wavelengths on the page"
        );
        // One run per wavelength, a one-point grid with the 10-nm band.
        let sky = |no_aerosol: bool| -> Vec<Vec<f64>> {
            let per_wavelength: Vec<Vec<Vec<f64>>> = wavelengths
                .iter()
                .map(|w| modelled(time, &format!("{w}:{w}:10"), no_aerosol, &scan, &[*w]))
                .collect();
            (0..81)
                .map(|d| per_wavelength.iter().map(|m| m[d][0]).collect())
                .collect()
        };
        let (model, free) = (sky(false), sky(true));
        check_wavelength_table(label, &scan, &wavelengths, &model, &free);
    }
}

/// The whole recipe, 75 wavelengths: the table per direction.
#[test]
#[ignore = "about 5 CPU-minutes a capture in a debug build: run with --release -- --ignored"]
fn the_pages_whole_recipe_gives_its_numbers() {
    for (label, stem, time) in CAPTURES {
        let scan = measured(stem);
        let model = modelled(time, "360:1100:10", false, &scan, &scan.wavelengths_nm);
        let rows = quoted_rows(label, 7);
        assert_eq!(rows.len(), 4, "{label}: four directions on the page");
        for row in rows {
            let d = row[0].0 as usize;
            assert_quoted(scan.elevation_deg[d], row[1], false, "elevation");
            assert_quoted(scan.azimuth_deg[d], row[2], false, "azimuth");
            let ratios: Vec<f64> = (0..scan.wavelengths_nm.len())
                .map(|j| model[d][j] / scan.radiance[d][j])
                .collect();
            let [mean, rms, shape] = statistics(&ratios);
            let what = format!("{label}, direction {d}");
            assert_quoted(mean, row[3], false, &format!("{what}, mean"));
            assert_quoted(rms, row[4], true, &format!("{what}, rms"));
            assert_quoted(shape, row[5], true, &format!("{what}, rms after the mean"));
        }
    }
}
