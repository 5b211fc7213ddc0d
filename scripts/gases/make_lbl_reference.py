#!/usr/bin/env python3
"""Line-by-line reference for the gas bands' direct-beam transmittance.

Writes crates/sora/tests/data/gas_line_by_line_reference.csv: the direct-beam
(column) transmittance of the O2 A band, band-averaged over 10 and 20 nm,
computed line by line from HITRAN line data through a layered U.S. Standard
Atmosphere 1976, for two sun elevations. crates/sora/tests/gas_line_by_line.rs
compares sora's banded gases with it.

Also writes crates/sora/src/data/o2_a_band_k_terms.csv, sora's O2 A band: for
each 0.5 nm bin of 749.5-780 nm, 5 weights and coefficients fitted together
(least squares, air masses 1-20, from sora's 5 shared k-term weights) to the
bin's line-by-line column transmittance T(M), per molecule of air
(bin_k_terms, write_k_terms; part of the run). sora re-sorts the bins into
each grid sample's band and fits the band's own five weights to them
(crates/sora/src/atmosphere/o2_a_band.rs).

What it covers, and what not
----------------------------
Only the O2 A band (750-780 nm). The water bands (940, 1130, 1400 and
1900 nm) are not here: no HITRAN H2O lines for 5000-11000 cm^-1 could be
had on the machine that wrote this (see "Line data" below), so their
reference is still to be made, with this script, from such a file.

Line data (one-time step; nothing else is read)
-----------------------------------------------
HITRAN 2016 (I. E. Gordon et al., JQSRT 203, 3-69, 2017) O2 lines,
12847-13339 cm^-1 (the b-X (0,0) A band and its (1,1) hot band; 16O2,
16O18O and 16O17O; 489 lines), in HITRAN's 160-character format, as
HITRANonline served them to HAPI in March 2019 (HITRAN data are free to use
with the citation above). The file is data/O2.data of the public repository
github.com/cminsky/CrossSection (MIT licence) at commit
5f968bc39f537ac318f67e215689b205470f8c79 (the file last changed in
db9003e99200550ecd8379e1bee7e7b546b402d3, 2019-03-06); its sha256 is
f95b8ae4526e2edb2e99b7af78f844579f58c156f87636bb7274aa4a04f2b35e (checked
below). Get it once, e.g.
    git clone https://github.com/cminsky/CrossSection && \
    git -C CrossSection show 5f968bc39f537ac318f67e215689b205470f8c79:data/O2.data > O2.data
and pass its path with --o2-lines (default target/lbl-lines/O2.data).

Partition sums: TIPS-2021 as shipped in HAPI, `pip install
hitran-api==1.3.0.0` (PyPI, MIT licence; hapi.partitionSum, no network).

Model
-----
- Atmosphere: U.S. Standard Atmosphere 1976 (NOAA-S/T 76-1562): its
  temperature lapse rates by geopotential height (0-86 km) and hydrostatic
  pressure from 1013.25 hPa, ideal gas; O2 a volume mixing ratio of 0.2095
  of the air. Layers 0-20 km by 1 km, 20-50 km by 2.5 km, 50-86 km as one;
  each layer's air column integrated on 20 sub-levels, its line-shape
  pressure and temperature the density-weighted means (Curtis-Godson).
  The air column above the ground is printed (2.15e25 cm^-2; sora's mixed
  gases hold one sea-level air column, 2.1484e25 cm^-2).
- Lines: HITRAN intensity at 296 K scaled to the layer's T with
  Q(296)/Q(T), the lower-state Boltzmann factor and the stimulated-emission
  factor; Lorentz half width gamma_air (p / 1013.25 hPa) (296 / T)^n_air
  (O2 is part of the air, so no self-broadening term); pressure shift
  delta_air p / 1013.25 hPa; Doppler half width from each isotopologue's
  mass. Voigt profile from the Faddeeva function w(z): Weideman's (1994,
  SIAM J. Numer. Anal. 31, 1497) rational series, N = 32, where
  |x| + y < 15, Humlicek's (1982) one-term asymptote beyond; the script
  checks both against a direct numerical convolution of a Gaussian and a
  Lorentzian and prints the largest error (relative to the profile's
  peak). Lines within 25 cm^-1 of the band's edges, each computed out to
  25 cm^-1 from its centre. No line mixing, no O2-O2 collision-induced
  absorption (sora has that as a separate species, `o2_o2`).
- Grid: 0.002 cm^-1, a sixth of the smallest Doppler half width (0.0120
  cm^-1: 16O2 at 12850 cm^-1 and 216.65 K), over each band.
- Path: a spherical shell of radius 6360 km (sora's Earth presets), no
  refraction: layer i's slant column is its vertical column times
  (sqrt(r2^2 - b^2) - sqrt(r1^2 - b^2)) / (r2 - r1), b = R cos(elevation).
  The direct-beam transmittance at wavenumber nu is
  exp(-sum_i m_i tau_i(nu)).
- Independent check (--check-hapi, measured): HAPI 1.3.0.0's own
  absorptionCoefficient_Voigt on the same lines gives the same optical
  depths over 760-770 nm in layers at 0-1, 12-13 and 32.5-35 km (within
  4.5e-6 of the peak; band-mean 1 - T equal to 5 decimals at air masses 1
  and 5). It needs O2.header beside O2.data (HAPI's column description,
  data/O2.header at the same commit, sha256
  251ae813bd86b6b86e7a7ba02155d021c47bd34c1ba8c6d88f8883a187bb2a0f).
- Band average: the mean over the band's wavelengths, uniform in
  wavelength (weight d lambda = d nu / nu^2), of that transmittance.
- Convergence (760-770 nm, suns 60 and 15 degrees; measured): a 0.001
  cm^-1 grid changes T by less than 3e-6, layers of 0.5 km to 20 km and 1 km
  to 50 km by less than 1e-5. The 25 cm^-1 line cut is a modelling choice
  (LBLRTM's): 50 cm^-1 of Lorentz wings would lower T by 0.0010 and
  0.0020, 0.3 % and 0.4 % of 1 - T (the A band's far wings are in fact
  sub-Lorentzian).

Bands: 755-765 and 765-775 nm (what samples at 760 and 770 nm on sora's
10 nm grid stand for) and 760-770 nm (the band's core); 740-760, 750-770,
760-780 and 770-790 nm (what one sample of a 20 nm grid stands for at 750,
760, 770 and 780 nm; the paper's grid, 380:780:20, has those at 760 and 780
nm). Suns 60 and 15 degrees. The reference is O2's alone: no H2O lines for
750-780 nm were at hand (sora's own water band model absorbs at most 0.16 %
of the direct beam there with 4 cm of water at air mass 3.86), so the
comparison leaves water out on both sides.

Run: target/python-venv/bin/python scripts/gases/make_lbl_reference.py
(numpy, scipy, hitran-api; about 40 s of CPU). With --curve-of-growth it also
prints, for 10 and 5 nm bands, the one band-model coefficient that fits the
line-by-line curve of growth best over air masses 1-8 and its largest
error (what a refit of sora's table alone could reach), and the largest
error of exponential sums fitted to each 10 nm band's T(m) (air mass
1-20) with the band's own weights (3-5 terms) and with sora's 5 shared
weights (needs scipy; printed, not written).
"""

import argparse
import hashlib
import pathlib

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
OUT = ROOT / "crates" / "sora" / "tests" / "data" / "gas_line_by_line_reference.csv"
K_TERMS_OUT = ROOT / "crates" / "sora" / "src" / "data" / "o2_a_band_k_terms.csv"
# The O2 A band's k-terms: 0.5 nm bins over 749.5-780 nm (the lines span
# 749.7-778.4 nm; the band model's O2 is 0 from 740 to 757.5 nm and from 780
# to 800 nm, so sora swaps the one for the other over this range only).
K_BINS_NM = (749.5, 780.0, 0.5)
# sora's unit of mixed-gas amount: one sea-level air column, cm^-2
# (AIR_MOLECULES_PER_M2_SEA_LEVEL_COLUMN).
SORA_AIR_COLUMN = 2.1484e25
O2_SHA256 = "f95b8ae4526e2edb2e99b7af78f844579f58c156f87636bb7274aa4a04f2b35e"

C2 = 1.4387769  # cm K, second radiation constant
K_B = 1.380649e-23  # J/K
AMU = 1.66053907e-27  # kg
C_LIGHT = 2.99792458e8  # m/s
P0_HPA = 1013.25
O2_VMR = 0.2095
EARTH_RADIUS_KM = 6360.0
GRID_STEP = 0.002  # cm^-1
WING = 25.0  # cm^-1
# 16O2, 16O18O, 16O17O (HITRAN local isotopologue ids 1, 2, 3)
O2_MASS = {1: 31.98983, 2: 33.994076, 3: 32.994045}

BANDS_NM = [(755.0, 765.0), (760.0, 770.0), (765.0, 775.0)]
# 20 nm bands: what one sample of a 20 nm grid stands for at 750, 760, 770
# and 780 nm (the paper's grid, 380:780:20, has samples at 760 and 780 nm).
WIDE_BANDS_NM = [(740.0, 760.0), (750.0, 770.0), (760.0, 780.0), (770.0, 790.0)]
SUN_ELEVATIONS_DEG = [60.0, 15.0]


# ---------------------------------------------------------------- atmosphere
# U.S. Standard Atmosphere 1976: base geopotential height (km), base
# temperature (K), lapse rate (K/km).
US76 = [
    (0.0, 288.15, -6.5),
    (11.0, 216.65, 0.0),
    (20.0, 216.65, 1.0),
    (32.0, 228.65, 2.8),
    (47.0, 270.65, 0.0),
    (51.0, 270.65, -2.8),
    (71.0, 214.65, -2.0),
    (84.852, 186.946, 0.0),
]
G0M_OVER_R = 9.80665 * 28.9644e-3 / 8.31432 * 1e3  # K/km (34.1632)
R_EARTH_GEOPOTENTIAL_KM = 6356.766


def us76(z_km):
    """Temperature (K) and pressure (hPa) at geometric height z (km)."""
    h = z_km * R_EARTH_GEOPOTENTIAL_KM / (R_EARTH_GEOPOTENTIAL_KM + z_km)
    p_base = P0_HPA
    for i, (hb, tb, lapse) in enumerate(US76):
        h_top = US76[i + 1][0] if i + 1 < len(US76) else np.inf
        dh = min(h, h_top) - hb
        if lapse == 0.0:
            p = p_base * np.exp(-G0M_OVER_R * dh / tb)
        else:
            p = p_base * (tb / (tb + lapse * dh)) ** (G0M_OVER_R / lapse)
        if h <= h_top:
            return tb + lapse * dh, p
        p_base = p
    raise AssertionError("unreachable")


def layers():
    """Each layer: (bottom km, top km, air column cm^-2, mean p hPa, mean T K)."""
    edges = list(np.arange(0.0, 20.0, 1.0)) + list(np.arange(20.0, 50.0, 2.5)) + [50.0, 86.0]
    out = []
    for z1, z2 in zip(edges[:-1], edges[1:]):
        z = np.linspace(z1, z2, 21)
        tp = np.array([us76(zz) for zz in z])
        t, p = tp[:, 0], tp[:, 1]
        n = p * 100.0 / (K_B * t) * 1e-6  # molecules cm^-3
        dz = (z[1] - z[0]) * 1e5  # cm
        weights = np.full(len(z), dz)
        weights[[0, -1]] *= 0.5
        column = float((n * weights).sum())
        out.append((z1, z2, column, float((p * n * weights).sum() / column),
                    float((t * n * weights).sum() / column)))
    return out


def slant_factors(layer_list, elevation_deg):
    """Each layer's slant column over its vertical column (spherical shell)."""
    b = EARTH_RADIUS_KM * np.cos(np.radians(elevation_deg))
    out = []
    for z1, z2, *_ in layer_list:
        r1, r2 = EARTH_RADIUS_KM + z1, EARTH_RADIUS_KM + z2
        out.append((np.sqrt(r2 * r2 - b * b) - np.sqrt(r1 * r1 - b * b)) / (r2 - r1))
    return np.array(out)


# ---------------------------------------------------------------- line shape
def _weideman_coefficients(n=32):
    m = 2 * n
    k = np.arange(-m + 1, m)
    length = np.sqrt(n / np.sqrt(2.0))
    t = length * np.tan(k * np.pi / (2 * m))
    f = np.concatenate([[0.0], np.exp(-t * t) * (length * length + t * t)])
    a = np.real(np.fft.fft(np.fft.fftshift(f))) / (2 * m)
    return length, np.flipud(a[1 : n + 1])


_WL, _WA = _weideman_coefficients()


def faddeeva(x, y):
    """w(x + i y) for y >= 0: Weideman N=32 near the core, Humlicek's asymptote far."""
    z = x + 1j * y
    out = np.empty(np.shape(x), dtype=complex)
    far = np.abs(x) + y >= 15.0
    t = y - 1j * x
    out[far] = (t[far] * 0.5641896) / (0.5 + t[far] * t[far])
    zc = z[~far]
    big_z = (_WL + 1j * zc) / (_WL - 1j * zc)
    p = np.polyval(_WA, big_z)
    out[~far] = 2.0 * p / (_WL - 1j * zc) ** 2 + (1.0 / np.sqrt(np.pi)) / (_WL - 1j * zc)
    return out


def voigt(dnu, alpha_d, gamma_l):
    """Area-normalised Voigt profile (cm) at dnu (cm^-1) from the centre."""
    s = np.sqrt(np.log(2.0)) / alpha_d
    return s / np.sqrt(np.pi) * faddeeva(dnu * s, np.full(np.shape(dnu), gamma_l * s)).real


def check_voigt():
    """Largest error of voigt() against a direct convolution, relative to the peak."""
    worst = 0.0
    for alpha_d, gamma_l in [(0.012, 0.0005), (0.012, 0.01), (0.012, 0.05), (0.012, 0.2)]:
        dnu = np.linspace(-2.0, 2.0, 801)
        u = np.linspace(-40 * alpha_d, 40 * alpha_d, 8001)
        du = u[1] - u[0]
        gauss = np.sqrt(np.log(2.0) / np.pi) / alpha_d * np.exp(-np.log(2.0) * (u / alpha_d) ** 2)
        lorentz = gamma_l / np.pi / ((dnu[:, None] - u[None, :]) ** 2 + gamma_l**2)
        slow = (gauss[None, :] * lorentz).sum(axis=1) * du
        fast = voigt(dnu, alpha_d, gamma_l)
        worst = max(worst, float(np.abs(fast - slow).max() / slow.max()))
    return worst


# ---------------------------------------------------------------- lines
def read_hitran(path):
    rows = []
    for line in pathlib.Path(path).read_text().splitlines():
        if len(line) < 67:
            continue
        rows.append((int(line[2:3]), float(line[3:15]), float(line[15:25]), float(line[35:40]),
                     float(line[45:55]), float(line[55:59]), float(line[59:67])))
    a = np.array(rows)
    return {
        "iso": a[:, 0].astype(int), "nu": a[:, 1], "s": a[:, 2], "gamma_air": a[:, 3],
        "elower": a[:, 4], "n_air": a[:, 5], "delta_air": a[:, 6],
    }


def optical_depths(lines, molecule, masses, nu, layer_list, vmr):
    """Vertical optical depth of each layer on the grid nu: array (layers, len(nu))."""
    import hapi  # TIPS partition sums

    lo, hi = nu[0] - WING, nu[-1] + WING
    keep = (lines["nu"] > lo) & (lines["nu"] < hi)
    ln = {k: v[keep] for k, v in lines.items()}
    print(f"  {keep.sum()} lines in {lo:.1f}-{hi:.1f} cm^-1")
    q296 = {i: hapi.partitionSum(molecule, i, 296.0) for i in masses}
    tau = np.zeros((len(layer_list), len(nu)))
    for li, (_, _, column, p, t) in enumerate(layer_list):
        q_ratio = np.array([q296[i] / hapi.partitionSum(molecule, i, t) for i in ln["iso"]])
        s = (ln["s"] * q_ratio
             * np.exp(-C2 * ln["elower"] / t) / np.exp(-C2 * ln["elower"] / 296.0)
             * (1 - np.exp(-C2 * ln["nu"] / t)) / (1 - np.exp(-C2 * ln["nu"] / 296.0)))
        mass = np.array([masses[i] for i in ln["iso"]]) * AMU
        alpha = ln["nu"] / C_LIGHT * np.sqrt(2 * np.log(2.0) * K_B * t / mass)
        gamma = ln["gamma_air"] * (p / P0_HPA) * (296.0 / t) ** ln["n_air"]
        centre = ln["nu"] + ln["delta_air"] * p / P0_HPA
        n_absorber = vmr * column
        for j in range(len(centre)):
            i0 = np.searchsorted(nu, centre[j] - WING)
            i1 = np.searchsorted(nu, centre[j] + WING)
            if i1 <= i0:
                continue
            tau[li, i0:i1] += s[j] * n_absorber * voigt(nu[i0:i1] - centre[j], alpha[j], gamma[j])
    return tau


def curve_of_growth_fits(lines, layer_list):
    """What a refit of the band model's coefficient could reach (printed only).

    For each band, the line-by-line band mean T(m) for a vertical path
    scaled by air masses m = 1-8 (plane parallel), and the one coefficient
    a_u for which the SPECTRL2 curve of growth T_u(a_u m) =
    exp(-1.41 y / (1 + 118.3 y)^0.45) comes closest to it (least largest
    error in units of 1 - T).
    """
    air_masses = np.array([1.0, 1.155, 1.5, 2.0, 3.0, 3.86, 5.0, 8.0])
    candidates = np.logspace(-3, 2, 4000)
    print("curve-of-growth fits (band model, one coefficient, air mass 1-8):")
    for lo_nm, hi_nm in [(755.0, 765.0), (760.0, 770.0), (765.0, 775.0), (757.5, 762.5),
                         (760.0, 765.0), (762.5, 767.5), (765.0, 770.0)]:
        nu = np.arange(1e7 / hi_nm, 1e7 / lo_nm, GRID_STEP)
        tau = optical_depths(lines, 7, O2_MASS, nu, layer_list, O2_VMR).sum(axis=0)
        weight = 1.0 / nu**2
        t = np.array([(np.exp(-m * tau) * weight).sum() / weight.sum() for m in air_masses])
        y = np.outer(candidates, air_masses)
        model = np.exp(-1.41 * y / (1 + 118.3 * y) ** 0.45)
        worst = (np.abs(model - t[None, :]) / (1 - t[None, :])).max(axis=1)
        best = int(np.argmin(worst))
        print(f"  {lo_nm:g}-{hi_nm:g} nm: 1 - T {np.round(1 - t, 4)}; a_u {candidates[best]:.4g}, "
              f"largest error {100 * worst[best]:.1f} % of 1 - T")
    print("exponential-sum fits of the 10 nm bands' T(m), air mass 1-20 (needs scipy):")
    for lo_nm, hi_nm in BANDS_NM:
        nu = np.arange(1e7 / hi_nm, 1e7 / lo_nm, GRID_STEP)
        tau = optical_depths(lines, 7, O2_MASS, nu, layer_list, O2_VMR).sum(axis=0)
        weight = 1.0 / nu**2
        m = np.logspace(0.0, np.log10(20.0), 60)
        t = np.array([(np.exp(-mm * tau) * weight).sum() / weight.sum() for mm in m])
        own = {n: exp_sum_fit(m, t, n, None) for n in (3, 4, 5)}
        shared = exp_sum_fit(m, t, 5, SORA_K_WEIGHTS)
        print(f"  {lo_nm:g}-{hi_nm:g} nm: the band's own weights: "
              + ", ".join(f"{n} terms {100 * e:.2f} %" for n, e in own.items())
              + f"; sora's 5 shared weights, the band's own k: {100 * shared:.2f} % of 1 - T")


def check_against_hapi(lines, layer_list, lines_dir):
    """Our layer optical depths against HAPI's own Voigt code (printed only).

    hapi.absorptionCoefficient_Voigt reads the same lines (the directory
    holding O2.data also needs O2.header, HAPI's description of its
    columns) with air broadening and the same 25 cm^-1 wing, for three
    layers over 760-770 nm; prints the band-mean 1 - T of each for air
    masses 1 and 5 and the largest relative difference of the optical depth.
    """
    import hapi

    hapi.db_begin(str(lines_dir))
    nu = np.arange(1e7 / 770.0, 1e7 / 760.0, GRID_STEP)
    weight = 1.0 / nu**2
    for index in (0, 12, 25):
        z1, z2, column, p, t = layer_list[index]
        ours = optical_depths(lines, 7, O2_MASS, nu, [layer_list[index]], O2_VMR)[0]
        _, coefficient = hapi.absorptionCoefficient_Voigt(
            SourceTables="O2", HITRAN_units=True, Environment={"p": p / P0_HPA, "T": t},
            Diluent={"air": 1.0}, WavenumberGrid=nu, WavenumberWing=WING)
        theirs = coefficient * O2_VMR * column
        band = [
            [1 - (np.exp(-m * tau) * weight).sum() / weight.sum() for tau in (ours, theirs)]
            for m in (1.0, 5.0)
        ]
        differs = np.abs(ours - theirs).max() / theirs.max()
        print(f"  layer {z1:g}-{z2:g} km ({p:.1f} hPa, {t:.1f} K): 1 - T ours/HAPI "
              f"{band[0][0]:.5f}/{band[0][1]:.5f} (m 1), {band[1][0]:.5f}/{band[1][1]:.5f} (m 5); "
              f"optical depth differs by {differs:.1e} of its peak")


# The weights of sora's k-terms (crates/sora/src/data/gas_bands_k_terms.csv).
SORA_K_WEIGHTS = np.array([0.4860725, 0.3700889, 0.1094314, 0.02870301, 0.00570418])


def exp_sum_fit(m, t, terms, weights):
    """Largest error, in units of 1 - T, of the best sum_j w_j exp(-k_j m) fit of t(m).

    weights None: the weights are fitted too; otherwise they are fixed.
    """
    from scipy.optimize import least_squares

    def model(p):
        if weights is None:
            w = np.exp(p[:terms])
            w, k = w / w.sum(), np.exp(p[terms:])
        else:
            w, k = weights, np.exp(p)
        return (w[None, :] * np.exp(-np.outer(m, k))).sum(axis=1)

    best = np.inf
    for trial in range(8):
        k0 = np.log(np.logspace(-4, 1.5, terms)) + np.random.default_rng(trial).normal(0, 0.5, terms) * (trial > 0)
        p0 = k0 if weights is not None else np.concatenate([np.zeros(terms), k0])
        r = least_squares(lambda p: (model(p) - t) / (1 - t), p0, max_nfev=5000)
        best = min(best, float(np.abs((model(r.x) - t) / (1 - t)).max()))
    return best


def bin_k_terms(tau_column, nu, lo_nm, hi_nm):
    """One bin's 5 weights and coefficients for its line-by-line T(M).

    T(M) is the bin's mean (uniform in wavelength) of exp(-M tau), tau the
    vertical column's optical depth, M = 1-20 (40 log-spaced points). The
    start is the bin's own k-distribution ranked into sora's shared weights'
    g-intervals (each interval's k matching its transmittance at M = 2);
    then least squares in log k of the error in units of max(1 - T, 0.001)
    with those weights, and from there with the weights fitted too (their
    logarithms relative to the first's). Returns (weights, k_j, both sorted
    by k; largest error of the shared weights' fit and of the bin's own, in
    units of max(1 - T, 0.001)).
    """
    from scipy.optimize import least_squares

    lam = 1e7 / nu
    keep = (lam >= lo_nm) & (lam < hi_nm)
    weight = 1.0 / nu[keep] ** 2
    weight /= weight.sum()
    order = np.argsort(tau_column[keep])
    k_sorted, w_sorted = tau_column[keep][order], weight[order]
    g = np.concatenate([[0.0], np.cumsum(w_sorted)])
    g_terms = np.concatenate([[0.0], np.cumsum(SORA_K_WEIGHTS)])
    start = []
    for j in range(len(SORA_K_WEIGHTS)):
        overlap = np.clip(np.minimum(g[1:], g_terms[j + 1]) - np.maximum(g[:-1], g_terms[j]), 0, None)
        inside = overlap > 0
        x = -2.0 * k_sorted[inside]
        top = x.max()
        t = (overlap[inside] * np.exp(x - top)).sum() / overlap.sum()
        start.append(max(-(top + np.log(t)) / 2.0, 1e-12))
    m = np.logspace(0.0, np.log10(20.0), 40)
    t = np.array([(np.exp(-mm * tau_column[keep]) * weight).sum() for mm in m])
    scale = np.maximum(1.0 - t, 1e-3)

    def residual(p):
        k = np.exp(np.sort(p))
        return ((SORA_K_WEIGHTS[None, :] * np.exp(-np.outer(m, k))).sum(axis=1) - t) / scale

    shared = least_squares(residual, np.log(start), max_nfev=4000)
    terms = len(SORA_K_WEIGHTS)

    def unpack(p):
        w = np.concatenate([[1.0], np.exp(p[: terms - 1])])
        return w / w.sum(), np.exp(p[terms - 1 :])

    def own_residual(p):
        w, k = unpack(p)
        return ((w[None, :] * np.exp(-np.outer(m, k))).sum(axis=1) - t) / scale

    p0 = np.concatenate([np.log(SORA_K_WEIGHTS[1:] / SORA_K_WEIGHTS[0]), np.sort(shared.x)])
    own = least_squares(own_residual, p0, max_nfev=8000)
    w, k = unpack(own.x)
    by_k = np.argsort(k)
    return (w[by_k], k[by_k], float(np.abs(residual(shared.x)).max()),
            float(np.abs(own_residual(own.x)).max()))


def write_k_terms(lines, layer_list, air_column):
    """The O2 A band's k-terms per 0.5 nm bin (crates/sora/src/data/o2_a_band_k_terms.csv)."""
    lo_nm, hi_nm, step = K_BINS_NM
    nu = np.arange(1e7 / hi_nm, 1e7 / lo_nm, GRID_STEP)
    tau = optical_depths(lines, 7, O2_MASS, nu, layer_list, O2_VMR).sum(axis=0)
    # Per molecule of air: sora's column holds SORA_AIR_COLUMN molecules.
    tau_sora = tau * SORA_AIR_COLUMN / air_column
    edges = np.arange(lo_nm, hi_nm + 0.5 * step, step)
    rows, worst_shared, worst = [], 0.0, 0.0
    for a, b in zip(edges[:-1], edges[1:]):
        w, k, error_shared, error = bin_k_terms(tau_sora, nu, a, b)
        worst_shared = max(worst_shared, error_shared)
        worst = max(worst, error)
        rows.append((a, b, w, k))
    print(f"k-terms: {len(rows)} bins of {step:g} nm, largest fit error {100 * worst:.3f} % of "
          f"max(1 - T, 0.001) (with sora's shared weights {100 * worst_shared:.2f} %)")
    header = (
        "# The O2 A band's k-terms: for each 0.5 nm bin (uniform in wavelength), 5 weights w_j (summing to 1) "
        f"and coefficients k_j, per sora sea-level air column ({SORA_AIR_COLUMN:.4e} molecules cm^-2; the "
        "line-by-line optical depth per molecule of air), fitted together to the bin's line-by-line T(M) = mean "
        "exp(-M tau) of the vertical U.S. Standard Atmosphere 1976 column scaled by M = 1-20 (least squares in "
        f"units of max(1 - T, 0.001); largest error {100 * worst:.3f} %; with sora's 5 shared weights "
        f"(data/gas_bands_k_terms.csv) it would be {100 * worst_shared:.2f} %). Lines, layers and line shapes as in "
        "tests/data/gas_line_by_line_reference.csv (HITRAN 2016 O2, sha256 " + O2_SHA256 + "). Written by "
        "scripts/gases/make_lbl_reference.py.\n"
    )
    body = "lo_nm,hi_nm,w1,w2,w3,w4,w5,k1,k2,k3,k4,k5\n" + "".join(
        f"{a:g},{b:g}," + ",".join(f"{v:.6e}" for v in np.concatenate([w, k])) + "\n"
        for a, b, w, k in rows
    )
    K_TERMS_OUT.write_text(header + body)
    print(f"wrote {K_TERMS_OUT.relative_to(ROOT)}")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--o2-lines", default=str(ROOT / "target" / "lbl-lines" / "O2.data"))
    parser.add_argument("--check-hapi", action="store_true",
                        help="also compare three layers' optical depths with HAPI's Voigt code")
    parser.add_argument("--curve-of-growth", action="store_true",
                        help="also print the best one-coefficient band-model fits (not written)")
    args = parser.parse_args()
    digest = hashlib.sha256(pathlib.Path(args.o2_lines).read_bytes()).hexdigest()
    if digest != O2_SHA256:
        raise SystemExit(f"{args.o2_lines}: sha256 {digest}, expected {O2_SHA256}")
    voigt_error = check_voigt()
    print(f"Voigt approximation: largest error {voigt_error:.2e} of the peak")
    layer_list = layers()
    air_column = sum(layer[2] for layer in layer_list)
    print(f"{len(layer_list)} layers, air column {air_column:.5e} cm^-2")
    lines = read_hitran(args.o2_lines)
    rows = []
    for lo_nm, hi_nm in BANDS_NM + WIDE_BANDS_NM:
        nu = np.arange(1e7 / hi_nm, 1e7 / lo_nm, GRID_STEP)
        print(f"{lo_nm:g}-{hi_nm:g} nm: {len(nu)} points")
        tau = optical_depths(lines, 7, O2_MASS, nu, layer_list, O2_VMR)
        weight = 1.0 / nu**2
        vertical = float((np.exp(-tau.sum(axis=0)) * weight).sum() / weight.sum())
        for elevation in SUN_ELEVATIONS_DEG:
            m = slant_factors(layer_list, elevation)
            t = float((np.exp(-(m[:, None] * tau).sum(axis=0)) * weight).sum() / weight.sum())
            rows.append((lo_nm, hi_nm, elevation, float(m[0]), t))
            print(f"  sun {elevation:g}: T = {t:.5f} (1 - T = {1 - t:.5f}); vertical T = {vertical:.5f}")
    header = (
        "# Line-by-line direct-beam transmittance of the O2 A band, band-averaged over 10 and 20 nm (uniform in "
        "wavelength), written by scripts/gases/make_lbl_reference.py from HITRAN 2016 O2 lines "
        "(Gordon et al. 2017, JQSRT 203, 3; 12847-13339 cm^-1, data/O2.data of github.com/cminsky/CrossSection "
        f"at 5f968bc39f537ac318f67e215689b205470f8c79, sha256 {O2_SHA256}) and HAPI 1.3.0.0's TIPS-2021 partition "
        "sums, through the U.S. Standard Atmosphere 1976 (O2 0.2095 of the air; "
        f"{len(layer_list)} layers to 86 km; air column {air_column:.4e} cm^-2), Voigt lines (Weideman N=32; "
        f"largest error {voigt_error:.1e} of the peak) to 25 cm^-1, grid 0.002 cm^-1, spherical shell of radius "
        "6360 km without refraction. No line mixing, no O2-O2 CIA, no H2O: O2 alone.\n"
        "# air_mass_ground: the slant factor of the lowest layer (the geometric air mass at the ground).\n"
    )
    body = "band_lo_nm,band_hi_nm,gas,sun_elevation_deg,air_mass_ground,transmittance\n" + "".join(
        f"{lo:g},{hi:g},O2,{e:g},{m:.5f},{t:.6f}\n" for lo, hi, e, m, t in rows
    )
    OUT.write_text(header + body)
    print(f"wrote {OUT.relative_to(ROOT)}")
    write_k_terms(lines, layer_list, air_column)
    if args.check_hapi:
        check_against_hapi(lines, layer_list, pathlib.Path(args.o2_lines).parent)
    if args.curve_of_growth:
        curve_of_growth_fits(lines, layer_list)


if __name__ == "__main__":
    main()
