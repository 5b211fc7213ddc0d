//! The front door, [`sora::Sky`]: one composition point for every method,
//! many views per call, images as XYZ and as spectra, and its errors.

use sora::colour::{Observer, SpectrumToXyz};
use sora::{Atmosphere, Camera, ImageSettings, Method, Scattering, Sky, ViewDirection};

fn views() -> Vec<ViewDirection> {
    [
        (90.0, 0.0),
        (30.0, 180.0),
        (5.0, 90.0),
        (-20.0, 0.0),
        (0.5, 300.0),
    ]
    .iter()
    .map(|&(e, a)| ViewDirection::new(e, a).unwrap())
    .collect()
}

/// Many views in one call give each view's own numbers to the last bit,
/// for the fast and reference methods, single and multiple scattering.
#[test]
fn many_views_equal_one_view_at_a_time() {
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    for (scattering, method) in [
        (Scattering::multiple(), Method::Fast),
        (Scattering::Single, Method::Fast),
        (
            Scattering::multiple(),
            Method::Reference {
                view_steps: 200,
                sun_steps: 50,
            },
        ),
    ] {
        let sky = Sky::builder(&atmosphere)
            .sun_deg(20.0, 200.0)
            .scattering(scattering)
            .method(method)
            .polarisation(sora::Polarisation::Scalar)
            .build()
            .unwrap();
        let together = sky.radiances(&views()).unwrap();
        for (view, all) in views().into_iter().zip(&together) {
            let alone = sky.radiance(view).unwrap();
            assert_eq!(&alone, all, "{view:?} {method:?}");
            assert!(alone.standard_error_w_m2_sr_nm.is_none());
            assert!(
                alone
                    .radiance_w_m2_sr_nm
                    .values()
                    .iter()
                    .all(|l| l.is_finite() && *l > 0.0)
            );
        }
    }
}

/// Multiple scattering only adds light, and the path tracer (all orders)
/// agrees with the fast method within 3 % plus three of its standard errors
/// at the zenith (a smoke test; the reference tests are thorough).
#[test]
fn the_orders_of_scattering_and_the_path_tracer_agree() {
    let atmosphere = Atmosphere::preset("clear-sky-reference").unwrap();
    let build = |scattering, method| {
        Sky::builder(&atmosphere)
            .sun_deg(40.0, 180.0)
            .scattering(scattering)
            .method(method)
            .polarisation(sora::Polarisation::Scalar)
            .build()
            .unwrap()
    };
    let zenith = ViewDirection::new(90.0, 0.0).unwrap();
    let single = build(Scattering::Single, Method::Fast)
        .radiance(zenith)
        .unwrap();
    let multiple = build(Scattering::multiple(), Method::Fast)
        .radiance(zenith)
        .unwrap();
    let traced = build(
        Scattering::multiple(),
        Method::PathTracing {
            samples: 4000,
            seed: 3,
        },
    )
    .radiance(zenith)
    .unwrap();
    let errors = traced.standard_error_w_m2_sr_nm.clone().unwrap();
    assert!(traced.worst_relative_standard_error() > 0.0);
    for i in 0..single.radiance_w_m2_sr_nm.len() {
        let (s, m, t) = (
            single.radiance_w_m2_sr_nm[i],
            multiple.radiance_w_m2_sr_nm[i],
            traced.radiance_w_m2_sr_nm[i],
        );
        assert!(m > s, "{i}: {m} <= {s}");
        assert!(
            (m - t).abs() < 0.03 * t + 3.0 * errors[i],
            "{i}: {m} vs {t} +- {}",
            errors[i]
        );
    }
}

/// The spectral image's pixels, integrated to XYZ, are the XYZ image's.
#[test]
fn spectral_and_xyz_images_agree() {
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    let sky = Sky::builder(&atmosphere)
        .sun_deg(10.0, 250.0)
        .polarisation(sora::Polarisation::Scalar)
        .build()
        .unwrap();
    let image = ImageSettings::new(Camera::Equirectangular, 24, 12);
    let to_xyz = SpectrumToXyz::new(sky.wavelengths(), Observer::Cie1931TwoDegree);
    let rows = std::sync::atomic::AtomicUsize::new(0);
    let xyz = sky
        .render_xyz(&image, &to_xyz, &|_| {
            rows.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        })
        .unwrap();
    assert_eq!(rows.into_inner(), 12);
    let spectral = sky.render_spectral(&image, &|_| {}).unwrap();
    let n = sky.wavelengths().len();
    assert_eq!(spectral.len(), 24 * 12 * n);
    for (pixel, colour) in spectral.chunks(n).zip(&xyz) {
        let spectrum = sora::spectrum::SampledSpectrum::from_values(pixel.to_vec());
        assert_eq!(to_xyz.to_xyz(&spectrum).unwrap(), *colour);
    }
}

/// An atmosphere without species is vacuum: a black sky, the sunlit
/// ground below the horizon, and no panic in any table.
#[test]
fn a_sky_without_species_is_black_above_the_horizon() {
    let preset = sora::atmosphere::presets::find_preset("earth-clear").unwrap();
    let text = &preset.toml[..preset.toml.find("[[species]]").unwrap()];
    let atmosphere = Atmosphere::from_toml_str(text).unwrap();
    assert!(atmosphere.species.is_empty());
    let sky = Sky::builder(&atmosphere)
        .sun_deg(30.0, 180.0)
        .polarisation(sora::Polarisation::Scalar)
        .build()
        .unwrap();
    let up = sky
        .radiance(ViewDirection::new(45.0, 0.0).unwrap())
        .unwrap();
    assert!(up.radiance_w_m2_sr_nm.values().iter().all(|l| *l == 0.0));
    let down = sky
        .radiance(ViewDirection::new(-45.0, 0.0).unwrap())
        .unwrap();
    assert!(down.radiance_w_m2_sr_nm.values().iter().all(|l| *l > 0.0));
    let to_xyz = SpectrumToXyz::new(sky.wavelengths(), Observer::Cie1931TwoDegree);
    let image = sky
        .render_xyz(&ImageSettings::new(Camera::Fisheye, 8, 8), &to_xyz, &|_| {})
        .unwrap();
    assert!(image.iter().all(|c| c.is_finite()));
}

/// Without species and with the sun low (10 degrees and below, where the
/// first order of the multiple scattering is marched in a sphere) the sky
/// is still vacuum: black radiance and Stokes vectors, the direct beam
/// alone on the ground, for scalar and polarised light.
#[test]
fn a_sky_without_species_under_a_low_sun_is_black_too() {
    let preset = sora::atmosphere::presets::find_preset("earth-clear").unwrap();
    let text = &preset.toml[..preset.toml.find("[[species]]").unwrap()];
    let atmosphere = Atmosphere::from_toml_str(text).unwrap();
    let to_xyz_of = |sky: &Sky| SpectrumToXyz::new(sky.wavelengths(), Observer::Cie1931TwoDegree);
    for elevation in [10.0, 5.0, 0.5, -3.0] {
        for polarisation in [sora::Polarisation::Scalar, sora::Polarisation::Vector] {
            let sky = Sky::builder(&atmosphere)
                .sun_deg(elevation, 180.0)
                .polarisation(polarisation)
                .build()
                .unwrap();
            let up = sky
                .radiance(ViewDirection::new(20.0, 0.0).unwrap())
                .unwrap();
            assert!(up.radiance_w_m2_sr_nm.values().iter().all(|l| *l == 0.0));
            if let Some(stokes) = &up.stokes {
                assert!(stokes.q_w_m2_sr_nm.values().iter().all(|q| *q == 0.0));
            }
            let image = sky
                .render_xyz(
                    &ImageSettings::new(Camera::Fisheye, 8, 8),
                    &to_xyz_of(&sky),
                    &|_| {},
                )
                .unwrap();
            assert!(image.iter().all(|c| c.is_finite()));
            let irradiance = sky.irradiance(sora::Plane::HORIZONTAL).unwrap();
            assert!(
                irradiance
                    .diffuse_w_m2_nm
                    .values()
                    .iter()
                    .all(|e| *e == 0.0)
            );
            assert_eq!(irradiance.direct_w_m2_nm, irradiance.global_w_m2_nm);
        }
    }
}

#[test]
fn bad_choices_are_errors_not_panics() {
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    let error = |builder: sora::SkyBuilder| builder.build().unwrap_err().to_string();
    assert!(error(Sky::builder(&atmosphere).sun_deg(95.0, 0.0)).contains("sun elevation = 95 deg"));
    assert!(
        error(Sky::builder(&atmosphere).observer_altitude_m(-1.0)).contains("observer altitude")
    );
    assert!(
        error(Sky::builder(&atmosphere).method(Method::PathTracing {
            samples: 1,
            seed: 0
        }))
        .contains("samples = 1")
    );
    assert!(
        error(
            Sky::builder(&atmosphere)
                .scattering(Scattering::Single)
                .method(Method::PathTracing {
                    samples: 10,
                    seed: 0
                })
        )
        .contains("all orders")
    );
    let settings = sora::MultipleScatteringSettings {
        layers: 1,
        ..Default::default()
    };
    assert!(
        error(Sky::builder(&atmosphere).scattering(Scattering::Multiple(settings)))
            .contains("multiple-scattering layers = 1")
    );
    // The reference march: each count, and their product per view (1e7 x
    // 1e7 steps would have run for days; the default is 1000 x 250).
    let march = |view_steps, sun_steps| Method::Reference {
        view_steps,
        sun_steps,
    };
    assert!(error(Sky::builder(&atmosphere).method(march(0, 5))).contains("view steps = 0"));
    assert!(
        error(Sky::builder(&atmosphere).method(march(10_000_000, 10_000_000)))
            .contains("view steps x sun steps = 1e14 is out of range: allowed <= 1e8")
    );
    assert!(
        Sky::builder(&atmosphere)
            .method(march(10_000, 10_000))
            .polarisation(sora::Polarisation::Scalar)
            .build()
            .is_ok()
    );
    assert!(ViewDirection::new(120.0, 0.0).is_err());
    assert!(ViewDirection::new(0.0, f64::NAN).is_err());
    // Images: sizes, and path tracing renders no images.
    let sky = Sky::builder(&atmosphere)
        .polarisation(sora::Polarisation::Scalar)
        .build()
        .unwrap();
    let to_xyz = SpectrumToXyz::new(sky.wavelengths(), Observer::Cie1931TwoDegree);
    let zero = ImageSettings::new(Camera::Fisheye, 0, 8);
    assert!(
        sky.render_xyz(&zero, &to_xyz, &|_| {})
            .unwrap_err()
            .to_string()
            .contains("image width = 0")
    );
    let traced = Sky::builder(&atmosphere)
        .method(Method::PathTracing {
            samples: 10,
            seed: 0,
        })
        .polarisation(sora::Polarisation::Scalar)
        .build()
        .unwrap();
    let image = ImageSettings::new(Camera::Fisheye, 4, 4);
    assert!(traced.render_xyz(&image, &to_xyz, &|_| {}).is_err());
    // A colour conversion on another grid.
    let other = SpectrumToXyz::new(
        &sora::WavelengthGrid::new(400.0, 700.0, 50.0).unwrap(),
        Observer::Cie1931TwoDegree,
    );
    assert!(sky.render_xyz(&image, &other, &|_| {}).is_err());
}

/// Image buffers are bounded by `MAX_IMAGE_BUFFER_BYTES` (4 GiB), checked
/// before anything is computed (issue 17): at the edge the request passes
/// the check (and meets the next one, that the path tracer renders no
/// images: nothing is allocated), one row past it is refused naming the
/// size, the limit and what to do; spectral images count every wavelength.
#[test]
fn image_buffers_are_bounded_before_allocating() {
    assert_eq!(sora::sky::MAX_IMAGE_BUFFER_BYTES, 4 << 30);
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    let traced = Sky::builder(&atmosphere)
        .method(Method::PathTracing {
            samples: 10,
            seed: 0,
        })
        .polarisation(sora::Polarisation::Scalar)
        .build()
        .unwrap();
    let to_xyz = SpectrumToXyz::new(traced.wavelengths(), Observer::Cie1931TwoDegree);
    // XYZ: 24 bytes a pixel, 16384 x 10922 = 4.2947e9 bytes fits, x 10923 does not.
    let edge = ImageSettings::new(Camera::Fisheye, 16384, 10922);
    let past = ImageSettings::new(Camera::Fisheye, 16384, 10923);
    let message = traced
        .render_xyz(&edge, &to_xyz, &|_| {})
        .unwrap_err()
        .to_string();
    assert!(message.contains("path tracing computes views"), "{message}");
    let message = traced
        .render_xyz(&past, &to_xyz, &|_| {})
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("image buffer (16384 x 10923 pixels x 1 values of 24 bytes) = 4.0")
            && message.contains("GiB is out of range: allowed <= 4: render fewer pixels"),
        "{message}"
    );
    // Spectral: 8 bytes a wavelength; 4 GiB / (n 8 bytes) pixels.
    let n = traced.wavelengths().len() as u64;
    let pixels_at_edge = (4u64 << 30) / (8 * n);
    let width = 16384u32;
    let height = (pixels_at_edge / u64::from(width)) as u32;
    let fits = ImageSettings::new(Camera::Fisheye, width, height);
    let message = traced
        .render_spectral(&fits, &|_| {})
        .unwrap_err()
        .to_string();
    assert!(message.contains("path tracing computes views"), "{message}");
    let over = ImageSettings::new(Camera::Fisheye, width, height + 1);
    let message = traced
        .render_spectral(&over, &|_| {})
        .unwrap_err()
        .to_string();
    assert!(
        message.contains(&format!("x {n} values of 8 bytes"))
            && message.contains("fewer wavelengths"),
        "{message}"
    );
}

/// A sky moved to another sun is the sky built for that sun, to the bit.
#[test]
fn moving_the_sun_equals_building_for_it() {
    let atmosphere = Atmosphere::preset("earth-clear").unwrap();
    let first = Sky::builder(&atmosphere)
        .sun_deg(20.0, 100.0)
        .polarisation(sora::Polarisation::Scalar)
        .build()
        .unwrap();
    let moved = first.with_sun_deg(-2.0, 250.0).unwrap();
    let built = Sky::builder(&atmosphere)
        .sun_deg(-2.0, 250.0)
        .polarisation(sora::Polarisation::Scalar)
        .build()
        .unwrap();
    assert_eq!(moved.sun_position_deg(), (-2.0, 250.0));
    for view in views() {
        assert_eq!(moved.radiance(view).unwrap(), built.radiance(view).unwrap());
    }
    assert!(first.with_sun_deg(91.0, 0.0).is_err());
}

/// A coarse sky of `atmosphere` (4 streams a hemisphere, 12 layers, 3
/// wavelengths) with the sun `sun_deg` up at azimuth 120 degrees.
fn coarse_sky(atmosphere: &Atmosphere, sun_deg: f64, polarisation: sora::Polarisation) -> Sky {
    let coarse = sora::MultipleScatteringSettings {
        streams_per_hemisphere: 4,
        layers: 12,
        ..Default::default()
    };
    Sky::builder(atmosphere)
        .sun_deg(sun_deg, 120.0)
        .wavelengths(sora::WavelengthGrid::new(440.0, 660.0, 110.0).unwrap())
        .scattering(Scattering::Multiple(coarse))
        .polarisation(polarisation)
        .build()
        .unwrap()
}

/// A polarised sky moved to another sun draws the image of the sky built
/// for that sun, to the bit: the polarisation table's harmonics that the
/// first sky's image kept (they do not depend on the sun) are the ones the
/// new sun would compute.
#[test]
fn a_moved_polarised_sky_draws_the_image_built_for_its_sun() {
    let atmosphere = Atmosphere::preset("earth-hazy").unwrap();
    let build = |sun: f64| coarse_sky(&atmosphere, sun, sora::Polarisation::Vector);
    let image = ImageSettings::new(Camera::Fisheye, 12, 12);
    let first = build(25.0);
    let drawn_first = first.render_spectral(&image, &|_| {}).unwrap();
    let moved = first.with_sun_deg(3.0, 120.0).unwrap();
    let built = build(3.0);
    assert_eq!(
        moved.render_spectral(&image, &|_| {}).unwrap(),
        built.render_spectral(&image, &|_| {}).unwrap()
    );
    // And the first sky's image is its own, not the moved one's.
    assert_ne!(drawn_first, built.render_spectral(&image, &|_| {}).unwrap());
}

/// A sky moved from sun to sun as a slider moves it draws at each sun the
/// image of the sky built for it, to the bit: the forward-peak tables and
/// the tilted beam's rows that the skies before it kept (they do not depend
/// on the sun) are the ones its own sun would compute.
#[test]
fn a_sky_moved_down_through_twilight_draws_the_images_built_for_its_suns() {
    let atmosphere = Atmosphere::preset("earth-hazy").unwrap();
    let build = |sun: f64| coarse_sky(&atmosphere, sun, sora::Polarisation::Scalar);
    let image = ImageSettings::new(Camera::Fisheye, 12, 12);
    let first = build(10.0);
    first.render_spectral(&image, &|_| {}).unwrap();
    for sun in [5.0, 2.0, -4.0, 5.0] {
        let moved = first.with_sun_deg(sun, 120.0).unwrap();
        assert_eq!(
            moved.render_spectral(&image, &|_| {}).unwrap(),
            build(sun).render_spectral(&image, &|_| {}).unwrap(),
            "sun {sun}"
        );
    }
}

/// One default light for every front end, set here: polarised
/// (`Polarisation::Vector`) for the fast method and path tracing, scalar
/// for the reference march; the default gives the explicit choice's
/// radiance to the bit; the names parse and print as one vocabulary.
#[test]
fn the_default_light_is_polarised_except_for_the_reference_march() {
    use sora::Polarisation;
    let atmosphere = Atmosphere::preset("us-standard-1976-rayleigh").unwrap();
    let grid: sora::WavelengthGrid = "440:640:100".parse().unwrap();
    let build = |method: Method, polarisation: Option<Polarisation>| {
        let builder = Sky::builder(&atmosphere)
            .sun_deg(30.0, 180.0)
            .wavelengths(grid)
            .method(method);
        match polarisation {
            Some(p) => builder.polarisation(p),
            None => builder,
        }
        .build()
        .unwrap()
    };
    let march = Method::Reference {
        view_steps: 40,
        sun_steps: 10,
    };
    let traced = Method::PathTracing {
        samples: 20,
        seed: 1,
    };
    for (method, expected) in [
        (Method::Fast, Polarisation::Vector),
        (traced, Polarisation::Vector),
        (march, Polarisation::Scalar),
    ] {
        assert_eq!(Polarisation::for_method(method), expected);
        let default = build(method, None);
        assert_eq!(default.polarisation(), expected, "{method:?}");
        let view = ViewDirection::new(20.0, 90.0).unwrap();
        assert_eq!(
            default.radiance(view).unwrap(),
            build(method, Some(expected)).radiance(view).unwrap(),
            "{method:?}"
        );
    }
    // The polarised intensity differs from the scalar light's.
    let view = ViewDirection::new(20.0, 90.0).unwrap();
    let (vector, scalar) = (
        build(Method::Fast, None).radiance(view).unwrap(),
        build(Method::Fast, Some(Polarisation::Scalar))
            .radiance(view)
            .unwrap(),
    );
    assert_ne!(vector.radiance_w_m2_sr_nm, scalar.radiance_w_m2_sr_nm);
    for polarisation in [Polarisation::Scalar, Polarisation::Vector] {
        let name = polarisation.to_string();
        assert_eq!(name.parse::<Polarisation>().unwrap(), polarisation);
    }
    assert_eq!(Polarisation::Scalar.to_string(), "scalar");
    let message = "off".parse::<Polarisation>().unwrap_err().to_string();
    assert_eq!(
        message,
        "polarisation: 'off' is unknown: use 'scalar' or 'vector'"
    );
}
