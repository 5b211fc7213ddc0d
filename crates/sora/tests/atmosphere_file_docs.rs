//! docs/atmosphere-file.md, the user reference of the atmosphere file
//! format, against the parser: its reference tables list exactly the keys
//! the parser accepts (`sora::atmosphere::file::accepted_keys`, read off
//! the serde schema, so neither side can drift), each with a unit, an
//! allowed range and a default; and every TOML example on it loads and
//! computes its optics over the whole wavelength range.

use std::collections::BTreeSet;

use sora::atmosphere::Atmosphere;
use sora::atmosphere::file::accepted_keys;
use sora::spectrum::WavelengthGrid;

const PAGE: &str = include_str!("../../../docs/atmosphere-file.md");
const README: &str = include_str!("../../../README.md");

/// A row of a reference table: `| \`key\` | unit | allowed | default | meaning |`.
struct KeyRow {
    line: usize,
    key: String,
    cells: Vec<String>,
}

/// The rows of the page's tables whose first cell is one `code` span (the
/// reference tables; other tables start with plain text).
fn key_rows() -> Vec<KeyRow> {
    PAGE.lines()
        .enumerate()
        .filter_map(|(i, line)| {
            let line = line.trim();
            let inner = line.strip_prefix('|')?.strip_suffix('|')?;
            let cells: Vec<String> = inner.split('|').map(|c| c.trim().to_string()).collect();
            let key = cells[0].strip_prefix('`')?.strip_suffix('`')?;
            (!key.contains('`')).then(|| KeyRow {
                line: i + 1,
                key: key.to_string(),
                cells: cells.clone(),
            })
        })
        .collect()
}

#[test]
fn the_page_documents_every_key_the_parser_accepts_and_no_other() {
    let accepted: BTreeSet<String> = accepted_keys().into_iter().collect();
    let rows = key_rows();
    let documented: BTreeSet<String> = rows.iter().map(|r| r.key.clone()).collect();
    let missing: Vec<&String> = accepted.difference(&documented).collect();
    let unknown: Vec<&String> = documented.difference(&accepted).collect();
    assert!(
        missing.is_empty(),
        "keys the parser accepts with no row in docs/atmosphere-file.md: {missing:#?}"
    );
    assert!(
        unknown.is_empty(),
        "rows of docs/atmosphere-file.md for keys the parser rejects: {unknown:#?}"
    );
    assert_eq!(rows.len(), documented.len(), "a key has two rows");
}

#[test]
fn every_key_row_gives_unit_range_default_and_meaning() {
    for row in key_rows() {
        assert_eq!(
            row.cells.len(),
            5,
            "line {}: {} needs 5 cells (key, unit, allowed, default, meaning)",
            row.line,
            row.key
        );
        let tables_leave_allowed_empty = row.cells[1] == "table";
        for (i, cell) in row.cells.iter().enumerate() {
            if i == 2 && tables_leave_allowed_empty {
                continue;
            }
            assert!(
                !cell.is_empty(),
                "line {}: {} has an empty cell {i}",
                row.line,
                row.key
            );
        }
    }
}

/// The ```lang blocks of the page, with the line each starts on.
fn code_blocks(lang: &str) -> Vec<(usize, String)> {
    let mut blocks = Vec::new();
    let mut current: Option<(usize, String, bool)> = None;
    for (i, line) in PAGE.lines().enumerate() {
        let fence = line.trim_start();
        match &mut current {
            None => {
                if let Some(info) = fence.strip_prefix("```") {
                    current = Some((i + 1, String::new(), info.trim() == lang));
                }
            }
            Some((start, text, wanted)) => {
                if fence.starts_with("```") {
                    if *wanted {
                        blocks.push((*start, std::mem::take(text)));
                    }
                    current = None;
                } else {
                    text.push_str(line);
                    text.push('\n');
                }
            }
        }
    }
    assert!(current.is_none(), "an unclosed code block");
    blocks
}

/// A TOML example as a whole file: a fragment (`[sun]`, `[[species]]`, ...)
/// gets a name, and the planet and sun it lacks.
fn complete(example: &str) -> String {
    let has = |header: &str| example.lines().any(|l| l.trim_start().starts_with(header));
    let mut text = String::new();
    if !example
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .is_some_and(|l| l.starts_with("name"))
    {
        text.push_str("name = \"documentation example\"\n");
    }
    text.push_str(example);
    if !has("[planet]") {
        text.push_str("\n[planet]\nradius_m = 6360e3\natmosphere_height_m = 100e3\n");
    }
    if !has("[sun]") {
        text.push_str("\n[sun]\nspectrum = \"flat\"\nirradiance_w_m2_nm = 1.0\n");
    }
    text
}

#[test]
fn every_toml_example_loads_and_covers_every_wavelength() {
    let examples = code_blocks("toml");
    assert!(examples.len() >= 10, "{} examples", examples.len());
    // A CSV sun names a file: the page's CSV example is that file.
    let csv = code_blocks("csv");
    assert_eq!(csv.len(), 1, "one CSV example, the solar spectrum");
    let csv = csv[0].1.clone();
    // The two ends of every grid: tables must cover both.
    let grid = WavelengthGrid::new(360.0, 830.0, 470.0).unwrap();
    for (line, example) in examples {
        let text = complete(&example);
        let mut read_file = |_: &str| Ok(csv.clone());
        let atmosphere = Atmosphere::from_toml_str_with_files(&text, &mut read_file)
            .unwrap_or_else(|e| panic!("the example at line {line} does not load: {e}\n{text}"));
        atmosphere
            .compute_optics(&grid)
            .unwrap_or_else(|e| panic!("the example at line {line}: {e}"));
    }
}

#[test]
fn the_readme_links_the_page() {
    assert!(README.contains("docs/atmosphere-file.md"));
}

#[test]
fn the_pages_error_examples_are_the_parsers() {
    // The page's complete file, broken twice.
    let (_, example) = &code_blocks("toml")[0];
    for (from, to) in [
        ("atmosphere_height_m", "atmosphere_heigth_m"),
        ("scale_height_m = 1200", "scale_height_m = -1200"),
    ] {
        assert_eq!(example.matches(from).count(), 1, "{from}");
        let e = Atmosphere::from_toml_str(&example.replacen(from, to, 1))
            .expect_err(to)
            .to_string();
        assert!(
            PAGE.contains(&format!("  {e}\n")),
            "docs/atmosphere-file.md should show the error: {e}"
        );
    }
}
