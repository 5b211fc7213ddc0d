//! Library errors as Python exceptions: a value the library refuses is a
//! `ValueError` carrying the library's one-line message (the same text the
//! command line prints), a file that cannot be read or written an
//! `OSError`. Nothing panics across the boundary: every fallible call
//! returns one of these.

use pyo3::PyErr;
use pyo3::exceptions::{PyOSError, PyValueError};

/// `error` as the Python exception a user of the field expects.
pub fn to_py_err(error: sora::Error) -> PyErr {
    match error {
        sora::Error::Io { .. } => PyOSError::new_err(error.to_string()),
        other => PyValueError::new_err(other.to_string()),
    }
}

/// A `ValueError` with `message` (checks made at the boundary).
pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}
