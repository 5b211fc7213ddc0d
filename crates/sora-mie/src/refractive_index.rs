//! # Refractive index of the particle material against wavelength
//!
//! Mie theory needs the complex refractive index `m = n + i k` of the particle
//! relative to the surrounding medium (here vacuum or air, index 1), with the
//! Bohren & Huffman (1983) sign convention: `k >= 0` is absorption. Real
//! materials are dispersive, so the index is a function of the wavelength
//! `lambda` (nm, in vacuum). Two models:
//!
//! - [`RefractiveIndexModel::Constant`]: one `m` at every wavelength (the
//!   Mie reference tables use `m = 1.5 + 0.01 i` this way).
//! - [`RefractiveIndexModel::Tabulated`]: rows `(lambda_i, n_i, k_i)` sorted
//!   by wavelength, interpolated between rows:
//!   `n` linearly in `lambda`, and `k` linearly in `ln k`:
//!
//!   ```text
//!       n(lambda) = n_i + t (n_{i+1} - n_i)
//!       k(lambda) = k_i^(1 - t) k_{i+1}^t,      t = (lambda - lambda_i) / (lambda_{i+1} - lambda_i)
//!   ```
//!
//!   `k` of minerals spans decades across the visible (Mars dust: 0.0077 at
//!   440 nm, 0.0009 at 700 nm; Wolff et al. 2009), and a straight line
//!   between two rows of such a table overshoots the absorption in between;
//!   the geometric interpolation follows an exponential absorption edge
//!   exactly. Where either neighbouring row has `k = 0` the geometric mean
//!   is meaningless, and that interval falls back to linear `k`.
//!
//! The table is never extrapolated: a wavelength outside `[lambda_first,
//! lambda_last]` is an error that names it and the table's range (nm). A
//! table is parsed from text ([`TabulatedRefractiveIndex::parse_csv`]);
//! reading the file is the caller's business (no I/O here). One table is
//! built in, as text: [`MARS_DUST_WOLFF2009_CSV`].

use crate::Complex64;

/// The Mars dust refractive index of Wolff et al. (2009, JGR 114, E00D04;
/// CRISM retrieval, with two ultraviolet rows from Wolff's distributed
/// compilation), as the CSV text [`TabulatedRefractiveIndex::parse_csv`]
/// reads: wavelength (um), n, k, 263-2480 nm, its provenance in the leading
/// comment lines. Embedded once, here, for this crate's tests and benches and
/// for sora's built-in `mars-dust-wolff2009`.
pub const MARS_DUST_WOLFF2009_CSV: &str =
    include_str!("data/mars_dust_refractive_index_wolff2009.csv");

/// Why a refractive index could not be given or a table could not be built.
#[derive(Debug, Clone, PartialEq)]
pub enum RefractiveIndexError {
    /// The wavelength lies outside the table; the table is not extrapolated.
    WavelengthOutsideTable {
        wavelength_nm: f64,
        table_min_wavelength_nm: f64,
        table_max_wavelength_nm: f64,
    },
    /// The wavelength is not finite and positive.
    InvalidWavelength { wavelength_nm: f64 },
    /// A refractive index that Mie theory cannot use: `n` must be finite and
    /// > 0, `k` finite and >= 0.
    InvalidRefractiveIndex { real_part: f64, imaginary_part: f64 },
    /// The table text could not be read (line numbers count from 1).
    Parse { line_number: usize, message: String },
    /// The rows do not make a table: too few, unsorted, or columns of
    /// different lengths.
    InvalidTable { message: String },
}

impl std::fmt::Display for RefractiveIndexError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RefractiveIndexError::WavelengthOutsideTable {
                wavelength_nm,
                table_min_wavelength_nm,
                table_max_wavelength_nm,
            } => write!(
                f,
                "wavelength {wavelength_nm} nm is outside the refractive-index table, which covers {table_min_wavelength_nm} nm to {table_max_wavelength_nm} nm (no extrapolation)"
            ),
            RefractiveIndexError::InvalidWavelength { wavelength_nm } => write!(
                f,
                "wavelength {wavelength_nm} nm is invalid: it must be finite and greater than 0"
            ),
            RefractiveIndexError::InvalidRefractiveIndex {
                real_part,
                imaginary_part,
            } => write!(
                f,
                "refractive index {real_part}{imaginary_part:+}i is invalid: the real part must be finite and > 0, the imaginary part (absorption) finite and >= 0"
            ),
            RefractiveIndexError::Parse {
                line_number,
                message,
            } => write!(f, "refractive-index table, line {line_number}: {message}"),
            RefractiveIndexError::InvalidTable { message } => {
                write!(f, "invalid refractive-index table: {message}")
            }
        }
    }
}

impl std::error::Error for RefractiveIndexError {}

fn validate_refractive_index(
    real_part: f64,
    imaginary_part: f64,
) -> Result<(), RefractiveIndexError> {
    if real_part.is_finite()
        && real_part > 0.0
        && imaginary_part.is_finite()
        && imaginary_part >= 0.0
    {
        Ok(())
    } else {
        Err(RefractiveIndexError::InvalidRefractiveIndex {
            real_part,
            imaginary_part,
        })
    }
}

fn validate_wavelength(wavelength_nm: f64) -> Result<(), RefractiveIndexError> {
    if wavelength_nm.is_finite() && wavelength_nm > 0.0 {
        Ok(())
    } else {
        Err(RefractiveIndexError::InvalidWavelength { wavelength_nm })
    }
}

/// A refractive index tabulated against wavelength: `n` interpolated
/// linearly, `k` geometrically (linearly in `ln k`), never extrapolated.
#[derive(Debug, Clone, PartialEq)]
pub struct TabulatedRefractiveIndex {
    wavelength_nm: Vec<f64>,
    real_part: Vec<f64>,
    imaginary_part: Vec<f64>,
}

impl TabulatedRefractiveIndex {
    /// A table from its columns: wavelengths in nm (strictly increasing, at
    /// least two), `n` (> 0) and `k` (>= 0) of equal lengths.
    pub fn from_columns(
        wavelength_nm: Vec<f64>,
        real_part: Vec<f64>,
        imaginary_part: Vec<f64>,
    ) -> Result<Self, RefractiveIndexError> {
        if wavelength_nm.len() != real_part.len() || wavelength_nm.len() != imaginary_part.len() {
            return Err(RefractiveIndexError::InvalidTable {
                message: format!(
                    "columns have different lengths: {} wavelengths, {} n, {} k",
                    wavelength_nm.len(),
                    real_part.len(),
                    imaginary_part.len()
                ),
            });
        }
        if wavelength_nm.len() < 2 {
            return Err(RefractiveIndexError::InvalidTable {
                message: format!(
                    "{} row(s): at least 2 are needed to interpolate",
                    wavelength_nm.len()
                ),
            });
        }
        for &lambda in &wavelength_nm {
            validate_wavelength(lambda)?;
        }
        for pair in wavelength_nm.windows(2) {
            if pair[1] <= pair[0] {
                return Err(RefractiveIndexError::InvalidTable {
                    message: format!(
                        "wavelengths must increase strictly: {} nm is followed by {} nm",
                        pair[0], pair[1]
                    ),
                });
            }
        }
        for (&n, &k) in real_part.iter().zip(&imaginary_part) {
            validate_refractive_index(n, k)?;
        }
        Ok(Self {
            wavelength_nm,
            real_part,
            imaginary_part,
        })
    }

    /// Parse a CSV table. Lines starting with `#` and blank lines are
    /// skipped; the first other line is the header, which must name a
    /// wavelength column `wavelength_um` or `wavelength_nm` (the unit is taken
    /// from the name) and the columns `n` and `k`, in any order (other columns
    /// are ignored). Every following line is one row.
    pub fn parse_csv(text: &str) -> Result<Self, RefractiveIndexError> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(index, line)| (index + 1, line.trim()))
            .filter(|(_, line)| !line.is_empty() && !line.starts_with('#'));
        let (header_line_number, header) = lines.next().ok_or(RefractiveIndexError::Parse {
            line_number: 0,
            message: "no header line (only comments or blank lines)".to_string(),
        })?;
        let column_names: Vec<&str> = header.split(',').map(str::trim).collect();
        let find_column = |name: &str| column_names.iter().position(|c| *c == name);
        let (wavelength_column, nm_per_unit) = if let Some(c) = find_column("wavelength_nm") {
            (c, 1.0)
        } else if let Some(c) = find_column("wavelength_um") {
            (c, 1000.0)
        } else {
            return Err(RefractiveIndexError::Parse {
                line_number: header_line_number,
                message: format!(
                    "header `{header}` has no column `wavelength_nm` or `wavelength_um`"
                ),
            });
        };
        let missing = |name: &str| RefractiveIndexError::Parse {
            line_number: header_line_number,
            message: format!("header `{header}` has no column `{name}`"),
        };
        let real_column = find_column("n").ok_or_else(|| missing("n"))?;
        let imaginary_column = find_column("k").ok_or_else(|| missing("k"))?;

        let mut wavelength_nm = Vec::new();
        let mut real_part = Vec::new();
        let mut imaginary_part = Vec::new();
        for (line_number, line) in lines {
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let field = |column: usize, name: &str| -> Result<f64, RefractiveIndexError> {
                let text = fields
                    .get(column)
                    .ok_or_else(|| RefractiveIndexError::Parse {
                        line_number,
                        message: format!("missing column `{name}` in `{line}`"),
                    })?;
                text.parse::<f64>()
                    .map_err(|error| RefractiveIndexError::Parse {
                        line_number,
                        message: format!("column `{name}`: `{text}` is not a number ({error})"),
                    })
            };
            wavelength_nm
                .push(field(wavelength_column, column_names[wavelength_column])? * nm_per_unit);
            real_part.push(field(real_column, "n")?);
            imaginary_part.push(field(imaginary_column, "k")?);
        }
        Self::from_columns(wavelength_nm, real_part, imaginary_part)
    }

    /// The wavelength range covered, `(first, last)` row, in nm.
    pub fn wavelength_range_nm(&self) -> (f64, f64) {
        (
            self.wavelength_nm[0],
            self.wavelength_nm[self.wavelength_nm.len() - 1],
        )
    }

    /// The table's wavelengths (nm), increasing.
    pub fn wavelengths_nm(&self) -> &[f64] {
        &self.wavelength_nm
    }

    /// The refractive index `n + i k` at `wavelength_nm` (nm), interpolated as
    /// the module docs describe; an error outside the table's range.
    pub fn refractive_index_at(
        &self,
        wavelength_nm: f64,
    ) -> Result<Complex64, RefractiveIndexError> {
        validate_wavelength(wavelength_nm)?;
        let (first_nm, last_nm) = self.wavelength_range_nm();
        if !(first_nm..=last_nm).contains(&wavelength_nm) {
            return Err(RefractiveIndexError::WavelengthOutsideTable {
                wavelength_nm,
                table_min_wavelength_nm: first_nm,
                table_max_wavelength_nm: last_nm,
            });
        }
        // Index of the first row at or above the wavelength; rows at a node
        // return the node's values exactly.
        let upper = self
            .wavelength_nm
            .partition_point(|&lambda| lambda < wavelength_nm);
        if self.wavelength_nm[upper] == wavelength_nm {
            return Ok(Complex64::new(
                self.real_part[upper],
                self.imaginary_part[upper],
            ));
        }
        let lower = upper - 1;
        let t = (wavelength_nm - self.wavelength_nm[lower])
            / (self.wavelength_nm[upper] - self.wavelength_nm[lower]);
        let real_part = self.real_part[lower] + t * (self.real_part[upper] - self.real_part[lower]);
        let (k_lower, k_upper) = (self.imaginary_part[lower], self.imaginary_part[upper]);
        let imaginary_part = if k_lower > 0.0 && k_upper > 0.0 {
            (k_lower.ln() + t * (k_upper.ln() - k_lower.ln())).exp()
        } else {
            k_lower + t * (k_upper - k_lower)
        };
        Ok(Complex64::new(real_part, imaginary_part))
    }
}

/// The refractive index of a particle material as a function of wavelength.
#[derive(Debug, Clone, PartialEq)]
pub enum RefractiveIndexModel {
    /// The same `m = n + i k` at every wavelength.
    Constant(Complex64),
    /// Tabulated against wavelength (see [`TabulatedRefractiveIndex`]).
    Tabulated(TabulatedRefractiveIndex),
}

impl RefractiveIndexModel {
    /// A constant index `n + i k`, validated (`n > 0`, `k >= 0`, finite).
    pub fn constant(refractive_index: Complex64) -> Result<Self, RefractiveIndexError> {
        validate_refractive_index(refractive_index.re, refractive_index.im)?;
        Ok(Self::Constant(refractive_index))
    }

    /// The refractive index `n + i k` at `wavelength_nm` (nm, vacuum).
    pub fn refractive_index_at(
        &self,
        wavelength_nm: f64,
    ) -> Result<Complex64, RefractiveIndexError> {
        match self {
            RefractiveIndexModel::Constant(m) => {
                validate_wavelength(wavelength_nm)?;
                validate_refractive_index(m.re, m.im)?;
                Ok(*m)
            }
            RefractiveIndexModel::Tabulated(table) => table.refractive_index_at(wavelength_nm),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL_TABLE: &str = "# a comment\n\
        # another: interpolate k in log space\n\
        wavelength_um,n,k\n\
        0.400,1.50,0.0100\n\
        \n\
        0.500,1.52,0.0010\n\
        0.600,1.51,0.0000\n";

    #[test]
    fn parses_comments_header_and_units() {
        let table = TabulatedRefractiveIndex::parse_csv(SMALL_TABLE).unwrap();
        assert_eq!(table.wavelengths_nm(), &[400.0, 500.0, 600.0]);
        assert_eq!(table.wavelength_range_nm(), (400.0, 600.0));
        let m = table.refractive_index_at(500.0).unwrap();
        assert_eq!(m, Complex64::new(1.52, 0.001));
    }

    #[test]
    fn columns_may_come_in_any_order_with_nanometres() {
        let text = "k,extra,n,wavelength_nm\n0.1,x,1.4,300\n0.2,y,1.6,700\n";
        let table = TabulatedRefractiveIndex::parse_csv(text).unwrap();
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
    fn n_is_linear_and_k_geometric_between_rows() {
        let table = TabulatedRefractiveIndex::parse_csv(SMALL_TABLE).unwrap();
        let m = table.refractive_index_at(450.0).unwrap();
        assert!((m.re - 1.51).abs() < 1e-14);
        // Half-way between k = 0.01 and 0.001 in log space: sqrt(1e-5).
        assert!((m.im - 1e-5f64.sqrt()).abs() < 1e-16, "{}", m.im);
        // A quarter of the way: 0.01^(3/4) 0.001^(1/4).
        let m = table.refractive_index_at(425.0).unwrap();
        let expected = 0.01f64.powf(0.75) * 0.001f64.powf(0.25);
        assert!((m.im / expected - 1.0).abs() < 1e-14);
        // k = 0 at the upper row: linear fallback.
        let m = table.refractive_index_at(550.0).unwrap();
        assert!((m.im - 0.0005).abs() < 1e-17);
    }

    #[test]
    fn outside_the_table_is_an_error_naming_wavelength_and_range() {
        let table = TabulatedRefractiveIndex::parse_csv(SMALL_TABLE).unwrap();
        let error = table.refractive_index_at(380.0).unwrap_err();
        assert_eq!(
            error,
            RefractiveIndexError::WavelengthOutsideTable {
                wavelength_nm: 380.0,
                table_min_wavelength_nm: 400.0,
                table_max_wavelength_nm: 600.0
            }
        );
        let message = error.to_string();
        assert!(
            message.contains("380 nm") && message.contains("400 nm") && message.contains("600 nm"),
            "{message}"
        );
        assert!(table.refractive_index_at(600.000_001).is_err());
        assert!(table.refractive_index_at(f64::NAN).is_err());
    }

    #[test]
    fn malformed_tables_are_rejected_with_line_numbers() {
        let error = TabulatedRefractiveIndex::parse_csv("# c\nwavelength_um,n,k\n0.4,1.5,abc\n")
            .unwrap_err();
        assert!(
            matches!(error, RefractiveIndexError::Parse { line_number: 3, .. }),
            "{error:?}"
        );
        let error = TabulatedRefractiveIndex::parse_csv("lambda,n,k\n0.4,1.5,0.1\n").unwrap_err();
        assert!(
            matches!(error, RefractiveIndexError::Parse { line_number: 1, .. }),
            "{error:?}"
        );
        let error =
            TabulatedRefractiveIndex::parse_csv("wavelength_nm,n,k\n500,1.5,0.1\n400,1.5,0.1\n")
                .unwrap_err();
        assert!(
            matches!(error, RefractiveIndexError::InvalidTable { .. }),
            "{error:?}"
        );
        let error =
            TabulatedRefractiveIndex::parse_csv("wavelength_nm,n,k\n400,1.5,-0.1\n500,1.5,0.1\n")
                .unwrap_err();
        assert!(
            matches!(error, RefractiveIndexError::InvalidRefractiveIndex { .. }),
            "{error:?}"
        );
        let error =
            TabulatedRefractiveIndex::parse_csv("wavelength_nm,n,k\n400,1.5,0.1\n").unwrap_err();
        assert!(
            matches!(error, RefractiveIndexError::InvalidTable { .. }),
            "{error:?}"
        );
        assert!(TabulatedRefractiveIndex::parse_csv("# only comments\n").is_err());
    }

    #[test]
    fn constant_model_is_validated() {
        let model = RefractiveIndexModel::constant(Complex64::new(1.5, 0.01)).unwrap();
        assert_eq!(
            model.refractive_index_at(550.0).unwrap(),
            Complex64::new(1.5, 0.01)
        );
        assert!(model.refractive_index_at(-1.0).is_err());
        assert!(RefractiveIndexModel::constant(Complex64::new(1.5, -0.01)).is_err());
        assert!(RefractiveIndexModel::constant(Complex64::new(0.0, 0.0)).is_err());
    }

    /// The built-in Mars dust table of Wolff et al. (2009): the rows this project relies on (380-780 nm) come out as
    /// the published values at the nodes and geometric means in between.
    #[test]
    fn mars_dust_table_covers_the_visible() {
        let table = TabulatedRefractiveIndex::parse_csv(MARS_DUST_WOLFF2009_CSV).unwrap();
        assert_eq!(table.wavelength_range_nm(), (263.0, 2480.0));
        let model = RefractiveIndexModel::Tabulated(table);
        assert_eq!(
            model.refractive_index_at(500.0).unwrap(),
            Complex64::new(1.5, 0.00548876)
        );
        assert_eq!(
            model.refractive_index_at(440.0).unwrap(),
            Complex64::new(1.49915, 0.00767169)
        );
        let m_380 = model.refractive_index_at(380.0).unwrap();
        // Between the 321 nm (k 0.0127) and 440 nm (k 0.00767169) rows.
        let t = (380.0 - 321.0) / (440.0 - 321.0);
        let expected_k = 0.0127f64.powf(1.0 - t) * 0.00767169f64.powf(t);
        assert!((m_380.im / expected_k - 1.0).abs() < 1e-13);
        assert!((m_380.re - (1.49413 + t * (1.49915 - 1.49413))).abs() < 1e-14);
        for lambda in (380..=780).step_by(20) {
            let m = model.refractive_index_at(lambda as f64).unwrap();
            assert!(
                m.re > 1.49 && m.re < 1.51 && m.im > 8e-4 && m.im < 0.011,
                "{lambda}: {m}"
            );
        }
        assert!(model.refractive_index_at(250.0).is_err());
    }
}
