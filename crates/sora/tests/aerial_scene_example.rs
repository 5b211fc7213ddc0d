//! The README's aerial-perspective scene (`docs/readme_aerial_scene.png`)
//! is what its command writes, byte for byte: the example `aerial_scene`
//! (which `cargo test` builds with the other examples) run into a
//! temporary file. The README names the command and the picture.
//!
//! When the sky's numbers change on purpose, regenerate the picture with
//! `cargo run --release -p sora --example aerial_scene -- docs/readme_aerial_scene.png`.

use std::path::{Path, PathBuf};

fn repository_file(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path)
}

/// The example's executable beside this test's (target/<profile>/examples).
fn example(name: &str) -> PathBuf {
    let test = std::env::current_exe().unwrap();
    let profile = test.parent().unwrap().parent().unwrap();
    let path = profile
        .join("examples")
        .join(format!("{name}{}", std::env::consts::EXE_SUFFIX));
    assert!(
        path.exists(),
        "{} is not built: `cargo test -p sora` builds the examples (a `--test` filter alone does not: `cargo build -p sora --profile test --example {name}` first)",
        path.display()
    );
    path
}

#[test]
fn the_readme_scene_is_what_its_command_writes() {
    let readme = std::fs::read_to_string(repository_file("README.md")).unwrap();
    assert!(
        readme.contains("cargo run --release -p sora --example aerial_scene -- scene.png"),
        "README.md names the command"
    );
    assert!(readme.contains("](docs/readme_aerial_scene.png)"));
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("scene.png");
    let run = std::process::Command::new(example("aerial_scene"))
        .arg(&output)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (written, documented) = (
        std::fs::read(&output).unwrap(),
        std::fs::read(repository_file("docs/readme_aerial_scene.png")).unwrap(),
    );
    let differing = written
        .iter()
        .zip(&documented)
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        written == documented,
        "aerial_scene writes {} bytes, {differing} of them differing from docs/readme_aerial_scene.png ({} bytes)",
        written.len(),
        documented.len()
    );
}
