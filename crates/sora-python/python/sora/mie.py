"""Mie theory of homogeneous spheres over numpy arrays (the ``sora-mie``
crate: the same solver as ``sora mie`` and the atmospheres' aerosols).

Conventions (Bohren & Huffman 1983): the refractive index ``m = n + i k`` is
relative to the medium around the sphere, and **k >= 0 means absorption**
(time dependence exp(-i w t)). miepython writes the same index as
``n - i k`` (its imaginary part is negative for absorbing spheres): pass
``m.conjugate()`` of a miepython index; a negative imaginary part raises
``ValueError`` saying so. The size parameter is ``x = 2 pi r / lambda``
with lambda in the medium. Efficiencies are cross-sections over pi r^2
(dimensionless); ``qback`` follows Bohren & Huffman eq. 4.82
(|sum (2n+1)(-1)^n (a_n - b_n)|^2 / x^2).

All functions release the GIL; :func:`efficiencies` runs on
``sora.set_num_threads(n)`` threads.
"""

from __future__ import annotations

import numbers
from typing import NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np
import xarray as xr

from . import _checks, _sora
from ._arrays import broadcast_flat

__all__ = ["Efficiencies", "efficiencies", "phase_function", "lognormal", "gamma"]


class Efficiencies(NamedTuple):
    """Efficiencies and asymmetry parameter, each an array of the broadcast
    shape of ``m`` and ``x`` (dimensionless)."""

    qext: np.ndarray
    qsca: np.ndarray
    qabs: np.ndarray
    qback: np.ndarray
    g: np.ndarray


def efficiencies(m, x) -> Efficiencies:
    """Q_ext, Q_sca, Q_abs (computed directly, accurate when tiny), Q_back
    and g of spheres of index ``m`` (complex, n + ik with k >= 0) and size
    parameter ``x`` (> 0, at most 1e6), numpy arrays that broadcast
    together. A bad sphere raises ``ValueError`` naming its flat index.

    >>> q = efficiencies(1.5 + 0.01j, np.logspace(-1, 2, 1000))
    """
    for name, value in (("m", m), ("x", x)):
        if value is None:
            raise TypeError(f"{name} must be a number or an array of numbers, not None")
    (m_flat, x_flat), shape = broadcast_flat(("m", "x"), m, x, dtype=complex)
    if np.any(x_flat.imag != 0):
        raise ValueError("x must be real (the size parameter 2 pi r / lambda)")
    columns = _sora.mie_efficiencies(
        np.ascontiguousarray(m_flat.real),
        np.ascontiguousarray(m_flat.imag),
        np.ascontiguousarray(x_flat.real),
    )
    return Efficiencies(*(c.reshape(shape) for c in columns))


def phase_function(m: complex, x: float, angle_deg, polarization: bool = False):
    """The phase function of one sphere at scattering angles ``angle_deg``
    (array, 0..180 deg), sr^-1, normalised to 1 over 4 pi sr:
    S11 / (pi x^2 Q_sca). With ``polarization=True``, also S12/S11 as a
    second array (the degree of linear polarization is -S12/S11)."""
    angles = np.asarray(angle_deg, dtype=float)
    if not np.all(np.isfinite(angles)) or np.any((angles < 0) | (angles > 180)):
        bad = angles[~(np.isfinite(angles) & (angles >= 0) & (angles <= 180))].reshape(-1)[0]
        raise ValueError(f"angle_deg = {bad} deg is out of range: allowed 0..=180 deg")
    if m is None or isinstance(m, (str, bytes, bool)) or not isinstance(m, numbers.Complex):
        raise TypeError(f"m must be a complex number, not {type(m).__name__}")
    try:
        m = complex(m)
    except OverflowError:
        raise ValueError("m is out of range: it is not a finite complex number") from None
    phase, ratio = _sora.mie_phase_function(
        m.real, m.imag, _checks.number("x", x, "(size parameter)"),
        np.ascontiguousarray(np.cos(np.radians(angles)).reshape(-1)),
    )
    phase = phase.reshape(angles.shape)
    return (phase, ratio.reshape(angles.shape)) if polarization else phase


def _wavelengths(wavelengths_nm) -> np.ndarray:
    if isinstance(wavelengths_nm, str):
        # The command line's start:stop:step, checked as `sora mie
        # --wavelengths` checks it (280-2500 nm, at most 10,000).
        return np.asarray(_sora.wavelength_grid_nm(wavelengths_nm), dtype=float)
    if wavelengths_nm is None:
        raise TypeError("wavelengths_nm must be 'start:stop:step' or an array of wavelengths in nm, not None")
    try:
        values = np.asarray(wavelengths_nm, dtype=float)
    except (TypeError, ValueError, OverflowError) as error:
        raise ValueError(f"wavelengths_nm must be numbers in nm ({error})") from None
    if values.ndim > 1:
        raise ValueError(f"wavelengths_nm must be 1-D (nm), not of shape {values.shape}")
    if values.size > _sora.MAX_WAVELENGTH_COUNT:
        raise ValueError(
            f"wavelengths_nm has {values.size} wavelengths, more than the limit of {_sora.MAX_WAVELENGTH_COUNT}"
        )
    return np.ascontiguousarray(values.reshape(-1))


def _ensemble(kind, first, second, m, wavelengths_nm, radius_window_um, parameters) -> xr.Dataset:
    wavelengths = _wavelengths(wavelengths_nm)
    if m is None:
        raise TypeError("m must be a complex number or one per wavelength, not None")
    try:
        m_values = np.asarray(m, dtype=complex)
    except (TypeError, ValueError, OverflowError) as error:
        raise ValueError(f"m must be complex numbers ({error})") from None
    if m_values.ndim == 0:
        m_values = np.full(wavelengths.shape, complex(m_values))
    if m_values.shape != wavelengths.shape:
        raise ValueError(
            f"m has shape {m_values.shape}: give one index or one per wavelength ({wavelengths.size})"
        )
    if radius_window_um is not None and (
        isinstance(radius_window_um, (str, bytes)) or not hasattr(radius_window_um, "__len__")
    ):
        raise TypeError("radius_window_um must be (min_um, max_um)")
    window = None if radius_window_um is None else tuple(
        _checks.number("radius_window_um", v, "um") for v in radius_window_um
    )
    if window is not None and len(window) != 2:
        raise ValueError("radius_window_um must be (min_um, max_um)")
    c_ext, c_sca, c_abs, albedo, g, paper_g, fraction = _sora.mie_ensemble(
        kind, first, second,
        np.ascontiguousarray(m_values.real), np.ascontiguousarray(m_values.imag),
        wavelengths, window,
    )
    dims = ("wavelength",)
    attrs = dict(parameters, distribution=kind)
    if window is not None:
        attrs["radius_window_um"] = list(window)
    return xr.Dataset(
        {
            "extinction_cross_section": (dims, c_ext, {"units": "m2", "long_name": "<C_ext> per particle"}),
            "scattering_cross_section": (dims, c_sca, {"units": "m2", "long_name": "<C_sca> per particle"}),
            "absorption_cross_section": (dims, c_abs, {"units": "m2", "long_name": "<C_abs> per particle"}),
            "single_scattering_albedo": (dims, albedo, {"units": "1"}),
            "asymmetry_parameter": (dims, g, {"units": "1", "long_name": "scattering-weighted <cos theta>"}),
            "paper_asymmetry_parameter": (dims, paper_g, {"units": "1", "long_name": "the paper's Henyey-Greenstein g"}),
            "number_fraction_in_window": (dims, fraction, {"units": "1"}),
            "refractive_index_real": (dims, m_values.real.copy(), {"units": "1"}),
            "refractive_index_imag": (dims, m_values.imag.copy(), {"units": "1"}),
        },
        coords={"wavelength": ("wavelength", wavelengths, {"units": "nm", "long_name": "vacuum wavelength"})},
        attrs=attrs,
    )


def lognormal(
    m,
    median_radius_um: float,
    geometric_standard_deviation: float,
    wavelengths_nm: Union[str, Sequence[float], np.ndarray] = "380:780:20",
    radius_window_um: Optional[Tuple[float, float]] = None,
) -> xr.Dataset:
    """Per-particle optics of a log-normal population (number median radius,
    um; geometric standard deviation > 1), optionally truncated to
    ``radius_window_um``, at each wavelength (nm, vacuum): cross-sections
    (m^2), albedo, g, as ``sora mie --lognormal``. ``m`` is one index or
    one per wavelength."""
    median_radius_um = _checks.number("median_radius_um", median_radius_um, "um")
    geometric_standard_deviation = _checks.number(
        "geometric_standard_deviation", geometric_standard_deviation, ""
    )
    return _ensemble(
        "lognormal", median_radius_um, geometric_standard_deviation, m, wavelengths_nm,
        radius_window_um,
        {"median_radius_um": median_radius_um, "geometric_standard_deviation": geometric_standard_deviation},
    )


def gamma(
    m,
    effective_radius_um: float,
    effective_variance: float,
    wavelengths_nm: Union[str, Sequence[float], np.ndarray] = "380:780:20",
    radius_window_um: Optional[Tuple[float, float]] = None,
) -> xr.Dataset:
    """As :func:`lognormal` for a modified gamma population (Hansen & Travis
    1974) by effective radius (um) and effective variance, as ``sora mie
    --gamma``."""
    effective_radius_um = _checks.number("effective_radius_um", effective_radius_um, "um")
    effective_variance = _checks.number("effective_variance", effective_variance, "")
    return _ensemble(
        "gamma", effective_radius_um, effective_variance, m, wavelengths_nm, radius_window_um,
        {"effective_radius_um": effective_radius_um, "effective_variance": effective_variance},
    )
