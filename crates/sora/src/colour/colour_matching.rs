//! The CIE colour-matching functions x̄(λ), ȳ(λ), z̄(λ): how strongly each
//! wavelength stimulates the three tristimulus values X, Y, Z of a standard
//! observer (CIE 015:2018, *Colorimetry*, 4th edition).
//!
//! Two observers are embedded, both tabulated every 1 nm from 360 to 830 nm:
//! - CIE 1931 2-degree ([`Observer::Cie1931TwoDegree`], the default and the
//!   paper's, via JIS Z 8701): colour seen by the fovea, for fields up to
//!   about 4 degrees. `data/cie1931_2deg_cmf_1nm.csv`.
//! - CIE 1964 10-degree ([`Observer::Cie1964TenDegree`]): for large fields,
//!   which a sky filling the view is. `data/cie1964_10deg_cmf_1nm.csv`.
//!
//! Both tables are the CIE's, as shipped by the colour-science package (see
//! each file's `# source:` line). They are dimensionless, ȳ peaks at 1
//! (at 555 nm for 2 degrees, 557 nm for 10 degrees), and each function's 1 nm
//! sum is close to the others' (106.9 for 2 degrees, 116.7 for 10 degrees), so
//! an equal-energy spectrum is near x = y = 1/3.
//!
//! Between the 1 nm rows the functions are interpolated linearly (at most
//! 9e-4 from the smooth curve through the rows, estimated from their second
//! differences; grids on whole nanometres, such as the paper's, hit the rows
//! exactly). Outside 360-830 nm they are not defined; asking there is an
//! error, not a zero. A wavelength grid may reach beyond them (sora's grids
//! span 280-2500 nm): colour is then integrated over the part of the grid
//! inside 360-830 nm, the range over which the CIE defines colorimetric
//! integrals (see `xyz.rs`).

use std::fmt;
use std::str::FromStr;

use crate::error::{Error, Result};
use crate::table::NumericTable;

/// Shortest wavelength of the colour-matching tables, nm.
pub const CIE_MIN_WAVELENGTH_NM: f64 = 360.0;
/// Longest wavelength of the colour-matching tables, nm.
pub const CIE_MAX_WAVELENGTH_NM: f64 = 830.0;

/// How far outside 360-830 nm a wavelength may be and still count as inside
/// (a grid's wavelengths are `start + i * step`, with rounding errors), nm.
const RANGE_TOLERANCE_NM: f64 = 1e-9;

const CIE1931_TWO_DEGREE_CSV: &str = include_str!("../data/cie1931_2deg_cmf_1nm.csv");
const CIE1964_TEN_DEGREE_CSV: &str = include_str!("../data/cie1964_10deg_cmf_1nm.csv");

/// Number of 1 nm rows from 360 to 830 nm inclusive.
const ROW_COUNT: usize = 471;

/// A CIE standard colorimetric observer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Observer {
    /// CIE 1931 2-degree standard observer (the paper's; the default).
    #[default]
    Cie1931TwoDegree,
    /// CIE 1964 10-degree supplementary standard observer.
    Cie1964TenDegree,
}

impl Observer {
    /// Every observer, in the order of [`Observer::NAMES`].
    pub const ALL: [Observer; 2] = [Observer::Cie1931TwoDegree, Observer::Cie1964TenDegree];

    /// The names accepted by [`FromStr`] (and written by [`fmt::Display`]).
    pub const NAMES: [&'static str; 2] = ["cie1931-2deg", "cie1964-10deg"];

    /// The observer's name as the command line and atmosphere files spell it.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Observer::Cie1931TwoDegree => Observer::NAMES[0],
            Observer::Cie1964TenDegree => Observer::NAMES[1],
        }
    }

    /// The embedded CSV table of this observer (`# source:` line first).
    fn table_text(self) -> &'static str {
        match self {
            Observer::Cie1931TwoDegree => CIE1931_TWO_DEGREE_CSV,
            Observer::Cie1964TenDegree => CIE1964_TEN_DEGREE_CSV,
        }
    }
}

impl fmt::Display for Observer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Observer {
    type Err = Error;

    /// Parses `cie1931-2deg` or `cie1964-10deg`; the error lists both.
    fn from_str(text: &str) -> Result<Observer> {
        let text = text.trim();
        Observer::ALL
            .into_iter()
            .find(|observer| observer.name() == text)
            .ok_or_else(|| {
                Error::parse(
                    "observer",
                    0,
                    format!(
                        "unknown observer '{text}'; valid names: {}",
                        Observer::NAMES.join(", ")
                    ),
                )
            })
    }
}

/// The colour-matching functions of one observer, parsed from the embedded
/// table once, on construction, and kept here (no global state).
///
/// Values are dimensionless `[x̄, ȳ, z̄]`, wavelengths in nm.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourMatchingFunctions {
    observer: Observer,
    /// Row `i` is the value at `CIE_MIN_WAVELENGTH_NM + i` nm.
    rows: Vec<[f64; 3]>,
}

impl ColourMatchingFunctions {
    /// The functions of `observer`, parsed from the embedded table.
    pub(crate) fn new(observer: Observer) -> ColourMatchingFunctions {
        let rows = parse_one_nanometre_table(observer.table_text(), observer.name())
            .expect("the embedded colour-matching tables are valid (tested below)");
        ColourMatchingFunctions { observer, rows }
    }

    /// The observer these functions belong to.
    pub(crate) fn observer(&self) -> Observer {
        self.observer
    }

    /// `[x̄, ȳ, z̄]` at `wavelength_nm` (dimensionless), interpolated linearly
    /// between the 1 nm rows. Fails outside 360-830 nm (or for NaN).
    #[cfg(test)]
    pub(crate) fn value_at_nm(&self, wavelength_nm: f64) -> Result<[f64; 3]> {
        if !(CIE_MIN_WAVELENGTH_NM..=CIE_MAX_WAVELENGTH_NM).contains(&wavelength_nm) {
            return Err(Error::out_of_range(
                "wavelength_nm",
                wavelength_nm,
                "nm",
                format!("{CIE_MIN_WAVELENGTH_NM}..={CIE_MAX_WAVELENGTH_NM}"),
            ));
        }
        Ok(self.value_at_nm_clamped(wavelength_nm))
    }

    /// Whether `wavelength_nm` lies in 360-830 nm, to a rounding error.
    pub(crate) fn covers_nm(wavelength_nm: f64) -> bool {
        (CIE_MIN_WAVELENGTH_NM - RANGE_TOLERANCE_NM..=CIE_MAX_WAVELENGTH_NM + RANGE_TOLERANCE_NM)
            .contains(&wavelength_nm)
    }

    /// Like [`ColourMatchingFunctions::value_at_nm`], for wavelengths already
    /// known to be in range ([`ColourMatchingFunctions::covers_nm`]): a
    /// wavelength a rounding error outside 360-830 nm gets the end row.
    pub(crate) fn value_at_nm_clamped(&self, wavelength_nm: f64) -> [f64; 3] {
        let offset_nm = (wavelength_nm - CIE_MIN_WAVELENGTH_NM).clamp(0.0, (ROW_COUNT - 1) as f64);
        // The row at or below the wavelength, kept one short of the last row
        // so that 830 nm interpolates inside the last interval (t = 1).
        let lower = (offset_nm.floor() as usize).min(ROW_COUNT - 2);
        let t = offset_nm - lower as f64;
        let (a, b) = (self.rows[lower], self.rows[lower + 1]);
        [
            a[0] + t * (b[0] - a[0]),
            a[1] + t * (b[1] - a[1]),
            a[2] + t * (b[2] - a[2]),
        ]
    }
}

/// Parses a table `lambda_nm, x, y, z` that must have one row per nm from 360
/// to 830 nm, with non-negative values.
fn parse_one_nanometre_table(text: &str, what: &str) -> Result<Vec<[f64; 3]>> {
    let what = format!("colour-matching functions {what}");
    let table = NumericTable::parse(text, &what)?;
    if table.column_names.len() != 4 || table.rows.len() != ROW_COUNT {
        return Err(Error::parse(
            &what,
            0,
            format!(
                "expected 4 columns and {ROW_COUNT} rows (360-830 nm every 1 nm), found {} and {}",
                table.column_names.len(),
                table.rows.len()
            ),
        ));
    }
    table
        .rows
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let expected_nm = CIE_MIN_WAVELENGTH_NM + i as f64;
            if row[0] != expected_nm {
                return Err(Error::parse(
                    &what,
                    0,
                    format!("row {i} is at {} nm, expected {expected_nm} nm", row[0]),
                ));
            }
            if row[1..].iter().any(|v| *v < 0.0) {
                return Err(Error::parse(
                    &what,
                    0,
                    format!("negative value at {expected_nm} nm"),
                ));
            }
            Ok([row[1], row[2], row[3]])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sums of the 1 nm rows, 360-830 nm: the equal-energy tristimulus
    /// values per nm of bandwidth.
    fn one_nanometre_sums(cmfs: &ColourMatchingFunctions) -> [f64; 3] {
        let mut sums = [0.0; 3];
        for row in &cmfs.rows {
            for (sum, value) in sums.iter_mut().zip(row) {
                *sum += value;
            }
        }
        sums
    }

    #[test]
    fn embedded_tables_parse_with_one_row_per_nanometre() {
        for observer in Observer::ALL {
            let cmfs = ColourMatchingFunctions::new(observer);
            assert_eq!(cmfs.rows.len(), ROW_COUNT);
            assert_eq!(cmfs.observer(), observer);
        }
    }

    #[test]
    fn tables_carry_a_provenance_line() {
        for observer in Observer::ALL {
            let first_line = observer.table_text().lines().next().unwrap();
            assert!(first_line.starts_with("# source: "), "{first_line}");
            assert!(first_line.contains("colour-science"), "{first_line}");
        }
    }

    #[test]
    fn two_degree_table_has_the_cie_values_and_sums() {
        let cmfs = ColourMatchingFunctions::new(Observer::Cie1931TwoDegree);
        // The CIE 1931 table at 555 nm and 600 nm.
        assert_eq!(
            cmfs.value_at_nm(555.0).unwrap(),
            [0.5120501, 1.0, 0.005749999]
        );
        assert_eq!(cmfs.value_at_nm(600.0).unwrap(), [1.0622, 0.631, 0.0008]);
        let sums = one_nanometre_sums(&cmfs);
        for (sum, expected) in sums.iter().zip([106.8655, 106.8569, 106.8923]) {
            assert!((sum - expected).abs() < 1e-3, "{sums:?}");
        }
    }

    #[test]
    fn ten_degree_table_has_the_cie_values_and_sums() {
        let cmfs = ColourMatchingFunctions::new(Observer::Cie1964TenDegree);
        // The CIE 1964 table: ȳ10 peaks at 1 at 557 nm; both ends.
        assert_eq!(cmfs.value_at_nm(557.0).unwrap(), [0.651901, 1.0, 0.000407]);
        assert_eq!(
            cmfs.value_at_nm(360.0).unwrap(),
            [1.222e-7, 1.3398e-8, 5.35027e-7]
        );
        assert_eq!(
            cmfs.value_at_nm(830.0).unwrap(),
            [1.55314e-6, 6.297e-7, 0.0]
        );
        // The 1 nm sums are each 116.6 ± 0.2 (equal-energy white near x = y = 1/3).
        let sums = one_nanometre_sums(&cmfs);
        for (sum, expected) in sums.iter().zip([116.6485, 116.6619, 116.6740]) {
            assert!((sum - expected).abs() < 1e-3, "{sums:?}");
        }
    }

    #[test]
    fn values_between_rows_are_linearly_interpolated() {
        let cmfs = ColourMatchingFunctions::new(Observer::Cie1931TwoDegree);
        let below = cmfs.value_at_nm(600.0).unwrap();
        let above = cmfs.value_at_nm(601.0).unwrap();
        let quarter = cmfs.value_at_nm(600.25).unwrap();
        for k in 0..3 {
            let expected = below[k] + 0.25 * (above[k] - below[k]);
            assert!((quarter[k] - expected).abs() < 1e-15, "{quarter:?}");
        }
        // The ends of the table are reachable exactly.
        assert_eq!(
            cmfs.value_at_nm(360.0).unwrap(),
            [0.0001299, 3.917e-6, 0.0006061]
        );
        assert_eq!(
            cmfs.value_at_nm(830.0).unwrap(),
            [1.251141e-6, 4.5181e-7, 0.0]
        );
    }

    #[test]
    fn wavelengths_outside_the_table_are_errors() {
        let cmfs = ColourMatchingFunctions::new(Observer::Cie1931TwoDegree);
        for nm in [359.9, 830.1, f64::NAN, f64::INFINITY] {
            let message = cmfs.value_at_nm(nm).unwrap_err().to_string();
            assert!(message.contains("wavelength_nm"), "{message}");
        }
    }

    #[test]
    fn observer_names_round_trip_and_errors_list_them() {
        for observer in Observer::ALL {
            assert_eq!(observer.to_string().parse::<Observer>().unwrap(), observer);
        }
        assert_eq!(Observer::default(), Observer::Cie1931TwoDegree);
        let message = "cie2015".parse::<Observer>().unwrap_err().to_string();
        assert!(
            message.contains("cie1931-2deg") && message.contains("cie1964-10deg"),
            "{message}"
        );
    }

    #[test]
    fn malformed_tables_are_rejected() {
        let short = "lambda_nm,x,y,z\n360,0,0,0\n361,0,0,0\n";
        assert!(parse_one_nanometre_table(short, "t").is_err());
        let mut skipped = String::from("lambda_nm,x,y,z\n");
        for nm in 360..=831 {
            if nm != 500 {
                skipped.push_str(&format!("{nm},0,0,0\n"));
            }
        }
        let message = parse_one_nanometre_table(&skipped, "t")
            .unwrap_err()
            .to_string();
        assert!(message.contains("expected 500 nm"), "{message}");
    }
}
