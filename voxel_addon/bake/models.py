"""Minecraft model blocks in a bake (issue 30): with the world's resource stack (meta
`mc_resources`, storage/minecraft.py) every voxel whose kept state the stack knows is
baked from its model (mcres.mesh) with the stack's textures, and left out of the
greedy path; everything else keeps today's look, voxel by voxel. A stack whose files
are gone bakes today's look (said in `Models.note`).

Model quads go to one Part per bake, lit per vertex (sampled like the greedy parts),
with one material per (texture, layer, tint): `MaterialSpec.image` names the sprite,
`Bake.images` holds its pixels; layers map to the render modes (solid → opaque,
cutout → alpha_test, translucent → blend).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core import chunk as C
from ..core.blocks import REGISTRY
from ..core.errors import VoxelError

RENDER = {"solid": "opaque", "cutout": "alpha_test", "translucent": "blend"}
COLOR = REGISTRY.id("color")


@dataclass
class Models:
    res: object                 # mcres.Resources
    palette: list               # state strings
    state: np.ndarray           # (W, H, 256) int32 state per voxel of the region
    biomes: np.ndarray | None   # (W, H) indices into biome_names
    biome_names: list
    y_min: int
    note: str = ""


def of_world(world, x0, y0, x1, y1, blocks, data) -> tuple[Models | None, str]:
    """The region's states, biomes and the stack, or (None, why not)."""
    from ..storage import minecraft as mcfile
    meta = world.file.meta
    try:
        got = mcfile.kept(meta)
    except ValueError:
        return None, "the world's Minecraft states (meta) are damaged: today's look"
    if got is None or (data is None and got[4] is None):   # no data, no defaults: no states
        return None, ""
    paths, palette, cstates, y_min, dflt = got
    from ..mcres import Resources, Stack
    try:
        res = Resources(Stack.open(paths))
    except VoxelError as e:
        return None, f"resource stack not read ({e}): today's look"
    state = mcfile.states(blocks, data, palette, cstates, COLOR, dflt)
    names = mcfile.names(meta) or ["minecraft:plains"]
    biomes = mcfile.region(world.file, x0, y0, x1, y1, len(names))
    return Models(res, palette, state, biomes, names, y_min), ""


def mesh(models: Models, blocks: np.ndarray, origin):
    """mcres.mesh.build over the region (blocks: the region's registry ids)."""
    from ..mcres import mesh as M
    opaque = (REGISTRY.shape[blocks] == 1) & (REGISTRY.render[blocks] == 1)
    return M.build(models.res, models.palette, models.state, opaque, origin=origin,
                   y_min=models.y_min, biomes=models.biomes, biome_names=models.biome_names)


def light_blocks(models: Models, blocks: np.ndarray) -> np.ndarray:
    """The region's blocks as the light solve sees them (mcres.mesh.light_blocks)."""
    from ..mcres import mesh as M
    return M.light_blocks(models.res, models.palette, models.state, blocks)


def part_and_materials(m, res, blocks, origin, light, offset, specs: list, images: dict):
    """(Part, specs grown) of a model mesh M: materials keyed by (sprite, layer, tint)."""
    from . import Part, MaterialSpec
    from ..light import sample
    from ..mcres.mesh import LAYERS
    base = REGISTRY.texture_names[int(REGISTRY.face_texture[REGISTRY.id("stone"), 0])]
    index = {}
    mat = np.empty(m.quads, np.int32)
    for i in range(m.quads):
        sp = int(m.sprite[i])
        key = (sp, int(m.layer[i]), tuple(int(c) for c in m.tint[i]))
        j = index.get(key)
        if j is None:
            sprite = m.sprites[sp] if sp >= 0 else None
            tex = res.texture(sprite) if sprite else None
            ns, _, path = (sprite or "minecraft:missing").rpartition(":")
            short = ("" if ns == "minecraft" else f"{ns}_") + \
                path.removeprefix("block/").replace("/", "_")   # unique: names key materials
            tint = None if key[2] == (255, 255, 255) else tuple(c / 255 for c in key[2])
            name = f"mc_{short}_{LAYERS[key[1]]}" + ("" if tint is None else "_%02x%02x%02x" % key[2])
            if tex is not None:
                images[sprite] = tex.rgba
            j = index[key] = len(specs)
            specs.append(MaterialSpec(name, base, 0, RENDER[LAYERS[key[1]]], 0.0, False, tint,
                                      image=sprite if tex is not None else None, per_vertex=True))
        mat[i] = j
    local = m.positions - np.asarray(origin, np.float32)
    nrm = m.normals.copy()
    flat = np.repeat(~m.shade, 4)     # unshaded quads (crosses): their voxel's own light,
    if flat.any():                    # as the greedy path lights plants
        local[flat] = np.repeat(m.voxel.astype(np.float32) + 0.5, 4, axis=0)[flat]
        nrm[flat] = 0
    s = sample(light, local + np.asarray(offset, np.float32), nrm)
    vx = m.voxel
    n = m.normals[::4]
    axis = np.argmax(np.abs(n), axis=1)      # the nearest cube face (core.blocks.FACES)
    face = axis * 2 + (n[np.arange(m.quads), axis] > 0)
    uvs = m.uvs.astype(np.float32)
    uvs[:, 1] = 1.0 - uvs[:, 1]      # Minecraft's v runs down the texture, Blender's up
    return Part(f"minecraft_{origin[0]}_{origin[1]}", m.positions.astype(np.float32),
                m.normals.astype(np.float32), uvs,
                np.ascontiguousarray(s[:, :3]), np.ascontiguousarray(s[:, 3]), mat,
                blocks[vx[:, 0], vx[:, 1], vx[:, 2]].astype(np.uint16), face.astype(np.uint8))
