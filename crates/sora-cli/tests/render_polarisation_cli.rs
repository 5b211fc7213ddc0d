//! `sora render` with polarised light (the default): the Stokes images as
//! OpenEXR layers (--stokes), the degree and angle maps as PNGs (--dolp,
//! --aop), --polarisation scalar, and the choices that cannot work.

mod common;

use common::{exr_channel, one_line_error, sora};

/// Width and height from a PNG's IHDR chunk.
fn png_size(path: &std::path::Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let number = |at: usize| u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap());
    (number(16), number(20))
}

const SIDE: usize = 64;

/// A Rayleigh sky, sun 30 degrees up in the south: the Stokes EXR's
/// layers hold S0 = the image, and along the sun's vertical (the image's
/// middle column, north at the top) the degree of linear polarisation
/// peaks about 90 degrees from the sun and falls to nearly nothing at a
/// neutral point near the sun (Babinet's above it, Brewster's below: the
/// multiply scattered light's doing; single scattering alone would be
/// polarised everywhere but at the sun).
#[test]
fn stokes_layers_hold_the_image_and_the_skys_polarisation() {
    let dir = tempfile::tempdir().unwrap();
    let (exr, dolp, aop) = (
        dir.path().join("sky.exr"),
        dir.path().join("dolp.png"),
        dir.path().join("aop.png"),
    );
    let side = SIDE.to_string();
    let out = sora(&[
        "render",
        "--preset",
        "us-standard-1976-rayleigh",
        "--sun-elevation",
        "30",
        "--width",
        &side,
        "--no-sun-disc",
        "--exr-xyz",
        "--stokes",
        "-o",
        exr.to_str().unwrap(),
        "--dolp",
        dolp.to_str().unwrap(),
        "--aop",
        aop.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("polarisation vector"), "{stderr}");
    let y = exr_channel(&exr, "Y");
    let [s0, s1, s2, s3] = ["S0.Y", "S1.Y", "S2.Y", "S3.Y"].map(|name| exr_channel(&exr, name));
    assert_eq!(y, s0);
    // Rayleigh sunlight scattered by spheres and molecules: V stays ~0.
    assert!(
        s3.iter()
            .zip(&s0)
            .all(|(v, i)| v.abs() <= 1e-6 * i.abs().max(1e-30))
    );
    // The sun's vertical: the middle column, north (top) to south.
    let column = SIDE / 2;
    let mut profile = Vec::new();
    for row in 0..SIDE {
        let k = row * SIDE + column;
        if s0[k] <= 0.0 {
            continue;
        }
        // Equidistant fisheye: zenith angle 90 degrees at the rim.
        let offset = ((row as f64 + 0.5) / SIDE as f64 * 2.0 - 1.0) * 90.0;
        // Angle from the sun (30 up in the south): north of the zenith
        // (offset < 0) adds to the 60 degrees from the sun to the zenith.
        let from_sun = (60.0 - offset).abs();
        let degree = f64::from(s1[k]).hypot(f64::from(s2[k])) / f64::from(s0[k]);
        assert!((0.0..=1.0).contains(&degree), "row {row}: {degree}");
        profile.push((from_sun, degree));
    }
    let (peak_at, peak) = profile
        .iter()
        .copied()
        .fold((0.0, 0.0), |best, p| if p.1 > best.1 { p } else { best });
    assert!((0.6..0.95).contains(&peak), "peak degree {peak}");
    assert!(
        (80.0..100.0).contains(&peak_at),
        "peak {peak_at} deg from the sun"
    );
    let near_sun_minimum = profile
        .iter()
        .filter(|(from_sun, _)| *from_sun < 30.0)
        .map(|p| p.1)
        .fold(f64::MAX, f64::min);
    assert!(near_sun_minimum < 0.03, "{near_sun_minimum}");
    // The maps: the image and a legend strip below it.
    for map in [&dolp, &aop] {
        let (width, height) = png_size(map);
        assert_eq!(width as usize, SIDE);
        assert!(height as usize > SIDE, "{height}");
    }
}

#[test]
fn polarisation_scalar_is_the_scalar_sky_and_off_its_old_spelling() {
    let dir = tempfile::tempdir().unwrap();
    let (vector, scalar, off) = (
        dir.path().join("v.exr"),
        dir.path().join("s.exr"),
        dir.path().join("o.exr"),
    );
    for (path, extra) in [
        (&vector, None),
        (&scalar, Some("scalar")),
        (&off, Some("off")),
    ] {
        let mut args = vec![
            "render",
            "--preset",
            "us-standard-1976-rayleigh",
            "--sun-elevation",
            "30",
            "--width",
            "32",
            "--exr-xyz",
            "-o",
            path.to_str().unwrap(),
        ];
        if let Some(choice) = extra {
            args.extend(["--polarisation", choice]);
        }
        let out = sora(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stderr}");
        assert_eq!(
            stderr.contains("note: --polarisation off is now spelled --polarisation scalar"),
            extra == Some("off"),
            "{stderr}"
        );
        let said = if extra.is_some() { "scalar" } else { "vector" };
        assert!(stderr.contains(&format!("polarisation {said}")), "{stderr}");
    }
    let (v, s) = (exr_channel(&vector, "Y"), exr_channel(&scalar, "Y"));
    assert_eq!(s, exr_channel(&off, "Y"));
    // The polarised intensity differs from the scalar by a few per cent
    // at most (docs/polarisation.md: -5 % to +2 %).
    let worst = v
        .iter()
        .zip(&s)
        .filter(|(_, s)| **s > 0.0)
        .map(|(v, s)| (v / s - 1.0).abs())
        .fold(0.0f32, f32::max);
    assert!((0.005..0.08).contains(&worst), "{worst}");
}

#[test]
fn polarisation_outputs_that_cannot_be_made_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let base = [
        "render",
        "--preset",
        "us-standard-1976-rayleigh",
        "--sun-elevation",
        "30",
        "--width",
        "16",
    ];
    let cases: [(Vec<String>, &str); 5] = [
        (
            vec!["-o".into(), path("a.png"), "--stokes".into()],
            "FILE.exr",
        ),
        (
            vec![
                "-o".into(),
                path("b.exr"),
                "--stokes".into(),
                "--polarisation".into(),
                "scalar".into(),
            ],
            "polarised light",
        ),
        (
            vec![
                "-o".into(),
                path("c.png"),
                "--method".into(),
                "reference".into(),
                "--dolp".into(),
                path("d.png"),
            ],
            "polarised light",
        ),
        (
            vec!["-o".into(), path("e.png"), "--aop".into(), path("f.exr")],
            "PNG",
        ),
        (
            vec![
                "-o".into(),
                path("g.png"),
                "--dolp".into(),
                path("h.png"),
                "--sun-elevation-to".into(),
                "20".into(),
            ],
            "sequence",
        ),
    ];
    for (extra, expected) in cases {
        let args: Vec<&str> = base
            .iter()
            .copied()
            .chain(extra.iter().map(String::as_str))
            .collect();
        let error = one_line_error(&sora(&args));
        assert!(error.contains(expected), "{args:?}: {error}");
    }
    // Nothing was written.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}
