"""The near/far seam by a beach (issue 28): shallow water over sand, seen from high
up, looks the same drawn as chunks and as far tiles, and the chunks' edge shows no
line. The same flat shallows (sand, one block of water) are rendered twice through
the real pipeline: with the chunks reaching x = 64 (the truth: the strip x 32..64 is
chunks) and with the chunks ending at x = 32 (the strip is far tiles). Far tiles are
built from samples equal to the chunks' columns (far/tiles.py's contract).

The old code failed both checks: the seam wall under the chunks (far.vert) sloped
down just outside the edge, and the near water by the edge, seeing that slope
through it, was drawn as deep water: a blue line along the seam; far shallow water
was darker than near (its floor dimmed by exp(-depth/2), not by the light levels
under the water, and its depth taken straight down, not along the view ray)."""
import numpy as np
import pytest

from voxel_addon import light
from voxel_addon.core import chunk
from voxel_addon.core.blocks import REGISTRY as R
from voxel_addon.far import mesh, tiles
from voxel_addon.render import Camera, Settings
from voxel_addon.render.pipeline import Renderer

FLOOR, WATER = 60, 61          # sand top block, the one water block above it
W, H, FOV = 320, 180, 60.0
KEYS = [(1, tx, ty) for tx in (-1, 0, 1) for ty in (-1, 0, 1)]  # 64-block tiles, s = 2


def flat_tiles(keys, floor: int, water: int) -> list:
    """Far tiles of KEYS: sand at FLOOR under water up to WATER."""
    a = tiles.empty()
    a["height"][:] = floor
    a["top"][:] = R.id("sand")
    a["water"][:] = water
    return [mesh.build(k, a) for k in keys]


def _render(gl, cam, nx: int, **kw) -> np.ndarray:
    """The shallows with chunks over x 0..16*nx, y 0..32, far tiles around."""
    b = chunk.empty(width=16 * nx + 32, depth=64)  # a chunk of neighbours around: light
    b[:, :, :FLOOR] = R.id("stone")
    b[:, :, FLOOR] = R.id("sand")
    b[:, :, WATER] = R.id("water")
    s = Settings(msaa=1, dof=False, godrays=False, clouds=False, fov=FOV,
                 sea_level=WATER + 1, far=16, distance=2, **kw)
    r = Renderer(gl, s)
    try:  # the chunks with their ring of neighbours (as the CLI): water goes on
        r.set_area(np.asfortranarray(b[15:-15, 15:-15]), light.solve(b), 0, 0, ring=True,
                   light_at=(-1, -1))
        r.update_far(flat_tiles(KEYS, FLOOR, WATER))
        return r.render(cam, 11.0, (W, H)).astype(float)
    finally:
        r.release()


def _pixels(cam, pts) -> tuple[np.ndarray, np.ndarray]:
    """Pixel (row, column) of world points on the water surface."""
    vp = cam.fitted(W / H, FOV, cam.far).view_proj()
    p = np.c_[pts, np.full(len(pts), WATER + 1.0), np.ones(len(pts))] @ vp.T
    ndc = p[:, :2] / p[:, 3:]
    col = np.clip(((ndc[:, 0] + 1) / 2 * W).astype(int), 0, W - 1)
    row = np.clip(((1 - ndc[:, 1]) / 2 * H).astype(int), 0, H - 1)
    return row, col


@pytest.mark.parametrize("pitch", [-55.0, -30.0])
def test_far_shallows_look_like_near_ones_and_the_edge_shows_no_line(gl, pitch):
    cam = Camera(4.0, 16.0, 100.0 if pitch < -40 else 75.0, 0.0, pitch, FOV, W / H)
    # (no haze: it is the same on both)
    kw = dict(fog=False)
    truth, seam = _render(gl, cam, 4, **kw), _render(gl, cam, 2, **kw)
    ys = np.linspace(4, 28, 25)

    def diff(xs):  # seam - truth over the water at each x (RGB, the mean over ys)
        r, c = _pixels(cam, np.array([(x, y) for x in xs for y in ys]))
        return (seam[r, c] - truth[r, c]).reshape(len(xs), len(ys), 3).mean(1)
    # the strip that is far tiles in one and chunks in the other, off the edge
    strip = diff(np.linspace(36, 60, 13)).mean(0)
    # the chunks' last block and the far tiles' first: a line along the edge
    edge = diff(np.linspace(31.05, 32.95, 12))
    worst = edge[np.abs(edge).max(1).argmax()]
    # measured (llvmpipe): the strip within 2.1 levels per channel, the edge 3.5; the
    # old code: the strip up to 21 lighter (seen flat), the edge 14 bluer; the last
    # half block lit as dry land (include/lightvol.glsl): 6 lighter
    print("far - near shallows (RGB):", strip.round(2), "the edge, worst:", worst.round(2))
    assert np.abs(strip).max() < 3.0, strip
    assert np.abs(worst).max() < 4.5, edge.round(1)


def test_the_far_shader_takes_the_light_levels_of_water_as_the_light_does():
    """far.frag's WATER_LEVELS (the sky light a block of water takes) is core.blocks'."""
    from pathlib import Path
    import re
    src = (Path(__file__).resolve().parents[2] / "shaders" / "far.frag").read_text()
    levels = float(re.search(r"#define WATER_LEVELS ([0-9.]+)", src).group(1))
    assert levels == R.attenuation[R.id("water")]


def test_a_world_smaller_than_the_view_goes_on_in_far_terrain(tmp_path):
    """render --far on a world of 3 x 3 chunks at view distance 8: far tiles leave out
    only the chunks the file has, not the whole view square (the demo's beach beyond
    its chunks was a gap down to the sea plane, its edge a line in the sand)."""
    from voxel_addon.cli.render import _whole
    from voxel_addon.far import grid
    from voxel_addon.world import World
    with World.create(tmp_path / "w.sqlite", seed=1, generator="flat") as w:
        w.generate_area([(x, y) for x in (-1, 0, 1) for y in (-1, 0, 1)])
        wf = w.file
        assert _whole(wf, 8.0, 8.0, 8) == 1
        assert _whole(wf, 8.0, 8.0, 0) == 0
        assert _whole(wf, 40.0, 8.0, 8) == 0      # (its own chunk is the edge)
        assert _whole(wf, 200.0, 8.0, 8) == 0     # (none: far tiles everywhere)

    def covered(near):  # is column (40, 8), just beyond the chunks, in a far tile?
        return any(x0 <= 40 < x1 and y0 <= 8 < y1
                   for x0, y0, x1, y1 in (grid.rect(k) for k, _ in grid.select(8.0, 8.0, 32, near)))
    assert covered(1) and not covered(8)
