//! Single scattering against closed forms and symmetries that need no
//! reference data.

use crate::atmosphere::Atmosphere;
use crate::geometry::direction_from_elevation_azimuth;
use crate::spectrum::{SampledSpectrum, WavelengthGrid};
use crate::transport::{Observation, SingleScatteringScene, SunColumns};

/// Pure Rayleigh air, exponential with an 8 km scale height, flat sun of
/// 1 W m^-2 nm^-1, black ground.
const RAYLEIGH_ONLY: &str = r#"
name = "pure Rayleigh, exponential"
[planet]
radius_m = 6360e3
atmosphere_height_m = 100e3
ground_albedo = 0.0
[sun]
spectrum = "flat"
irradiance_w_m2_nm = 1.0
angular_diameter_deg = 0.0
[[species]]
name = "air"
profile.exponential.scale_height_m = 8000
scattering.rayleigh = { coefficient_per_m = 1.16e-5, reference_wavelength_nm = 550, wavelength_exponent = 4.0 }
"#;

fn sky(text: &str, sun_elevation_deg: f64, sun_azimuth_deg: f64) -> SingleScatteringScene {
    let atmosphere = Atmosphere::from_toml_str(text).unwrap();
    let observation = Observation {
        observer_altitude_m: 0.0,
        sun_elevation_deg,
        sun_azimuth_deg,
    };
    SingleScatteringScene::new(&atmosphere, &WavelengthGrid::paper(), observation).unwrap()
}

fn fast(sky: &SingleScatteringScene, elevation: f64, azimuth: f64) -> SampledSpectrum {
    let mut scratch = sky.scratch();
    let mut radiance = SampledSpectrum::zeros(sky.optics().grid.len());
    sky.compute_radiance(
        direction_from_elevation_azimuth(elevation, azimuth),
        SunColumns::Exact,
        &mut scratch,
        &mut radiance,
    );
    radiance
}

/// Sun at the zenith, looking straight up: at height h the view path's
/// optical depth beta H (1 - e^{-h/H}) and the sun path's
/// beta H (e^{-h/H} - e^{-top/H}) add up to the whole column tau, so
/// L = E p(0) integral beta e^{-h/H} e^{-tau} dh = E p(0) tau e^{-tau},
/// with p(0) = 3 / (8 pi) for Rayleigh scattering.
#[test]
fn zenith_sky_under_a_zenith_sun_is_e_p_tau_exp_minus_tau() {
    let sky = sky(RAYLEIGH_ONLY, 90.0, 0.0);
    let fast = fast(&sky, 90.0, 0.0);
    let reference =
        sky.compute_radiance_reference(direction_from_elevation_azimuth(90.0, 0.0), 4000, 800);
    let column_m = 8000.0 * (1.0 - (-100e3f64 / 8000.0).exp());
    for (i, wavelength) in WavelengthGrid::paper().wavelengths_nm().enumerate() {
        let tau = 1.16e-5 * (550.0 / wavelength).powi(4) * column_m;
        let expected = 3.0 / (8.0 * std::f64::consts::PI) * tau * (-tau).exp();
        assert!(
            (fast[i] / expected - 1.0).abs() < 1e-3,
            "{wavelength} nm fast {} vs {expected}",
            fast[i]
        );
        assert!(
            (reference[i] / expected - 1.0).abs() < 1e-3,
            "{wavelength} nm reference {} vs {expected}",
            reference[i]
        );
    }
}

#[test]
fn the_sky_is_symmetric_about_the_solar_meridian() {
    let sky = sky(
        include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/atmosphere_clear-sky-reference.toml"
        )),
        25.0,
        207.0,
    );
    for (elevation, offset) in [
        (0.5, 10.0),
        (17.0, 140.0),
        (45.0, 3.0),
        (-5.0, 60.0),
        (80.0, 179.0),
    ] {
        let left = fast(&sky, elevation, 207.0 - offset);
        let right = fast(&sky, elevation, 207.0 + offset);
        for (l, r) in left.values().iter().zip(right.values()) {
            assert!(
                (l - r).abs() <= 1e-9 * l.abs().max(r.abs()),
                "elevation {elevation} offset {offset}: {l} vs {r}"
            );
        }
        let left = sky.compute_radiance_reference(
            direction_from_elevation_azimuth(elevation, 207.0 - offset),
            400,
            100,
        );
        let right = sky.compute_radiance_reference(
            direction_from_elevation_azimuth(elevation, 207.0 + offset),
            400,
            100,
        );
        for (l, r) in left.values().iter().zip(right.values()) {
            assert!(
                (l - r).abs() <= 1e-9 * l.abs().max(r.abs()),
                "reference, elevation {elevation} offset {offset}: {l} vs {r}"
            );
        }
    }
}

/// With the sun at the nadir, every point above the observer is in the
/// planet's shadow: single scattering gives exactly nothing.
#[test]
fn the_planets_shadow_is_dark() {
    let night = sky(
        include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/atmosphere_clear-sky-reference.toml"
        )),
        -90.0,
        0.0,
    );
    for (elevation, azimuth) in [(90.0, 0.0), (45.0, 123.0), (5.0, 300.0)] {
        assert!(
            fast(&night, elevation, azimuth)
                .values()
                .iter()
                .all(|v| *v == 0.0)
        );
        let reference = night.compute_radiance_reference(
            direction_from_elevation_azimuth(elevation, azimuth),
            200,
            50,
        );
        assert!(reference.values().iter().all(|v| *v == 0.0));
    }
    // Twilight, sun 10 degrees below the horizon: over the observer the
    // sun's rays clear the ground only above R (1 / cos 10 deg - 1) = 98 km,
    // so the zenith sky is lit in the last 2 km below the top: faint, not
    // zero.
    let clear_sky = include_str!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/atmosphere_clear-sky-reference.toml"
    ));
    let twilight = fast(&sky(clear_sky, -10.0, 0.0), 90.0, 0.0);
    let sunset = fast(&sky(clear_sky, 0.0, 0.0), 90.0, 0.0);
    for (t, s) in twilight.values().iter().zip(sunset.values()) {
        assert!(*t > 0.0 && *t < 1e-3 * s, "{t} vs {s}");
    }
}

/// The sun's disc is seen only along rays that reach space. From 1 km the
/// ground's horizon dips acos(R / (R + h)) = 1.01 deg below the
/// horizontal, so a sun at -0.5 deg is still seen there, one at -3 deg is
/// not, and from the ground one at -2 deg is not.
#[test]
fn the_sun_disc_is_never_drawn_on_the_ground() {
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    for (altitude, sun_elevation, visible) in [
        (0.0, -2.0, false),
        (1000.0, -3.0, false),
        (1000.0, -0.5, true),
        (0.0, 10.0, true),
    ] {
        let observation = Observation {
            observer_altitude_m: altitude,
            sun_elevation_deg: sun_elevation,
            sun_azimuth_deg: 270.0,
        };
        let sky =
            SingleScatteringScene::new(&atmosphere, &WavelengthGrid::paper(), observation).unwrap();
        assert_eq!(
            sky.is_in_sun_disc(sky.sun_direction()),
            visible,
            "altitude {altitude} m, sun {sun_elevation} deg"
        );
    }
}
