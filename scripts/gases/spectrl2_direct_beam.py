#!/usr/bin/env python3
"""The direct normal irradiance of `earth-clear-summer` from SPECTRL2's
band model evaluated spectrally: an independent reference for sora's
direct beam at suns 10-90 degrees.

Why: pvlib's broadband clear-sky models (Bird, simplified Solis) differ
from each other by 13 % in the direct normal irradiance with the sun 10
degrees high (docs/spectrum.md), so neither can judge sora's there. This
script computes the direct beam the way a spectral code does, with the
transmittance formulas of Bird & Riordan (1986, SPECTRL2, as pvlib 0.13.1
implements them: `pvlib.spectrum.spectrl2`, its coefficient table
`_SPECTRL2_COEFFS`; BSD 3-clause), none of sora's code:

- Rayleigh: tau = 1 / (lambda_um^4 (115.6406 - 1.3366 / lambda_um^2)), at
  sora's wavelength samples;
- aerosol: exp(-tau_a(lambda) m_a), tau_a the preset's aerosol optical
  depth at each sample as `sora atmosphere show` prints it (the input both
  models are given; Bird and Solis take it at 380/500 and 700 nm only);
- water, ozone and the mixed gases: SPECTRL2's band formulas (its Eq.
  2-8, 2-9, 2-11) with its coefficients interpolated linearly onto a
  0.5 nm grid and the transmittance averaged over each sample's 10 nm
  band (a sora sample stands for its band: docs/spectrum.md), 2.92 cm of
  water, 300 DU of ozone, 1013.25 hPa;
- air masses: each profile's own in a spherical shell (R = 6371 km, no
  refraction, as sora's direct beam): the air's and the mixed gases'
  exponential of 8435 m, water's of 2000 m, the aerosol's of 1200 m,
  ozone's tent (peak 25 km, half width 15 km), integrated along the slant
  path (300,001 points over 1500 km);
- the sun: sora's own band means (its direct normal irradiance over its
  transmittance at each sample), so that only the atmosphere differs.

What it leaves out that sora has: O2-O2 collision-induced absorption
(0.9 % of the direct beam at sun 10, 0.13 % at 90), NO2 and the O2 A band
from line data (SPECTRL2's A band absorbs less: docs/spectrum.md).

Writes crates/sora-cli/tests/data/spectrl2_direct_beam_earth_clear_summer.csv
(sun_elevation_deg, dni_w_m2 over 300-2500 nm), which
crates/sora-cli/tests/pvlib_clearsky_cli.rs compares sora with.

Run (from the repository root, a release build of sora):
    pip install pvlib==0.13.1
    python3 scripts/gases/spectrl2_direct_beam.py target/release/sora
"""

import csv
import importlib
import io
import pathlib
import subprocess
import sys

import numpy as np
import pvlib

ROOT = pathlib.Path(__file__).resolve().parents[2]
ATMOSPHERE = ROOT / "atmospheres/earth-clear-summer.toml"
WATER_CM, OZONE_ATM_CM = 2.92, 0.3
RADIUS_M = 6371e3
SCALE_HEIGHTS_M = {"air": 8435.0, "water": 2000.0, "aerosol": 1200.0}
OZONE_TENT_M = (25e3, 15e3)


def slant_path(elevation_deg):
    """Distances along the path (m) and the altitudes there (m)."""
    s = np.linspace(0.0, 1500e3, 300001)
    mu = np.sin(np.radians(elevation_deg))
    return s, np.sqrt(RADIUS_M**2 + s * s + 2 * RADIUS_M * s * mu) - RADIUS_M


def air_mass(elevation_deg, density_at, vertical_column_m):
    s, h = slant_path(elevation_deg)
    return np.trapezoid(density_at(h), s) / vertical_column_m


def run_sora(sora, args):
    return subprocess.run(
        [sora, *args], check=True, capture_output=True, text=True
    ).stdout


def main():
    sora = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "target/release/sora")
    coeffs = importlib.import_module("pvlib.spectrum.spectrl2")._SPECTRL2_COEFFS
    wl = coeffs["wavelength"]
    shown = csv.DictReader(io.StringIO(
        run_sora(sora, ["atmosphere", "show", "--atmosphere", str(ATMOSPHERE),
                        "--wavelengths", "300:2500:10", "--format", "csv"])
    ))
    aerosol = np.array([(float(r["wavelength_nm"]), float(r["tau_extinction"]))
                        for r in shown if r["species"] == "continental aerosol"])
    fine = np.arange(295.0, 2505.01, 0.5)
    a_water = np.interp(fine, wl, coeffs["water_vapor_absorption"])
    a_mixed = np.interp(fine, wl, coeffs["mixed_absorption"])
    a_ozone = np.interp(fine, wl, coeffs["ozone_absorption"])
    rows = []
    for elevation in range(10, 91, 10):
        beam = np.genfromtxt(
            io.StringIO(
                run_sora(sora, ["irradiance", "--atmosphere", str(ATMOSPHERE),
                                "--sun-elevation", str(elevation), "--broadband",
                                "--scattering", "single", "--polarisation", "scalar"])
            ),
            delimiter=",", names=True,
        )
        lam, t_sora = beam["wavelength_nm"], beam["direct_beam_transmittance"]
        sun = np.where(t_sora > 0, beam["direct_normal_irradiance_w_m2_nm"]
                       / np.where(t_sora > 0, t_sora, 1.0), 0.0)
        m = {k: air_mass(elevation, lambda h, H=H: np.exp(-h / H), H)
             for k, H in SCALE_HEIGHTS_M.items()}
        peak, half = OZONE_TENT_M
        m["ozone"] = air_mass(elevation, lambda h: np.clip(1 - abs(h - peak) / half, 0, None), half)
        um = lam / 1000.0
        t_rayleigh = np.exp(-m["air"] / (um**4 * (115.6406 - 1.3366 / um**2)))
        t_aerosol = np.exp(-np.interp(lam, aerosol[:, 0], aerosol[:, 1]) * m["aerosol"])
        awm = a_water * WATER_CM * m["water"]
        am = a_mixed * m["air"]
        t_gases = (np.exp(-0.2385 * awm / (1 + 20.07 * awm) ** 0.45)
                   * np.exp(-1.41 * am / (1 + 118.3 * am) ** 0.45)
                   * np.exp(-a_ozone * OZONE_ATM_CM * m["ozone"]))
        t_band = np.array([t_gases[(fine >= l - 5) & (fine <= l + 5)].mean() for l in lam])
        dni = np.sum(sun * t_rayleigh * t_aerosol * t_band) * 10.0
        rows.append((elevation, dni, np.sum(sun * t_sora) * 10.0))
        print(f"sun {elevation}: SPECTRL2 spectral {dni:.2f} W m^-2, sora {rows[-1][2]:.2f} "
              f"({rows[-1][2] / dni - 1:+.2%})")
    out = ROOT / "crates/sora-cli/tests/data/spectrl2_direct_beam_earth_clear_summer.csv"
    lines = [
        f"# SPECTRL2's band model (pvlib {pvlib.__version__}) evaluated spectrally for "
        "atmospheres/earth-clear-summer.toml: direct normal irradiance over 300-2500 nm "
        "(written by scripts/gases/spectrl2_direct_beam.py; inputs in its docstring)",
        "sun_elevation_deg,dni_w_m2",
    ] + [f"{e},{d:.2f}" for e, d, _ in rows]
    out.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
