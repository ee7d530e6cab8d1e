"""The sun's (or moon's) shadow map fitted to the view (§5.4.1): an orthographic light
matrix around the part of the view frustum that gets shadows (up to the fade distance;
an orthographic view: its view box where the shown area is), its near plane pulled
back to the top of the shown area so casters off screen still cast."""
from __future__ import annotations

import numpy as np

from . import camera as cam

# clip space -> shadow-map texture coordinates and depth
BIAS = np.array([[.5, 0, 0, .5], [0, .5, 0, .5], [0, 0, .5, .5], [0, 0, 0, 1]])


def fit(camera: cam.Camera, light_dir, area, fade: float, size: int):
    """(light view-projection, world size of a shadow texel, depth bias in depth units).
    area: (cx0, cy0, cx1, cy1) of the shown chunks, or None.

    Python floats throughout: a few dozen products, where NumPy's per-call cost was
    most of the frame's matrix work."""
    if camera.ortho:  # the view box, in depth where the shown area is
        lo, hi = camera.near, camera.far
        if area:
            d = [camera.depth(p) for p in _area_corners(area)]
            lo, hi = max(lo, min(d)), min(hi, max(d))
        pts = camera.corners(max(hi, lo + 1.0), lo)
    else:
        pts = camera.corners(fade + 2.0)
    n = len(pts)
    mid = [sum(p[k] for p in pts) / n for k in range(3)]
    rows = cam.view_rows(mid, [-v for v in light_dir])  # light space: +z to the light
    lc = [[r[0] * x + r[1] * y + r[2] * z + r[3] for r in rows] for x, y, z in pts]
    lo = [min(c[k] for c in lc) for k in range(3)]
    hi = [max(c[k] for c in lc) for k in range(3)]
    # the near plane reaches back to the top of the shown area so off-screen casters
    # between the light and the view still cast; depth precision stays bounded
    top = hi[2]
    if area:
        r = rows[2]
        top = max(top, max(r[0] * x + r[1] * y + r[2] * z + r[3] for x, y, z in _area_corners(area)))
    near, far = -top - 1.0, -lo[2] + 1.0
    # ortho(lo.x, hi.x, lo.y, hi.y, near, far) @ view, row by row
    sx, sy, sz = 2 / (hi[0] - lo[0]), 2 / (hi[1] - lo[1]), -2 / (far - near)
    ox, oy = -(hi[0] + lo[0]) / (hi[0] - lo[0]), -(hi[1] + lo[1]) / (hi[1] - lo[1])
    oz = -(far + near) / (far - near)
    m = np.array([[v * sx for v in rows[0][:3]] + [rows[0][3] * sx + ox],
                  [v * sy for v in rows[1][:3]] + [rows[1][3] * sy + oy],
                  [v * sz for v in rows[2][:3]] + [rows[2][3] * sz + oz],
                  [0.0, 0.0, 0.0, 1.0]])
    texel = max(hi[0] - lo[0], hi[1] - lo[1]) / size
    return m, texel, 0.05 / (far - near)  # 0.05 blocks of depth bias


def _area_corners(area):
    cx0, cy0, cx1, cy1 = area
    return [(x, y, z) for x in (16.0 * cx0, 16.0 * cx1) for y in (16.0 * cy0, 16.0 * cy1)
            for z in (0.0, 256.0)]
