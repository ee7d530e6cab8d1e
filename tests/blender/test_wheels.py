"""The extension zip with bundled wheels (cp311 and cp313, as `build.py extension`
makes it) installs into this interpreter's Blender — the bpy module (Python 3.11,
NumPy 1.26) or, under tests/run.py, the real Blender 4.3 (Python 3.13, NumPy 2) —
which unpacks only the wheels for its Python, and those wheels work with this
NumPy: OpenCL, an EGL GL context and zstandard, imported from the installed copy."""
from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
WHEELS = ROOT / ".cache" / "wheels" / "linux-x64"  # build.py setup downloads them
MOD = "bl_ext.user_default.voxel_worlds"
CHECK = """
import json, os, sys
site = sys.argv[1]
sys.path.insert(0, site)
import numpy, pyopencl, moderngl, zstandard, lz4.block
from voxel_addon import opencl
ctx = moderngl.create_standalone_context(backend="egl")
data = zstandard.ZstdCompressor().compress(b"voxel" * 100)
print(json.dumps({"files": [os.path.realpath(m.__file__) for m in (pyopencl, moderngl, zstandard)],
                  "numpy": numpy.__version__, "gl": ctx.version_code,
                  "cl": opencl.describe() if opencl.available() else opencl.why_not(),
                  "zstd": zstandard.ZstdDecompressor().decompress(data) == b"voxel" * 100,
                  "lz4": lz4.block.decompress(lz4.block.compress(b"voxel" * 100)) == b"voxel" * 100}))
"""


@pytest.fixture(scope="module")
def zip_path(bpy, tmp_path_factory):
    if not list(WHEELS.glob("*cp313*.whl")):
        pytest.skip(f"no wheels in {WHEELS} (run `python build.py setup`)")
    scripts = Path(bpy.utils.system_resource("SCRIPTS"))
    os.environ.setdefault("VOXEL_BLENDER_EXT",
                          str(scripts / "addons_core" / "bl_pkg" / "cli" / "blender_ext.py"))
    spec = importlib.util.spec_from_file_location("voxel_ext_tool", ROOT / "tools" / "extension.py")
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    return tool.build(tmp_path_factory.mktemp("dist"), WHEELS, platforms=["linux-x64"])


def test_wheels_of_this_python_install_and_work_with_its_numpy(bpy, zip_path):
    import addon_utils
    repos = [r.module for r in bpy.context.preferences.extensions.repos]
    tag = f"cp{sys.version_info.major}{sys.version_info.minor}"
    r = bpy.ops.extensions.package_install_files(filepath=str(zip_path), repo="user_default",
                                                 enable_on_install=True)
    try:
        assert r == {"FINISHED"} and MOD in bpy.context.preferences.addons.keys()
        site = Path(bpy.utils.user_resource("EXTENSIONS")) / ".local" / "lib" / \
            f"python{sys.version_info.major}.{sys.version_info.minor}" / "site-packages"
        exts = [p.name for p in site.rglob("*.so") if "cpython-" in p.name]
        assert any(f"cpython-{tag[2:]}" in n for n in exts), exts
        assert not [n for n in exts if f"cpython-{tag[2:]}" not in n], exts  # only ours
        # a plain interpreter of this Python (no bpy needed) imports them from there
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        p = subprocess.run([sys.executable, "-c", CHECK, str(site)], capture_output=True,
                           text=True, env=env, cwd=ROOT, timeout=300)
        assert p.returncode == 0, p.stderr[-3000:]
        got = json.loads(p.stdout.strip().splitlines()[-1])
        assert all(f.startswith(os.path.realpath(site)) for f in got["files"]), got
        import numpy
        assert got["numpy"] == numpy.__version__, got
        from voxel_addon import opencl  # pocl from the wheel, or the switch says why not
        want = "switched off" if opencl.switched_off() else "Portable Computing Language"
        assert want in got["cl"] and got["gl"] >= 410 and got["zstd"] and got["lz4"], got
    finally:
        addon_utils.disable(MOD)
        bpy.ops.extensions.package_uninstall(repo_index=repos.index("user_default"),
                                             pkg_id="voxel_worlds")
    assert not site.exists() or not list(site.rglob("pyopencl"))
