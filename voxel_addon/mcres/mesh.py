"""Voxels with Minecraft states → model quads for the bake and the drawing.

`build` takes a box of voxels: each voxel's state index (0: none, drawn the project's
way), the state palette, which other voxels are opaque cubes, the box's biomes. Every
voxel whose state the stack knows gets its shape's quads; a quad with a cullface is
dropped when the neighbour there is a whole opaque cube (a full shape, or an opaque
voxel of the project's own), a model whose opaque quads cover that side whole (a
stair's bottom hides the top of the block below) or the same see-through block in
any state when the game's code says so (`hides_itself`: glass beside glass, a pane's
arm against the pane it joins; HalfTransparentBlock and IronBarsBlock skip those
faces, leaves draw theirs).
A state whose model has no elements (the game draws chests, beds, signs and water
by code) keeps today's look. Voxels inside (all six neighbours whole) are skipped before any shape is looked at,
so a stone hill costs its surface only. Weighted variants are drawn by each voxel's
Minecraft position (`to_minecraft`), as the game draws them.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.blocks import REGISTRY
from . import tints
from .pack import SOLID, CUTOUT, TRANSLUCENT

LAYERS = (SOLID, CUTOUT, TRANSLUCENT)
# project blocks that hold light out and make none: a model block stored as one of
# them may pass light instead (light_blocks)
DARK = REGISTRY.light_opaque & (REGISTRY.emission.max(axis=1) == 0)
# project face index → voxel offset (core.blocks.FACES: -x +x -y +y -z +z)
OFFSETS = np.array([(-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0), (0, 0, -1), (0, 0, 1)])


@dataclass
class Mesh:
    positions: np.ndarray   # (4N, 3) float32, voxel units of the box's frame + origin
    uvs: np.ndarray         # (4N, 2) float32, 0..1 over the sprite (v down)
    normals: np.ndarray     # (4N, 3) float32
    sprite: np.ndarray      # (N,) int32 index into `sprites` (-1: the pack leaves it unset)
    tint: np.ndarray        # (N, 3) uint8, white when untinted
    layer: np.ndarray       # (N,) uint8 index into LAYERS
    shade: np.ndarray       # (N,) bool
    voxel: np.ndarray       # (N, 3) int32 the voxel each quad belongs to (box frame)
    sprites: list           # texture ids
    drawn: np.ndarray       # (W, H, D) bool: voxels drawn here (leave them out elsewhere)

    @property
    def quads(self) -> int:
        return len(self.sprite)

    def subset(self, keep: np.ndarray) -> "Mesh":
        """The quads where KEEP (N,) is true."""
        v4 = np.repeat(keep, 4)
        return Mesh(self.positions[v4], self.uvs[v4], self.normals[v4], self.sprite[keep],
                    self.tint[keep], self.layer[keep], self.shade[keep], self.voxel[keep],
                    self.sprites, self.drawn)


def hides_itself(name: str) -> bool:
    """Whether the game drops a face of block NAME against the same block: glass
    (stained, tinted), ice, slime, honey, copper grates (HalfTransparentBlock),
    panes and iron bars (IronBarsBlock), powder snow and mangrove roots
    (`skipRendering`). Leaves do not (fancy graphics draws their inner faces, so a
    tree shows leaves inside, not the floor through the holes), nor does a block the
    game's code does not name (a mod's own: the default draws them)."""
    n = name.rpartition(":")[2]
    return (n.endswith(("glass", "glass_pane", "copper_grate")) or n == "ice"
            or n.endswith("_ice") or n in ("iron_bars", "slime_block", "honey_block",
                                           "powder_snow", "mangrove_roots"))


def _present(state: np.ndarray, n: int) -> np.ndarray:
    """The states other than 0 found in STATE (indices below N), ascending."""
    return np.flatnonzero(np.bincount(state.reshape(-1), minlength=n)[1:]) + 1


def to_minecraft(vx, vy, vz, y_min: int) -> tuple[int, int, int]:
    """Voxel → Minecraft block position (formats/README's mapping, inverted)."""
    return int(vx), int(vz) + y_min, -1 - int(vy)


def build(res, palette: list, state: np.ndarray, opaque: np.ndarray, *, origin=(0, 0, 0),
          y_min: int = -64, biomes=None, biome_names=("minecraft:plains",),
          cols=None) -> Mesh:
    """STATE (W, H, D) indices into PALETTE (`minecraft:name[k=v,…]`, entry 0 unused);
    OPAQUE (W, H, D) bool: voxels of the project's own that hide a face; voxels
    outside the box hide nothing. ORIGIN: the box's [0, 0, 0] in world voxels (for
    positions and the variants' random). BIOMES (W, H) indices into BIOME_NAMES.
    COLS (x0, y0, x1, y1): only voxels in those columns get quads (the others only
    hide faces: a chunk's ring), the quads all-columns would give there, in order."""
    from .states import parse_key
    W, H, D = state.shape
    full_of = np.zeros(len(palette), bool)        # per state: a whole opaque cube
    side_of = np.zeros((len(palette), 6), bool)   # per state and side: covered whole
    shapes: dict = {}
    mixed = np.zeros(len(palette), bool)          # weighted or position-dependent
    block_of = np.full(len(palette), -1)          # per state: its block (name) number
    selfish = np.zeros(len(palette), bool)        # per state: hides faces against itself
    names: dict = {}
    for i in _present(state, len(palette)).tolist():
        name, props = parse_key(palette[i])
        block_of[i] = names.setdefault(name, len(names))
        selfish[i] = hides_itself(name)
        bs = res.blockstate(name)
        if bs is None:
            continue
        sh = res.shape(name, props)
        if not sh.quads:      # drawn by code in the game (chests, beds, water): today's look
            continue
        shapes[i] = (name, props, sh)
        full_of[i] = sh.full
        side_of[i] = sh.faces
        opts = bs.variants if bs.variants is not None else bs.parts
        mixed[i] = any(len(o) > 1 for _, o in opts)
    draws = np.zeros(len(palette), bool)
    draws[list(shapes)] = True
    drawn = draws[state]
    hides = (opaque & ~drawn) | full_of[state]
    # a voxel with every neighbour hiding it draws nothing
    pad = np.pad(hides, 1)
    inner = np.ones_like(drawn)
    for dx, dy, dz in OFFSETS:
        inner &= pad[1 + dx:1 + dx + W, 1 + dy:1 + dy + H, 1 + dz:1 + dz + D]
    shown = drawn & ~(inner & hides)
    if cols is None:
        todo = np.argwhere(shown)
    else:
        x0, y0, x1, y1 = cols
        todo = np.argwhere(shown[x0:x1, y0:y1]) + np.array([x0, y0, 0])
    padstate = np.pad(state, 1)
    padrawn = np.pad(drawn, 1)
    st = state[tuple(todo.T)]
    # each distinct shape's quads once, as rows of arrays (most voxels share few shapes)
    rows = _Rows()
    sid = np.zeros(len(todo), np.int64)
    for s in np.unique(st).tolist():
        at = np.flatnonzero(st == s)
        name, props, sh = shapes[s]
        if not mixed[s]:
            sid[at] = rows.add(sh)
            continue
        v = todo[at] + np.asarray(origin, np.int64)
        mc = np.stack([v[:, 0], v[:, 2] + y_min, -1 - v[:, 1]], axis=1)   # to_minecraft
        pick = res.blockstate(name).picks(props, mc)
        if pick is None:      # multipart: drawn voxel by voxel
            for k, p in zip(at.tolist(), mc.tolist()):
                sid[k] = rows.add(res.shape(name, props, tuple(p)))
            continue
        # one shape per drawn option, asked for at a voxel that draws it
        u, rep, inv = np.unique(pick, return_index=True, return_inverse=True)
        ks = [rows.add(res.shape(name, props, tuple(mc[r].tolist()))) for r in rep.tolist()]
        sid[at] = np.array(ks, np.int64)[inv.reshape(-1)]
    # per voxel and side: whether a quad culled there is dropped
    nb = todo[:, None, :] + 1 + OFFSETS[None]
    at = (nb[..., 0], nb[..., 1], nb[..., 2])
    ns = padstate[at]
    hid = pad[at] | (padrawn[at] & side_of[ns, np.arange(6) ^ 1])   # the neighbour's model
    hid |= (selfish[st][:, None] & (ns != 0)                         # covers the face; glass
            & (block_of[ns] == block_of[st][:, None]))             # against glass
    # every voxel's candidate quads, voxel by voxel in its shape's order, as before
    R = rows.arrays()
    cnt = R["count"][sid]
    vi = np.repeat(np.arange(len(todo)), cnt)
    first = np.cumsum(cnt) - cnt
    qr = np.repeat(R["start"][sid] - first, cnt) + np.arange(len(vi))
    cull = R["cull"][qr]
    keep = (cull < 0) | ~hid[vi, np.maximum(cull, 0)]
    vi, qr = vi[keep], qr[keep]
    # sprites numbered in the order the quads first use them
    sg = R["sprite"][qr]
    used = sg[sg >= 0]
    u, firsts = np.unique(used, return_index=True)
    u = u[np.argsort(firsts)]
    remap = np.full(len(rows.sprites) + 1, -1, np.int32)
    remap[u] = np.arange(len(u))
    sprites = [rows.sprites[i] for i in u.tolist()]
    # tints: one colour per (state, biome) among the tinted quads
    tint = np.full((len(qr), 3), 255, np.uint8)
    tinted = np.flatnonzero(R["tint"][qr])
    if len(tinted):
        vox = todo[vi[tinted]]
        bix = biomes[vox[:, 0], vox[:, 1]].astype(np.int64) if biomes is not None \
            else np.zeros(len(vox), np.int64)
        key = st[vi[tinted]].astype(np.int64) * (int(bix.max()) + 1) + bix
        uk, inv = np.unique(key, return_inverse=True)
        cols = np.empty((len(uk), 3), np.uint8)
        for j, kk in enumerate(uk.tolist()):
            s, b = divmod(kk, int(bix.max()) + 1)
            name, props, _ = shapes[s]
            cols[j] = tints.colour(res, name, props, biome_names[b]) or (255, 255, 255)
        tint[tinted] = cols[inv.reshape(-1)]
    voxel = todo[vi].astype(np.int32).reshape(-1, 3)
    pos = (R["pos"][qr] + voxel.astype(np.float32)[:, None, :]).reshape(-1, 3)
    return Mesh(pos + np.asarray(origin, np.float32), R["uv"][qr].reshape(-1, 2),
                np.repeat(R["nrm"][qr], 4, axis=0).reshape(-1, 3), remap[sg],
                tint, R["layer"][qr], R["shade"][qr], voxel, sprites, drawn)


def _normal(p) -> np.ndarray:
    n = np.cross(p[1] - p[0], p[2] - p[0])
    return n / (np.linalg.norm(n) or 1.0)


def _arrays(sh) -> dict:
    """A shape's quads as arrays, made once per shape (`Resources` caches shapes)."""
    if sh.arrays is None:
        qs = sh.quads
        sh.arrays = {
            "pos": np.array([q.pos for q in qs], np.float32).reshape(-1, 4, 3),
            "nrm": np.array([_normal(q.pos) for q in qs], np.float32).reshape(-1, 3),
            "uv": np.array([q.uv for q in qs], np.float32).reshape(-1, 4, 2),
            "sprite": [q.sprite for q in qs],
            "cull": np.array([q.cull for q in qs], np.int64),
            "tint": np.array([q.tint >= 0 for q in qs], bool),
            "layer": np.array([LAYERS.index(q.layer) for q in qs], np.uint8),
            "shade": np.array([q.shade for q in qs], bool)}
    return sh.arrays


class _Rows:
    """The quads of the distinct shapes of one `build` as rows of arrays, each shape
    (by identity) added once."""

    def __init__(self):
        self.ix: dict = {}
        self.sprites: list = []
        self.start, self.count = [], []
        self.shapes: list = []    # held: ids stay unique

    def add(self, sh) -> int:
        k = self.ix.get(id(sh))
        if k is None:
            k = self.ix[id(sh)] = len(self.start)
            self.start.append(sum(self.count))
            self.count.append(len(sh.quads))
            self.shapes.append(sh)
        return k

    def arrays(self) -> dict:
        parts = [_arrays(sh) for sh in self.shapes]
        ids: dict = {}
        sprite = [-1 if t is None else ids.setdefault(t, len(ids))
                  for p in parts for t in p["sprite"]]
        self.sprites = list(ids)
        out = {"start": np.array(self.start, np.int64), "count": np.array(self.count, np.int64),
               "sprite": np.array(sprite, np.int64)}
        for k, shape, dt in (("pos", (0, 4, 3), np.float32), ("nrm", (0, 3), np.float32),
                             ("uv", (0, 4, 2), np.float32), ("cull", (0,), np.int64),
                             ("tint", (0,), bool), ("layer", (0,), np.uint8),
                             ("shade", (0,), bool)):
            out[k] = np.concatenate([p[k] for p in parts]) if parts else np.zeros(shape, dt)
        return out


def opens(res, key: str) -> bool:
    """Whether the light passes a voxel of state KEY: its model is no whole opaque
    cube (light_blocks; a state the stack does not draw keeps its project block)."""
    from .states import parse_key
    name, props = parse_key(key)
    if res.blockstate(name) is None:
        return False
    sh = res.shape(name, props)
    return bool(sh.quads) and not sh.full


def light_blocks(res, palette: list, state: np.ndarray, blocks: np.ndarray) -> np.ndarray:
    """BLOCKS for the light solve: a voxel drawn from a model that is no whole opaque
    cube (a rail, door, fence, slab, torch…) passes light, as the game's: its
    project block (a whole opaque cube for today's look, rails as planks) would leave
    the floor under a rail and the sides next to a door dark. Voxels whose project
    block emits or already passes light keep it. BLOCKS itself when nothing changes."""
    known = state > 0
    if not known.any():
        return blocks
    op = np.zeros(len(palette), bool)
    for i in _present(state, len(palette)).tolist():
        op[i] = opens(res, palette[i])
    where = op[state] & DARK[blocks]
    if not where.any():
        return blocks
    out = blocks.copy(order="K")
    out[where] = 0
    return out
