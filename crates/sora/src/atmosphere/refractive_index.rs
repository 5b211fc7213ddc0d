//! Refractive-index tables as CSV text, read through the one reader of
//! numeric tables ([`crate::table::NumericTable`]) into the Mie crate's
//! [`TabulatedRefractiveIndex`] (interpolation and range checks are its).
//!
//! The header names a wavelength column `wavelength_nm` or `wavelength_um`
//! (the unit is taken from the name; micrometres are multiplied by 1000)
//! and the columns `n` and `k`, in any order; other columns are allowed and
//! ignored, but, as in every numeric table, every cell is a number. Rows
//! must be sorted by increasing wavelength, `n > 0`, `k >= 0`. Errors name
//! the table, the 1-based line, the column and its unit. The built-in
//! Mars dust table of Wolff et al. (2009) is the one table read this way
//! ([`super::file`]'s `refractive_index.builtin`).

use crate::error::{Error, Result};
use crate::mie::refractive_index::TabulatedRefractiveIndex;
use crate::table::NumericTable;

/// Parses a refractive-index table from CSV `text` (the dialect of
/// [`NumericTable::parse`], columns as the [module](self) describes);
/// `what` names the table in errors.
pub(crate) fn parse_refractive_index_csv(
    text: &str,
    what: &str,
) -> Result<TabulatedRefractiveIndex> {
    let table = NumericTable::parse(text, what)?;
    let header = table.column_names.join(",");
    let find = |name: &str| table.column_names.iter().position(|c| c == name);
    let (wavelength_column, wavelength_unit, nm_per_unit) = if let Some(c) = find("wavelength_nm") {
        (c, "nm", 1.0)
    } else if let Some(c) = find("wavelength_um") {
        (c, "um", 1000.0)
    } else {
        return Err(Error::parse(
            what,
            table.header_line,
            format!("header `{header}` has no column `wavelength_nm` or `wavelength_um`"),
        ));
    };
    let required = |name: &str| {
        find(name).ok_or_else(|| {
            Error::parse(
                what,
                table.header_line,
                format!("header `{header}` has no column `{name}`"),
            )
        })
    };
    let real_column = required("n")?;
    let imaginary_column = required("k")?;

    let mut wavelength_nm = Vec::with_capacity(table.rows.len());
    for (row, &line) in table.rows.iter().zip(&table.line_numbers) {
        let (wavelength, n, k) = (
            row[wavelength_column],
            row[real_column],
            row[imaginary_column],
        );
        let name = &table.column_names[wavelength_column];
        if wavelength <= 0.0 {
            return Err(Error::parse(
                what,
                line,
                format!("{name} = {wavelength} {wavelength_unit} must be > 0"),
            ));
        }
        let previous = wavelength_nm.last().copied().unwrap_or(0.0);
        if wavelength * nm_per_unit <= previous {
            return Err(Error::parse(
                what,
                line,
                format!(
                    "{name} = {wavelength} {wavelength_unit} does not increase on the row before ({} {wavelength_unit}): rows must be sorted by increasing wavelength",
                    previous / nm_per_unit
                ),
            ));
        }
        if n <= 0.0 {
            return Err(Error::parse(
                what,
                line,
                format!("n = {n} (real part, unitless) must be > 0"),
            ));
        }
        if k < 0.0 {
            return Err(Error::parse(
                what,
                line,
                format!("k = {k} (imaginary part, absorption, unitless) must be >= 0"),
            ));
        }
        wavelength_nm.push(wavelength * nm_per_unit);
    }
    TabulatedRefractiveIndex::from_columns(
        wavelength_nm,
        table.column(real_column),
        table.column(imaginary_column),
    )
    .map_err(|e| Error::parse(what, 0, e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mie::Complex64;
    use crate::mie::refractive_index::MARS_DUST_WOLFF2009_CSV;

    const SMALL_TABLE: &str = "# a comment\n\
        # another: interpolate k in log space\n\
        wavelength_um,n,k\n\
        0.400,1.50,0.0100\n\
        \n\
        0.500,1.52,0.0010\n\
        0.600,1.51,0.0000\n";

    #[test]
    fn parses_comments_header_and_units() {
        let table = parse_refractive_index_csv(SMALL_TABLE, "t").unwrap();
        assert_eq!(table.wavelengths_nm(), &[400.0, 500.0, 600.0]);
        assert_eq!(table.wavelength_range_nm(), (400.0, 600.0));
        let m = table.refractive_index_at(500.0).unwrap();
        assert_eq!(m, Complex64::new(1.52, 0.001));
    }

    #[test]
    fn columns_may_come_in_any_order_with_nanometres() {
        let text = "k,extra,n,wavelength_nm\n0.1,7,1.4,300\n0.2,8,1.6,700\n";
        let table = parse_refractive_index_csv(text, "t").unwrap();
        assert_eq!(
            table.refractive_index_at(300.0).unwrap(),
            Complex64::new(1.4, 0.1)
        );
        assert_eq!(
            table.refractive_index_at(700.0).unwrap(),
            Complex64::new(1.6, 0.2)
        );
    }

    #[test]
    fn malformed_tables_are_rejected_with_line_column_and_unit() {
        let message = |text: &str| {
            parse_refractive_index_csv(text, "dust.csv")
                .unwrap_err()
                .to_string()
        };
        let m = message("# c\nwavelength_um,n,k\n0.4,1.5,abc\n");
        assert!(
            m.starts_with("dust.csv, line 3:") && m.contains("k = 'abc'"),
            "{m}"
        );
        let m = message("lambda,n,k\n0.4,1.5,0.1\n");
        assert!(
            m.starts_with("dust.csv, line 1:") && m.contains("wavelength_um"),
            "{m}"
        );
        let m = message("wavelength_nm,n\n400,1.5\n");
        assert!(
            m.starts_with("dust.csv, line 1:") && m.contains("`k`"),
            "{m}"
        );
        let m = message("wavelength_nm,n,k\n500,1.5,0.1\n400,1.5,0.1\n");
        assert!(
            m.starts_with("dust.csv, line 3:") && m.contains("wavelength_nm = 400 nm"),
            "{m}"
        );
        let m = message("# x\nwavelength_um,n,k\n0.4,1.5,0.1\n-0.5,1.5,0.1\n");
        assert!(
            m.starts_with("dust.csv, line 4:") && m.contains("wavelength_um = -0.5 um"),
            "{m}"
        );
        let m = message("wavelength_nm,n,k\n400,1.5,-0.1\n500,1.5,0.1\n");
        assert!(
            m.starts_with("dust.csv, line 2:") && m.contains("k = -0.1"),
            "{m}"
        );
        let m = message("wavelength_nm,n,k\n400,1.5,0.1\n500,0,0.1\n");
        assert!(
            m.starts_with("dust.csv, line 3:") && m.contains("n = 0"),
            "{m}"
        );
        let m = message("wavelength_nm,n,k\n400,1.5,0.1\n");
        assert!(
            m.starts_with("dust.csv: ") && m.contains("at least 2"),
            "{m}"
        );
        assert!(parse_refractive_index_csv("# only comments\n", "t").is_err());
    }

    /// The built-in Mars dust table of Wolff et al. (2009): the rows this
    /// project relies on (380-780 nm) come out as the published values at
    /// the nodes and geometric means in between.
    #[test]
    fn mars_dust_table_covers_the_visible() {
        let table = parse_refractive_index_csv(MARS_DUST_WOLFF2009_CSV, "t").unwrap();
        assert_eq!(table.wavelength_range_nm(), (263.0, 2480.0));
        assert_eq!(
            table.refractive_index_at(500.0).unwrap(),
            Complex64::new(1.5, 0.00548876)
        );
        assert_eq!(
            table.refractive_index_at(440.0).unwrap(),
            Complex64::new(1.49915, 0.00767169)
        );
        let m_380 = table.refractive_index_at(380.0).unwrap();
        // Between the 321 nm (k 0.0127) and 440 nm (k 0.00767169) rows.
        let t = (380.0 - 321.0) / (440.0 - 321.0);
        let expected_k = 0.0127f64.powf(1.0 - t) * 0.00767169f64.powf(t);
        assert!((m_380.im / expected_k - 1.0).abs() < 1e-13);
        assert!((m_380.re - (1.49413 + t * (1.49915 - 1.49413))).abs() < 1e-14);
        for lambda in (380..=780).step_by(20) {
            let m = table.refractive_index_at(lambda as f64).unwrap();
            assert!(
                m.re > 1.49 && m.re < 1.51 && m.im > 8e-4 && m.im < 0.011,
                "{lambda}: {m}"
            );
        }
        assert!(table.refractive_index_at(250.0).is_err());
    }
}
