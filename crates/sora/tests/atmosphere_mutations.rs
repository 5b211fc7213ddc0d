//! Mutation fuzzing of the atmosphere-file loader (issue 17: never abort,
//! never print NaN).
//!
//! The shipped presets (`atmospheres/*.toml`) are mutated by a seeded
//! generator (one to three edits per file: delete, duplicate or swap lines,
//! swap two keys, replace a number by 0, -1, 1e308, NaN, inf, huge or tiny
//! values, truncate the text), then loaded with
//! `Atmosphere::from_toml_str` and, when that succeeds, put on a small grid
//! with `compute_optics`. Every outcome must be one of:
//! - an error of one non-empty line, or
//! - optics that are finite and non-negative (coefficients, solar
//!   irradiance, ground albedo, phase function, g within [-1, 1]);
//!
//! and nothing may panic (`catch_unwind` around both calls). A fixed-seed
//! short campaign runs with the tests; `cargo test -p sora --test
//! atmosphere_mutations -- --ignored --nocapture` runs a long one (10,000
//! files; `SORA_FUZZ_SEED` and `SORA_FUZZ_FILES` change the seed and the
//! count; `SORA_FUZZ_TRACE=FILE` writes each file there before it runs,
//! so that after a crash FILE is the culprit) and prints its counts.
//!
//! Found and fixed (issue 17): `SORA_FUZZ_SEED=99 SORA_FUZZ_FILES=50000`
//! reached `mars-dust` with `effective_variance = 1e-30` in its lognormal,
//! for which the radius quadrature's panels stopped advancing and it
//! allocated until the process aborted. Widths below sora-mie's
//! `MIN_GEOMETRIC_STANDARD_DEVIATION` / `MIN_EFFECTIVE_VARIANCE` are refused
//! naming the key, and the quadrature counts its nodes against a bound
//! before it allocates (`tests/atmosphere_files.rs` keeps the cases).
//! The same campaign also found `sun.irradiance_scale = 1e308` (an
//! infinite solar irradiance; now at most 1e4). After both fixes it gives
//! files 50000, parse errors 42989, optics errors 65, ok 6946, panics 0,
//! multi-line errors 0, NaN/negative optics 0 (665 s, release build).

mod common;

use std::panic::{AssertUnwindSafe, catch_unwind};

use sora::atmosphere::{Atmosphere, AtmosphereOptics, PRESETS};
use sora::spectrum::WavelengthGrid;

use common::Rng;

/// The values a number is replaced by (TOML spellings).
const NUMBERS: [&str; 16] = [
    "0", "-1", "1e308", "nan", "inf", "-inf", "1e-308", "5e-324", "1e30", "-1e30", "1e-30", "1",
    "2", "0.5", "1e6", "-0.0",
];

/// Byte ranges of the numbers in `line` (outside strings, after the `=`).
fn number_spans(line: &str) -> Vec<(usize, usize)> {
    let bytes = line.as_bytes();
    let Some(eq) = line.find('=') else {
        return Vec::new();
    };
    let mut spans = Vec::new();
    let mut in_string = false;
    let mut i = eq + 1;
    while i < bytes.len() {
        let c = bytes[i];
        if c == b'"' {
            in_string = !in_string;
            i += 1;
            continue;
        }
        let starts_number = !in_string
            && (c.is_ascii_digit() || c == b'-' || c == b'+')
            && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'));
        if starts_number {
            let start = i;
            i += 1;
            while i < bytes.len()
                && (bytes[i].is_ascii_alphanumeric() || matches!(bytes[i], b'.' | b'-' | b'+'))
            {
                i += 1;
            }
            spans.push((start, i));
        } else {
            i += 1;
        }
    }
    spans
}

/// One mutation of `text`.
fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    if lines.is_empty() {
        return String::new();
    }
    match rng.below(7) {
        // Delete a line.
        0 => {
            let i = rng.below(lines.len());
            lines.remove(i);
        }
        // Duplicate a line (in place or somewhere else).
        1 => {
            let i = rng.below(lines.len());
            let j = rng.below(lines.len() + 1);
            let line = lines[i].clone();
            lines.insert(j, line);
        }
        // Swap two lines.
        2 => {
            let (i, j) = (rng.below(lines.len()), rng.below(lines.len()));
            lines.swap(i, j);
        }
        // Swap the keys of two `key = value` lines.
        3 => {
            let keyed: Vec<usize> = (0..lines.len())
                .filter(|&i| lines[i].contains('=') && !lines[i].trim_start().starts_with('#'))
                .collect();
            if keyed.len() >= 2 {
                let i = keyed[rng.below(keyed.len())];
                let j = keyed[rng.below(keyed.len())];
                let (ki, vi) = lines[i].split_once('=').unwrap();
                let (kj, vj) = lines[j].split_once('=').unwrap();
                let (a, b) = (format!("{kj}={vi}"), format!("{ki}={vj}"));
                lines[i] = a;
                lines[j] = b;
            }
        }
        // Truncate the whole text at a character boundary.
        4 => {
            let joined = lines.join("\n");
            let mut cut = rng.below(joined.len() + 1);
            while !joined.is_char_boundary(cut) {
                cut -= 1;
            }
            return joined[..cut].to_string();
        }
        // Replace a number (twice as likely as the others: most of the
        // checks are of values).
        _ => {
            let candidates: Vec<(usize, (usize, usize))> = lines
                .iter()
                .enumerate()
                .filter(|(_, l)| !l.trim_start().starts_with('#'))
                .flat_map(|(i, l)| number_spans(l).into_iter().map(move |s| (i, s)))
                .collect();
            if !candidates.is_empty() {
                let (i, (start, end)) = candidates[rng.below(candidates.len())];
                let value = NUMBERS[rng.below(NUMBERS.len())];
                lines[i].replace_range(start..end, value);
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
    parse_errors: usize,
    optics_errors: usize,
    ok: usize,
    panics: Vec<String>,
    multi_line_errors: Vec<String>,
    non_finite: Vec<String>,
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "(non-string panic payload)".to_string()
    }
}

fn check_error(message: &str, text: &str, counts: &mut Counts) {
    if message.contains('\n') || message.trim().is_empty() {
        counts
            .multi_line_errors
            .push(format!("{message:?} for:\n{text}"));
    }
}

/// What is wrong with `optics`, if anything.
fn optics_problem(optics: &AtmosphereOptics) -> Option<String> {
    let bad = |v: &f64| !v.is_finite() || *v < 0.0;
    if optics.solar_irradiance_w_m2_nm.values().iter().any(bad) {
        return Some("solar irradiance".into());
    }
    if optics.ground_albedo.values().iter().any(bad) {
        return Some("ground albedo".into());
    }
    for s in &optics.species {
        if s.extinction_per_m.values().iter().any(bad) {
            return Some(format!("{}: extinction {:?}", s.name, s.extinction_per_m));
        }
        if s.scattering_per_m.values().iter().any(bad) {
            return Some(format!("{}: scattering {:?}", s.name, s.scattering_per_m));
        }
        if !s.vertical_column_m.is_finite() || s.vertical_column_m < 0.0 {
            return Some(format!("{}: column {}", s.name, s.vertical_column_m));
        }
        for i in 0..optics.grid.len() {
            let g = s.phase_function.asymmetry_g(i);
            if !g.is_finite() || g.abs() > 1.0 + 1e-12 {
                return Some(format!("{}: g = {g}", s.name));
            }
            for mu in [-1.0, -0.5, 0.0, 0.5, 0.99, 1.0] {
                let p = s.phase_function.eval(i, mu);
                if bad(&p) {
                    return Some(format!("{}: phase({mu}) = {p}", s.name));
                }
            }
        }
    }
    None
}

/// One file through the loader and the optics.
fn exercise(text: &str, grid: &WavelengthGrid, counts: &mut Counts) {
    counts.files += 1;
    let parsed = match catch_unwind(|| Atmosphere::from_toml_str(text)) {
        Err(payload) => {
            counts.panics.push(format!(
                "from_toml_str panicked: {} for:\n{text}",
                panic_message(&*payload)
            ));
            return;
        }
        Ok(parsed) => parsed,
    };
    let atmosphere = match parsed {
        Err(error) => {
            counts.parse_errors += 1;
            check_error(&error.to_string(), text, counts);
            return;
        }
        Ok(atmosphere) => atmosphere,
    };
    match catch_unwind(AssertUnwindSafe(|| atmosphere.compute_optics(grid))) {
        Err(payload) => counts.panics.push(format!(
            "compute_optics panicked: {} for:\n{text}",
            panic_message(&*payload)
        )),
        Ok(Err(error)) => {
            counts.optics_errors += 1;
            check_error(&error.to_string(), text, counts);
        }
        Ok(Ok(optics)) => match optics_problem(&optics) {
            Some(problem) => counts.non_finite.push(format!("{problem} for:\n{text}")),
            None => counts.ok += 1,
        },
    }
}

fn campaign(seed: u64, files: usize) -> Counts {
    let grid = WavelengthGrid::new(400.0, 700.0, 100.0).unwrap();
    let mut rng = Rng(seed);
    let mut counts = Counts::default();
    let trace = std::env::var_os("SORA_FUZZ_TRACE");
    // Panics are caught and counted; keep their messages off stderr.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    for _ in 0..files {
        let preset = &PRESETS[rng.below(PRESETS.len())];
        let mut text = preset.toml.to_string();
        for _ in 0..1 + rng.below(3) {
            text = mutate(&text, &mut rng);
        }
        if let Some(path) = &trace {
            // Each file before it runs: after a crash (out of memory, an
            // abort), the file at SORA_FUZZ_TRACE is the culprit.
            std::fs::write(path, &text).unwrap();
        }
        exercise(&text, &grid, &mut counts);
    }
    std::panic::set_hook(hook);
    counts
}

fn report(counts: &Counts) -> String {
    format!(
        "files {}, parse errors {}, optics errors {}, ok {}, panics {}, multi-line errors {}, NaN/negative optics {}",
        counts.files,
        counts.parse_errors,
        counts.optics_errors,
        counts.ok,
        counts.panics.len(),
        counts.multi_line_errors.len(),
        counts.non_finite.len()
    )
}

fn assert_clean(counts: &Counts) {
    let problems: Vec<&String> = counts
        .panics
        .iter()
        .chain(&counts.multi_line_errors)
        .chain(&counts.non_finite)
        .collect();
    assert!(
        problems.is_empty(),
        "{}\nfirst problems:\n{}",
        report(counts),
        problems
            .iter()
            .take(5)
            .map(|p| p.as_str())
            .collect::<Vec<_>>()
            .join("\n----\n")
    );
}

#[test]
fn the_mutator_changes_files_and_finds_numbers() {
    assert_eq!(
        number_spans("x = { a = 1.5e-3, b = [2, -3], s = \"v1\" }"),
        [(10, 16), (23, 24), (26, 28)]
    );
    let mut rng = Rng(1);
    let text = PRESETS[0].toml;
    let changed = (0..50).filter(|_| mutate(text, &mut rng) != text).count();
    assert!(changed > 30, "{changed} of 50 mutations changed the file");
}

#[test]
fn mutated_presets_never_panic_and_errors_are_one_line() {
    let counts = campaign(17, 400);
    eprintln!("short campaign: {}", report(&counts));
    assert_clean(&counts);
    // The campaign reaches both the errors and the optics.
    assert!(
        counts.parse_errors > 0 && counts.ok > 0,
        "{}",
        report(&counts)
    );
}

#[test]
#[ignore = "long campaign: run with --ignored --nocapture to print its counts"]
fn mutated_presets_long_campaign() {
    let start = std::time::Instant::now();
    // SORA_FUZZ_SEED and SORA_FUZZ_FILES override the seed and the count.
    let env = |name: &str, default: u64| {
        std::env::var(name)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(default)
    };
    let counts = campaign(
        env("SORA_FUZZ_SEED", 0x5eed_2026),
        env("SORA_FUZZ_FILES", 10_000) as usize,
    );
    println!(
        "long campaign ({:.1} s): {}",
        start.elapsed().as_secs_f64(),
        report(&counts)
    );
    assert_clean(&counts);
}
