"""The extension zip with its bundled wheels in the real Blender (Debian's 5.2 with
Python 3.14 or 4.3 with Python 3.13, NumPy 2): it installs into a fresh user folder and works from its own wheels —
generates a world with OpenCL, renders a view on Blender's GL context, bakes and
exports a .glb."""
from __future__ import annotations

import zipfile
from pathlib import Path


def test_zip_carries_wheels_for_python_311_313_and_314(ext_zip_wheels):
    names = [Path(n).name for n in zipfile.ZipFile(ext_zip_wheels).namelist()
             if n.endswith(".whl")]
    for mod in ("pyopencl", "moderngl", "glcontext", "zstandard", "lz4", "siphash24"):
        for tag in ("cp311", "cp313", "cp314"):
            assert any(n.startswith(mod + "-") and f"-{tag}-" in n for n in names), (mod, tag)
    assert any(n.startswith("pocl_binary_distribution-") for n in names)


def test_installed_extension_generates_renders_bakes_and_exports(app, gui, ext_zip_wheels, tmp_path):
    glb = tmp_path / "x.glb"
    res = gui("installed.py", zip=str(ext_zip_wheels), world=str(tmp_path / "w.sqlite"),
              glb=str(glb), timeout=420)
    r = res.result
    blender = app.get()  # the one this run asked for (VOXEL_BLENDER_APP)
    assert r["blender"].startswith(blender.version), r
    assert r["python"].startswith(blender.pyver + ".") and r["numpy"].startswith("2."), r
    # the packages come from the wheels Blender installed for the extension
    for name, path in r["modules"].items():
        assert path.startswith(r["user"]) and "/extensions/" in path, (name, path)
    assert "Portable Computing Language" in r["opencl"] and r["backend"] == "opencl", r
    assert r["warm_started"], r  # New World started the kernels' build (issue 28)
    assert r["edit"] == ["FINISHED"] and r["edited"] == "glass", r
    v = r["view"]
    assert r["render"] == ["FINISHED"] and v["size"] == [160, 90] and v["std"] > 0.02, r
    assert v["top"][2] > v["top"][0] + 0.1, f"sky is blue at noon: {v}"
    assert r["bake"] == ["FINISHED"] and r["baked"]["objects"] >= 1 \
        and r["baked"]["triangles"] > 100, r
    assert r["export"] == ["FINISHED"] and glb.read_bytes()[:4] == b"glTF"
