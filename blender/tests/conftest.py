"""The Blender add-on's tests: Blender as a Python module (``bpy``, pinned
in blender/requirements-test.txt) with sora's package in one virtual
environment (.ci/run, README "Blender").

The add-on is installed as an extension from a zip of blender/sora_sky
into a throw-away user directory (``BLENDER_USER_RESOURCES``), and enabled
there, as a user installs it. ``SORA_CLI`` names the ``sora`` binary whose
``sora irradiance`` the renders are checked against (.ci/run: what ``cargo
test`` built; otherwise looked for in target/).
"""

import json
import os
import pathlib
import subprocess
import sys
import tempfile
import zipfile

import pytest

REPOSITORY = pathlib.Path(__file__).resolve().parents[2]
ADDON = REPOSITORY / "blender" / "sora_sky"
sys.path.insert(0, str(REPOSITORY / "blender"))

# Before bpy is imported: the user directory the extension goes into.
_USER = tempfile.mkdtemp(prefix="sora-blender-user-")
os.environ["BLENDER_USER_RESOURCES"] = _USER

import bpy  # noqa: E402


def pytest_report_header(config):
    return f"Blender {bpy.app.version_string} (bpy), user resources {_USER}"


@pytest.fixture(scope="session")
def addon():
    """The add-on, installed from a zip and enabled, as bl_ext.user_default.sora_sky."""
    package = pathlib.Path(_USER) / "sora_sky.zip"
    with zipfile.ZipFile(package, "w") as archive:
        for path in sorted(ADDON.iterdir()):
            if path.suffix in (".py", ".toml"):
                archive.write(path, path.name)
    result = bpy.ops.extensions.package_install_files(
        filepath=str(package), repo="user_default", enable_on_install=True
    )
    assert result == {"FINISHED"}
    assert "bl_ext.user_default.sora_sky" in bpy.context.preferences.addons
    return sys.modules["bl_ext.user_default.sora_sky"]


@pytest.fixture(scope="session")
def sora_cli():
    named = os.environ.get("SORA_CLI")
    if named:
        return pathlib.Path(named)
    for profile in ("release", "debug"):
        path = REPOSITORY / "target" / profile / "sora"
        if path.exists():
            return path
    pytest.skip("no sora binary built: set SORA_CLI or cargo build it")


@pytest.fixture(scope="session")
def irradiance(sora_cli):
    """``sora irradiance`` (JSON) for arguments, cached."""
    cache = {}

    def run(*arguments):
        if arguments not in cache:
            output = subprocess.run(
                [str(sora_cli), "irradiance", "--format", "json", *arguments],
                check=True, capture_output=True, text=True,
            ).stdout
            cache[arguments] = json.loads(output)
        return cache[arguments]

    return run
