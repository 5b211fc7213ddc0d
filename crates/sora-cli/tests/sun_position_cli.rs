//! The sun from a date, a time and a place: `--time T --location LAT,LON[,ELEV]`
//! for `sora spectrum` and `sora render`, the position reported, and bad
//! inputs as one-line errors.

mod common;

use common::{one_line_error, sora, stdout};
use sora::sun_position::{Location, Refraction, parse_time_utc};

/// A cheap single-scattering spectrum of earth-clear with `sun` options,
/// as JSON.
fn spectrum_json(sun: &[&str], views: &[&str]) -> std::process::Output {
    spectrum_json_of(&["--preset", "earth-clear"], sun, views)
}

/// [`spectrum_json`] of the atmosphere `source` names.
fn spectrum_json_of(source: &[&str], sun: &[&str], views: &[&str]) -> std::process::Output {
    let common = [
        "spectrum",
        "--scattering",
        "single",
        "--wavelengths",
        "400:700:100",
        "--format",
        "json",
    ];
    sora(&[&common[..], source, sun, views].concat())
}

const ONE_VIEW: [&str; 4] = ["--view-elevation", "10", "--view-azimuth", "0"];

/// The number `key` of the JSON object `json`.
fn number(json: &str, key: &str) -> f64 {
    let value: serde_json::Value = serde_json::from_str(json).unwrap();
    value[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} in {json}"))
}

#[test]
fn spectrum_json_reports_the_sun_computed_for_the_time_and_place() {
    // NREL SPA's example instant and place (its own air is 820 hPa, 11 C;
    // here the defaults, the standard atmosphere's at the site's 1830 m,
    // or no refraction).
    let place = ["--location", "39.742476,-105.1786,1830.14"];
    let time = ["--time", "2003-10-17T12:30:30-07:00"];
    let expected = |refraction| {
        sora::SunPosition::at(
            parse_time_utc(time[1]).unwrap(),
            Location::new(39.742476, -105.1786, 1830.14).unwrap(),
            refraction,
        )
        .unwrap()
    };
    let site_air = Refraction::standard_at_elevation_m(1830.14);
    for (extra, refraction) in [
        (&[][..], site_air),
        (&["--refraction", "on"][..], site_air),
        (&["--refraction", "off"][..], Refraction::Off),
    ] {
        let json = stdout(&spectrum_json(
            &[&time[..], &place[..], extra].concat(),
            &ONE_VIEW,
        ));
        let sun = expected(refraction);
        assert_eq!(number(&json, "sun_elevation_deg"), sun.elevation_deg);
        assert_eq!(number(&json, "sun_azimuth_deg"), sun.azimuth_deg);
        // SPA's published azimuth (refraction changes only the elevation).
        assert!((sun.azimuth_deg - 194.34024).abs() < 1e-3, "{sun:?}");
        let value: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert!(value["radiance_w_m2_sr_nm"].is_array(), "{json}");
    }
    // Refraction lifts the sun (about 0.02 deg at 40 deg elevation).
    let lift = expected(site_air).elevation_deg - expected(Refraction::Off).elevation_deg;
    assert!((0.01..0.03).contains(&lift), "{lift}");
    // SPA's published topocentric elevation, 39.88838 deg (zenith
    // 50.11162), within 0.001 deg: from the site's altitude alone, and
    // with the example's measured air.
    for extra in [&[][..], &["--pressure-hpa", "820", "--temperature-c", "11"]] {
        let json = stdout(&spectrum_json(
            &[&time[..], &place[..], extra].concat(),
            &ONE_VIEW,
        ));
        let elevation = number(&json, "sun_elevation_deg");
        let azimuth = number(&json, "sun_azimuth_deg");
        assert!(
            (elevation - 39.88838).abs() < 1e-3,
            "{extra:?}: {elevation}"
        );
        assert!((azimuth - 194.34024).abs() < 1e-3, "{extra:?}: {azimuth}");
        // SPA's radius vector for the instant, 0.9965422974 AU.
        assert!((number(&json, "earth_sun_distance_au") - 0.9965423).abs() < 1e-6);
    }
    // Bad air is the library's one-line error, naming the unit.
    let out = spectrum_json(
        &[&time[..], &place[..], &["--pressure-hpa", "-5"]].concat(),
        &ONE_VIEW,
    );
    assert!(
        one_line_error(&out).contains("pressure = -5 hPa"),
        "{out:?}"
    );
}

#[test]
fn the_dates_sun_is_brighter_at_perihelion() {
    // Noon on the equator on 3 January and 4 July: the sun's light at the
    // top of the atmosphere scales as 1 / R^2, (1.01663 / 0.98330)^2 =
    // 1.069 (the suns stand 67.19 and 67.13 deg up: the air's
    // transmittances differ by 3e-4).
    let irradiance = |time: &str, extra: &[&str]| {
        let out = sora(
            &[
                &[
                    "irradiance",
                    "--preset",
                    "earth-clear",
                    "--location",
                    "0,0",
                    "--time",
                    time,
                    "--format",
                    "json",
                ][..],
                extra,
            ]
            .concat(),
        );
        stdout(&out)
    };
    let january = irradiance("2026-01-03T12:00:00Z", &[]);
    let july = irradiance("2026-07-04T12:00:00Z", &[]);
    let ratio = number(&january, "direct_normal_irradiance_w_m2")
        / number(&july, "direct_normal_irradiance_w_m2");
    assert!((ratio - 1.069).abs() < 1e-3, "{ratio}");
    let (near, far) = (
        number(&january, "sun_distance_au"),
        number(&july, "sun_distance_au"),
    );
    assert!((near - 0.98330).abs() < 1e-4 && (far - 1.01663).abs() < 1e-4);
    // Divided by the beam's transmittance, it is exactly the distance's
    // square (the first wavelength).
    let first = |json: &str, key: &str| -> f64 {
        let value: serde_json::Value = serde_json::from_str(json).unwrap();
        common::numbers(&value[key])[0]
    };
    let top = |json: &str| {
        first(json, "direct_normal_irradiance_w_m2_nm") / first(json, "direct_beam_transmittance")
    };
    let exact = (far / near).powi(2);
    assert!((top(&january) / top(&july) / exact - 1.0).abs() < 1e-8);
    // --sun-distance-au sets it by hand: 1 AU is the file's own sun.
    let at_one_au = irradiance("2026-01-03T12:00:00Z", &["--sun-distance-au", "1"]);
    assert_eq!(number(&at_one_au, "sun_distance_au"), 1.0);
    let undated = stdout(&sora(&[
        "irradiance",
        "--preset",
        "earth-clear",
        "--sun-elevation",
        &number(&january, "sun_elevation_deg").to_string(),
        "--sun-azimuth",
        &number(&january, "sun_azimuth_deg").to_string(),
        "--format",
        "json",
    ]));
    assert!(!undated.contains("sun_distance_au"), "{undated}");
    assert_eq!(
        number(&at_one_au, "direct_normal_irradiance_w_m2"),
        number(&undated, "direct_normal_irradiance_w_m2")
    );
    // Mars' preset sun is not at 1 AU: a date leaves it where its file
    // puts it, and a distance out of range is a one-line error.
    let mars = stdout(&sora(&[
        "irradiance",
        "--preset",
        "mars-dust",
        "--location",
        "0,0",
        "--time",
        "2026-01-03T12:00:00Z",
        "--format",
        "json",
    ]));
    assert!(!mars.contains("\"sun_distance_au\""), "{mars}");
    let out = sora(&[
        "irradiance",
        "--preset",
        "earth-clear",
        "--sun-elevation",
        "30",
        "--sun-distance-au",
        "0",
    ]);
    assert!(
        one_line_error(&out).contains("--sun-distance-au: sun distance = 0 AU"),
        "{out:?}"
    );
}

#[test]
fn spectrum_json_reports_the_sun_for_many_directions_and_for_angles() {
    // The almucantar follows the computed sun.
    let json = stdout(&spectrum_json(
        &[
            "--time",
            "2026-06-21T05:30:00+09:00",
            "--location",
            "35.68,139.77,40",
        ],
        &["--almucantar", "90"],
    ));
    let elevation = number(&json, "sun_elevation_deg");
    let azimuth = number(&json, "sun_azimuth_deg");
    // Tokyo, 05:30 on the June solstice: low in the north-east.
    assert!(
        (5.0..20.0).contains(&elevation) && (55.0..80.0).contains(&azimuth),
        "{elevation} {azimuth}"
    );
    let value: serde_json::Value = serde_json::from_str(&json).unwrap();
    let directions = value["directions"].as_array().unwrap();
    assert_eq!(directions.len(), 4, "{json}");
    assert_eq!(directions[0]["view_elevation_deg"], elevation);
    assert_eq!(directions[0]["view_azimuth_deg"], azimuth);
    // The sun given as angles is reported as given.
    let json = stdout(&spectrum_json(&["--sun-elevation", "30"], &ONE_VIEW));
    assert_eq!(number(&json, "sun_elevation_deg"), 30.0);
    assert_eq!(number(&json, "sun_azimuth_deg"), 180.0);
    let json = stdout(&spectrum_json(
        &["--sun-elevation", "-4.5", "--sun-azimuth", "270"],
        &["--principal-plane", "90"],
    ));
    assert_eq!(number(&json, "sun_elevation_deg"), -4.5);
    assert_eq!(number(&json, "sun_azimuth_deg"), 270.0);
}

#[test]
fn render_summary_reports_the_sun() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("sky.png");
    let out = sora(&[
        "render",
        "--preset",
        "earth-clear",
        "--time",
        "2026-06-20T20:30:00Z",
        "--location",
        "35.68,139.77",
        "--refraction",
        "off",
        "--scattering",
        "single",
        "--wavelengths",
        "400:700:100",
        "--width",
        "8",
        "-o",
        output.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{out:?}");
    assert!(output.is_file());
    let sun = sora::SunPosition::at(
        parse_time_utc("2026-06-20T20:30:00Z").unwrap(),
        Location::new(35.68, 139.77, 0.0).unwrap(),
        Refraction::Off,
    )
    .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let expected = format!(
        "sun at {:.4} deg elevation, {:.4} deg azimuth",
        sun.elevation_deg, sun.azimuth_deg
    );
    assert!(
        stderr.contains("rendered 8x8") && stderr.contains(&expected),
        "{stderr}"
    );
}

#[test]
fn bad_times_and_places_are_one_line_errors() {
    for (sun, expected) in [
        (
            ["--time", "2026-06-21T05:30:00+09:00", "--location", "91,0"],
            "--location: latitude = 91 deg is out of range: allowed -90..=90 deg",
        ),
        (
            [
                "--time",
                "2026-06-21T05:30:00+09:00",
                "--location",
                "0,-200",
            ],
            "longitude = -200 deg",
        ),
        (
            ["--time", "2026-06-21T05:30:00+09:00", "--location", "35"],
            "--location: '35' has 1 values",
        ),
        (
            [
                "--time",
                "2026-06-21T05:30:00",
                "--location",
                "35.68,139.77",
            ],
            "--time: '2026-06-21T05:30:00' has no zone",
        ),
        (
            ["--time", "2026-06-21", "--location", "35.68,139.77"],
            "without a time of day",
        ),
        (
            ["--time", "tomorrow at dawn", "--location", "35.68,139.77"],
            "--time: 'tomorrow at dawn' is not a time",
        ),
        (
            [
                "--time",
                "2026-02-30T05:30:00Z",
                "--location",
                "35.68,139.77",
            ],
            "day = 30",
        ),
    ] {
        let out = spectrum_json(&sun, &ONE_VIEW);
        let error = one_line_error(&out);
        assert!(error.contains(expected), "{sun:?}: {error}");
        assert!(out.stdout.is_empty(), "{sun:?}");
    }
}

#[test]
fn the_sun_is_given_one_way_exactly() {
    let time = "2026-06-21T05:30:00+09:00";
    for (sun, expected) in [
        (
            &[
                "--time",
                time,
                "--location",
                "35,139",
                "--sun-elevation",
                "30",
            ][..],
            "cannot be used with",
        ),
        (
            &[
                "--time",
                time,
                "--location",
                "35,139",
                "--sun-azimuth",
                "90",
            ][..],
            "cannot be used with",
        ),
        (&["--time", time][..], "--location"),
        (
            &["--sun-elevation", "30", "--location", "35,139"][..],
            "cannot be used with",
        ),
        (
            &["--sun-elevation", "30", "--refraction", "off"][..],
            "cannot be used with",
        ),
        (&[][..], "--sun-elevation <DEG>|--time <TIME>"),
    ] {
        let out = spectrum_json(sun, &ONE_VIEW);
        // clap's own argument errors: status 2, the first line says why.
        assert_eq!(out.status.code(), Some(2), "{sun:?}: {out:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(expected), "{sun:?}: {stderr}");
        assert!(out.stdout.is_empty());
    }
}

#[test]
fn the_locations_elevation_raises_the_ground() {
    // At 1 449 m by --location, and by the atmosphere file's key with the
    // same sun given as angles: the same sky.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("site.toml");
    let preset = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../atmospheres/earth-clear.toml"
    ))
    .unwrap();
    std::fs::write(
        &file,
        preset.replace(
            "atmosphere_height_m = 100e3",
            "atmosphere_height_m = 100e3\nground_altitude_m = 1449",
        ),
    )
    .unwrap();
    let site = stdout(&spectrum_json(
        &["--time", "2026-03-20T12:00:00Z", "--location", "45,0,1449"],
        &ONE_VIEW,
    ));
    let (elevation, azimuth, distance) = (
        number(&site, "sun_elevation_deg").to_string(),
        number(&site, "sun_azimuth_deg").to_string(),
        number(&site, "sun_distance_au").to_string(),
    );
    let by_file = stdout(&spectrum_json_of(
        &["--atmosphere", file.to_str().unwrap()],
        &[
            "--sun-elevation",
            &elevation,
            "--sun-azimuth",
            &azimuth,
            "--sun-distance-au",
            &distance,
        ],
        &ONE_VIEW,
    ));
    let radiances = |json: &str| {
        let start = json.find("\"radiance_w_m2_sr_nm\": [").unwrap();
        json[start..json[start..].find(']').unwrap() + start].to_string()
    };
    assert_eq!(radiances(&site), radiances(&by_file));
    // And not the sea level's sky.
    let sea = stdout(&spectrum_json(
        &["--time", "2026-03-20T12:00:00Z", "--location", "45,0"],
        &ONE_VIEW,
    ));
    assert_ne!(radiances(&site), radiances(&sea));
}
