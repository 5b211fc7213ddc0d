//! A parametric aerosol with a tabulated phase function
//! (`phase.tabulated`, issue 35): tabulated from Henyey-Greenstein every
//! 0.25 deg, it gives the sky of the analytic Henyey-Greenstein species,
//! single and multiple scattering, to the table's interpolation error;
//! with the Rayleigh phase matrix tabulated (F12/F11, F33/F11, F34/F11),
//! the polarised sky of a Rayleigh scatterer.

use sora::atmosphere::Atmosphere;
use sora::spectrum::WavelengthGrid;
use sora::{Method, Polarisation, Scattering, Sky, ViewDirection};

const G: f64 = 0.7;

const HEADER: &str = r#"name = "tabulated phase"

[planet]
radius_m = 6360e3
atmosphere_height_m = 100e3
ground_albedo = 0.1

[sun]
spectrum = "flat"
irradiance_w_m2_nm = 1.0
"#;

fn atmosphere(phase: &str) -> Atmosphere {
    let text = format!(
        r#"{HEADER}
[[species]]
name = "air"
number_density_m3 = 2.545e25
profile.exponential.scale_height_m = 8000
scattering.rayleigh = {{ gas = "air", depolarization = true }}

[[species]]
name = "haze"
optical_depth = 0.3
reference_wavelength_nm = 550
profile.exponential.scale_height_m = 1200
scattering.parametric.angstrom_exponent = 1.3
scattering.parametric.single_scattering_albedo = 0.9
scattering.parametric.phase.{phase}
"#
    );
    Atmosphere::from_toml_str(&text).unwrap()
}

fn henyey_greenstein(cos_theta: f64) -> f64 {
    (1.0 - G * G) / (4.0 * std::f64::consts::PI * (1.0 + G * G - 2.0 * G * cos_theta).powf(1.5))
}

#[test]
fn a_tabulated_henyey_greenstein_gives_the_analytic_sky() {
    let angles: Vec<f64> = (0..=720).map(|i| i as f64 * 0.25).collect();
    let values: Vec<String> = angles
        .iter()
        .map(|a| format!("{:.12e}", henyey_greenstein(a.to_radians().cos())))
        .collect();
    let angles: Vec<String> = angles.iter().map(|a| a.to_string()).collect();
    let tabulated = atmosphere(&format!(
        "tabulated = {{ angle_deg = [{}], value = [{}] }}",
        angles.join(", "),
        values.join(", ")
    ));
    let analytic = atmosphere(&format!("henyey_greenstein.g = {G}"));
    let views: Vec<ViewDirection> = [
        (30.0, 185.0),
        (30.0, 210.0),
        (30.0, 300.0),
        (60.0, 0.0),
        (5.0, 90.0),
    ]
    .iter()
    .map(|&(e, a)| ViewDirection::new(e, a).unwrap())
    .collect();
    let mut worst: f64 = 0.0;
    for scattering in [Scattering::Single, Scattering::multiple()] {
        let radiances = |atmosphere: &Atmosphere| {
            Sky::builder(atmosphere)
                .sun_deg(30.0, 180.0)
                .wavelengths(WavelengthGrid::new(440.0, 870.0, 430.0).unwrap())
                .scattering(scattering)
                .method(Method::Fast)
                .polarisation(Polarisation::Scalar)
                .build()
                .unwrap()
                .radiances(&views)
                .unwrap()
        };
        for ((view, t), a) in views
            .iter()
            .zip(radiances(&tabulated))
            .zip(radiances(&analytic))
        {
            for (x, y) in t
                .radiance_w_m2_sr_nm
                .values()
                .iter()
                .zip(a.radiance_w_m2_sr_nm.values())
            {
                worst = worst.max((x / y - 1.0).abs());
                assert!(
                    (x / y - 1.0).abs() < 1e-4,
                    "{scattering:?} {view:?}: tabulated {x} against analytic {y}"
                );
            }
        }
    }
    eprintln!("worst relative difference {worst:.2e}");
}

#[test]
fn a_tabulated_phase_function_is_named_non_polarising() {
    let sky = Sky::builder(&atmosphere(
        "tabulated = { angle_deg = [0, 90, 180], value = [3, 1, 1] }",
    ))
    .sun_deg(30.0, 180.0)
    .polarisation(Polarisation::Vector)
    .build()
    .unwrap();
    assert_eq!(sky.non_polarising_species(), [("haze", "tabulated")]);
}

/// The polarised sky of a Rayleigh scatterer (depolarisation 0) and of an
/// aerosol with the same optical depths and the Rayleigh phase matrix
/// tabulated every 0.5 deg: the same radiance and degree of polarisation.
#[test]
fn a_tabulated_phase_matrix_polarises_as_the_function_it_was_tabulated_from() {
    let scale_height_m: f64 = 8000.0;
    let column_m = scale_height_m * (1.0 - (-100e3 / scale_height_m).exp());
    let optical_depth = 0.25;
    let rayleigh = Atmosphere::from_toml_str(&format!(
        r#"{HEADER}
[[species]]
name = "scatterer"
profile.exponential.scale_height_m = {scale_height_m}
scattering.rayleigh = {{ coefficient_per_m = {}, reference_wavelength_nm = 550 }}
"#,
        optical_depth / column_m
    ))
    .unwrap();
    let (mut angles, mut f11, mut f12, mut f33, mut f34) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for i in 0..=360 {
        let angle = i as f64 * 0.5;
        let mu = angle.to_radians().cos();
        angles.push(angle.to_string());
        f11.push(format!("{:.15e}", 1.0 + mu * mu));
        f12.push(format!("{:.15e}", -(1.0 - mu * mu) / (1.0 + mu * mu)));
        f33.push(format!("{:.15e}", 2.0 * mu / (1.0 + mu * mu)));
        f34.push("0".to_string());
    }
    let list = |v: &[String]| v.join(", ");
    let tabulated = Atmosphere::from_toml_str(&format!(
        r#"{HEADER}
[[species]]
name = "scatterer"
optical_depth = {optical_depth}
reference_wavelength_nm = 550
profile.exponential.scale_height_m = {scale_height_m}
scattering.parametric.angstrom_exponent = 4
scattering.parametric.single_scattering_albedo = 1
scattering.parametric.phase.tabulated = {{ angle_deg = [{}], value = [{}], f12_over_f11 = [{}], f33_over_f11 = [{}], f34_over_f11 = [{}] }}
"#,
        list(&angles),
        list(&f11),
        list(&f12),
        list(&f33),
        list(&f34)
    ))
    .unwrap();
    let views: Vec<ViewDirection> = [
        (30.0, 200.0),
        (30.0, 270.0),
        (60.0, 0.0),
        (89.0, 0.0),
        (10.0, 90.0),
    ]
    .iter()
    .map(|&(e, a)| ViewDirection::new(e, a).unwrap())
    .collect();
    let sky = |atmosphere: &Atmosphere| {
        Sky::builder(atmosphere)
            .sun_deg(30.0, 180.0)
            .wavelengths(WavelengthGrid::new(450.0, 650.0, 200.0).unwrap())
            .method(Method::Fast)
            .polarisation(Polarisation::Vector)
            .build()
            .unwrap()
    };
    let (a, b) = (sky(&rayleigh), sky(&tabulated));
    assert!(b.non_polarising_species().is_empty());
    let mut worst: (f64, f64) = (0.0, 0.0);
    for (view, (x, y)) in views.iter().zip(
        a.radiances(&views)
            .unwrap()
            .iter()
            .zip(b.radiances(&views).unwrap()),
    ) {
        let (sx, sy) = (x.stokes.as_ref().unwrap(), y.stokes.as_ref().unwrap());
        let (dx, dy) = (
            sx.degree_of_linear_polarisation(&x.radiance_w_m2_sr_nm),
            sy.degree_of_linear_polarisation(&y.radiance_w_m2_sr_nm),
        );
        for i in 0..2 {
            let (ix, iy) = (x.radiance_w_m2_sr_nm[i], y.radiance_w_m2_sr_nm[i]);
            worst.0 = worst.0.max((iy / ix - 1.0).abs());
            worst.1 = worst.1.max((dy[i] - dx[i]).abs());
            assert!(
                (iy / ix - 1.0).abs() < 1e-4,
                "{view:?}: I {iy} against {ix}"
            );
            assert!(
                (dy[i] - dx[i]).abs() < 1e-4,
                "{view:?}: DoLP {} against {}",
                dy[i],
                dx[i]
            );
        }
        // The sky is polarised (a Rayleigh sky at 90 deg from the sun).
        assert!(dx.iter().all(|d| *d > 0.05), "{view:?} {dx:?}");
    }
    eprintln!(
        "worst: radiance {:.2e}, degree of polarisation {:.2e}",
        worst.0, worst.1
    );
}
