#!/usr/bin/env python3
"""Generates crates/sora/src/data/ozone_cross_section_233K_10nm_bogumil2003.csv.

One-time source (nothing else is read): the Bogumil et al. (2003) ozone
absorption cross-sections (SCIAMACHY pre-flight model, IUP Bremen; J.
Photochem. Photobiol. A 157, 167-184, doi:10.1016/S1010-6030(03)00062-5) in the
quadratic temperature form libRadtran distributes as data/crs/crs_O3_UBremen_cf.dat:

    sigma(T) = (C0 + C1 (T - 273.15) + C2 (T - 273.15)^2) 1e-20 cm^2

on 230.0-1066.2 nm (air) every 0.1 nm. The copy read is the one in the public
repository github.com/hygeos/smartg, tools/profile/crs_O3_UBremen_cf.dat at
commit 447611d0390ecf455dd2ffb60ef105c6cfb28d14 (502161 bytes, sha256
ad6d4215c1abc4b0561c3210aa4500ec34d7a8b06652736c9a42daa35fed1f73), e.g.

    git clone https://github.com/hygeos/smartg && cd smartg
    git show 447611d0390ecf455dd2ffb60ef105c6cfb28d14:tools/profile/crs_O3_UBremen_cf.dat > crs_O3_UBremen_cf.dat

Processing: sigma at T = 233 K from the quadratic; air wavelengths to vacuum
with the Edlen (1966) dispersion of standard air; the mean over each 10 nm bin
[lambda, lambda + 10) (vacuum) of the piecewise-linear curve through the 0.1 nm
points (trapezoidal integral over the bin width), rounded to 4 significant
digits. Bins 270-350 nm (the Hartley band's long-wave edge and the Huggins
band) and 840-1060 nm (the Wulf band; the 1060 nm bin averages the data to
their end, 1066.49 nm vacuum); 1070-1100 nm are written as 0 (no data). The
bins 360-830 nm come from Serdyuchenko et al. (2014) in another file.

Run: python3 scripts/gases/make_ozone_bogumil2003.py crs_O3_UBremen_cf.dat  (needs numpy)
"""

import pathlib
import sys

import numpy as np

OUT = (
    pathlib.Path(__file__).resolve().parents[2]
    / "crates/sora/src/data/ozone_cross_section_233K_10nm_bogumil2003.csv"
)

HEADER = """\
# Ozone absorption cross-section at 233 K, m^2 per molecule, bin-averaged over [lambda, lambda + 10) nm (vacuum), for the bins that the Serdyuchenko table (ozone_cross_section_233K_10nm.csv, 360-840 nm) does not cover: 270-360 nm (the Hartley band's long-wave edge and the Huggins band) and 840-1110 nm (Wulf band). Written by scripts/gases/make_ozone_bogumil2003.py.
# Data: Bogumil et al. (2003), SCIAMACHY pre-flight model O3 cross-sections (the file's header: K. Bogumil, J. Orphal and J. P. Burrows, IUP Bremen), J. Photochem. Photobiol. A 157, 167-184, doi:10.1016/S1010-6030(03)00062-5, in the quadratic temperature form distributed with libRadtran as data/crs/crs_O3_UBremen_cf.dat: sigma(T) = (C0 + C1 (T - 273.15) + C2 (T - 273.15)^2) * 1e-20 cm^2 on 230.0-1066.2 nm (air) every 0.1 nm. Copied from github hygeos/smartg tools/profile/crs_O3_UBremen_cf.dat at commit 447611d0390ecf455dd2ffb60ef105c6cfb28d14 (502161 bytes), identical in form to libRadtran's.
# Serdyuchenko/Gorshelev et al. 2014 (the source of the 360-840 nm table) also covers 213-1100 nm, but no copy of its data file could be obtained for this table (every public copy found is over the size the project's tools can fetch); Bogumil et al. 2003 is the same laboratory's earlier published data set.
# Processing: sigma at T = 233 K from the quadratic; air wavelengths to vacuum with the Edlen (1966) dispersion of standard air; the mean over each bin of the piecewise-linear curve through the 0.1 nm points (trapezoidal integral / bin width), rounded to 4 significant digits. The 1060 nm bin averages the data up to their end, 1066.49 nm (vacuum).
# Bins 1070-1100 nm: no data (the data end at 1066.49 nm); the cross-section is taken as 0 there. The data between 1000 and 1066 nm average 1.8e-28 m^2 (at most 8.1e-28 m^2 at one point, the measurement noise of the weakest part of the Wulf band): for 300 DU (8.06e22 m^-2) that is a vertical optical depth of 1.5e-5 (at most 6.5e-5), the size of the error made by the zeros.
# Where the two data sets overlap (360-840 nm, not used from this one) Bogumil's 233 K bins are 1.021-1.075 times Serdyuchenko's between 440 and 810 nm, 1.06-1.09 times at 400-430 nm, and 0.91-1.26 times in the weakest bins (360-390 and 820-830 nm), where 300 DU have a vertical optical depth below 2e-3: the seams at 360 and 840 nm join two measurements that differ by a few per cent.
wavelength_nm,ozone_cross_section_m2
"""


def edlen_refractive_index(wavelength_nm):
    """Standard air's refractive index (Edlen 1966), at the given wavelength."""
    s2 = (1e3 / wavelength_nm) ** 2  # wavenumber squared, um^-2
    return 1.0 + 1e-8 * (8342.13 + 2406030.0 / (130.0 - s2) + 15997.0 / (38.9 - s2))


def main():
    data = np.loadtxt(sys.argv[1], comments="#")
    air_nm, c0, c1, c2 = data.T
    dt = 233.0 - 273.15
    sigma_m2 = (c0 + c1 * dt + c2 * dt * dt) * 1e-20 * 1e-4
    vacuum_nm = air_nm * edlen_refractive_index(air_nm)

    def bin_mean(lo, hi):
        hi = min(hi, vacuum_nm[-1])
        inside = vacuum_nm[(vacuum_nm > lo) & (vacuum_nm < hi)]
        x = np.concatenate(([lo], inside, [hi]))
        y = np.interp(x, vacuum_nm, sigma_m2)
        return np.trapezoid(y, x) / (hi - lo)

    rows = [(lo, "%.4g" % bin_mean(lo, lo + 10)) for lo in range(270, 360, 10)]
    rows += [(lo, "%.4g" % bin_mean(lo, lo + 10)) for lo in range(840, 1070, 10)]
    rows += [(lo, "0") for lo in range(1070, 1110, 10)]
    OUT.write_text(HEADER + "".join(f"{lo},{value}\n" for lo, value in rows))
    print(f"wrote {OUT} ({len(rows)} bins)")


if __name__ == "__main__":
    main()
