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


@pytest.mark.parametrize("msaa", [1, 2])
def test_covered_layers_draw_what_every_pixel_draws(gl, monkeypatch, msaa):
    fast = _frames(gl, msaa)
    monkeypatch.setattr(targets, "COVERED", False)
    slow = _frames(gl, msaa)
    for a, b in zip(fast, slow):
        d = np.abs(a - b)
        assert d.max() <= 2, d.max()
    # the control: the second and third layers show (a layer left black would differ)
    one = _frames(gl, msaa, layers=1)
    assert max(np.abs(a - b).mean() for a, b in zip(one, slow)) > 1.0
