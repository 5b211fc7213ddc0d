"""sora.Sky from Python: shapes, units, the library's invariants (views
computed together equal views computed alone; symmetry of the almucantar;
images agree with views), path tracing with standard errors, threads and
the GIL."""

import pickle
import threading
import time

import numpy as np
import pytest
import xarray as xr

import sora


@pytest.fixture(scope="module")
def atmosphere():
    return sora.Atmosphere.preset("earth-clear")


@pytest.fixture(scope="module")
def sky(atmosphere):
    return sora.Sky(atmosphere, sun_elevation_deg=30, sun_azimuth_deg=180)


def test_radiance_is_a_dataarray_with_units(sky):
    radiance = sky.radiance(90, 0)
    assert isinstance(radiance, xr.DataArray)
    assert radiance.dims == ("direction", "wavelength")
    assert radiance.shape == (1, 21)
    assert radiance.attrs["units"] == "W m-2 sr-1 nm-1"
    assert radiance.wavelength.attrs["units"] == "nm"
    assert radiance.view_elevation_deg.attrs["units"] == "deg"
    np.testing.assert_array_equal(radiance.wavelength, np.arange(380, 781, 20))
    assert np.all(radiance.values > 0)


def test_views_together_equal_views_alone(sky):
    elevation, azimuth = sky.almucantar(30)
    together = sky.radiance(elevation, azimuth).values
    for k in range(len(azimuth)):
        np.testing.assert_array_equal(together[k], sky.radiance(elevation[k], azimuth[k]).values[0])


def test_broadcasting_gives_every_direction(sky):
    radiance = sky.radiance(np.array([[10.0], [40.0]]), np.array([0.0, 90.0, 180.0]))
    assert radiance.sizes["direction"] == 6
    np.testing.assert_array_equal(radiance.view_elevation_deg, [10, 10, 10, 40, 40, 40])
    np.testing.assert_array_equal(radiance.view_azimuth_deg, [0, 90, 180, 0, 90, 180])


def test_almucantar_is_symmetric_about_the_sun(sky):
    # A horizontally uniform atmosphere: the sky is mirror-symmetric about
    # the sun's vertical (to the rounding of the angles).
    offsets = np.array([15.0, 40.0, 90.0, 150.0])
    east = sky.radiance(30.0, 180.0 - offsets).values
    west = sky.radiance(30.0, 180.0 + offsets).values
    np.testing.assert_allclose(east, west, rtol=1e-9)


def test_single_scattering_is_less_than_multiple(atmosphere):
    multiple = sora.Sky(atmosphere, sun_elevation_deg=30).radiance(90, 0).values
    single = sora.Sky(atmosphere, sun_elevation_deg=30, scattering="single").radiance(90, 0).values
    assert np.all(single < multiple)
    assert np.all(single > 0.3 * multiple)


def test_spectral_image_centre_is_the_zenith(sky):
    # An odd fisheye's centre pixel looks exactly at the zenith; images read
    # the fast method's tables, within 0.1 % of the exact view.
    image = sky.render(camera="fisheye", width=33, output="spectral", draw_sun_disc=False)
    assert image.shape == (33, 33, 21)
    zenith = sky.radiance(90, 0).values[0]
    np.testing.assert_allclose(image[16, 16], zenith, rtol=1e-3)
    assert np.all(image[0, 0] == 0)  # outside the fisheye's circle


def test_xyz_image_and_linear_srgb(sky):
    xyz = sky.render(width=24, draw_sun_disc=False)
    rgb = sky.render(width=24, output="linear-srgb", draw_sun_disc=False)
    assert xyz.shape == rgb.shape == (24, 24, 3)
    assert xyz.dtype == np.float64 and xyz.flags["C_CONTIGUOUS"]
    inside = xyz[12, 12]
    assert np.all(inside > 0)
    # A clear sky is blue: Z > X and blue > red in linear sRGB.
    assert inside[2] > inside[0] and rgb[12, 12, 2] > rgb[12, 12, 0]
    # The sRGB (IEC 61966-2-1) matrix applied to the same XYZ.
    m = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])
    np.testing.assert_allclose(rgb[12, 12], m @ xyz[12, 12], rtol=2e-3)


def test_equirectangular_default_height(sky):
    assert sky.render(camera="equirectangular", width=16, output="xyz").shape == (8, 16, 3)


def test_render_defaults_are_the_librarys_and_the_clis(atmosphere):
    import inspect

    parameters = inspect.signature(sora.Sky.render).parameters
    shown = tuple(parameters[name].default for name in ("look_elevation_deg", "look_azimuth_deg", "fov_deg"))
    assert shown == sora._sora.PERSPECTIVE_DEFAULTS == (10.0, 180.0, 90.0)
    # Image sizes as `sora render`'s: 512 x 512, 1024 x 512 for the panorama.
    small = sora.Sky(atmosphere, sun_elevation_deg=30, wavelengths_nm="500:600:100", scattering="single")
    assert small.render(output="xyz").shape == (512, 512, 3)
    assert small.render(camera="equirectangular", output="xyz").shape == (512, 1024, 3)


def test_path_tracing_standard_errors_and_seed(atmosphere):
    def traced(seed, threads):
        sora.set_num_threads(threads)
        try:
            sky = sora.Sky(atmosphere, sun_elevation_deg=30, method="path-tracing", samples=4000, seed=seed,
                           wavelengths_nm="450:650:100")
            return sky.radiance_with_error([90.0, 20.0], [0.0, 0.0])
        finally:
            sora.set_num_threads(0)

    first = traced(5, 1)
    assert first.standard_error.attrs["units"] == "W m-2 sr-1 nm-1"
    assert np.all(first.standard_error > 0)
    assert np.all(first.standard_error < 0.1 * first.radiance)
    # The same seed on another thread count: the same numbers.
    xr.testing.assert_identical(first, traced(5, 2))
    # Another seed: independent, consistent within 5 combined sigma.
    other = traced(6, 2)
    assert not np.array_equal(first.radiance.values, other.radiance.values)
    sigma = np.hypot(first.standard_error, other.standard_error)
    assert np.all(np.abs(first.radiance - other.radiance) < 5 * sigma)


def test_deterministic_methods_have_no_standard_error(sky):
    with pytest.raises(ValueError):
        sky.radiance_with_error(90, 0)


def test_thread_count_does_not_change_results(atmosphere):
    results = []
    for threads in (1, 2):
        sora.set_num_threads(threads)
        assert sora.get_num_threads() == threads
        sky = sora.Sky(atmosphere, sun_elevation_deg=12)
        results.append((sky.radiance([90, 12, 5], [0, 180, 90]).values, sky.render(width=20)))
    sora.set_num_threads(0)
    np.testing.assert_array_equal(results[0][0], results[1][0])
    np.testing.assert_array_equal(results[0][1], results[1][1])


def test_computation_releases_the_gil(atmosphere):
    # While the native call runs on a worker thread, this thread keeps
    # running Python; with the GIL held it could not run at all inside the
    # call's window.
    sky = sora.Sky(atmosphere, sun_elevation_deg=20)
    window = {}

    def work():
        window["start"] = time.perf_counter()
        sky.render(width=64)
        window["end"] = time.perf_counter()

    worker = threading.Thread(target=work)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    start, end = window["start"], window["end"]
    margin = 0.2 * (end - start)
    inside = [t for t in ticks if start + margin < t < end - margin]
    assert end - start > 0.01
    assert len(inside) > 100


def test_sun_from_time_and_location(atmosphere):
    sky = sora.Sky(atmosphere, time="2026-06-21T12:00:00+09:00", location=(35.68, 139.77, 40.0))
    elevation, azimuth = sky.sun_position_deg
    # Tokyo at noon near the June solstice: the sun high in the south.
    assert 75 < elevation < 79 and 150 < azimuth < 220
    import datetime as dt
    aware = dt.datetime(2026, 6, 21, 3, 0, tzinfo=dt.timezone.utc)
    same = sora.Sky(atmosphere, time=aware, location=(35.68, 139.77, 40.0))
    assert same.sun_position_deg == sky.sun_position_deg


def test_the_dates_sun_and_the_sites_air(atmosphere):
    # NREL SPA's example: topocentric elevation 39.88838 deg, measured air
    # 820 hPa and 11 C at 1830 m; the radius vector 0.9965422974 AU.
    spa = dict(time="2003-10-17T12:30:30-07:00", location=(39.742476, -105.1786, 1830.14),
               wavelengths_nm="500:600:100", scattering="single")
    sky = sora.Sky(atmosphere, **spa)
    assert abs(sky.sun_position_deg[0] - 39.88838) < 1e-3
    measured = sora.Sky(atmosphere, pressure_hpa=820, temperature_c=11, **spa)
    assert abs(measured.sun_position_deg[0] - 39.88838) < 1e-4
    assert abs(sky.sun_distance_au - 0.9965423) < 1e-6
    # The date's sunlight against the same sun at 1 AU: 1 / R^2.
    one_au = sora.Sky(atmosphere, sun_distance_au=1.0, **spa)
    assert one_au.sun_distance_au == 1.0
    ratio = sky.direct_normal_irradiance().values / one_au.direct_normal_irradiance().values
    np.testing.assert_allclose(ratio, sky.sun_distance_au ** -2, rtol=1e-12)
    assert sora.Sky(atmosphere, sun_elevation_deg=30).sun_distance_au is None
    with pytest.raises(ValueError, match="sun_distance_au: sun distance = 0 AU"):
        sora.Sky(atmosphere, sun_elevation_deg=30, sun_distance_au=0)
    with pytest.raises(ValueError, match="apply with time only"):
        sora.Sky(atmosphere, sun_elevation_deg=30, pressure_hpa=900)
    with pytest.raises(ValueError, match="pressure = -5 hPa"):
        sora.Sky(atmosphere, pressure_hpa=-5, **spa)
    # The location's elevation is the ground's: the same sky as the
    # atmosphere file's planet.ground_altitude_m with the same sun.
    text = sora.Atmosphere.preset_toml("earth-clear").replace(
        "atmosphere_height_m = 100e3", "atmosphere_height_m = 100e3\nground_altitude_m = 1830.14")
    raised = sora.Atmosphere.from_toml_str(text)
    elevation, azimuth = sky.sun_position_deg
    same = sora.Sky(raised, sun_elevation_deg=elevation, sun_azimuth_deg=azimuth,
                    sun_distance_au=sky.sun_distance_au, wavelengths_nm="500:600:100",
                    scattering="single")
    np.testing.assert_array_equal(sky.radiance(30, 90).values, same.radiance(30, 90).values)
    sea = sora.Sky(atmosphere, sun_elevation_deg=elevation, sun_azimuth_deg=azimuth,
                   sun_distance_au=sky.sun_distance_au, wavelengths_nm="500:600:100",
                   scattering="single")
    assert np.all(sea.radiance(30, 90).values > sky.radiance(30, 90).values)


def test_skies_and_atmospheres_pickle(sky):
    copy = pickle.loads(pickle.dumps(sky))
    np.testing.assert_array_equal(copy.radiance(45, 10).values, sky.radiance(45, 10).values)


def test_direct_normal_irradiance(atmosphere):
    high = sora.Sky(atmosphere, sun_elevation_deg=60).direct_normal_irradiance()
    low = sora.Sky(atmosphere, sun_elevation_deg=5).direct_normal_irradiance()
    assert high.attrs["units"] == "W m-2 nm-1"
    # A longer path through the air: less light, and redder.
    assert np.all(low < high)
    assert (low[0] / high[0]) < (low[-1] / high[-1])


def test_colour_of_spectra_is_the_images_colour(sky):
    spectral = sky.render(camera="equirectangular", width=32, output="spectral", draw_sun_disc=False)
    for output in ("xyz", "linear-srgb"):
        image = sky.render(camera="equirectangular", width=32, output=output, draw_sun_disc=False)
        np.testing.assert_allclose(sky.colour(spectral, output), image, rtol=1e-12, atol=0)
    direct = sky.direct_normal_irradiance()
    assert sky.colour(direct.values).shape == (3,)
    with pytest.raises(ValueError, match="spectra have 3 values each"):
        sky.colour(np.ones((2, 3)))
    with pytest.raises(ValueError, match="output = 'rgb' is unknown"):
        sky.colour(direct.values, "rgb")


def test_write_exr_writes_through_the_librarys_writer(tmp_path):
    rgb = np.arange(2 * 3 * 3, dtype=float).reshape(2, 3, 3) / 7.0
    path = tmp_path / "map.exr"
    sora.write_exr(path, rgb)
    data = path.read_bytes()
    # OpenEXR's magic number, and the three channels named in its header.
    assert data[:4] == bytes([0x76, 0x2F, 0x31, 0x01])
    assert b"channels" in data and b"R\x00" in data
    assert [p.name for p in tmp_path.iterdir()] == ["map.exr"]
    bad = rgb.copy()
    bad[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match=r"pixel \(2, 1\) channel R"):
        sora.write_exr(tmp_path / "nan.exr", bad)
    with pytest.raises(ValueError, match="needs \\(height, width, 3\\)"):
        sora.write_exr(tmp_path / "flat.exr", rgb[0])
    # The library's one check of output paths refuses a missing folder.
    with pytest.raises(ValueError, match="does not exist"):
        sora.write_exr(tmp_path / "no-such-folder" / "map.exr", rgb)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map.exr"]


def test_aerial_perspective_is_a_dataset_that_broadcasts(sky):
    far = sky.aerial_perspective(np.array([[5.0], [30.0]]), np.array([0.0, 180.0]), 1e9)
    assert isinstance(far, xr.Dataset)
    assert far.radiance.shape == (4, 21)
    assert far.radiance.attrs["units"] == "W m-2 sr-1 nm-1"
    assert far.transmittance.attrs["units"] == "1"
    assert far.sky_irradiance_at_point.attrs["units"] == "W m-2 nm-1"
    assert far.distance_m.attrs["units"] == "m"
    # Past the atmosphere the segment is the whole view: the sky's radiance.
    sky_radiance = sky.radiance(np.array([[5.0], [30.0]]), np.array([0.0, 180.0])).values
    np.testing.assert_allclose(far.radiance.values, sky_radiance, rtol=1e-12)
    near = sky.aerial_perspective(5.0, 0.0, [1.0, 1e3, 1e4])
    assert np.all(np.diff(near.radiance.values, axis=0) > 0)
    assert np.all(np.diff(near.transmittance.values, axis=0) < 0)
    assert np.all((near.transmittance.values > 0) & (near.transmittance.values < 1))


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan")])
def test_aerial_perspective_refuses_bad_distances(sky, bad):
    with pytest.raises(ValueError, match="distance_m"):
        sky.aerial_perspective(5.0, 0.0, bad)
