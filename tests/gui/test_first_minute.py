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


def _terrain_fills(res, name):
    before, now = _view(res, "before"), _view(res, name)
    changed = (np.abs(now - before).max(-1) > 30).mean()  # dark shade or grey stone may match
    # terrain is textured block by block; a sky (the failure this guards) is smooth
    h, w = now.shape[0] // 16 * 16, now.shape[1] // 16 * 16
    tiles = now[:h, :w].reshape(h // 16, 16, w // 16, 16, 3).std(axis=(1, 3)).max(-1)
    return changed, float(np.median(tiles))


def test_new_world_show_brings_the_view_to_the_surface_and_terrain_fills_it(gui, ext_zip_wheels,
                                                                            tmp_path):
    res = gui("first_minute.py", zip=str(ext_zip_wheels), world=str(tmp_path / "w.sqlite"),
              timeout=600)
    r = res.result
    assert r["defaults"]["generator"] == "overworld", r["defaults"]
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
