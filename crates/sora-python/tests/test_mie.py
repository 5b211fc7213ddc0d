"""sora.mie against closed forms and conservation laws: the Rayleigh limit,
the extinction paradox, Q_ext = Q_sca + Q_abs, the phase function's
normalisation, broadcasting and thread independence."""

import numpy as np
import pytest

import sora


def test_broadcasting_shapes():
    m = np.array([1.33 + 0j, 1.5 + 0.01j])[:, None]
    x = np.logspace(-1, 2, 7)[None, :]
    q = sora.mie.efficiencies(m, x)
    assert q.qext.shape == (2, 7)
    for k in range(2):
        single = sora.mie.efficiencies(m[k, 0], x[0])
        np.testing.assert_allclose(q.qext[k], single.qext, rtol=1e-13)
    assert np.isscalar(sora.mie.efficiencies(1.5, 1.0).qext.item())


def test_rayleigh_limit():
    # x << 1: Q_sca = 8/3 x^4 |K|^2, Q_abs = 4 x Im(K), K = (m^2-1)/(m^2+2)
    # (Bohren & Huffman eq. 5.8, 5.9), to O(x^2).
    m = 1.5 + 0.01j
    x = np.array([1e-3, 3e-3])
    k = (m * m - 1) / (m * m + 2)
    q = sora.mie.efficiencies(m, x)
    np.testing.assert_allclose(q.qsca, 8 / 3 * x**4 * abs(k) ** 2, rtol=1e-4)
    np.testing.assert_allclose(q.qabs, 4 * x * k.imag, rtol=1e-4)


def test_extinction_paradox_and_conservation():
    x = np.logspace(-1, 4, 200)
    q = sora.mie.efficiencies(1.5 + 0.01j, x)
    np.testing.assert_allclose(q.qext, q.qsca + q.qabs, rtol=1e-10)
    assert abs(q.qext[-1] - 2.0) < 0.02  # Q_ext -> 2 for x -> infinity
    assert np.all((q.g > -1) & (q.g < 1))


def test_thread_count_does_not_change_efficiencies():
    x = np.logspace(-1, 3, 10_000)
    m = np.where(np.arange(x.size) % 2 == 0, 1.5 + 0.01j, 1.33 + 0j)
    sora.set_num_threads(1)
    one = sora.mie.efficiencies(m, x)
    sora.set_num_threads(2)
    two = sora.mie.efficiencies(m, x)
    sora.set_num_threads(0)
    for a, b in zip(one, two):
        np.testing.assert_array_equal(a, b)


def test_phase_function_is_normalised_and_has_the_asymmetry_parameter():
    mu, weights = np.polynomial.legendre.leggauss(400)
    angles = np.degrees(np.arccos(mu))
    for m, x in [(1.33 + 0j, 5.0), (1.5 + 0.01j, 0.5)]:
        phase, ratio = sora.mie.phase_function(m, x, angles, polarization=True)
        assert np.all(phase > 0) and np.all(np.abs(ratio) <= 1 + 1e-12)
        np.testing.assert_allclose(2 * np.pi * np.sum(weights * phase), 1.0, rtol=1e-9)
        g = 2 * np.pi * np.sum(weights * phase * mu)
        np.testing.assert_allclose(g, sora.mie.efficiencies(m, x).g, rtol=1e-8, atol=1e-12)


def test_rayleigh_phase_function():
    angles = np.array([0.0, 45.0, 90.0, 135.0, 180.0])
    mu = np.cos(np.radians(angles))
    phase = sora.mie.phase_function(1.5, 1e-4, angles)
    np.testing.assert_allclose(phase, 3 * (1 + mu**2) / (16 * np.pi), rtol=1e-6)


def test_lognormal_and_gamma_per_wavelength():
    lognormal = sora.mie.lognormal(1.5 + 0.01j, 0.1, 2.0, wavelengths_nm=[400.0, 550.0, 700.0])
    assert lognormal.extinction_cross_section.attrs["units"] == "m2"
    np.testing.assert_allclose(
        lognormal.extinction_cross_section,
        lognormal.scattering_cross_section + lognormal.absorption_cross_section,
        rtol=1e-10,
    )
    # Aerosol extinction falls with wavelength (Angstrom exponent > 0).
    assert np.all(np.diff(lognormal.extinction_cross_section) < 0)
    gamma = sora.mie.gamma(1.33, 1.0, 0.1, wavelengths_nm="400:700:150")
    np.testing.assert_array_equal(gamma.wavelength, [400.0, 550.0, 700.0])
    np.testing.assert_allclose(gamma.single_scattering_albedo, 1.0, rtol=1e-12)


def test_per_wavelength_index():
    m = np.array([1.5 + 0.01j, 1.5 + 0.02j])
    both = sora.mie.gamma(m, 0.5, 0.2, wavelengths_nm=[500.0, 600.0])
    alone = sora.mie.gamma(m[1], 0.5, 0.2, wavelengths_nm=[600.0])
    assert both.absorption_cross_section[1] == alone.absorption_cross_section[0]
    with pytest.raises(ValueError):
        sora.mie.gamma(m, 0.5, 0.2, wavelengths_nm=[500.0, 600.0, 700.0])
