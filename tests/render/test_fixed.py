"""Frame switches built into the shading programs as constants (render/graph.py FIXED,
glsl.py's CONST_name): frames equal the same frames whose programs read the switches
from the frame block, and one renderer switching them back and forth draws what a
fresh one draws (each combination its own graph)."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon.render import Camera, Settings, graph

# (hours, settings): the sea, the walls, clouds, stars and the tone curve each on and
# off somewhere
CASES = [(12.0, {}), (12.0, {"clouds": False, "walls": False}),
         (23.0, {"sea": False, "water": False, "tonemap": False}),
         (17.5, {"cloud_shadows": False, "ssr": False})]
SIZE = (96, 54)


def _frames(gl, cases):
    from voxel_addon.render import source
    from voxel_addon.render.pipeline import Renderer
    a = source.scene_area("ocean")
    r = Renderer(gl, Settings(msaa=1, dof=False, sea_level=source.scene_sea_level("ocean")))
    r.set_area(a.blocks, a.light, a.cx0, a.cy0, ring=True, light_at=a.light_at)
    # outside the area, looking across its edge at the sea beyond (walls and sea in view)
    cam = Camera(16 * a.cx0 - 20, 16 * a.cy0 - 20, 90, 45, -20)
    out = []
    try:
        for hours, kw in cases:
            for k, v in kw.items():
                setattr(r.s, k, v)
            out.append(r.render(cam, hours, SIZE).astype(int))
            for k in kw:
                setattr(r.s, k, getattr(Settings(), k))
    finally:
        r.release()
    return out


def test_constant_switches_draw_what_the_frame_block_draws(gl, monkeypatch):
    fixed = _frames(gl, CASES + CASES[::-1])  # and back: each combination's own graph
    monkeypatch.setattr(graph, "FIXED", ())  # programs read every switch from the block
    block = _frames(gl, CASES)
    for i, (want, (hours, kw)) in enumerate(zip(block, CASES)):
        for got in (fixed[i], fixed[len(fixed) - 1 - i]):
            d = np.abs(got - want)
            assert d.max() <= 2, (hours, kw, d.max())
    # the cases differ from each other (the control: a switch that did nothing would pass)
    for i in range(1, len(CASES)):
        assert np.abs(block[i] - block[0]).mean() > 1.0, CASES[i]
