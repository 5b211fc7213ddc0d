//! Aerial perspective on the command line: `sora spectrum --distance-m D`
//! gives the light the air scatters into the view between the eye and a
//! point D m away and a transmittance column (the README's command among
//! them), and bad distances are one-line errors with nothing on stdout.

mod common;

use common::{one_line_error, sora, stdout};

/// The README's aerial-perspective command (the line of its "Aerial
/// perspective" paragraph that runs `sora spectrum ... --distance-m`),
/// as arguments.
fn readme_command() -> Vec<String> {
    let readme = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md"),
    )
    .unwrap();
    let line = readme
        .lines()
        .find(|l| l.starts_with("target/release/sora spectrum") && l.contains("--distance-m"))
        .expect("README has an aerial-perspective command");
    let command = &line[line.find("sora spectrum").unwrap() + "sora ".len()..];
    command.split_whitespace().map(str::to_string).collect()
}

/// (wavelength, radiance, transmittance) rows of a one-view CSV with a
/// transmittance column.
fn rows(csv: &str) -> Vec<(f64, f64, f64)> {
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("wavelength_nm,radiance_w_m2_sr_nm,transmittance")
    );
    lines
        .map(|line| {
            let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            (v[0], v[1], v[2])
        })
        .collect()
}

/// The README's command: the air's light is positive and less than the
/// whole sky's along the same view, the transmittance between 0 and 1 and
/// lower in the blue (Rayleigh and haze extinguish short wavelengths more).
#[test]
fn the_readme_command_gives_the_air_light_and_its_transmittance() {
    let args = readme_command();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let segment = rows(&stdout(&sora(&args)));
    // The same view without --distance-m: the whole sky.
    let at = args.iter().position(|a| *a == "--distance-m").unwrap();
    let sky_args: Vec<&str> = [&args[..at], &args[at + 2..]].concat();
    let sky = common::spectrum_rows(&stdout(&sora(&sky_args)));
    assert_eq!(segment.len(), sky.len());
    for ((w, air, t), (_, whole)) in segment.iter().zip(&sky) {
        assert!(*air > 0.0 && air < whole, "{w} nm: {air} vs {whole}");
        assert!(*t > 0.0 && *t < 1.0, "{w} nm: transmittance {t}");
    }
    assert!(segment[0].2 < segment[segment.len() - 1].2);
}

/// `sora spectrum` of earth-clear, sun 20 degrees, one view 1 degree up
/// across the sun, with `extra`.
fn spectrum(extra: &[&str]) -> std::process::Output {
    let common = [
        "spectrum",
        "--preset",
        "earth-clear",
        "--sun-elevation",
        "20",
        "--view-elevation",
        "1",
        "--view-azimuth",
        "90",
    ];
    sora(&[&common[..], extra].concat())
}

/// JSON carries the transmittance and the distance; a longer segment
/// scatters more and lets less through.
#[test]
fn json_has_the_transmittance_and_longer_segments_are_hazier() {
    let run = |distance: &str| {
        let out = common::json(&spectrum(&[
            "--wavelengths",
            "450:650:100",
            "--distance-m",
            distance,
            "--format",
            "json",
        ]));
        assert_eq!(out["distance_m"].as_f64(), distance.parse().ok(), "{out}");
        (
            common::numbers(&out["radiance_w_m2_sr_nm"]),
            common::numbers(&out["transmittance"]),
        )
    };
    let (near_l, near_t) = run("1000");
    let (far_l, far_t) = run("30000");
    for i in 0..3 {
        assert!(far_l[i] > near_l[i] && far_t[i] < near_t[i]);
    }
}

#[test]
fn bad_distances_are_one_line_errors_with_nothing_written() {
    for bad in ["0", "-5", "NaN"] {
        let out = spectrum(&["--distance-m", bad]);
        let message = one_line_error(&out);
        assert!(message.contains("--distance-m"), "{message}");
        assert!(out.stdout.is_empty());
    }
}

/// A depth EXR of `width` x `height` pixels: one channel Z, 32-bit
/// floats (NaN included, which sora's own writer refuses).
fn write_depth(path: &std::path::Path, (width, height): (usize, usize), depth: &[f32]) {
    use exr::prelude::*;
    let channel = AnyChannel::new("Z", FlatSamples::F32(depth.to_vec()));
    let image = Image::from_channels(
        (width, height),
        AnyChannels::sort(SmallVec::from_vec(vec![channel])),
    );
    image.write().to_file(path).unwrap();
}

fn render(extra: &[&str], output: &std::path::Path) -> std::process::Output {
    let common = [
        "render",
        "--preset",
        "earth-hazy",
        "--sun-elevation",
        "10",
        "--width",
        "12",
        "--height",
        "12",
        "--wavelengths",
        "440:680:60",
        "--polarisation",
        "scalar",
        "--no-sun-disc",
        "-o",
        output.to_str().unwrap(),
    ];
    sora(&[&common[..], extra].concat())
}

/// `render --distance-m` writes the air's light and a transmittance layer;
/// a depth file of one distance everywhere gives the same image, and the
/// air's light is less than the sky's.
#[test]
fn render_writes_the_air_light_and_a_transmittance_layer() {
    let dir = tempfile::tempdir().unwrap();
    let (uniform, from_depth, sky) = (
        dir.path().join("air.exr"),
        dir.path().join("depth_air.exr"),
        dir.path().join("sky.exr"),
    );
    stdout(&render(&["--distance-m", "5000"], &uniform));
    let depth = dir.path().join("depth.exr");
    write_depth(&depth, (12, 12), &[5000.0; 144]);
    stdout(&render(&["--depth", depth.to_str().unwrap()], &from_depth));
    stdout(&render(&[], &sky));
    let air = common::exr_channel(&uniform, "G");
    assert_eq!(air, common::exr_channel(&from_depth, "G"));
    let sky = common::exr_channel(&sky, "G");
    let through = common::exr_channel(&uniform, "transmittance.G");
    let mut seen = 0;
    for ((a, s), t) in air.iter().zip(&sky).zip(&through) {
        if *s > 0.0 {
            seen += 1;
            assert!(*a > 0.0 && a < s, "air {a} sky {s}");
            assert!(*t > 0.0 && *t < 1.0, "transmittance {t}");
        }
    }
    assert!(seen > 50, "{seen} pixels see the sky");
}

/// Bad depths are one-line errors and nothing is written.
#[test]
fn bad_depths_are_one_line_errors_with_nothing_written() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("air.exr");
    let wrong_size = dir.path().join("wrong_size.exr");
    write_depth(&wrong_size, (6, 12), &[1000.0; 72]);
    let nan = dir.path().join("nan.exr");
    let mut values = [1000.0f32; 144];
    values[13] = f32::NAN;
    write_depth(&nan, (12, 12), &values);
    let negative = dir.path().join("negative.exr");
    values[13] = -3.0;
    write_depth(&negative, (12, 12), &values);
    let png = dir.path().join("air.png");
    for (args, expected, out) in [
        (vec!["--distance-m", "0"], "--distance-m", &output),
        (
            vec!["--depth", wrong_size.to_str().unwrap()],
            "6 x 12",
            &output,
        ),
        (
            vec!["--depth", nan.to_str().unwrap()],
            "pixel (1, 1)",
            &output,
        ),
        (vec!["--depth", negative.to_str().unwrap()], "-3 m", &output),
        (vec!["--distance-m", "100"], "OpenEXR", &png),
    ] {
        let message = one_line_error(&render(&args, out));
        assert!(message.contains(expected), "{message}");
        assert!(!out.exists());
    }
}

/// The aerial-perspective EXR is written as a plain render's: --units
/// sets its units and whiteLuminance (1 for cd/m^2), --exr-half half
/// floats (under --half-overflow's rule) for the image and the layer.
#[test]
fn the_air_exr_takes_the_renders_units_and_half_floats() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("air.exr");
    stdout(&render(
        &["--distance-m", "5000", "--units", "luminance", "--exr-half"],
        &output,
    ));
    let image = exr::prelude::read_all_flat_layers_from_file(&output).unwrap();
    let layer = &image.layer_data[0];
    assert_eq!(layer.attributes.white_luminance, Some(1.0));
    let units = layer
        .attributes
        .other
        .get(&exr::meta::attribute::Text::from("sora:units"));
    assert!(
        matches!(units, Some(exr::meta::attribute::AttributeValue::Text(t)) if t.to_string().starts_with("luminance_cd_m2")),
        "{units:?}"
    );
    let mut names = Vec::new();
    for channel in &layer.channel_data.list {
        names.push(channel.name.to_string());
        assert!(
            matches!(channel.sample_data, exr::prelude::FlatSamples::F16(_)),
            "{}",
            channel.name
        );
    }
    assert!(names.contains(&"G".to_string()) && names.contains(&"transmittance.G".to_string()));
}
