#!/usr/bin/env python3
"""Generates sora's embedded water vapour and mixed-gas (O2, CO2) band tables.

One-time sources (nothing else is read):
- pvlib-python 0.13.1 (PyPI `pip install pvlib==0.13.1`, BSD 3-clause licence),
  module pvlib/spectrum/spectrl2.py, table `_SPECTRL2_COEFFS`: the absorption
  coefficients of Bird & Riordan (1986), "Simple solar spectral model for direct
  and diffuse irradiance on horizontal and tilted planes at the Earth's surface
  for cloudless atmospheres", J. Climate Appl. Meteor. 25, 87-97 (SERI/NREL
  report TR-215-2436, a U.S. Government work), which take them from Leckner
  (1978), Solar Energy 20, 143-150. 122 wavelengths, 300-4000 nm.
- The band-model transmittances of the same paper (its eqs. 2-8 and 2-11, the
  constant 118.3 of the SPECTRL2 C code as pvlib uses it):
      water vapour:  T_w = exp(-0.2385 x / (1 + 20.07 x)^0.45),  x = a_w W m
      mixed gases:   T_u = exp(-1.41 y / (1 + 118.3 y)^0.45),    y = a_u M
  (W precipitable water in cm, m the relative air mass, M the pressure-
  corrected air mass m p / 1013 hPa).

Outputs (in crates/sora/src/data/):
- gas_bands_spectrl2.csv: wavelength_nm, water_absorption_per_cm, mixed_absorption
  (the coefficients as published; a row of zeros at 200 nm so a grid from
  280 nm is covered).
- gas_bands_k_terms.csv: an exponential-sum (k-distribution) fit of the two
  band transmittances with shared weights:
      T_w(x) ~ sum_j w_j exp(-c_w,j x),   T_u(y) ~ sum_j w_j exp(-c_u,j y)
  (Wiscombe & Evans 1977, J. Comput. Phys. 24, 416). The fit minimises the
  error relative to the absorption 1 - T over x in [1e-6, 1e5] and
  y in [1e-6, 1e4] (beyond them T < 1e-7); the script prints its largest
  error.

Run: python3 scripts/gases/make_gas_bands.py  (needs numpy, scipy, pvlib==0.13.1)
"""

import pathlib

import numpy as np
from scipy.optimize import least_squares
from pvlib.spectrum.spectrl2 import _SPECTRL2_COEFFS

TERMS = 5
OUT = pathlib.Path(__file__).resolve().parents[2] / "crates" / "sora" / "src" / "data"


def t_water(x):
    return np.exp(-0.2385 * x / (1 + 20.07 * x) ** 0.45)


def t_mixed(y):
    return np.exp(-1.41 * y / (1 + 118.3 * y) ** 0.45)


X = np.logspace(-6, 5, 400)
Y = np.logspace(-6, 4, 400)


def unpack(p):
    w = np.exp(p[:TERMS])
    return w / w.sum(), np.exp(p[TERMS : 2 * TERMS]), np.exp(p[2 * TERMS :])


def expsum(w, c, x):
    return (w[None, :] * np.exp(-np.outer(x, c))).sum(axis=1)


def residuals(p):
    w, cw, cu = unpack(p)
    rw = (expsum(w, cw, X) - t_water(X)) / np.maximum(1 - t_water(X), 1e-3)
    ru = (expsum(w, cu, Y) - t_mixed(Y)) / np.maximum(1 - t_mixed(Y), 1e-3)
    return np.concatenate([rw, ru])


def fit():
    c0 = np.logspace(-3, 1.5, TERMS)
    p0 = np.concatenate([np.zeros(TERMS), np.log(c0), np.log(5 * c0)])
    best = None
    for trial in range(3):
        start = p0 if trial == 0 else p0 + np.random.default_rng(trial).normal(0, 0.3, 3 * TERMS)
        r = least_squares(residuals, start, loss="soft_l1", max_nfev=20000)
        worst = np.abs(residuals(r.x)).max()
        if best is None or worst < best[0]:
            best = (worst, r.x)
    w, cw, cu = unpack(best[1])
    order = np.argsort(cw)
    return best[0], w[order], cw[order], cu[order]


def main():
    c = _SPECTRL2_COEFFS
    header = (
        "# Water vapour and uniformly mixed gas (O2, CO2) absorption coefficients of Bird & Riordan (1986), "
        "J. Climate Appl. Meteor. 25, 87-97 (SPECTRL2; from Leckner 1978, Solar Energy 20, 143), as tabulated in "
        "pvlib-python 0.13.1 pvlib/spectrum/spectrl2.py _SPECTRL2_COEFFS (BSD 3-clause). Written by "
        "scripts/gases/make_gas_bands.py.\n"
        "# water_absorption_per_cm: a_w, cm^-1 of precipitable water (T_w = exp(-0.2385 a_w u / (1 + 20.07 a_w u)^0.45), "
        "u the slant precipitable water, cm). mixed_absorption: a_u per unit pressure-corrected air mass "
        "(T_u = exp(-1.41 a_u M / (1 + 118.3 a_u M)^0.45)). Wavelengths as published (nm); the 200 nm row of zeros "
        "is added so that grids from 280 nm are covered (both are 0 below 593 nm).\n"
    )
    rows = ["200,0,0"] + [
        f"{wl:g},{aw:g},{au:g}"
        for wl, aw, au in zip(c["wavelength"], c["water_vapor_absorption"], c["mixed_absorption"])
    ]
    (OUT / "gas_bands_spectrl2.csv").write_text(
        header + "wavelength_nm,water_absorption_per_cm,mixed_absorption\n" + "\n".join(rows) + "\n"
    )
    worst, w, cw, cu = fit()
    header = (
        f"# Exponential-sum (k-distribution) fit, {TERMS} terms with shared weights, of the SPECTRL2 band "
        "transmittances T_w(x) = exp(-0.2385 x / (1 + 20.07 x)^0.45) and T_u(y) = exp(-1.41 y / (1 + 118.3 y)^0.45): "
        "T_w ~ sum_j weight_j exp(-water_factor_j x), T_u ~ sum_j weight_j exp(-mixed_factor_j y). "
        f"Largest error {worst:.4f} of the absorption 1 - T over x in [1e-6, 1e5], y in [1e-6, 1e4] "
        "(least squares, soft-L1, 400 log-spaced points each). Written by scripts/gases/make_gas_bands.py.\n"
    )
    rows = [f"{a:.6e},{b:.6e},{d:.6e}" for a, b, d in zip(w, cw, cu)]
    (OUT / "gas_bands_k_terms.csv").write_text(
        header + "weight,water_factor,mixed_factor\n" + "\n".join(rows) + "\n"
    )
    print(f"{TERMS} terms, largest error {worst:.4f} of 1 - T")


if __name__ == "__main__":
    main()
