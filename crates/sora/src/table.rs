//! Numeric CSV tables as text: the one reader of every data table sora
//! reads or embeds (colour-matching functions, solar spectra, user spectra,
//! filters, retrieval inputs) and of the command-line tool's numeric CSV
//! inputs (`sora spectrum --directions`).
//!
//! The dialect [`NumericTable::parse`] accepts:
//! - UTF-8 text, an optional byte-order mark before it (as spreadsheets
//!   write); lines end in `\n` or `\r\n`, and spaces around a line or a
//!   field are ignored;
//! - blank lines, and lines whose first non-space character is `#`
//!   (comments: provenance, units), anywhere;
//! - the first other line is the header: column names separated by commas;
//! - every following line is one row: one number per column, separated by
//!   commas (no other separator: no semicolons, no tabs), no quotes, no
//!   thousands separators; a number is what Rust's `f64` parses (`380`,
//!   `-1.5`, `2e-3`) and must be finite (`NaN`, `inf` are refused);
//! - at least one row.
//!
//! The cell rule alone ([`cells`]: split at commas, trim) is also what the
//! AERONET readers split their lines with: those files are CSV too, but
//! hold dates and `N/A` beside their numbers.
//!
//! Every error is an [`Error::Parse`] naming the table (`what`) and the
//! 1-based line. Parsing works on `&str`: reading the file is the caller's
//! business ([`crate::input::read_text`]), so this module stays free of
//! file I/O.

use crate::error::{Error, Result};

/// A parsed table: column names and rows of numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct NumericTable {
    /// The header's column names, trimmed.
    pub column_names: Vec<String>,
    /// The 1-based line of the header in the text.
    pub header_line: usize,
    /// The rows, each with one number per column.
    pub rows: Vec<Vec<f64>>,
    /// The 1-based line of each row in the text, for errors found later.
    pub line_numbers: Vec<usize>,
}

impl NumericTable {
    /// Parses `text` in the dialect the [module](self) describes. `what`
    /// names the table in errors (`"solar spectrum CSV"`, a file name);
    /// every error gives the 1-based line, e.g. `my.csv, line 3: 1 fields,
    /// expected 2 (a,b)` or `my.csv, line 2: b = 'x' is not a finite
    /// number`.
    pub fn parse(text: &str, what: &str) -> Result<NumericTable> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, line)| (i + 1, line.trim()))
            .filter(|(_, line)| !line.is_empty() && !line.starts_with('#'));
        let Some((header_line, header)) = lines.next() else {
            return Err(Error::parse(what, 0, "the table is empty (no header line)"));
        };
        let column_names: Vec<String> = cells(header).into_iter().map(str::to_string).collect();
        let mut rows = Vec::new();
        let mut line_numbers = Vec::new();
        for (line_number, line) in lines {
            let fields = cells(line);
            if fields.len() != column_names.len() {
                return Err(Error::parse(
                    what,
                    line_number,
                    format!(
                        "{} fields, expected {} ({})",
                        fields.len(),
                        column_names.len(),
                        header
                    ),
                ));
            }
            let row = fields
                .iter()
                .zip(&column_names)
                .map(|(field, name)| match field.parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(v),
                    _ => Err(Error::parse(
                        what,
                        line_number,
                        format!("{name} = '{field}' is not a finite number"),
                    )),
                })
                .collect::<Result<Vec<f64>>>()?;
            rows.push(row);
            line_numbers.push(line_number);
        }
        if rows.is_empty() {
            return Err(Error::parse(what, 0, "the table has a header but no rows"));
        }
        Ok(NumericTable {
            column_names,
            header_line,
            rows,
            line_numbers,
        })
    }

    /// Column `index` as a vector (panics if `index` is not below the
    /// number of columns).
    pub fn column(&self, index: usize) -> Vec<f64> {
        self.rows.iter().map(|row| row[index]).collect()
    }
}

/// The cells of one CSV line in sora's dialect: split at every comma
/// (no quoting: no cell of a numeric table or of the network's files
/// holds one), each trimmed. [`NumericTable::parse`] and the AERONET
/// readers share it.
pub fn cells(line: &str) -> Vec<&str> {
    line.split(',').map(str::trim).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_comments_header_and_rows() {
        let table = NumericTable::parse(
            "# source: test\nlambda_nm, value\n380,1.5\n\n400,2e-3\n",
            "t",
        )
        .unwrap();
        assert_eq!(table.column_names, ["lambda_nm", "value"]);
        assert_eq!(table.rows, vec![vec![380.0, 1.5], vec![400.0, 2e-3]]);
        assert_eq!(table.column(1), vec![1.5, 2e-3]);
        assert_eq!(table.line_numbers, [3, 5]);
        assert_eq!(table.header_line, 2);
        // A byte-order mark, CRLF line ends and indented comments.
        let table = NumericTable::parse("\u{feff}a,b\r\n  # note\r\n1, 2\r\n", "t").unwrap();
        assert_eq!(table.column_names, ["a", "b"]);
        assert_eq!(table.rows, vec![vec![1.0, 2.0]]);
        assert_eq!((table.header_line, table.line_numbers[0]), (1, 3));
    }

    #[test]
    fn errors_name_the_line() {
        let e = NumericTable::parse("a,b\n1,2\n3\n", "my table")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "my table, line 3: 1 fields, expected 2 (a,b)");
        let e = NumericTable::parse("a,b\n1,x\n", "t")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2") && e.contains("b = 'x'"), "{e}");
        let e = NumericTable::parse("a,b\n1,NaN\n", "t")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a finite number"), "{e}");
        let e = NumericTable::parse("a;b\n1;2\n", "t")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2") && e.contains("a;b = '1;2'"), "{e}");
        assert!(NumericTable::parse("# only a comment\n", "t").is_err());
        assert!(NumericTable::parse("a,b\n", "t").is_err());
    }
}
