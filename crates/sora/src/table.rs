//! Numeric CSV tables as text: the format of every data table sora reads or
//! embeds (colour-matching functions, solar spectra, user spectra).
//!
//! Format: lines starting with `#` are comments (provenance); the first other
//! line is a header of column names; every following non-empty line has one
//! number per column, comma-separated. Parsing works on `&str`: reading the
//! file is the caller's business, so the library stays free of file I/O.

use crate::error::{Error, Result};

/// A parsed table: column names and rows of numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct NumericTable {
    pub column_names: Vec<String>,
    pub rows: Vec<Vec<f64>>,
    /// The 1-based line of each row in the text, for errors found later.
    pub line_numbers: Vec<usize>,
}

impl NumericTable {
    /// Parses `text`. `what` names the table in errors ("solar spectrum CSV");
    /// every error gives the 1-based line. Non-finite numbers are rejected.
    pub(crate) fn parse(text: &str, what: &str) -> Result<NumericTable> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, line)| (i + 1, line.trim()))
            .filter(|(_, line)| !line.is_empty() && !line.starts_with('#'));
        let Some((_, header)) = lines.next() else {
            return Err(Error::parse(what, 0, "the table is empty (no header line)"));
        };
        let column_names: Vec<String> = header.split(',').map(|s| s.trim().to_string()).collect();
        let mut rows = Vec::new();
        let mut line_numbers = Vec::new();
        for (line_number, line) in lines {
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
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
            rows,
            line_numbers,
        })
    }

    /// Column `index` as a vector.
    pub(crate) fn column(&self, index: usize) -> Vec<f64> {
        self.rows.iter().map(|row| row[index]).collect()
    }
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
        assert!(NumericTable::parse("# only a comment\n", "t").is_err());
        assert!(NumericTable::parse("a,b\n", "t").is_err());
    }
}
