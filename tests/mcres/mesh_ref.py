"""The first, per-quad Python `mcres.mesh.build` (before it was batched per shape):
kept as the oracle the batched one must equal quad for quad."""
from __future__ import annotations

import numpy as np

from voxel_addon.mcres import tints
from voxel_addon.mcres.mesh import LAYERS, OFFSETS, Mesh, hides_itself, to_minecraft


def build(res, palette: list, state: np.ndarray, opaque: np.ndarray, *, origin=(0, 0, 0),
          y_min: int = -64, biomes=None, biome_names=("minecraft:plains",)) -> Mesh:
    """STATE (W, H, D) indices into PALETTE (`minecraft:name[k=v,…]`, entry 0 unused);
    OPAQUE (W, H, D) bool: voxels of the project's own that hide a face; voxels
    outside the box hide nothing. ORIGIN: the box's [0, 0, 0] in world voxels (for
    positions and the variants' random). BIOMES (W, H) indices into BIOME_NAMES."""
    from voxel_addon.mcres.states import parse_key
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
