"""Model elements → quads, as the game's FaceBakery builds them, then into the voxel
frame.

Minecraft's frame: x east, y up, z south, a block spans 0..16. Per face the four
corners run top-left, bottom-left, bottom-right, top-right seen from outside, and
corner i takes uv corner `(i + rotation/90) % 4` of (u0,v0) (u0,v1) (u1,v1) (u1,v0).
The voxel frame (formats/README: block (x, y, z) → voxel (x, −1−z, y)) maps a point of
a block to (x, 1 − z, y) in 0..1: a proper rotation, so windings are kept.
"""
from __future__ import annotations

import math

import numpy as np

# Minecraft directions, their unit vectors, and the project's face index
# (core.blocks.FACES: -x +x -y +y -z +z) once in the voxel frame.
DIRS = ("down", "up", "north", "south", "west", "east")
VEC = {"down": (0, -1, 0), "up": (0, 1, 0), "north": (0, 0, -1), "south": (0, 0, 1),
       "west": (-1, 0, 0), "east": (1, 0, 0)}
FACE = {"down": 4, "up": 5, "north": 3, "south": 2, "west": 0, "east": 1}
_BY_VEC = {v: d for d, v in VEC.items()}

# corners per face: (x, y, z) each choosing from (0 = from, 1 = to)
_CORNERS = {
    "down": ((0, 0, 1), (0, 0, 0), (1, 0, 0), (1, 0, 1)),
    "up": ((0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)),
    "north": ((1, 1, 0), (1, 0, 0), (0, 0, 0), (0, 1, 0)),
    "south": ((0, 1, 1), (0, 0, 1), (1, 0, 1), (1, 1, 1)),
    "west": ((0, 1, 0), (0, 0, 0), (0, 0, 1), (0, 1, 1)),
    "east": ((1, 1, 1), (1, 0, 1), (1, 0, 0), (1, 1, 0)),
}
_UV_CORNER = ((0, 1), (0, 3), (2, 3), (2, 1))    # indices into (u0, v0, u1, v1)


def world_uv(direction: str, p) -> tuple[float, float]:
    """The texture position (in 1/16) the game gives point P (1/16 units) of a face
    looking DIRECTION when no uv is set: the texture sits still in the world."""
    x, y, z = p
    return {"down": (x, 16 - z), "up": (x, z), "north": (16 - x, 16 - y),
            "south": (x, 16 - y), "west": (z, 16 - y), "east": (16 - z, 16 - y)}[direction]


def default_uv(direction: str, f, t) -> list[float]:
    """A face's uv rect when the model gives none (FaceBakery's defaults)."""
    uv = np.array([world_uv(direction, _corner(direction, i, f, t)) for i in range(4)])
    return [*uv.min(axis=0).tolist(), *uv.max(axis=0).tolist()]


def _corner(direction, i, f, t):
    return tuple((f, t)[c][k] for k, c in enumerate(_CORNERS[direction][i]))


def _rot(axis: str, deg: float) -> np.ndarray:
    """Right-handed rotation by DEG about AXIS."""
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    c, s = round(c, 12), round(s, 12)
    if axis == "x":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == "y":
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def variant_matrix(x: int, y: int) -> np.ndarray:
    """A variant's rotation: x first, then y, both clockwise looking down their axis
    (`"y": 90` turns north to east), as BlockModelRotation."""
    return _rot("y", -y) @ _rot("x", -x)


def rotate_dir(m: np.ndarray, direction: str) -> str:
    v = tuple(int(round(c)) for c in m @ np.array(VEC[direction], float))
    return _BY_VEC[v]


def element_quads(el: dict, m: np.ndarray, uvlock: bool):
    """Yield (direction after M, corners (4,3) in 1/16, uv (4,2) in 1/16, face dict,
    cullface after M or None) for each face of element EL."""
    f, t = el["from"], el["to"]
    r = el.get("rotation")
    for d in DIRS:
        face = el["faces"].get(d)
        if face is None:
            continue
        pts = np.array([_corner(d, i, f, t) for i in range(4)], float)
        uv = face.get("uv") or default_uv(d, f, t)
        turn = (face.get("rotation", 0) // 90) % 4
        uvs = np.array([[uv[_UV_CORNER[(i + turn) % 4][0]], uv[_UV_CORNER[(i + turn) % 4][1]]]
                        for i in range(4)], float)
        if r:
            axis, ang = r["axis"], r["angle"]
            o = np.array(r.get("origin", (8, 8, 8)), float)
            scale = np.ones(3)
            if r.get("rescale") and ang % 90:
                s = 1 / math.cos(math.radians(abs(ang)))
                scale = np.array([1.0 if a == axis else s for a in "xyz"])
            pts = ((pts - o) @ _rot(axis, ang).T) * scale + o
        pts = (pts - 8) @ m.T + 8
        nd = rotate_dir(m, d)
        if uvlock and not np.allclose(m, np.eye(3)):   # the face's own rotation is dropped
            uvs = np.array([world_uv(nd, p) for p in pts], float)
        cull = face.get("cullface")
        yield nd, pts, uvs, face, (rotate_dir(m, cull) if cull in VEC else None)


def to_voxel(pts: np.ndarray) -> np.ndarray:
    """Corners in 1/16 (Minecraft frame) → block units in the voxel frame."""
    p = np.asarray(pts, float) / 16.0
    return np.stack([p[..., 0], 1.0 - p[..., 2], p[..., 1]], axis=-1)
