//! `sora tables`: the README's command writes the five files the docs
//! promise, and bad input (an unknown format, a directory that is not
//! sora's tables, a bad node count) is a one-line error that writes nothing.

mod common;

use common::{exr_channel, one_line_error, sora};

/// The README's command line for the engine tables.
const README_COMMAND: &str = "sora tables --preset earth-clear -o earth-clear-tables";

#[test]
fn the_readme_command_writes_the_tables_and_their_manifest() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md")).unwrap();
    assert!(
        readme.contains(README_COMMAND),
        "README lacks `{README_COMMAND}`"
    );
    assert!(readme.contains("docs/engine-tables.md"));
    let directory = tempfile::tempdir().unwrap();
    let output = directory.path().join("earth-clear-tables");
    let mut args: Vec<String> = README_COMMAND
        .split_whitespace()
        .skip(1)
        .map(String::from)
        .collect();
    *args.last_mut().unwrap() = output.display().to_string();
    // Fewer nodes and single scattering: the same code at a debug build's
    // pace (the default tables take minutes there).
    args.extend(
        "--scattering single --sun-nodes 3 --altitude-nodes 2 --zenith-nodes 4 --azimuth-nodes 3 \
         --aerial-zenith-nodes 3 --aerial-azimuth-nodes 2 --aerial-distance-nodes 2"
            .split_whitespace()
            .map(String::from),
    );
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = sora(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(output.join("manifest.json")).unwrap())
            .unwrap();
    assert_eq!(manifest["format"], "sora-engine-tables");
    let sky = &manifest["tables"]["sky"];
    assert_eq!(sky["height"], 2 * 4 * 3 * 2);
    // Another count of zenith nodes than the default's: the plain axis.
    assert_eq!(sky["zenith_fine_cells_per_half"], 0);
    assert_eq!(sky["zenith_wide_cells_per_half"], 0);
    let texels = exr_channel(&output.join("sky.exr"), "Y");
    assert_eq!(texels.len(), 3 * 2 * 4 * 3 * 2);
    // The zenith at the highest sun (layer s * 2 + a = 4: s = 2, a = 0,
    // the ground; 8 rows of 3 texels a layer) is lit.
    let top_layer_zenith = texels[4 * 8 * 3];
    assert!(top_layer_zenith > 0.0, "{top_layer_zenith}");
    assert_eq!(
        exr_channel(&output.join("aerial.exr"), "Y").len(),
        2 * 2 * 3 * 2 * 3 * 2
    );
    for name in ["transmittance.exr", "irradiance.exr"] {
        assert!(output.join(name).is_file(), "{name}");
    }
}

#[test]
fn bad_input_is_one_line_and_writes_nothing() {
    let directory = tempfile::tempdir().unwrap();
    let fresh = directory.path().join("fresh");
    let fresh_path = fresh.display().to_string();
    let message = one_line_error(&sora(&[
        "tables",
        "--preset",
        "earth-clear",
        "--format",
        "ktx2",
        "-o",
        &fresh_path,
    ]));
    assert!(
        message.contains("--format ktx2: unknown table format"),
        "{message}"
    );
    let message = one_line_error(&sora(&[
        "tables",
        "--preset",
        "earth-clear",
        "--sun-nodes",
        "1",
        "-o",
        &fresh_path,
    ]));
    assert!(message.contains("sun nodes"), "{message}");
    // Fine cells that do not fit the zenith nodes asked for.
    let message = one_line_error(&sora(&[
        "tables",
        "--preset",
        "earth-clear",
        "--zenith-nodes",
        "8",
        "--zenith-fine-cells",
        "21",
        "-o",
        &fresh_path,
    ]));
    assert!(
        message.contains("zenith fine cells per half = 21"),
        "{message}"
    );
    assert!(!fresh.exists());
    let foreign = directory.path().join("photos");
    std::fs::create_dir(&foreign).unwrap();
    std::fs::write(foreign.join("a.jpg"), b"x").unwrap();
    let message = one_line_error(&sora(&[
        "tables",
        "--preset",
        "earth-clear",
        "-o",
        &foreign.display().to_string(),
    ]));
    assert!(message.contains("is not sora's tables"), "{message}");
    assert_eq!(std::fs::read_dir(&foreign).unwrap().count(), 1);
    // Another tool's manifest is not sora's either (checked before the
    // bake: the refusal is immediate), and is left as it was.
    let other = directory.path().join("other-tables");
    std::fs::create_dir(&other).unwrap();
    let manifest = r#"{"format": "bruneton-textures", "version": 4}"#;
    std::fs::write(other.join("manifest.json"), manifest).unwrap();
    let message = one_line_error(&sora(&[
        "tables",
        "--preset",
        "earth-clear",
        "-o",
        &other.display().to_string(),
    ]));
    assert!(message.contains("is not sora's tables"), "{message}");
    assert_eq!(
        std::fs::read_to_string(other.join("manifest.json")).unwrap(),
        manifest
    );
    assert_eq!(std::fs::read_dir(&other).unwrap().count(), 1);
}
