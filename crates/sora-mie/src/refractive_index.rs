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
//! table is built from its columns ([`TabulatedRefractiveIndex::from_columns`]);
//! reading tables from text or files is the caller's business (sora reads
//! refractive-index CSV with its one numeric-table reader). One table is
//! built in, as text: [`MARS_DUST_WOLFF2009_CSV`].

use crate::Complex64;

/// The Mars dust refractive index of Wolff et al. (2009, JGR 114, E00D04;
/// CRISM retrieval, with two ultraviolet rows from Wolff's distributed
/// compilation), as CSV text (header `wavelength_um,n,k`; sora reads it):
/// wavelength (um), n, k, 263-2480 nm, its provenance in the leading
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

    /// 400, 500 and 600 nm; `k` falls a decade, then to 0.
    fn small_table() -> TabulatedRefractiveIndex {
        TabulatedRefractiveIndex::from_columns(
            vec![400.0, 500.0, 600.0],
            vec![1.50, 1.52, 1.51],
            vec![0.0100, 0.0010, 0.0000],
        )
        .unwrap()
    }

    #[test]
    fn nodes_return_the_rows() {
        let table = small_table();
        assert_eq!(table.wavelengths_nm(), &[400.0, 500.0, 600.0]);
        assert_eq!(table.wavelength_range_nm(), (400.0, 600.0));
        let m = table.refractive_index_at(500.0).unwrap();
        assert_eq!(m, Complex64::new(1.52, 0.001));
    }

    #[test]
    fn n_is_linear_and_k_geometric_between_rows() {
        let table = small_table();
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
        let table = small_table();
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
    fn malformed_columns_are_rejected() {
        let table = |w: &[f64], n: &[f64], k: &[f64]| {
            TabulatedRefractiveIndex::from_columns(w.to_vec(), n.to_vec(), k.to_vec())
        };
        let error = table(&[500.0, 400.0], &[1.5, 1.5], &[0.1, 0.1]).unwrap_err();
        assert!(
            matches!(error, RefractiveIndexError::InvalidTable { .. }),
            "{error:?}"
        );
        let error = table(&[400.0, 500.0], &[1.5, 1.5], &[-0.1, 0.1]).unwrap_err();
        assert!(
            matches!(error, RefractiveIndexError::InvalidRefractiveIndex { .. }),
            "{error:?}"
        );
        let error = table(&[400.0], &[1.5], &[0.1]).unwrap_err();
        assert!(
            matches!(error, RefractiveIndexError::InvalidTable { .. }),
            "{error:?}"
        );
        let error = table(&[400.0, 500.0], &[1.5], &[0.1, 0.1]).unwrap_err();
        assert!(
            matches!(error, RefractiveIndexError::InvalidTable { .. }),
            "{error:?}"
        );
        let error = table(&[-400.0, 500.0], &[1.5, 1.5], &[0.1, 0.1]).unwrap_err();
        assert!(
            matches!(error, RefractiveIndexError::InvalidWavelength { .. }),
            "{error:?}"
        );
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
}
