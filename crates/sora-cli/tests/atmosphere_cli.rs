//! `sora atmosphere` end to end: the built binary on presets and files.

mod common;

use common::{one_line_error as error, sora, stdout};

#[test]
fn presets_are_listed_with_descriptions() {
    let text = stdout(&sora(&["atmosphere", "presets"]));
    for name in [
        "paper-earth",
        "paper-mars",
        "earth-clear",
        "earth-hazy",
        "mars-dust",
        "clear-sky-reference",
    ] {
        let line = text
            .lines()
            .find(|l| l.split_whitespace().next() == Some(name))
            .unwrap_or_else(|| panic!("{name} missing from:\n{text}"));
        assert!(line.len() > name.len() + 20, "no description: {line}");
    }
}

/// The CSV of the clear-sky reference is the reference's optical depths.
#[test]
fn csv_of_the_clear_sky_reference() {
    let text = stdout(&sora(&[
        "atmosphere",
        "show",
        "--preset",
        "clear-sky-reference",
        "--format",
        "csv",
    ]));
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some(
            "wavelength_nm,species,tau_extinction,tau_scattering,single_scattering_albedo,asymmetry_g"
        )
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 42, "21 wavelengths x 2 species");
    // 380 nm: tau_R = 0.4072515344, aerosol 0.1617159367 / 0.1455443431
    // (reference/sky/clear_sky_optical_depths.csv).
    assert_eq!(rows[0][..2], ["380", "air"]);
    let value = |row: usize, column: usize| rows[row][column].parse::<f64>().unwrap();
    assert!((value(0, 2) / 4.072515344e-1 - 1.0).abs() < 1e-6);
    assert_eq!(rows[1][..2], ["380", "aerosol"]);
    assert!((value(1, 2) / 1.617159367e-1 - 1.0).abs() < 1e-6);
    assert!((value(1, 3) / 1.455443431e-1 - 1.0).abs() < 1e-6);
    assert_eq!((value(1, 4), value(1, 5)), (0.9, 0.7));
    assert_eq!(rows[41][..2], ["780", "aerosol"]);
}

#[test]
fn table_and_json_formats() {
    let text = stdout(&sora(&[
        "atmosphere",
        "show",
        "--preset",
        "earth-clear",
        "--wavelengths",
        "400:700:150",
    ]));
    assert!(text.contains("Earth, clear continental sky"), "{text}");
    assert!(text.contains("ozone") && text.contains("(total)"), "{text}");
    let json = common::json(&sora(&[
        "atmosphere",
        "show",
        "--preset",
        "paper-mars",
        "--wavelengths",
        "550",
        "--format",
        "json",
    ]));
    assert_eq!(common::numbers(&json["wavelengths_nm"]), [550.0]);
    let optics = json["optics"].as_array().unwrap();
    assert!(optics.iter().any(|row| row["species"] == "dust"), "{json}");
}

#[test]
fn a_bad_file_is_one_line_naming_the_key() {
    let directory = tempfile::tempdir().unwrap();
    let path = directory.path().join("bad.toml");
    let good = sora::atmosphere::presets::find_preset("clear-sky-reference")
        .unwrap()
        .toml;
    std::fs::write(
        &path,
        good.replace("scale_height_m = 1200", "scale_height_m = -1200"),
    )
    .unwrap();
    let message = error(&sora(&[
        "atmosphere",
        "show",
        "--atmosphere",
        path.to_str().unwrap(),
    ]));
    assert!(
        message.contains("bad.toml")
            && message.contains("species[1].profile.exponential.scale_height_m = -1200 m"),
        "{message}"
    );
    std::fs::write(&path, "name = \"x\"\n[planet\n").unwrap();
    let message = error(&sora(&[
        "atmosphere",
        "show",
        "--atmosphere",
        path.to_str().unwrap(),
    ]));
    assert!(message.contains("line 2"), "{message}");
    let message = error(&sora(&[
        "atmosphere",
        "show",
        "--atmosphere",
        directory.path().join("missing.toml").to_str().unwrap(),
    ]));
    assert!(message.contains("missing.toml"), "{message}");
    let message = error(&sora(&["atmosphere", "show", "--preset", "venus"]));
    assert!(message.contains("'venus' is not a preset"), "{message}");
}

/// A file's solar CSV is read relative to the file, and every shipped
/// atmosphere file loads from disk like its preset.
#[test]
fn files_on_disk() {
    let directory = tempfile::tempdir().unwrap();
    let text = sora::atmosphere::presets::find_preset("clear-sky-reference")
        .unwrap()
        .toml
        .replace(
            "spectrum = \"flat\"              # the paper's equal-energy sun\nirradiance_w_m2_nm = 1.0",
            "spectrum = \"csv\"\ncsv_file = \"sun.csv\"",
        );
    assert!(text.contains("sun.csv"));
    std::fs::write(directory.path().join("sky.toml"), text).unwrap();
    std::fs::write(
        directory.path().join("sun.csv"),
        "# a grey sun\nwavelength_nm,irradiance_w_m2_nm\n350,2\n850,2\n",
    )
    .unwrap();
    let path = directory.path().join("sky.toml");
    stdout(&sora(&[
        "atmosphere",
        "show",
        "--atmosphere",
        path.to_str().unwrap(),
    ]));

    let atmospheres = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../atmospheres");
    let mut count = 0;
    for entry in std::fs::read_dir(atmospheres).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let text = stdout(&sora(&[
                "atmosphere",
                "show",
                "--atmosphere",
                path.to_str().unwrap(),
                "--wavelengths",
                "550",
                "--format",
                "csv",
            ]));
            assert!(text.lines().count() >= 2, "{}", path.display());
            count += 1;
        }
    }
    assert!(count >= 6);
}

#[test]
fn help_explains_the_commands() {
    let text = stdout(&sora(&["atmosphere", "--help"]));
    assert!(text.contains("presets") && text.contains("show"), "{text}");
    let text = stdout(&sora(&["atmosphere", "show", "--help"]));
    for fragment in [
        "--preset",
        "--atmosphere",
        "--wavelengths",
        "--format",
        "single_scattering_albedo",
    ] {
        assert!(text.contains(fragment), "{fragment} in {text}");
    }
}

/// Issue 17: an aerosol of index 1 + 0i does not scatter. Given by number
/// density it is non-scattering in both phase modes (optical depths 0,
/// albedo 0, g 0, no NaN); given by an optical depth at a wavelength where
/// it does not extinguish, it is a one-line error naming the index.
#[test]
fn an_aerosol_of_index_one_is_non_scattering_or_refused() {
    let paper = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../atmospheres/paper-earth.toml"),
    )
    .unwrap();
    let index_one = paper.replace("{ n = 1.5, k = 0.01 }", "{ n = 1.0, k = 0.0 }");
    assert_ne!(index_one, paper, "the paper's aerosol index moved");
    let directory = tempfile::tempdir().unwrap();
    for phase in ["paper-hg", "mie"] {
        let with_phase = index_one.replace("phase = \"paper-hg\"", &format!("phase = \"{phase}\""));
        let path = directory.path().join(format!("depth-{phase}.toml"));
        std::fs::write(&path, &with_phase).unwrap();
        let message = error(&sora(&[
            "atmosphere",
            "show",
            "--atmosphere",
            path.to_str().unwrap(),
        ]));
        assert!(message.contains("refractive index 1 + 0i"), "{message}");
        assert!(message.contains("optical_depth"), "{message}");
        let by_density: String = with_phase
            .lines()
            .map(|line| {
                if line.starts_with("optical_depth = 0.15") {
                    "number_density_m3 = 1e9"
                } else if line.starts_with("reference_wavelength_nm = 550") {
                    ""
                } else {
                    line
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        let path = directory.path().join(format!("density-{phase}.toml"));
        std::fs::write(&path, by_density).unwrap();
        for format in ["table", "csv", "json"] {
            let text = stdout(&sora(&[
                "atmosphere",
                "show",
                "--atmosphere",
                path.to_str().unwrap(),
                "--format",
                format,
            ]));
            assert!(
                !text.to_lowercase().contains("nan"),
                "{phase} {format}:\n{text}"
            );
            assert!(!text.contains("inf"), "{phase} {format}:\n{text}");
            if format == "table" {
                let aerosol_rows: Vec<&str> = text
                    .lines()
                    .filter(|l| l.split_whitespace().nth(1) == Some("aerosol"))
                    .collect();
                assert_eq!(aerosol_rows.len(), 21, "{text}");
                for row in aerosol_rows {
                    let fields: Vec<&str> = row.split_whitespace().collect();
                    for value in &fields[2..] {
                        assert_eq!(value.parse::<f64>().unwrap(), 0.0, "{row}");
                    }
                }
            }
        }
    }
}
