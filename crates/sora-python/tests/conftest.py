"""Shared fixtures: the Rust programs the bindings are checked against.

``SORA_CLI`` and ``SORA_RADIANCE_VALUES`` name the ``sora`` binary and the
``radiance_values`` example (``.ci/run`` sets both to what ``cargo test``
built); otherwise they are looked for in the workspace's ``target/``, and
the tests that need them are skipped when they are absent.
"""

import os
import pathlib

import pytest

REPOSITORY = pathlib.Path(__file__).resolve().parents[3]


def _find(variable, *relative):
    named = os.environ.get(variable)
    if named:
        path = pathlib.Path(named)
        if not path.exists():
            pytest.fail(f"{variable}={named} does not exist")
        return path
    for profile in ("release", "debug"):
        path = REPOSITORY / "target" / profile / pathlib.Path(*relative)
        if path.exists():
            return path
    pytest.skip(f"no {pathlib.Path(*relative)} built: set {variable} or cargo build it")


@pytest.fixture(scope="session")
def sora_cli():
    return _find("SORA_CLI", "sora")


@pytest.fixture(scope="session")
def radiance_values():
    return _find("SORA_RADIANCE_VALUES", "examples", "radiance_values")


@pytest.fixture(scope="session")
def atmospheres_dir():
    return REPOSITORY / "atmospheres"
