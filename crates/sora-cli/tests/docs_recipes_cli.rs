//! The recipes of README.md and docs/README.md that promise an output, run
//! and compared: the README's main command writes `docs/readme_sky.png`
//! byte for byte (and its time-and-place command `docs/readme_tokyo.png`),
//! the documented command of a docs picture writes it byte for byte, and
//! the Table 1 numbers quoted are what `sora spectrum` prints. Each recipe
//! is first found, word for word, in the document that promises it, so a
//! changed recipe fails here until the document and its output agree.
//!
//! When the sky's numbers change on purpose, regenerate the pictures with
//! the commands below (README.md, docs/README.md) and the quoted numbers.

mod common;

use common::{sora, stdout};

fn repository_file(path: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path)
}

fn document(path: &str) -> String {
    std::fs::read_to_string(repository_file(path)).unwrap()
}

/// Runs `sora render` with `options` (as the document writes them) into a
/// temporary PNG and asserts it equals `picture`, byte for byte.
fn assert_render_writes(options: &str, picture: &str) {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("picture.png");
    let mut args = vec!["render"];
    args.extend(options.split_whitespace());
    args.extend(["-o", output.to_str().unwrap()]);
    stdout(&sora(&args));
    let (written, documented) = (
        std::fs::read(&output).unwrap(),
        std::fs::read(repository_file(picture)).unwrap(),
    );
    let differing = written
        .iter()
        .zip(&documented)
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        written == documented,
        "sora {} writes {} bytes, {differing} of them differing from {picture} ({} bytes)",
        args.join(" "),
        written.len(),
        documented.len()
    );
}

#[test]
fn the_readme_command_writes_the_readme_picture() {
    let readme = document("README.md");
    let command = "render --preset earth-clear --sun-elevation 30 -o sky.png";
    assert!(readme.contains(&format!("cargo run --release -p sora-cli -- {command}")));
    assert!(
        readme.contains(
            "![sky.png: earth-clear, sun 30 degrees up in the south](docs/readme_sky.png)"
        )
    );
    assert_render_writes(
        "--preset earth-clear --sun-elevation 30",
        "docs/readme_sky.png",
    );
    let tokyo = "--preset earth-clear --time 2026-06-21T05:30:00+09:00 --location 35.68,139.77";
    assert!(readme.contains(&format!("sora render {tokyo} -o tokyo.png")));
    assert_render_writes(tokyo, "docs/readme_tokyo.png");
}

/// docs/README.md: "the multiple-scattering fisheyes byte for byte", each
/// by the command of its table row with the page's common options.
#[test]
fn the_docs_fisheyes_are_what_their_commands_write() {
    let docs = document("docs/README.md");
    let common = "--gamut preserve-hue --polarisation scalar";
    assert!(docs.contains(&format!("(`sora render ... {common} -o FILE.png`;")));
    for (name, atmosphere, sun) in [
        ("earth_clear_noon", "earth-clear", "60 / 180"),
        ("earth_clear_sunset", "earth-clear", "3 / 270"),
        ("earth_clear_twilight", "earth-clear", "-2 / 270"),
        ("paper_earth_noon", "paper-earth", "60 / 180"),
        ("paper_mars_sunset", "paper-mars", ""),
        ("mars_dust_sunset", "mars-dust", ""),
    ] {
        let (elevation, azimuth) = sun.split_once(" / ").unwrap_or(("3", "270"));
        let mut options = format!("--preset {atmosphere} --sun-elevation {elevation}");
        if azimuth != "180" {
            options.push_str(&format!(" --sun-azimuth {azimuth}"));
        }
        let row = if sun.is_empty() {
            format!("| `{name}_fisheye_*.png` | {atmosphere} | `{options}` |")
        } else {
            format!("| `{name}_fisheye_*.png` | {atmosphere} | {sun} | `{options}` |")
        };
        assert!(docs.contains(&row), "docs/README.md has no row {row}");
        assert_render_writes(
            &format!("{options} {common}"),
            &format!("docs/{name}_fisheye_multiple.png"),
        );
    }
}

/// The radiance at 380 nm of the paper's Table 1 view, as `sora spectrum`
/// prints it with `extra` options.
fn table1_at_380_nm(extra: &[&str]) -> f64 {
    let base = ["spectrum", "--preset", "paper-earth"];
    let csv = stdout(&sora(
        &[&base[..], &common::TABLE1_GEOMETRY, extra].concat(),
    ));
    let rows = common::spectrum_rows(&csv);
    assert_eq!(rows[0].0, 380.0);
    rows[0].1
}

#[test]
fn the_table1_numbers_are_what_sora_spectrum_prints() {
    let docs = document("docs/README.md");
    let single = table1_at_380_nm(&["--scattering", "single", "--polarisation", "scalar"]);
    let multiple = table1_at_380_nm(&["--polarisation", "scalar"]);
    let polarised = table1_at_380_nm(&[]);
    // The table (4 digits), the text (7 digits) and the default's value.
    for quoted in [
        format!("| paper-earth, flat sun | **multiple** | {multiple:.3e} | **380 nm** |"),
        format!("{single:.6e} and {multiple:.6e} W m^-2 sr^-1 nm^-1 at 380 nm"),
        format!("({polarised:.3e} at 380 nm for all orders)"),
    ] {
        assert!(
            docs.contains(&quoted),
            "docs/README.md does not say {quoted}"
        );
    }
    assert!(polarised < multiple);
}

/// docs/retrieval.md's example: its command (the README's, with the plot
/// into `docs/`) prints the table the document shows, digit for digit (the
/// timing line on stderr aside), and writes `docs/retrieval_fit.png` byte
/// for byte.
#[test]
fn the_retrieval_example_prints_its_table_and_draws_its_plot() {
    let docs = document("docs/retrieval.md");
    let inputs = "--radiances docs/retrieval_case4_radiances.csv \\\n    --optical-depths docs/retrieval_case4_optical_depths.csv";
    assert!(docs.contains(&format!(
        "sora retrieve {inputs} --plot docs/retrieval_fit.png\n```"
    )));
    assert!(document("README.md").contains(&format!(
        "target/release/sora retrieve {inputs} --plot fit.png\n```"
    )));
    let shown = docs
        .split("```text\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .unwrap();
    let (table, timing) = shown.trim_end().rsplit_once('\n').unwrap();
    assert!(timing.starts_with("1 scan(s) retrieved in "), "{timing}");
    let dir = tempfile::tempdir().unwrap();
    let plot = dir.path().join("fit.png");
    // From the repository's root, as the document runs it (the table names
    // the file as given).
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_sora"))
        .current_dir(repository_file(""))
        .arg("retrieve")
        .args(inputs.replace("\\\n", " ").split_whitespace())
        .args(["--plot", plot.to_str().unwrap()])
        .output()
        .unwrap();
    let printed = stdout(&out);
    assert_eq!(printed.trim_end(), table, "docs/retrieval.md's table");
    let (written, documented) = (
        std::fs::read(&plot).unwrap(),
        std::fs::read(repository_file("docs/retrieval_fit.png")).unwrap(),
    );
    assert!(
        written == documented,
        "--plot differs from docs/retrieval_fit.png"
    );
}
