"""The paper's Table 1 sky spectrum, single and multiple scattering, from
Python (a notebook-style script: run it cell by cell or whole).

    python examples/paper_table1.py [OUT.png]

Prints the two spectra and, where matplotlib is installed (``pip install
'./crates/sora-python[plot]'``), plots them into OUT.png (default
python_table1_spectrum.png in the current directory; the repository's
picture of this spectrum, docs/table1_spectrum.png, is drawn by the Rust
example paper_figures, not by this script). The geometry is
the paper's Table 1: sun 36 deg up at azimuth 207, view 17 deg up at
azimuth 347, atmosphere ``paper-earth``, scalar light as the paper's (the
polarised intensity, sora's default, is 1-3 % lower here).
"""

# %% The sky, twice: the paper's single scattering, and all orders.
import pathlib
import sys

import numpy as np

import sora

atmosphere = sora.Atmosphere.preset("paper-earth")
geometry = dict(sun_elevation_deg=36.0, sun_azimuth_deg=207.0, wavelengths_nm="380:780:20", polarisation="scalar")
single = sora.Sky(atmosphere, scattering="single", **geometry).radiance(17.0, 347.0).isel(direction=0)
multiple = sora.Sky(atmosphere, scattering="multiple", **geometry).radiance(17.0, 347.0).isel(direction=0)

# %% The numbers.
print("wavelength_nm  single_W_m2_sr_nm  multiple_W_m2_sr_nm  multiple/single")
for nm, s, m in zip(single.wavelength.values, single.values, multiple.values):
    print(f"{nm:13.0f}  {s:17.6e}  {m:19.6e}  {m / s:15.3f}")
print(f"peak: single at {float(single.idxmax()):.0f} nm, multiple at {float(multiple.idxmax()):.0f} nm")

# %% The plot (only where matplotlib is installed).
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    sys.exit("matplotlib is not installed: no plot (pip install './crates/sora-python[plot]')")

out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path("python_table1_spectrum.png")
figure, axes = plt.subplots(figsize=(7, 4.2), dpi=110)
axes.plot(single.wavelength, single, "--o", ms=3, label="single scattering (the paper's model)")
axes.plot(multiple.wavelength, multiple, "-o", ms=3, label="all orders of scattering")
axes.set_xlabel(f"wavelength ({single.wavelength.attrs['units']})")
axes.set_ylabel(f"spectral radiance ({single.attrs['units']})")
axes.set_title("paper-earth, Table 1: sun 36° up at 207°, view 17° up at 347°", fontsize=10)
axes.set_ylim(bottom=0)
axes.grid(alpha=0.3)
axes.legend()
figure.tight_layout()
figure.savefig(out)
print(f"wrote {out}")
