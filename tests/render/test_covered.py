"""Peel layers shaded only where they have a surface (render/targets.py COVERED: each
layer's coverage as a one-sample depth buffer, shaders/cover.frag, and its lighting
drawn on the far plane against it, test "greater"): the same frames as lighting every
pixel of every layer, water and glass stacked three layers deep, with and without MSAA."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon.core import chunk
from voxel_addon.core.blocks import REGISTRY as R
from voxel_addon.light import solve
from voxel_addon.render import Camera, Settings, targets


def _stacked():
    """Three panes of glass over a pool, the sky and a stone wall beside them."""
    b = chunk.empty(width=32, depth=32)
    b[:, :, :60] = R.id("stone")
    b[:, :, 60] = R.id("sand")
    b[8:24, 8:24, 58:61] = R.id("water")
    for z in (64, 67, 70):
        b[10:22, 10:22, z] = R.id("glass")
    b[26:30, 4:28, 61:72] = R.id("stone")
    return b


def _frames(gl, msaa, layers=3):
    from voxel_addon.render.pipeline import Renderer
    b = _stacked()
    r = Renderer(gl, Settings(msaa=msaa, dof=False, peel_layers=layers))
    r.set_area(b, solve(b), 0, 0)
    out = []
    try:
        for cam in (Camera(16, 16, 80, 0, -89), Camera(-6, 16, 66, 0, 8), Camera(2, 2, 75, 45, -30)):
            out.append(r.render(cam, 10.0, (96, 64)).astype(int))
    finally:
        r.release()
    return out


def _both(monkeypatch, frames):
    """frames() the short way, then the long way (targets.COVERED off): every pair
    within 2 levels; the long way's frames."""
    fast = frames()
    monkeypatch.setattr(targets, "COVERED", False)
    slow = frames()
    for a, b in zip(fast, slow):
        d = np.abs(a - b)
        assert d.max() <= 2, d.max()
    return slow


@pytest.mark.parametrize("msaa", [1, 2])
def test_covered_layers_draw_what_every_pixel_draws(gl, monkeypatch, msaa):
    slow = _both(monkeypatch, lambda: _frames(gl, msaa))
    # the control: the second and third layers show (a layer left black would differ)
    one = _frames(gl, msaa, layers=1)
    assert max(np.abs(a - b).mean() for a, b in zip(one, slow)) > 1.0


def _tunnel():
    """Stone under grass, a pit and a tunnel open to the area's west edge (x = 0), a
    pond: from inside, the outer wall closes what no mesh does."""
    b = chunk.empty(width=34, depth=34)  # (with its one-voxel ring: 2 x 2 chunks)
    b[:, :, :60] = R.id("stone")
    b[:, :, 60] = R.id("grass")
    b[0:24, 16:20, 50:55] = 0
    b[0:9, 3:15, 40:61] = 0
    b[20:28, 22:30, 58:61] = R.id("water")
    b[6:20:4, 19, 54] = R.id("lamp_white")  # (the tunnel lit)
    return b


def _inside(gl, cams):
    from voxel_addon.render.pipeline import Renderer
    b = _tunnel()
    # (distance 1: the area's far side fades into the sky, shade.glsl's edge_fade)
    r = Renderer(gl, Settings(msaa=1, dof=False, sea_level=62, distance=1))
    r.set_area(b, solve(b)[1:-1, 1:-1], 0, 0, ring=True, closed=False)
    out = []
    try:
        for cam, hours in cams:
            out.append(r.render(Camera(*cam), hours, (96, 64)).astype(int))
    finally:
        r.release()
    return out


# from inside the area: down into the pit by the edge, from its floor, along the
# tunnel to the wall at its end, out over the edge to the sea beyond (noon, night),
# up at the sky
INSIDE = [((14, 9, 70, 180, -35), 12.0), ((3, 8, 45, 160, 10), 12.0), ((16, 18, 52.5, 180, 0), 12.0),
          ((16, 16, 70, 200, -8), 12.0), ((16, 16, 70, 200, -8), 23.5),
          ((16, 16, 70, 30, 45), 17.0)]


def test_the_sky_drawn_where_no_surface_is_what_the_composite_drew(gl, monkeypatch):
    """From inside the area without MSAA the opaque layer is lit in two passes by its
    coverage, the second drawing the holes' fill, the outer wall, the fade band and
    the sky or sea behind (graph.Switches.sky): the same frames as one pass and the
    sky in the composite."""
    for b in _both(monkeypatch, lambda: _inside(gl, INSIDE)):
        assert b.std() > 5, "a view with something in it"
