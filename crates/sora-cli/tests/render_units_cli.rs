//! `sora render`: physical units in OpenEXR, half floats and the sun,
//! photographic exposure and sequences at one exposure.

mod common;

use common::{exr_channel, one_line_error, sora};

fn render(args: &[&str]) -> std::process::Output {
    let base = ["render", "--preset", "earth-clear", "--width", "48"];
    sora(&[&base[..], args].concat())
}

#[test]
fn luminance_exr_is_683_times_radiance_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let (radiance, luminance) = (dir.path().join("r.exr"), dir.path().join("l.exr"));
    let scene = ["--sun-elevation", "25", "--exr-xyz"];
    assert!(
        render(&[&scene[..], &["-o", radiance.to_str().unwrap()]].concat())
            .status
            .success()
    );
    assert!(
        render(
            &[
                &scene[..],
                &["--units", "luminance", "-o", luminance.to_str().unwrap()]
            ]
            .concat()
        )
        .status
        .success()
    );
    let (r, l) = (exr_channel(&radiance, "Y"), exr_channel(&luminance, "Y"));
    for (r, l) in r.iter().zip(&l) {
        assert!(
            (l - 683.0 * r).abs() <= 1e-6 * l.abs().max(1e-30),
            "{l} vs 683 x {r}"
        );
        assert!(r.is_finite() && *r >= 0.0);
    }
    let header = exr::prelude::read_first_flat_layer_from_file(&luminance).unwrap();
    let attributes = &header.layer_data.attributes;
    assert_eq!(attributes.white_luminance, Some(1.0));
    let text = |name: &str| match attributes
        .other
        .get(&exr::meta::attribute::Text::from(name))
    {
        Some(exr::meta::attribute::AttributeValue::Text(text)) => text.to_string(),
        other => panic!("{name}: {other:?}"),
    };
    assert!(text("sora:units").starts_with("luminance_cd_m2"));
    assert_eq!(text("sora:sun_elevation_deg"), "25");
}

#[test]
fn half_floats_with_the_sun_fail_naming_the_options_or_clamp() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("half.exr");
    let scene = [
        "--sun-elevation",
        "40",
        "--units",
        "luminance",
        "--exr-half",
        "-o",
    ];
    let error = one_line_error(&render(&[&scene[..], &[path.to_str().unwrap()]].concat()));
    for option in ["--half-overflow clamp", "--no-sun-disc", "--exr-half"] {
        assert!(error.contains(option), "{error}");
    }
    assert!(!path.exists(), "nothing is written");
    let out = render(
        &[
            &scene[..],
            &[path.to_str().unwrap(), "--half-overflow", "clamp"],
        ]
        .concat(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in ["R", "G", "B"] {
        let values = exr_channel(&path, name);
        assert!(
            values
                .iter()
                .all(|v| v.is_finite() && *v >= 0.0 && *v <= 65504.0)
        );
        assert_eq!(
            values.iter().copied().fold(0.0, f32::max),
            65504.0,
            "the sun is clamped"
        );
    }
}

/// A sequence writes numbered frames at one exposure: each frame is the
/// single image at its sun with that exposure given, byte for byte.
#[test]
fn a_sequence_shares_one_exposure() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("day.png");
    let out = render(&[
        "--sun-elevation",
        "10",
        "--sun-elevation-to",
        "-2",
        "--sun-elevation-step",
        "6",
        "-o",
        output.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{stderr}");
    let scale = stderr
        .lines()
        .find_map(|l| l.strip_prefix("sequence exposure: "))
        .and_then(|l| l.split_whitespace().next())
        .unwrap_or_else(|| panic!("{stderr}"))
        .to_string();
    for (frame, elevation) in [(0, "10"), (1, "4"), (2, "-2")] {
        let framed = dir.path().join(format!("day_{frame:03}.png"));
        let single = dir.path().join(format!("single_{frame}.png"));
        let out = render(&[
            "--sun-elevation",
            elevation,
            "--exposure",
            &scale,
            "-o",
            single.to_str().unwrap(),
        ]);
        assert!(out.status.success());
        assert_eq!(
            std::fs::read(&framed).unwrap(),
            std::fs::read(&single).unwrap(),
            "frame {frame}"
        );
    }
    // --ev100 is one fixed exposure for every frame too.
    let ev = dir.path().join("ev.png");
    let out = render(&[
        "--sun-elevation",
        "10",
        "--sun-elevation-to",
        "4",
        "--sun-elevation-step",
        "6",
        "--ev100",
        "12",
        "-o",
        ev.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).contains("sequence exposure"));
    let single = dir.path().join("ev_single.png");
    assert!(
        render(&[
            "--sun-elevation",
            "4",
            "--ev100",
            "12",
            "-o",
            single.to_str().unwrap()
        ])
        .status
        .success()
    );
    assert_eq!(
        std::fs::read(dir.path().join("ev_001.png")).unwrap(),
        std::fs::read(&single).unwrap()
    );
    let error = one_line_error(&render(&[
        "--sun-elevation",
        "10",
        "--ev100",
        "99",
        "-o",
        ev.to_str().unwrap(),
    ]));
    assert!(error.contains("EV100 = 99"), "{error}");
}

/// Night (the sun 30 degrees down): darker than the night floor
/// (1e-6 cd/m^2) everywhere, so every pixel is written black, not an
/// amplified numerical floor; auto exposure says so on stderr; a fixed
/// exposure still works. At -12 degrees the sky is above the floor and
/// nothing is said.
#[test]
fn a_night_sky_is_black_and_auto_exposure_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let (png, exr) = (dir.path().join("night.png"), dir.path().join("night.exr"));
    let night = ["--sun-elevation", "-30"];
    let out = render(&[&night[..], &["-o", png.to_str().unwrap()]].concat());
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("night floor of 1e-6 cd/m^2") && stderr.contains("black image"),
        "{stderr}"
    );
    let out = render(
        &[
            &night[..],
            &[
                "--units",
                "luminance",
                "--exr-xyz",
                "-o",
                exr.to_str().unwrap(),
            ],
        ]
        .concat(),
    );
    assert!(out.status.success());
    for channel in ["X", "Y", "Z"] {
        assert!(exr_channel(&exr, channel).iter().all(|v| *v == 0.0));
    }
    let fixed = render(&[&night[..], &["--ev100", "-20", "-o", png.to_str().unwrap()]].concat());
    assert!(fixed.status.success(), "{}", one_line_error(&fixed));
    assert!(!String::from_utf8_lossy(&fixed.stderr).contains("night floor"));
    // Nautical twilight is darker than a day but not night.
    let twilight = dir.path().join("twilight.exr");
    let out = render(&[
        "--sun-elevation",
        "-12",
        "--units",
        "luminance",
        "--exr-xyz",
        "-o",
        twilight.to_str().unwrap(),
    ]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("night floor"));
    let y = exr_channel(&twilight, "Y");
    let brightest = y.iter().copied().fold(0.0f32, f32::max);
    assert!(brightest > 1e-4, "{brightest}");
    assert!(
        y.iter().all(|v| *v == 0.0 || *v >= 1e-6),
        "a pixel below the floor"
    );
}
