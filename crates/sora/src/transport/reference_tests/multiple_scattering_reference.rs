//! Multiple scattering (`transport::multiple_scattering`) against DISORT and
//! against physics that needs no reference data.
//!
//! - Every row of `data/clear_sky_radiance.csv` (atmosphere
//!   `clear-sky-reference`, flat sun of 1 W m^-2 nm^-1, ground albedo 0 and
//!   0.3): single scattering plus multiple scattering against DISORT's
//!   `L_multi_plane_parallel` (plane-parallel, approximated by a planet of
//!   radius 6.36e9 m, as in `single_scattering_reference.rs`), along all
//!   three paths: the field's exact synthesis (`sora spectrum`), the
//!   per-image source table, and the sky-view table (`sora render`).
//! - Sanity: multiple scattering adds light, relatively more in the blue;
//!   it is finite and non-negative for every preset, sun, eye and
//!   direction; in twilight it brightens the zenith beyond single
//!   scattering.
//! - The default resolution against a fine one on the spherical atmosphere
//!   for suns from 90 down to 5 degrees (the method's own convergence).
//! - The spherical atmosphere against the Monte Carlo path tracer
//!   (`transport::path_tracing`, all orders, unbiased) for suns from 90 down
//!   to 5 degrees: every wavelength within the 2 % plus three
//!   standard errors of the path tracer (a modest-sample version here, a
//!   heavier one with `--ignored`), and twilight reported.

use std::sync::Arc;

use crate::atmosphere::{Atmosphere, Planet};
use crate::geometry::{Vector3, direction_from_elevation_azimuth};
use crate::spectrum::{SampledSpectrum, Spectrum, WavelengthGrid};
use crate::transport::multiple_scattering::{
    MultipleScatteringField, MultipleScatteringSettings, MultipleScatteringTable,
};
use crate::transport::{Observation, PathTracer, SingleScatteringScene, SunColumns};
use crate::{FastTableSize, ImageSettings, Method, Scattering, Sky, ViewDirection};

use super::reference_data::reference_rows;

fn sky(
    atmosphere: &Atmosphere,
    sun_elevation_deg: f64,
    observer_altitude_m: f64,
) -> SingleScatteringScene {
    let observation = Observation {
        observer_altitude_m,
        sun_elevation_deg,
        sun_azimuth_deg: 0.0,
    };
    SingleScatteringScene::new(atmosphere, &WavelengthGrid::paper(), observation).unwrap()
}

/// Worst relative errors against DISORT (field, source table, sky-view
/// table) over the rows of one ground albedo.
fn worst_errors_against_disort(ground_albedo: f64) -> [f64; 3] {
    let mut atmosphere = Atmosphere::preset("clear-sky-reference").unwrap();
    atmosphere.planet = Planet::new(6.36e9, 100e3, Spectrum::Constant(ground_albedo)).unwrap();
    let grid = WavelengthGrid::paper();
    let n = grid.len();
    let rows = reference_rows();
    let mut worst = [0.0f64; 3];
    for sun_elevation in [36.0, 60.0] {
        let sky = sky(&atmosphere, sun_elevation, 0.0);
        let field =
            MultipleScatteringField::compute(&sky, MultipleScatteringSettings::default(), false)
                .unwrap();
        let table = MultipleScatteringTable::compute(Arc::new(field.clone()));
        let image_sky = Sky::from_scene(
            sky.clone(),
            Scattering::multiple(),
            Method::Fast,
            FastTableSize::default(),
        )
        .unwrap();
        let (mut scratch, mut ms_scratch) = (sky.scratch(), field.scratch());
        let mut single = SampledSpectrum::zeros(n);
        let (mut exact, mut tabulated) = (vec![0.0; n], vec![0.0; n]);
        let mut geometries: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.sun_elevation_deg == sun_elevation && r.ground_albedo == ground_albedo)
            .map(|r| (r.view_elevation_deg, r.relative_azimuth_deg))
            .collect();
        geometries.dedup();
        for (view_elevation, relative_azimuth) in geometries {
            let view = direction_from_elevation_azimuth(view_elevation, relative_azimuth);
            sky.compute_radiance(view, SunColumns::Exact, &mut scratch, &mut single);
            field.compute_radiance(view, SunColumns::Exact, &mut ms_scratch, &mut exact);
            table.compute_radiance(view, SunColumns::Exact, &mut ms_scratch, &mut tabulated);
            let image = image_sky
                .radiance_from_image_tables(
                    ViewDirection::new(view_elevation, relative_azimuth).unwrap(),
                )
                .unwrap()
                .radiance_w_m2_sr_nm;
            for row in rows.iter().filter(|r| {
                r.sun_elevation_deg == sun_elevation
                    && r.ground_albedo == ground_albedo
                    && r.view_elevation_deg == view_elevation
                    && r.relative_azimuth_deg == relative_azimuth
            }) {
                let i = ((row.wavelength_nm - grid.start_nm()) / grid.step_nm()).round() as usize;
                let expected = row.multiple_plane_parallel;
                let errors = [
                    (single[i] + exact[i]) / expected - 1.0,
                    (single[i] + tabulated[i]) / expected - 1.0,
                    image[i] / expected - 1.0,
                ];
                if errors.iter().any(|e| e.abs() > 2e-3) {
                    eprintln!(
                        "albedo {ground_albedo} sun {sun_elevation} view {view_elevation} rel {relative_azimuth} {} nm: field {:+.3e} table {:+.3e} image {:+.3e}",
                        row.wavelength_nm, errors[0], errors[1], errors[2]
                    );
                }
                for (w, e) in worst.iter_mut().zip(errors) {
                    *w = w.max(e.abs());
                }
            }
        }
    }
    worst
}

#[test]
fn black_ground_matches_disort_at_every_row() {
    let [field, table, image] = worst_errors_against_disort(0.0);
    eprintln!(
        "albedo 0: worst relative error vs DISORT: field {field:.3e}, source table {table:.3e}, sky-view table {image:.3e}"
    );
    // The target is 2 %; measured: 7.4e-4, 8.9e-4, 1.04e-3.
    assert!(field < 8e-4, "field {field}");
    assert!(table < 1e-3, "source table {table}");
    assert!(image < 1.2e-3, "sky-view table {image}");
}

#[test]
fn bright_ground_matches_disort_at_every_row() {
    let [field, table, image] = worst_errors_against_disort(0.3);
    eprintln!(
        "albedo 0.3: worst relative error vs DISORT: field {field:.3e}, source table {table:.3e}, sky-view table {image:.3e}"
    );
    // Measured: 6.1e-4, 8.5e-4, 1.38e-3.
    assert!(field < 7e-4, "field {field}");
    assert!(table < 1e-3, "source table {table}");
    assert!(image < 1.5e-3, "sky-view table {image}");
}

/// Directions spread evenly over the sphere (a Fibonacci lattice), none
/// within 0.3 degrees of the horizon.
fn directions(count: usize) -> Vec<Vector3> {
    (0..count)
        .map(|k| {
            let u = (k as f64 + 0.5) / count as f64;
            let elevation = (2.0 * u - 1.0).asin().to_degrees();
            let elevation = elevation.signum() * elevation.abs().max(0.3);
            direction_from_elevation_azimuth(elevation, (k as f64 * 137.507_764) % 360.0)
        })
        .collect()
}

/// Single and multiple scattering (exact synthesis) along `view`.
fn both(
    sky: &SingleScatteringScene,
    field: &MultipleScatteringField,
    view: Vector3,
) -> (Vec<f64>, Vec<f64>) {
    let n = sky.optics().grid.len();
    let mut single = SampledSpectrum::zeros(n);
    let mut multiple = vec![0.0; n];
    sky.compute_radiance(view, SunColumns::Exact, &mut sky.scratch(), &mut single);
    field.compute_radiance(view, SunColumns::Exact, &mut field.scratch(), &mut multiple);
    (single.into_values(), multiple)
}

#[test]
fn multiple_scattering_adds_light_relatively_more_in_the_blue() {
    let atmosphere = Atmosphere::preset("clear-sky-reference").unwrap();
    for sun_elevation in [60.0, 20.0] {
        let sky = sky(&atmosphere, sun_elevation, 0.0);
        let field =
            MultipleScatteringField::compute(&sky, MultipleScatteringSettings::default(), false)
                .unwrap();
        for view in directions(60).into_iter().filter(|v| v.z > 0.0) {
            let (single, multiple) = both(&sky, &field, view);
            assert!(multiple.iter().all(|m| *m > 0.0), "{view:?}: {multiple:?}");
            let last = single.len() - 1;
            let (blue, red) = (multiple[0] / single[0], multiple[last] / single[last]);
            assert!(blue > red, "{view:?}: blue {blue} red {red}");
        }
    }
}

#[test]
fn multiple_scattering_is_finite_and_non_negative_everywhere() {
    let settings = MultipleScatteringSettings::default();
    for preset in ["clear-sky-reference", "earth-clear", "paper-mars"] {
        let atmosphere = Atmosphere::preset(preset).unwrap();
        for (sun_elevation, altitude) in [
            (90.0, 0.0),
            (25.0, 10e3),
            (3.0, 0.0),
            (-4.0, 0.0),
            (-9.0, 30e3),
            (40.0, 400e3),
        ] {
            let sky = sky(&atmosphere, sun_elevation, altitude);
            let table = MultipleScatteringTable::compute(Arc::new(
                MultipleScatteringField::compute(&sky, settings, false).unwrap(),
            ));
            let mut scratch = table.scratch();
            let mut radiance = vec![0.0; sky.optics().grid.len()];
            for view in directions(40) {
                table.compute_radiance(view, SunColumns::Exact, &mut scratch, &mut radiance);
                assert!(
                    radiance.iter().all(|r| r.is_finite() && *r >= 0.0),
                    "{preset} sun {sun_elevation} eye {altitude} m view {view:?}: {radiance:?}"
                );
                table.field().compute_radiance(
                    view,
                    SunColumns::Exact,
                    &mut scratch,
                    &mut radiance,
                );
                assert!(
                    radiance.iter().all(|r| r.is_finite() && *r >= 0.0),
                    "{preset} sun {sun_elevation} eye {altitude} m view {view:?} (exact): {radiance:?}"
                );
            }
        }
    }
}

#[test]
fn twilight_zenith_is_brighter_than_single_scattering() {
    let atmosphere = Atmosphere::preset("clear-sky-reference").unwrap();
    let zenith = direction_from_elevation_azimuth(90.0, 0.0);
    for sun_elevation in [-2.0, -4.0, -6.0] {
        let sky = sky(&atmosphere, sun_elevation, 0.0);
        let field =
            MultipleScatteringField::compute(&sky, MultipleScatteringSettings::default(), false)
                .unwrap();
        let (single, multiple) = both(&sky, &field, zenith);
        eprintln!(
            "sun {sun_elevation}: zenith multiple / single {:.3} at 380 nm, {:.3} at 780 nm",
            multiple[0] / single[0],
            multiple[20] / single[20]
        );
        // Light scattered down from the still-lit upper air: measured
        // ratios 1.14..1.16 at 380 nm and 0.15..0.17 at 780 nm.
        assert!(
            multiple[0] > single[0],
            "380 nm: {} vs {}",
            multiple[0],
            single[0]
        );
        for (i, (s, m)) in single.iter().zip(&multiple).enumerate() {
            assert!(*m > 0.1 * s, "{i}: {m} vs {s}");
        }
    }
}

#[test]
fn default_resolution_is_converged_on_the_spherical_sky() {
    let atmosphere = Atmosphere::preset("clear-sky-reference").unwrap();
    let fine = MultipleScatteringSettings {
        streams_per_hemisphere: 12,
        layers: 80,
        sun_zenith_step_deg: 1.0,
        sunset_sun_zenith_step_deg: 0.25,
        view_ray_panels: 32,
        table_view_zenith_nodes: 73,
        table_azimuth_nodes: 37,
        polarisation_wavelength_stride: 1,
        first_order_panels: 4,
        first_order_fine_nodes: 4,
        twilight_shift_pieces: 1,
    };
    for sun_elevation in [90.0, 30.0, 5.0] {
        let sky = sky(&atmosphere, sun_elevation, 0.0);
        let reference = MultipleScatteringField::compute(&sky, fine, false).unwrap();
        let table = MultipleScatteringTable::compute(Arc::new(
            MultipleScatteringField::compute(&sky, MultipleScatteringSettings::default(), false)
                .unwrap(),
        ));
        let (mut worst_field, mut worst_table) = (0.0f64, 0.0f64);
        let mut radiance = vec![0.0; sky.optics().grid.len()];
        let mut scratch = table.scratch();
        for view in directions(120) {
            let (single, expected) = both(&sky, &reference, view);
            table
                .field()
                .compute_radiance(view, SunColumns::Exact, &mut scratch, &mut radiance);
            for i in 0..radiance.len() {
                if single[i] + expected[i] > 0.0 {
                    worst_field = worst_field
                        .max((radiance[i] - expected[i]).abs() / (single[i] + expected[i]));
                }
            }
            table.compute_radiance(view, SunColumns::Exact, &mut scratch, &mut radiance);
            for i in 0..radiance.len() {
                if single[i] + expected[i] > 0.0 {
                    worst_table = worst_table
                        .max((radiance[i] - expected[i]).abs() / (single[i] + expected[i]));
                }
            }
        }
        eprintln!(
            "sun {sun_elevation}: default vs fine, share of the total radiance: field {worst_field:.3e}, table {worst_table:.3e}"
        );
        // Measured 3.9e-3 / 4.5e-3 (sun 90) to 6.4e-3 / 7.6e-3 (sun 5).
        assert!(worst_field < 7e-3, "field {worst_field}");
        assert!(worst_table < 8.5e-3, "table {worst_table}");
    }
}

/// Worst relative difference (single + multiple scattering, exact
/// synthesis, and the source table) from the path tracer's total over the
/// `views` (elevation, azimuth from the sun) of each sun, and the worst
/// excess over `bound` plus three standard errors; prints every view.
fn compare_with_path_tracer(
    preset: &str,
    suns: &[f64],
    views: &[(f64, f64)],
    samples: u64,
    bound: f64,
) -> (f64, f64) {
    let atmosphere = Atmosphere::preset(preset).unwrap();
    let (mut worst, mut worst_excess) = (0.0f64, f64::NEG_INFINITY);
    for (n, &sun_elevation) in suns.iter().enumerate() {
        let sky = sky(&atmosphere, sun_elevation, 0.0);
        let table = MultipleScatteringTable::compute(Arc::new(
            MultipleScatteringField::compute(&sky, MultipleScatteringSettings::default(), false)
                .unwrap(),
        ));
        let tracer = PathTracer::new(&sky);
        let mut scratch = table.scratch();
        let mut tabulated = vec![0.0; sky.optics().grid.len()];
        for (k, &(elevation, azimuth)) in views.iter().enumerate() {
            let view = direction_from_elevation_azimuth(elevation, azimuth);
            let traced = tracer
                .compute_radiance(view, samples, 1000 * n as u64 + k as u64 + 1)
                .unwrap();
            let (single, multiple) = both(&sky, table.field(), view);
            table.compute_radiance(view, SunColumns::Exact, &mut scratch, &mut tabulated);
            let (mut row_worst, mut at) = (0.0f64, 0);
            for i in 0..single.len() {
                let expected = traced.total.mean[i];
                let sigma = traced.total.standard_error[i] / expected;
                for value in [single[i] + multiple[i], single[i] + tabulated[i]] {
                    let error = value / expected - 1.0;
                    worst_excess = worst_excess.max(error.abs() - bound - 3.0 * sigma);
                    if error.abs() > row_worst.abs() {
                        (row_worst, at) = (error, i);
                    }
                }
            }
            worst = worst.max(row_worst.abs());
            eprintln!(
                "{preset}: sun {sun_elevation:>5} view {elevation:>5} at {azimuth:>5} from the sun: worst {:+.2} % at {} nm (path tracer +-{:.2} %)",
                100.0 * row_worst,
                sky.optics().grid.wavelength_nm(at),
                100.0 * traced.total.standard_error[at] / traced.total.mean[at]
            );
        }
    }
    (worst, worst_excess)
}

/// The views of the path-tracer comparisons: zenith, both sides of the
/// sun's vertical, across it, and the horizon toward the sun (where the
/// method errs most for a low sun).
const PATH_TRACER_VIEWS: [(f64, f64); 6] = [
    (90.0, 0.0),
    (45.0, 0.0),
    (45.0, 180.0),
    (10.0, 90.0),
    (2.0, 0.0),
    (2.0, 180.0),
];

#[test]
fn spherical_sky_matches_the_path_tracer_within_two_percent() {
    let (worst, excess) = compare_with_path_tracer(
        "clear-sky-reference",
        &[90.0, 30.0, 10.0, 5.0],
        &PATH_TRACER_VIEWS,
        20_000,
        0.02,
    );
    eprintln!("sun 90..5 degrees: worst relative difference {worst:.3e}");
    assert!(excess <= 0.0, "beyond 2 % + 3 sigma by {excess}");
}

/// Exact Mie phase functions (a hazy Earth: polluted continental aerosol
/// of optical depth 0.4, ground albedo 0.1) away from the sun, where
/// delta-M's forward-peak term matters most: measured within 1 % with
/// 100 000 paths.
#[test]
fn mie_aerosols_match_the_path_tracer_away_from_the_sun() {
    let views = [
        (90.0, 0.0),
        (45.0, 0.0),
        (45.0, 180.0),
        (10.0, 90.0),
        (10.0, 180.0),
    ];
    let (worst, excess) = compare_with_path_tracer("earth-hazy", &[30.0], &views, 20_000, 0.02);
    eprintln!("earth-hazy, sun 30 degrees: worst relative difference {worst:.3e}");
    assert!(excess <= 0.0, "beyond 2 % + 3 sigma by {excess}");
}

/// Heavier: 400 000 paths per view, more views and suns (15 minutes).
/// Measured worst, sun 90..5: 1.6 % (1 degree above the horizon away from
/// a sun 5 degrees high, 380 nm); hazy Earth 1.7 %. Twilight is printed,
/// not asserted: sun -2 degrees up to 11 %, -4 degrees up to 95 % (at the
/// horizon; see the module docs).
#[test]
#[ignore]
fn spherical_sky_matches_the_path_tracer_exhaustively() {
    let views = [
        (90.0, 0.0),
        (60.0, 0.0),
        (45.0, 0.0),
        (45.0, 180.0),
        (17.0, 140.0),
        (10.0, 0.0),
        (10.0, 90.0),
        (10.0, 180.0),
        (3.0, 0.0),
        (3.0, 30.0),
        (3.0, 180.0),
        (1.0, 0.0),
        (1.0, 90.0),
        (1.0, 180.0),
    ];
    let (worst, excess) = compare_with_path_tracer(
        "clear-sky-reference",
        &[90.0, 60.0, 36.0, 20.0, 10.0, 5.0],
        &views,
        400_000,
        0.02,
    );
    eprintln!("sun 90..5 degrees: worst relative difference {worst:.3e}");
    let (hazy, hazy_excess) = compare_with_path_tracer(
        "earth-hazy",
        &[30.0, 5.0],
        &[(90.0, 0.0), (45.0, 180.0), (10.0, 90.0), (10.0, 180.0)],
        400_000,
        0.02,
    );
    eprintln!("earth-hazy away from the sun: worst relative difference {hazy:.3e}");
    let (twilight, _) =
        compare_with_path_tracer("clear-sky-reference", &[-2.0, -4.0], &views, 400_000, 0.02);
    eprintln!("twilight (sun -2, -4 degrees): worst relative difference {twilight:.3e}");
    assert!(excess <= 0.0, "beyond 2 % + 3 sigma by {excess}");
    assert!(
        hazy_excess <= 0.0,
        "earth-hazy beyond 2 % + 3 sigma by {hazy_excess}"
    );
}

/// The fast image (multiply scattered radiance in the sky-view table,
/// marched at every other node) against the reference method's image (the
/// paper's march and the field's exact synthesis per pixel), on a small
/// fisheye.
#[test]
fn fast_image_matches_the_per_pixel_march() {
    use crate::camera::Camera;
    use crate::colour::{Observer, SpectrumToXyz};
    let atmosphere = Atmosphere::preset("clear-sky-reference").unwrap();
    let to_xyz = SpectrumToXyz::new(&WavelengthGrid::paper(), Observer::Cie1931TwoDegree);
    let scattering = Scattering::multiple();
    for sun_elevation in [36.0, 5.0] {
        let scene = sky(&atmosphere, sun_elevation, 0.0);
        let image = ImageSettings {
            draw_sun_disc: false,
            ..ImageSettings::new(Camera::Fisheye, 24, 24)
        };
        let render = |scattering: Scattering, method: Method| {
            Sky::from_scene(scene.clone(), scattering, method, FastTableSize::default())
                .unwrap()
                .render_xyz(&image, &to_xyz, &|_| {})
                .unwrap()
        };
        let fast = render(scattering, Method::Fast);
        let reference = render(
            scattering,
            Method::Reference {
                view_steps: 2000,
                sun_steps: 400,
            },
        );
        let single = render(Scattering::Single, Method::Fast);
        let mut worst: f64 = 0.0;
        for ((f, r), s) in fast.iter().zip(&reference).zip(&single) {
            for (a, b, c) in [(f.x, r.x, s.x), (f.y, r.y, s.y), (f.z, r.z, s.z)] {
                if b > 0.0 {
                    worst = worst.max((a / b - 1.0).abs());
                    // Multiple scattering only ever adds light.
                    assert!(a > c, "{a} vs single {c}");
                }
            }
        }
        eprintln!(
            "sun {sun_elevation}: fisheye 24x24 fast vs per-pixel march, worst XYZ {worst:.3e}"
        );
        // Measured 1.7e-3 and 2.4e-3 (the single-scattering parts alone
        // differ by up to 1e-3, see render_accuracy.rs).
        assert!(worst < 3e-3, "{worst}");
    }
}
