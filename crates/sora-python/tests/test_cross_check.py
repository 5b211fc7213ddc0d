"""The bindings against the Rust library and the command line: the same
code path, so the values agree to 1e-12 relative (in fact to the bit);
against the CLI's JSON (every digit of each f64), to 1e-12 relative too."""

import json
import subprocess

import numpy as np
import pytest

import sora


def library_values(binary, preset, sun, scattering, method, grid, views):
    arguments = [str(binary), preset, str(sun[0]), str(sun[1]), scattering, method, grid]
    arguments += [f"{e},{a}" for e, a in views]
    output = subprocess.run(arguments, check=True, capture_output=True, text=True).stdout
    rows = [line.split() for line in output.strip().splitlines()]
    return np.array([[float(v) for v in row[2:]] for row in rows])


CASES = [
    ("earth-clear", (30.0, 180.0), "multiple", "fast", "fast", "380:780:20"),
    ("paper-earth", (36.0, 207.0), "single", "fast", "fast", "400:700:50"),
    ("mars-dust", (5.0, 270.0), "multiple", "fast", "fast", "380:780:40"),
    ("clear-sky-reference", (36.0, 207.0), "multiple", "path-tracing", "path-tracing:400:7", "450:650:100"),
]


@pytest.mark.parametrize("preset, sun, scattering, method, rust_method, grid", CASES)
def test_radiance_equals_the_rust_library(radiance_values, preset, sun, scattering, method, rust_method, grid):
    views = [(90.0, 0.0), (17.0, 347.0), (sun[0], sun[1] + 10.0), (2.0, 90.0)]
    expected = library_values(radiance_values, preset, sun, scattering, rust_method, grid, views)
    options = dict(samples=400, seed=7) if method == "path-tracing" else {}
    sky = sora.Sky(
        sora.Atmosphere.preset(preset), sun_elevation_deg=sun[0], sun_azimuth_deg=sun[1],
        wavelengths_nm=grid, scattering=scattering, method=method, **options,
    )
    got = sky.radiance([v[0] for v in views], [v[1] for v in views]).values
    assert got.shape == expected.shape
    assert np.all(expected > 0)
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=0)


@pytest.mark.parametrize("polarisation", [None, "scalar"])
def test_almucantar_equals_the_cli(sora_cli, polarisation):
    """The defaults of the two front ends (polarised light) give the same
    radiance, and so does scalar light asked for by the same name."""
    option = [] if polarisation is None else ["--polarisation", polarisation]
    output = subprocess.run(
        [str(sora_cli), "spectrum", "--preset", "earth-hazy", "--sun-elevation", "20",
         "--sun-azimuth", "135", "--almucantar", "30", "--format", "json", *option],
        check=True, capture_output=True, text=True,
    ).stdout
    cli = json.loads(output)
    sky = sora.Sky(sora.Atmosphere.preset("earth-hazy"), sun_elevation_deg=20, sun_azimuth_deg=135,
                   polarisation=polarisation)
    assert sky.polarisation == cli["polarisation"] == (polarisation or "vector")
    elevation, azimuth = sky.almucantar(30)
    got = sky.radiance(elevation, azimuth)
    np.testing.assert_array_equal(got.wavelength.values, cli["wavelength_nm"])
    assert len(cli["directions"]) == got.sizes["direction"] == 12
    for k, direction in enumerate(cli["directions"]):
        assert direction["view_azimuth_deg"] == azimuth[k]
        # The JSON holds every digit: the defaults agree far inside 1e-9.
        np.testing.assert_allclose(got.values[k], direction["radiance_w_m2_sr_nm"], rtol=1e-12, atol=0)


def test_mie_batch_equals_the_cli(sora_cli, tmp_path):
    rng = np.random.default_rng(3)
    x = np.concatenate([np.logspace(-3, 4, 40), rng.uniform(0.1, 50, 20)])
    m = np.where(np.arange(x.size) % 3 == 0, 1.33 + 0j, 1.5 + 0.01j)
    m[5] = 2.0 + 1.0j
    csv = tmp_path / "spheres.csv"
    csv.write_text("m_re,m_im,x\n" + "".join(f"{float(a.real)!r},{float(a.imag)!r},{float(b)!r}\n" for a, b in zip(m, x)))
    output = subprocess.run([str(sora_cli), "mie", "--batch", str(csv)], check=True, capture_output=True, text=True).stdout
    table = np.array([[float(v) for v in line.split(",")] for line in output.strip().splitlines()[1:]])
    q = sora.mie.efficiencies(m, x)
    for column, name in enumerate(["qext", "qsca", "qabs", "qback", "g"], start=3):
        # The batched solver agrees with one-sphere calls to rounding (1e-13).
        np.testing.assert_allclose(getattr(q, name), table[:, column], rtol=1e-12, atol=1e-300, err_msg=name)


def test_lognormal_equals_the_cli(sora_cli):
    output = subprocess.run(
        [str(sora_cli), "mie", "--m", "1.5+0.01i", "--lognormal", "0.1,2.0,0.1,2.5", "--wavelengths", "400:700:100"],
        check=True, capture_output=True, text=True,
    ).stdout
    table = np.array([[float(v) for v in line.split(",")] for line in output.strip().splitlines()[1:]])
    got = sora.mie.lognormal(1.5 + 0.01j, 0.1, 2.0, wavelengths_nm="400:700:100", radius_window_um=(0.1, 2.5))
    np.testing.assert_array_equal(got.wavelength.values, table[:, 0])
    names = ["extinction_cross_section", "scattering_cross_section", "absorption_cross_section",
             "single_scattering_albedo", "asymmetry_parameter", "paper_asymmetry_parameter",
             "number_fraction_in_window"]
    for column, name in enumerate(names, start=1):
        # The CLI prints 13 significant digits.
        np.testing.assert_allclose(got[name].values, table[:, column], rtol=1e-12, err_msg=name)


def test_streams_and_layers_equal_the_cli(sora_cli):
    """The field's resolution has one spelling: Python's streams= and
    layers= give what ``sora spectrum --streams --layers`` gives, and a finer
    field moves the zenith by well under 1 %."""
    command = [str(sora_cli), "spectrum", "--preset", "earth-clear", "--sun-elevation", "30",
               "--view-elevation", "90", "--view-azimuth", "0", "--format", "json",
               "--streams", "12", "--layers", "60"]
    cli = json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)
    atmosphere = sora.Atmosphere.preset("earth-clear")
    finer = sora.Sky(atmosphere, sun_elevation_deg=30, streams=12, layers=60)
    default = sora.Sky(atmosphere, sun_elevation_deg=30)
    got = finer.radiance(90, 0).values[0]
    np.testing.assert_allclose(got, cli["radiance_w_m2_sr_nm"], rtol=1e-12, atol=0)
    baseline = default.radiance(90, 0).values[0]
    assert np.all(got != baseline)
    np.testing.assert_allclose(got, baseline, rtol=1e-2, atol=0)
    for keywords, message in [
        (dict(streams=40), "streams per hemisphere = 40"),
        (dict(layers=1), "multiple-scattering layers = 1"),
        (dict(scattering="single", streams=12), "streams and layers apply to multiple scattering"),
        (dict(method="path-tracing", layers=60), "streams and layers apply to the fast and reference methods"),
    ]:
        with pytest.raises(ValueError, match=message):
            sora.Sky(atmosphere, sun_elevation_deg=30, **keywords)


def test_twilight_shift_pieces_equal_the_cli(sora_cli):
    """The after-sunset shift in pieces has one spelling: Python's
    twilight_shift_pieces= gives what ``sora spectrum --twilight-shift-pieces``
    gives; after sunset it moves the red by a fraction of a percent, by day
    it changes nothing, and 0 pieces is refused."""
    view = ["--view-elevation", "5", "--view-azimuth", "0", "--wavelengths", "560:680:120", "--format", "json"]
    atmosphere = sora.Atmosphere.preset("earth-hazy")
    for sun, moves in [(-2, True), (30, False)]:
        command = [str(sora_cli), "spectrum", "--preset", "earth-hazy", "--sun-elevation", str(sun),
                   *view, "--twilight-shift-pieces", "3"]
        cli = json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)
        wavelengths = dict(wavelengths_nm="560:680:120")
        pieces = sora.Sky(atmosphere, sun_elevation_deg=sun, twilight_shift_pieces=3, **wavelengths)
        whole = sora.Sky(atmosphere, sun_elevation_deg=sun, **wavelengths)
        got = pieces.radiance(5, 0).values[0]
        np.testing.assert_allclose(got, cli["radiance_w_m2_sr_nm"], rtol=1e-12, atol=0)
        baseline = whole.radiance(5, 0).values[0]
        if moves:
            assert np.all(got != baseline)
            np.testing.assert_allclose(got, baseline, rtol=2e-2, atol=0)
        else:
            np.testing.assert_array_equal(got, baseline)
    with pytest.raises(ValueError, match="twilight shift pieces = 0 is out of range"):
        sora.Sky(atmosphere, sun_elevation_deg=-2, twilight_shift_pieces=0)
