//! The sky above a raised ground (`planet.ground_altitude_m`, the CLI's
//! `--location LAT,LON,ELEV`): the sea-level atmosphere with everything
//! below the ground taken away, against the same atmosphere written by hand
//! for the site, and the air's optical depth against the standard
//! atmosphere's surface pressure.

use sora::spectrum::WavelengthGrid;
use sora::{Atmosphere, Sky, ViewDirection};

/// A site at the height of a sun photometer network site (1 449 m).
const SITE_M: f64 = 1449.0;

const EARTH_CLEAR: &str = include_str!("../../../atmospheres/earth-clear.toml");

/// earth-clear with its ground at `SITE_M`, by the key.
fn raised() -> Atmosphere {
    let text = EARTH_CLEAR.replace(
        "atmosphere_height_m = 100e3",
        &format!("atmosphere_height_m = 100e3\nground_altitude_m = {SITE_M}"),
    );
    Atmosphere::from_toml_str(&text).unwrap()
}

/// earth-clear as seen from `SITE_M`, written by hand: the planet's radius
/// at the site, the air above it, each profile's altitudes from the site
/// and each amount what lies above it.
fn by_hand() -> Atmosphere {
    let top = 100e3;
    // An exponential layer of scale height h keeps exp(-g / h) of its
    // density, and of its column to the top the part above the ground.
    let kept_column = |h: f64| {
        (-SITE_M / h).exp() * (1.0 - (-(top - SITE_M) / h).exp()) / (1.0 - (-top / h).exp())
    };
    let text = EARTH_CLEAR
        .replace(
            "radius_m = 6360e3",
            &format!("radius_m = {:e}", 6360e3 + SITE_M),
        )
        .replace(
            "atmosphere_height_m = 100e3",
            &format!("atmosphere_height_m = {:e}", top - SITE_M),
        )
        .replace(
            "number_density_m3 = 2.546899e25",
            &format!(
                "number_density_m3 = {:e}",
                2.546899e25 * (-SITE_M / 8435.0).exp()
            ),
        )
        .replace(
            "peak_altitude_m = 25e3",
            &format!("peak_altitude_m = {:e}", 25e3 - SITE_M),
        )
        .replace(
            "optical_depth = 0.1",
            &format!("optical_depth = {:e}", 0.1 * kept_column(1200.0)),
        );
    Atmosphere::from_toml_str(&text).unwrap()
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

#[test]
fn a_raised_ground_has_the_optics_of_the_atmosphere_above_it() {
    let grid = WavelengthGrid::new(380.0, 780.0, 100.0).unwrap();
    let (site, hand) = (
        raised().compute_optics(&grid).unwrap(),
        by_hand().compute_optics(&grid).unwrap(),
    );
    let (site_tau, hand_tau) = (
        site.total_optical_depth_extinction(),
        hand.total_optical_depth_extinction(),
    );
    for (a, b) in site_tau.values().iter().zip(hand_tau.values()) {
        assert!(relative(*a, *b) < 1e-12, "{a} {b}");
    }
    // And less than at sea level: the air's column by exp(-g / H).
    let sea = Atmosphere::from_toml_str(EARTH_CLEAR)
        .unwrap()
        .compute_optics(&grid)
        .unwrap();
    let air = |optics: &sora::atmosphere::AtmosphereOptics| {
        optics.species[0].optical_depth_extinction()[0]
    };
    let ratio = air(&site) / air(&sea);
    let expected = (-SITE_M / 8435.0).exp() * (1.0 - (-(100e3 - SITE_M) / 8435.0).exp())
        / (1.0 - (-100e3_f64 / 8435.0).exp());
    assert!(relative(ratio, expected) < 1e-12, "{ratio} {expected}");
}

#[test]
fn a_sky_from_a_raised_ground_is_the_sea_level_sky_without_what_lies_below() {
    let views = [
        ViewDirection::new(90.0, 0.0).unwrap(),
        ViewDirection::new(20.0, 0.0).unwrap(),
        ViewDirection::new(5.0, 180.0).unwrap(),
        ViewDirection::new(-10.0, 90.0).unwrap(),
    ];
    let grid = WavelengthGrid::new(400.0, 700.0, 150.0).unwrap();
    for sun_elevation in [30.0, 4.0] {
        let radiances = |atmosphere: &Atmosphere| {
            Sky::builder(atmosphere)
                .sun_deg(sun_elevation, 180.0)
                .wavelengths(grid)
                .polarisation(sora::Polarisation::Scalar)
                .build()
                .unwrap()
                .radiances(&views)
                .unwrap()
        };
        let (site, hand) = (radiances(&raised()), radiances(&by_hand()));
        for (a, b) in site.iter().zip(&hand) {
            for (x, y) in a
                .radiance_w_m2_sr_nm
                .values()
                .iter()
                .zip(b.radiance_w_m2_sr_nm.values())
            {
                assert!(relative(*x, *y) < 1e-6, "sun {sun_elevation}: {x} {y}");
            }
        }
    }
}

#[test]
fn the_airs_optical_depth_at_a_site_follows_the_standard_atmospheres_pressure() {
    // The U.S. Standard Atmosphere 1976 (its density table) at sea level
    // and from 1 449 m: Rayleigh optical depth in proportion to the
    // surface pressure, 1013.25 (1 - 0.0065 z / 288.15)^5.25588 hPa.
    let text = include_str!("../../../atmospheres/us-standard-1976-rayleigh.toml");
    let sea = Atmosphere::from_toml_str(text).unwrap();
    let mut site = sea.clone();
    site.planet = site.planet.with_ground_altitude_m(SITE_M).unwrap();
    let grid = WavelengthGrid::new(550.0, 550.0, 1.0).unwrap();
    let tau = |a: &Atmosphere| {
        a.compute_optics(&grid)
            .unwrap()
            .total_optical_depth_extinction()[0]
    };
    let pressure_ratio = (1.0 - 0.0065 * SITE_M / 288.15).powf(5.25588);
    let ratio = tau(&site) / tau(&sea);
    // Density, not pressure, is tabulated: the table's own interpolation
    // between its rows is what the tolerance allows for.
    assert!(
        relative(ratio, pressure_ratio) < 2e-3,
        "{ratio} {pressure_ratio}"
    );
}

#[test]
fn a_ground_above_the_air_is_a_one_line_error() {
    let text = EARTH_CLEAR.replace(
        "atmosphere_height_m = 100e3",
        "atmosphere_height_m = 100e3\nground_altitude_m = 99500",
    );
    let message = Atmosphere::from_toml_str(&text).unwrap_err().to_string();
    assert!(
        message.contains("planet.ground_altitude_m = 99500 m") && !message.contains('\n'),
        "{message}"
    );
}
