//! Output paths: what every output (`sora render -o`, `--dolp`, `--aop`,
//! sequences, `sora colour --swatch`, `sora retrieve --residuals`,
//! `--plot`) does with a directory, a symbolic link, a read-only file, a
//! device (a FIFO or a link to /dev/null stands in for one) and two
//! outputs on one file, checked before any work (the policy is
//! `sora::output::output_target` and `sora render --help`).

mod common;

use common::{one_line_error, sora};

/// A tiny render into `output` (with `extra` options); the atmosphere is
/// `atmosphere` (a preset name, or a path that need not exist).
fn render(atmosphere: &[&str], output: &str, extra: &[&str]) -> std::process::Output {
    let base = [
        "render",
        "--sun-elevation",
        "30",
        "--width",
        "8",
        "--scattering",
        "single",
        "--wavelengths",
        "400:700:100",
        "-o",
        output,
    ];
    sora(&[&base[..], atmosphere, extra].concat())
}

const PRESET: [&str; 2] = ["--preset", "clear-sky-reference"];

#[test]
fn a_directory_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let directory = dir.path().join("images.png");
    std::fs::create_dir(&directory).unwrap();
    let path = directory.to_str().unwrap();
    // The atmosphere file does not exist either: the output is checked first.
    let out = render(&["--atmosphere", "/nonexistent/air.toml"], path, &[]);
    let stderr = one_line_error(&out);
    assert!(
        stderr.contains(&format!("-o {path} is a directory")),
        "{stderr}"
    );
    // Every frame of a sequence is checked up front too.
    std::fs::create_dir(dir.path().join("seq_002.png")).unwrap();
    let sequence = dir.path().join("seq.png");
    let out = render(
        &PRESET,
        sequence.to_str().unwrap(),
        &["--sun-elevation-to", "33"],
    );
    let stderr = one_line_error(&out);
    assert!(stderr.contains("seq_002.png is a directory"), "{stderr}");
    assert!(!dir.path().join("seq_000.png").exists(), "no frame written");
    // And the swatch of sora colour.
    let spectrum = dir.path().join("flat.csv");
    std::fs::write(&spectrum, "wavelength_nm,value\n360,1\n830,1\n").unwrap();
    let out = sora(&["colour", spectrum.to_str().unwrap(), "--swatch", path]);
    let stderr = one_line_error(&out);
    assert!(stderr.contains("--swatch"), "{stderr}");
    assert!(stderr.contains("is a directory"), "{stderr}");
    assert!(out.stdout.is_empty(), "nothing printed before the refusal");
}

#[cfg(unix)]
#[test]
fn a_symbolic_link_is_followed_and_kept() {
    let dir = tempfile::tempdir().unwrap();
    let renders = dir.path().join("renders");
    std::fs::create_dir(&renders).unwrap();
    let target = renders.join("today.png");
    std::fs::write(&target, b"old contents").unwrap();
    let link = dir.path().join("latest.png");
    // A relative link: resolved from the link's own directory.
    std::os::unix::fs::symlink("renders/today.png", &link).unwrap();
    let out = render(&PRESET, link.to_str().unwrap(), &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink(),
        "the link is kept"
    );
    assert_eq!(
        &std::fs::read(&target).unwrap()[..8],
        b"\x89PNG\r\n\x1a\n",
        "its target holds the image"
    );
    // No temporary file is left in either directory.
    for directory in [dir.path(), renders.as_path()] {
        for entry in std::fs::read_dir(directory).unwrap() {
            let name = entry.unwrap().file_name();
            assert!(!name.to_string_lossy().contains(".tmp-"), "{name:?}");
        }
    }
    // A dangling link writes the file it names.
    let dangling = dir.path().join("next.png");
    std::os::unix::fs::symlink("renders/tomorrow.png", &dangling).unwrap();
    let out = render(&PRESET, dangling.to_str().unwrap(), &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(renders.join("tomorrow.png").is_file());
    // A link to a directory is refused, naming both; a loop of links too.
    let to_directory = dir.path().join("dir.png");
    std::os::unix::fs::symlink("renders", &to_directory).unwrap();
    let stderr = one_line_error(&render(&PRESET, to_directory.to_str().unwrap(), &[]));
    assert!(
        stderr.contains("a symbolic link to") && stderr.contains("is a directory"),
        "{stderr}"
    );
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    std::os::unix::fs::symlink("b.png", &a).unwrap();
    std::os::unix::fs::symlink("a.png", &b).unwrap();
    let stderr = one_line_error(&render(&PRESET, a.to_str().unwrap(), &[]));
    assert!(stderr.contains("symbolic links in a chain"), "{stderr}");
}

#[cfg(unix)]
#[test]
fn a_read_only_file_is_refused_and_left_alone() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let protected = dir.path().join("keep.png");
    std::fs::write(&protected, b"precious").unwrap();
    std::fs::set_permissions(&protected, std::fs::Permissions::from_mode(0o444)).unwrap();
    let path = protected.to_str().unwrap();
    let out = render(&["--atmosphere", "/nonexistent/air.toml"], path, &[]);
    let stderr = one_line_error(&out);
    assert!(
        stderr.contains(&format!("-o {path} exists and is read-only")),
        "{stderr}"
    );
    assert_eq!(std::fs::read(&protected).unwrap(), b"precious");
    // Through a link, the message names the link and its target.
    let link = dir.path().join("link.png");
    std::os::unix::fs::symlink(&protected, &link).unwrap();
    let stderr = one_line_error(&render(&PRESET, link.to_str().unwrap(), &[]));
    assert!(
        stderr.contains("a symbolic link to") && stderr.contains("read-only"),
        "{stderr}"
    );
    assert_eq!(std::fs::read(&protected).unwrap(), b"precious");
    // A writable existing file is replaced.
    let writable = dir.path().join("old.png");
    std::fs::write(&writable, b"old").unwrap();
    let out = render(&PRESET, writable.to_str().unwrap(), &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(&std::fs::read(&writable).unwrap()[..4], b"\x89PNG");
}

/// The perspective camera's options with the whole-sky cameras are an
/// error naming the option and the camera (issue 17: they were silently
/// ignored), before any work; with the perspective camera they apply.
#[test]
fn perspective_options_with_whole_sky_cameras_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("sky.png");
    let output = output.to_str().unwrap();
    for (camera, shown) in [
        (None, "fisheye"),
        (Some("fisheye"), "fisheye"),
        (Some("equirect"), "equirect"),
    ] {
        for (option, value) in [
            ("--fov-deg", "60"),
            ("--view-elevation", "20"),
            ("--view-azimuth", "-90"),
        ] {
            let mut extra = vec![option, value];
            if let Some(camera) = camera {
                extra.extend(["--camera", camera]);
            }
            let out = render(&["--atmosphere", "/nonexistent/air.toml"], output, &extra);
            let stderr = one_line_error(&out);
            assert!(
                stderr.contains(&format!(
                    "{option} applies to --camera perspective only; the {shown} camera"
                )),
                "{extra:?}: {stderr}"
            );
        }
    }
    assert!(!std::path::Path::new(output).exists());
    let out = render(
        &PRESET,
        output,
        &[
            "--camera",
            "perspective",
            "--fov-deg",
            "60",
            "--view-elevation",
            "20",
            "--view-azimuth",
            "-90",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The repository's sample radiances for `sora retrieve` (it never gets to
/// read them here: the outputs are refused first).
fn radiances_csv() -> String {
    format!(
        "{}/../../docs/retrieval_case4_radiances.csv",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// `sora retrieve` of the sample radiances with `--residuals` and `--plot`.
fn retrieve_into(residuals: &std::path::Path, plot: &std::path::Path) -> std::process::Output {
    sora(&[
        "retrieve",
        "--radiances",
        &radiances_csv(),
        "--residuals",
        residuals.to_str().unwrap(),
        "--plot",
        plot.to_str().unwrap(),
    ])
}

/// Stand-ins for devices in a temporary directory (the real /dev is never
/// touched): a FIFO, a link to /dev/null and a link to the FIFO.
#[cfg(unix)]
fn device_stand_ins(dir: &std::path::Path, extension: &str) -> Vec<std::path::PathBuf> {
    let fifo = dir.join(format!("fifo.{extension}"));
    let status = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(status.success());
    let null = dir.join(format!("null.{extension}"));
    std::os::unix::fs::symlink("/dev/null", &null).unwrap();
    let to_fifo = dir.join(format!("to-fifo.{extension}"));
    std::os::unix::fs::symlink(&fifo, &to_fifo).unwrap();
    vec![fifo, null, to_fifo]
}

#[cfg(unix)]
#[test]
fn devices_and_fifos_are_refused_by_every_output() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let png = device_stand_ins(dir.path(), "png");
    let csv = device_stand_ins(&dir.path().join("."), "csv");
    let spectrum = dir.path().join("flat.csv");
    std::fs::write(&spectrum, "wavelength_nm,value\n360,1\n830,1\n").unwrap();
    let radiances = radiances_csv();
    let fine = dir.path().join("fine.png");
    let fine = fine.to_str().unwrap();
    for (device, csv_device) in png.iter().zip(&csv) {
        let device = device.to_str().unwrap();
        let csv_device = csv_device.to_str().unwrap();
        let runs: Vec<(Vec<&str>, &str)> = vec![
            (vec!["render", "--sun-elevation", "30", "-o", device], "-o"),
            (
                vec![
                    "render",
                    "--sun-elevation",
                    "30",
                    "-o",
                    fine,
                    "--dolp",
                    device,
                ],
                "--dolp",
            ),
            (
                vec![
                    "render",
                    "--sun-elevation",
                    "30",
                    "-o",
                    fine,
                    "--aop",
                    device,
                ],
                "--aop",
            ),
            (
                vec!["colour", spectrum.to_str().unwrap(), "--swatch", device],
                "--swatch",
            ),
            (
                vec![
                    "retrieve",
                    "--radiances",
                    &radiances,
                    "--residuals",
                    csv_device,
                ],
                "--residuals",
            ),
            (
                vec!["retrieve", "--radiances", &radiances, "--plot", device],
                "--plot",
            ),
        ];
        for (mut args, option) in runs {
            if args[0] == "render" {
                args.extend(["--preset", "clear-sky-reference", "--width", "8"]);
            }
            let stderr = one_line_error(&sora(&args));
            assert!(
                stderr.contains(option) && stderr.contains("is not a regular file"),
                "{args:?}: {stderr}"
            );
        }
    }
    // The stand-ins are as they were, and nothing else was written.
    for path in png.iter().chain(&csv) {
        let metadata = std::fs::symlink_metadata(path).unwrap();
        assert!(metadata.file_type().is_fifo() || metadata.file_type().is_symlink());
    }
    assert!(!std::path::Path::new(fine).exists());
}

#[cfg(unix)]
#[test]
fn two_outputs_on_one_file_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let image = dir.path().join("sky.png");
    let image = image.to_str().unwrap();
    let stderr = one_line_error(&render(&PRESET, image, &["--dolp", image]));
    assert!(
        stderr.contains(&format!("--dolp {image} is the same file as -o {image}")),
        "{stderr}"
    );
    // By another spelling, or through a link.
    let spelled = format!("{}/./sky.png", dir.path().display());
    let stderr = one_line_error(&render(&PRESET, image, &["--aop", &spelled]));
    assert!(stderr.contains("is the same file as -o"), "{stderr}");
    let link = dir.path().join("link.csv");
    std::os::unix::fs::symlink("fit.png", &link).unwrap();
    let plot = dir.path().join("fit.png");
    let stderr = one_line_error(&retrieve_into(&link, &plot));
    assert!(
        stderr.contains("--plot") && stderr.contains("is the same file as --residuals"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "only the link"
    );
}

/// An output in a read-only directory (`sora retrieve --residuals res.csv
/// --plot ro/fit.png`) is refused before any work, in one line naming the
/// option and the directory, and the other output is not written either:
/// as root too (a directory with no write permission is refused whoever
/// runs sora, as a read-only file is).
#[cfg(unix)]
#[test]
fn an_output_in_a_read_only_directory_is_refused_and_nothing_is_written() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let locked = dir.path().join("ro");
    std::fs::create_dir(&locked).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    let residuals = dir.path().join("res.csv");
    let plot = locked.join("fit.png");
    let started = std::time::Instant::now();
    let stderr = one_line_error(&retrieve_into(&residuals, &plot));
    // Before the fit (which takes seconds even in a release build).
    assert!(started.elapsed().as_secs_f64() < 10.0);
    assert!(
        stderr.contains(&format!("--plot {}", plot.display()))
            && stderr.contains(&format!("the directory {} is read-only", locked.display())),
        "{stderr}"
    );
    assert!(!residuals.exists());
    // The same for an image.
    let stderr = one_line_error(&render(
        &PRESET,
        locked.join("sky.png").to_str().unwrap(),
        &[],
    ));
    assert!(stderr.contains("is read-only"), "{stderr}");
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
    assert_eq!(std::fs::read_dir(&locked).unwrap().count(), 0);
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "only ro/"
    );
}
