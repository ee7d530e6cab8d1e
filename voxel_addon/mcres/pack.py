"""`Resources`: one resource stack read as the game reads it. `shape(name, props, pos)`
gives a block state's quads in the voxel frame (cached per state and drawn variant),
`texture(id)` its pixels (the first animation frame) and render layer."""
from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import VoxelError
from . import geometry, models, png
from .states import BlockState

SOLID, CUTOUT, TRANSLUCENT = "solid", "cutout", "translucent"
_ORDER = {SOLID: 0, CUTOUT: 1, TRANSLUCENT: 2}


@dataclass
class Texture:
    id: str
    rgba: np.ndarray      # (h, w, 4) uint8, row 0 at the top: the first animation frame
    layer: str            # solid (all opaque), cutout (alpha 0 or 255), translucent


@dataclass
class Quad:
    pos: np.ndarray       # (4, 3) float32, block units in the voxel frame, corners
                          # top-left, bottom-left, bottom-right, top-right seen from outside
    uv: np.ndarray        # (4, 2) float32, 0..1 across the texture (v down), may leave 0..1
    sprite: str | None    # texture id; None: the pack leaves it unset
    face: int             # the direction it looks (core.blocks.FACES index)
    cull: int             # dropped when the neighbour there is a full block; -1 never
    tint: int             # tintindex, -1 none
    shade: bool
    layer: str


@dataclass
class Shape:
    quads: list = field(default_factory=list)
    ao: bool = True
    full: bool = False    # a whole opaque cube: neighbours' faces against it are hidden
    layer: str = SOLID    # the most see-through layer of its quads
    faces: tuple = (False,) * 6   # per side (core.blocks.FACES): opaque quads cover it
                                  # whole (a stair's bottom and back): what it hides there
    arrays: dict | None = field(default=None, repr=False, compare=False)   # mcres.mesh's


def _layer(rgba: np.ndarray) -> str:
    a = rgba[..., 3]
    if (a == 255).all():
        return SOLID
    return CUTOUT if np.isin(a, (0, 255)).all() else TRANSLUCENT


def first_frame(rgba: np.ndarray, meta) -> np.ndarray:
    """The first frame of an animated texture (`.mcmeta` `animation`): frames are
    `width`×`height` (default: squares of the smaller side), laid row by row."""
    anim = meta.get("animation") if isinstance(meta, dict) else None
    if not isinstance(anim, dict):
        return rgba
    h, w = rgba.shape[:2]
    side = min(h, w)
    fw, fh = anim.get("width", side), anim.get("height", side)
    if not (isinstance(fw, int) and isinstance(fh, int) and 0 < fw <= w and 0 < fh <= h):
        return rgba
    frames = anim.get("frames")
    i = 0
    if isinstance(frames, list) and frames:
        f0 = frames[0]
        i = f0.get("index", 0) if isinstance(f0, dict) else f0
        i = i if isinstance(i, int) and i >= 0 else 0
    cols = w // fw
    col, row = i % cols, i // cols
    if (row + 1) * fh > h:
        col, row = 0, 0
    return rgba[row * fh:(row + 1) * fh, col * fw:(col + 1) * fw]


LIFT = 1 / 512   # blocks an overlay stands off the face under it


def _lift_overlays(quads) -> None:
    """A quad on the very place of an earlier one (grass sides' overlay) is drawn
    after it in the game, in the same depth; a bake or a viewer would z-fight, so it
    is lifted off along its normal (by LIFT per quad under it)."""
    seen: dict = {}
    for q in quads:
        n = np.cross(q.pos[1] - q.pos[0], q.pos[2] - q.pos[0])
        n = n / (np.linalg.norm(n) or 1.0)
        # the same corners facing the same way (a plane's back is no overlay)
        key = (tuple(sorted(map(tuple, np.round(q.pos, 5).tolist()))),
               tuple(np.round(n, 3).tolist()))
        k = seen.get(key, 0)
        seen[key] = k + 1
        if k:
            q.pos = (q.pos + n * LIFT * k).astype(np.float32)


def _covers(quads, d: int) -> bool:
    """Do the opaque quads on side D of the block (lying in its boundary plane) cover
    it whole? Rasterised at 1/16 block (models are drawn on that grid)."""
    axis, hi = d // 2, d % 2
    grid = np.zeros((16, 16), bool)
    for q in quads:
        if q.layer != SOLID or q.face != d or not np.allclose(q.pos[:, axis], hi):
            continue
        uv = np.delete(q.pos, axis, axis=1) * 16
        (a, b), (c, e) = np.floor(uv.min(axis=0) + 1e-6).astype(int), \
            np.ceil(uv.max(axis=0) - 1e-6).astype(int)
        grid[max(a, 0):min(c, 16), max(b, 0):min(e, 16)] = True
    return bool(grid.all())


class Resources:
    def __init__(self, stack):
        self.stack = stack
        self._states: dict = {}
        self._models: dict = {}
        self._textures: dict = {}
        self._shapes: dict = {}

    def blockstate(self, name: str) -> BlockState | None:
        name = models.canon(name)
        if name not in self._states:
            j = models.load_json(self.stack, models.location(name, "blockstates", ".json"),
                                 f"blockstate {name}")
            self._states[name] = None if j is None else BlockState(name, j)
        return self._states[name]

    def model(self, ref: str):
        ref = models.canon(ref)
        if ref not in self._models:
            self._models[ref] = models.load(self.stack, ref)
        return self._models[ref]

    def texture(self, tid: str | None) -> Texture | None:
        if tid is None:
            return None
        if tid not in self._textures:
            name = models.location(tid, "textures", ".png")
            data = self.stack.read(name)
            tex = None
            if data is not None:
                rgba = png.decode(data, name)
                meta = self.stack.read(name + ".mcmeta")
                if meta is not None:
                    try:
                        rgba = first_frame(rgba, json.loads(meta.decode("utf-8-sig")))
                    except (UnicodeDecodeError, json.JSONDecodeError):
                        raise VoxelError(f"{name}.mcmeta: bad JSON") from None
                tex = Texture(tid, np.ascontiguousarray(rgba), _layer(rgba))
            self._textures[tid] = tex
        return self._textures[tid]

    def shape(self, name: str, props: dict | None = None, pos=(0, 0, 0)) -> Shape | None:
        """The quads of block NAME with PROPS at POS (Minecraft's frame, for weighted
        variants); None when the stack has no blockstate for it (the caller falls back
        to the project's own look)."""
        bs = self.blockstate(name)
        if bs is None:
            return None
        chosen = bs.choose(props or {}, pos)
        key = tuple((o["model"], o["x"], o["y"], o["uvlock"]) for o in chosen)
        if key not in self._shapes:
            self._shapes[key] = self._build(chosen)
        return self._shapes[key]

    def _build(self, chosen) -> Shape:
        shape = Shape()
        for o in chosen:
            m = self.model(o["model"])
            if m is None:
                continue
            shape.ao = shape.ao and m.ao
            mat = geometry.variant_matrix(o["x"], o["y"])
            for el in m.elements:
                for d, pts, uvs, face, cull in geometry.element_quads(el, mat, o["uvlock"]):
                    tex = self.texture(face["sprite"])
                    layer = tex.layer if tex else SOLID
                    shape.quads.append(Quad(
                        geometry.to_voxel(pts).astype(np.float32), (uvs / 16).astype(np.float32),
                        face["sprite"], geometry.FACE[d],
                        geometry.FACE[cull] if cull else -1, face["tintindex"], el["shade"], layer))
                if self._full(el) and all(
                        (t := self.texture(f["sprite"])) is None or t.layer == SOLID
                        for f in el["faces"].values()):
                    shape.full = True     # overlays around it (grass sides) do not matter
        _lift_overlays(shape.quads)
        if shape.quads:
            shape.layer = max((q.layer for q in shape.quads), key=_ORDER.get)
        shape.faces = tuple(shape.full or _covers(shape.quads, d) for d in range(6))
        return shape

    def _full(self, el) -> bool:
        return (el["from"] == [0, 0, 0] and el["to"] == [16, 16, 16] and not el.get("rotation")
                and len(el["faces"]) == 6)

    def close(self):
        self.stack.close()
