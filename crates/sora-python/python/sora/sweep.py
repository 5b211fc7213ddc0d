"""Sweeps of many skies: every (atmosphere, sun position) pair computed as
an independent task, serially or on a Dask cluster, collected into one
``xarray.Dataset``.

Each task builds its own :class:`sora.Sky` from picklable inputs (the
atmosphere travels by its recipe) and computes the zenith spectrum and the
almucantar (the circle of sky at the sun's elevation). The library is
deterministic: a task's result depends only on its inputs, not on the
worker, the thread count or the order tasks run in, so a sweep on a cluster
is bit-identical to the serial loop. For the path tracer the seed is part
of the inputs (``seed=``, or per task from :func:`task_seed`), so shards
draw independent, reproducible random numbers without sharing a generator.

The same code runs on a real cluster: pass any ``dask.distributed.Client``
(``Client("tcp://scheduler:8786")``, a ``dask_jobqueue`` or Kubernetes
cluster's client) as ``client``; the workers need ``pip install sora`` of
the same version. With Ray, pass ``map_function=lambda f, *a:
ray.get([ray.remote(f).remote(*x) for x in zip(*a)])``; with a local
process pool, ``concurrent.futures.ProcessPoolExecutor().map``.
"""

from __future__ import annotations

from typing import Callable, Dict, Optional, Sequence

import numpy as np
import xarray as xr

from . import RADIANCE_UNITS, Atmosphere, Sky

__all__ = ["sky_task", "sweep", "task_seed"]


def task_seed(base_seed: int, atmosphere_index: int, sun_index: int) -> int:
    """A path-tracing seed for one task, from the sweep's ``base_seed`` and
    the task's place in it: distinct for every task, the same on every run
    and every cluster (the library's generator streams differ by seed)."""
    return (int(base_seed) * 1_000_003 + atmosphere_index) * 1_000_003 + sun_index


def sky_task(
    atmosphere: Atmosphere,
    sun_elevation_deg: float,
    sun_azimuth_deg: float,
    wavelengths_nm,
    almucantar_step_deg: float,
    sky_options: Dict,
):
    """One sky's wavelengths (nm), zenith spectrum (wavelength) and
    almucantar (relative azimuth, wavelength), W m^-2 sr^-1 nm^-1, as numpy
    arrays."""
    sky = Sky(
        atmosphere,
        sun_elevation_deg=sun_elevation_deg,
        sun_azimuth_deg=sun_azimuth_deg,
        wavelengths_nm=wavelengths_nm,
        **sky_options,
    )
    elevation, azimuth = sky.almucantar(almucantar_step_deg)
    radiance = sky.radiance(np.r_[90.0, elevation], np.r_[0.0, azimuth]).values
    return sky.wavelengths_nm, radiance[0], radiance[1:]


def sweep(
    atmospheres: Dict[str, Atmosphere],
    sun_elevation_deg: Sequence[float],
    sun_azimuth_deg: Sequence[float],
    wavelengths_nm="380:780:20",
    almucantar_step_deg: float = 10.0,
    client=None,
    map_function: Optional[Callable] = None,
    **sky_options,
) -> xr.Dataset:
    """The zenith and almucantar radiance of every atmosphere (a dict name ->
    :class:`sora.Atmosphere`) with the sun at every (elevation, azimuth) pair
    (deg), as a Dataset with dims ``atmosphere, sun, wavelength`` and
    ``relative_azimuth`` (deg from the sun's azimuth, clockwise).

    Runs on ``client`` (a ``dask.distributed.Client``) when given, else
    through ``map_function`` (a ``map``-like callable), else serially;
    ``sky_options`` go to every :class:`sora.Sky` (``scattering=``,
    ``method=``...; with path tracing, ``seed=`` is the sweep's base seed and
    each task traces with :func:`task_seed` of it).
    """
    elevations = np.asarray(sun_elevation_deg, dtype=float).reshape(-1)
    azimuths = np.asarray(sun_azimuth_deg, dtype=float).reshape(-1)
    if elevations.shape != azimuths.shape:
        raise ValueError(
            f"sun_elevation_deg ({elevations.size}) and sun_azimuth_deg ({azimuths.size}) must have one value per sun position"
        )
    names = list(atmospheres)
    tasks = [
        (atmospheres[name], float(e), float(a)) for name in names for e, a in zip(elevations, azimuths)
    ]
    columns = [list(column) for column in zip(*tasks)] if tasks else [[], [], []]
    count = len(tasks)
    # Path tracing: each task its own seed, from seed= and its place.
    if sky_options.get("method") == "path-tracing":
        base_seed = sky_options.get("seed", 1)
        options = [
            dict(sky_options, seed=task_seed(base_seed, i, j))
            for i in range(len(names))
            for j in range(elevations.size)
        ]
    else:
        options = [sky_options] * count
    constants = [[wavelengths_nm] * count, [almucantar_step_deg] * count, options]
    if client is not None:
        futures = client.map(sky_task, *columns, *constants, pure=False)
        results = client.gather(futures)
    elif map_function is not None:
        results = list(map_function(sky_task, *columns, *constants))
    else:
        results = list(map(sky_task, *columns, *constants))
    shape = (len(names), elevations.size)
    if not results:
        raise ValueError("the sweep is empty: give at least one atmosphere and one sun position")
    wavelengths = results[0][0]
    zenith = np.stack([r[1] for r in results]).reshape(shape + results[0][1].shape)
    almucantar = np.stack([r[2] for r in results]).reshape(shape + results[0][2].shape)
    relative = almucantar_step_deg * np.arange(almucantar.shape[2])
    radiance_attrs = {"units": RADIANCE_UNITS}
    return xr.Dataset(
        {
            "zenith_radiance": (("atmosphere", "sun", "wavelength"), zenith, dict(radiance_attrs, long_name="zenith spectral radiance")),
            "almucantar_radiance": (("atmosphere", "sun", "relative_azimuth", "wavelength"), almucantar, dict(radiance_attrs, long_name="almucantar spectral radiance")),
        },
        coords={
            "atmosphere": ("atmosphere", names),
            "sun_elevation_deg": ("sun", elevations, {"units": "deg"}),
            "sun_azimuth_deg": ("sun", azimuths, {"units": "deg"}),
            "wavelength": ("wavelength", wavelengths, {"units": "nm"}),
            "relative_azimuth": ("relative_azimuth", relative, {"units": "deg", "long_name": "azimuth clockwise from the sun's"}),
        },
        attrs={"scattering": sky_options.get("scattering", "multiple"), "method": sky_options.get("method", "fast")},
    )
