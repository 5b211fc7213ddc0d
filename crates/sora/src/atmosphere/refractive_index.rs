//! Refractive-index tables as CSV text, read through the one reader of
//! numeric tables ([`crate::table::NumericTable`]) into the Mie crate's
//! [`TabulatedRefractiveIndex`] (interpolation and range checks are its).
//!
//! The header names a wavelength column `wavelength_nm` or `wavelength_um`
//! (the unit is taken from the name; micrometres are multiplied by 1000)
//! and the columns `n` and `k`, in any order; other columns are allowed and
//! ignored, but, as in every numeric table, every cell is a number. Rows
//! must be sorted by increasing wavelength, `n > 0`, `k >= 0` (checked by
//! [`TabulatedRefractiveIndex::from_columns`], naming the values); a cell
//! or header that does not read is named by its 1-based line. The built-in
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
    let (wavelength_column, nm_per_unit) = if let Some(c) = find("wavelength_nm") {
        (c, 1.0)
    } else if let Some(c) = find("wavelength_um") {
        (c, 1000.0)
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

    // The values' checks (positive, increasing wavelengths; n > 0, k >= 0)
    // are the Mie crate's, for tables from any source.
    let wavelength_nm = table
        .column(wavelength_column)
        .into_iter()
        .map(|w| w * nm_per_unit)
        .collect();
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
            m.starts_with("dust.csv: ") && m.contains("500 nm is followed by 400 nm"),
            "{m}"
        );
        let m = message("# x\nwavelength_um,n,k\n0.4,1.5,0.1\n-0.5,1.5,0.1\n");
        assert!(m.starts_with("dust.csv: ") && m.contains("-500"), "{m}");
        let m = message("wavelength_nm,n,k\n400,1.5,-0.1\n500,1.5,0.1\n");
        assert!(m.starts_with("dust.csv: ") && m.contains("-0.1"), "{m}");
        let m = message("wavelength_nm,n,k\n400,1.5,0.1\n500,0,0.1\n");
        assert!(m.starts_with("dust.csv: ") && m.contains('0'), "{m}");
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
