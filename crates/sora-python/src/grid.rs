//! Wavelength grids from Python: `"start:stop:step"` (nm, as on the command
//! line) or an evenly spaced 1-D array (or list) of wavelengths in nm (sora's grids are uniform; an uneven array is refused
//! rather than resampled).

use pyo3::prelude::*;
use pyo3::types::PyString;
use sora::WavelengthGrid;

use crate::errors::{to_py_err, value_error};

/// The grid `value` describes (None: the paper's 380-780 nm every 20 nm).
pub fn grid_from_python(value: Option<&Bound<'_, PyAny>>) -> PyResult<WavelengthGrid> {
    let Some(value) = value.filter(|v| !v.is_none()) else {
        return Ok(WavelengthGrid::paper());
    };
    if let Ok(text) = value.cast::<PyString>() {
        let text: String = text.extract()?;
        let text = text.as_str();
        return text
            .parse::<WavelengthGrid>()
            .map_err(|e| value_error(format!("wavelengths_nm = '{text}': {e}")));
    }
    let values: Vec<f64> = value.extract().map_err(|_| {
        value_error(
            "wavelengths_nm must be 'start:stop:step' or a 1-D array of evenly spaced wavelengths in nm",
        )
    })?;
    grid_from_values(&values)
}

/// The wavelengths (nm) of the grid `text` ('start:stop:step', checked as
/// the command line checks `--wavelengths`: 280-2500 nm, at most 10,000).
#[pyfunction]
pub fn wavelength_grid_nm(text: &str) -> PyResult<Vec<f64>> {
    let grid = text
        .parse::<WavelengthGrid>()
        .map_err(|e| value_error(format!("wavelengths_nm = '{text}': {e}")))?;
    Ok(grid.wavelengths_nm().collect())
}

/// The uniform grid through `values` (nm): one value, three numbers read
/// as an array, or any evenly spaced sequence.
fn grid_from_values(values: &[f64]) -> PyResult<WavelengthGrid> {
    if let Some(bad) = values.iter().find(|v| !v.is_finite()) {
        return Err(value_error(format!(
            "wavelengths_nm contains {bad} nm: every wavelength must be finite"
        )));
    }
    match values {
        [] => Err(value_error(
            "wavelengths_nm is empty: give at least one wavelength in nm",
        )),
        [single] => WavelengthGrid::new(*single, *single, 1.0).map_err(to_py_err),
        [first, second, ..] => {
            let step = second - first;
            let last = values[values.len() - 1];
            let grid = WavelengthGrid::new(*first, last, step).map_err(to_py_err)?;
            let uniform = grid.len() == values.len()
                && grid
                    .wavelengths_nm()
                    .zip(values)
                    .all(|(g, v)| (g - v).abs() <= 1e-9 * v.abs().max(1.0));
            if !uniform {
                return Err(value_error(format!(
                    "wavelengths_nm must be evenly spaced ({} values from {first} to {last} nm are not, first step {step} nm): sora's grids are uniform",
                    values.len()
                )));
            }
            Ok(grid)
        }
    }
}
