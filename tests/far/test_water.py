"""Far water looks like the water beside it (issue 28): a far tile of open water, drawn
opaque into the G-buffer, is shaded as the open sea (deep water, the sky's reflection)
and matches the sea plane seen the same way, at noon and at dusk. (Its flat albedo made
it another blue than the sea and the near water, and dark under a bright dusk sky.)"""
import numpy as np
import pytest

from voxel_addon.far import grid, mesh, tiles
from voxel_addon.core.blocks import REGISTRY
from voxel_addon import light
from voxel_addon.render import Camera, Settings
from voxel_addon.render.pipeline import Renderer

SEA = 62
KEY = (1, 1, 0)  # x 64..128, y 0..64: beyond the 32 x 32 area


def _water_tile():
    a = tiles.empty()
    a["height"][:] = 20  # deep: the sea's colour
    a["top"][:] = REGISTRY.id("sand")
    a["water"][:] = SEA
    return mesh.build(KEY, a)


def _patch(gl, far: bool, hours: float) -> np.ndarray:
    from tests.render.test_render import floor
    b = floor()
    s = Settings(msaa=1, dof=False, godrays=False, clouds=False, sea_level=SEA + 1,
                 far=16 if far else 0, distance=1)
    r = Renderer(gl, s)
    try:
        r.set_area(b, light.solve(b), 0, 0)
        if far:
            r.update_far([_water_tile()])
        img = r.render(Camera(16, 32, 100, 0, -30), hours, (160, 90)).astype(float)
    finally:
        r.release()
    return img[20:45, 40:120].reshape(-1, 3).mean(0)


@pytest.mark.parametrize("hours", [12.0, 18.5])
def test_far_water_looks_like_the_sea_beside_it(gl, hours):
    far, sea = _patch(gl, True, hours), _patch(gl, False, hours)
    assert np.abs(far - sea).max() < 8, (far, sea)  # (flat albedo: 21-26)


def test_shallow_far_water_shows_its_floor_deep_water_is_the_seas():
    """A far water vertex's colour: over sand one block deep it shows the sand (as the
    near water layer does by a beach), forty blocks deep it is deep water's colour
    (water.glsl WATER_DEEP, linear (0.0018, 0.029, 0.08): sRGB ~ (15, 50, 81))."""
    sand = mesh.palette()[REGISTRY.id("sand")]
    shallow, deep = mesh._water_over(np.array([sand, sand]), np.array([1.0, 40.0]))
    assert shallow.sum() > deep.sum() + 100, (shallow, deep)
    assert np.abs(deep - [15, 50, 81]).max() < 3, deep
