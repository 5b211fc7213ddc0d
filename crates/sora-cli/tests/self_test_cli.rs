//! `sora self-test`: the reference cases shipped in the binary pass, each
//! check prints its line, and the run is quick.

mod common;

use common::sora;

#[test]
fn self_test_passes_and_prints_every_check() {
    let start = std::time::Instant::now();
    let out = sora(&["self-test"]);
    let elapsed = start.elapsed().as_secs_f64();
    let stdout = String::from_utf8(out.stdout.clone()).unwrap();
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<&str> = stdout.lines().collect();
    let checks: Vec<&&str> = lines.iter().filter(|l| l.starts_with("ok ")).collect();
    assert!(
        !stdout.contains("FAILED"),
        "a check failed although the exit status is 0:\n{stdout}"
    );
    assert!(
        !stdout.to_lowercase().contains("nan"),
        "NaN printed:\n{stdout}"
    );
    for what in [
        "mie efficiencies",
        "single scattering",
        "multiple scattering",
        "atmosphere file",
    ] {
        assert!(
            checks.iter().any(|l| l.contains(what)),
            "no '{what}' check:\n{stdout}"
        );
    }
    for preset in sora::atmosphere::PRESETS {
        assert!(
            checks
                .iter()
                .any(|l| l.contains(&format!("atmosphere file {}:", preset.name))),
            "preset {} not checked:\n{stdout}",
            preset.name
        );
    }
    // 10 Mie spheres, single, multiple, one line per preset.
    assert_eq!(
        checks.len(),
        12 + sora::atmosphere::PRESETS.len(),
        "{stdout}"
    );
    assert!(
        lines.last().is_some_and(
            |l| l.starts_with(&format!("self-test: all {} checks passed", checks.len()))
        ),
        "{stdout}"
    );
    // The bound is for release builds; debug builds (cargo test) are
    // slower, so only a generous bound here.
    assert!(elapsed < 120.0, "self-test took {elapsed:.1} s");
}
