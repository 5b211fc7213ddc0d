"""Bad input raises a Python exception with a one-line message naming the
bad value; nothing panics across the boundary. The second part holds
inputs that once hung, panicked or raised an undocumented exception type
(OverflowError, MemoryError, PanicException): each now returns a correct
result or raises ValueError or TypeError (before any work: the limits are
checked on the arguments, so a call that returns at all has not hung)."""

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
        sora.Sky(atmosphere, sun_elevation_deg=30, wavelengths_nm="270:700:10")
    message = one_line(error)
    assert "270" in message and "nm" in message and "280..=2500" in message


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


NO_SPECIES = """
name = "vacuum"
[planet]
radius_m = 6360e3
atmosphere_height_m = 100e3
[sun]
spectrum = "flat"
irradiance_w_m2_nm = 1.0
"""


@pytest.fixture(scope="module")
def small_sky():
    return sora.Sky(
        sora.Atmosphere.preset("clear-sky-reference"),
        sun_elevation_deg=30,
        scattering="single",
        wavelengths_nm="500:600:100",
    )


def test_no_species_under_a_low_sun_is_a_black_sky():
    vacuum = sora.Atmosphere.from_toml_str(NO_SPECIES)
    for polarisation in ("scalar", "vector"):
        sky = sora.Sky(vacuum, sun_elevation_deg=5, polarisation=polarisation, wavelengths_nm="500:600:100")
        assert np.all(sky.radiance(20, 0).values == 0.0)
        assert np.all(np.isfinite(sky.render(width=8)))


@pytest.mark.parametrize("m", [complex("nan"), complex(1.5, math.nan), complex(math.nan, 0.01), None])
def test_mie_efficiencies_of_a_nan_or_missing_index_return_at_once(m):
    expected = TypeError if m is None else ValueError
    with pytest.raises(expected) as error:
        sora.mie.efficiencies(m, 1.0)
    message = one_line(error)
    assert "m" in message


def test_a_tiny_almucantar_step_is_refused_by_the_direction_limit(small_sky):
    with pytest.raises(ValueError) as error:
        small_sky.almucantar(1e-300)
    assert "more than the limit of 100000" in one_line(error)
    # At the limit's edge: 0.0036 deg gives 100,000 directions.
    elevation, azimuth = small_sky.almucantar(0.0036)
    assert len(azimuth) == 100_000


@pytest.mark.parametrize(
    "arguments, exception, words",
    [
        (dict(sun_elevation_deg=10**400), ValueError, "sun_elevation_deg"),
        (dict(sun_elevation_deg=30, method="path-tracing", samples=-1), ValueError, "samples = -1"),
        (dict(sun_elevation_deg=30, method="path-tracing", seed=-1), ValueError, "seed = -1"),
        (dict(sun_elevation_deg=30, method="path-tracing", samples=10**30), ValueError, "samples"),
        (dict(sun_elevation_deg=30, method="reference", reference_steps=(-1, 5)), ValueError, "view steps = -1"),
        (dict(sun_elevation_deg=30, method="reference", reference_steps=(10, 10**20)), ValueError, "sun steps"),
        (dict(sun_elevation_deg=30, method="reference", reference_steps=(10**7, 10**7)), ValueError, "view steps x sun steps"),
        (dict(sun_elevation_deg=None), ValueError, "sun_elevation_deg"),
        (dict(sun_elevation_deg="30"), TypeError, "sun_elevation_deg"),
        (dict(sun_elevation_deg=30, observer_altitude_m=None), TypeError, "observer_altitude_m"),
        (dict(sun_elevation_deg=30, method=None), TypeError, "method"),
        (dict(sun_elevation_deg=30, wavelengths_nm="380:inf:20"), ValueError, "wavelengths_nm"),
        (dict(sun_elevation_deg=30, wavelengths_nm="380:780:1e-9"), ValueError, "wavelengths_nm"),
    ],
)
def test_sky_arguments_raise_documented_exceptions(atmosphere, arguments, exception, words):
    with pytest.raises(exception) as error:
        sora.Sky(atmosphere, **arguments)
    assert words in one_line(error)


@pytest.mark.parametrize(
    "arguments, exception, words",
    [
        (dict(width=-1), ValueError, "width = -1"),
        (dict(width=16385), ValueError, "width = 16385"),
        (dict(width=8, height=-3), ValueError, "height = -3"),
        (dict(width=8.5), TypeError, "width"),
        (dict(width=8, fov_deg=10**400), ValueError, "fov_deg"),
        (dict(width=8, camera=3), TypeError, "camera"),
    ],
)
def test_render_arguments_raise_documented_exceptions(small_sky, arguments, exception, words):
    with pytest.raises(exception) as error:
        small_sky.render(**arguments)
    assert words in one_line(error)


def test_set_num_threads_refuses_negative_and_huge_counts():
    for threads in (-1, 10**30, 5000):
        with pytest.raises(ValueError) as error:
            sora.set_num_threads(threads)
        assert "threads" in one_line(error)
    with pytest.raises(TypeError):
        sora.set_num_threads(1.5)
    sora.set_num_threads(0)


@pytest.mark.parametrize("wavelengths", ["380:inf:20", "380:780:1e-9", "380:780", "a:b:c"])
def test_mie_wavelength_strings_are_checked_as_the_command_line_checks_them(wavelengths):
    with pytest.raises(ValueError) as error:
        sora.mie.lognormal(1.5 + 0.01j, 0.1, 2.0, wavelengths_nm=wavelengths)
    assert "wavelengths_nm" in one_line(error)


def test_mie_ensemble_numbers_are_checked():
    with pytest.raises(ValueError) as error:
        sora.mie.lognormal(1.5, 10**400, 2.0)
    assert "median_radius_um" in one_line(error)
    with pytest.raises(TypeError):
        sora.mie.gamma(None, 1.0, 0.1)
    with pytest.raises(TypeError):
        sora.mie.phase_function(None, 1.0, [0.0])


def test_a_bad_atmosphere_height_names_the_key():
    text = NO_SPECIES.replace("100e3", "1e-9")
    with pytest.raises(ValueError) as error:
        sora.Atmosphere.from_toml_str(text)
    assert "planet.atmosphere_height_m = 1e-9 m is out of range" in one_line(error)


def test_an_endless_atmosphere_file_is_too_large(tmp_path):
    huge = tmp_path / "huge.toml"
    with open(huge, "wb") as file:
        file.truncate(300_000_000)
    with pytest.raises(OSError) as error:
        sora.Atmosphere.from_toml(huge)
    assert "file too large" in one_line(error)
