//! Clear-sky broadband irradiance against pvlib's clear-sky models (Bird,
//! simplified Solis) for the same aerosol optical depth, water and ozone
//! (`earth-clear-summer`; the models' values computed once by
//! `scripts/gases/pvlib_clearsky.py` into
//! `tests/data/pvlib_clearsky_earth_clear_summer.csv`, with its inputs).
//! sora integrates `--broadband`'s grid, 300:2500:10 nm (95.8 % of the
//! sun's energy: its samples' bands span 295-2505 nm); the models the whole
//! spectrum (Bird takes 0.9662 of its sun for the direct beam).

mod common;

use common::{sora, stdout};

/// (GHI, DNI, DHI), W m^-2, of each model at `elevation`.
fn pvlib(elevation: f64) -> [[f64; 3]; 2] {
    let text =
        std::fs::read_to_string(common::data("pvlib_clearsky_earth_clear_summer.csv")).unwrap();
    let row: Vec<f64> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("sun_"))
        .map(|l| {
            l.split(',')
                .map(|v| v.parse().unwrap())
                .collect::<Vec<f64>>()
        })
        .find(|r| r[0] == elevation)
        .expect("the elevation's row");
    [[row[1], row[2], row[3]], [row[4], row[5], row[6]]]
}

/// The sun at 30 degrees (measured: sora GHI 472.3, DNI 774.1, DHI 85.2
/// W m^-2; Bird 474.6, 759.6, 94.8; Solis 459.8, 771.3, 82.7): global
/// within 3 % and direct normal within 2 % of both models, diffuse within
/// 10 % of Solis. Bird's diffuse is 10 % above sora's (its own
/// forward-scattering fraction, 0.85, not the aerosol's phase function);
/// the path tracer has not yet judged it.
#[test]
fn broadband_irradiance_at_sun_30_matches_pvlibs_clear_sky_models() {
    let table = stdout(&sora(&[
        "irradiance",
        "--atmosphere",
        "../../atmospheres/earth-clear-summer.toml",
        "--sun-elevation",
        "30",
        "--broadband",
        "--format",
        "table",
    ]));
    // --broadband's grid, 300:2500:10, and the sun's share in it (the
    // rest of the sun, 4.2 %, is outside what sora solves).
    assert!(table.contains("300 to 2500 nm"), "{table}");
    assert!(
        table.contains("extraterrestrial irradiance over 300-2500 nm: 1308.4390 W m^-2 (95.78 % of the sun's 1366.1 W m^-2"),
        "{table}"
    );
    let value = |name: &str| -> f64 {
        let line = table.lines().find(|l| l.starts_with(name)).expect(name);
        line[name.len()..]
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let sora = [
        value("global horizontal irradiance"),
        value("direct normal irradiance"),
        value("diffuse horizontal irradiance"),
    ];
    let [bird, solis] = pvlib(30.0);
    for (model, values) in [("Bird", bird), ("Solis", solis)] {
        let error = |k: usize| sora[k] / values[k] - 1.0;
        assert!(error(0).abs() < 0.03, "{model} GHI: {sora:?} vs {values:?}");
        assert!(error(1).abs() < 0.02, "{model} DNI: {sora:?} vs {values:?}");
    }
    assert!(
        (sora[2] / solis[2] - 1.0).abs() < 0.10,
        "Solis DHI: {sora:?} vs {solis:?}"
    );
}
