"""Cut the shipped subset of Kider et al. (2014)'s sky scans out of their archive.

    python scripts/measured_skies/extract_kider2014.py ARCHIVE_DIR OUT_DIR

ARCHIVE_DIR holds the unpacked RADIANCE archives of
github.com/spectralskylight/sky-measurements-2014 (commit f915674f, e.g.
`data/2013-05-27/RADIANCE/2013-05-27___12.00.00.7z` unpacked with 7-Zip or
py7zr into `2013-05-27___12.00.00/`). Each folder has one ASD text file per
direction, named `<date>___<time>_-_<index>____<azimuth>___<altitude>.asd.rad.txt`,
with the spectral radiance in W m^-2 sr^-1 nm^-1 every 1 nm from 350 to 2500 nm.

For each capture in CAPTURES this writes OUT_DIR/<capture>.csv: one row per
direction (the archive's 81), with

- `index`: the archive's sample index (0-80),
- `view_elevation_deg`: the archive's altitude,
- `file_azimuth_deg`: the archive's azimuth, as in the file name,
- `view_azimuth_deg`: sora's azimuth (clockwise from north), 360 - file azimuth
  modulo 360 (the archive counts its azimuth the other way: docs/measured-skies.md,
  "Directions", says how this was established),
- `L360` ... `L1100`: the mean radiance over each 10-nm box centred on the
  wavelength (trapezoid over the box's 11 1-nm samples, W m^-2 sr^-1 nm^-1,
  4 significant digits): what sora's `--wavelengths 360:1100:10` grid computes,
  a band mean per grid point.

The spectroradiometer (an ASD FieldSpec; 3 nm resolution at 700 nm) covers
350-2500 nm; the subset keeps 355-1105 nm (10-nm boxes from 360 to 1100 nm), the range of Kider et al.'s comparison does.
"""

import pathlib
import re
import sys

import numpy as np

CAPTURES = ["2013-05-27___12.00.00", "2013-09-24___13.10.00"]
CENTRES_NM = np.arange(360, 1101, 10)
NAME = re.compile(r"_-_(\d+)____([0-9.]+)___([0-9.]+)\.asd\.rad\.txt$")


def box_mean(wavelength, radiance, centre):
    """Trapezoid mean of a 1-nm spectrum over [centre - 5, centre + 5] nm."""
    inside = (wavelength >= centre - 5) & (wavelength <= centre + 5)
    w, r = wavelength[inside], radiance[inside]
    if w.size != 11:
        raise ValueError(f"{centre} nm: the box has {w.size} samples, not 11")
    return np.trapezoid(r, w) / 10.0


def main():
    archive, out = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    out.mkdir(parents=True, exist_ok=True)
    for capture in CAPTURES:
        rows = []
        for path in (archive / capture).glob("*.asd.rad.txt"):
            m = NAME.search(path.name)
            if m is None:
                raise ValueError(f"{path.name}: not an ASD radiance file name")
            index, file_az, elevation = int(m[1]), float(m[2]), float(m[3])
            data = np.loadtxt(path, skiprows=1)
            means = [box_mean(data[:, 0], data[:, 1], c) for c in CENTRES_NM]
            rows.append((index, elevation, file_az, (360.0 - file_az) % 360.0, means))
        rows.sort()
        if [r[0] for r in rows] != list(range(81)):
            raise ValueError(f"{capture}: expected the 81 indices 0-80")
        lines = [
            f"# Kider et al. (2014), github.com/spectralskylight/sky-measurements-2014 (Apache-2.0),",
            f"# capture {capture} (local time, EDT = UTC-4); see crates/sora-cli/tests/data/measured/README.md",
            "index,view_elevation_deg,file_azimuth_deg,view_azimuth_deg,"
            + ",".join(f"L{c}" for c in CENTRES_NM),
        ]
        for index, elevation, file_az, az, means in rows:
            values = ",".join(f"{v:.4g}" for v in means)
            lines.append(f"{index},{elevation:g},{file_az:g},{az:g},{values}")
        (out / f"{capture.replace('___', '_').replace('.', '')}.csv").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
