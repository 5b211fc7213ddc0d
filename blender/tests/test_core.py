"""The add-on's computations without rendering: the map's units and
layout, the sun's energy, and how far the haze is from the library along a
horizontal path."""

import math

import numpy as np
import pytest

from sora_sky import core


def _solid_angles(width):
    """Solid angle and cosine-weighted solid angle (up) of each row of a
    map, bottom row first."""
    height = width // 2
    rows = np.arange(height)
    low = np.radians(-90.0 + 180.0 * rows / height)
    high = np.radians(-90.0 + 180.0 * (rows + 1) / height)
    omega = 2.0 * math.pi / width * (np.sin(high) - np.sin(low))
    omega_cos = 2.0 * math.pi / width * 0.5 * (np.sin(high) ** 2 - np.sin(low) ** 2)
    return omega, np.where(rows >= height // 2, omega_cos, 0.0)


@pytest.fixture(scope="module")
def sky_and_table():
    return core.make_sky(core.SkySettings(sun_elevation_deg=30.0, sun_azimuth_deg=137.0))


def test_pixels_weigh_to_the_broadband_radiance(sky_and_table):
    sky, _ = sky_and_table
    spectra = sky.render(camera="equirectangular", width=64, output="spectral", draw_sun_disc=False)
    rgb = core.broadband_rgb(sky, spectra)
    np.testing.assert_allclose(rgb @ core.LUMINANCE_WEIGHTS, core.broadband(sky, spectra), rtol=1e-12)
    assert np.all(rgb >= 0.0)
    # The sky is blue: more blue than red per unit luminance, overhead.
    zenith = rgb[0].mean(axis=0)
    assert zenith[2] > zenith[0]


def test_the_map_integrates_to_soras_irradiance_and_the_disc_to_the_direct_beam(sky_and_table):
    sky, table = sky_and_table
    width = 1024
    omega, omega_cos = _solid_angles(width)
    without = core.world_map(sky, width, draw_sun_disc=False) @ core.LUMINANCE_WEIGHTS
    with_disc = core.world_map(sky, width, draw_sun_disc=True) @ core.LUMINANCE_WEIGHTS
    lamp = core.sun_lamp(sky, table)
    # The disc's pixels times their solid angles: the direct normal
    # irradiance (the horizon does not cut it at 30 degrees).
    disc = ((with_disc - without) * omega[:, None]).sum()
    assert disc == pytest.approx(lamp.strength_w_m2, rel=1e-4)
    # The sky's hemisphere, cosine-weighted: the diffuse horizontal
    # irradiance as sora integrates it (its own quadrature) within 0.1 %.
    diffuse = (without * omega_cos[:, None]).sum()
    ghi_minus_direct = _diffuse_horizontal(sky)
    assert diffuse == pytest.approx(ghi_minus_direct, rel=1e-3)


def _diffuse_horizontal(sky):
    """Diffuse horizontal irradiance, W m^-2, by a fine quadrature of the
    library's views (not of the map): Gauss-Legendre in sin(elevation)."""
    mu, weights = np.polynomial.legendre.leggauss(64)
    mu, weights = 0.5 * (mu + 1.0), 0.5 * weights
    azimuths = (np.arange(128) + 0.5) * 360.0 / 128
    elevation = np.degrees(np.arcsin(mu))
    grid_e, grid_a = np.meshgrid(elevation, azimuths, indexing="ij")
    radiance = core.broadband(sky, sky.radiance(grid_e.ravel(), grid_a.ravel()).values)
    radiance = radiance.reshape(grid_e.shape).mean(axis=1)
    return float(2.0 * math.pi * np.sum(weights * mu * radiance))


def test_the_sun_is_where_blender_looks_for_it(sky_and_table):
    # The brightest pixel of the disc map, through Blender's equirectangular
    # lookup (u = 0.5 - atan2(y, x) / 2 pi, v = 0.5 + elevation / pi),
    # is the sun's direction in Blender's frame (+X east, +Y north).
    sky, _ = sky_and_table
    width = 512
    with_disc = core.world_map(sky, width, draw_sun_disc=True) @ core.LUMINANCE_WEIGHTS
    row, column = np.unravel_index(np.argmax(with_disc), with_disc.shape)
    direction = core.sun_direction(*sky.sun_position_deg)
    u = (0.5 - math.atan2(direction[1], direction[0]) / (2.0 * math.pi)) % 1.0
    v = 0.5 + math.asin(direction[2]) / math.pi
    assert (column, row) == (int(u * width), int(v * width // 2))
    # East of north: azimuth 137 is south-east, x > 0 and y < 0.
    assert direction[0] > 0 > direction[1]


def test_panel_overrides_reach_the_atmosphere():
    settings = core.SkySettings(aerosol_optical_depth=0.3, ozone_dobson_units=400.0, ground_albedo=0.3)
    atmosphere, table = core.make_atmosphere(settings)
    optics = atmosphere.optical_depths("550")
    tau = dict(zip(optics.kind.values, optics.optical_depth_extinction.values[:, 0]))
    assert tau["mie"] == pytest.approx(0.3, rel=1e-9)
    base = core.make_atmosphere(core.SkySettings())[0].optical_depths("550")
    base_tau = dict(zip(base.kind.values, base.optical_depth_extinction.values[:, 0]))
    assert tau["absorbing gas"] == pytest.approx(base_tau["absorbing gas"] * 400.0 / 300.0, rel=1e-9)
    assert table["planet"]["ground_albedo"] == 0.3
    with pytest.raises(ValueError, match="no ozone species"):
        core.make_atmosphere(core.SkySettings(preset="paper-mars", ozone_dobson_units=300.0))


#: (preset, eye altitude m, distance m) -> bounds on T_haze / T_library at
#: 549 nm, as measured (the haze darker: its optical depth does not fall
#: with the ray's rise over the curved ground).
HAZE_CASES = [
    ("earth-clear", 0.0, 1e3, 0.9999, 1.0),
    ("earth-clear", 0.0, 1e4, 0.997, 0.999),
    ("earth-clear", 0.0, 5e4, 0.79, 0.81),
    ("earth-clear", 1000.0, 5e4, 0.90, 0.91),
    ("earth-hazy", 0.0, 1e4, 0.99, 0.995),
    ("earth-hazy", 0.0, 5e4, 0.41, 0.43),
]


@pytest.mark.parametrize("preset, altitude, distance, low, high", HAZE_CASES)
def test_haze_transmittance_against_the_librarys_horizontal_path(preset, altitude, distance, low, high):
    atmosphere, table = core.make_atmosphere(core.SkySettings(preset=preset))
    haze = core.haze_coefficients(atmosphere, altitude)
    radius = table["planet"]["radius_m"]
    tau_library = core.horizontal_optical_depth(atmosphere, radius, altitude, distance, 549.0)
    tau_haze = haze.extinction[1] * distance
    ratio = math.exp(tau_library - tau_haze)
    print(
        f"\n{preset}, eye {altitude:g} m, {distance / 1e3:g} km at 549 nm: optical depth library "
        f"{tau_library:.5f}, haze {tau_haze:.5f}; transmittance {math.exp(-tau_library):.5f} vs "
        f"{math.exp(-tau_haze):.5f} (haze / library {ratio:.5f})"
    )
    assert low <= ratio <= high


def test_the_horizontal_path_is_the_uniform_one_on_a_flat_planet():
    # The reference integral: on a (nearly) flat planet the ray stays at
    # the eye's altitude, and the optical depth is beta d.
    atmosphere, _ = core.make_atmosphere(core.SkySettings())
    haze = core.haze_coefficients(atmosphere, 500.0)
    tau = core.horizontal_optical_depth(atmosphere, 1e15, 500.0, 5e4, 549.0)
    assert tau == pytest.approx(haze.extinction[1] * 5e4, rel=1e-8)
