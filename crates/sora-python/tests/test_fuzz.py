"""The public API fuzzed with hypothesis: arguments drawn from values a
careless script passes (None, strings, bools, NaN, infinities, 10**400,
negative counts, huge counts, empty and nested arrays). Every call must
return finite numbers or raise ``ValueError``, ``TypeError`` or
``OSError`` with a one-line message, within a minute: never
``PanicException``, ``RuntimeError`` (a caught panic), ``OverflowError``,
``MemoryError`` or a hang (``faulthandler`` ends the run if one call takes
past two minutes).

``test_public_api_fuzz`` runs in CI (300 examples, a fixed seed);
``test_public_api_fuzz_long`` (``@pytest.mark.slow``, deselected by
default) runs 3,000 with another seed and prints the outcomes by kind:
``pytest crates/sora-python/tests/test_fuzz.py -m slow -s``
(``SORA_FUZZ_SEED`` and ``SORA_FUZZ_EXAMPLES`` change its seed and count). The work of
each call is kept small (a few wavelengths, images of at most 8 x 8
pixels, few paths), so that a legal call is quick too.
"""

import collections
import faulthandler
import math
import os
import time

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, seed, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import sora  # noqa: E402

#: The exceptions the package documents for bad input.
DOCUMENTED = (ValueError, TypeError, OSError)

#: Values a careless caller passes for anything.
ODD = [
    None, True, False, "", "30", "x", b"1", [], [1.0], [[1.0]], (1, 2, 3), {}, 0, -1, 1, 2, 8,
    10**400, -(10**400), 2**64, -(2**63), math.nan, math.inf, -math.inf, 0.0, -0.0, 1e-300,
    5e-324, 1e300, 0.5, 30.0, 89.9, 90.0, 91.0, -91.0, 360.0, 1e6, 1e7, complex(math.nan, 0),
    complex(1.5, 0.01), complex(1.5, -0.01), complex(1.0, 0.0), np.float64(math.nan), np.int64(-1),
    np.array([]), np.array([1.0, math.nan]), np.array([[30.0, 40.0]]),
]


def odd():
    return st.one_of(
        st.sampled_from(ODD),
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(min_value=-(10**30), max_value=10**30),
    )


GRIDS = st.sampled_from(
    [None, "500:500:1", "450:650:100", "380:inf:20", "380:780:1e-9", "780:380:20", "1:2:3",
     "a:b:c", "", [500.0], [500.0, 600.0], [500.0, 510.0, 600.0], [], [math.nan], 5, None]
)
METHODS = st.sampled_from(["fast", "reference", "path-tracing", "slow", None, 3])
SMALL_COUNTS = st.sampled_from([None, -1, 0, 1, 2, 4, 10**30, 2.5, "4", True])
STEPS = st.sampled_from([None, (-1, 5), (2, 2), (10, 4), (0, 0), (10**20, 1), (1,), "ab", (2.5, 3)])
WIDTHS = st.sampled_from([-1, 0, 1, 4, 8, 16385, 10**30, None, 8.0, "8", True])


@pytest.fixture(scope="module")
def atmosphere():
    return sora.Atmosphere.preset("clear-sky-reference")


def finite(result):
    """Whether every number in `result` (arrays, xarray objects, tuples)
    is finite."""
    if hasattr(result, "data_vars"):
        return all(finite(v.values) for v in result.data_vars.values())
    if hasattr(result, "values") and not callable(result.values):
        return finite(result.values)
    if isinstance(result, tuple):
        return all(finite(r) for r in result)
    if isinstance(result, np.ndarray) and result.dtype.kind in "fc":
        return bool(np.all(np.isfinite(result)))
    return True


def call(outcomes, name, function, *args, **kwargs):
    """Runs one call and records its outcome; fails on anything but a
    finite result or a documented one-line exception."""
    started = time.monotonic()
    # A hang ends the run with every thread's traceback (a call stuck in
    # native code cannot be interrupted otherwise).
    faulthandler.dump_traceback_later(120, exit=True)
    try:
        result = function(*args, **kwargs)
    except DOCUMENTED as error:
        message = str(error)
        assert message and "\n" not in message, f"{name}{args}{kwargs}: {message!r}"
        outcomes["one-line error"] += 1
        return None
    except BaseException as error:  # PanicException is a BaseException
        if isinstance(error, (KeyboardInterrupt, SystemExit)):
            raise
        pytest.fail(f"{name}(*{args!r}, **{kwargs!r}) raised {type(error).__name__}: {error}")
    finally:
        faulthandler.cancel_dump_traceback_later()
    assert time.monotonic() - started < 60.0, f"{name}{args}{kwargs} took past 60 s"
    assert finite(result), f"{name}(*{args!r}, **{kwargs!r}) gave a non-finite number"
    outcomes["ok"] += 1
    return result


def exercise(atmosphere, outcomes, data):
    """One randomised session of the public API."""
    draw = data.draw
    which = draw(st.integers(0, 6))
    if which == 0:
        sky = call(
            outcomes, "Sky", sora.Sky, atmosphere,
            sun_elevation_deg=draw(odd()),
            sun_azimuth_deg=draw(st.sampled_from([None, 0.0, 180.0, math.nan, 10**400, "s"])),
            observer_altitude_m=draw(st.sampled_from([0.0, 1e3, -1.0, 1e9, math.nan, None])),
            wavelengths_nm=draw(GRIDS),
            scattering=draw(st.sampled_from(["single", "multiple", "double", None])),
            method=draw(METHODS),
            samples=draw(SMALL_COUNTS),
            seed=draw(st.sampled_from([None, -1, 0, 1, 2**64 - 1, 2**64, "1"])),
            reference_steps=draw(STEPS),
            polarisation=draw(st.sampled_from(["scalar", "vector", "both", None])),
        )
        if sky is not None:
            call(outcomes, "radiance", sky.radiance, draw(odd()), draw(odd()))
            if sky.method != "path-tracing":
                call(outcomes, "render", sky.render, width=draw(st.sampled_from([1, 4, 8, -1, 16385])),
                     output=draw(st.sampled_from(["xyz", "spectral", "stokes-xyz", "rgb", None])))
            call(outcomes, "almucantar", sky.almucantar, draw(odd()))
    elif which == 1:
        sky = sora.Sky(atmosphere, sun_elevation_deg=20, scattering="single", wavelengths_nm="500:600:100")
        call(outcomes, "render", sky.render,
             camera=draw(st.sampled_from(["fisheye", "equirectangular", "perspective", "pinhole", None, 1])),
             width=draw(WIDTHS), height=draw(st.sampled_from([None, -1, 0, 4, 10**30, 2.5])),
             look_elevation_deg=draw(odd()), look_azimuth_deg=draw(odd()), fov_deg=draw(odd()))
    elif which == 2:
        sky = sora.Sky(atmosphere, sun_elevation_deg=20, scattering="single", wavelengths_nm="500:600:100")
        call(outcomes, "radiance", sky.radiance, draw(odd()), draw(odd()))
        call(outcomes, "almucantar", sky.almucantar, draw(odd()))
        call(outcomes, "stokes", sky.stokes, draw(odd()), draw(odd()))
    elif which == 3:
        call(outcomes, "mie.efficiencies", sora.mie.efficiencies, draw(odd()), draw(odd()))
    elif which == 4:
        call(outcomes, "mie.phase_function", sora.mie.phase_function, draw(odd()), draw(odd()),
             draw(st.sampled_from([[0.0, 90.0], [math.nan], [], 181.0, "x", [[10.0]]])))
    elif which == 5:
        ensemble = draw(st.sampled_from([sora.mie.lognormal, sora.mie.gamma]))
        call(outcomes, ensemble.__name__, ensemble, draw(odd()),
             draw(st.sampled_from([0.1, 1.0, 0.0, -1.0, math.nan, 10**400, None, "1", 1e-9])),
             draw(st.sampled_from([2.0, 0.1, 1.0, 1.00001, 0.0, -1.0, math.inf, None])),
             wavelengths_nm=draw(st.sampled_from(["500:500:1", "380:inf:20", "380:780:1e-9", [500.0], [], [math.nan], None, 3])),
             radius_window_um=draw(st.sampled_from([None, (0.1, 2.0), (2.0, 0.1), (math.nan, 1.0), (1.0,), "ab", 5])))
    else:
        # (4096 threads, the largest count, is legal but takes tens of
        # seconds to start on a loaded machine: 64 stands in for it.)
        threads = draw(st.sampled_from([-1, 0, 1, 2, 64, 4097, 10**30, 1.5, None, "2"]))
        call(outcomes, "set_num_threads", sora.set_num_threads, threads)
        sora.set_num_threads(0)
        text = draw(st.sampled_from(["", "name = 1", "[planet]", "name=\"x\"\n[planet]\nradius_m=1\n"]))
        call(outcomes, "Atmosphere.from_toml_str", sora.Atmosphere.from_toml_str, text)
        call(outcomes, "Atmosphere.preset", sora.Atmosphere.preset, draw(odd()))


OUTCOMES = collections.Counter()


@seed(20261204)
@settings(max_examples=300, deadline=None, derandomize=False, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_public_api_fuzz(atmosphere, data):
    exercise(atmosphere, OUTCOMES, data)


@pytest.mark.slow
@seed(int(os.environ.get("SORA_FUZZ_SEED", "4815162342")))
@settings(max_examples=int(os.environ.get("SORA_FUZZ_EXAMPLES", "3000")), deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_public_api_fuzz_long(atmosphere, data):
    exercise(atmosphere, OUTCOMES, data)


def teardown_module(module):
    if OUTCOMES:
        print(f"\nfuzz outcomes: {dict(OUTCOMES)} (calls: {sum(OUTCOMES.values())})")
