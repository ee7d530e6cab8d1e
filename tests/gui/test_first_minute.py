"""The first minute, as a new user meets it (factory settings, issue 18): the zip
installs, New World makes an Overworld, Show in Viewport brings Blender's default
view (inside the rock) up to the surface and the terrain fills the view; Frame World
(View menu) brings a view back from far away."""
from __future__ import annotations

import numpy as np


def _view(res, name):
    """The 3D view's pixels without its header, toolbar and navigation gizmos."""
    x, y, w, h = res.result["region"]
    img = res.crop(name, [x, y, w, h]).astype(int)
    return img[60:h - 20, 60:w - 120]


def _terrain_fills(res, name, part=False):
    """(share of the view changed since "before", median texture of 16-pixel tiles);
    part: the texture of the changed tiles only (a first frame of a few chunks)."""
    before, now = _view(res, "before"), _view(res, name)
    diff = np.abs(now - before).max(-1) > 30  # dark shade or grey stone may match
    # terrain is textured block by block; a sky (the failure this guards) is smooth
    h, w = now.shape[0] // 16 * 16, now.shape[1] // 16 * 16
    tiles = now[:h, :w].reshape(h // 16, 16, w // 16, 16, 3).std(axis=(1, 3)).max(-1)
    if part:
        hit = diff[:h, :w].reshape(h // 16, 16, w // 16, 16).mean(axis=(1, 3)) > 0.5
        tiles = tiles[hit] if hit.any() else np.zeros(1)
    return diff.mean(), float(np.median(tiles))


# generous: CI's 2 cores may be busy, and a fresh Blender compiles its shaders on the
# main thread (Vulkan on lavapipe: ~6 s of the first frames). Goals: 2 s and 5 s; at
# load 4-9 on 2 cores here: first drawn 1-5 s, whole view 7-31 s (issue 28's fixes;
# before them 14-41 s)
FIRST_S, WHOLE_S = 20.0, 90.0


def test_new_world_show_brings_the_view_to_the_surface_and_terrain_fills_it(gui, ext_zip_wheels,
                                                                            tmp_path):
    # a fresh install: no kernel built yet (pocl's and pyopencl's caches empty)
    cache = tmp_path / "kernels"
    env = {"POCL_CACHE_DIR": str(cache / "pocl"), "PYOPENCL_CACHE_DIR": str(cache / "pyopencl")}
    res = gui("first_minute.py", zip=str(ext_zip_wheels), world=str(tmp_path / "w.sqlite"),
              timeout=600, env=env)
    r = res.result
    assert r["defaults"]["generator"] == "overworld", r["defaults"]
    # the first chunks come while OpenCL still builds (NumPy meanwhile), not after it
    first, whole = r["first"], r["whole"]
    print(f"\nShow -> first chunks ready {first['ready_s']:.1f} s, drawn {first['s']:.1f} s, "
          f"whole view {whole['s']:.1f} s; OpenCL warm-up {whole['warm']['took']} s")
    assert first["warm"]["started"] and first["ready_before_opencl"], (first, whole)
    assert first["backends"] == ["numpy", "numpy"], first  # made while the kernels built
    assert first["s"] < FIRST_S and whole["s"] < WHOLE_S, (first, whole)
    # the frame taking in the last chunks is a draft (a full one on llvmpipe took ~0.5 s
    # more before the whole view showed); the full frame follows (_wait_full below)
    assert whole["quality"] == "draft", whole
    assert any((cache / "pocl").iterdir()), "the kernels were built elsewhere: not cold"
    changed, texture = _terrain_fills(res, "first", part=True)
    assert changed > 0.02 and texture > 6, (changed, texture)
    # Blender's default view starts inside the rock of a generated world ...
    b = r["before"]
    assert b["eye"][2] < b["ground"] - 2, b
    # ... and Show brings it up: above the ground, near the origin, every chunk drawn
    s = r["shown"]
    assert s["eye"][2] > s["ground"] + 2 and np.hypot(*s["pivot"][:2]) < 16, s
    changed, texture = _terrain_fills(res, "shown")
    assert changed > 0.8 and texture > 6, (changed, texture)
    # Frame World, from the View menu, brings a view back from far away
    f = r["framed"]
    assert r["in_view_menu"] and r["frame"] == ["FINISHED"], r
    assert f["from_origin"] < 16 and f["eye"][2] > f["ground"] + 2, f
    changed, texture = _terrain_fills(res, "framed")
    assert changed > 0.8 and texture > 6, (changed, texture)
