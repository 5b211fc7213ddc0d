"""sora.Atmosphere: presets, files, text and dicts give the same
atmosphere; optical depths as an xarray Dataset with units."""

import numpy as np
import pytest
import xarray as xr

import sora


def test_presets_are_listed_and_load():
    names = sora.Atmosphere.presets()
    assert "earth-clear" in names and "mars-dust" in names
    for name in names:
        assert sora.Atmosphere.preset(name).species_names


def test_optical_depths(atmospheres_dir):
    depths = sora.Atmosphere.preset("earth-clear").optical_depths("400:700:50")
    assert list(depths.wavelength.values) == [400, 450, 500, 550, 600, 650, 700]
    assert isinstance(depths, xr.Dataset)
    assert depths.optical_depth_extinction.dims == ("species", "wavelength")
    assert depths.solar_irradiance.attrs["units"] == "W m-2 nm-1"
    assert depths.wavelength.attrs["units"] == "nm"
    air = depths.sel(species=depths.species[depths.kind == "rayleigh"][0])
    tau = air.optical_depth_scattering.values
    # Rayleigh optical depth ~ lambda^-4 (plus the dispersion of n - 1):
    # between 4 and 4.3 over the visible, about 0.1 at 550 nm.
    exponent = -np.log(tau[-1] / tau[0]) / np.log(700 / 400)
    assert 4.0 < exponent < 4.3
    assert 0.08 < float(air.optical_depth_scattering.sel(wavelength=550.0)) < 0.11
    np.testing.assert_allclose(depths.optical_depth_total, depths.optical_depth_extinction.sum("species"))


def test_file_text_dict_and_preset_agree(atmospheres_dir):
    path = atmospheres_dir / "earth-clear.toml"
    reference = sora.Atmosphere.preset("earth-clear").optical_depths()
    from_file = sora.Atmosphere.from_toml(path).optical_depths()
    from_text = sora.Atmosphere.from_toml_str(path.read_text()).optical_depths()
    xr.testing.assert_identical(reference, from_file)
    xr.testing.assert_identical(reference, from_text)
    tomllib = pytest.importorskip("tomllib")
    from_dict = sora.Atmosphere.from_dict(tomllib.loads(path.read_text())).optical_depths()
    xr.testing.assert_identical(reference, from_dict)


def test_a_dict_change_changes_the_sky(atmospheres_dir):
    tomllib = pytest.importorskip("tomllib")
    table = tomllib.loads((atmospheres_dir / "earth-clear.toml").read_text())
    table["planet"]["ground_albedo"] = 0.8
    bright = sora.Atmosphere.from_dict(table)
    base = sora.Atmosphere.preset("earth-clear")
    up = dict(sun_elevation_deg=40, wavelengths_nm="500:600:100")
    assert np.all(sora.Sky(bright, **up).radiance(10, 0).values > sora.Sky(base, **up).radiance(10, 0).values)


def test_preset_toml_is_the_presets_text():
    text = sora.Atmosphere.preset_toml("earth-clear")
    from_text = sora.Atmosphere.from_toml_str(text).optical_depths()
    preset = sora.Atmosphere.preset("earth-clear").optical_depths()
    np.testing.assert_array_equal(from_text.optical_depth_extinction, preset.optical_depth_extinction)
    with pytest.raises(ValueError, match="'earth-claer' is not a preset.*did you mean earth-clear"):
        sora.Atmosphere.preset_toml("earth-claer")


def test_coefficients_integrate_to_the_vertical_optical_depths():
    # The local coefficients, integrated from the ground to the top, are
    # the column optical depths (exponential air and aerosol, ozone's tent).
    atmosphere = sora.Atmosphere.preset("earth-clear")
    altitudes = np.linspace(0.0, 100e3, 20001)
    local = atmosphere.coefficients(altitudes, "400:700:100")
    assert local.extinction_coefficient.dims == ("species", "altitude", "wavelength")
    assert local.extinction_coefficient.attrs["units"] == "m-1"
    columns = atmosphere.optical_depths("400:700:100")
    for name, column in (
        ("extinction_coefficient", columns.optical_depth_extinction),
        ("scattering_coefficient", columns.optical_depth_scattering),
    ):
        values = local[name].values
        step = altitudes[1] - altitudes[0]
        integral = step * (values.sum(axis=1) - 0.5 * (values[:, 0] + values[:, -1]))
        np.testing.assert_allclose(integral, column.values, rtol=2e-5)
    np.testing.assert_array_equal(local.asymmetry_parameter, columns.asymmetry_parameter)
    # Air at the ground: the Rayleigh optical depth over the column of an
    # exponential of scale height 8435 m cut at 100 km.
    ground = atmosphere.coefficients(0.0, "400:700:100").extinction_coefficient.sel(species="air")
    column_m = 8435.0 * (1.0 - np.exp(-100e3 / 8435.0))
    np.testing.assert_allclose(
        ground.values[0], columns.optical_depth_extinction.sel(species="air").values / column_m, rtol=1e-12
    )


@pytest.mark.parametrize("altitude", [-1.0, 100e3 + 1.0, float("nan")])
def test_coefficients_refuse_altitudes_outside_the_atmosphere(altitude):
    with pytest.raises(ValueError, match=r"altitude_m = .* m is out of range"):
        sora.Atmosphere.preset("earth-clear").coefficients([0.0, altitude])
