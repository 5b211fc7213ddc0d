//! # sora-python: the Python bindings of sora
//!
//! The native module `sora._sora`, a thin layer over the library's front
//! door ([`sora::Sky`], [`sora::Atmosphere`], [`sora::mie`]): it checks
//! shapes and values at the boundary, releases the GIL around every
//! computation, runs it on the thread pool of [`threads`], and hands
//! numpy arrays back. The pure-Python package (`python/sora/`) wraps these
//! arrays into xarray objects with units.
//!
//! - [`atmosphere`]: `Atmosphere` (presets, TOML files and text, dicts with
//!   the file schema) and its vertical optical depths;
//! - [`sky`]: `Sky` (radiance of many views, images, path tracing);
//! - [`mie`]: efficiencies of numpy arrays of spheres, phase functions,
//!   log-normal and modified-gamma ensembles per wavelength;
//! - [`output`]: OpenEXR files through the library's writer;
//! - [`errors`]: library errors -> `ValueError`, files -> `OSError`.
//!
//! Nothing here computes physics: every number comes from `sora` or
//! `sora-mie` by the same code path as the command-line tool.

use pyo3::prelude::*;

mod atmosphere;
mod errors;
mod grid;
mod mie;
mod output;
mod sky;
mod threads;

/// The native module (imported by the `sora` package as `sora._sora`).
#[pymodule]
fn _sora(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add_class::<atmosphere::Atmosphere>()?;
    module.add_class::<sky::Sky>()?;
    // The library's camera defaults, which `Sky.render`'s signature shows
    // as literals (tests/test_sky.py holds them equal).
    use sora::camera::PerspectiveCamera;
    module.add(
        "PERSPECTIVE_DEFAULTS",
        (
            PerspectiveCamera::DEFAULT_ELEVATION_DEG,
            PerspectiveCamera::DEFAULT_AZIMUTH_DEG,
            PerspectiveCamera::DEFAULT_FOV_DEG,
        ),
    )?;
    module.add_function(wrap_pyfunction!(threads::set_num_threads, module)?)?;
    module.add_function(wrap_pyfunction!(threads::get_num_threads, module)?)?;
    module.add_function(wrap_pyfunction!(mie::mie_efficiencies, module)?)?;
    module.add_function(wrap_pyfunction!(mie::mie_phase_function, module)?)?;
    module.add_function(wrap_pyfunction!(mie::mie_ensemble, module)?)?;
    module.add_function(wrap_pyfunction!(atmosphere::preset_names, module)?)?;
    module.add_function(wrap_pyfunction!(atmosphere::preset_toml, module)?)?;
    module.add_function(wrap_pyfunction!(output::write_exr, module)?)?;
    module.add_function(wrap_pyfunction!(grid::wavelength_grid_nm, module)?)?;
    // The library's limits, which the Python layer checks arguments
    // against before any work.
    module.add("MAX_VIEWS", sora::sky::MAX_VIEWS)?;
    module.add("MAX_IMAGE_SIDE", sora::sky::MAX_IMAGE_SIDE)?;
    module.add("MAX_SAMPLES", sora::sky::MAX_SAMPLES)?;
    module.add("MAX_REFERENCE_STEPS", sora::sky::MAX_REFERENCE_STEPS)?;
    module.add("MAX_WAVELENGTH_COUNT", sora::spectrum::MAX_WAVELENGTH_COUNT)?;
    module.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
