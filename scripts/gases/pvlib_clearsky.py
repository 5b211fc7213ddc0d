#!/usr/bin/env python3
"""pvlib's clear-sky broadband irradiance for sora's `earth-clear-summer`.

Computes, once, pvlib's Bird (Bird & Hulstrom 1981) and simplified Solis
(Ineichen 2008) clear-sky models for the atmosphere of
atmospheres/earth-clear-summer.toml, for suns 10-90 degrees high, and writes
crates/sora-cli/tests/data/pvlib_clearsky_earth_clear_summer.csv:
sun_elevation_deg, then GHI, DNI and DHI (W m^-2) of each model.

Inputs (the preset's; the aerosol optical depths are sora's own, from
`sora atmosphere show --atmosphere atmospheres/earth-clear-summer.toml
--wavelengths 380:700:20 --format csv`, species "continental aerosol"):
- aerosol optical depth 0.1636 at 380 nm, 0.1150 at 500 nm, 0.0676 at 700 nm
- precipitable water 2.92 cm, ozone 300 DU (0.3 atm-cm), 1013.25 hPa
- ground albedo 0.1 (Bird only; its forward-scattering fraction the default 0.85)
- extraterrestrial normal irradiance 1366.1 W m^-2 (ASTM E490, sora's sun;
  sora's broadband values integrate only its grid, e.g. 300-2500 nm, which
  holds about 96 % of it)
- relative air mass: Kasten & Young (1989) of the true zenith angle.

Run: pip install pvlib==0.13.1 && python3 scripts/gases/pvlib_clearsky.py
(pvlib: BSD 3-clause).
"""

import pathlib

import numpy as np
import pvlib

AOD380, AOD500, AOD700 = 0.1636, 0.1150, 0.0676
WATER_CM, OZONE_ATM_CM, PRESSURE_PA = 2.92, 0.3, 101325.0
ALBEDO, DNI_EXTRA = 0.1, 1366.1

elevations = np.arange(10.0, 91.0, 10.0)
zenith = 90.0 - elevations
airmass = pvlib.atmosphere.get_relative_airmass(zenith, model="kastenyoung1989")
bird = pvlib.clearsky.bird(
    zenith,
    airmass,
    AOD380,
    AOD500,
    WATER_CM,
    ozone=OZONE_ATM_CM,
    pressure=PRESSURE_PA,
    dni_extra=DNI_EXTRA,
    albedo=ALBEDO,
)
solis = pvlib.clearsky.simplified_solis(
    elevations,
    aod700=AOD700,
    precipitable_water=WATER_CM,
    pressure=PRESSURE_PA,
    dni_extra=DNI_EXTRA,
)
out = pathlib.Path(__file__).resolve().parents[2] / "crates/sora-cli/tests/data"
lines = [
    f"# pvlib {pvlib.__version__} clear-sky models for atmospheres/earth-clear-summer.toml "
    "(written by scripts/gases/pvlib_clearsky.py; inputs in its docstring)",
    "sun_elevation_deg,bird_ghi_w_m2,bird_dni_w_m2,bird_dhi_w_m2,"
    "solis_ghi_w_m2,solis_dni_w_m2,solis_dhi_w_m2",
]
for i, e in enumerate(elevations):
    lines.append(
        f"{e:g},{bird['ghi'][i]:.2f},{bird['dni'][i]:.2f},{bird['dhi'][i]:.2f},"
        f"{solis['ghi'][i]:.2f},{solis['dni'][i]:.2f},{solis['dhi'][i]:.2f}"
    )
(out / "pvlib_clearsky_earth_clear_summer.csv").write_text("\n".join(lines) + "\n")
print("\n".join(lines))
