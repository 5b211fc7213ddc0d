//! Files the package writes through the library's writers (`sora::output`):
//! atomic, and the same bytes as `sora render` writes.

use numpy::PyReadonlyArray3;
use pyo3::prelude::*;
use sora::output::{ChannelKind, ExrOptions, LinearImage, write_exr as write_exr_file};

use crate::errors::{to_py_err, value_error};
use crate::threads::run_detached;

/// Writes `rgb` (height, width, 3: linear RGB, rows top first) as a 32-bit
/// float OpenEXR at `path`, ZIP-compressed, atomically (a failure leaves no
/// file and an existing one unchanged), through `sora::output::write_exr`
/// (which refuses devices, FIFOs and directories: `sora::output::output_target`).
#[pyfunction]
pub fn write_exr(
    py: Python<'_>,
    path: std::path::PathBuf,
    rgb: PyReadonlyArray3<'_, f64>,
) -> PyResult<()> {
    let rgb = rgb.as_array();
    let (height, width, channels) = rgb.dim();
    if channels != 3 {
        return Err(value_error(format!(
            "rgb has {channels} channels: an EXR image needs (height, width, 3)"
        )));
    }
    let pixels: Vec<[f32; 3]> = rgb
        .outer_iter()
        .flat_map(|row| {
            row.outer_iter()
                .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32])
                .collect::<Vec<_>>()
        })
        .collect();
    run_detached(py, || {
        let image = LinearImage::new(width, height, ChannelKind::Rgb, pixels)?;
        write_exr_file(&path, &image, ExrOptions::default())
    })?
    .map_err(to_py_err)
}
