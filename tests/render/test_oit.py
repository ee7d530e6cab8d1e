"""Weighted blended OIT (Settings.transparency = "oit") against depth peeling, on real
frames (Mesa llvmpipe through EGL)."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon.core.blocks import REGISTRY as R
from voxel_addon.core.errors import VoxelError
from voxel_addon.render import Camera, Settings

from .test_render import SIZE, _pool, floor, renderer

POOL_CAM = Camera(16, 16, 72, 0, -89)


def frame(gl, blocks, cam, **kw):
    r = renderer(gl, blocks, **kw)
    img = r.render(cam, 12.0, SIZE).astype(float)
    r.release()
    return img


def test_water_shows_what_is_behind_it_with_oit(gl):
    # test_render's property, with OIT instead of peeling
    tint = lambda x: x[..., 2].mean() - x[..., 0].mean()  # noqa: E731
    imgs = {}
    for under in ("sand", "stone"):
        for t, layers in (("oit", 3), ("peel", 0)):
            img = frame(gl, _pool(under), POOL_CAM, transparency=t, peel_layers=layers,
                        shadows=False)
            imgs[under, t] = img[24:40, 40:56]
    assert abs(imgs["sand", "oit"] - imgs["stone", "oit"]).mean() > 10, "the bottom shows"
    for u in ("sand", "stone"):
        assert tint(imgs[u, "oit"]) > tint(imgs[u, "peel"]) + 5, "and the water tints it"


@pytest.mark.parametrize("msaa", [1, 4])
def test_one_layer_matches_peeling(gl, msaa):
    """A pool seen from above has one transparent layer (its surface; the faces against
    the bottom and the walls are hidden). For one layer WBOIT's eq. 6 is exact: accum
    / weight = the layer's colour, 1 - revealage = its alpha, whatever the weight. What
    remains is arithmetic: the colour goes through RGBA16F (10-bit mantissa, ~0.1 %
    of a 0..1 value: under one 8-bit step), revealage through exp(-log(1 - a)) in
    fp16, and the forward pass shades the interpolated world position where the
    deferred one reconstructs it from depth (a light sample a hair apart). So: the
    mean difference well under one step, no pixel more than 3 steps off. (Without
    the water effects: the colour by depth needs the opaque depth, which only the
    peeled layer reads.)"""
    b = _pool("sand")
    imgs = [frame(gl, b, POOL_CAM, transparency=t, msaa=msaa, shadows=True, water=False)
            for t in ("peel", "oit")]
    d = np.abs(imgs[0] - imgs[1])
    assert d.mean() < 0.3 and d.max() <= 3, (d.mean(), d.max())
    # and the layer is really there (the comparison is not between two empty frames)
    none = frame(gl, b, POOL_CAM, peel_layers=0, msaa=msaa, shadows=True)
    assert np.abs(none - imgs[1])[24:40, 40:56].mean() > 10


def _panes(first, second):
    """Two differently coloured transparent walls across the view, x = 14 and x = 16:
    four layers (each wall's front and back face)."""
    b = floor()
    b[14, 4:28, 61:76] = R.id(first)
    b[16, 4:28, 61:76] = R.id(second)
    return b


def test_swapping_two_layers_in_depth_keeps_the_oit_blend(gl):
    """WBOIT's defining property: the blend is a weighted sum, so it does not depend on
    which surface is in front (where the weights are equal). The four faces lie 3-6
    blocks from the camera, where the weight of eq. 9 is clamped to its 3e3 maximum:
    equal weights, an exactly commutative blend. Peeling composites in depth order (and
    keeps only 3 of the 4 layers): swapping glass and water changes its image a lot.
    The walls cover the whole view, but the nearer one's texture is projected larger,
    so pixels differ: compare the mean colour of the frame (many texture periods)."""
    cam = Camera(11, 16, 67, 0, 0)
    kw = dict(shadows=False, fog=False, waving=False)
    mean = {}
    for order in (("glass", "water"), ("water", "glass")):
        for t in ("peel", "oit"):
            mean[order, t] = frame(gl, _panes(*order), cam, transparency=t, **kw).mean((0, 1))
    oit = np.abs(mean[("glass", "water"), "oit"] - mean[("water", "glass"), "oit"])
    peel = np.abs(mean[("glass", "water"), "peel"] - mean[("water", "glass"), "peel"])
    assert oit.max() < 2.0 and peel.max() > 20, (oit, peel)
    # and it is a blend of these surfaces (not, say, black both times): between the two
    # order-dependent ones, per channel
    lo = np.minimum(*(mean[o, "peel"] for o in (("glass", "water"), ("water", "glass"))))
    hi = np.maximum(*(mean[o, "peel"] for o in (("glass", "water"), ("water", "glass"))))
    for o in (("glass", "water"), ("water", "glass")):
        assert np.all(mean[o, "oit"] > lo - 10) and np.all(mean[o, "oit"] < hi + 10), mean


def test_transparency_setting():
    s = Settings().with_effects("oit")
    assert s.transparency == "oit"
    assert Settings().with_effects("oit,peel2").transparency == "peel"
    assert Settings().with_effects("oit,-oit").transparency == "peel"
    assert Settings().transparency == "peel", "peeling stays the default (golden images)"
    with pytest.raises(VoxelError, match="unknown transparency"):
        Settings(transparency="sorted").check()
