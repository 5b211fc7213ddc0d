//! Inputs at the edges that once panicked: an atmosphere without species
//! under a low sun (every command that computes the sky), and a sequence
//! whose first sun comes from --time.

mod common;

use common::{sora, stdout};

/// An atmosphere file with a planet and a sun and no species (vacuum).
const NO_SPECIES: &str = "name = \"vacuum\"\n[planet]\nradius_m = 6360e3\natmosphere_height_m = 100e3\n[sun]\nspectrum = \"flat\"\nirradiance_w_m2_nm = 1.0\n";

#[test]
fn no_species_under_a_low_sun_is_a_black_sky_in_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("nospecies.toml");
    std::fs::write(&file, NO_SPECIES).unwrap();
    let file = file.to_str().unwrap();
    let image = dir.path().join("sky.exr");
    let image = image.to_str().unwrap();
    for elevation in ["10", "5", "-3"] {
        let view = ["--view-elevation", "20", "--view-azimuth", "0"];
        let base = ["--atmosphere", file, "--sun-elevation", elevation];
        // The radiance (and its Stokes vector) is zero at every wavelength.
        for extra in [&[][..], &["--stokes"][..]] {
            let out = sora(&[&["spectrum"][..], &base, &view, extra].concat());
            let text = stdout(&out);
            for row in text.lines().skip(1) {
                let values: Vec<f64> = row
                    .split(',')
                    .skip(1)
                    .filter(|v| !v.is_empty())
                    .filter_map(|v| v.parse().ok())
                    .collect();
                assert!(values[0] == 0.0, "{row}");
            }
        }
        let out = sora(
            &[
                &["render"][..],
                &base,
                &["--width", "8", "--stokes", "-o", image],
            ]
            .concat(),
        );
        stdout(&out);
        let intensity = common::exr_channel(std::path::Path::new(image), "S0.G");
        assert!(intensity.iter().all(|v| v.is_finite() && *v >= 0.0));
        if elevation == "-3" {
            // The sun below the horizon and nothing to scatter: black.
            assert!(intensity.iter().all(|v| *v == 0.0));
        }
        // Irradiance: the direct beam alone (diffuse 0, global = direct).
        let out = sora(&[&["irradiance"][..], &base].concat());
        let text = stdout(&out);
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let column = |name: &str| header.iter().position(|h| h.starts_with(name)).unwrap();
        let (direct, diffuse, global) = (
            column("direct_horizontal"),
            column("diffuse"),
            column("global"),
        );
        for row in text.lines().skip(1) {
            let v: Vec<f64> = row.split(',').map(|x| x.parse().unwrap()).collect();
            assert_eq!(v[diffuse], 0.0, "{row}");
            assert_eq!(v[direct], v[global], "{row}");
        }
    }
}

#[test]
fn a_sequence_from_a_time_starts_at_that_suns_elevation() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("s.png");
    // The sun at --time; with --sun-elevation-to a sequence from there.
    let render = |extra: &[&str], output: &std::path::Path| {
        let base = [
            "render",
            "--preset",
            "clear-sky-reference",
            "--scattering",
            "single",
            "--wavelengths",
            "400:700:100",
            "--width",
            "8",
            "--time",
            "2026-06-21T05:30:00+09:00",
            "--location",
            "35.68,139.77",
            "-o",
            output.to_str().unwrap(),
        ];
        sora(&[&base[..], extra].concat())
    };
    let out = render(
        &["--sun-elevation-to", "20", "--sun-elevation-step", "2"],
        &output,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8(out.stderr).unwrap();
    // The sun at 05:30 in Tokyo on the solstice is at about 11.1 degrees
    // (the same run without a sequence says where); frames every 2 degrees
    // up to 20 degrees: 5 of them, each at the time's azimuth.
    let single = render(&[], &dir.path().join("one.png"));
    let single = String::from_utf8(single.stderr).unwrap();
    let sun = |line: &str| -> (f64, f64) {
        let after = line.split("sun at ").nth(1).unwrap();
        let elevation: f64 = after.split(' ').next().unwrap().parse().unwrap();
        let azimuth: f64 = after
            .split("elevation, ")
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        (elevation, azimuth)
    };
    let (first_elevation, azimuth) = sun(single.lines().find(|l| l.contains("sun at")).unwrap());
    let frames: Vec<(f64, f64)> = stderr
        .lines()
        .filter(|l| l.contains("sun at"))
        .map(sun)
        .collect();
    let expected = ((20.0 - first_elevation) / 2.0 + 1e-9).floor() as usize + 1;
    assert_eq!(frames.len(), expected, "{stderr}");
    for (k, (elevation, frame_azimuth)) in frames.iter().enumerate() {
        assert!(
            (elevation - (first_elevation + 2.0 * k as f64)).abs() < 1e-3,
            "{stderr}"
        );
        assert!((frame_azimuth - azimuth).abs() < 1e-3, "{stderr}");
        assert!(dir.path().join(format!("s_{k:03}.png")).is_file());
    }
}
