//! `sora spectrum` and `sora render` on grids beyond the visible (280-2500
//! nm; issue 16 opened 300-1100): the sun-photometer grid runs, colour comes from its part
//! in 360-830 nm, a grid with no part there has no colour, and grids past
//! the range are refused with the value and its unit.

mod common;

use common::{one_line_error, sora, spectrum_rows, stdout};

const VIEW: [&str; 10] = [
    "--preset",
    "earth-clear",
    "--sun-elevation",
    "30",
    "--sun-azimuth",
    "180",
    "--view-elevation",
    "45",
    "--view-azimuth",
    "90",
];

#[test]
fn the_photometer_grid_gives_81_rows_and_the_colour_of_its_visible_part() {
    let out = sora(&[&["spectrum"][..], &VIEW, &["--wavelengths", "300:1100:10"]].concat());
    let rows = spectrum_rows(&stdout(&out));
    assert_eq!(rows.len(), 81);
    for (i, (wavelength, radiance)) in rows.iter().enumerate() {
        assert_eq!(*wavelength, 300.0 + 10.0 * i as f64);
        assert!(
            radiance.is_finite() && *radiance > 0.0,
            "{wavelength}: {radiance}"
        );
    }
    let at = |nm: f64| rows.iter().find(|(w, _)| *w == nm).unwrap().1;
    // Ozone's Hartley-Huggins edge darkens the ultraviolet sky by orders of
    // magnitude between 340 and 300 nm; in the infrared the sky fades as
    // Rayleigh scattering does (lambda^-4) with aerosol light added.
    assert!(at(300.0) < 1e-2 * at(340.0), "{} {}", at(300.0), at(340.0));
    assert!(at(1020.0) < at(870.0) && at(870.0) < at(670.0));
    // Colour: on stderr, from the 48 wavelengths in 360-830 nm.
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.starts_with("XYZ ")
            && stderr.contains("(colour from the 48 of 81 wavelengths in 360-830 nm)"),
        "{stderr}"
    );
    // A grid inside 360-830 nm prints its colour as it always did: no note.
    let out = sora(&[&["spectrum"][..], &VIEW, &["--wavelengths", "360:830:10"]].concat());
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.starts_with("XYZ ") && !stderr.contains("colour from"),
        "{stderr}"
    );
}

#[test]
fn an_infrared_grid_has_no_colour() {
    let out = sora(&[&["spectrum"][..], &VIEW, &["--wavelengths", "870:1020:150"]].concat());
    assert_eq!(spectrum_rows(&stdout(&out)).len(), 2);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains("no colour: no wavelength of 870:1020:150 lies in 360-830 nm"),
        "{stderr}"
    );
    let out = sora(
        &[
            &["spectrum"][..],
            &VIEW,
            &["--wavelengths", "870:1020:150", "--format", "json"],
        ]
        .concat(),
    );
    let json: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert!(
        json["xyz_w_m2_sr"].is_null() && json["linear_srgb_w_m2_sr"].is_null(),
        "{json}"
    );
    // An image needs colour: a one-line error, and no file.
    let dir = std::env::temp_dir().join(format!("sora-wide-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("infrared.png");
    let out = sora(&[
        "render",
        "--preset",
        "earth-clear",
        "--sun-elevation",
        "30",
        "--wavelengths",
        "870:1020:150",
        "--width",
        "16",
        "--height",
        "8",
        "-o",
        png.to_str().unwrap(),
    ]);
    let message = one_line_error(&out);
    assert!(message.contains("360-830 nm"), "{message}");
    assert!(!png.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn grids_past_280_to_2500_nm_are_refused_with_value_and_unit() {
    for (grid, expected) in [
        (
            "270:1100:10",
            "start_nm = 270 nm is out of range: allowed 280..=2500 nm",
        ),
        (
            "280:2510:10",
            "stop_nm = 2510 nm is out of range: allowed 280..=2500 nm",
        ),
    ] {
        let out = sora(&[&["spectrum"][..], &VIEW, &["--wavelengths", grid]].concat());
        // Out of range: status 1 and one line, whichever parser saw it.
        assert_eq!(out.status.code(), Some(1), "{grid}: {out:?}");
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(
            stderr.lines().next().unwrap().contains(expected),
            "{grid}: {stderr}"
        );
        assert!(out.stdout.is_empty());
    }
    // A table that stops short of a grid: a one-line error naming both
    // ranges (the paper's Mars dust indices cover 321-800 nm).
    let out = sora(&[
        "spectrum",
        "--preset",
        "paper-mars",
        "--sun-elevation",
        "30",
        "--view-elevation",
        "45",
        "--view-azimuth",
        "90",
        "--wavelengths",
        "300:1100:10",
    ]);
    let message = one_line_error(&out);
    assert!(
        message.contains("321-800 nm") && message.contains("300-1100 nm"),
        "{message}"
    );
}

/// The whole range, 300-2500 nm: the zenith sky of `earth-clear-summer`
/// (2.92 cm of water in `[gases]`) keeps under 1 % of the light of the same
/// sky without the gases (`earth-clear`) in the 1400 and 1900 nm water
/// bands and over half in the windows at 1600 and 2200 nm; colour still
/// comes from the samples in 360-830 nm.
#[test]
fn the_grid_reaches_2500_nm_with_the_water_bands_dark() {
    let zenith = |atmosphere: &str| {
        let out = common::zenith_spectrum(atmosphere, "300:2500:100", &[]);
        let stderr = String::from_utf8(out.stderr.clone()).unwrap();
        assert!(
            stderr.contains("colour from the 5 of 23 wavelengths in 360-830 nm"),
            "{stderr}"
        );
        let rows = spectrum_rows(&stdout(&out));
        assert_eq!(rows.len(), 23);
        assert_eq!(rows[22].0, 2500.0);
        assert!(rows.iter().all(|(_, l)| *l > 0.0), "{rows:?}");
        rows
    };
    let wet = zenith("../../atmospheres/earth-clear-summer.toml");
    let dry = zenith("../../atmospheres/earth-clear.toml");
    let kept = |nm: f64| {
        let i = ((nm - 300.0) / 100.0) as usize;
        wet[i].1 / dry[i].1
    };
    for nm in [1400.0, 1900.0] {
        assert!(kept(nm) < 0.01, "{nm} nm: {}", kept(nm));
    }
    for nm in [1600.0, 2200.0] {
        assert!(kept(nm) > 0.5, "{nm} nm: {}", kept(nm));
    }
}

/// The grid's short end, 280 nm, on the long-wave edge of ozone's Hartley
/// band: the zenith sky of `earth-clear` (sun 60 degrees) darkens by 16
/// orders of magnitude from 320 to 280 nm (10 of them from 290 to 280 nm),
/// as 300 DU of ozone go from 0.24 to 33 vertical optical depths, and
/// stays positive and finite; the direct beam's transmittance at 280 nm is
/// below 1e-15.
#[test]
fn the_grid_reaches_280_nm_where_the_hartley_band_darkens_the_sky() {
    let out = common::zenith_spectrum("../../atmospheres/earth-clear.toml", "280:320:10", &[]);
    let rows = spectrum_rows(&stdout(&out));
    assert_eq!(rows.len(), 5);
    assert_eq!(rows[0].0, 280.0);
    assert!(
        rows.iter().all(|(_, l)| l.is_finite() && *l > 0.0),
        "{rows:?}"
    );
    for pair in rows.windows(2) {
        let ratio = pair[1].1 / pair[0].1;
        assert!(ratio > 2.0, "{pair:?}: {ratio}");
    }
    assert!(rows[0].1 < 1e-8 * rows[1].1, "{rows:?}");
    assert!(rows[0].1 < 1e-14 * rows[4].1, "{rows:?}");
    let out = sora(&[
        "irradiance",
        "--atmosphere",
        "../../atmospheres/earth-clear.toml",
        "--sun-elevation",
        "60",
        "--wavelengths",
        "280:320:10",
    ]);
    let text = stdout(&out);
    let row_280 = text.lines().find(|l| l.starts_with("280,")).unwrap();
    let transmittance: f64 = row_280.split(',').nth(2).unwrap().parse().unwrap();
    assert!(transmittance > 0.0 && transmittance < 1e-15, "{row_280}");
}
