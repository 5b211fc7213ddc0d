//! `sora.mie` (native part): Mie theory of homogeneous spheres from
//! `sora-mie`, over numpy arrays.
//!
//! Convention (Bohren & Huffman): m = n + i k relative to the medium,
//! k >= 0 absorbs; x = 2 pi r / lambda. The Python layer broadcasts m and x
//! and flattens them; here the spheres are solved in fixed chunks (so the
//! result does not depend on the thread count), each run of equal m in a
//! chunk eight spheres side by side (`compute_efficiencies_many_with`,
//! equal to one-sphere calls to 1e-13), chunks in parallel.

use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use rayon::prelude::*;
use sora::mie::Complex64;
use sora::mie::distribution::quadrature::RadiusQuadratureSettings;
use sora::mie::distribution::{RadiusWindow, SizeDistribution};
use sora::mie::ensemble::compute_ensemble_cross_sections;
use sora::mie::sphere::{
    Efficiencies, MieSolution, SphereWorkspace, compute_efficiencies,
    compute_efficiencies_many_with,
};

use crate::errors::value_error;
use crate::threads::run_detached;

/// Spheres per parallel task: large enough that a task outweighs its
/// scheduling, small enough to balance two to many cores.
const SPHERES_PER_TASK: usize = 2048;

const ZERO: Efficiencies = Efficiencies {
    qext: 0.0,
    qsca: 0.0,
    qabs: 0.0,
    qback: 0.0,
    g: 0.0,
};

/// Solves one chunk: each run of equal m in one batched call.
fn solve_chunk(m: &[Complex64], x: &[f64], out: &mut [Efficiencies]) -> Result<(), ()> {
    let mut workspace = SphereWorkspace::new();
    let mut start = 0;
    while start < m.len() {
        // At least the first sphere: a NaN index equals nothing, not even
        // itself (the solver then refuses it).
        let end = start
            + 1
            + m[start + 1..]
                .iter()
                .take_while(|v| **v == m[start])
                .count();
        compute_efficiencies_many_with(
            &mut workspace,
            m[start],
            &x[start..end],
            &mut out[start..end],
        )
        .map_err(|_| ())?;
        start = end;
    }
    Ok(())
}

type FiveArrays<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
);

/// Q_ext, Q_sca, Q_abs, Q_back and g of every sphere (flat arrays of equal
/// length: real and imaginary parts of m, size parameter x).
#[pyfunction]
pub fn mie_efficiencies<'py>(
    py: Python<'py>,
    m_re: PyReadonlyArray1<'py, f64>,
    m_im: PyReadonlyArray1<'py, f64>,
    x: PyReadonlyArray1<'py, f64>,
) -> PyResult<FiveArrays<'py>> {
    let (m_re, m_im, x) = (m_re.as_array(), m_im.as_array(), x.as_array());
    if m_re.len() != x.len() || m_im.len() != x.len() {
        return Err(value_error(format!(
            "m ({} values) and x ({} values) must have the same shape after broadcasting",
            m_re.len(),
            x.len()
        )));
    }
    let m: Vec<Complex64> = m_re
        .iter()
        .zip(m_im.iter())
        .map(|(re, im)| Complex64::new(*re, *im))
        .collect();
    let x: Vec<f64> = x.iter().copied().collect();
    let mut out = vec![ZERO; x.len()];
    let failed = run_detached(py, || {
        out.par_chunks_mut(SPHERES_PER_TASK)
            .enumerate()
            .map(|(task, chunk)| {
                let start = task * SPHERES_PER_TASK;
                let end = start + chunk.len();
                solve_chunk(&m[start..end], &x[start..end], chunk)
                    .err()
                    .map(|_| task)
            })
            .filter_map(|failed| failed)
            .min()
    })?;
    if let Some(task) = failed {
        // The first sphere the solver refuses, with its message.
        let start = task * SPHERES_PER_TASK;
        for i in start..(start + SPHERES_PER_TASK).min(x.len()) {
            if let Err(error) = compute_efficiencies(m[i], x[i]) {
                let hint = if m[i].im < 0.0 {
                    " (sora's convention is m = n + ik with k >= 0 for absorption; miepython's is n - ik: pass m.conjugate())"
                } else {
                    ""
                };
                return Err(value_error(format!("sphere {i}: {error}{hint}")));
            }
        }
        unreachable!("a chunk that failed has a sphere that fails");
    }
    let column =
        |f: fn(&Efficiencies) -> f64| out.iter().map(f).collect::<Vec<_>>().into_pyarray(py);
    Ok((
        column(|q| q.qext),
        column(|q| q.qsca),
        column(|q| q.qabs),
        column(|q| q.qback),
        column(|q| q.g),
    ))
}

type TwoArrays<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// The phase function (sr^-1, normalised to 1 over 4 pi sr) and S12/S11 of
/// one sphere at each scattering angle cosine.
#[pyfunction]
pub fn mie_phase_function<'py>(
    py: Python<'py>,
    m_re: f64,
    m_im: f64,
    x: f64,
    cos_theta: PyReadonlyArray1<'py, f64>,
) -> PyResult<TwoArrays<'py>> {
    let m = Complex64::new(m_re, m_im);
    let cos_theta: Vec<f64> = cos_theta.as_array().iter().copied().collect();
    if let Some(bad) = cos_theta.iter().find(|c| !(-1.0..=1.0).contains(*c)) {
        return Err(value_error(format!(
            "a scattering angle gives cos(theta) = {bad}: angles must be finite, in degrees"
        )));
    }
    if m == Complex64::new(1.0, 0.0) {
        return Err(value_error(
            "m = 1+0i: the sphere does not scatter (Q_sca = 0), so it has no phase function",
        ));
    }
    let (phase, ratio) = run_detached(py, || {
        let solution = MieSolution::compute(m, x)?;
        let count = cos_theta.len();
        let (mut s11, mut s12) = (vec![0.0; count], vec![0.0; count]);
        solution.s11_s12_table(&cos_theta, &mut s11, &mut s12);
        // S11 / (pi x^2 Q_sca): normalised to 1 over 4 pi sr.
        let normalisation = 1.0 / (std::f64::consts::PI * x * x * solution.efficiencies().qsca);
        let phase: Vec<f64> = s11.iter().map(|s| s * normalisation).collect();
        let ratio: Vec<f64> = s11
            .iter()
            .zip(&s12)
            .map(|(a, b)| if *a > 0.0 { b / a } else { 0.0 })
            .collect();
        Ok::<_, sora::mie::sphere::MieError>((phase, ratio))
    })?
    .map_err(|e| value_error(e.to_string()))?;
    if phase.iter().chain(&ratio).any(|v| !v.is_finite()) {
        return Err(value_error(format!(
            "m = {m_re}{m_im:+}i, x = {x}: the sphere scatters too weakly for its phase function to be computed in double precision (Q_sca underflows)"
        )));
    }
    Ok((phase.into_pyarray(py), ratio.into_pyarray(py)))
}

/// The largest effective size parameter 2 pi r_eff / lambda of the
/// ensembles (as `sora mie`): about half a minute of work per wavelength.
const MAX_EFFECTIVE_SIZE_PARAMETER: f64 = 1e5;

type SevenArrays<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
);

/// Per-particle ensemble optics of a size distribution at each wavelength
/// (nm), with the index `m` per wavelength: `kind` 'lognormal' (parameters:
/// number median radius um, geometric standard deviation) or 'gamma'
/// (effective radius um, effective variance); optional radius window um.
/// Returns C_ext, C_sca, C_abs (m^2), albedo, g, the paper's HG g and the
/// number fraction in the window.
#[pyfunction]
#[pyo3(signature = (kind, first, second, m_re, m_im, wavelengths_nm, window_um=None))]
#[allow(clippy::too_many_arguments)]
pub fn mie_ensemble<'py>(
    py: Python<'py>,
    kind: &str,
    first: f64,
    second: f64,
    m_re: PyReadonlyArray1<'py, f64>,
    m_im: PyReadonlyArray1<'py, f64>,
    wavelengths_nm: PyReadonlyArray1<'py, f64>,
    window_um: Option<(f64, f64)>,
) -> PyResult<SevenArrays<'py>> {
    let distribution = match kind {
        "lognormal" => SizeDistribution::log_normal(first * 1e-6, second),
        "gamma" => SizeDistribution::modified_gamma(first * 1e-6, second),
        other => return Err(value_error(format!("unknown size distribution '{other}'"))),
    }
    .map_err(|e| value_error(format!("{kind}: {e}")))?;
    let distribution = match window_um {
        None => distribution,
        Some((min, max)) => distribution
            .truncated_to(
                RadiusWindow::from_micrometres(min, max)
                    .map_err(|e| value_error(format!("radius_window_um: {e}")))?,
            )
            .map_err(|e| value_error(format!("radius_window_um: {e}")))?,
    };
    let wavelengths: Vec<f64> = wavelengths_nm.as_array().iter().copied().collect();
    let (m_re, m_im) = (m_re.as_array(), m_im.as_array());
    if m_re.len() != wavelengths.len() || m_im.len() != wavelengths.len() {
        return Err(value_error(format!(
            "m ({} values) must be one index or one per wavelength ({})",
            m_re.len(),
            wavelengths.len()
        )));
    }
    if let Some(bad) = wavelengths.iter().find(|w| !(w.is_finite() && **w > 0.0)) {
        return Err(value_error(format!(
            "wavelengths_nm contains {bad} nm: every wavelength must be finite and > 0 nm"
        )));
    }
    let mut radius_m = distribution.shape().effective_radius_m();
    if let Some(window) = distribution.radius_window() {
        radius_m = radius_m.min(window.max_radius_m());
    }
    let shortest_nm = wavelengths.iter().copied().fold(f64::INFINITY, f64::min);
    let x_eff = 2.0 * std::f64::consts::PI * radius_m * 1e9 / shortest_nm;
    if x_eff.is_nan() || x_eff > MAX_EFFECTIVE_SIZE_PARAMETER {
        return Err(value_error(format!(
            "the distribution's effective radius {radius_m:e} m is a size parameter of {x_eff:e} at {shortest_nm} nm, more than the limit of {MAX_EFFECTIVE_SIZE_PARAMETER:e}"
        )));
    }
    let m: Vec<Complex64> = m_re
        .iter()
        .zip(m_im.iter())
        .map(|(re, im)| Complex64::new(*re, *im))
        .collect();
    let settings = RadiusQuadratureSettings::cross_sections();
    let results = run_detached(py, || {
        wavelengths
            .par_iter()
            .zip(&m)
            .map(|(wavelength_nm, m)| {
                compute_ensemble_cross_sections(*wavelength_nm, *m, &distribution, &settings)
                    .map_err(|e| format!("at {wavelength_nm} nm: {e}"))
            })
            .collect::<Result<Vec<_>, String>>()
    })?
    .map_err(value_error)?;
    let column = |f: &dyn Fn(&sora::mie::ensemble::EnsembleCrossSections) -> f64| {
        results.iter().map(f).collect::<Vec<_>>().into_pyarray(py)
    };
    Ok((
        column(&|e| e.extinction_cross_section_m2),
        column(&|e| e.scattering_cross_section_m2),
        column(&|e| e.absorption_cross_section_m2),
        column(&|e| e.single_scattering_albedo),
        column(&|e| e.asymmetry_parameter),
        column(&|e| e.paper_asymmetry_parameter),
        column(&|e| e.number_fraction_in_window),
    ))
}
