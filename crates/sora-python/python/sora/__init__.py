"""sora: physically based spectral atmospheric scattering, from Python.

A thin layer over the Rust library's front door (``sora::Sky``): the same
code computes every number as the ``sora`` command-line tool, here from
numpy arrays and into xarray objects with units in their ``attrs``.

>>> import sora
>>> sky = sora.Sky(sora.Atmosphere.preset("earth-clear"), sun_elevation_deg=30)
>>> zenith = sky.radiance(90, 0)          # DataArray (direction, wavelength)
>>> image = sky.render(camera="fisheye", width=256)   # (256, 256, 3) XYZ

Conventions: angles in degrees (elevation above the horizon, azimuth
clockwise from north: 0 N, 90 E, 180 S, 270 W), altitudes in m, wavelengths
in nm, spectral radiance in W m^-2 sr^-1 nm^-1. Bad values raise
``ValueError`` with the library's one-line message; unreadable files raise
``OSError``. Computations release the GIL and run on
``sora.set_num_threads(n)`` threads (default: one per core); results do not
depend on the thread count.

Modules: :mod:`sora.mie` (Mie theory over numpy arrays), :mod:`sora.sweep`
(many skies, serially or on Dask).
"""

from __future__ import annotations

import datetime as _datetime
import os as _os
from typing import Any, Dict, Optional, Sequence, Tuple, Union

import numpy as np
import xarray as xr

from . import _checks
from . import _sora
from ._arrays import broadcast_flat as _broadcast_flat
from ._sora import __version__, get_num_threads

__all__ = [
    "Atmosphere",
    "Sky",
    "mie",
    "sweep",
    "set_num_threads",
    "get_num_threads",
    "__version__",
    "RADIANCE_UNITS",
    "write_exr",
]

def set_num_threads(threads: int) -> None:
    """Uses ``threads`` threads for every later computation (0: one per
    core, the default); at most 4096."""
    _sora.set_num_threads(_checks.integer("threads", threads, 0, 4096))


#: Units of spectral radiance, as written in ``attrs["units"]``.
RADIANCE_UNITS = "W m-2 sr-1 nm-1"

WavelengthsLike = Union[str, Sequence[float], np.ndarray, None]


def write_exr(path: Union[str, "_os.PathLike[str]"], rgb: Any) -> None:
    """Writes ``rgb`` (an array of shape (height, width, 3): linear RGB,
    rows top first, finite values) as a 32-bit float OpenEXR at ``path``
    by sora's own writer (the bytes ``sora render -o FILE.exr`` writes),
    atomically: a failure leaves no file, and an existing file unchanged."""
    array = np.ascontiguousarray(rgb, dtype=np.float64)
    if array.ndim != 3:
        raise ValueError(
            f"rgb has shape {array.shape}: an EXR image needs (height, width, 3)"
        )
    _sora.write_exr(_os.fspath(path), array)


def _wavelength_coordinate(wavelengths_nm: np.ndarray) -> xr.DataArray:
    return xr.DataArray(
        np.asarray(wavelengths_nm, dtype=float),
        dims="wavelength",
        attrs={"units": "nm", "long_name": "vacuum wavelength"},
    )


def _native_wavelengths(wavelengths_nm: WavelengthsLike):
    """A grid argument for the native module: None, a 'start:stop:step'
    string, or a 1-D float array."""
    if wavelengths_nm is None or isinstance(wavelengths_nm, str):
        return wavelengths_nm
    values = np.asarray(wavelengths_nm, dtype=float)
    if values.ndim > 1:
        raise ValueError(
            f"wavelengths_nm must be 1-D (nm), not an array of shape {values.shape}"
        )
    return values.reshape(-1).tolist()


class Atmosphere:
    """An atmosphere: the planet, the sun's spectrum and the species (air,
    ozone, aerosols), with the schema of sora's atmosphere files.

    Build one with :meth:`preset`, :meth:`from_toml`, :meth:`from_toml_str`
    or :meth:`from_dict`. Atmospheres pickle (by their recipe), so they can
    be sent to Dask workers.
    """

    __slots__ = ("_native", "_recipe")

    def __init__(self, native: _sora.Atmosphere, recipe: Tuple[Any, ...]):
        self._native = native
        self._recipe = recipe

    @staticmethod
    def presets() -> list:
        """The names of the built-in atmospheres."""
        return list(_sora.preset_names())

    @classmethod
    def preset(cls, name: str) -> "Atmosphere":
        """A built-in atmosphere, e.g. ``"earth-clear"``, ``"paper-earth"``,
        ``"mars-dusty"`` (see :meth:`presets`). An unknown name raises
        ``ValueError``."""
        return cls(_sora.Atmosphere.preset(name), ("preset", name))

    @classmethod
    def from_toml(cls, path: Union[str, "_os.PathLike[str]"]) -> "Atmosphere":
        """An atmosphere file (TOML). Files it names (a solar spectrum CSV)
        are read relative to its directory. ``OSError`` if a file cannot be
        read, ``ValueError`` if it is invalid."""
        path = _os.fspath(path)
        return cls(_sora.Atmosphere.from_toml(path), ("toml", path))

    @classmethod
    def from_toml_str(
        cls, text: str, base_dir: Optional[Union[str, "_os.PathLike[str]"]] = None
    ) -> "Atmosphere":
        """An atmosphere from TOML text; files it names are read relative to
        ``base_dir`` (default: the working directory)."""
        base = None if base_dir is None else _os.fspath(base_dir)
        return cls(_sora.Atmosphere.from_toml_str(text, base), ("toml_str", text, base))

    @classmethod
    def from_dict(
        cls,
        table: Dict[str, Any],
        base_dir: Optional[Union[str, "_os.PathLike[str]"]] = None,
    ) -> "Atmosphere":
        """An atmosphere from a dict with the atmosphere files' schema:
        TOML tables are dicts, arrays are lists, e.g. the result of
        ``tomllib.load`` on a file. The same checks and messages as the
        files (``ValueError`` naming the bad key and value)."""
        base = None if base_dir is None else _os.fspath(base_dir)
        return cls(_sora.Atmosphere.from_dict(table, base), ("dict", table, base))

    @staticmethod
    def preset_toml(name: str) -> str:
        """The atmosphere file of the preset ``name``, verbatim: the text
        :meth:`preset` loads, to read or edit (``tomllib.loads``, then
        :meth:`from_dict`). An unknown name raises ``ValueError``."""
        return _sora.preset_toml(name)

    @property
    def species_names(self) -> list:
        """The species' names, in the file's order."""
        return list(self._native.species_names)

    def optical_depths(self, wavelengths_nm: WavelengthsLike = None) -> xr.Dataset:
        """Vertical optical depths, ground to top of the atmosphere, per
        species and wavelength (``"380:780:20"``, an evenly spaced array in
        nm, or None for the paper's 380-780 nm every 20 nm).

        Variables (dims ``species, wavelength``): ``optical_depth_extinction``
        and ``optical_depth_scattering`` (dimensionless),
        ``single_scattering_albedo``, ``asymmetry_parameter``; and
        ``optical_depth_total`` (dims ``wavelength``) and
        ``solar_irradiance`` (W m^-2 nm^-1, top of the atmosphere).
        """
        (names, kinds, wavelengths, tau_ext, tau_sca, albedo, g, solar) = (
            self._native.optical_depth_arrays(_native_wavelengths(wavelengths_nm))
        )
        dims = ("species", "wavelength")
        dataset = xr.Dataset(
            {
                "optical_depth_extinction": (dims, tau_ext, {"units": "1", "long_name": "vertical extinction optical depth"}),
                "optical_depth_scattering": (dims, tau_sca, {"units": "1", "long_name": "vertical scattering optical depth"}),
                "single_scattering_albedo": (dims, albedo, {"units": "1"}),
                "asymmetry_parameter": (dims, g, {"units": "1", "long_name": "asymmetry parameter <cos theta>"}),
                "optical_depth_total": (("wavelength",), tau_ext.sum(axis=0), {"units": "1", "long_name": "total vertical extinction optical depth"}),
                "solar_irradiance": (("wavelength",), solar, {"units": "W m-2 nm-1", "long_name": "top-of-atmosphere solar spectral irradiance"}),
            },
            coords={
                "species": ("species", list(names)),
                "kind": ("species", list(kinds)),
                "wavelength": _wavelength_coordinate(wavelengths),
            },
        )
        return dataset

    def coefficients(
        self, altitude_m, wavelengths_nm: WavelengthsLike = None
    ) -> xr.Dataset:
        """The local optics at altitudes above the ground (a number or a
        1-D array, m, within the ground and the top of the atmosphere): the
        library's relative density of each species there times its
        coefficients at relative density 1 (the paper's eq. 1).

        Variables: ``extinction_coefficient`` and
        ``scattering_coefficient`` (dims ``species, altitude, wavelength``,
        m^-1) and ``asymmetry_parameter`` (dims ``species, wavelength``).
        A straight path's optical depth is the integral of the extinction
        along it; a horizontal path at altitude h of length d sees
        ``extinction_coefficient * d`` only where the atmosphere is uniform
        over it.
        """
        altitudes = np.atleast_1d(np.asarray(altitude_m, dtype=float))
        if altitudes.ndim != 1:
            raise ValueError(
                f"altitude_m must be a number or 1-D (m), not an array of shape {altitudes.shape}"
            )
        extinction, scattering, g = self._native.coefficient_arrays(
            np.ascontiguousarray(altitudes), _native_wavelengths(wavelengths_nm)
        )
        wavelengths = self._native.optical_depth_arrays(_native_wavelengths(wavelengths_nm))[2]
        dims = ("species", "altitude", "wavelength")
        return xr.Dataset(
            {
                "extinction_coefficient": (dims, extinction, {"units": "m-1", "long_name": "extinction coefficient"}),
                "scattering_coefficient": (dims, scattering, {"units": "m-1", "long_name": "scattering coefficient"}),
                "asymmetry_parameter": (("species", "wavelength"), g, {"units": "1", "long_name": "asymmetry parameter <cos theta>"}),
            },
            coords={
                "species": ("species", self.species_names),
                "altitude": ("altitude", altitudes, {"units": "m", "long_name": "altitude above the ground"}),
                "wavelength": _wavelength_coordinate(wavelengths),
            },
        )

    def __reduce__(self):
        return (_atmosphere_from_recipe, (self._recipe,))

    def __repr__(self) -> str:
        return repr(self._native)


def _atmosphere_from_recipe(recipe: Tuple[Any, ...]) -> Atmosphere:
    kind, *arguments = recipe
    build = {
        "preset": Atmosphere.preset,
        "toml": Atmosphere.from_toml,
        "toml_str": Atmosphere.from_toml_str,
        "dict": Atmosphere.from_dict,
    }[kind]
    return build(*arguments)


class Sky:
    """A sky: an atmosphere, the sun, the eye, the wavelengths and the
    choice of physics and method; built once, asked for radiance and
    images many times (its tables are built on first use and kept).

    Parameters (keywords):

    - ``sun_elevation_deg``: the sun's elevation above the horizon, deg
      (-90..90; negative: twilight); ``sun_azimuth_deg`` clockwise from
      north, deg (default 180, south);
    - or ``time`` (RFC 3339 text such as ``"2026-06-21T05:30:00+09:00"``,
      or a timezone-aware ``datetime``) and ``location``
      ``(latitude_deg, longitude_deg[, elevation_m])`` (the elevation is
      also the ground's: the atmosphere above it, as ``sora --location``), with
      ``refraction`` (default True: the sun's apparent position, through
      the standard atmosphere's air at the site's elevation, or the
      measured ``pressure_hpa`` and ``temperature_c``); an Earth sun (an
      atmosphere whose sun is at 1 AU) is then at the date's Earth-Sun
      distance (its light 1/R^2, 6.9 % more on 3 January than on 4 July);
    - ``sun_distance_au``: the sun's distance, AU (0.1..100), instead of
      the date's or the atmosphere file's (:attr:`sun_distance_au` says
      which was used);
    - ``observer_altitude_m``: the eye's height above the ground, m;
    - ``wavelengths_nm``: ``"start:stop:step"`` or an evenly spaced array,
      nm (default: the paper's 380-780 nm every 20 nm);
    - ``scattering``: ``"multiple"`` (all orders and skylight reflected by
      the ground; default) or ``"single"`` (the paper's model);
    - ``method``: ``"fast"`` (default), ``"reference"`` (the paper's
      uniform march; ``reference_steps=(view_steps, sun_steps)``) or
      ``"path-tracing"`` (Monte Carlo, all orders: ``samples`` paths per
      view, default 10000, and ``seed``, default 1; the same seed gives the
      same result on any thread count);
    - ``polarisation``: ``"vector"`` (Stokes vectors, :meth:`stokes`, all
      orders, by the fast method or path tracing; Mie aerosols get their
      phase matrix computed; :meth:`render` gives the polarised intensity,
      and with ``output="stokes-xyz"`` the XYZ of I, Q, U and V) or
      ``"scalar"`` (faster; what scalar radiative-transfer codes compute);
      default None: ``"vector"``, or ``"scalar"`` with
      ``method="reference"`` (whose march is scalar), the same default as
      ``sora spectrum`` and ``sora render``, so the two give the same
      radiance. With ``"vector"`` the radiance is the polarised intensity
      I (up to a few per cent from the scalar one). A species with a
      parametric phase function (Henyey-Greenstein, Cornette-Shanks,
      isotropic) has no phase matrix: it is treated as non-polarising,
      with a ``UserWarning`` naming it when ``"vector"`` is asked for by
      name; a Rayleigh depolarisation ratio above 0.5 is a ``ValueError``
      with polarised light (give ``polarisation="scalar"``);
    - ``streams`` and ``layers``: the multiple-scattering field's
      resolution, as ``sora spectrum --streams --layers`` (default None: 8
      streams per hemisphere and 40 layers, which hold Coulson's tables to
      1.1e-4; ``streams=10`` holds them within 1e-4 at about 1.4-1.5
      times the cost, docs/polarisation.md); not with
      ``scattering="single"`` or ``method="path-tracing"``;
    - ``twilight_shift_pieces``: after sunset, the most pieces each
      near-horizontal stream's path is read in at the sun angle of where
      its light was gathered, as ``sora spectrum --twilight-shift-pieces``
      (1..64; default None: 1, whole paths, 2-3 % too bright at 560 and 680
      nm in earth-hazy's red twilight; 3 takes most of that away at
      1.1-1.2 times the CPU, docs/aerial_perspective.md); not with
      ``scattering="single"`` or ``method="path-tracing"``.

    Skies pickle (by their arguments), so Dask can ship them.
    """

    __slots__ = ("_native", "_arguments")

    def __init__(
        self,
        atmosphere: Atmosphere,
        *,
        sun_elevation_deg: Optional[float] = None,
        sun_azimuth_deg: Optional[float] = None,
        time: Union[str, _datetime.datetime, None] = None,
        location: Optional[Sequence[float]] = None,
        refraction: bool = True,
        pressure_hpa: Optional[float] = None,
        temperature_c: Optional[float] = None,
        sun_distance_au: Optional[float] = None,
        observer_altitude_m: float = 0.0,
        wavelengths_nm: WavelengthsLike = None,
        scattering: str = "multiple",
        method: str = "fast",
        samples: Optional[int] = None,
        seed: Optional[int] = None,
        reference_steps: Optional[Tuple[int, int]] = None,
        polarisation: Optional[str] = None,
        streams: Optional[int] = None,
        layers: Optional[int] = None,
        twilight_shift_pieces: Optional[int] = None,
    ):
        if not isinstance(atmosphere, Atmosphere):
            raise ValueError(
                f"atmosphere must be a sora.Atmosphere, not {type(atmosphere).__name__}"
            )
        if isinstance(time, _datetime.datetime):
            if time.tzinfo is None:
                raise ValueError(
                    "time is a naive datetime: give its time zone (e.g. tzinfo=datetime.timezone.utc)"
                )
            time = time.isoformat()
        if time is not None and not isinstance(time, str):
            raise TypeError(f"time must be RFC 3339 text or a datetime, not {type(time).__name__}")
        if location is not None:
            if isinstance(location, (str, bytes)) or not hasattr(location, "__len__"):
                raise TypeError("location must be (latitude_deg, longitude_deg[, elevation_m])")
            location = [
                _checks.number(name, value, unit)
                for name, value, unit in zip(
                    ("latitude_deg", "longitude_deg", "elevation_m"), location, ("deg", "deg", "m")
                )
            ] + [None] * max(0, len(location) - 3)
            if None in location:
                raise ValueError(
                    f"location has {len(location)} values: give (latitude_deg, longitude_deg) or (latitude_deg, longitude_deg, elevation_m)"
                )
        if reference_steps is not None:
            if isinstance(reference_steps, (str, bytes)) or not hasattr(reference_steps, "__len__") or len(reference_steps) != 2:
                raise TypeError("reference_steps must be (view_steps, sun_steps), two integers")
            reference_steps = tuple(
                _checks.integer(name, value, 1, _sora.MAX_REFERENCE_STEPS)
                for name, value in zip(("view steps", "sun steps"), reference_steps)
            )
        arguments = dict(
            sun_elevation_deg=_checks.optional_number("sun_elevation_deg", sun_elevation_deg, "deg"),
            sun_azimuth_deg=_checks.optional_number("sun_azimuth_deg", sun_azimuth_deg, "deg"),
            time=time,
            location=location,
            refraction=_checks.flag("refraction", refraction),
            pressure_hpa=_checks.optional_number("pressure_hpa", pressure_hpa, "hPa"),
            temperature_c=_checks.optional_number("temperature_c", temperature_c, "C"),
            sun_distance_au=_checks.optional_number("sun_distance_au", sun_distance_au, "AU"),
            observer_altitude_m=_checks.number("observer_altitude_m", observer_altitude_m, "m"),
            wavelengths_nm=_native_wavelengths(wavelengths_nm),
            scattering=_checks.text("scattering", scattering),
            method=_checks.text("method", method),
            samples=_checks.optional_integer("samples", samples, 2, _sora.MAX_SAMPLES, " (paths per view)"),
            seed=_checks.optional_integer("seed", seed, 0, 2**64 - 1),
            reference_steps=reference_steps,
            polarisation=None if polarisation is None else _checks.text("polarisation", polarisation),
            # The library checks the ranges (1..=32 streams, 2..=10000 layers).
            streams=_checks.optional_integer("streams", streams, 0, 2**31),
            layers=_checks.optional_integer("layers", layers, 0, 2**31),
            twilight_shift_pieces=_checks.optional_integer(
                "twilight_shift_pieces", twilight_shift_pieces, 0, 2**31
            ),
        )
        self._native = _sora.Sky(atmosphere._native, **arguments)
        self._arguments = (atmosphere, arguments)

    @property
    def wavelengths_nm(self) -> np.ndarray:
        """The wavelengths of every spectrum, nm."""
        return self._native.wavelengths_nm

    @property
    def sun_position_deg(self) -> Tuple[float, float]:
        """The sun's (elevation, azimuth), degrees."""
        return self._native.sun_position_deg

    @property
    def sun_distance_au(self) -> Optional[float]:
        """The sun's distance, AU, when ``sun_distance_au`` or a time set
        it (the date's Earth-Sun distance); None: the atmosphere file's
        sun."""
        return self._native.sun_distance_au

    @property
    def method(self) -> str:
        return self._native.method

    @property
    def scattering(self) -> str:
        return self._native.scattering

    @property
    def polarisation(self) -> str:
        """'scalar' or 'vector' (Stokes vectors: :meth:`stokes`)."""
        return self._native.polarisation

    def almucantar(self, step_deg: float = 5.0) -> Tuple[np.ndarray, np.ndarray]:
        """Directions of the almucantar (the sun's elevation) every
        ``step_deg`` of azimuth from the sun's, as ``sora spectrum
        --almucantar``: (view_elevation_deg, view_azimuth_deg) arrays."""
        step = _checks.number("step_deg", step_deg, "deg")
        if not 0.0 < step <= 90.0:
            raise ValueError(
                f"step_deg = {step} deg is out of range: allowed > 0 and <= 90 deg"
            )
        # Counted in floating point and checked before the list is made, as
        # `sora spectrum --almucantar` does (a step of 1e-300 deg is 3.6e302
        # directions).
        count = np.floor((360.0 - 1e-6) / step + 1e-9) + 1
        if not count <= _sora.MAX_VIEWS:
            raise ValueError(
                f"step_deg = {step:e} deg gives {count:e} directions, more than the limit of {_sora.MAX_VIEWS}: use a coarser step"
            )
        count = int(count)
        elevation, azimuth = self.sun_position_deg
        azimuths = np.array([(azimuth + k * step) % 360.0 for k in range(count)])
        return np.full(count, elevation), azimuths

    def _radiance_arrays(self, view_elevation_deg, view_azimuth_deg):
        (elevation, azimuth), _ = _broadcast_flat(
            ("view_elevation_deg", "view_azimuth_deg"), view_elevation_deg, view_azimuth_deg
        )
        values, errors = self._native.radiances(elevation, azimuth)
        return elevation, azimuth, values, errors

    def _coords(self, elevation, azimuth):
        return {
            "view_elevation_deg": ("direction", elevation, {"units": "deg", "long_name": "view elevation above the horizon"}),
            "view_azimuth_deg": ("direction", azimuth, {"units": "deg", "long_name": "view azimuth clockwise from north"}),
            "wavelength": _wavelength_coordinate(self.wavelengths_nm),
        }

    def _attrs(self) -> Dict[str, Any]:
        elevation, azimuth = self.sun_position_deg
        return {
            "sun_elevation_deg": elevation,
            "sun_azimuth_deg": azimuth,
            "scattering": self.scattering,
            "method": self.method,
            "polarisation": self.polarisation,
            "wavelengths_nm": self._native.wavelength_grid,
        }

    def radiance(self, view_elevation_deg, view_azimuth_deg) -> xr.DataArray:
        """The spectral radiance arriving at the eye from each direction
        (numbers or arrays that broadcast together, deg; an almucantar is
        one call), as a DataArray with dims ``(direction, wavelength)``,
        W m^-2 sr^-1 nm^-1. Directions are flattened in C order; their
        angles are the coordinates ``view_elevation_deg`` and
        ``view_azimuth_deg``. With path tracing, :meth:`radiance_with_error`
        also gives the standard errors."""
        elevation, azimuth, values, _ = self._radiance_arrays(view_elevation_deg, view_azimuth_deg)
        attrs = {"units": RADIANCE_UNITS, "long_name": "spectral radiance"}
        attrs.update(self._attrs())
        return xr.DataArray(
            values,
            dims=("direction", "wavelength"),
            coords=self._coords(elevation, azimuth),
            name="radiance",
            attrs=attrs,
        )

    def radiance_with_error(self, view_elevation_deg, view_azimuth_deg) -> xr.Dataset:
        """As :meth:`radiance`, as a Dataset with ``radiance`` and, for
        ``method="path-tracing"``, ``standard_error`` (the Monte Carlo
        standard error of each value, same units; it shrinks as
        1/sqrt(samples)). Other methods are deterministic: ``ValueError``."""
        if self.method != "path-tracing":
            raise ValueError(
                f"method = '{self.method}' is deterministic and has no standard errors: use method='path-tracing'"
            )
        elevation, azimuth, values, errors = self._radiance_arrays(view_elevation_deg, view_azimuth_deg)
        dims = ("direction", "wavelength")
        attrs = self._attrs()
        arguments = self._arguments[1]
        attrs.update(samples=int(arguments["samples"] or 10000), seed=int(arguments["seed"] or 1))
        return xr.Dataset(
            {
                "radiance": (dims, values, {"units": RADIANCE_UNITS, "long_name": "spectral radiance (Monte Carlo mean)"}),
                "standard_error": (dims, errors, {"units": RADIANCE_UNITS, "long_name": "standard error of the radiance"}),
            },
            coords=self._coords(elevation, azimuth),
            attrs=attrs,
        )

    def aerial_perspective(self, view_elevation_deg, view_azimuth_deg, distance_m) -> xr.Dataset:
        """Aerial perspective: the light the air scatters toward the eye
        between it and a point ``distance_m`` (m, > 0) along each view, and
        how much of the point's own light gets through (numbers or arrays
        that broadcast together, as :meth:`radiance`). A Dataset with dims
        ``(direction, wavelength)``: ``radiance`` (W m^-2 sr^-1 nm^-1, the
        air's light), ``transmittance`` (the segment's), and what lights
        the point, ``sun_transmittance_at_point`` and
        ``sky_irradiance_at_point`` (the sky's horizontal diffuse
        irradiance, W m^-2 nm^-1, at the point's altitude and sun
        elevation: each such point costs a sky). A scene point of
        radiance L is seen as ``L * transmittance + radiance``
        (docs/aerial_perspective.md)."""
        (elevation, azimuth, distance), _ = _broadcast_flat(
            ("view_elevation_deg", "view_azimuth_deg", "distance_m"),
            view_elevation_deg,
            view_azimuth_deg,
            distance_m,
        )
        radiance, transmittance, sun, irradiance = self._native.aerial_perspective(
            elevation, azimuth, distance
        )
        dims = ("direction", "wavelength")
        coords = self._coords(elevation, azimuth)
        coords["distance_m"] = ("direction", distance, {"units": "m", "long_name": "distance to the point"})
        return xr.Dataset(
            {
                "radiance": (dims, radiance, {"units": RADIANCE_UNITS, "long_name": "spectral radiance scattered into the segment"}),
                "transmittance": (dims, transmittance, {"units": "1", "long_name": "transmittance of the segment"}),
                "sun_transmittance_at_point": (dims, sun, {"units": "1", "long_name": "transmittance of the sun's beam to the point"}),
                "sky_irradiance_at_point": (dims, irradiance, {"units": "W m-2 nm-1", "long_name": "diffuse sky irradiance on a horizontal plane at the point"}),
            },
            coords=coords,
            attrs=self._attrs(),
        )

    def stokes(self, view_elevation_deg, view_azimuth_deg) -> xr.Dataset:
        """The Stokes vector of the light from each direction (as
        :meth:`radiance`), for a sky with ``polarisation="vector"``: a
        Dataset with ``I``, ``Q``, ``U``, ``V`` (W m^-2 sr^-1 nm^-1), the
        ``degree_of_linear_polarisation`` sqrt(Q^2 + U^2) / I, and with path
        tracing ``standard_error_I`` ... ``standard_error_V``.

        Q and U are referred to the meridian plane of each view (the
        vertical plane through it): Q > 0 for a mostly vertical electric
        field, Q < 0 for a horizontal one; the angle of polarisation,
        0.5 * arctan2(U, Q), turns from the vertical toward the observer's
        left (docs/polarisation.md)."""
        (elevation, azimuth), _ = _broadcast_flat(
            ("view_elevation_deg", "view_azimuth_deg"), view_elevation_deg, view_azimuth_deg
        )
        values, errors = self._native.stokes(elevation, azimuth)
        dims = ("direction", "wavelength")
        names = ("I", "Q", "U", "V")
        variables = {
            name: (dims, values[k], {"units": RADIANCE_UNITS, "long_name": f"Stokes {name}"})
            for k, name in enumerate(names)
        }
        intensity = values[0]
        degree = np.divide(
            np.hypot(values[1], values[2]),
            intensity,
            out=np.zeros_like(intensity),
            where=intensity > 0,
        )
        variables["degree_of_linear_polarisation"] = (
            dims,
            degree,
            {"units": "1", "long_name": "degree of linear polarisation"},
        )
        if errors is not None:
            for k, name in enumerate(names):
                variables[f"standard_error_{name}"] = (
                    dims,
                    errors[k],
                    {"units": RADIANCE_UNITS, "long_name": f"standard error of Stokes {name}"},
                )
        attrs = self._attrs()
        attrs["reference_plane"] = "meridian plane of each view"
        return xr.Dataset(variables, coords=self._coords(elevation, azimuth), attrs=attrs)

    def direct_normal_irradiance(self) -> xr.DataArray:
        """The sun's direct beam at the eye on a plane facing it,
        W m^-2 nm^-1 (0 where the planet hides the sun)."""
        return xr.DataArray(
            self._native.direct_normal_irradiance(),
            dims="wavelength",
            coords={"wavelength": _wavelength_coordinate(self.wavelengths_nm)},
            name="direct_normal_irradiance",
            attrs={"units": "W m-2 nm-1"},
        )

    def colour(self, spectra, output: str = "xyz") -> np.ndarray:
        """The colour of spectra on this sky's wavelengths (an array whose
        last axis is :attr:`wavelengths_nm`: radiance or irradiance), as
        images' pixels are made: ``output="xyz"`` CIE 1931 XYZ (Y in
        W m^-2 sr^-1 for radiance, W m^-2 for irradiance in W m^-2 nm^-1:
        times 683 lm/W, cd m^-2 and lux) or
        ``"linear-srgb"``; shape ``spectra.shape[:-1] + (3,)``."""
        if output not in ("xyz", "linear-srgb"):
            raise ValueError(f"output = '{output}' is unknown: use 'xyz' or 'linear-srgb'")
        values = np.asarray(spectra, dtype=float)
        if values.ndim == 0:
            raise ValueError("spectra must have a wavelength axis (the last), not be a number")
        flat = np.ascontiguousarray(values.reshape(-1, values.shape[-1]))
        colours = self._native.colours(flat, output == "linear-srgb")
        return colours.reshape(values.shape[:-1] + (3,))

    def render(
        self,
        camera: str = "fisheye",
        width: Optional[int] = None,
        height: Optional[int] = None,
        output: str = "xyz",
        draw_sun_disc: bool = True,
        look_elevation_deg: float = 10.0,
        look_azimuth_deg: float = 180.0,
        fov_deg: float = 90.0,
    ) -> np.ndarray:
        """An image as a numpy array (rows top first), handed over without a
        copy from the library's buffer:

        - ``output="xyz"``: (height, width, 3), CIE 1931 XYZ of the spectral
          radiance (Y = the integral of L(lambda) y-bar(lambda) d lambda, in
          W m^-2 sr^-1: multiply by 683 lm/W for the luminance in cd m^-2);
        - ``"linear-srgb"``: (height, width, 3), linear sRGB of the same XYZ
          (no exposure, no clipping);
        - ``"spectral"``: (height, width, wavelengths), W m^-2 sr^-1 nm^-1;
        - ``"stokes-xyz"`` (a ``polarisation="vector"`` sky): (height, width,
          4, 3), the XYZ of the Stokes I, Q, U and V (Q and U referred to
          each pixel's meridian plane, Q > 0 vertical; they may be
          negative), the sun's disc in I only.

        ``camera``: ``"fisheye"`` (the whole sky, zenith at the centre, north
        up, east left; black outside the circle), ``"equirectangular"`` or
        ``"perspective"`` (``look_elevation_deg``, ``look_azimuth_deg``,
        ``fov_deg`` across the width; by default 10 degrees up, toward the
        south, 90 degrees wide, as ``sora render --camera perspective``).
        ``width`` defaults to 512 pixels (1024 for equirectangular) and
        ``height`` to ``width`` (half of it for equirectangular), as
        ``sora render``'s. Path tracing renders no images.
        """
        # Any 64-bit integer passes here; the library checks the range, with
        # the message of ``sora render --width``.
        low, high = -(2**63), 2**63 - 1
        return self._native.render(
            _checks.text("camera", camera),
            _checks.optional_integer("width", width, low, high, " (pixels)"),
            _checks.optional_integer("height", height, low, high, " (pixels)"),
            _checks.text("output", output),
            _checks.flag("draw_sun_disc", draw_sun_disc),
            _checks.number("look_elevation_deg", look_elevation_deg, "deg"),
            _checks.number("look_azimuth_deg", look_azimuth_deg, "deg"),
            _checks.number("fov_deg", fov_deg, "deg"),
        )

    def __reduce__(self):
        atmosphere, arguments = self._arguments
        return (_sky_from_arguments, (atmosphere, arguments))

    def __repr__(self) -> str:
        return repr(self._native)


def _sky_from_arguments(atmosphere: Atmosphere, arguments: Dict[str, Any]) -> Sky:
    return Sky(atmosphere, **arguments)


from . import mie, sweep  # noqa: E402  (after the classes, which sweep uses)
