"""Polarised skies from Python (polarisation="vector"): the Stokes Dataset,
the closed form of single Rayleigh scattering, path-traced standard errors,
and the choices that cannot give Stokes vectors."""

import warnings

import numpy as np
import pytest
import xarray as xr

import sora


@pytest.fixture(scope="module")
def rayleigh():
    return sora.Atmosphere.preset("us-standard-1976-rayleigh")


def test_single_scattering_stokes_have_the_rayleigh_degree(rayleigh):
    sky = sora.Sky(
        rayleigh,
        sun_elevation_deg=0,
        sun_azimuth_deg=90,
        scattering="single",
        polarisation="vector",
    )
    assert sky.polarisation == "vector"
    stokes = sky.stokes([90, 30], [0, 270])
    assert isinstance(stokes, xr.Dataset)
    assert stokes["Q"].dims == ("direction", "wavelength")
    assert stokes["I"].attrs["units"] == "W m-2 sr-1 nm-1"
    # 90 degrees from a sun on the horizon, at the zenith: the Rayleigh
    # maximum (1 - rho) / (1 + rho), rho of air about 0.028-0.03.
    zenith = stokes["degree_of_linear_polarisation"].isel(direction=0).values
    assert np.all((zenith > 0.93) & (zenith < 0.96))
    # The intensity is the scalar single-scattering radiance.
    scalar = sora.Sky(rayleigh, sun_elevation_deg=0, sun_azimuth_deg=90, scattering="single")
    np.testing.assert_array_equal(stokes["I"].values, scalar.radiance([90, 30], [0, 270]).values)
    assert np.all(stokes["V"].values == 0.0)
    assert "standard_error_Q" not in stokes


def test_path_traced_stokes_have_standard_errors(rayleigh):
    sky = sora.Sky(
        rayleigh,
        sun_elevation_deg=30,
        method="path-tracing",
        samples=500,
        seed=3,
        polarisation="vector",
        wavelengths_nm="450:650:100",
    )
    stokes = sky.stokes(60, 0)
    for name in ("I", "Q", "U", "V"):
        assert f"standard_error_{name}" in stokes
    # 90 degrees from the sun in its vertical: horizontally polarised, Q < 0.
    assert np.all(stokes["Q"].values < -5 * stokes["standard_error_Q"].values)
    degree = stokes["degree_of_linear_polarisation"].values
    assert np.all((degree > 0.5) & (degree < 1.0))


def test_mie_aerosols_polarise():
    sky = sora.Sky(
        sora.Atmosphere.preset("earth-clear"),
        sun_elevation_deg=30,
        scattering="single",
        polarisation="vector",
    )
    degree = sky.stokes(60, 0)["degree_of_linear_polarisation"].values
    assert np.all((degree > 0.3) & (degree < 0.95))


def test_the_fast_method_polarises_all_orders(rayleigh):
    vector = sora.Sky(rayleigh, sun_elevation_deg=30, polarisation="vector")
    scalar = sora.Sky(rayleigh, sun_elevation_deg=30, polarisation="scalar")
    stokes = vector.stokes(30, 90)
    intensity = stokes["I"].values
    ratio = intensity / scalar.radiance(30, 90).values
    assert np.all((ratio > 0.97) & (ratio < 0.999))
    # Images of a vector sky: the polarised intensity, and the Stokes XYZ
    # whose I is that image.
    image = vector.render(width=16, draw_sun_disc=False)
    scalar_image = scalar.render(width=16, draw_sun_disc=False)
    seen = scalar_image[..., 1] > 0
    change = image[..., 1][seen] / scalar_image[..., 1][seen]
    assert np.all((change > 0.93) & (change < 1.04))
    assert np.any(np.abs(change - 1) > 0.005)
    stokes = vector.render(width=16, draw_sun_disc=False, output="stokes-xyz")
    assert stokes.shape == (16, 16, 4, 3)
    np.testing.assert_array_equal(stokes[:, :, 0, :], image)
    degree = np.hypot(stokes[..., 1, 1], stokes[..., 2, 1])[seen] / image[..., 1][seen]
    assert 0.6 < degree.max() < 0.95
    with pytest.raises(ValueError, match="Polarisation::Vector"):
        scalar.render(width=8, output="stokes-xyz")


def test_choices_without_stokes_vectors_raise(rayleigh):
    with pytest.raises(ValueError, match="polarisation"):
        sora.Sky(rayleigh, sun_elevation_deg=30, method="reference", polarisation="vector")
    with pytest.raises(ValueError, match="'scalar' or 'vector'"):
        sora.Sky(rayleigh, sun_elevation_deg=30, polarisation="circular")
    with pytest.raises(ValueError, match="polarisation='vector'"):
        sora.Sky(rayleigh, sun_elevation_deg=30, polarisation="scalar").stokes(90, 0)


def test_a_non_polarising_species_is_a_warning(atmospheres_dir, tmp_path):
    # clear-sky-reference's aerosol is Henyey-Greenstein: a polarised sky
    # treats it as non-polarising and says so; a scalar sky has nothing to say.
    reference = sora.Atmosphere.preset("clear-sky-reference")
    with pytest.warns(UserWarning, match="aerosol has a Henyey-Greenstein .* non-polarising"):
        sora.Sky(reference, sun_elevation_deg=30, scattering="single", polarisation="vector")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sora.Sky(reference, sun_elevation_deg=30, scattering="single", polarisation="scalar")
        # The default (polarised) light warns only when asked for by name.
        sora.Sky(reference, sun_elevation_deg=30, scattering="single")
        sora.Sky(
            sora.Atmosphere.preset("us-standard-1976-rayleigh"),
            sun_elevation_deg=30,
            scattering="single",
            polarisation="vector",
        )
    # A depolarisation ratio above 0.5 has no polarised Rayleigh matrix:
    # a ValueError naming the species and the range; scalar light takes it.
    text = (atmospheres_dir / "clear-sky-reference.toml").read_text()
    depolarised = text.replace(
        "wavelength_exponent = 4.0 }", "wavelength_exponent = 4.0, depolarization_ratio = 0.7 }"
    )
    assert depolarised != text
    path = tmp_path / "depolarised.toml"
    path.write_text(depolarised)
    atmosphere = sora.Atmosphere.from_toml(path)
    sora.Sky(atmosphere, sun_elevation_deg=30, scattering="single", polarisation="scalar")
    with pytest.raises(ValueError, match=r'"air" depolarization_ratio = 0.7 .*0\.\.=0\.5'):
        sora.Sky(atmosphere, sun_elevation_deg=30, scattering="single", polarisation="vector")


def test_the_default_light_is_polarised_and_said_everywhere(rayleigh):
    """One default with the command line and the library: vector light,
    scalar for the reference march; repr and every DataArray say which."""
    default = sora.Sky(rayleigh, sun_elevation_deg=30, wavelengths_nm="450:650:100")
    assert default.polarisation == "vector"
    named = sora.Sky(rayleigh, sun_elevation_deg=30, wavelengths_nm="450:650:100", polarisation="vector")
    np.testing.assert_array_equal(default.radiance(40, 90).values, named.radiance(40, 90).values)
    assert "polarisation='vector'" in repr(default)
    attrs = default.radiance(40, 90).attrs
    assert attrs["polarisation"] == "vector"
    assert attrs["method"] == "fast" and attrs["scattering"] == "multiple"
    assert attrs["wavelengths_nm"] == "450:650:100"
    assert attrs["sun_elevation_deg"] == 30
    march = sora.Sky(rayleigh, sun_elevation_deg=30, wavelengths_nm="550:550:1", method="reference",
                     reference_steps=(20, 5))
    assert march.polarisation == "scalar"
    assert "polarisation='scalar'" in repr(march)
    with pytest.raises(ValueError, match="polarisation = 'off' is unknown: use 'scalar' or 'vector'"):
        sora.Sky(rayleigh, sun_elevation_deg=30, polarisation="off")
