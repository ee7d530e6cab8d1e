"""Quads -> float triangle meshes (for the bake) and the one definition of quad corners,
normals and UVs that the packed viewport format (vertex.py, shaders/include/vertex.glsl)
reproduces."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.blocks import REGISTRY

# The face code tables (README): 0..5 cube faces in core.blocks.FACES order
# (-x +x -y +y -z +z: code = 2 * axis + positive side), 6, 7 the X planes, 8..11 the
# # planes (the sides 0..3 moved inward). Per code: the axis of its normal and the sign
# (X planes take +x, +y: they sample light like those sides), its tangent axes t1, t2
# (axis x: y, z; y: x, z; z: x, y) and the cube side whose texture it shows.
AXIS = np.array([0, 0, 1, 1, 2, 2, 0, 1, 0, 0, 1, 1], np.int8)
SIGN = np.array([-1, 1, -1, 1, -1, 1, 1, 1, -1, 1, -1, 1], np.int8)
T1 = np.array([1, 0, 0], np.int8)[AXIS]
T2 = np.array([2, 2, 1], np.int8)[AXIS]
SIDE = np.array([0, 1, 2, 3, 4, 5, 0, 0, 0, 1, 2, 3], np.int8)

# Unit corner offsets (4, 3) per face code, counter-clockwise seen from the front.
# Cube faces: corners in (t1, t2) units (scaled by w, h); shapes are 1×1.
_CCW = ((0, 0), (1, 0), (1, 1), (0, 1))


def _corners():
    c = np.zeros((12, 4, 3), np.float32)         # unit offsets, already oriented
    for f in range(6):
        a, sign, t1, t2 = int(AXIS[f]), int(SIGN[f] > 0), int(T1[f]), int(T2[f])
        # (t1 x t2) points along +a for x and z, along -a for y
        front = (sign == 1) == (a != 1)
        order = _CCW if front else _CCW[::-1]
        for k, (i, j) in enumerate(order):
            c[f, k, t1], c[f, k, t2] = i, j
            c[f, k, a] = sign
    c[6] = [(0, 0, 0), (1, 1, 0), (1, 1, 1), (0, 0, 1)]
    c[7] = [(1, 0, 0), (0, 1, 0), (0, 1, 1), (1, 0, 1)]
    c[8:12] = c[0:4]
    return c


CORNERS = _corners()
NORMALS = np.zeros((12, 3), np.float32)
NORMALS[np.arange(6), AXIS[:6]] = SIGN[:6]
NORMALS[6] = np.array([1, -1, 0]) / np.sqrt(2)
NORMALS[7] = np.array([1, 1, 0]) / np.sqrt(2)
NORMALS[8:12] = NORMALS[0:4]
# UV = (p · U[face], p · V[face]) on the local position p.
UV_U = np.array([(0, -1, 0), (0, 1, 0), (1, 0, 0), (-1, 0, 0), (1, 0, 0), (1, 0, 0),
                 (1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 1, 0), (1, 0, 0), (-1, 0, 0)], np.float32)
UV_V = np.array([(0, 0, 1)] * 4 + [(0, -1, 0), (0, 1, 0)] + [(0, 0, 1)] * 6, np.float32)
INSET = np.array([b.inset for b in REGISTRY.blocks], np.float32) / 16


def quad_indices(n: int, dtype=np.uint32) -> np.ndarray:
    """The one quad -> triangles pattern, for n quads of 4 counter-clockwise vertices:
    (0,1,2, 0,2,3) + 4k, flat (reshape(-1, 3) for triangles)."""
    k = 4 * np.arange(n, dtype=dtype)[:, None]
    return (k + np.array([0, 1, 2, 0, 2, 3], dtype)).ravel()


@dataclass
class Mesh:
    positions: np.ndarray   # (4N, 3) float32
    normals: np.ndarray     # (4N, 3) float32
    uvs: np.ndarray         # (4N, 2) float32
    face: np.ndarray        # (N,) uint8
    block: np.ndarray       # (N,) uint16
    layer: np.ndarray       # (N,) uint16

    def triangles(self) -> np.ndarray:
        return quad_indices(len(self.face), np.int32).reshape(-1, 3)


def corner_positions(q, inset=True) -> np.ndarray:
    """(N, 4, 3) float32 local corner positions of quads (before any origin shift);
    inset=False leaves # planes on the cell side (the packed format adds it in GLSL)."""
    f = q["face"].astype(np.intp)
    c = CORNERS[f].copy()
    cube = f < 6
    t1, t2 = T1[f], T2[f]
    n = np.arange(len(q))
    c[n, :, t1] *= np.where(cube, q["w"], 1).astype(np.float32)[:, None]
    c[n, :, t2] *= np.where(cube, q["h"], 1).astype(np.float32)[:, None]
    c += np.stack([q["x"], q["y"], q["z"]], -1).astype(np.float32)[:, None, :]
    hs = f >= 8
    if inset and hs.any():  # # planes sit inset from the cell side, toward the centre
        side = f[hs] - 8
        shift = INSET[q["block"][hs]] * np.where(side % 2, -1, 1)
        c[np.nonzero(hs)[0], :, side // 2] += shift[:, None]
    return c


def uv_of(face, p):
    """UVs (…, 2) for local positions p (…, 3) on faces with codes `face` (…)."""
    return np.stack([(p * UV_U[face]).sum(-1), (p * UV_V[face]).sum(-1)], -1)


def to_mesh(q, origin=(0, 0, 0), two_sided=False) -> Mesh:
    q = np.asarray(q)
    if two_sided:
        ds = np.array([b.double_sided for b in REGISTRY.blocks])[q["block"]]
        back = q[ds]
    p = corner_positions(q)
    f = q["face"].astype(np.intp)
    uv = uv_of(f[:, None], p)
    nrm = np.repeat(NORMALS[f][:, None, :], 4, axis=1)
    face, block, layer = q["face"], q["block"], q["layer"]
    if two_sided and len(back):
        m = np.nonzero(ds)[0]
        p = np.concatenate([p, p[m, ::-1]])
        uv = np.concatenate([uv, uv[m, ::-1]])
        nrm = np.concatenate([nrm, -nrm[m]])
        face, block, layer = (np.concatenate([a, a[m]]) for a in (face, block, layer))
    p = p + np.asarray(origin, np.float32)
    return Mesh(p.reshape(-1, 3).astype(np.float32), nrm.reshape(-1, 3).astype(np.float32),
                uv.reshape(-1, 2).astype(np.float32), face.copy(), block.copy(), layer.copy())
