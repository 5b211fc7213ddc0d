"""Builds the sora_sky extension as one zip for one platform with sora's
wheel and its pure dependencies bundled (Blender installs an extension's
wheels into its own site-packages; numpy comes with Blender):

    python blender/build_extension.py SORA_WHEEL [PLATFORM] [OUTPUT_DIR]

SORA_WHEEL: the wheel of crates/sora-python built for PLATFORM (``pip wheel
--no-deps -w wheels ./crates/sora-python`` on that platform: one abi3
wheel serves every CPython >= 3.9); PLATFORM: Blender's name for it,
``linux-x64`` (default), ``macos-arm64``, ``macos-x64`` or
``windows-x64``. xarray, pandas and pandas' own dependencies are fetched
from PyPI for CPython 3.11 and that platform (``pip download
--only-binary``). The result, ``sora_sky-<version>-<platform>.zip``,
installs with Edit > Preferences > Get Extensions > Install from Disk.
"""

import os
import subprocess
import sys
import tempfile
import tomllib
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
ADDON = os.path.join(HERE, "sora_sky")

#: Blender's platform names and pip's platform tags.
PIP_PLATFORMS = {
    "linux-x64": ["manylinux2014_x86_64", "manylinux_2_17_x86_64", "manylinux_2_28_x86_64"],
    "macos-arm64": ["macosx_11_0_arm64"],
    "macos-x64": ["macosx_10_9_x86_64", "macosx_10_13_x86_64"],
    "windows-x64": ["win_amd64"],
}

#: sora's dependencies other than numpy (Blender ships numpy 1.26 for
#: CPython 3.11), pinned as blender/requirements-test.txt pins them.
DEPENDENCIES = ["xarray==2026.9.0", "pandas==2.3.3", "packaging", "python-dateutil", "pytz", "tzdata", "six"]


def build(sora_wheel: str, platform: str = "linux-x64", output_dir: str = ".") -> str:
    if platform not in PIP_PLATFORMS:
        raise SystemExit(f"platform '{platform}' is unknown: use one of {', '.join(PIP_PLATFORMS)}")
    with tempfile.TemporaryDirectory() as wheels:
        command = [sys.executable, "-m", "pip", "download", "--quiet", "--no-deps",
                   "--only-binary=:all:", "--python-version", "3.11", "--dest", wheels]
        for tag in PIP_PLATFORMS[platform]:
            command += ["--platform", tag]
        subprocess.run(command + DEPENDENCIES, check=True)
        names = sorted(os.listdir(wheels)) + [os.path.basename(sora_wheel)]
        with open(os.path.join(ADDON, "blender_manifest.toml"), "rb") as file:
            manifest = tomllib.load(file)
        text = open(os.path.join(ADDON, "blender_manifest.toml"), encoding="utf-8").read()
        # Top-level keys, so before the first table ([permissions]).
        table = text.index("\n[")
        added = "\nwheels = [\n" + "".join(f'    "./wheels/{name}",\n' for name in names) + "]\n"
        added += f'platforms = ["{platform}"]\n'
        text = text[:table] + added + text[table:]
        assert tomllib.loads(text)["platforms"] == [platform]
        output = os.path.join(output_dir, f"sora_sky-{manifest['version']}-{platform}.zip")
        partial = output + ".partial"
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
            for name in sorted(os.listdir(ADDON)):
                if name.endswith(".py"):
                    archive.write(os.path.join(ADDON, name), name)
            archive.writestr("blender_manifest.toml", text)
            for name in names[:-1]:
                archive.write(os.path.join(wheels, name), f"wheels/{name}")
            archive.write(sora_wheel, f"wheels/{os.path.basename(sora_wheel)}")
        os.replace(partial, output)
    return output


if __name__ == "__main__":
    if not 2 <= len(sys.argv) <= 4:
        raise SystemExit(__doc__)
    print(build(*sys.argv[1:]))
