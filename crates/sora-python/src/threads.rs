//! The thread count of the bindings' computations. The library has no
//! global state and never configures rayon's global pool; the bindings keep
//! one pool of their own when the user asks for a thread count
//! (`sora.set_num_threads(n)`), and run every computation inside it.
//! Without one, rayon's default (one thread per core) is used. Results do
//! not depend on the thread count (the library computes each view and pixel
//! by the same code on any thread).

use std::sync::{Arc, Mutex};

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use crate::errors::value_error;

/// The pool set by `set_num_threads`, or None for rayon's default.
static POOL: Mutex<Option<(usize, Arc<rayon::ThreadPool>)>> = Mutex::new(None);

/// Most threads accepted (far beyond any machine; a typo guard).
const MAX_THREADS: usize = 4096;

/// Uses `threads` threads for every later computation (0: one per core,
/// rayon's default).
#[pyfunction]
pub fn set_num_threads(threads: usize) -> PyResult<()> {
    if threads > MAX_THREADS {
        return Err(value_error(format!(
            "threads = {threads} is out of range: allowed 0 (one per core) ..= {MAX_THREADS}"
        )));
    }
    let pool = if threads == 0 {
        None
    } else {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| value_error(format!("cannot start {threads} threads: {e}")))?;
        Some((threads, Arc::new(pool)))
    };
    *POOL.lock().unwrap_or_else(|poisoned| poisoned.into_inner()) = pool;
    Ok(())
}

/// The number of threads computations use.
#[pyfunction]
pub fn get_num_threads() -> usize {
    match &*POOL.lock().unwrap_or_else(|poisoned| poisoned.into_inner()) {
        Some((threads, _)) => *threads,
        None => rayon::current_num_threads(),
    }
}

/// Runs `work` with the GIL released, on the chosen pool. A panic in it
/// (a bug: every input is checked before any work) is caught here and
/// raised as `RuntimeError`, which `except Exception` catches, never as
/// pyo3's `PanicException`: the last line of defence, not a way to report
/// bad input.
pub fn run_detached<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    let pool = POOL
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
        .as_ref()
        .map(|(_, pool)| Arc::clone(pool));
    let caught = py.detach(move || {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match pool {
            Some(pool) => pool.install(work),
            None => work(),
        }))
    });
    caught.map_err(|payload| {
        let message = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".to_string());
        PyRuntimeError::new_err(format!(
            "internal error in sora (a bug; please report it with the call): {message}"
        ))
    })
}
