"""Minecraft model quads of the chunks a batch meshes (issue 30 d), for the live view:
with the world's resource stack (meta `mc_resources`, storage/minecraft.py) every
voxel whose kept state the stack knows becomes its model's quads (mcres.mesh) and
air for the greedy mesher (its light was solved with it); each chunk's mesh carries
its quads and their sprites (`ChunkMesh.models`). No stack, or one whose files are
gone: None, today's look. The stack is read once per world."""
from __future__ import annotations

import threading
import weakref
from typing import NamedTuple

import numpy as np

from ..core import chunk as C
from ..core.blocks import REGISTRY

_STACKS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
_LOCK = threading.Lock()


class ChunkModels(NamedTuple):
    """A chunk's model quads (mcres.mesh.Mesh, world voxels) and {sprite id: (h, w, 4)
    uint8 RGBA, top row first} of the sprites its `sprites` names."""
    mesh: object
    images: dict


def stack(world):
    """(Resources, palette, colour states, y_min, biome names, default states) of the
    world, or None."""
    with _LOCK:
        if world in _STACKS:
            return _STACKS[world]
        from ..storage import minecraft as mcfile
        got = None
        try:
            kept = mcfile.kept(world.file.meta)
        except ValueError:
            kept = None
        if kept is not None:
            from ..core.errors import VoxelError
            from ..mcres import Resources, Stack
            paths, palette, cstates, y_min, dflt = kept
            try:
                got = (Resources(Stack.open(paths)), palette, cstates, y_min,
                       mcfile.names(world.file.meta) or ["minecraft:plains"], dflt)
            except VoxelError:
                got = None   # files gone: today's look (the bake says so, the view draws it)
        _STACKS[world] = got
        return got


def build(world, blocks: np.ndarray, data, cx0: int, cy0: int) -> dict:
    """{key: ChunkModels} of the chunks of BLOCKS ((16w + 2, 16h + 2, 256): chunks from
    (cx0, cy0) and a one-voxel ring) and the voxels they draw set to air in BLOCKS;
    {} without a stack."""
    st = stack(world)
    if st is None or (data is None and st[5] is None):   # no data, no defaults: no states
        return {}
    from ..mcres import mesh as M
    from ..storage import minecraft as mcfile
    res, palette, cstates, y_min, names, dflt = st
    x0, y0 = cx0 * C.SIZE - 1, cy0 * C.SIZE - 1
    W, H = blocks.shape[:2]
    state = mcfile.states(blocks, data, palette, cstates, REGISTRY.id("color"), dflt)
    if not state.any():
        return {}
    biomes = mcfile.region(world.file, x0, y0, x0 + W, y0 + H, len(names))
    opaque = (REGISTRY.shape[blocks] == 1) & (REGISTRY.render[blocks] == 1)
    m = M.build(res, palette, state, opaque, origin=(x0, y0, 0), y_min=y_min,
                biomes=biomes, biome_names=names, cols=(1, 1, W - 1, H - 1))
    blocks[m.drawn] = 0
    out = {}
    if not m.quads:
        return out
    ck = (m.voxel[:, :2] - 1) // C.SIZE          # the chunk (from cx0, cy0) of each quad
    inside = (m.voxel[:, 0] > 0) & (m.voxel[:, 1] > 0) & (m.voxel[:, 0] < W - 1) \
        & (m.voxel[:, 1] < H - 1)
    for i, j in {(int(a), int(b)) for a, b in ck[inside]}:
        sub = m.subset(inside & (ck[:, 0] == i) & (ck[:, 1] == j))
        used = sorted(set(sub.sprite.tolist()) - {-1})
        sprites = [m.sprites[u] for u in used]
        remap = np.full(len(m.sprites) + 1, -1, np.int32)
        remap[used] = np.arange(len(used))
        sub.sprite = remap[sub.sprite]
        sub.sprites = sprites
        images = {}
        for sid in sprites:
            t = res.texture(sid)
            images[sid] = t.rgba if t is not None else np.full((16, 16, 4), 255, np.uint8)
        out[(cx0 + i, cy0 + j)] = ChunkModels(sub, images)
    return out


class Sight:
    """What the light solve sees through in a world with a resource stack: a model
    block that is no whole cube (mcres.mesh.light_blocks). Per state a table filled as
    states turn up, so a window costs a few array lookups (an edit's relight)."""

    def __init__(self, st):
        from ..mcres import mesh as M
        self.st = st
        n = len(st[1])
        self.opens = np.zeros(n, bool)
        self.known = np.zeros(n, bool)
        self.known[0] = True
        self.dark = M.DARK

    def opened(self, blocks: np.ndarray, data) -> np.ndarray:
        """Bool mask of BLOCKS (DATA: their small data, None for all 0) the light
        passes although their project block holds it out."""
        from ..mcres import mesh as M
        from ..storage import minecraft as mcfile
        res, palette, cstates, _, _, dflt = self.st
        cand = self.dark[blocks]
        if not cand.any():
            return cand
        state = mcfile.states(blocks[cand], None if data is None else data[cand], palette,
                              cstates, REGISTRY.id("color"), dflt)
        new = ~self.known[state]
        if new.any():   # another thread may fill the same entry: the same value
            for i in np.unique(state[new]).tolist():
                self.opens[i] = M.opens(res, palette[i])
                self.known[i] = True
        cand[cand] = self.opens[state]
        return cand


_SIGHTS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def sight(world):
    """The world's Sight, or None without a stack (or states): light sees BLOCKS."""
    st = stack(world)
    if st is None:
        return None
    with _LOCK:
        got = _SIGHTS.get(world)
        if got is None or got.st is not st:
            got = _SIGHTS[world] = Sight(st)
        return got


def light_blocks(world, blocks: np.ndarray, data) -> np.ndarray:
    """BLOCKS as the light solve should see them with the world's resource stack
    (Sight: model blocks that are no whole cube pass light); BLOCKS itself without a
    stack or where nothing changes. The edit's incremental relight sees the same."""
    s = sight(world)
    if s is None or (data is None and s.st[5] is None):   # no data, no defaults: no states
        return blocks
    where = s.opened(blocks, data)
    if not where.any():
        return blocks
    out = blocks.copy(order="K")
    out[where] = 0
    return out
