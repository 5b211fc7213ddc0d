//! The polarised path tracer (issue 13) against closed forms and the
//! Coulson tables.
//!
//! - **Single scattering**, closed forms: in a Rayleigh layer thin enough
//!   that multiple scattering is below 1e-4 of the light, the degree of
//!   linear polarisation is (1 - mu^2) / (1 + mu^2) of the scattering angle
//!   (mu its cosine), (1 - rho) / (1 + rho) at 90 degrees with a
//!   depolarisation ratio rho, and the light is polarised perpendicular to
//!   the plane through the sun, the eye and the view.
//! - **All orders**: I, Q, U reflected to the top of a plane-parallel
//!   Rayleigh layer (optical depth 0.5, sun at mu0 = 0.2, ground albedo 0
//!   and 0.8) against the corrected Coulson, Dave & Sekera tables of
//!   Natraj, Li & Yung (2009), `tests/data/coulson_rayleigh_toa.csv`.
//! - Non-polarising species leave the scalar result unchanged.

use super::reference_data::coulson_table;
use crate::atmosphere::{Atmosphere, Planet};
use crate::geometry::direction_from_elevation_azimuth;
use crate::spectrum::{Spectrum, WavelengthGrid};
use crate::transport::stokes::meridian_reference;
use crate::transport::{Observation, PathTracer, SingleScatteringScene};

/// A pure Rayleigh layer of vertical optical depth `tau` at 550 nm
/// (exponential, scale height `top_m` / 12.5, top at `top_m`),
/// depolarisation `rho`, a flat sun of irradiance `irradiance`, on a
/// planet of `radius_m` with a ground of albedo `albedo`.
fn rayleigh_layer(
    tau: f64,
    rho: f64,
    irradiance: f64,
    (radius_m, top_m): (f64, f64),
    albedo: f64,
) -> Atmosphere {
    let scale_height_m = top_m / 12.5;
    let coefficient = tau / (scale_height_m * (1.0 - (-12.5f64).exp()));
    let text = format!(
        r#"
name = "Rayleigh layer"
[planet]
radius_m = {radius_m:e}
atmosphere_height_m = {top_m:e}
ground_albedo = 0.0
[sun]
spectrum = "flat"
irradiance_w_m2_nm = {irradiance:e}
angular_diameter_deg = 0.0
[[species]]
name = "air"
profile.exponential.scale_height_m = {scale_height_m:e}
scattering.rayleigh = {{ coefficient_per_m = {coefficient:e}, reference_wavelength_nm = 550, wavelength_exponent = 4.0, depolarization_ratio = {rho} }}
"#
    );
    let mut atmosphere = Atmosphere::from_toml_str(&text).unwrap();
    atmosphere.planet = Planet::new(radius_m, top_m, Spectrum::Constant(albedo)).unwrap();
    atmosphere
}

/// An Earth-sized planet with a 100 km atmosphere, m.
const EARTH: (f64, f64) = (6.36e6, 100e3);

/// The plane-parallel limit: a planet of radius 6.36e9 m (the largest an
/// atmosphere file takes) under a layer 1 km thick. The light of a grazing
/// view (mu = 0.02) crosses 50 km of it, over which the local vertical
/// turns by 50 km / 6.36e9 m = 8e-6 rad, 4e-4 of mu: the tables' numbers
/// stay plane-parallel to well below the Monte Carlo noise (a 100 km
/// layer would turn mu by 4 % and put the grazing rows 5 standard errors
/// off).
const PLANE_PARALLEL: (f64, f64) = (6.36e9, 1e3);

fn scene(atmosphere: &Atmosphere, altitude_m: f64, sun: (f64, f64)) -> SingleScatteringScene {
    let observation = Observation {
        observer_altitude_m: altitude_m,
        sun_elevation_deg: sun.0,
        sun_azimuth_deg: sun.1,
    };
    let grid = WavelengthGrid::new(550.0, 550.0, 20.0).unwrap();
    SingleScatteringScene::new(atmosphere, &grid, observation).unwrap()
}

/// (I, Q, U, V) and their standard errors at 550 nm of the view
/// (elevation, azimuth), referred to its meridian plane.
fn stokes(
    scene: &SingleScatteringScene,
    view: (f64, f64),
    samples: u64,
    seed: u64,
) -> ([f64; 4], [f64; 4]) {
    let (stokes, errors, _) = stokes_and_scalar(scene, view, samples, seed);
    (stokes, errors)
}

/// [`stokes`], and the scalar estimate of the same paths.
fn stokes_and_scalar(
    scene: &SingleScatteringScene,
    view: (f64, f64),
    samples: u64,
    seed: u64,
) -> ([f64; 4], [f64; 4], f64) {
    let tracer = PathTracer::new_polarised(scene).unwrap();
    let traced = tracer
        .compute_stokes_with_progress(
            direction_from_elevation_azimuth(view.0, view.1),
            meridian_reference(view.0, view.1),
            samples,
            seed,
            &|_| {},
        )
        .unwrap();
    let parts = traced.stokes.unwrap();
    (
        parts.each_ref().map(|p| p.mean[0]),
        parts.each_ref().map(|p| p.standard_error[0]),
        traced.total.mean[0],
    )
}

/// The angle of polarisation 0.5 atan2(U, Q) in (-90, 90], degrees.
fn angle_deg(q: f64, u: f64) -> f64 {
    let angle = 0.5 * u.atan2(q).to_degrees();
    if angle <= -90.0 { angle + 180.0 } else { angle }
}

/// The standard error of the angle of polarisation 0.5 atan2(U, Q),
/// degrees, from those of Q and U (`q_u_errors`) by first-order
/// propagation: 0.5 sqrt(U^2 s_Q^2 + Q^2 s_U^2) / (Q^2 + U^2) rad.
fn angle_standard_error_deg((q, u): (f64, f64), (q_error, u_error): (f64, f64)) -> f64 {
    (0.5 * (u * q_error).hypot(q * u_error) / (q * q + u * u)).to_degrees()
}

/// The difference of two angles of polarisation (modulo 180), degrees.
fn angle_difference_deg(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(180.0);
    d.min(180.0 - d)
}

#[test]
fn thin_rayleigh_single_scattering_has_the_closed_form_polarisation() {
    // tau = 1e-5: light scattered twice is at most ~1e-4 of the total (at
    // 5 degrees elevation), so the degree of polarisation is the
    // single-scattering one to ~1e-4 (and,
    // the scattering angle being the same along the whole view ray for a
    // parallel sun, every path's first-order estimate has it exactly).
    let sun = (30.0, 180.0);
    let s = direction_from_elevation_azimuth(sun.0, sun.1);
    for rho in [0.0, 0.1] {
        let atmosphere = rayleigh_layer(1e-5, rho, 1.0, EARTH, 0.0);
        let scene = scene(&atmosphere, 0.0, sun);
        for view in [
            (90.0, 0.0),
            (30.0, 0.0),
            (10.0, 90.0),
            (45.0, 300.0),
            (60.0, 170.0),
            (5.0, 225.0),
        ] {
            let (stokes, _) = stokes(&scene, view, 2_000, 1);
            let w = direction_from_elevation_azimuth(view.0, view.1);
            let mu = w.dot(s);
            let d = (1.0 - rho) / (1.0 + 0.5 * rho);
            // -b1 / a1 of the Rayleigh matrix (Hansen & Travis 1974, eq. 2.15).
            let expected = 0.75 * d * (1.0 - mu * mu) / (0.75 * d * (1.0 + mu * mu) + 1.0 - d);
            let degree = stokes[1].hypot(stokes[2]) / stokes[0];
            assert!(
                (degree - expected).abs() < 5e-4,
                "rho {rho} view {view:?}: degree {degree}, closed form {expected}"
            );
            // The field is perpendicular to the plane of the sun, the eye
            // and the view: along n = k_in x k_out, in the eye's frame
            // (e_l = meridian reference, e_r = k x e_l with k = -w).
            let (k_in, k_out) = (-s, -w);
            let n = k_in.cross(k_out).normalized();
            let e_l = meridian_reference(view.0, view.1);
            let e_r = k_out.cross(e_l);
            let expected_angle = angle_deg(
                n.dot(e_l).powi(2) - n.dot(e_r).powi(2),
                2.0 * n.dot(e_l) * n.dot(e_r),
            );
            let angle = angle_deg(stokes[1], stokes[2]);
            assert!(
                angle_difference_deg(angle, expected_angle) < 0.05,
                "rho {rho} view {view:?}: angle {angle}, expected {expected_angle}"
            );
            assert_eq!(stokes[3], 0.0, "Rayleigh scattering of sunlight makes no V");
        }
    }
    // Without depolarisation the light 90 degrees from the sun is wholly
    // polarised; with rho = 0.1 its degree is (1 - rho) / (1 + rho).
    for (rho, expected) in [(0.0, 1.0), (0.1, 0.9 / 1.1)] {
        let atmosphere = rayleigh_layer(1e-5, rho, 1.0, EARTH, 0.0);
        let (stokes, _) = stokes(
            &scene(&atmosphere, 0.0, (0.0, 180.0)),
            (90.0, 0.0),
            2_000,
            2,
        );
        let degree = stokes[1].hypot(stokes[2]) / stokes[0];
        assert!(
            (degree - expected).abs() < 5e-4,
            "rho {rho}: {degree} vs {expected}"
        );
    }
}

#[test]
fn non_polarising_species_leave_the_scalar_result() {
    // A Henyey-Greenstein aerosol alone: its phase matrix keeps light
    // unpolarised, so the polarised tracer's I is the scalar estimate of
    // the same paths and Q = U = V = 0.
    let text = r#"
name = "HG only"
[planet]
radius_m = 6360e3
atmosphere_height_m = 100e3
ground_albedo = 0.3
[sun]
spectrum = "flat"
irradiance_w_m2_nm = 1.0
angular_diameter_deg = 0.0
[[species]]
name = "haze"
optical_depth = 0.3
reference_wavelength_nm = 550
profile.exponential.scale_height_m = 1200
scattering.parametric = { angstrom_exponent = 1.3, single_scattering_albedo = 0.9, phase.henyey_greenstein.g = 0.7 }
"#;
    let atmosphere = Atmosphere::from_toml_str(text).unwrap();
    let observation = Observation {
        observer_altitude_m: 0.0,
        sun_elevation_deg: 20.0,
        sun_azimuth_deg: 100.0,
    };
    let scene =
        SingleScatteringScene::new(&atmosphere, &WavelengthGrid::paper(), observation).unwrap();
    let view = (15.0, 130.0);
    let tracer = PathTracer::new_polarised(&scene).unwrap();
    let traced = tracer
        .compute_stokes_with_progress(
            direction_from_elevation_azimuth(view.0, view.1),
            meridian_reference(view.0, view.1),
            4_000,
            3,
            &|_| {},
        )
        .unwrap();
    let [i, q, u, v] = traced.stokes.unwrap();
    for k in 0..i.mean.len() {
        let scalar = traced.total.mean[k];
        assert!(
            (i.mean[k] - scalar).abs() <= 1e-12 * scalar,
            "{k}: {} vs {scalar}",
            i.mean[k]
        );
        assert_eq!((q.mean[k], u.mean[k], v.mean[k]), (0.0, 0.0, 0.0));
    }
    // And the scalar tracer's estimate is the same to the last bit.
    let scalar = PathTracer::new(&scene)
        .compute_radiance(direction_from_elevation_azimuth(view.0, view.1), 4_000, 3)
        .unwrap();
    assert_eq!(scalar.total, traced.total);
}

#[test]
fn stokes_vectors_match_the_coulson_tables() {
    // The layer is plane-parallel in the limit of a planet of radius
    // 6.36e9 m (as the DISORT comparison); the eye is 100 km above its
    // top. mu is the cosine of the reflected direction's zenith angle, so
    // the eye looks down at elevation -asin(mu); phi = 0 is the view
    // toward the sun's azimuth (reflected light travelling on away from the
    // sun: the forward-scattering side, the brighter one near the horizon).
    //
    // Conventions: the tables' Q and U are both of the opposite sign to
    // sora's (Q_table = -Q, U_table = -U), i.e. they are referred to the
    // plane perpendicular to the meridian plane (a frame turned by 90
    // degrees), as the physics shows: single scattering polarises
    // perpendicular to the scattering plane, which for the nadir view at
    // phi = 0 is the meridian plane, and the tables give Q > 0 there
    // (0.0376), sora Q < 0 (its Q > 0 means a field in the meridian plane).
    let table = coulson_table();
    let sun = (0.2f64.asin().to_degrees(), 180.0);
    let mut worst = (0.0f64, String::new());
    for (k, row) in table.rows.iter().enumerate() {
        let (albedo, mu, phi) = (row[0], row[1], row[2]);
        let atmosphere = rayleigh_layer(0.5, 0.0, std::f64::consts::PI, PLANE_PARALLEL, albedo);
        let scene = scene(&atmosphere, 2.0 * PLANE_PARALLEL.1, sun);
        let view = (-mu.asin().to_degrees(), sun.1 + phi);
        let (s, e, scalar) = stokes_and_scalar(&scene, view, 120_000, 100 + k as u64);
        println!(
            "albedo {albedo} mu {mu} phi {phi}: vector I / table {:.4} (+- {:.4}), scalar I / table {:.4}",
            s[0] / row[3],
            e[0] / row[3],
            scalar / row[3]
        );
        let ours = [s[0], -s[1], -s[2]];
        for (c, name) in ["I", "Q", "U"].iter().enumerate() {
            let z = (ours[c] - row[3 + c]) / e[c];
            assert!(
                z.abs() <= 3.0,
                "albedo {albedo} mu {mu} phi {phi}: {name} {} vs table {} ({z:.2} standard errors of {})",
                ours[c],
                row[3 + c],
                e[c]
            );
            if z.abs() > worst.0 {
                worst = (
                    z.abs(),
                    format!("{name} at albedo {albedo} mu {mu} phi {phi}"),
                );
            }
        }
        assert!(e[0] < 3e-3 * s[0], "standard error {} of I {}", e[0], s[0]);
        assert_eq!(s[3], 0.0);
    }
    println!("worst: {:.2} standard errors, {}", worst.0, worst.1);
}

/// I, Q, U at 550 nm of `view` by the fast method with Stokes vectors
/// (all orders), referred to the view's meridian plane.
fn fast_stokes(
    atmosphere: &Atmosphere,
    altitude_m: f64,
    sun: (f64, f64),
    settings: crate::MultipleScatteringSettings,
    views: &[(f64, f64)],
) -> Vec<[f64; 3]> {
    let sky = crate::Sky::builder(atmosphere)
        .sun_deg(sun.0, sun.1)
        .observer_altitude_m(altitude_m)
        .wavelengths(WavelengthGrid::new(550.0, 550.0, 20.0).unwrap())
        .scattering(crate::Scattering::Multiple(settings))
        .polarisation(crate::Polarisation::Vector)
        .build()
        .unwrap();
    let views: Vec<crate::ViewDirection> = views
        .iter()
        .map(|v| crate::ViewDirection::new(v.0, v.1).unwrap())
        .collect();
    sky.radiances(&views)
        .unwrap()
        .iter()
        .map(|r| {
            let s = r.stokes.as_ref().unwrap();
            [
                r.radiance_w_m2_sr_nm[0],
                s.q_w_m2_sr_nm[0],
                s.u_w_m2_sr_nm[0],
            ]
        })
        .collect()
}

/// The largest absolute difference in I, Q or U between the whole fast
/// method (single scattering, the scalar field, its polarisation
/// correction) and the Coulson tables, on the plane-parallel layer of
/// `stokes_vectors_match_the_coulson_tables` with the tables' signs of Q
/// and U mapped as there, and where it is.
fn fast_method_against_coulson(settings: crate::MultipleScatteringSettings) -> (f64, String) {
    let table = coulson_table();
    let sun = (0.2f64.asin().to_degrees(), 180.0);
    let mut worst = (0.0f64, String::new());
    for albedo in [0.0, 0.8] {
        let atmosphere = rayleigh_layer(0.5, 0.0, std::f64::consts::PI, PLANE_PARALLEL, albedo);
        let rows: Vec<&Vec<f64>> = table.rows.iter().filter(|r| r[0] == albedo).collect();
        let views: Vec<(f64, f64)> = rows
            .iter()
            .map(|r| (-r[1].asin().to_degrees(), sun.1 + r[2]))
            .collect();
        let ours = fast_stokes(&atmosphere, 2.0 * PLANE_PARALLEL.1, sun, settings, &views);
        for (row, s) in rows.iter().zip(&ours) {
            let mapped = [s[0], -s[1], -s[2]];
            for (c, name) in ["I", "Q", "U"].iter().enumerate() {
                let error = (mapped[c] - row[3 + c]).abs();
                let place = format!("{name} at albedo {albedo} mu {} phi {}", row[1], row[2]);
                println!(
                    "{place}: {:.8} vs table {:.8} ({error:.1e})",
                    mapped[c],
                    row[3 + c]
                );
                if error > worst.0 {
                    worst = (error, place);
                }
            }
        }
    }
    println!("worst: {:.2e}, {}", worst.0, worst.1);
    worst
}

#[test]
fn the_fast_method_matches_the_coulson_tables() {
    // 10 streams a hemisphere and 40 layers: the setting `--help` and
    // docs/polarisation.md name for the 1e-4 bar (5.6e-5 at the grazing
    // rows; 12 streams and 60 layers give 4.7e-5).
    let (worst, place) = fast_method_against_coulson(crate::MultipleScatteringSettings {
        streams_per_hemisphere: 10,
        layers: 40,
        ..Default::default()
    });
    assert!(worst <= 1e-4, "worst {worst:.2e}, {place}");
}

#[test]
fn the_default_resolution_holds_the_coulson_tables_to_its_stated_error() {
    // The default 8 streams and 40 layers: `--help` and
    // docs/polarisation.md state its error at the grazing rows (1.1e-4,
    // in Q at albedo 0.8 and mu 0.02), above the 1e-4 that 10 streams meet.
    let (worst, place) = fast_method_against_coulson(Default::default());
    assert!(worst <= 1.2e-4, "worst {worst:.2e}, {place}");
}

#[test]
fn the_fast_method_matches_the_vector_path_tracer() {
    // The spherical planet, all orders, at 440, 560 and 680 nm: the fast
    // method's polarised intensity within 1 % + 3 standard errors of the
    // vector path tracer's, its degree of linear polarisation within 0.01 +
    // 3 standard errors and its angle within 1 degree. The first case is
    // where the scalar intensity is furthest off (sun 60, view 10 degrees
    // up at 90 degrees from it: 5 % too bright at 440 nm), so a scalar
    // field fails the test (checked at the end). The last is mars-dust
    // away from a low sun, where much of the multiply scattered light is
    // the forward-peak term: with the polarisation correction's column
    // ratios applied to that term (which single scattering's polarisation
    // suits), the degree at 440 nm was 0.049 against 0.073 (+- 0.0016 with
    // 400 000 paths, outside the bar of 0.015); now 0.076.
    let grid = WavelengthGrid::new(440.0, 680.0, 120.0).unwrap();
    let cases = [
        (
            "us-standard-1976-rayleigh",
            (60.0, 0.0),
            (10.0, 90.0),
            100_000,
        ),
        (
            "us-standard-1976-rayleigh",
            (30.0, 0.0),
            (10.0, 180.0),
            100_000,
        ),
        ("earth-clear", (30.0, 0.0), (30.0, 90.0), 100_000),
        ("mars-dust", (5.0, 0.0), (10.0, 180.0), 400_000),
    ];
    for (k, (preset, sun, view, samples)) in cases.into_iter().enumerate() {
        let atmosphere = Atmosphere::preset(preset).unwrap();
        let sky = |method, polarisation| {
            crate::Sky::builder(&atmosphere)
                .sun_deg(sun.0, sun.1)
                .wavelengths(grid)
                .method(method)
                .polarisation(polarisation)
                .build()
                .unwrap()
                .radiance(crate::ViewDirection::new(view.0, view.1).unwrap())
                .unwrap()
        };
        let fast = sky(crate::Method::Fast, crate::Polarisation::Vector);
        let scalar = sky(crate::Method::Fast, crate::Polarisation::Scalar);
        let traced = sky(
            crate::Method::PathTracing {
                samples,
                seed: 40 + k as u64,
            },
            crate::Polarisation::Vector,
        );
        let (fs, ts) = (fast.stokes.unwrap(), traced.stokes.unwrap());
        let errors = traced.standard_error_w_m2_sr_nm.unwrap();
        let q_u_errors = ts.standard_errors_w_m2_sr_nm.unwrap();
        for i in 0..grid.len() {
            let (fi, ti) = (fast.radiance_w_m2_sr_nm[i], traced.radiance_w_m2_sr_nm[i]);
            let place = format!(
                "{preset} sun {sun:?} view {view:?} {} nm",
                grid.wavelength_nm(i)
            );
            let allowed = 0.01 * ti + 3.0 * errors[i];
            println!(
                "{place}: I fast / traced {:.4} (+- {:.4}), scalar / traced {:.4}",
                fi / ti,
                errors[i] / ti,
                scalar.radiance_w_m2_sr_nm[i] / ti
            );
            assert!((fi - ti).abs() <= allowed, "{place}: I {fi} vs {ti}");
            let degree = |q: f64, u: f64, i: f64| q.hypot(u) / i;
            let fd = degree(fs.q_w_m2_sr_nm[i], fs.u_w_m2_sr_nm[i], fi);
            let td = degree(ts.q_w_m2_sr_nm[i], ts.u_w_m2_sr_nm[i], ti);
            let degree_error = q_u_errors[0][i].hypot(q_u_errors[1][i]) / ti;
            println!("  degree {fd:.4} vs {td:.4} (+- {degree_error:.4})");
            assert!(
                (fd - td).abs() <= 0.01 + 3.0 * degree_error,
                "{place}: degree {fd} vs {td}"
            );
            if td > 0.05 {
                let fa = angle_deg(fs.q_w_m2_sr_nm[i], fs.u_w_m2_sr_nm[i]);
                let ta = angle_deg(ts.q_w_m2_sr_nm[i], ts.u_w_m2_sr_nm[i]);
                assert!(
                    angle_difference_deg(fa, ta) <= 1.0,
                    "{place}: angle {fa} vs {ta}"
                );
            }
            if k == 0 && i == 0 {
                let si = scalar.radiance_w_m2_sr_nm[i];
                assert!(
                    (si - ti).abs() > 0.03 * ti + 3.0 * errors[i],
                    "{place}: scalar {si}"
                );
            }
        }
    }
}

/// The issue's whole grid, fast against the vector path tracer (the README
/// names it): us-standard-1976-rayleigh, earth-clear and mars-dust; suns
/// 60, 30, 10 and 5 degrees; the zenith and views 10, 30 and 60 degrees up
/// at 0, 90 and 180 degrees from the sun; 440, 560 and 680 nm; 100 000
/// paths a view. Prints every comparison and the worst of each quantity,
/// and holds I to 1 % + 3 standard errors, the degree to 0.01 + 3 standard
/// errors, the angle to 1 degree + 3 standard errors where the degree is
/// above 0.05 (the path tracer's angle has one too: about 1 degree for
/// mars-dust at (30, 180) with the sun 5 degrees high, where its degree
/// is 0.08 +- 0.005 with 100 000 paths; the issue's 1 degree is met there
/// with 1 000 000 paths, `docs/polarisation.md`).
/// `cargo test --release -p sora --lib -- --ignored fast_polarisation_over_the_whole_grid --nocapture`
///
/// Settings by environment (all optional, for re-measuring part of the
/// grid with more paths): `SORA_GRID_PRESETS` and `SORA_GRID_SUNS`
/// (comma-separated), `SORA_GRID_SAMPLES` (paths a view, default
/// 100 000), `SORA_GRID_SEED` (default 7).
#[test]
#[ignore = "minutes: 120 path-traced views"]
fn fast_polarisation_over_the_whole_grid() {
    let setting = |name: &str, default: &str| std::env::var(name).unwrap_or(default.to_string());
    let presets = setting(
        "SORA_GRID_PRESETS",
        "us-standard-1976-rayleigh,earth-clear,mars-dust",
    );
    let suns: Vec<f64> = setting("SORA_GRID_SUNS", "60,30,10,5")
        .split(',')
        .map(|s| s.trim().parse().unwrap())
        .collect();
    let samples: u64 = setting("SORA_GRID_SAMPLES", "100000").parse().unwrap();
    let seed: u64 = setting("SORA_GRID_SEED", "7").parse().unwrap();
    let grid = WavelengthGrid::new(440.0, 680.0, 120.0).unwrap();
    let mut views = vec![(90.0, 0.0)];
    for elevation in [10.0, 30.0, 60.0] {
        for azimuth in [0.0, 90.0, 180.0] {
            views.push((elevation, azimuth));
        }
    }
    let mut failures = Vec::new();
    let mut worst = [
        (0.0f64, String::new()),
        (0.0, String::new()),
        (0.0, String::new()),
    ];
    for preset in presets.split(',').map(str::trim) {
        let atmosphere = Atmosphere::preset(preset).unwrap();
        for &sun in &suns {
            let sky = |method| {
                crate::Sky::builder(&atmosphere)
                    .sun_deg(sun, 0.0)
                    .wavelengths(grid)
                    .method(method)
                    .polarisation(crate::Polarisation::Vector)
                    .build()
                    .unwrap()
            };
            let directions: Vec<crate::ViewDirection> = views
                .iter()
                .map(|v| crate::ViewDirection::new(v.0, v.1).unwrap())
                .collect();
            let fast = sky(crate::Method::Fast).radiances(&directions).unwrap();
            let traced = sky(crate::Method::PathTracing { samples, seed })
                .radiances(&directions)
                .unwrap();
            for ((view, f), t) in views.iter().zip(&fast).zip(&traced) {
                let (fs, ts) = (f.stokes.as_ref().unwrap(), t.stokes.as_ref().unwrap());
                let errors = t.standard_error_w_m2_sr_nm.as_ref().unwrap();
                let qu = ts.standard_errors_w_m2_sr_nm.as_ref().unwrap();
                for i in 0..grid.len() {
                    let place = format!(
                        "{preset} sun {sun} view {view:?} {} nm",
                        grid.wavelength_nm(i)
                    );
                    let (fi, ti) = (f.radiance_w_m2_sr_nm[i], t.radiance_w_m2_sr_nm[i]);
                    let fd = fs.q_w_m2_sr_nm[i].hypot(fs.u_w_m2_sr_nm[i]) / fi;
                    let td = ts.q_w_m2_sr_nm[i].hypot(ts.u_w_m2_sr_nm[i]) / ti;
                    let degree_error = qu[0][i].hypot(qu[1][i]) / ti;
                    let (angle, angle_error) = if td > 0.05 {
                        let traced = (ts.q_w_m2_sr_nm[i], ts.u_w_m2_sr_nm[i]);
                        (
                            angle_difference_deg(
                                angle_deg(fs.q_w_m2_sr_nm[i], fs.u_w_m2_sr_nm[i]),
                                angle_deg(traced.0, traced.1),
                            ),
                            angle_standard_error_deg(traced, (qu[0][i], qu[1][i])),
                        )
                    } else {
                        (0.0, 0.0)
                    };
                    println!(
                        "{place}: I {:+.2} % (se {:.2} %), degree {fd:.4} vs {td:.4} (se {degree_error:.4}), angle {angle:.2} (se {angle_error:.2})",
                        100.0 * (fi / ti - 1.0),
                        100.0 * errors[i] / ti
                    );
                    let measures = [(fi / ti - 1.0).abs(), (fd - td).abs(), angle];
                    for (w, m) in worst.iter_mut().zip(measures) {
                        if m > w.0 {
                            *w = (m, place.clone());
                        }
                    }
                    if (fi - ti).abs() > 0.01 * ti + 3.0 * errors[i]
                        || (fd - td).abs() > 0.01 + 3.0 * degree_error
                        || angle > 1.0 + 3.0 * angle_error
                    {
                        failures.push(place);
                    }
                }
            }
        }
    }
    println!("worst I {:.2} % at {}", 100.0 * worst[0].0, worst[0].1);
    println!("worst degree {:.4} at {}", worst[1].0, worst[1].1);
    println!("worst angle {:.2} deg at {}", worst[2].0, worst[2].1);
    assert!(
        failures.is_empty(),
        "{} outside: {failures:#?}",
        failures.len()
    );
}
