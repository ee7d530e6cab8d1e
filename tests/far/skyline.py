"""Skylines for the far silhouette tests: the generator's true terrain (every block
column's top face) and a far mesh set's, per image column, in pixel rows (0 = the
top of the image, +inf where a column shows no terrain)."""
from __future__ import annotations

import numpy as np

from voxel_addon.far import grid, mesh


def _screen(vp, p, width, height):
    """World points (n, 3) -> (px x, px y from the top, in front)."""
    h = np.c_[p, np.ones(len(p))] @ vp.T
    w = h[:, 3]
    front = w > 1e-6
    x = (h[:, 0] / np.where(front, w, 1) + 1) * 0.5 * width
    y = (1 - h[:, 1] / np.where(front, w, 1)) * 0.5 * height
    return x, y, front


def true_skyline(gen, cam, width, height, reach, per_px=2, inside=None):
    """Topmost screen y of the true terrain per pixel column: the top face centres
    of the columns along rays from the camera, 1 block apart to 512, then 2;
    inside(xy) -> bool mask: the columns that count (the drawn area)."""
    vp = cam.view_proj()
    half = np.radians(cam.fov) / 2
    hfov = 2 * np.arctan(np.tan(half) * cam.aspect)
    az = np.radians(cam.yaw) + np.linspace(hfov / 2 * 1.02, -hfov / 2 * 1.02, width * per_px)
    d = np.r_[np.arange(1.0, min(reach, 512)), np.arange(512.0, reach, 2.0)]
    X = np.floor(cam.x + np.cos(az)[:, None] * d[None, :]).astype(np.int64)
    Y = np.floor(cam.y + np.sin(az)[:, None] * d[None, :]).astype(np.int64)
    xy = np.unique(np.stack([X.ravel(), Y.ravel()], -1), axis=0)
    if inside is not None:
        xy = xy[inside(xy)]
    s = gen.surface(xy)
    p = np.c_[xy + 0.5, s["height"] + 1.0]
    return _top(p, vp, width, height)


def _top(p, vp, width, height):
    x, y, front = _screen(vp, p, width, height)
    col = np.floor(x).astype(np.int64)
    ok = front & (col >= 0) & (col < width)
    out = np.full(width, np.inf)
    np.minimum.at(out, col[ok], y[ok])
    return out


def in_rects(rects):
    """inside() for true_skyline: columns within any of the [x0, x1) x [y0, y1)."""
    r = np.array(list(rects), np.int64).reshape(-1, 4)

    def f(xy):
        ok = np.zeros(len(xy), bool)
        for x0, y0, x1, y1 in r:
            ok |= (xy[:, 0] >= x0) & (xy[:, 0] < x1) & (xy[:, 1] >= y0) & (xy[:, 1] < y1)
        return ok
    return f


def positions(m, view=None):
    """World positions of a FarMesh's vertices, morphed for a view point (x, y) as
    the far shader draws them (grid.morph), or unmorphed."""
    w0, w2 = m.vertices[:, 0], m.vertices[:, 2]
    x = m.origin[0] + (w0 & 63) * m.spacing + 0.5
    y = m.origin[1] + ((w0 >> 6) & 63) * m.spacing + 0.5
    z, zc = ((w0 >> 12) & 8191) / 8.0, (w2 & 8191) / 8.0
    if view is not None:
        k = grid.morph(np.hypot(x - view[0], y - view[1]), m.key[0])
        z = z + (zc - z) * k
    return np.stack([x, y, z], -1)


def mesh_skyline(meshes, cam, width, height, morph=True):
    """Topmost screen y of the far meshes' ground per pixel column (rasterised on
    the CPU: each triangle's upper edge at the column centres), morphed for the
    camera's position as drawn."""
    vp = cam.view_proj()
    out = np.full(width, np.inf)
    for m in meshes:
        w0 = m.vertices[:, 0]
        p = positions(m, (cam.x, cam.y) if morph else None)
        kind = (w0 >> 25) & 3
        x, y, front = _screen(vp, p, width, height)
        t = m.ground.reshape(-1, 3)
        t = t[front[t].all(1) & (kind[t] != mesh.SKIRT).all(1)]
        tx, ty = x[t], y[t]
        lo = np.ceil(tx.min(1) - 0.5).astype(np.int64)
        hi = np.floor(tx.max(1) - 0.5).astype(np.int64)
        keep = (hi >= lo) & (hi >= 0) & (lo < width)
        tx, ty, lo, hi = tx[keep], ty[keep], lo[keep], hi[keep]
        for j in range(int((hi - lo).max(initial=-1)) + 1):
            c = lo + j
            on = (c <= hi) & (c >= 0) & (c < width)
            xc = c[on] + 0.5
            best = np.full(on.sum(), np.inf)
            for a, b in ((0, 1), (1, 2), (2, 0)):
                xa, xb = tx[on, a], tx[on, b]
                ya, yb = ty[on, a], ty[on, b]
                span = (np.minimum(xa, xb) <= xc) & (xc <= np.maximum(xa, xb)) & (xa != xb)
                f = np.where(span, (xc - xa) / np.where(xa != xb, xb - xa, 1), 0)
                yc = np.where(span, ya + f * (yb - ya), np.inf)
                best = np.minimum(best, yc)
            np.minimum.at(out, c[on], best)
    return out


def tile_of(gen, key, trees: bool = True) -> dict:
    """A far tile's samples straight from the generator's 2D passes (trees=False: the
    bare ground, whose skyline the true heights give)."""
    X, Y = grid.columns(key)
    s = gen.surface(np.stack([X.ravel(), Y.ravel()], -1))
    t = np.rint(s["trees"] * 255).reshape(X.shape) if trees else np.zeros(X.shape)
    return {"height": s["height"].reshape(X.shape).astype(np.int16),
            "top": s["top"].reshape(X.shape).astype(np.uint16),
            "water": s["water"].reshape(X.shape).astype(np.int16),
            "trees": t.astype(np.uint8)}
