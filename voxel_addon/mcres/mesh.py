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


def to_minecraft(vx, vy, vz, y_min: int) -> tuple[int, int, int]:
    """Voxel → Minecraft block position (formats/README's mapping, inverted)."""
    return int(vx), int(vz) + y_min, -1 - int(vy)


def build(res, palette: list, state: np.ndarray, opaque: np.ndarray, *, origin=(0, 0, 0),
          y_min: int = -64, biomes=None, biome_names=("minecraft:plains",)) -> Mesh:
    """STATE (W, H, D) indices into PALETTE (`minecraft:name[k=v,…]`, entry 0 unused);
    OPAQUE (W, H, D) bool: voxels of the project's own that hide a face; voxels
    outside the box hide nothing. ORIGIN: the box's [0, 0, 0] in world voxels (for
    positions and the variants' random). BIOMES (W, H) indices into BIOME_NAMES."""
    from .states import parse_key
    W, H, D = state.shape
    known = state > 0
    full_of = np.zeros(len(palette), bool)        # per state: a whole opaque cube
    side_of = np.zeros((len(palette), 6), bool)   # per state and side: covered whole
    shapes: dict = {}
    mixed = np.zeros(len(palette), bool)          # weighted or position-dependent
    block_of = np.full(len(palette), -1)          # per state: its block (name) number
    selfish = np.zeros(len(palette), bool)        # per state: hides faces against itself
    names: dict = {}
    for i in np.unique(state[known]).tolist():
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
    drawn = known & np.isin(state, list(shapes) or [-1])
    hides = (opaque & ~drawn) | (drawn & full_of[state])
    # a voxel with every neighbour hiding it draws nothing
    pad = np.pad(hides, 1)
    inner = np.ones_like(drawn)
    for dx, dy, dz in OFFSETS:
        inner &= pad[1 + dx:1 + dx + W, 1 + dy:1 + dy + H, 1 + dz:1 + dz + D]
    todo = np.argwhere(drawn & ~(inner & hides))
    padstate = np.pad(state, 1)
    padrawn = np.pad(drawn, 1)
    sprites, sprite_ix = [], {}
    out = {k: [] for k in ("pos", "uv", "nrm", "sprite", "tint", "layer", "shade", "voxel")}
    ox, oy, oz = origin
    for v in todo:
        x, y, z = (int(c) for c in v)
        s = int(state[x, y, z])
        name, props, sh = shapes[s]
        if mixed[s]:
            sh = res.shape(name, props, to_minecraft(ox + x, oy + y, oz + z, y_min))
        biome = biome_names[int(biomes[x, y])] if biomes is not None else biome_names[0]
        colour = None
        for q in sh.quads:
            if q.cull >= 0:
                dx, dy, dz = OFFSETS[q.cull]
                if pad[1 + x + dx, 1 + y + dy, 1 + z + dz]:
                    continue
                ns = padstate[1 + x + dx, 1 + y + dy, 1 + z + dz]
                if padrawn[1 + x + dx, 1 + y + dy, 1 + z + dz] and side_of[ns, q.cull ^ 1]:
                    continue      # the neighbour's model covers the face toward us
                if selfish[s] and ns and block_of[ns] == block_of[s]:
                    continue      # glass against glass, a pane's arm against the next pane
            if q.sprite not in sprite_ix:
                sprite_ix[q.sprite] = len(sprites) if q.sprite is not None else -1
                if q.sprite is not None:
                    sprites.append(q.sprite)
            if q.tint >= 0 and colour is None:
                colour = tints.colour(res, name, props, biome) or (255, 255, 255)
            out["pos"].append(q.pos + (x, y, z))
            out["uv"].append(q.uv)
            n = np.cross(q.pos[1] - q.pos[0], q.pos[2] - q.pos[0])
            n = n / (np.linalg.norm(n) or 1.0)
            out["nrm"].append(np.repeat(n[None], 4, 0))
            out["sprite"].append(sprite_ix[q.sprite])
            out["tint"].append(colour if q.tint >= 0 else (255, 255, 255))
            out["layer"].append(LAYERS.index(q.layer))
            out["shade"].append(q.shade)
            out["voxel"].append((x, y, z))
    n = len(out["sprite"])
    cat = (lambda k, shape, dt: np.concatenate(out[k]).astype(dt) if n
           else np.zeros(shape, dt))
    return Mesh(cat("pos", (0, 3), np.float32) + np.asarray(origin, np.float32),
                cat("uv", (0, 2), np.float32), cat("nrm", (0, 3), np.float32),
                np.array(out["sprite"], np.int32), np.array(out["tint"], np.uint8).reshape(-1, 3),
                np.array(out["layer"], np.uint8), np.array(out["shade"], bool),
                np.array(out["voxel"], np.int32).reshape(-1, 3), sprites, drawn)


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
    for i in np.unique(state[known]).tolist():
        op[i] = opens(res, palette[i])
    where = op[state] & DARK[blocks]
    if not where.any():
        return blocks
    out = blocks.copy(order="K")
    out[where] = 0
    return out
