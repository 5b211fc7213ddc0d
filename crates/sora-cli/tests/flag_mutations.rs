//! Mutation fuzzing of the command-line flags (issue 17: never abort,
//! never print NaN, never leave a partial file), through the binary.
//!
//! Tiny valid invocations of every command (`mie`, `spectrum`, `render`
//! with sequences from `--time` and polarisation maps, `irradiance` with
//! `--time`, `atmosphere show`, `colour`, `retrieve` of ten radiances with
//! `--residuals` and `--plot`: a few pixels, two wavelengths) are mutated
//! by a seeded generator (one or two edits:
//! replace a value by 0, -1, 1e308, NaN, inf, 5e-324, a word, an empty
//! string, a value past a limit; drop, duplicate or misspell a flag; add a
//! flag of another command with an awkward value; point an output at a
//! device stand-in (a FIFO, a link to /dev/null or to the FIFO), a
//! directory, a link or another output's file; swap the command), and
//! each is run in a fresh directory. Every run must:
//!
//! - exit with status 0, 1 (sora's own error) or 2 (clap's usage error),
//!   never 101 (panic), 134 (abort) or a signal;
//! - on status 1, print exactly one line, `error: ...`; on status 2,
//!   clap's message, whose first line is `error: ...`;
//! - print no NaN or infinity on stdout;
//! - leave no partial file: no temporary file ever, nothing new after a
//!   failure, and only complete images (PNG or OpenEXR magic and, for PNG,
//!   the IEND chunk at the end) and CSV after a success;
//! - leave the device stand-ins, the directory and the links as they were.
//!
//! A run still going after [`TIMEOUT`] (a legal but long job the mutation
//! made, e.g. many frames) is killed and counted as slow, not judged. A
//! fixed-seed short campaign runs with the tests; `cargo test -p sora-cli
//! --test flag_mutations -- --ignored --nocapture` runs a long one (1,000
//! flag sets; `SORA_FUZZ_SEED`, `SORA_FUZZ_CASES` change them) and prints
//! its counts.
//!
//! Found and fixed: `sora mie --phase --angle-step-deg 5e-324` and
//! `sora spectrum --almucantar 5e-324` overflowed their counts (panics in
//! debug builds). Counts after the fixes: seed 2026, 1,000 cases: 127 ok,
//! 235 one-line errors, 638 usage errors, 0 slow, 0 problems; seed 7, 5,000
//! cases: 646 ok, 1194 one-line errors, 3160 usage errors, 0 slow, 0
//! problems; seed 11, 8,000 cases: 1073 ok, 1858 one-line errors, 5069
//! usage errors, 0 slow, 0 problems; seed 20261205, 2,000 cases (release,
//! 111 s): 269 ok, 669 one-line errors, 1061 usage errors, 1 slow, 0
//! problems. The slow case read its input from the FIFO stand-in
//! (`retrieve --radiances fifo.csv`), which waits for a writer as every
//! reader of a named pipe does (process substitution, `<(...)`, needs it).

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::Rng;

/// A run past this is killed and counted as slow.
const TIMEOUT: Duration = Duration::from_secs(30);

/// The valid starting points: a command and its flags (a flag without a
/// value is `(flag, None)`; a positional argument is `("", Some(value))`).
fn templates() -> Vec<Vec<(&'static str, Option<&'static str>)>> {
    let scene = [
        ("--preset", Some("clear-sky-reference")),
        ("--sun-elevation", Some("30")),
        ("--wavelengths", Some("500:600:100")),
    ];
    let with_scene = |command: &[(&'static str, Option<&'static str>)],
                      extra: &[(&'static str, Option<&'static str>)]| {
        [command, &scene[..], extra].concat()
    };
    vec![
        vec![
            ("mie", None),
            ("--m", Some("1.5+0.01i")),
            ("--x", Some("1")),
        ],
        vec![
            ("mie", None),
            ("--m", Some("1.5+0.01i")),
            ("--lognormal", Some("0.1,2.0")),
            ("--wavelengths", Some("500:600:100")),
        ],
        vec![
            ("mie", None),
            ("--m", Some("1.33")),
            ("--gamma", Some("0.5,0.2")),
            ("--wavelengths", Some("500:600:100")),
        ],
        vec![
            ("mie", None),
            ("--m", Some("1.5+0.01i")),
            ("--radius-um", Some("0.3")),
            ("--wavelength-nm", Some("550")),
            ("--phase", None),
            ("--angle-step-deg", Some("10")),
        ],
        with_scene(
            &[("spectrum", None)],
            &[
                ("--view-elevation", Some("10")),
                ("--view-azimuth", Some("0")),
                ("--scattering", Some("single")),
                ("--format", Some("csv")),
            ],
        ),
        with_scene(
            &[("spectrum", None)],
            &[
                ("--almucantar", Some("30")),
                ("--method", Some("path-tracing")),
                ("--samples", Some("50")),
                ("--format", Some("json")),
            ],
        ),
        with_scene(
            &[("render", None)],
            &[
                ("--width", Some("4")),
                ("--scattering", Some("single")),
                ("-o", Some("out.png")),
            ],
        ),
        with_scene(
            &[("render", None)],
            &[
                ("--camera", Some("perspective")),
                ("--width", Some("3")),
                ("--height", Some("2")),
                ("--fov-deg", Some("60")),
                ("--exr-half", None),
                ("-o", Some("out.exr")),
            ],
        ),
        with_scene(
            &[("irradiance", None)],
            &[("--scattering", Some("single")), ("--format", Some("csv"))],
        ),
        vec![
            ("atmosphere", None),
            ("show", None),
            ("--preset", Some("paper-mars")),
            ("--format", Some("csv")),
        ],
        vec![
            ("colour", None),
            ("", Some("flat.csv")),
            ("--wavelengths", Some("400:700:100")),
            ("--swatch", Some("swatch.png")),
        ],
        // A sequence whose first sun comes from --time (about 11 degrees at
        // 05:30 in Tokyo on the solstice: two frames).
        vec![
            ("render", None),
            ("--preset", Some("clear-sky-reference")),
            ("--time", Some("2026-06-21T05:30:00+09:00")),
            ("--location", Some("35.68,139.77")),
            ("--sun-elevation-to", Some("12")),
            ("--wavelengths", Some("500:600:100")),
            ("--scattering", Some("single")),
            ("--width", Some("2")),
            ("-o", Some("seq.png")),
        ],
        with_scene(
            &[("render", None)],
            &[
                ("--width", Some("2")),
                ("--dolp", Some("dolp.png")),
                ("--aop", Some("aop.png")),
                ("-o", Some("out.exr")),
            ],
        ),
        vec![
            ("irradiance", None),
            ("--preset", Some("clear-sky-reference")),
            ("--time", Some("2026-06-21T12:00:00Z")),
            ("--location", Some("0,0")),
            ("--wavelengths", Some("500:600:100")),
            ("--scattering", Some("single")),
        ],
        vec![
            ("retrieve", None),
            ("--radiances", Some("radiances.csv")),
            ("--preset", Some("clear-sky-reference")),
            ("--max-iterations", Some("1")),
            ("--starting-points", Some("1")),
            ("--residuals", Some("res.csv")),
            ("--plot", Some("fit.png")),
        ],
    ]
}

/// Awkward values for any flag.
const VALUES: [&str; 26] = [
    "0",
    "-1",
    "1e308",
    "-1e308",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "5e-324",
    "1e-300",
    "-0",
    "abc",
    "",
    " ",
    "2",
    "91",
    "-91",
    "16385",
    "4294967296",
    "1e30",
    "1,2",
    "1,2,3,4,5",
    "1+1i",
    "1.5-0.1i",
    "360:830:0.01",
    "380:780:7",
];

/// Flags that a mutation may add: the commands that take them, and values
/// chosen to stay cheap when they are legal.
const EXTRA_FLAGS: [(&str, &str, &[&str]); 41] = [
    // Output paths: device stand-ins (a FIFO, links to /dev/null and to
    // the FIFO), a directory, a link to a file, and the other outputs'
    // names (two outputs on one file).
    (
        "-o",
        "render",
        &[
            "out.png",
            "fifo.png",
            "null.png",
            "sub",
            "link.png",
            "dolp.png",
            "to-fifo.png",
        ],
    ),
    (
        "--dolp",
        "render",
        &[
            "dolp.png", "fifo.png", "null.png", "out.png", "link.png", "sub",
        ],
    ),
    (
        "--aop",
        "render",
        &["aop.png", "null.png", "dolp.png", "to-fifo.png"],
    ),
    (
        "--swatch",
        "colour",
        &["swatch.png", "fifo.png", "null.png", "sub", "link.png"],
    ),
    (
        "--residuals",
        "retrieve",
        &[
            "res.csv", "fifo.csv", "null.csv", "fit.png", "sub", "link.png",
        ],
    ),
    (
        "--plot",
        "retrieve",
        &["fit.png", "fifo.png", "null.png", "res.csv", "link.png"],
    ),
    ("--max-scans", "retrieve", &["0", "1", "-1"]),
    (
        "--radiances",
        "retrieve",
        &["flat.csv", "fifo.csv", "missing.csv", "radiances.csv"],
    ),
    ("--width", "render", &["0", "1", "3", "16385", "nan"]),
    ("--height", "render", &["0", "1", "2", "99999999"]),
    (
        "--camera",
        "render",
        &["fisheye", "equirect", "perspective", "pinhole"],
    ),
    ("--fov-deg", "render", &["0", "1", "179", "180", "nan"]),
    (
        "--view-elevation",
        "render spectrum",
        &["-90", "90", "91", "nan"],
    ),
    ("--view-azimuth", "render spectrum", &["-720", "360", "inf"]),
    (
        "--method",
        "render spectrum irradiance",
        &["fast", "path-tracing", "reference-ish"],
    ),
    (
        "--scattering",
        "render spectrum irradiance",
        &["single", "multiple", "double"],
    ),
    (
        "--samples",
        "spectrum irradiance",
        &["0", "1", "2", "20", "1000000000000"],
    ),
    (
        "--seed",
        "spectrum irradiance",
        &["0", "18446744073709551615", "-1"],
    ),
    (
        "--format",
        "spectrum irradiance atmosphere",
        &["csv", "json", "table", "xml"],
    ),
    (
        "--sun-azimuth",
        "render spectrum irradiance",
        &["0", "-360", "nan", "1e308"],
    ),
    (
        "--observer-altitude-m",
        "render spectrum irradiance",
        &["-5", "0", "1e6", "99999"],
    ),
    (
        "--exposure",
        "render colour",
        &["0", "-1", "1e308", "auto", "nan"],
    ),
    ("--ev100", "render colour", &["0", "-100", "1e308"]),
    (
        "--time",
        "render spectrum irradiance",
        &["2026-06-21T05:30:00+09:00", "2026-13-01T00:00:00Z", "now"],
    ),
    (
        "--location",
        "render spectrum irradiance",
        &["35.68,139.77", "91,0", "0", "a,b"],
    ),
    ("--no-sun-disc", "render", &[]),
    ("--png-16-bit", "render", &[]),
    ("--units", "render", &["radiance", "luminance", "lux"]),
    ("--sun-elevation-to", "render", &["31", "29", "91", "nan"]),
    (
        "--sun-elevation-step",
        "render",
        &["0", "-1", "1", "nan", "1e-300"],
    ),
    (
        "--atmosphere",
        "render spectrum irradiance atmosphere",
        &["missing.toml", "flat.csv", "."],
    ),
    (
        "--directions",
        "spectrum",
        &["missing.csv", "flat.csv", "directions.csv"],
    ),
    ("--principal-plane", "spectrum", &["1", "0", "-5", "nan"]),
    (
        "--wavelengths",
        "render spectrum irradiance mie colour",
        &["550", "360:830:470", "380:780:7", "829:830:1"],
    ),
    ("--x", "mie", &["1e-300", "1e6", "0.5", "nan"]),
    ("--radius-um", "mie", &["0", "1e-9", "1e4"]),
    ("--wavelength-nm", "mie", &["0", "550", "1e9"]),
    ("--phase", "mie", &[]),
    ("--angle-step-deg", "mie", &["1e-9", "180", "0", "45"]),
    (
        "--lognormal",
        "mie",
        &["0.1,1.00001", "0.1,2,0.2,0.1", "1e5,2"],
    ),
    ("--gamma", "mie", &["0.1,1e-30", "0.5,0.49", "0.5,0.5"]),
];

const COMMANDS: [&str; 7] = [
    "mie",
    "spectrum",
    "render",
    "irradiance",
    "colour",
    "retrieve",
    "self-test",
];

type Arguments = Vec<(String, Option<String>)>;

fn mutate(args: &mut Arguments, rng: &mut Rng) {
    let flag_positions: Vec<usize> = (0..args.len())
        .filter(|&i| args[i].0.starts_with('-'))
        .collect();
    match rng.below(16) {
        0..=7 => {
            // Replace a value (flags with values, positionals): mostly by a
            // number, which passes clap and meets sora's own checks.
            let with_values: Vec<usize> =
                (0..args.len()).filter(|&i| args[i].1.is_some()).collect();
            if !with_values.is_empty() {
                let i = with_values[rng.below(with_values.len())];
                args[i].1 = Some(rng.pick(&VALUES).to_string());
            }
        }
        13 if !flag_positions.is_empty() => {
            args.remove(flag_positions[rng.below(flag_positions.len())]);
        }
        14 if !flag_positions.is_empty() && rng.below(2) == 0 => {
            let i = flag_positions[rng.below(flag_positions.len())];
            let copy = args[i].clone();
            args.push(copy);
        }
        14 if !flag_positions.is_empty() => {
            // A misspelling: a letter dropped or doubled.
            let i = flag_positions[rng.below(flag_positions.len())];
            let name = &mut args[i].0;
            let at = 2 + rng.below(name.len().saturating_sub(2).max(1));
            if at < name.len() {
                if rng.below(2) == 0 {
                    name.remove(at);
                } else {
                    let c = name.as_bytes()[at] as char;
                    name.insert(at, c);
                }
            }
        }
        8..=12 => {
            // Mostly a flag the command takes.
            let command = args[0].0.clone();
            let fitting: Vec<usize> = (0..EXTRA_FLAGS.len())
                .filter(|&i| EXTRA_FLAGS[i].1.split(' ').any(|c| c == command))
                .collect();
            let index = if !fitting.is_empty() && rng.below(4) != 0 {
                fitting[rng.below(fitting.len())]
            } else {
                rng.below(EXTRA_FLAGS.len())
            };
            let (flag, _, values) = EXTRA_FLAGS[index];
            let value = if values.is_empty() {
                None
            } else {
                Some(rng.pick(values).to_string())
            };
            // A flag already there gets the new value (a second copy is
            // the duplicate mutation's job).
            match args.iter_mut().find(|(name, _)| name == flag) {
                Some(existing) => existing.1 = value,
                None => {
                    let at = 1 + rng.below(args.len());
                    args.insert(at.min(args.len()), (flag.to_string(), value));
                }
            }
        }
        15 if rng.below(2) == 0 => {
            args[0].0 = rng.pick(&COMMANDS).to_string();
        }
        _ => {}
    }
}

/// The arguments as a command line. A value that starts with '-' is joined
/// to its flag (`--sun-azimuth=-360`), as a user must write it for clap to
/// take it as a value, so that it reaches sora's own checks.
fn command_line(args: &Arguments) -> Vec<String> {
    let mut line = Vec::new();
    for (name, value) in args {
        match value {
            Some(value) if name.starts_with("--") && value.starts_with('-') => {
                line.push(format!("{name}={value}"));
            }
            _ => {
                if !name.is_empty() {
                    line.push(name.clone());
                }
                if let Some(value) = value {
                    line.push(value.clone());
                }
            }
        }
    }
    line
}

/// Input files a case may name, written into its directory.
fn write_inputs(directory: &Path) {
    std::fs::write(
        directory.join("flat.csv"),
        "wavelength_nm,value\n360,1\n830,1\n",
    )
    .unwrap();
    std::fs::write(
        directory.join("directions.csv"),
        "elevation_deg,azimuth_deg\n10,0\n45,90\n",
    )
    .unwrap();
    std::fs::write(directory.join("radiances.csv"), RADIANCES).unwrap();
    // Stand-ins for devices, never the real /dev files: FIFOs and links
    // to /dev/null and to a FIFO; a directory; a link to a file.
    for fifo in ["fifo.png", "fifo.csv"] {
        let status = Command::new("mkfifo")
            .arg(directory.join(fifo))
            .status()
            .unwrap();
        assert!(status.success());
    }
    for null in ["null.png", "null.csv"] {
        std::os::unix::fs::symlink("/dev/null", directory.join(null)).unwrap();
    }
    std::os::unix::fs::symlink("fifo.png", directory.join("to-fifo.png")).unwrap();
    std::os::unix::fs::symlink("linked.png", directory.join("link.png")).unwrap();
    std::fs::create_dir(directory.join("sub")).unwrap();
}

/// A small set of sky radiances for `sora retrieve` (10 of the case-4
/// almucantar's, at 440 and 870 nm: docs/retrieval_case4_radiances.csv).
const RADIANCES: &str = "wavelength_nm,sun_elevation_deg,sun_azimuth_deg,view_elevation_deg,view_azimuth_deg,radiance_w_m2_sr_nm,uncertainty_w_m2_sr_nm
440,19.1476,180,19.1476,184.0000,3.783041e-1,1.1572e-2
440,19.1476,180,19.1476,190.0000,2.960933e-1,9.0731e-3
440,19.1476,180,19.1476,200.0000,2.417940e-1,7.4358e-3
440,19.1476,180,19.1476,225.0000,1.319842e-1,4.1333e-3
440,19.1476,180,19.1476,270.0000,5.586914e-2,1.8195e-3
870,19.1476,180,19.1476,184.0000,3.917878e-1,1.1788e-2
870,19.1476,180,19.1476,190.0000,1.976243e-1,5.9532e-3
870,19.1476,180,19.1476,200.0000,1.229544e-1,3.7119e-3
870,19.1476,180,19.1476,225.0000,6.268490e-2,1.9038e-3
870,19.1476,180,19.1476,270.0000,1.967825e-2,6.2201e-4
";

/// The inputs (and the stand-ins, checked untouched after every run).
const INPUTS: [&str; 10] = [
    "directions.csv",
    "flat.csv",
    "radiances.csv",
    "fifo.png",
    "fifo.csv",
    "null.png",
    "null.csv",
    "to-fifo.png",
    "link.png",
    "sub",
];

/// A problem if a stand-in for a device (or the directory, or the link)
/// is not what it was: every output must have refused it.
fn stand_ins_changed(directory: &Path) -> Option<String> {
    use std::os::unix::fs::FileTypeExt;
    let kind = |name: &str| std::fs::symlink_metadata(directory.join(name)).map(|m| m.file_type());
    for fifo in ["fifo.png", "fifo.csv"] {
        if !kind(fifo).is_ok_and(|t| t.is_fifo()) {
            return Some(format!("the FIFO {fifo} was replaced"));
        }
    }
    for (link, target) in [
        ("null.png", "/dev/null"),
        ("null.csv", "/dev/null"),
        ("to-fifo.png", "fifo.png"),
        ("link.png", "linked.png"),
    ] {
        if std::fs::read_link(directory.join(link)).ok().as_deref() != Some(Path::new(target)) {
            return Some(format!("the link {link} was replaced"));
        }
    }
    if !kind("sub").is_ok_and(|t| t.is_dir()) {
        return Some("the directory sub was replaced".to_string());
    }
    None
}

/// Whether `bytes` is a complete output file of its kind (an image, or
/// retrieve's residuals).
fn complete_image(name: &str, bytes: &[u8]) -> bool {
    if bytes.starts_with(b"scan,") {
        // retrieve --residuals, by whatever name (through a link named
        // .png too): a header, whole lines.
        bytes.ends_with(b"\n")
    } else if name.ends_with(".png") {
        bytes.starts_with(b"\x89PNG\r\n\x1a\n")
            && bytes.len() > 20
            && &bytes[bytes.len() - 8..bytes.len() - 4] == b"IEND"
    } else if name.ends_with(".exr") {
        bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01])
    } else {
        false
    }
}

/// Whether stdout holds a NaN or an infinity as a word.
fn prints_non_finite(stdout: &str) -> bool {
    stdout
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '-' || c == '+' || c == '.'))
        .any(|word| {
            let word = word.trim_start_matches(['-', '+']).to_ascii_lowercase();
            word == "nan" || word == "inf" || word == "infinity"
        })
}

#[derive(Debug, Default)]
struct Counts {
    cases: usize,
    ok: usize,
    errors: usize,
    usage_errors: usize,
    slow: usize,
    problems: Vec<String>,
}

/// Runs one case in `directory`; returns a problem, if any.
fn run_case(line: &[String], directory: &Path, counts: &mut Counts) -> Option<String> {
    let started = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_sora"))
        .args(line)
        .current_dir(directory)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the sora binary runs");
    // Read the pipes on threads so a chatty child never blocks on them.
    let mut stdout_pipe = child.stdout.take().unwrap();
    let mut stderr_pipe = child.stderr.take().unwrap();
    let stdout_reader = std::thread::spawn(move || {
        let mut text = Vec::new();
        std::io::Read::read_to_end(&mut stdout_pipe, &mut text).ok();
        text
    });
    let stderr_reader = std::thread::spawn(move || {
        let mut text = Vec::new();
        std::io::Read::read_to_end(&mut stderr_pipe, &mut text).ok();
        text
    });
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break Some(status);
        }
        if started.elapsed() > TIMEOUT {
            child.kill().ok();
            child.wait().ok();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let stdout = String::from_utf8_lossy(&stdout_reader.join().unwrap()).into_owned();
    let stderr = String::from_utf8_lossy(&stderr_reader.join().unwrap()).into_owned();
    counts.cases += 1;
    let Some(status) = status else {
        // Named, so that a slow case can be run again to its end.
        eprintln!(
            "slow (killed after {} s): sora {}",
            TIMEOUT.as_secs(),
            line.join(" ")
        );
        counts.slow += 1;
        return None;
    };
    let files: Vec<(String, Vec<u8>)> = std::fs::read_dir(directory)
        .unwrap()
        .map(|entry| entry.unwrap())
        .filter(|entry| !INPUTS.contains(&entry.file_name().to_string_lossy().as_ref()))
        .map(|entry| {
            let name = entry.file_name().to_string_lossy().into_owned();
            let bytes = if entry.path().is_file() {
                std::fs::read(entry.path()).unwrap_or_default()
            } else {
                Vec::new()
            };
            (name, bytes)
        })
        .collect();
    if let Some((name, _)) = files.iter().find(|(name, _)| name.contains(".tmp-")) {
        return Some(format!("temporary file left: {name}"));
    }
    if let Some(problem) = stand_ins_changed(directory) {
        return Some(problem);
    }
    match status.code() {
        Some(0) => {
            counts.ok += 1;
            if prints_non_finite(&stdout) {
                return Some(format!("NaN or inf printed: {stdout}"));
            }
            if let Some((name, _)) = files
                .iter()
                .find(|(name, bytes)| !complete_image(name, bytes))
            {
                return Some(format!("not a complete image: {name}"));
            }
            None
        }
        Some(1) => {
            counts.errors += 1;
            if stderr.lines().count() != 1 || !stderr.starts_with("error: ") {
                Some(format!("not a one-line error: {stderr:?}"))
            } else if stderr.to_ascii_lowercase().contains("panicked") {
                Some(format!("panic: {stderr}"))
            } else if !files.is_empty() {
                Some(format!(
                    "files left after a failure: {:?}",
                    files.iter().map(|f| &f.0).collect::<Vec<_>>()
                ))
            } else {
                None
            }
        }
        Some(2) => {
            counts.usage_errors += 1;
            if std::env::var_os("SORA_FUZZ_SHOW_USAGE").is_some() {
                eprintln!("usage: {}", stderr.lines().next().unwrap_or(""));
            }
            if !stderr.starts_with("error: ") {
                Some(format!("usage error without 'error: ': {stderr:?}"))
            } else if !files.is_empty() {
                Some("files left after a usage error".to_string())
            } else {
                None
            }
        }
        other => Some(format!(
            "exit status {other:?} (panic, abort or signal): {stderr}"
        )),
    }
}

fn campaign(seed: u64, cases: usize) -> Counts {
    let mut rng = Rng(seed);
    let templates = templates();
    let root = tempfile::tempdir().unwrap();
    let mut counts = Counts::default();
    for case in 0..cases {
        let template = &templates[rng.below(templates.len())];
        let mut args: Arguments = template
            .iter()
            .map(|(name, value)| (name.to_string(), value.map(str::to_string)))
            .collect();
        for _ in 0..1 + rng.below(2) {
            mutate(&mut args, &mut rng);
        }
        // self-test runs for a second: keep it rare.
        if args[0].0 == "self-test" && rng.below(8) != 0 {
            args[0].0 = "mie".to_string();
        }
        let directory = root.path().join(format!("case{case}"));
        std::fs::create_dir(&directory).unwrap();
        write_inputs(&directory);
        let line = command_line(&args);
        if let Some(problem) = run_case(&line, &directory, &mut counts) {
            counts
                .problems
                .push(format!("{problem}\nfor: sora {}", line.join(" ")));
        }
        std::fs::remove_dir_all(&directory).ok();
    }
    counts
}

fn report(counts: &Counts) -> String {
    format!(
        "cases {}, ok {}, one-line errors {}, usage errors {}, slow (killed after {} s) {}, problems (panics, aborts, NaN, partial files, multi-line errors) {}",
        counts.cases,
        counts.ok,
        counts.errors,
        counts.usage_errors,
        TIMEOUT.as_secs(),
        counts.slow,
        counts.problems.len()
    )
}

fn assert_clean(counts: &Counts) {
    common::assert_no_problems(&report(counts), &counts.problems);
}

#[test]
fn the_checks_catch_what_they_should() {
    assert!(prints_non_finite("a,NaN,1"));
    assert!(prints_non_finite("x = -inf"));
    assert!(!prints_non_finite(
        "\"name\": \"infrared\", 1e-5, information"
    ));
    assert!(complete_image(
        "a.png",
        b"\x89PNG\r\n\x1a\n0000000000000IEND\xaeB`\x82"
    ));
    assert!(!complete_image("a.png", b"\x89PNG\r\n\x1a\n000"));
    assert!(!complete_image("a.txt", b"anything"));
}

#[test]
fn mutated_flags_short_campaign() {
    let counts = campaign(17, 60);
    assert_clean(&counts);
    // The mutations reach both sides of the checks.
    assert!(
        counts.ok > 0 && counts.errors > 0 && counts.usage_errors > 0,
        "{}",
        report(&counts)
    );
}

#[test]
#[ignore = "long: 1,000 flag sets (a few minutes)"]
fn mutated_flags_long_campaign() {
    let seed = std::env::var("SORA_FUZZ_SEED").map_or(2026, |s| s.parse().unwrap());
    let cases = std::env::var("SORA_FUZZ_CASES").map_or(1000, |s| s.parse().unwrap());
    let started = Instant::now();
    let counts = campaign(seed, cases);
    println!(
        "long campaign (seed {seed}, {:.1} s): {}",
        started.elapsed().as_secs_f64(),
        report(&counts)
    );
    assert_clean(&counts);
}
