"""The zips `build.py extension` makes: one per Blender platform (its name says which),
built and validated by the real Blender's own extension tool, each carrying a
complete wheel set for every Python of the Blenders on that platform. pip resolves
the zip's wheels offline for that platform and Python (--no-index --find-links, as
Blender installs them), so a missing dependency fails here, not on a user's machine.
numpy is Blender's own: a metadata-only stand-in wheel plays it for the resolver."""
from __future__ import annotations

import json
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

import build
from tools import blender_app

ROOT = Path(__file__).resolve().parent.parent
WANT = ["pyopencl", "moderngl", "zstandard", "lz4"]  # what the add-on imports
EXTRA = {"linux-x64": ["pocl-binary-distribution"]}  # the CPU OpenCL device, Linux only


@pytest.fixture(scope="module")
def zips(tmp_path_factory):
    folders = {p: build.WHEEL_DIR / p for p in build.WHEEL_PLATFORMS}
    if not all(list(f.glob("*.whl")) for f in folders.values()):
        pytest.skip(f"no wheels in {build.WHEEL_DIR} (run `python build.py setup`)")
    if blender_app.gui_missing():
        pytest.skip(f"no real Blender: {blender_app.gui_missing()}")
    spec = __import__("importlib.util").util.spec_from_file_location(
        "voxel_ext_tool", ROOT / "tools" / "extension.py")
    tool = __import__("importlib.util").util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    out = tmp_path_factory.mktemp("dist")
    made = tool.build_all(out, folders, blender=blender_app.get().launcher)
    return {z.stem.rsplit("-", 1)[1].replace("_", "-"): z for z in made}


def _numpy_standin(dest: Path) -> Path:
    """numpy-2.2.0-py3-none-any.whl with metadata only: 'Blender provides numpy'."""
    dest.mkdir(parents=True, exist_ok=True)
    whl = dest / "numpy-2.2.0-py3-none-any.whl"
    info = "numpy-2.2.0.dist-info"
    with zipfile.ZipFile(whl, "w") as z:
        z.writestr(f"{info}/METADATA", "Metadata-Version: 2.1\nName: numpy\nVersion: 2.2.0\n")
        z.writestr(f"{info}/WHEEL", "Wheel-Version: 1.0\nGenerator: test\nRoot-Is-Purelib: true\n"
                                    "Tag: py3-none-any\n")
        z.writestr(f"{info}/RECORD", "")
    return dest


def test_one_zip_per_platform_each_declaring_it(zips):
    assert sorted(zips) == sorted(build.WHEEL_PLATFORMS), list(zips)
    for platform, z in zips.items():
        manifest = zipfile.ZipFile(z).read("blender_manifest.toml").decode()
        generated = manifest.split("[build.generated]")[1]
        assert f'platforms = ["{platform}"]' in generated, (platform, generated)


@pytest.mark.parametrize("platform", sorted(build.WHEEL_PLATFORMS))
def test_each_zip_resolves_offline_for_every_python_of_its_platform(zips, platform, tmp_path):
    z = zipfile.ZipFile(zips[platform])
    wheels = tmp_path / "wheels"
    wheels.mkdir()
    names = [n for n in z.namelist() if n.endswith(".whl")]
    for n in names:
        (wheels / Path(n).name).write_bytes(z.read(n))
    host = _numpy_standin(tmp_path / "host")
    tags, _, _ = build.WHEEL_PLATFORMS[platform]
    used = set()
    for python in build.wheel_pythons(platform):
        report = tmp_path / f"report-{python}.json"
        r = subprocess.run(
            [sys.executable, "-m", "pip", "install", "--dry-run", "--ignore-installed", "-q",
             "--disable-pip-version-check", "--no-index", "--find-links", str(wheels),
             "--find-links", str(host), "--only-binary=:all:", "--implementation", "cp",
             "--python-version", python, *[a for t in tags for a in ("--platform", t)],
             "--target", str(tmp_path / "target"), "--report", str(report),
             *WANT, *EXTRA.get(platform, [])], capture_output=True, text=True)
        assert r.returncode == 0, f"{platform} Python {python}:\n{r.stdout[-2000:]}{r.stderr[-2000:]}"
        got = [Path(i["download_info"]["url"]).name for i in json.loads(report.read_text())["install"]]
        assert all(g in {Path(n).name for n in names} for g in got if not g.startswith("numpy-")), got
        used.update(got)
    # and nothing in the zip that no Python of the platform installs
    assert {Path(n).name for n in names} <= used, sorted({Path(n).name for n in names} - used)
