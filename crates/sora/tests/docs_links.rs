//! The repository's Markdown (README.md, docs/, the test data's READMEs)
//! as a reader of the repository meets it: every relative link and image
//! names a file that exists (and a heading of it, for `#anchor` links), and
//! nothing points outside the repository (`../shared`, issue numbers of a
//! tracker the reader cannot see).

use std::path::{Path, PathBuf};

/// The repository's root (this crate is crates/sora).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every Markdown file this test reads, relative to the root.
fn markdown_files() -> Vec<PathBuf> {
    let mut files = vec![PathBuf::from("README.md")];
    for folder in [
        "docs",
        "crates/sora/tests/data/aeronet",
        "crates/sora/tests/data/retrieval",
        "crates/sora-cli/tests/data/measured",
    ] {
        let mut found: Vec<PathBuf> = std::fs::read_dir(root().join(folder))
            .unwrap()
            .map(|entry| entry.unwrap().path())
            .filter(|path| path.extension().is_some_and(|e| e == "md"))
            .map(|path| Path::new(folder).join(path.file_name().unwrap()))
            .collect();
        found.sort();
        files.extend(found);
    }
    files
}

/// The targets of the inline links and images `[text](target)` of
/// `markdown`, outside code blocks and code spans, with their line numbers.
fn link_targets(markdown: &str) -> Vec<(usize, String)> {
    let mut targets = Vec::new();
    let mut in_code_block = false;
    for (number, line) in markdown.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            in_code_block = !in_code_block;
            continue;
        }
        if in_code_block {
            continue;
        }
        // Code spans hold examples, not links.
        let prose: String = line
            .split('`')
            .enumerate()
            .filter(|(i, _)| i % 2 == 0)
            .map(|(_, part)| part)
            .collect::<Vec<_>>()
            .join(" ");
        let mut rest = prose.as_str();
        while let Some(start) = rest.find("](") {
            let after = &rest[start + 2..];
            let Some(end) = after.find(')') else { break };
            let target = after[..end].split_whitespace().next().unwrap_or("");
            targets.push((number + 1, target.to_string()));
            rest = &after[end..];
        }
    }
    targets
}

/// GitHub's anchor of a heading: lower case, spaces to '-', and only
/// letters, digits, '-' and '_' kept.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of every heading of `markdown` (outside code blocks).
fn anchors(markdown: &str) -> Vec<String> {
    let mut in_code_block = false;
    let mut found = Vec::new();
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            in_code_block = !in_code_block;
        } else if !in_code_block && line.starts_with('#') {
            found.push(anchor(line.trim_start_matches('#')));
        }
    }
    found
}

#[test]
fn every_relative_link_in_the_docs_names_a_file_and_heading_that_exist() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for file in markdown_files() {
        let text = std::fs::read_to_string(root().join(&file)).unwrap();
        let folder = file.parent().unwrap();
        for (line, target) in link_targets(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            checked += 1;
            let (path, fragment) = match target.split_once('#') {
                Some((path, fragment)) => (path, Some(fragment)),
                None => (target.as_str(), None),
            };
            let linked = if path.is_empty() {
                file.clone()
            } else {
                folder.join(path)
            };
            let full = root().join(&linked);
            if !full.exists() {
                broken.push(format!(
                    "{}:{line}: {target} (no such file)",
                    file.display()
                ));
                continue;
            }
            if let Some(fragment) = fragment
                && full.extension().is_some_and(|e| e == "md")
            {
                let headings = anchors(&std::fs::read_to_string(&full).unwrap());
                if !headings.iter().any(|h| h == fragment) {
                    broken.push(format!(
                        "{}:{line}: {target} (no such heading)",
                        file.display()
                    ));
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
    // The README alone links a dozen files.
    assert!(checked > 20, "only {checked} links found");
}

#[test]
fn the_docs_point_nowhere_outside_the_repository() {
    let mut found = Vec::new();
    for file in markdown_files() {
        let text = std::fs::read_to_string(root().join(&file)).unwrap();
        for (number, line) in text.lines().enumerate() {
            let lower = line.to_lowercase();
            let issue_number = lower.match_indices("issue ").any(|(i, _)| {
                lower[i + 6..]
                    .chars()
                    .next()
                    .is_some_and(|c| c.is_ascii_digit())
            });
            if line.contains("../shared") || issue_number {
                found.push(format!("{}:{}: {line}", file.display(), number + 1));
            }
        }
    }
    assert!(
        found.is_empty(),
        "references a reader of the repository cannot follow:\n{}",
        found.join("\n")
    );
}

#[test]
fn links_and_anchors_are_read_as_github_does() {
    let text = "See [a](docs/a.md#the-sky) and ![b](b.png \"title\"), not `[c](c.md)`.\n```\n[d](d.md)\n```\n";
    assert_eq!(
        link_targets(text),
        vec![
            (1, "docs/a.md#the-sky".to_string()),
            (1, "b.png".to_string())
        ]
    );
    assert_eq!(anchor(" The `[sun]` table, 2 "), "the-sun-table-2");
}
