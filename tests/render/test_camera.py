"""Region culling: the fast plane test equals the thesis's brute-force 8-corner clip test."""
import numpy as np

from voxel_addon.render import camera as C

_CORNERS = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float)


def brute(mvp, lo, hi):
    pts = lo[:, None, :] + (hi - lo)[:, None, :] * _CORNERS[None]
    clip = (np.c_[pts.reshape(-1, 3), np.ones(len(pts) * 8)] @ mvp.T).reshape(-1, 8, 4)
    x, y, z, w = np.moveaxis(clip, -1, 0)
    return ~((x < -w).all(1) | (x > w).all(1) | (y < -w).all(1) | (y > w).all(1)
             | (z < -w).all(1) | (z > w).all(1))


def test_culling_equals_brute_force():
    rng = np.random.default_rng(0)
    culled = 0
    for _ in range(40):
        cam = C.Camera(*rng.uniform(-50, 50, 2), rng.uniform(0, 200), rng.uniform(0, 360),
                       rng.uniform(-89, 89))
        lo = rng.uniform(-300, 300, (2000, 3))
        hi = lo + rng.uniform(0, 40, (2000, 3))
        got = C.visible(cam.view_proj(), lo, hi)
        assert (got == brute(cam.view_proj(), lo, hi)).all()
        culled += (~got).sum()
    assert culled > 10000  # the cameras do cull
