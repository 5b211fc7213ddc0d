//! CSV out: the one quoting rule of every text cell the commands write
//! (RFC 4180: a cell holding a comma, a quote or a line break is quoted,
//! its quotes doubled). Numbers are written by each command in its own
//! documented precision; CSV in is `sora::table`.

/// `text` as one CSV cell: as it is, or quoted when it holds a comma, a
/// quote or a line break.
pub fn cell(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        quoted(text)
    } else {
        text.to_string()
    }
}

/// `text` as one CSV cell, always quoted (so that a reader sees one cell
/// even when it is empty).
pub fn quoted(text: &str) -> String {
    format!("\"{}\"", text.replace('"', "\"\""))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_quoted_when_needed() {
        assert_eq!(cell("a b"), "a b");
        assert_eq!(cell("dust"), "dust");
        assert_eq!(cell("water, soluble"), "\"water, soluble\"");
        assert_eq!(cell("say \"x\""), "\"say \"\"x\"\"\"");
        assert_eq!(cell("two\nlines"), "\"two\nlines\"");
        assert_eq!(quoted(""), "\"\"");
        assert_eq!(quoted("a \"b\"; c"), "\"a \"\"b\"\"; c\"");
    }
}
