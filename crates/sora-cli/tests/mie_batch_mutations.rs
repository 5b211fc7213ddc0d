//! Mutation fuzzing of `sora mie --batch` (issue 17: never abort, never
//! print NaN), through the binary: the batch reader lives in the CLI.
//!
//! A valid batch (header, a comment, rows of reference spheres) is mutated
//! by a seeded generator (one to three edits: delete, duplicate or swap
//! lines, replace a field by 0, -1, 1e308, NaN, inf, huge, tiny or not a
//! number, add or drop a field, truncate) and fed to `sora mie --batch -`.
//! Every run must either succeed, printing the header and rows of eight
//! finite numbers with non-negative efficiencies and g in [-1, 1], or fail
//! with exit status 1 and a one-line error; never a panic (status 101), a
//! signal, or NaN. A fixed-seed short campaign runs with the tests;
//! `-- --ignored --nocapture` runs a long one (5,000 files) and prints its
//! counts.

mod common;

use std::io::Write;
use std::process::{Command, Stdio};

use common::Rng;

const VALID: &str = "# spheres of the reference table\n\
m_re,m_im,x\n\
1.33,0.0,0.5\n\
1.33,0.0,10.0\n\
1.5,0.01,1.0\n\
1.5,0.01,100.0\n\
1.55,0.001,10.0\n\
\n\
1.5,1.0,1.0\n";

const VALUES: [&str; 20] = [
    "0",
    "-1",
    "1e308",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e-308",
    "5e-324",
    "1e6",
    "1e5",
    "1e300",
    "-0.0",
    "1",
    "abc",
    "",
    " 1.5 ",
    "1.5+0.01i",
    "1e",
    "+2",
];

fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    if lines.is_empty() {
        return String::new();
    }
    match rng.below(7) {
        0 => {
            let i = rng.below(lines.len());
            lines.remove(i);
        }
        1 => {
            let i = rng.below(lines.len());
            let j = rng.below(lines.len() + 1);
            let line = lines[i].clone();
            lines.insert(j, line);
        }
        2 => {
            let (i, j) = (rng.below(lines.len()), rng.below(lines.len()));
            lines.swap(i, j);
        }
        3 => {
            // Add or drop a field.
            let i = rng.below(lines.len());
            if rng.below(2) == 0 {
                lines[i].push_str(",1.0");
            } else if let Some((head, _)) = lines[i].rsplit_once(',') {
                lines[i] = head.to_string();
            }
        }
        4 => {
            let joined = lines.join("\n");
            let mut cut = rng.below(joined.len() + 1);
            while !joined.is_char_boundary(cut) {
                cut -= 1;
            }
            return joined[..cut].to_string();
        }
        _ => {
            // Replace one field of a row (never the header: that is one
            // error, found at once).
            let rows: Vec<usize> = (0..lines.len())
                .filter(|&i| lines[i].contains(',') && !lines[i].starts_with("m_re"))
                .collect();
            if !rows.is_empty() {
                let i = rows[rng.below(rows.len())];
                let mut fields: Vec<String> = lines[i].split(',').map(str::to_string).collect();
                let f = rng.below(fields.len());
                fields[f] = VALUES[rng.below(VALUES.len())].to_string();
                lines[i] = fields.join(",");
            }
        }
    }
    let mut out = lines.join("\n");
    out.push('\n');
    out
}

#[derive(Debug, Default)]
struct Counts {
    files: usize,
    ok: usize,
    errors: usize,
    problems: Vec<String>,
}

/// What is wrong with one run's output, if anything.
fn problem(code: Option<i32>, stdout: &str, stderr: &str) -> Option<String> {
    match code {
        Some(0) => {
            if stdout.to_ascii_lowercase().contains("nan") {
                return Some("NaN printed".into());
            }
            let mut lines = stdout.lines();
            if lines.next() != Some("m_re,m_im,x,qext,qsca,qabs,qback,g") {
                return Some("no header".into());
            }
            for line in lines {
                let numbers: Vec<f64> = line.split(',').filter_map(|f| f.parse().ok()).collect();
                if numbers.len() != 8 || numbers.iter().any(|v| !v.is_finite()) {
                    return Some(format!("row not eight finite numbers: {line}"));
                }
                if numbers[3..7].iter().any(|q| *q < 0.0) || numbers[7].abs() > 1.0 {
                    return Some(format!("negative efficiency or |g| > 1: {line}"));
                }
            }
            None
        }
        Some(1) => {
            if stderr.lines().count() != 1 || !stderr.starts_with("error: ") {
                Some(format!("not a one-line error: {stderr:?}"))
            } else if stderr.to_ascii_lowercase().contains("panicked") {
                Some(format!("panic: {stderr}"))
            } else {
                None
            }
        }
        other => Some(format!("exit status {other:?} (panic or signal): {stderr}")),
    }
}

fn campaign(seed: u64, files: usize) -> Counts {
    let mut rng = Rng(seed);
    let mut counts = Counts::default();
    for _ in 0..files {
        let mut text = VALID.to_string();
        for _ in 0..1 + rng.below(3) {
            text = mutate(&text, &mut rng);
        }
        let mut child = Command::new(env!("CARGO_BIN_EXE_sora"))
            .args(["mie", "--batch", "-"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("the sora binary runs");
        // The reader may stop early (a bad line): a broken pipe is fine.
        let _ = child.stdin.take().unwrap().write_all(text.as_bytes());
        let out = child.wait_with_output().unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        counts.files += 1;
        match problem(out.status.code(), &stdout, &stderr) {
            Some(p) => counts.problems.push(format!("{p}\nfor:\n{text}")),
            None if out.status.success() => counts.ok += 1,
            None => counts.errors += 1,
        }
    }
    counts
}

fn report(counts: &Counts) -> String {
    format!(
        "files {}, ok {}, one-line errors {}, problems (panics, NaN, bad output) {}",
        counts.files,
        counts.ok,
        counts.errors,
        counts.problems.len()
    )
}

fn assert_clean(counts: &Counts) {
    common::assert_no_problems(&report(counts), &counts.problems);
}

#[test]
fn mutated_batches_never_panic_and_errors_are_one_line() {
    let counts = campaign(17, 200);
    eprintln!("short campaign: {}", report(&counts));
    assert_clean(&counts);
    assert!(counts.ok > 0 && counts.errors > 0, "{}", report(&counts));
}

#[test]
#[ignore = "long campaign: run with --ignored --nocapture to print its counts"]
fn mutated_batches_long_campaign() {
    let start = std::time::Instant::now();
    let counts = campaign(0x5eed_2026, 5_000);
    println!(
        "long campaign ({:.1} s): {}",
        start.elapsed().as_secs_f64(),
        report(&counts)
    );
    assert_clean(&counts);
}
