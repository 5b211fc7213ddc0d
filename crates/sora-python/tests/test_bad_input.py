"""One rule for bad input, as the command line's (README, "Errors"): a
value out of range is a ValueError with the library's message, the one
``sora`` prints with exit status 1; azimuths are angles, read modulo 360;
the sky's choices are the library's names."""

import subprocess

import numpy as np
import pytest

import sora


@pytest.fixture(scope="module")
def sky():
    return sora.Sky(sora.Atmosphere.preset("earth-clear"), sun_elevation_deg=30,
                    scattering="single", wavelengths_nm="500:600:100")


@pytest.mark.parametrize("width", [-5, 0])
def test_bad_widths_are_the_cli_message(sora_cli, sky, tmp_path, width):
    with pytest.raises(ValueError) as error:
        sky.render(width=width)
    message = str(error.value)
    assert message == f"image width = {width} pixels is out of range: allowed 1..=16384 pixels"
    output = tmp_path / "sky.png"
    cli = subprocess.run([str(sora_cli), "render", "--preset", "earth-clear", "--sun-elevation", "30",
                          f"--width={width}", "-o", str(output)], capture_output=True, text=True)
    assert cli.returncode == 1
    assert cli.stderr == f"error: {message}\n"
    assert not output.exists()


@pytest.mark.parametrize("python, cli, library", [
    ({"wavelengths_nm": "200:800:10"}, ["--sun-elevation", "30", "--wavelengths", "200:800:10"],
     "start_nm = 200 nm is out of range: allowed 280..=2500 nm"),
    ({"sun_elevation_deg": 95}, ["--sun-elevation", "95"],
     "sun elevation = 95 deg is out of range: allowed -90..=90 deg"),
])
def test_out_of_range_values_are_the_librarys_message(sora_cli, python, cli, library):
    # The sky's ValueError and the command's one line (status 1) both end in
    # the library's message, whichever parser read the value first.
    settings = {"sun_elevation_deg": 30, **python}
    with pytest.raises(ValueError) as error:
        sora.Sky(sora.Atmosphere.preset("earth-clear"), **settings)
    assert str(error.value).endswith(library), str(error.value)
    command = [str(sora_cli), "spectrum", "--preset", "earth-clear", "--view-elevation", "10",
               "--view-azimuth", "0", *cli]
    result = subprocess.run(command, capture_output=True, text=True)
    assert result.returncode == 1, result
    assert result.stderr.startswith("error: ") and result.stderr.endswith(f"{library}\n"), result.stderr
    assert result.stderr.count("\n") == 1, result.stderr
    assert result.stdout == ""


def test_a_bad_height_is_the_librarys_message(sky):
    with pytest.raises(ValueError, match=r"^image height = -3 pixels is out of range"):
        sky.render(width=8, height=-3)


def test_azimuths_are_read_modulo_360():
    atmosphere = sora.Atmosphere.preset("earth-clear")

    def radiance(sun_azimuth, view_azimuth):
        sky = sora.Sky(atmosphere, sun_elevation_deg=30, sun_azimuth_deg=sun_azimuth,
                       wavelengths_nm="450:650:100")
        return sky.radiance(20, view_azimuth).values[0]

    base = radiance(320, 40)
    for sun, view in [(-400, 40), (320, 400), (680, -320)]:
        # The same direction up to the rounding of the sine and cosine.
        np.testing.assert_allclose(radiance(sun, view), base, rtol=1e-9, atol=0)
    with pytest.raises(ValueError, match="azimuth"):
        radiance(320, float("inf"))


def test_the_choices_are_the_librarys_names():
    atmosphere = sora.Atmosphere.preset("earth-clear")
    with pytest.raises(ValueError, match="^method: 'slow' is unknown: use 'fast', 'reference' or 'path-tracing'$"):
        sora.Sky(atmosphere, sun_elevation_deg=30, method="slow")
    with pytest.raises(ValueError, match="^scattering: 'double' is unknown: use 'single' or 'multiple'$"):
        sora.Sky(atmosphere, sun_elevation_deg=30, scattering="double")
    sky = sora.Sky(atmosphere, sun_elevation_deg=30, method="path-tracing", samples=10)
    assert (sky.method, sky.scattering) == ("path-tracing", "multiple")
    small = sora.Sky(atmosphere, sun_elevation_deg=30, scattering="single", wavelengths_nm="550")
    # The panorama's older name still reads.
    np.testing.assert_array_equal(small.render("equirect", width=8),
                                  small.render("equirectangular", width=8))
    with pytest.raises(ValueError, match="camera: 'cube' is unknown"):
        small.render("cube", width=8)
