"""What the add-on computes, without Blender: plain functions over sora's
Python package and numpy, tested on their own (blender/tests/test_core.py)
and used by the operators.

Units and conventions (README "Blender"):

- **The world map.** An equirectangular image in Blender's layout (column
  u = 0.5 - atan2(y, x) / 2 pi, row v = elevation / 180 + 0.5, bottom row
  first), with Blender's +Y north and +X east: north at a quarter of the
  width, east at the centre, south at three quarters. Each pixel is the
  sky's (and below the horizon the ground's) radiance seen from the eye,
  as sora's equirectangular image computes it, averaged over nothing: the
  value at the pixel's centre, the sun's disc (when drawn) energy-true
  over the pixels it covers.
- **Pixel values, W m^-2 sr^-1.** Linear Rec.709 RGB (Blender's default
  working space) whose luminance-weighted sum
  ``0.2126 R + 0.7152 G + 0.0722 B`` is the spectral radiance integrated
  over sora's wavelength grid (the rectangle rule sora's broadband values
  use: 380-780 nm every 20 nm by default), and whose chromaticity is the
  spectrum's (CIE 1931, as sora's images). Cycles' Background shader at
  strength 1 emits that radiance, so a Lambertian plane of albedo a under
  the map has ``a E / pi`` as its weighted sum, E = integral L cos dw the
  broadband irradiance of ``sora irradiance`` over the same grid; every
  channel is linear, so the sum of the parts holds channel by channel.
- **The sun.** Either as sora draws it in the map (the disc, energy-true:
  the pixels' radiance times their solid angle sums to the direct normal
  irradiance) or as a Sun lamp of strength the broadband direct normal
  irradiance (W m^-2: Cycles' sun strength is the irradiance on a surface
  facing it) with the same RGB rule for its colour, the disc left out of
  the map; the angular diameter is the atmosphere file's.
- **Haze.** The local coefficients at the eye's altitude, held constant
  in a low slab (see :func:`haze_coefficients`).
"""

from __future__ import annotations

import dataclasses
import math
import os
import tomllib
from typing import Optional, Tuple

import numpy as np

import sora

#: Blender's luminance weights of linear Rec.709 (its OCIO configuration's).
LUMINANCE_WEIGHTS = np.array([0.2126, 0.7152, 0.0722])

#: The wavelengths (nm) at which the haze's R, G and B coefficients are
#: taken: the dominant wavelengths of the Rec.709 primaries.
HAZE_WAVELENGTHS_NM = (612.0, 549.0, 465.0)

#: The aerosol optical depth's wavelength, nm.
AEROSOL_REFERENCE_NM = 550.0


@dataclasses.dataclass
class SkySettings:
    """Everything that makes a sky: the panel's fields."""

    preset: str = "earth-clear"
    #: An atmosphere file (TOML); empty: the preset.
    atmosphere_path: str = ""
    #: None: as the atmosphere says.
    aerosol_optical_depth: Optional[float] = None
    ozone_dobson_units: Optional[float] = None
    ground_albedo: Optional[float] = None
    #: "angles" (elevation and azimuth) or "time" (time and place).
    sun_from: str = "angles"
    sun_elevation_deg: float = 30.0
    sun_azimuth_deg: float = 180.0
    #: RFC 3339 with a zone, e.g. 2026-06-21T19:00:00+09:00.
    time: str = ""
    latitude_deg: float = 0.0
    longitude_deg: float = 0.0
    site_elevation_m: float = 0.0
    observer_altitude_m: float = 0.0
    #: "scalar" (the library's default) or "vector".
    polarisation: str = "scalar"
    #: Width of the world map, pixels (a multiple of 4; height half of it).
    map_width: int = 1024
    #: "lamp" (a Sun lamp, the disc left out of the map) or "disc".
    sun_as: str = "lamp"


def atmosphere_table(settings: SkySettings) -> Tuple[dict, Optional[str]]:
    """The atmosphere file's table (a preset's text or the file) and the
    directory files it names are read from. A file that does not parse is
    the library's one-line ``ValueError``."""
    if settings.atmosphere_path:
        path = os.path.abspath(settings.atmosphere_path)
        # The library reads and checks it first: its one-line error.
        sora.Atmosphere.from_toml(path)
        with open(path, "rb") as file:
            return tomllib.load(file), os.path.dirname(path)
    return tomllib.loads(sora.Atmosphere.preset_toml(settings.preset)), None


def make_atmosphere(settings: SkySettings) -> Tuple[sora.Atmosphere, dict]:
    """The atmosphere with the panel's overrides: the aerosols scaled to
    ``aerosol_optical_depth`` at 550 nm (each keeps its share), the ozone
    column, a constant ground albedo. Returns it and its table."""
    table, base_dir = atmosphere_table(settings)
    species = table.get("species", [])
    if settings.aerosol_optical_depth is not None or settings.ozone_dobson_units is not None:
        optics = sora.Atmosphere.from_dict(table, base_dir).optical_depths(
            f"{AEROSOL_REFERENCE_NM:g}"
        )
        kinds = list(optics.kind.values)
        tau = optics.optical_depth_extinction.values[:, 0]
    if settings.aerosol_optical_depth is not None:
        wanted = float(settings.aerosol_optical_depth)
        if not (math.isfinite(wanted) and wanted >= 0.0):
            raise ValueError(f"aerosol optical depth = {wanted} is out of range: allowed >= 0")
        aerosols = [i for i, kind in enumerate(kinds) if kind in ("mie", "parametric aerosol")]
        total = sum(tau[i] for i in aerosols)
        if not aerosols or (total <= 0.0 and wanted > 0.0):
            raise ValueError(
                f"aerosol optical depth = {wanted} at 550 nm: the atmosphere has no aerosol to scale"
            )
        for i in aerosols:
            share = tau[i] / total if total > 0.0 else 0.0
            species[i].pop("number_density_m3", None)
            species[i]["optical_depth"] = wanted * share
            species[i]["reference_wavelength_nm"] = AEROSOL_REFERENCE_NM
    if settings.ozone_dobson_units is not None:
        ozone = [
            i
            for i, entry in enumerate(species)
            if kinds[i] == "absorbing gas" and entry.get("absorption", {}).get("gas") == "ozone"
        ]
        if not ozone:
            raise ValueError(
                f"ozone = {settings.ozone_dobson_units} DU: the atmosphere has no ozone species"
            )
        for i in ozone:
            species[i].pop("number_density_m3", None)
            species[i].pop("column_molecules_cm2", None)
            species[i]["column_dobson_units"] = float(settings.ozone_dobson_units)
    if settings.ground_albedo is not None:
        table.setdefault("planet", {})["ground_albedo"] = float(settings.ground_albedo)
    return sora.Atmosphere.from_dict(table, base_dir), table


def make_sky(settings: SkySettings) -> Tuple[sora.Sky, dict]:
    """The sora sky of the settings, and its atmosphere's table. Bad
    values (a time without a zone, an elevation out of range) are the
    library's one-line ``ValueError``."""
    atmosphere, table = make_atmosphere(settings)
    common = dict(
        observer_altitude_m=settings.observer_altitude_m,
        polarisation=settings.polarisation,
    )
    if settings.sun_from == "time":
        sky = sora.Sky(
            atmosphere,
            time=settings.time,
            location=(settings.latitude_deg, settings.longitude_deg, settings.site_elevation_m),
            **common,
        )
    elif settings.sun_from == "angles":
        sky = sora.Sky(
            atmosphere,
            sun_elevation_deg=settings.sun_elevation_deg,
            sun_azimuth_deg=settings.sun_azimuth_deg,
            **common,
        )
    else:
        raise ValueError(f"sun_from = '{settings.sun_from}' is unknown: use 'angles' or 'time'")
    return sky, table


def broadband(sky: sora.Sky, spectra: np.ndarray) -> np.ndarray:
    """Spectral values (last axis: the sky's wavelengths) integrated over
    the grid by sora's rule (the sum times the step), e.g. W m^-2 sr^-1
    from W m^-2 sr^-1 nm^-1."""
    wavelengths = np.asarray(sky.wavelengths_nm)
    step = wavelengths[1] - wavelengths[0] if wavelengths.size > 1 else 1.0
    return np.asarray(spectra).sum(axis=-1) * step


def broadband_rgb(sky: sora.Sky, spectra: np.ndarray) -> np.ndarray:
    """Linear Rec.709 RGB of spectra with the spectrum's chromaticity and
    luminance-weighted sum (:data:`LUMINANCE_WEIGHTS`) equal to its
    broadband value (:func:`broadband`). Out-of-gamut (negative) components
    are clipped to 0 before the scaling, so the sum stays exact; a spectrum
    with no colour (zero) is grey."""
    spectra = np.asarray(spectra, dtype=float)
    total = broadband(sky, spectra)
    rgb = np.clip(sky.colour(spectra, "linear-srgb"), 0.0, None)
    weight = rgb @ LUMINANCE_WEIGHTS
    coloured = weight > 0.0
    scale = np.divide(total, weight, out=np.zeros_like(total), where=coloured)
    out = rgb * scale[..., None]
    out[~coloured] = total[~coloured][..., None]
    return out


def world_map(sky: sora.Sky, width: int, draw_sun_disc: bool) -> np.ndarray:
    """The world map (see the module docs): (width / 2, width, 3) float32,
    bottom row first, columns in Blender's equirectangular layout."""
    if width < 8 or width % 4 != 0:
        raise ValueError(f"map width = {width} px: give a multiple of 4, at least 8")
    spectral = sky.render(
        camera="equirectangular", width=width, height=width // 2,
        output="spectral", draw_sun_disc=draw_sun_disc,
    )
    rgb = broadband_rgb(sky, spectral)
    # sora: north at the centre, azimuth growing to the right; Blender
    # (+Y north): east at the centre, so column j is sora's j + width / 4.
    rgb = np.roll(rgb, -width // 4, axis=1)
    return np.ascontiguousarray(rgb[::-1], dtype=np.float32)


def sun_direction(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    """The unit vector toward the sun in Blender's frame (+X east, +Y
    north, +Z up)."""
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return np.array([math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e)])


@dataclasses.dataclass
class SunLamp:
    """A Sun lamp with sora's direct beam."""

    #: Broadband direct normal irradiance, W m^-2 (Cycles' sun strength).
    strength_w_m2: float
    #: Linear Rec.709, luminance-weighted sum 1.
    colour: Tuple[float, float, float]
    elevation_deg: float
    azimuth_deg: float
    angular_diameter_deg: float


def sun_lamp(sky: sora.Sky, table: dict) -> SunLamp:
    """The Sun lamp of ``sky`` (0 W m^-2 when the planet hides the sun)."""
    direct = sky.direct_normal_irradiance().values
    strength = float(broadband(sky, direct))
    rgb = broadband_rgb(sky, direct)
    colour = rgb / strength if strength > 0.0 else np.ones(3)
    elevation, azimuth = sky.sun_position_deg
    diameter = float(table.get("sun", {}).get("angular_diameter_deg", 0.53))
    return SunLamp(strength, tuple(float(c) for c in colour), elevation, azimuth, diameter)


@dataclasses.dataclass
class HazeCoefficients:
    """A homogeneous medium: sora's local coefficients at one altitude, in
    m^-1, at :data:`HAZE_WAVELENGTHS_NM` (R, G, B)."""

    altitude_m: float
    #: Rayleigh (air) scattering.
    rayleigh_scattering: Tuple[float, float, float]
    #: The aerosols' scattering, with their scattering-weighted asymmetry
    #: parameter at 549 nm.
    aerosol_scattering: Tuple[float, float, float]
    aerosol_g: float
    #: Everything absorbed (gases and aerosols).
    absorption: Tuple[float, float, float]

    @property
    def extinction(self) -> np.ndarray:
        return (
            np.array(self.rayleigh_scattering)
            + np.array(self.aerosol_scattering)
            + np.array(self.absorption)
        )


def haze_coefficients(atmosphere: sora.Atmosphere, altitude_m: float) -> HazeCoefficients:
    """The eye's air as a homogeneous medium: extinction, scattering and the
    aerosols' asymmetry at ``altitude_m`` (sora's profiles and optics, the
    paper's eq. 1), taken as constant everywhere in the haze.

    What it approximates: single- and multiple-scattered light along a path
    in a uniform slab at the eye's altitude. Along a horizontal path the
    real atmosphere thins as the path rises over the curved ground (about
    d^2 / 2R: 0.08 m at 1 km, 7.9 m at 10 km, 196 m at 50 km), so the
    haze's optical depth is too large by the aerosol's and air's decrease
    over that rise (blender/tests/test_core.py measures it); sunlight
    reaching the haze is Cycles' (the lamp or the map), not attenuated
    along a slant path through the haze's own profile."""
    wavelengths = np.asarray(HAZE_WAVELENGTHS_NM)
    grid = f"{wavelengths.min():g}:{wavelengths.max():g}:1"
    local = atmosphere.coefficients(float(altitude_m), grid)
    at = local.sel(wavelength=wavelengths, method="nearest").isel(altitude=0)
    kinds = list(atmosphere.optical_depths("550").kind.values)
    extinction = at.extinction_coefficient.values
    scattering = at.scattering_coefficient.values
    is_rayleigh = np.array([kind == "rayleigh" for kind in kinds])
    rayleigh = scattering[is_rayleigh].sum(axis=0)
    aerosol = scattering[~is_rayleigh].sum(axis=0)
    g_values = at.asymmetry_parameter.values[~is_rayleigh, 1]
    weights = scattering[~is_rayleigh, 1]
    g = float(np.sum(g_values * weights) / weights.sum()) if weights.sum() > 0 else 0.0
    absorption = (extinction - scattering).sum(axis=0)
    as_tuple = lambda v: tuple(float(x) for x in v)  # noqa: E731
    return HazeCoefficients(
        float(altitude_m), as_tuple(rayleigh), as_tuple(aerosol), g, as_tuple(absorption)
    )


def horizontal_optical_depth(
    atmosphere: sora.Atmosphere,
    planet_radius_m: float,
    altitude_m: float,
    distance_m: float,
    wavelength_nm: float = 550.0,
    steps: int = 2000,
) -> float:
    """The optical depth of a horizontal ray from ``altitude_m`` over
    ``distance_m`` through the real (curved, stratified) atmosphere: the
    integral of sora's local extinction at the ray's altitude
    h(s) = sqrt((R + h0)^2 + s^2) - R, R the planet's radius (the atmosphere
    file's ``planet.radius_m``; Simpson's rule): the reference the haze is
    compared with."""
    radius = float(planet_radius_m)
    s = np.linspace(0.0, float(distance_m), 2 * (steps // 2) + 1)
    heights = np.sqrt((radius + altitude_m) ** 2 + s**2) - radius
    local = atmosphere.coefficients(heights, f"{wavelength_nm:g}")
    beta = local.extinction_coefficient.values[:, :, 0].sum(axis=0)
    weights = np.ones_like(s)
    weights[1:-1:2], weights[2:-1:2] = 4.0, 2.0
    return float((s[1] - s[0]) / 3.0 * np.sum(weights * beta))


def write_exr(path: str, rgb: np.ndarray) -> None:
    """Writes ``rgb`` (height, width, 3; rows top first) as a 32-bit float
    OpenEXR, scene-linear values as they are (Blender's own ``Image.save``
    applies its display transform to float images), by sora's writer
    (:func:`sora.write_exr`: atomic, the bytes ``sora render`` writes)."""
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ValueError(f"an EXR map needs (height, width, 3), not {rgb.shape}")
    sora.write_exr(path, rgb)
