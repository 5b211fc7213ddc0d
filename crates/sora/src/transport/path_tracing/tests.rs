//! The path tracer's own tests (the reference tests against other methods
//! are in `transport/reference_tests/`).

use std::f64::consts::PI;

use super::estimate::{ChunkStatistics, MAX_SAMPLES, SpectralEstimate, worst_relative_error};
use super::free_path::sunlit_parts;
use super::tracer::PathTracer;
use crate::atmosphere::{Atmosphere, AtmosphereOptics, DensityProfile, PhaseFunction};
use crate::geometry::{Vector3, direction_from_elevation_azimuth};
use crate::spectrum::{SampledSpectrum, WavelengthGrid};
use crate::transport::random::RandomStream;
use crate::transport::single_scattering::SingleScatteringScene;
use crate::transport::{Observation, SunColumns};

fn clear_sky(ground_albedo: f64) -> SingleScatteringScene {
    let atmosphere = Atmosphere::preset("clear-sky-reference").unwrap();
    let mut optics = atmosphere.compute_optics(&WavelengthGrid::paper()).unwrap();
    optics.ground_albedo = SampledSpectrum::constant(optics.grid.len(), ground_albedo);
    let observation = Observation {
        observer_altitude_m: 0.0,
        sun_elevation_deg: 36.0,
        sun_azimuth_deg: 207.0,
    };
    SingleScatteringScene::from_optics(
        optics,
        atmosphere.planet.radius_m(),
        atmosphere.planet.top_radius_m(),
        0.0,
        observation,
    )
    .unwrap()
}

/// The sunlit parts of random segments against the shadow test of the
/// sun columns (`ray_intersects_ground` at each point), at 2001 points
/// along each: every point agrees except within a step of a boundary.
#[test]
fn sunlit_parts_match_the_pointwise_shadow_test() {
    let ground = 6_360e3;
    let mut random = RandomStream::new(7, 0);
    let mut partial = 0;
    for _ in 0..2000 {
        let unit = |random: &mut RandomStream| {
            let z = 2.0 * random.next_f64() - 1.0;
            let phi = 2.0 * PI * random.next_f64();
            let r = (1.0 - z * z).sqrt();
            Vector3::new(r * phi.cos(), r * phi.sin(), z)
        };
        let sun = unit(&mut random);
        let start = unit(&mut random) * (ground + 100e3 * random.next_f64());
        let direction = unit(&mut random);
        let length = 2_000e3 * random.next_f64();
        let lit = sunlit_parts(start, direction, length, sun, ground);
        if lit.is_partial(length) {
            partial += 1;
        }
        let step = length / 2000.0;
        for k in 0..=2000 {
            let t = k as f64 * step;
            let p = start + direction * t;
            let r = p.length();
            let in_shadow = crate::geometry::ray_intersects_ground(r, p.dot(sun) / r, ground);
            let near_boundary = lit
                .parts()
                .iter()
                .any(|(a, b)| (t - a).abs() <= step || (t - b).abs() <= step);
            if !near_boundary {
                assert_eq!(
                    lit.contains(t),
                    !in_shadow,
                    "t {t} of {length}, sun {sun:?}"
                );
            }
        }
    }
    assert!(partial > 100, "only {partial} segments cut by the shadow");
}

/// Drawing a share of the free paths from the sunlit parts and of the
/// directions toward the sunlit air (with the roulette's exception in
/// shadow) changes the noise, not the expectation: at sun -3, -6 and
/// -9 degrees (earth-clear, zenith and 10 degrees above the sunward
/// horizon), the two ways agree within 4 combined standard errors at
/// every wavelength, and the sunlit sampling is the less noisy at the
/// zenith. At -3 degrees the air below 9 km over the eye is in shadow,
/// so every sampler is at work, and both ways are precise (200 000
/// paths: 1-2 % without): there the test sees a bias of a few per cent;
/// at -6 and -9 degrees (40 000 paths) the way without is too noisy to
/// see less than 30-100 %.
#[test]
fn sunlit_sampling_is_unbiased_at_twilight() {
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    for (sun, samples) in [(-3.0, 200_000), (-6.0, 40_000), (-9.0, 40_000)] {
        let observation = Observation {
            observer_altitude_m: 0.0,
            sun_elevation_deg: sun,
            sun_azimuth_deg: 270.0,
        };
        let sky =
            SingleScatteringScene::new(&atmosphere, &WavelengthGrid::paper(), observation).unwrap();
        let with = PathTracer::new(&sky);
        let without = PathTracer::new(&sky).without_twilight_sampling();
        for (name, view) in [
            ("zenith", Vector3::new(0.0, 0.0, 1.0)),
            (
                "sunward 10 deg",
                crate::geometry::direction_from_elevation_azimuth(10.0, 270.0),
            ),
        ] {
            let a = with.compute_radiance(view, samples, 11).unwrap().total;
            let b = without.compute_radiance(view, samples, 12).unwrap().total;
            let mut worst: f64 = 0.0;
            for i in 0..a.mean.len() {
                let sigma = a.standard_error.values()[i].hypot(b.standard_error.values()[i]);
                let z = (a.mean.values()[i] - b.mean.values()[i]) / sigma;
                worst = worst.max(z.abs());
            }
            let noise = |e: &SpectralEstimate| {
                worst_relative_error(e.mean.values(), e.standard_error.values())
            };
            eprintln!(
                "sun {sun}, {name}: worst |difference| {worst:.2} sigma; relative standard error {:.3} with sunlit sampling, {:.3} without",
                noise(&a),
                noise(&b)
            );
            assert!(worst < 4.0, "sun {sun}, {name}: {worst:.2} sigma apart");
            if name == "zenith" {
                assert!(
                    noise(&a) < noise(&b),
                    "sun {sun}: {} >= {}",
                    noise(&a),
                    noise(&b)
                );
            }
        }
    }
}

/// The error bars at twilight (earth-clear, sun -6 degrees, the zenith
/// and 10 degrees above the sunward horizon, 380, 540 and 780 nm): 100
/// runs of 10 000 paths against one of 8 000 000. The runs' mean agrees
/// with the reference within 4 standard errors of that mean, and the
/// standard error the runs report (root mean square) is their actual
/// spread within 20 %. Measured: the spread 16.5, 9.1, 6.7 % at the
/// zenith and 9.3, 5.3, 2.4 % sunward (without the sunlit sampling 32,
/// 22, 15 and 17, 15, 7.0 %), reported within 8 %, the means within
/// 1.2 standard errors. The z-scores of
/// single runs are skewed (mean -0.45 to 0, root mean square 0.96 to
/// 1.41): twilight light arrives in rare heavy paths, and a run that
/// misses them is low and reports a small error, so at 10 000 paths one
/// run's error bar is honest on average, not run by run. Two minutes on
/// two cores.
#[test]
#[ignore]
fn error_bars_are_calibrated_at_twilight() {
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    let grid = WavelengthGrid::paper();
    let observation = Observation {
        observer_altitude_m: 0.0,
        sun_elevation_deg: -6.0,
        sun_azimuth_deg: 270.0,
    };
    let sky = SingleScatteringScene::new(&atmosphere, &grid, observation).unwrap();
    let tracer = PathTracer::new(&sky);
    for (name, view) in [
        ("zenith", Vector3::new(0.0, 0.0, 1.0)),
        (
            "sunward 10 deg",
            direction_from_elevation_azimuth(10.0, 270.0),
        ),
    ] {
        let reference = tracer.compute_radiance(view, 8_000_000, 500).unwrap().total;
        for wavelength in [380.0, 540.0, 780.0] {
            let i = ((wavelength - grid.start_nm()) / grid.step_nm()).round() as usize;
            let runs: Vec<(f64, f64)> = (0..100)
                .map(|run| {
                    let e = tracer
                        .compute_radiance(view, 10_000, 1_000 + run)
                        .unwrap()
                        .total;
                    (e.mean.values()[i], e.standard_error.values()[i])
                })
                .collect();
            let n = runs.len() as f64;
            let (truth, truth_error) = (
                reference.mean.values()[i],
                reference.standard_error.values()[i],
            );
            let mean = runs.iter().map(|r| r.0).sum::<f64>() / n;
            let spread =
                (runs.iter().map(|r| (r.0 - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            let reported = (runs.iter().map(|r| r.1 * r.1).sum::<f64>() / n).sqrt();
            let z: Vec<f64> = runs
                .iter()
                .map(|(m, e)| (m - truth) / e.hypot(truth_error))
                .collect();
            let z_mean = z.iter().sum::<f64>() / n;
            let z_rms = (z.iter().map(|z| z * z).sum::<f64>() / n).sqrt();
            eprintln!(
                "{name}, {wavelength} nm: runs' spread {:.2} %, reported {:.2} %, runs' mean / reference {:.4} (+-{:.4}); single-run z mean {z_mean:+.2}, rms {z_rms:.2}",
                100.0 * spread / mean,
                100.0 * reported / mean,
                mean / truth,
                (spread / n.sqrt()).hypot(truth_error) / truth
            );
            assert!(
                (mean - truth).abs() < 4.0 * (spread / n.sqrt()).hypot(truth_error),
                "{name}, {wavelength} nm: runs' mean {mean} against {truth}"
            );
            assert!(
                (reported / spread - 1.0).abs() < 0.2,
                "{name}, {wavelength} nm: reported {reported} against a spread of {spread}"
            );
        }
    }
}

/// More than MAX_SAMPLES paths is an error before anything is
/// allocated (issue 17), naming the value and the limit.
#[test]
fn samples_are_limited() {
    let sky = clear_sky(0.3);
    let tracer = PathTracer::new(&sky);
    let view = direction_from_elevation_azimuth(17.0, 347.0);
    for samples in [MAX_SAMPLES + 1, 1_000_000_000_000, u64::MAX] {
        let message = tracer
            .compute_radiance(view, samples, 1)
            .unwrap_err()
            .to_string();
        assert!(message.contains("samples = "), "{message}");
        assert!(message.contains("<= 1e9"), "{message}");
    }
}

/// The same seed gives bit-identical results on one thread and on
/// several; another seed gives another (equally valid) result.
#[cfg(feature = "parallel")]
#[test]
fn results_do_not_depend_on_the_thread_count() {
    let sky = clear_sky(0.3);
    let tracer = PathTracer::new(&sky);
    let view = direction_from_elevation_azimuth(17.0, 347.0);
    // Not a multiple of the chunk size: the last chunk is partial.
    let samples = 5 * super::estimate::SAMPLES_PER_CHUNK + 37;
    let on = |threads: usize, seed: u64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| tracer.compute_radiance(view, samples, seed).unwrap())
    };
    let one = on(1, 9);
    assert_eq!(one, on(3, 9));
    assert_eq!(one, on(2, 9));
    let other = on(2, 10);
    assert_ne!(one.total.mean, other.total.mean);
    assert_eq!(one.samples, samples);
    // The parts add up to the total, sample by sample, hence in the mean.
    for i in 0..one.total.mean.len() {
        let parts = one.single_scattering.mean[i]
            + one.sunlit_ground.mean[i]
            + one.multiple_scattering.mean[i];
        assert!((parts / one.total.mean[i] - 1.0).abs() < 1e-12);
    }
}

/// Without any species, the eye looking down sees only the sunlit
/// Lambertian ground, a/pi E mu_s, exactly (every path scores the same),
/// and looking up sees nothing.
#[test]
fn an_empty_sky_shows_the_sunlit_ground_exactly() {
    let grid = WavelengthGrid::new(400.0, 700.0, 100.0).unwrap();
    let n = grid.len();
    let optics = AtmosphereOptics {
        grid,
        solar_irradiance_w_m2_nm: SampledSpectrum::from_values(vec![1.0, 2.0, 1.5, 0.5]),
        ground_albedo: SampledSpectrum::from_values(vec![0.1, 0.5, 0.9, 1.0]),
        species: Vec::new(),
    };
    let observation = Observation {
        observer_altitude_m: 2e3,
        sun_elevation_deg: 30.0,
        sun_azimuth_deg: 0.0,
    };
    let sky = SingleScatteringScene::from_optics(optics, 6360e3, 6460e3, 0.0, observation).unwrap();
    let tracer = PathTracer::new(&sky);
    let down = tracer
        .compute_radiance(direction_from_elevation_azimuth(-40.0, 10.0), 100, 1)
        .unwrap();
    for i in 0..n {
        // The ground point is a little away from the eye's nadir: the sun
        // is a little lower or higher there on the sphere.
        let expected =
            sky.optics().ground_albedo[i] / PI * sky.optics().solar_irradiance_w_m2_nm[i] * 0.5;
        assert!((down.total.mean[i] / expected - 1.0).abs() < 2e-3, "{i}");
        assert_eq!(down.total.mean[i], down.sunlit_ground.mean[i]);
        assert!(down.total.standard_error[i] <= 1e-12 * expected);
    }
    let up = tracer
        .compute_radiance(direction_from_elevation_azimuth(40.0, 10.0), 100, 1)
        .unwrap();
    assert!(up.total.mean.values().iter().all(|v| *v == 0.0));
}

/// A kinked (tent) scattering layer, 2-4 km: the rays are cut where
/// they cross its corners, and the single-scattering part agrees with
/// the paper's uniform double march (fine steps, which sees the
/// corners), within 3 standard errors at every wavelength, from below,
/// inside and at the peak of the layer. (Without the cuts the tracer
/// was 1.4% low at 400 nm from the ground at 10 deg elevation, and the
/// single-scattering fast path 0.9% high.) The fast path, cut at the
/// same corners, agrees with the march to 1e-4.
#[test]
fn a_layer_profile_is_sampled_without_bias() {
    use crate::atmosphere::SpeciesOptics;
    let grid = WavelengthGrid::new(400.0, 700.0, 100.0).unwrap();
    let n = grid.len();
    let layer = SpeciesOptics {
        name: "layer".into(),
        kind: "parametric aerosol",
        profile: DensityProfile::tent(3e3, 1e3, "layer").unwrap(),
        vertical_column_m: 1e3,
        reference_number_density_m3: None,
        extinction_per_m: SampledSpectrum::from_values(vec![3e-4, 2.5e-4, 2e-4, 1.5e-4]),
        scattering_per_m: SampledSpectrum::from_values(vec![2.7e-4, 2.2e-4, 1.8e-4, 1.4e-4]),
        phase_function: PhaseFunction::HenyeyGreenstein {
            asymmetry_g: vec![0.6, 0.65, 0.7, 0.75],
        },
    };
    for (altitude, elevation) in [(0.0, 10.0), (3.5e3, -20.0), (3e3, 2.0)] {
        let optics = AtmosphereOptics {
            grid,
            solar_irradiance_w_m2_nm: SampledSpectrum::constant(n, 1.0),
            ground_albedo: SampledSpectrum::zeros(n),
            species: vec![layer.clone()],
        };
        let observation = Observation {
            observer_altitude_m: altitude,
            sun_elevation_deg: 40.0,
            sun_azimuth_deg: 0.0,
        };
        let sky =
            SingleScatteringScene::from_optics(optics, 6360e3, 6460e3, 0.0, observation).unwrap();
        let view = direction_from_elevation_azimuth(elevation, 150.0);
        let march = sky.compute_radiance_reference(view, 20_000, 2_000);
        let mut fast = SampledSpectrum::zeros(n);
        sky.compute_radiance(view, SunColumns::Exact, &mut sky.scratch(), &mut fast);
        for i in 0..n {
            assert!(
                (fast[i] / march[i] - 1.0).abs() < 1e-4,
                "fast path, eye {altitude} m, view {elevation} deg, {i}: {} vs {}",
                fast[i],
                march[i]
            );
        }
        let traced = PathTracer::new(&sky)
            .compute_radiance(view, 20_000, 3)
            .unwrap();
        let single = &traced.single_scattering;
        for i in 0..n {
            let z = (single.mean[i] - march[i]) / single.standard_error[i];
            assert!(
                z.abs() < 3.0 && single.standard_error[i] < 0.01 * march[i],
                "eye {altitude} m, view {elevation} deg, {i}: {} +- {} vs {} ({z} sigma)",
                single.mean[i],
                single.standard_error[i],
                march[i]
            );
        }
    }
}

#[test]
fn arguments_are_checked() {
    let sky = clear_sky(0.0);
    let tracer = PathTracer::new(&sky);
    let up = Vector3::new(0.0, 0.0, 1.0);
    assert!(tracer.compute_radiance(up, 1, 1).is_err());
    assert!(tracer.compute_radiance(up * 2.0, 10, 1).is_err());
    assert!(
        tracer
            .compute_irradiance(Vector3::default(), 10, 1)
            .is_err()
    );
    assert!(tracer.compute_radiance(up, 2, 1).is_ok());
}

#[test]
fn chunk_statistics_combine_like_one_pass() {
    let values: Vec<f64> = (0..1000)
        .map(|i| ((i * 37) % 101) as f64 * 0.1 + 3.0)
        .collect();
    let mut one = ChunkStatistics::default();
    for v in &values {
        one.add(&[*v]);
    }
    let mut combined = ChunkStatistics::default();
    for chunk in values.chunks(77) {
        let mut part = ChunkStatistics::default();
        for v in chunk {
            part.add(&[*v]);
        }
        combined.merge(&part);
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let m2: f64 = values.iter().map(|v| (v - mean).powi(2)).sum();
    assert!((one.mean[0] - mean).abs() < 1e-12 && (combined.mean[0] - mean).abs() < 1e-12);
    assert!((one.squared_deviations[0] / m2 - 1.0).abs() < 1e-12);
    assert!((combined.squared_deviations[0] / m2 - 1.0).abs() < 1e-12);
}
