"""A small NumPy mesher the pipeline uses until `voxel_addon.meshing` lands.

No aggregation; the hidden-face rule of the meshing issue (a cube face toward B is
drawn unless B is an opaque cube, or both are the same blend block). Vertices are
20 bytes: position (3 float, world units relative to the scene origin), then two
uint32 words: A = normal xyz as int8 + texture layer; B = u, v (texels, 0..255),
animation (4 bits), quad id (12 bits, for the aggregation view).
"""
from __future__ import annotations

import numpy as np

from ..core.blocks import ANIMATIONS, REGISTRY, RENDERS, SHAPES

CONTEXTS = ("opaque", "alpha_test", "blend")  # the thesis's face contexts, reduced
REGION_H = 32
VERTEX = np.dtype([("pos", "<f4", 3), ("a", "<u4"), ("b", "<u4")])

_R = REGISTRY
_CUBE = _R.shape == SHAPES.index("cube")
_OPAQUE_CUBE = _CUBE & (_R.render == RENDERS.index("opaque"))
_BLEND = _R.render == RENDERS.index("blend")
_ANIM = np.array([ANIMATIONS.index(b.animation) for b in _R.blocks], np.uint32)
_CTX = np.array([max(0, int(r) - 1) for r in _R.render], np.uint8)  # opaque/alpha/blend
_TRI = (0, 1, 2, 0, 2, 3)


def _pack(pos, normal, layer, uv, anim, qid):
    n = len(pos)
    v = np.empty(n, VERTEX)
    v["pos"] = pos
    nb = (np.round(np.asarray(normal, float) * 127).astype(np.int32) & 0xFF).astype(np.uint32)
    nb = np.broadcast_to(nb, (n, 3))
    v["a"] = nb[:, 0] | (nb[:, 1] << 8) | (nb[:, 2] << 16) | (layer.astype(np.uint32) << 24)
    v["b"] = (uv[:, 0].astype(np.uint32) | (uv[:, 1].astype(np.uint32) << 8)
              | (anim.astype(np.uint32) << 16) | ((qid.astype(np.uint32) & 0xFFF) << 20))
    return v


def _quads(corners, normal, layer, uvs, anim, qid):
    """corners (q,4,3), uvs (4,2) or (q,4,2) -> 6 vertices per quad."""
    q = len(corners)
    idx = np.array(_TRI)
    pos = corners[:, idx].reshape(-1, 3)
    uv = np.broadcast_to(uvs, (q, 4, 2))[:, idx].reshape(-1, 2)
    rep = lambda a: np.repeat(np.asarray(a), 6, axis=0)  # noqa: E731
    nrm = np.asarray(normal, float)
    nrm = rep(nrm) if nrm.ndim == 2 else nrm
    return _pack(pos, nrm, rep(layer), uv, rep(anim), rep(qid))


def mesh(blocks: np.ndarray, origin=(0, 0, 0)) -> dict:
    """blocks (W,H,256) -> {(context, rz): vertex array}, positions + origin."""
    W, H, Z = blocks.shape
    pad = np.zeros((W + 2, H + 2, Z + 2), np.uint16)
    pad[1:-1, 1:-1, 1:-1] = blocks
    pad[:, :, 0] = 1  # below the world counts as stone: no bottom faces
    ox = np.asarray(origin, float)
    out: dict = {}
    b = pad[1:-1, 1:-1, 1:-1]
    cube = _CUBE[b]
    for face in range(6):
        axis, pos_side = divmod(face, 2)
        sh = [1, 1, 1]
        sh[axis] += 1 if pos_side else -1
        nb = pad[sh[0]:sh[0] + W, sh[1]:sh[1] + H, sh[2]:sh[2] + Z]
        show = cube & ~_OPAQUE_CUBE[nb] & ~(_BLEND[b] & (nb == b))
        xs, ys, zs = np.nonzero(show)
        if not len(xs):
            continue
        ids = b[xs, ys, zs]
        u, v = (axis + 1) % 3, (axis + 2) % 3
        c = np.zeros((4, 3))
        c[:, axis] = pos_side
        c[[1, 2], u] = 1
        c[[2, 3], v] = 1
        if not pos_side:
            c = c[::-1]
        # texture v runs up z on side faces, u along the horizontal axis
        if axis == 0:
            uvs = np.stack([c[:, 1], c[:, 2]], 1) * 16
        elif axis == 1:
            uvs = np.stack([c[:, 0], c[:, 2]], 1) * 16
        else:
            uvs = np.stack([c[:, 0], c[:, 1]], 1) * 16
        if axis != 2 and pos_side == (axis == 1):
            uvs[:, 0] = 16 - uvs[:, 0]  # mirror so textures read left-to-right outside
        corners = np.stack([xs, ys, zs], 1)[:, None, :] + c[None] + ox
        normal = np.zeros(3)
        normal[axis] = 1 if pos_side else -1
        layer = _R.face_texture[ids, face]
        qid = (xs * 73856093 ^ ys * 19349663 ^ zs * 83492791 ^ face * 2654435761) & 0xFFF
        _emit(out, ids, zs, _quads(corners, normal, layer, uvs, _ANIM[ids], qid))
    _plants(out, b, ox)
    return out


def _plants(out, b, ox):
    shape = _R.shape[b]
    for kind in (SHAPES.index("x"), SHAPES.index("hash")):
        xs, ys, zs = np.nonzero(shape == kind)
        if not len(xs):
            continue
        ids = b[xs, ys, zs]
        base = np.stack([xs, ys, zs], 1).astype(float)[:, None, :] + ox
        planes = []
        if kind == SHAPES.index("x"):
            planes = [np.array([[0, 0, 0], [1, 1, 0], [1, 1, 1], [0, 0, 1]], float),
                      np.array([[1, 0, 0], [0, 1, 0], [0, 1, 1], [1, 0, 1]], float)]
            per = [np.zeros(len(ids))] * 2
        else:
            t = np.array([_R.blocks[i].inset for i in range(len(_R))], float)[ids] / 16
            per = [t, 1 - t, t, 1 - t]
            planes = ["x", "x", "y", "y"]
        for k, pl in enumerate(planes):
            if isinstance(pl, str):
                off = per[k][:, None]
                corners = np.zeros((len(ids), 4, 3))
                a, o = (0, 1) if pl == "x" else (1, 0)
                corners[:, :, a] = off
                corners[:, :, o] = np.array([0, 1, 1, 0])
                corners[:, :, 2] = np.array([0, 0, 1, 1])
            else:
                corners = np.broadcast_to(pl, (len(ids), 4, 3)).copy()
            uvs = np.array([[0, 0], [16, 0], [16, 16], [0, 16]], float)
            qid = (xs * 73856093 ^ ys * 19349663 ^ zs * 83492791 ^ k) & 0xFFF
            _emit(out, ids, zs, _quads(corners + base, (0, 0, 1), _R.face_texture[ids, 0],
                                       uvs, _ANIM[ids], qid))


def _emit(out, ids, zs, verts):
    ctx = np.repeat(_CTX[ids], 6)
    rz = np.repeat(zs // REGION_H, 6)
    key = ctx.astype(np.int64) * 64 + rz
    order = np.argsort(key, kind="stable")
    key, verts = key[order], verts[order]
    cuts = np.flatnonzero(np.diff(key)) + 1
    for part_k, part_v in zip(np.split(key, cuts), np.split(verts, cuts)):
        k = (CONTEXTS[part_k[0] // 64], int(part_k[0] % 64))
        out[k] = np.concatenate([out[k], part_v]) if k in out else part_v
