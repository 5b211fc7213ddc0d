//! The limits on work and memory of the CLI (issue 17; docs/limits.md):
//! each refused before any work, in one line naming the value, the limit
//! and what to do.

mod common;

use common::{one_line_error, sora};

/// `sora render` refuses image buffers beyond 4 GiB before loading the
/// atmosphere (which here does not even exist); the estimate line of a long
/// legal render is printed on a terminal only, so a piped stderr holds just
/// the error.
#[test]
fn render_memory_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    for (name, width, height, expected) in [
        (
            "big.png",
            "16384",
            "16384",
            "30 bytes a pixel for 8-bit PNG",
        ),
        ("big.exr", "9460", "9460", "48 bytes a pixel for OpenEXR"),
    ] {
        let output = dir.path().join(name);
        let out = sora(&[
            "render",
            "--atmosphere",
            "/nonexistent/air.toml",
            "--sun-elevation",
            "30",
            "--width",
            width,
            "--height",
            height,
            "-o",
            output.to_str().unwrap(),
        ]);
        let stderr = one_line_error(&out);
        assert!(
            stderr.contains(expected) && stderr.contains("more than the limit of 4294967296 bytes"),
            "{stderr}"
        );
        assert!(!output.exists());
    }
    // Just inside the OpenEXR bound (9459 x 9459 pixels): the next check
    // fails (the missing atmosphere), with no estimate on a piped stderr.
    let out = sora(&[
        "render",
        "--atmosphere",
        "/nonexistent/air.toml",
        "--sun-elevation",
        "30",
        "--width",
        "9459",
        "--height",
        "9459",
        "-o",
        dir.path().join("edge.exr").to_str().unwrap(),
    ]);
    let stderr = one_line_error(&out);
    assert!(stderr.contains("air.toml"), "{stderr}");
    assert!(!stderr.contains("estimate"), "{stderr}");
}
