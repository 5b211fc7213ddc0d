"""sora against Kider et al. (2014)'s measured clear skies: the numbers and
pictures of docs/measured-skies.md.

    python scripts/measured_skies/plot.py OUT_DIR --may MAY.csv --september SEPTEMBER.csv \
        --may-points FILE... --september-points FILE... \
        --may-no-aerosol FILE... --september-no-aerosol FILE...

Each file is the long CSV of `sora spectrum ... --directions
crates/sora-cli/tests/data/measured/kider2014_directions.csv` for that
capture (the commands are on the page): `--may`/`--september` the preset's
sky on `--wavelengths 360:1100:10` (the spectra and the table per
direction), `--*-points` the preset's sky and `--*-no-aerosol` the
aerosol-free sky at the maps' wavelengths, one file per one-point grid
`W:W:10` (the maps and the table per wavelength; several files per option
are merged). The measured radiances are read from
crates/sora-cli/tests/data/measured/ (10-nm box means, W m^-2 sr^-1 nm^-1,
the same grid). Prints the page's tables (sora / measured per wavelength
over the 81 directions, and per direction over 360-1100 nm) and writes,
where matplotlib is installed, OUT_DIR/measured_skies_maps_<capture>.png and
OUT_DIR/measured_skies_spectra.png. numpy and matplotlib only.
"""

import pathlib
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
DATA = ROOT / "crates/sora-cli/tests/data/measured"
CAPTURES = [
    # (file stem, label); the sun (elevation, azimuth in degrees) as sora's JSON
    # reports it for the page's --location and --time, drawn as a star on the maps
    ("2013-05-27_120000", "2013-05-27 12:00 EDT"),
    ("2013-09-24_131000", "2013-09-24 13:10 EDT"),
]
SUN_DEG = {"2013-05-27_120000": (65.16, 142.97), "2013-09-24_131000": (46.76, 184.46)}
MAP_NM = [450, 550, 650, 850]
# Directions for the spectra, by the archive's index: the zenith, the 53-degree ring
# and the 12-degree ring (see the page for where each lies from the sun).
SPECTRA_INDEX = [80, 64, 60, 8]


def read_measured(stem):
    lines = [l for l in (DATA / f"{stem}.csv").read_text().splitlines() if not l.startswith("#")]
    header = lines[0].split(",")
    table = np.array([[float(x) for x in l.split(",")] for l in lines[1:]])
    wl = np.array([float(h[1:]) for h in header[4:]])
    return table[:, 1], table[:, 3], wl, table[:, 4:]


def read_model(paths, elevation, azimuth, wl, needed_nm):
    """sora's long CSVs into an (81, wavelengths) array in the archive's order
    (NaN where no file gives a value); every direction at `needed_nm` required."""
    out = np.full((elevation.size, wl.size), np.nan)
    for path in paths:
        rows = np.loadtxt(path, delimiter=",", skiprows=1, usecols=(0, 1, 2, 3), ndmin=2)
        for e, a, w, v in rows:
            i = np.flatnonzero((np.abs(elevation - e) < 1e-6) & (np.abs(azimuth - a) < 1e-6))
            j = np.flatnonzero(np.abs(wl - w) < 1e-6)
            if i.size == 1 and j.size == 1:
                out[i[0], j[0]] = v
    for w in needed_nm:
        if np.isnan(out[:, int(np.flatnonzero(wl == w)[0])]).any():
            sys.exit(f"{' '.join(paths)}: not all 81 directions at {w} nm")
    return out


def stats(ratio):
    """Mean of model/measured, rms of (ratio - 1), rms of (ratio / mean - 1)."""
    mean = ratio.mean()
    return mean, np.sqrt(np.mean((ratio - 1) ** 2)), np.sqrt(np.mean((ratio / mean - 1) ** 2))


def main():
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir", type=pathlib.Path)
    for name in ["may", "september", "may-points", "september-points", "may-no-aerosol", "september-no-aerosol"]:
        parser.add_argument(f"--{name}", nargs="+", required=True)
    args = parser.parse_args()
    out_dir = args.out_dir
    skies = []
    for (stem, label), paths, point_paths, free_paths in zip(
        CAPTURES,
        [args.may, args.september],
        [args.may_points, args.september_points],
        [args.may_no_aerosol, args.september_no_aerosol],
    ):
        elevation, azimuth, wl, measured = read_measured(stem)
        full = read_model(paths, elevation, azimuth, wl, wl)
        points = read_model(point_paths, elevation, azimuth, wl, MAP_NM)
        free = read_model(free_paths, elevation, azimuth, wl, MAP_NM)
        skies.append((stem, label, elevation, azimuth, wl, measured, full, points, free))

    print(
        "capture | wavelength_nm | mean sora/measured | rms(sora/measured - 1) | rms after dividing by the mean"
        " | directions measured between the aerosol-free sky and the preset's"
    )
    for stem, label, elevation, azimuth, wl, measured, _, model, free in skies:
        for w in MAP_NM:
            j = int(np.flatnonzero(wl == w)[0])
            mean, rms, shape = stats(model[:, j] / measured[:, j])
            lo, hi = np.minimum(model[:, j], free[:, j]), np.maximum(model[:, j], free[:, j])
            between = int(((lo <= measured[:, j]) & (measured[:, j] <= hi)).sum())
            print(f"| {label} | {w} | {mean:.3f} | {100 * rms:.1f} % | {100 * shape:.1f} % | {between} |")
    print("the aerosol-free sky: capture | wavelength_nm | mean | rms | rms after the mean")
    for stem, label, elevation, azimuth, wl, measured, _, _, free in skies:
        for w in MAP_NM:
            j = int(np.flatnonzero(wl == w)[0])
            mean, rms, shape = stats(free[:, j] / measured[:, j])
            print(f"| {label}, no aerosol | {w} | {mean:.3f} | {100 * rms:.1f} % | {100 * shape:.1f} % |")
    print("capture | index | elevation_deg | azimuth_deg | mean sora/measured 360-1100 nm | rms | rms after dividing by the mean")
    for stem, label, elevation, azimuth, wl, measured, model, _, _ in skies:
        for i in SPECTRA_INDEX:
            mean, rms, shape = stats(model[i] / measured[i])
            print(
                f"| {label} | {i} | {elevation[i]:g} | {azimuth[i]:g} | {mean:.3f} | {100 * rms:.1f} % | {100 * shape:.1f} % |"
            )

    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.colors import LogNorm, TwoSlopeNorm
    except ImportError:
        sys.exit("matplotlib is not installed: no pictures")

    for stem, label, elevation, azimuth, wl, measured, _, model, _ in skies:
        fig, axes = plt.subplots(3, 4, figsize=(11, 8.4), subplot_kw={"projection": "polar"})
        theta, r = np.radians(azimuth), 90 - elevation
        for col, w in enumerate(MAP_NM):
            j = int(np.flatnonzero(wl == w)[0])
            norm = LogNorm(min(measured[:, j].min(), model[:, j].min()), max(measured[:, j].max(), model[:, j].max()))
            ratio = model[:, j] / measured[:, j]
            for row, (values, name, cmap, nrm) in enumerate(
                [
                    (measured[:, j], "measured", "viridis", norm),
                    (model[:, j], "sora", "viridis", norm),
                    (ratio, "sora / measured", "RdBu_r", TwoSlopeNorm(1.0, 0.5, 1.5)),
                ]
            ):
                ax = axes[row, col]
                ax.set_theta_zero_location("N")
                ax.set_theta_direction(1)  # east left: a sky chart held overhead
                sc = ax.scatter(theta, r, c=values, cmap=cmap, norm=nrm, s=70, edgecolors="none")
                sun_elevation, sun_azimuth = SUN_DEG[stem]
                ax.plot(np.radians(sun_azimuth), 90 - sun_elevation, "*", color="orange", ms=12, mec="k")
                ax.set_ylim(0, 90)
                ax.set_yticks([30, 60])
                ax.set_yticklabels([])
                ax.set_xticks(np.radians([0, 90, 180, 270]))
                ax.set_xticklabels(["N", "E", "S", "W"], fontsize=8)
                ax.set_title(f"{name}, {w} nm", fontsize=9)
                fig.colorbar(sc, ax=ax, shrink=0.7, pad=0.1)
        fig.suptitle(
            f"Cornell, {label}: radiance (W m$^{{-2}}$ sr$^{{-1}}$ nm$^{{-1}}$) in the 81 directions\n"
            "zenith at the centre, horizon at the rim, north up, east left"
        )
        fig.tight_layout()
        path = out_dir / f"measured_skies_maps_{stem}.png"
        fig.savefig(path, dpi=56)
        plt.close(fig)
        print("wrote", path)

    fig, axes = plt.subplots(len(skies), len(SPECTRA_INDEX), figsize=(13, 6), sharex=True)
    for row, (stem, label, elevation, azimuth, wl, measured, model, _, _) in enumerate(skies):
        for col, i in enumerate(SPECTRA_INDEX):
            ax = axes[row, col]
            ax.plot(wl, measured[i], "k-", label="measured")
            ax.plot(wl, model[i], "C3--", label="sora")
            ax.set_title(f"{label}\nelevation {elevation[i]:g}, azimuth {azimuth[i]:g} deg", fontsize=9)
            ax.grid(alpha=0.3)
            if col == 0:
                ax.set_ylabel("W m$^{-2}$ sr$^{-1}$ nm$^{-1}$")
            if row == len(skies) - 1:
                ax.set_xlabel("wavelength (nm)")
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    path = out_dir / "measured_skies_spectra.png"
    fig.savefig(path, dpi=70)
    plt.close(fig)
    print("wrote", path)


if __name__ == "__main__":
    main()
