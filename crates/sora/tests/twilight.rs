//! Twilight: the sun from the horizon to 16 degrees below it.
//!
//! - The image path (`Sky::render_xyz`: sun-column, source and sky-view
//!   tables, read by `Sky::radiance_from_image_tables`) against the
//!   per-view path (`Sky::radiance`, what `sora spectrum` prints) in every
//!   kind of direction, toward, across and away from the sun, at every
//!   wavelength. Before the field's first order was spherical the two
//!   differed by 12 % at sun -11 degrees and every value below -10 degrees
//!   was the same whatever the sun (the field's sun axis stopped at the
//!   column's sunset, 100 degrees, and clamped).
//! - The fast method against the path tracer in civil twilight (a subset
//!   here, the whole grid down to -12 degrees with `--ignored`).
//! - Near a low sun with Mie aerosols (earth-hazy, mars-dust), where
//!   delta-M's forward-peak term carries much of the multiply scattered
//!   light: the image path against the per-view path, and the fast method
//!   against the path tracer.
//! - The zenith radiance against the sun's elevation, +10 to -18 degrees
//!   every 0.25 degree, at 440, 560 and 660 nm, in scalar and polarised
//!   light: monotone, and with no staircase or kink (|second difference of
//!   ln L| below 0.05 per step, the bar).

use sora::spectrum::WavelengthGrid;
use sora::{Atmosphere, Polarisation, Sky, ViewDirection};

/// Directions from the zenith to the ground, toward (azimuth 0), across
/// and away from the sun (which stands at azimuth 0).
const VIEWS: [(f64, f64); 11] = [
    (90.0, 0.0),
    (60.0, 135.0),
    (45.0, 180.0),
    (45.0, 0.0),
    (20.0, 90.0),
    (5.0, 0.0),
    (5.0, 180.0),
    (2.0, 0.0),
    (2.0, 180.0),
    (-10.0, 0.0),
    (-10.0, 180.0),
];

/// The largest relative difference, over `views` (elevation, azimuth) and
/// every wavelength, between the image path and the per-view path of
/// `sky`, panicking where it reaches `bound` (`place` names the sky).
fn worst_table_difference(sky: &Sky, views: &[(f64, f64)], bound: f64, place: &str) -> f64 {
    let mut worst = 0.0f64;
    for &(elevation, azimuth) in views {
        let view = ViewDirection::new(elevation, azimuth).unwrap();
        let exact = sky.radiance(view).unwrap().radiance_w_m2_sr_nm;
        let table = sky
            .radiance_from_image_tables(view)
            .unwrap()
            .radiance_w_m2_sr_nm;
        for (i, (e, t)) in exact.values().iter().zip(table.values()).enumerate() {
            assert!(
                *e > 0.0 && e.is_finite(),
                "{place}, view ({elevation}, {azimuth}), index {i}: {e}"
            );
            let error = (t / e - 1.0).abs();
            worst = worst.max(error);
            assert!(
                error < bound,
                "{place}, view ({elevation}, {azimuth}), {} nm: table {t:e} vs per view {e:e}",
                sky.wavelengths().wavelength_nm(i)
            );
        }
    }
    worst
}

#[test]
fn image_tables_agree_with_the_per_view_path_in_twilight() {
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    let mut worst = 0.0f64;
    for sun in [0.0, -4.0, -8.0, -12.0, -16.0] {
        let sky = Sky::builder(&atmosphere)
            .sun_deg(sun, 0.0)
            .polarisation(sora::Polarisation::Scalar)
            .build()
            .unwrap();
        // Measured at most 7.1e-3 (5.8e-3 down to -12 degrees, at 780 nm
        // 20 degrees up across the sun's vertical, where the sky-view
        // table's azimuth interpolation is coarsest).
        worst = worst.max(worst_table_difference(
            &sky,
            &VIEWS,
            1e-2,
            &format!("sun {sun}"),
        ));
    }
    eprintln!("worst relative difference, image tables vs per view: {worst:.3e}");
}

/// Views near a sun at `sun` degrees (azimuth 0) and a few farther away.
fn views_near_the_sun(sun: f64) -> Vec<(f64, f64)> {
    let low = sun.max(1.0);
    vec![
        (low, 1.0),
        (low, 2.0),
        (low, 5.0),
        (low + 2.0, 0.0),
        (low + 5.0, 0.0),
        (low + 10.0, 0.0),
        (low, 30.0),
        (20.0, 0.0),
        (45.0, 90.0),
    ]
}

/// The image path against the per-view path near a low sun (5 and 2
/// degrees) with Mie aerosols, where delta-M's forward-peak term (its
/// integrals interpolated over the sky-view table, its kernels per pixel)
/// carries much of the multiply scattered light. Measured at 380-780 nm
/// (21 wavelengths; the test takes 440, 560 and 680):
/// earth-hazy within 0.7 %, mars-dust within 2.4 % (2.6 % at the test's
/// three wavelengths; 2 degrees along the
/// horizon from the sun 2 degrees high, 5 degrees from it: the tables a
/// little darker; 1.2 % at 5 degrees from a sun 5 degrees high), the same
/// with three times the sky-view table's azimuth nodes (so not its
/// azimuth interpolation; the source table's reading of mars-dust's
/// still peaked p* near the sun, or the sky-view table's zenith axis, not
/// separated yet).
#[test]
fn image_tables_agree_with_the_per_view_path_near_a_low_sun_with_aerosols() {
    // Three wavelengths keep it to a few seconds (the 21 of the default
    // grid were measured once, above).
    let grid = WavelengthGrid::new(440.0, 680.0, 120.0).unwrap();
    let mut worst = 0.0f64;
    for preset in ["earth-hazy", "mars-dust"] {
        let atmosphere = Atmosphere::preset(preset).unwrap();
        for sun in [5.0, 2.0] {
            let sky = Sky::builder(&atmosphere)
                .wavelengths(grid)
                .sun_deg(sun, 0.0)
                .polarisation(sora::Polarisation::Scalar)
                .build()
                .unwrap();
            worst = worst.max(worst_table_difference(
                &sky,
                &views_near_the_sun(sun),
                3e-2,
                &format!("{preset}, sun {sun}"),
            ));
        }
    }
    eprintln!("worst relative difference, image tables vs per view: {worst:.3e}");
}

/// The wavelengths for the zenith's smoothness, nm.
const SMOOTHNESS_WAVELENGTHS_NM: [f64; 3] = [440.0, 560.0, 660.0];

/// Zenith radiances at 440, 560 and 660 nm for each sun elevation, in
/// scalar or polarised light (a grid every 20 nm from 440 to 660, read at
/// those three).
fn zenith_radiances(suns: &[f64], polarisation: Polarisation) -> Vec<[f64; 3]> {
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    let grid = WavelengthGrid::new(440.0, 660.0, 20.0).unwrap();
    let indices = SMOOTHNESS_WAVELENGTHS_NM.map(|nm| {
        grid.wavelengths_nm()
            .position(|w| (w - nm).abs() < 1e-9)
            .unwrap()
    });
    let base = Sky::builder(&atmosphere)
        .wavelengths(grid)
        .sun_deg(suns[0], 0.0)
        .polarisation(polarisation)
        .build()
        .unwrap();
    let zenith = ViewDirection::new(90.0, 0.0).unwrap();
    suns.iter()
        .map(|sun| {
            let sky = base.with_sun_deg(*sun, 0.0).unwrap();
            let values = sky.radiance(zenith).unwrap().radiance_w_m2_sr_nm;
            indices.map(|i| values.values()[i])
        })
        .collect()
}

/// Monotone and smooth: returns the worst |second difference of ln L| and
/// where, panicking on a radiance that grows as the sun sinks.
#[allow(clippy::needless_range_loop)] // c indexes the inner arrays
fn check_smooth(suns: &[f64], radiances: &[[f64; 3]]) -> (f64, f64, usize) {
    let (mut worst, mut at_sun, mut at_wavelength) = (0.0f64, 0.0, 0);
    for c in 0..3 {
        for k in 1..suns.len() {
            assert!(
                radiances[k][c] < radiances[k - 1][c],
                "wavelength {c}: zenith radiance grows from sun {} ({:e}) to {} ({:e})",
                suns[k - 1],
                radiances[k - 1][c],
                suns[k],
                radiances[k][c]
            );
        }
        for k in 1..suns.len() - 1 {
            let second =
                radiances[k + 1][c].ln() - 2.0 * radiances[k][c].ln() + radiances[k - 1][c].ln();
            if second.abs() > worst {
                (worst, at_sun, at_wavelength) = (second.abs(), suns[k], c);
            }
        }
    }
    (worst, at_sun, at_wavelength)
}

/// Every 0.25 degree over `range` (start above end), both included.
fn suns_every_quarter_degree(start: f64, end: f64) -> Vec<f64> {
    let steps = ((start - end) / 0.25).round() as usize;
    (0..=steps).map(|k| start - 0.25 * k as f64).collect()
}

/// Where a kink is likeliest, every 0.25 degree: the sun crossing 6
/// degrees, where the eye's own sun node starts taking the spherical
/// first order (from 84 degrees zenith), and -8.5 to -10 degrees, where
/// the full sweep (ignored test below) measured its worst scalar second
/// difference; in polarised light also -9.25 to -10.75 degrees, where the
/// polarisation column's sun stops (-9.64 degrees on Earth; before it did,
/// the polarised zenith stepped 9 % onto the scalar one at -10.25), and
/// -11.75 to -12.75, where its polarisation starts to fade (-12.14;
/// `transport/multiple_scattering/regimes.rs`).
#[test]
fn zenith_radiance_is_smooth_where_it_could_kink() {
    for (polarisation, windows) in [
        (Polarisation::Scalar, &[(7.0, 4.5), (-8.5, -10.0)][..]),
        (
            Polarisation::Vector,
            &[(-9.25, -10.75), (-11.75, -12.75)][..],
        ),
    ] {
        for &(start, end) in windows {
            let suns = suns_every_quarter_degree(start, end);
            let radiances = zenith_radiances(&suns, polarisation);
            let (worst, sun, wavelength) = check_smooth(&suns, &radiances);
            eprintln!(
                "{polarisation:?}, sun {start}..{end}: worst |second difference of ln L| {worst:.4} at sun {sun}"
            );
            assert!(
                worst < 0.05,
                "{polarisation:?}: {worst} at sun {sun}, wavelength {wavelength}"
            );
        }
    }
}

/// The whole range, +10 to -18 degrees every 0.25 degree (113
/// skies each in scalar and polarised light). Measured: see
/// `docs/twilight_survey.md` (the zenith's smoothness).
#[test]
#[ignore]
fn zenith_radiance_is_smooth_from_day_to_astronomical_twilight() {
    let suns = suns_every_quarter_degree(10.0, -18.0);
    for polarisation in [Polarisation::Scalar, Polarisation::Vector] {
        let radiances = zenith_radiances(&suns, polarisation);
        for (sun, l) in suns.iter().zip(&radiances) {
            eprintln!(
                "{polarisation:?}, sun {sun:>6.2}: zenith {:.4e} {:.4e} {:.4e}",
                l[0], l[1], l[2]
            );
        }
        let (worst, sun, wavelength) = check_smooth(&suns, &radiances);
        eprintln!(
            "{polarisation:?}: worst |second difference of ln L| {worst:.4} at sun {sun} ({} nm)",
            SMOOTHNESS_WAVELENGTHS_NM[wavelength]
        );
        assert!(
            worst < 0.05,
            "{polarisation:?}: {worst} at sun {sun}, wavelength {wavelength}"
        );
    }
}

/// The fast method against the path tracer (all orders, unbiased) for
/// earth-clear with the sun at the given elevations and `views`
/// (elevation, azimuth from the sun): the worst excess over `bound(sun)`
/// plus three standard errors, over every wavelength; prints each view.
fn excess_over_path_tracer(
    suns: &[f64],
    views: &[(f64, f64)],
    samples: u64,
    bound: impl Fn(f64) -> f64,
) -> f64 {
    use sora::Method;
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    let directions: Vec<ViewDirection> = views
        .iter()
        .map(|(e, a)| ViewDirection::new(*e, *a).unwrap())
        .collect();
    let mut worst_excess = f64::NEG_INFINITY;
    for (n, &sun) in suns.iter().enumerate() {
        let fast = Sky::builder(&atmosphere)
            .sun_deg(sun, 0.0)
            .polarisation(sora::Polarisation::Scalar)
            .build()
            .unwrap();
        let traced = Sky::builder(&atmosphere)
            .sun_deg(sun, 0.0)
            .method(Method::PathTracing {
                samples,
                seed: 100 + n as u64,
            })
            .polarisation(sora::Polarisation::Scalar)
            .build()
            .unwrap()
            .radiances(&directions)
            .unwrap();
        let computed = fast.radiances(&directions).unwrap();
        for ((view, f), t) in views.iter().zip(&computed).zip(&traced) {
            let errors = t.standard_error_w_m2_sr_nm.as_ref().unwrap();
            let (mut worst, mut at, mut sigma_at) = (0.0f64, 0, 0.0);
            for i in 0..f.radiance_w_m2_sr_nm.len() {
                let expected = t.radiance_w_m2_sr_nm.values()[i];
                let sigma = errors.values()[i] / expected;
                let error = f.radiance_w_m2_sr_nm.values()[i] / expected - 1.0;
                worst_excess = worst_excess.max(error.abs() - bound(sun) - 3.0 * sigma);
                if error.abs() > worst.abs() {
                    (worst, at, sigma_at) = (error, i, sigma);
                }
            }
            eprintln!(
                "sun {sun:>5}, view {view:?}: worst {:+.2} % at {} nm (path tracer +-{:.2} %)",
                100.0 * worst,
                fast.wavelengths().wavelength_nm(at),
                100.0 * sigma_at
            );
        }
    }
    worst_excess
}

/// Civil twilight, a representative subset: within 3 % + 3 standard
/// errors at suns -2 and -4 degrees, 5 % + 3 standard errors at -6, in
/// the zenith, toward the sun low and away from it, every wavelength
/// (100 000 paths: the path tracer's standard error is 1-2 % at -2
/// degrees, 1-3 % at -4, 2-8 % at -6, at 380 nm the largest; 6-14 % at -6
/// before it drew free paths from the sunlit parts). Measured
/// with 400 000 paths (the ignored test's grid, 460/540/620 nm): within
/// 1.9 % at -2, 3.0 % at -4, 7.3 % at -6 (the zenith, the path tracer at
/// +-3.2 %). Before the field's first order was spherical: -2 degrees
/// +16 %, -4 +20 %, -6 -39 %.
#[test]
fn civil_twilight_matches_the_path_tracer() {
    let views = [(90.0, 0.0), (20.0, 0.0), (5.0, 180.0)];
    let excess = excess_over_path_tracer(&[-2.0, -4.0, -6.0], &views, 100_000, |sun| {
        if sun >= -4.0 { 0.03 } else { 0.05 }
    });
    assert!(excess <= 0.0, "beyond the bound + 3 sigma by {excess}");
}

/// The whole grid (about an hour on 2 cores): suns 0 to -12 degrees, the
/// zenith and view elevations 5, 20, 45 degrees at 0, 90 and 180 degrees
/// from the sun, within 3 % plus 3 standard errors down to -6 degrees and
/// 5 % plus 3 standard errors at -8 to -12 (400 000 paths; 1 000 000 at
/// -10 and -12, where the path tracer's standard error at the worst
/// wavelength was 7-12 % and 12-28 % before it drew directions toward the
/// sunlit air from shadowed vertices, and is now 1-8 % at 560 and 680 nm
/// at 1 000 000 paths; 10-60 % before it drew free paths from the sunlit
/// parts). With that precision it failed at -12 degrees until the first
/// order's moments were integrated finely: the fast method was 10-17 %
/// too dark there; the survey's 1 000 000-path runs of these views now
/// have all of -8 to -12 within the bound (`docs/twilight_survey.md`,
/// deep twilight, fixed). Not run whole since.
#[test]
#[ignore]
fn twilight_matches_the_path_tracer_over_the_whole_grid() {
    let mut views = vec![(90.0, 0.0)];
    for elevation in [5.0, 20.0, 45.0] {
        for azimuth in [0.0, 90.0, 180.0] {
            views.push((elevation, azimuth));
        }
    }
    let bound = |sun: f64| if sun >= -6.0 { 0.03 } else { 0.05 };
    let civil = excess_over_path_tracer(&[0.0, -2.0, -4.0, -6.0, -8.0], &views, 400_000, bound);
    let nautical = excess_over_path_tracer(&[-10.0, -12.0], &views, 1_000_000, bound);
    assert!(
        civil <= 0.0,
        "sun 0..-8: beyond the bound + 3 sigma by {civil}"
    );
    assert!(
        nautical <= 0.0,
        "sun -10, -12: beyond the bound + 3 sigma by {nautical}"
    );
}

/// The fast method against the path tracer (`samples` paths, `seed`) at
/// the sun `sun_deg` high (azimuth 0), every view and wavelength of
/// `grid`, within the 3 % plus 3 standard errors (`place` names
/// the sky in the messages).
fn assert_fast_matches_the_path_tracer(
    place: &str,
    atmosphere: &Atmosphere,
    grid: WavelengthGrid,
    sun_deg: f64,
    views: &[ViewDirection],
    (samples, seed): (u64, u64),
) {
    use sora::Method;
    let sky = |method| {
        Sky::builder(atmosphere)
            .wavelengths(grid)
            .sun_deg(sun_deg, 0.0)
            .method(method)
            .polarisation(sora::Polarisation::Scalar)
            .build()
            .unwrap()
            .radiances(views)
            .unwrap()
    };
    let fast = sky(Method::Fast);
    let traced = sky(Method::PathTracing { samples, seed });
    for ((view, f), t) in views.iter().zip(&fast).zip(&traced) {
        let view = (view.elevation_deg(), view.azimuth_deg());
        let errors = t.standard_error_w_m2_sr_nm.as_ref().unwrap();
        for i in 0..grid.len() {
            let expected = t.radiance_w_m2_sr_nm.values()[i];
            let sigma = errors.values()[i] / expected;
            let error = f.radiance_w_m2_sr_nm.values()[i] / expected - 1.0;
            eprintln!(
                "{place}, view {view:?}, {} nm: {:+.2} % (path tracer +-{:.2} %)",
                grid.wavelength_nm(i),
                100.0 * error,
                100.0 * sigma
            );
            assert!(
                error.abs() <= 0.03 + 3.0 * sigma,
                "{place}, view {view:?}, {} nm: {error:+.4} against +-{sigma:.4}",
                grid.wavelength_nm(i)
            );
        }
    }
}

/// The fast method against the path tracer where civil twilight is
/// hardest for it (earth-clear, sun -6 degrees, 440, 560 and 680 nm):
/// toward the sun 5 degrees up and the zenith, within the 3 %
/// plus 3 standard errors (200 000 paths: 0.6-3 %; about 4 s of CPU).
/// Measured with 1 600 000 paths
/// (`transport/reference_tests/twilight_survey.rs`): -1.7, -0.2 and
/// -0.1 % toward the sun (+-0.5, 0.4, 0.2 %), -2.8, -0.9 and -0.4 % at
/// the zenith (+-1.1, 0.7, 0.4 %), -2.0, -0.3 and +1.1 % away from it
/// (+-1.4, 1.3, 1.1 %); before the orders >= 2 of the near-horizontal
/// streams were shifted to where they gather their light, -3.4, -1.5
/// and -0.9 % toward the sun, -3.9, -2.2 and -1.3 % at the zenith.
#[test]
fn sun_six_below_matches_the_path_tracer_at_three_wavelengths() {
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    let grid = WavelengthGrid::new(440.0, 680.0, 120.0).unwrap();
    let views: Vec<ViewDirection> = [(5.0, 0.0), (90.0, 0.0)]
        .iter()
        .map(|(e, a)| ViewDirection::new(*e, *a).unwrap())
        .collect();
    assert_fast_matches_the_path_tracer(
        "earth-clear, sun -6",
        &atmosphere,
        grid,
        -6.0,
        &views,
        (200_000, 6),
    );
}

/// Near a low sun with Mie aerosols, where delta-M's forward-peak term
/// (`transport/multiple_scattering/forward_peak.rs`) carries much of the
/// multiply scattered light: the fast method against the path tracer
/// within the 3 % plus 3 standard errors at 440, 560 and 680 nm,
/// mars-dust 5 degrees from a sun 5 degrees high (along the horizon)
/// and earth-hazy 2 degrees from it (50 000 paths: standard errors
/// 0.6-0.8 %; about 5 s of CPU). Measured with 400 000 and 800 000 paths
/// (`transport/reference_tests/twilight_survey.rs`, docs/twilight_survey.md);
/// with the forward-peak term taken as p(theta) out of a 4.3 degree cone
/// (before) mars-dust was +10 to +17 % here and earth-hazy -5 to -6 %.
#[test]
fn near_a_low_sun_with_aerosols_matches_the_path_tracer() {
    let grid = WavelengthGrid::new(440.0, 680.0, 120.0).unwrap();
    for (preset, view, seed) in [
        ("mars-dust", (5.0, 5.0), 51),
        ("earth-hazy", (5.0, 2.0), 52),
    ] {
        let atmosphere = Atmosphere::preset(preset).unwrap();
        assert_fast_matches_the_path_tracer(
            preset,
            &atmosphere,
            grid,
            5.0,
            &[ViewDirection::new(view.0, view.1).unwrap()],
            (50_000, seed),
        );
    }
}

/// The sun on the horizon seen through mars-dust, 1 degree above the
/// horizon 2 degrees from the sun, where the eye sees almost only light
/// scattered more than once, most of it in the dust's forward peak: the
/// fast method against the path tracer within the 3 % plus 3
/// standard errors at 440, 560 and 680 nm (400 000 paths: 0.7-1.0 %;
/// about 6 s of CPU). Measured: -4.7, -3.3 and -2.2 % (+-1.0, 0.8,
/// 0.7 %); without the peak's last scattering at its angle
/// (`transport/multiple_scattering/peak_beam.rs`) -8.7 % at 440 nm
/// against a bar of 6.1 %, which failed.
#[test]
fn the_sun_on_the_horizon_through_dust_matches_the_path_tracer() {
    let atmosphere = Atmosphere::preset("mars-dust").unwrap();
    assert_fast_matches_the_path_tracer(
        "mars-dust",
        &atmosphere,
        WavelengthGrid::new(440.0, 680.0, 120.0).unwrap(),
        0.0,
        &[ViewDirection::new(1.0, 2.0).unwrap()],
        (400_000, 53),
    );
}

/// The streams converge in nautical twilight: with the sun 12 degrees
/// below the horizon (earth-clear; the zenith, 45 degrees up toward and
/// away from the sun; 440, 560 and 680 nm) the default 8 streams per
/// hemisphere are within 2 % of 16 (measured +0.2 to +1.1 %). Before the
/// first order's moments were integrated on a fine grid near the horizon,
/// 16 streams were 4-12 % brighter (docs/twilight_survey.md): the 8
/// streams' quadrature of the first order's narrow peak above the sunward
/// horizon.
#[test]
fn nautical_twilight_is_converged_in_the_streams() {
    use sora::{MultipleScatteringSettings, Scattering};
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    let grid = WavelengthGrid::new(440.0, 680.0, 120.0).unwrap();
    let views: Vec<ViewDirection> = [(90.0, 0.0), (45.0, 0.0), (45.0, 180.0)]
        .iter()
        .map(|(e, a)| ViewDirection::new(*e, *a).unwrap())
        .collect();
    let radiances = |streams_per_hemisphere: usize| {
        let settings = MultipleScatteringSettings {
            streams_per_hemisphere,
            ..MultipleScatteringSettings::default()
        };
        Sky::builder(&atmosphere)
            .wavelengths(grid)
            .sun_deg(-12.0, 0.0)
            .scattering(Scattering::Multiple(settings))
            .polarisation(sora::Polarisation::Scalar)
            .build()
            .unwrap()
            .radiances(&views)
            .unwrap()
    };
    let (default, more) = (radiances(8), radiances(16));
    for ((view, d), m) in views.iter().zip(&default).zip(&more) {
        for i in 0..grid.len() {
            let ratio = d.radiance_w_m2_sr_nm.values()[i] / m.radiance_w_m2_sr_nm.values()[i];
            eprintln!(
                "view ({}, {}), {} nm: 8 / 16 streams - 1 = {:+.2} %",
                view.elevation_deg(),
                view.azimuth_deg(),
                grid.wavelength_nm(i),
                100.0 * (ratio - 1.0)
            );
            assert!(
                (ratio - 1.0).abs() < 0.02,
                "view ({}, {}), {} nm: 8 streams / 16 = {ratio}",
                view.elevation_deg(),
                view.azimuth_deg(),
                grid.wavelength_nm(i)
            );
        }
    }
}
