"""The blue aureole of a Martian sunset, from Python (a notebook-style
script): the radiance of the sky above the setting sun against the angle
from it, at a blue and a red wavelength.

    python examples/mars_aureole.py [OUT.png]

Mars's dust (particles ~1.5 um, absorbing in the blue) scatters blue light
into a narrower forward peak than red, so near the sun the sky is bluer
than the sun itself, and the ratio of blue to red radiance, relative to the
sun's direct beam, exceeds 1 within a few degrees of it and falls below 1
farther out (the dusty sky's butterscotch). Prints the ratio; plots the
curves into OUT.png where matplotlib is installed (``pip install
'./crates/sora-python[plot]'``; default python_mars_aureole.png in the
current directory; the repository's docs/python_mars_aureole.png is this
script's plot). Scalar light, as the numbers of docs/README.md.
"""

# %% The sky of mars-dust with the sun 3 deg above the western horizon.
import pathlib
import sys

import numpy as np

import sora

sun_elevation_deg, sun_azimuth_deg = 3.0, 270.0
sky = sora.Sky(
    sora.Atmosphere.preset("mars-dust"),
    sun_elevation_deg=sun_elevation_deg,
    sun_azimuth_deg=sun_azimuth_deg,
    wavelengths_nm="440:700:20",
    polarisation="scalar",
)

# %% The sun's vertical: from 0.5 deg above the sun to 80 deg, one call.
angle_deg = np.concatenate([np.arange(0.5, 10.0, 0.5), np.arange(10.0, 81.0, 2.5)])
radiance = sky.radiance(sun_elevation_deg + angle_deg, sun_azimuth_deg)
radiance = radiance.assign_coords(angle_from_sun_deg=("direction", angle_deg, {"units": "deg"}))
blue, red = radiance.sel(wavelength=440.0), radiance.sel(wavelength=700.0)
sun = sky.direct_normal_irradiance()
sun_ratio = float(sun.sel(wavelength=440.0) / sun.sel(wavelength=700.0))
ratio = (blue / red) / sun_ratio

# %% The numbers.
print("angle_from_sun_deg  L440_W_m2_sr_nm  L700_W_m2_sr_nm  (L440/L700)/(E440/E700 of the sun)")
for a, b, r, q in zip(angle_deg, blue.values, red.values, ratio.values):
    print(f"{a:18.1f}  {b:15.4e}  {r:15.4e}  {q:10.3f}")
bluer = angle_deg[ratio.values > 1.0]
print(f"bluer than the sun out to {bluer.max():.1f} deg" if bluer.size else "nowhere bluer than the sun")

# %% The plot (only where matplotlib is installed).
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    sys.exit("matplotlib is not installed: no plot (pip install './crates/sora-python[plot]')")

out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path("python_mars_aureole.png")
figure, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), dpi=110, sharex=True)
top.semilogy(angle_deg, blue, color="tab:blue", label="440 nm")
top.semilogy(angle_deg, red, color="tab:red", label="700 nm")
top.set_ylabel(f"radiance ({radiance.attrs['units']})")
top.set_title("mars-dust, sun 3° up in the west: the sky above the sun", fontsize=10)
top.legend()
top.grid(alpha=0.3, which="both")
bottom.plot(angle_deg, ratio, color="tab:purple")
bottom.axhline(1.0, color="grey", lw=0.8)
bottom.set_xscale("log")
bottom.set_xlabel("angle from the sun (deg)")
bottom.set_ylabel("(L440 / L700) / sun's")
bottom.grid(alpha=0.3, which="both")
figure.tight_layout()
figure.savefig(out)
print(f"wrote {out}")
