"""Bad input raises a Python exception with a one-line message naming the
bad value; nothing panics across the boundary."""

import math

import numpy as np
import pytest

import sora


def one_line(error_info):
    message = str(error_info.value)
    assert message and "\n" not in message, repr(message)
    assert "panicked" not in message
    return message


@pytest.fixture(scope="module")
def atmosphere():
    return sora.Atmosphere.preset("earth-clear")


@pytest.fixture(scope="module")
def sky(atmosphere):
    return sora.Sky(atmosphere, sun_elevation_deg=30, scattering="single")


def test_nan_view_elevation(sky):
    with pytest.raises(ValueError) as error:
        sky.radiance([10.0, math.nan], [0.0, 0.0])
    message = one_line(error)
    assert "direction 1" in message and "NaN" in message and "deg" in message


def test_nan_sun_elevation(atmosphere):
    with pytest.raises(ValueError) as error:
        sora.Sky(atmosphere, sun_elevation_deg=float("nan"))
    message = one_line(error)
    assert "sun_elevation_deg" in message and "NaN" in message


def test_sun_elevation_out_of_range(atmosphere):
    with pytest.raises(ValueError) as error:
        sora.Sky(atmosphere, sun_elevation_deg=91)
    assert "91" in one_line(error)


def test_negative_size_parameter():
    with pytest.raises(ValueError) as error:
        sora.mie.efficiencies(1.5 + 0.01j, [1.0, 2.0, -1.0])
    message = one_line(error)
    assert "sphere 2" in message and "x = -1" in message


def test_miepython_sign_convention_is_explained():
    with pytest.raises(ValueError) as error:
        sora.mie.efficiencies(1.5 - 0.01j, 1.0)
    message = one_line(error)
    assert "m.conjugate()" in message and "miepython" in message


def test_unknown_preset():
    with pytest.raises(ValueError) as error:
        sora.Atmosphere.preset("earth-claer")
    message = one_line(error)
    assert "earth-claer" in message and "earth-clear" in message


def test_malformed_dict_wrong_type():
    with pytest.raises(ValueError) as error:
        sora.Atmosphere.from_dict({"planet": {"radius_m": None}})
    message = one_line(error)
    assert "planet.radius_m" in message and "None" in message


def test_malformed_dict_bad_value(atmospheres_dir):
    tomllib = pytest.importorskip("tomllib")
    table = tomllib.loads((atmospheres_dir / "earth-clear.toml").read_text())
    table["planet"]["radius_m"] = -5.0
    with pytest.raises(ValueError) as error:
        sora.Atmosphere.from_dict(table)
    message = one_line(error)
    assert "radius_m" in message and "-5" in message


def test_dict_that_is_not_a_dict():
    with pytest.raises(ValueError) as error:
        sora.Atmosphere.from_dict(["planet"])
    assert "list" in one_line(error)


def test_wrong_array_shape(sky):
    with pytest.raises(ValueError) as error:
        sky.radiance(np.zeros(3), np.zeros(2))
    message = one_line(error)
    assert "(3,)" in message and "(2,)" in message and "view_azimuth_deg" in message


def test_wrong_shape_of_wavelengths(atmosphere):
    with pytest.raises(ValueError) as error:
        sora.Sky(atmosphere, sun_elevation_deg=30, wavelengths_nm=np.zeros((2, 2)))
    assert "1-D" in one_line(error)


def test_uneven_wavelengths(atmosphere):
    with pytest.raises(ValueError) as error:
        sora.Sky(atmosphere, sun_elevation_deg=30, wavelengths_nm=[400, 450, 550])
    assert "evenly spaced" in one_line(error)


def test_wavelength_outside_the_range(atmosphere):
    with pytest.raises(ValueError) as error:
        sora.Sky(atmosphere, sun_elevation_deg=30, wavelengths_nm="290:700:10")
    message = one_line(error)
    assert "290" in message and "nm" in message and "300..=1100" in message


def test_missing_file_is_an_os_error(tmp_path):
    with pytest.raises(OSError) as error:
        sora.Atmosphere.from_toml(tmp_path / "missing.toml")
    assert "missing.toml" in one_line(error)


def test_missing_named_file_is_an_os_error(atmospheres_dir, tmp_path):
    text = (atmospheres_dir / "earth-clear.toml").read_text()
    named = text.replace('spectrum = "astm-e490"', 'spectrum = "csv"\ncsv_file = "no-such-sun.csv"', 1)
    assert named != text
    broken = tmp_path / "broken.toml"
    broken.write_text(named)
    with pytest.raises(OSError) as error:
        sora.Atmosphere.from_toml(broken)
    message = one_line(error)
    assert "no-such-sun.csv" in message and "sun.csv_file" in message


def test_unknown_method_and_scattering(atmosphere):
    with pytest.raises(ValueError) as error:
        sora.Sky(atmosphere, sun_elevation_deg=30, method="slow")
    assert "'slow'" in one_line(error)
    with pytest.raises(ValueError) as error:
        sora.Sky(atmosphere, sun_elevation_deg=30, scattering="double")
    assert "'double'" in one_line(error)


def test_path_tracing_with_too_few_samples(atmosphere):
    with pytest.raises(ValueError) as error:
        sora.Sky(atmosphere, sun_elevation_deg=30, method="path-tracing", samples=1)
    assert "samples" in one_line(error)


def test_path_tracing_renders_no_images(atmosphere):
    sky = sora.Sky(atmosphere, sun_elevation_deg=30, method="path-tracing", samples=10)
    with pytest.raises(ValueError) as error:
        sky.render(width=8)
    assert "path tracing" in one_line(error)


def test_image_too_large(sky):
    with pytest.raises(ValueError) as error:
        sky.render(width=100_000)
    assert "100000" in one_line(error)


def test_no_sun(atmosphere):
    with pytest.raises(ValueError) as error:
        sora.Sky(atmosphere)
    assert "sun_elevation_deg" in one_line(error)


def test_bad_time(atmosphere):
    with pytest.raises(ValueError) as error:
        sora.Sky(atmosphere, time="yesterday", location=(35.0, 139.0))
    assert "time" in one_line(error)


def test_phase_function_angle_out_of_range():
    with pytest.raises(ValueError) as error:
        sora.mie.phase_function(1.5, 2.0, [0.0, 190.0])
    assert "190" in one_line(error)


def test_non_numeric_input():
    with pytest.raises(ValueError) as error:
        sora.mie.efficiencies(1.5, "big")
    assert "x" in one_line(error)
