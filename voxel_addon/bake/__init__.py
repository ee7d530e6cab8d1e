"""Bake a block region into Blender-independent mesh arrays + a materials spec (SPEC F10).

    bake_world(world, x0, y0, x1, y1, per="region"|"chunk"|"tile", method="greedy",
               instances=False, light="atlas"|"vertex", progress=None) -> Bake
    bake_blocks(blocks, origin=(x0, y0, 0), ...) -> Bake      # any (W, H, 256) array
    steps(blocks, origin, ...) -> generator of (stage, fraction) returning the Bake

The region is half-open in block coordinates, full height; voxels outside it count
as air, so the baked solid is closed. Light is solved for exactly that island (a ring
of open air around it), so the bake depends only on the region's blocks.

Each `Part` (one per region, chunk or tile) holds quads: 4 vertices each,
counter-clockwise from the front; `uvs` are in voxel units (tile with REPEAT);
`light` (4N, 3) block RGB light and `daylight` (4N,) in 0..1, sampled per vertex.
light="atlas" (default) keeps merged quads whole and puts the light in
`Bake.atlas` (bake.atlas: one texel per unit-grid corner, read through `Part.uv2`);
light="vertex" splits merged quads whose light is not constant into unit quads
(bake.light) so the per-vertex light alone is exact, for tools without a second
UV set. `Bake.materials` lists one `MaterialSpec` per (texture, render mode, glow,
sidedness); quads index it through `Part.material`. With instances=True, X/#
plants are left out of the parts and listed in `Bake.plants` (block name -> (n, 3)
voxel positions) for instancing.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core import chunk as C
from ..core.blocks import REGISTRY
from ..core.errors import VoxelError
from . import atlas as A, light as L

PAD = 16  # air ring around the region for the light solve (any >= 1 keeps it closed)


@dataclass(frozen=True)
class MaterialSpec:
    name: str           # unique, e.g. "grass_top" or "leaves"
    texture: str        # REGISTRY.texture_names entry (textures.image(texture))
    layer: int
    render: str         # "opaque" | "alpha_test" | "blend"
    glow: float         # emission strength (block's glow); texture glow mask says where
    double_sided: bool
    tint: tuple | None = None  # sRGB 0..1 the texture is multiplied by (the `color` block)
    image: str | None = None   # a Minecraft sprite (Bake.images) instead of `texture` (models.py)
    per_vertex: bool = False   # light from colour attributes even in an atlas bake (models.py)


@dataclass
class Part:
    name: str
    positions: np.ndarray   # (4N, 3) float32 world coordinates
    normals: np.ndarray     # (4N, 3) float32
    uvs: np.ndarray         # (4N, 2) float32, voxel units
    light: np.ndarray       # (4N, 3) float32 0..1 block RGB light
    daylight: np.ndarray    # (4N,) float32 0..1
    material: np.ndarray    # (N,) int32 index into Bake.materials
    block: np.ndarray       # (N,) uint16
    face: np.ndarray        # (N,) uint8 meshing face code
    uv2: np.ndarray | None = None  # (4N, 2) light-atlas UVs (light="atlas")

    @property
    def quads(self) -> int:
        return len(self.material)

    def triangles(self) -> np.ndarray:
        from ..meshing import quad_indices
        return quad_indices(self.quads, np.int32).reshape(-1, 3)


@dataclass
class Bake:
    region: tuple[int, int, int, int]
    parts: list[Part]
    materials: list[MaterialSpec]
    plants: dict[str, np.ndarray] = field(default_factory=dict)
    atlas: np.ndarray | None = None   # (AH, AW, 4) float32 light atlas (bake.atlas), or None
    atlas_face: np.ndarray | None = None  # (AH, AW) uint8 face code per texel
    images: dict = field(default_factory=dict)  # sprite id -> (h, w, 4) uint8 (models.py)
    note: str = ""      # why a world's resource stack was not used, or ""

    @property
    def light(self) -> str:
        return "vertex" if self.atlas is None else "atlas"

    @property
    def triangles(self) -> int:
        return sum(2 * p.quads for p in self.parts)


def check_region(x0, y0, x1, y1, limit: int = 4096) -> tuple[int, int, int, int]:
    x0, y0, x1, y1 = map(int, (x0, y0, x1, y1))
    if x1 <= x0 or y1 <= y0:
        raise VoxelError(f"empty region [{x0},{x1})x[{y0},{y1}): need X0 < X1 and Y0 < Y1")
    if (x1 - x0) * (y1 - y0) > limit * limit:
        raise VoxelError(f"region {x1 - x0}x{y1 - y0} is too large to bake at once")
    return x0, y0, x1, y1


def region_of(world, x0, y0, x1, y1) -> np.ndarray:
    """(X1-X0, Y1-Y0, 256) blocks of the region from a world.World."""
    cx0, cy0, cx1, cy1 = x0 >> 4, y0 >> 4, ((x1 - 1) >> 4) + 1, ((y1 - 1) >> 4) + 1
    b = world.region_blocks(cx0, cy0, cx1, cy1)
    ox, oy = x0 - cx0 * C.SIZE, y0 - cy0 * C.SIZE
    return np.asfortranarray(b[ox:ox + x1 - x0, oy:oy + y1 - y0])


def colors_of(world, x0, y0, x1, y1):
    """(small data of the region or None, the world's palette): what `color` voxels
    need (their colour is their data)."""
    from ..core import colors
    cx0, cy0, cx1, cy1 = x0 >> 4, y0 >> 4, ((x1 - 1) >> 4) + 1, ((y1 - 1) >> 4) + 1
    got = world.load([(cx, cy) for cy in range(cy0, cy1) for cx in range(cx0, cx1)])
    pieces = [(k, c.data) for k, c in got.items() if c.data is not None]
    if not pieces:
        return None, None
    d = C.paste(pieces, cx0, cy0, cx1, cy1)
    ox, oy = x0 - cx0 * C.SIZE, y0 - cy0 * C.SIZE
    return np.asfortranarray(d[ox:ox + x1 - x0, oy:oy + y1 - y0]), colors.parse(world.file.meta)


def inputs(world, x0, y0, x1, y1, blocks) -> tuple[dict, str]:
    """What steps() needs of a world beside the region's blocks: the small data and
    palette (`color` voxels), the Minecraft models (bake.models), and a note (why a
    world's resource stack was not used, or "")."""
    from . import models as MD
    data, palette = colors_of(world, x0, y0, x1, y1)
    models, note = MD.of_world(world, x0, y0, x1, y1, blocks, data)
    return dict(data=data, palette=palette, models=models), note


def bake_world(world, x0, y0, x1, y1, **kw) -> Bake:
    x0, y0, x1, y1 = check_region(x0, y0, x1, y1)
    blocks = region_of(world, x0, y0, x1, y1)
    extra, note = inputs(world, x0, y0, x1, y1, blocks)
    bk = bake_blocks(blocks, origin=(x0, y0, 0), **extra, **kw)
    bk.note = note
    return bk


def _materials():
    """Material index per (block, face code) and the spec list."""
    specs: list[MaterialSpec] = []
    index: dict[tuple, int] = {}
    table = np.full((len(REGISTRY), 12), -1, np.int32)
    from ..meshing.mesh import SIDE  # X planes use the side texture
    codes = {"cube": range(6), "x": (6, 7), "hash": (4, 5, 8, 9, 10, 11)}
    for bid, b in enumerate(REGISTRY.blocks):
        if b.shape == "none":
            continue
        for code in codes[b.shape]:
            layer = int(REGISTRY.face_texture[bid, SIDE[code]])
            tex = REGISTRY.texture_names[layer]
            key = (tex, b.render, float(b.glow), b.double_sided)
            if key not in index:
                name = tex if not any(s.texture == tex for s in specs) else \
                    f"{tex}_{b.render}{'_2s' if b.double_sided else ''}{'_glow' if b.glow else ''}"
                index[key] = len(specs)
                specs.append(MaterialSpec(name, tex, layer, b.render, float(b.glow), b.double_sided))
            table[bid, code] = index[key]
    return table, specs


LIGHTS = ("atlas", "vertex")
COLOR = REGISTRY.id("color")


def _tints(table, specs, quad_lists, palette):
    """(table, specs + one spec per colour of `color` quads, {palette index: spec})."""
    used = sorted({int(c) for q in quad_lists for c in np.unique(q["color"][q["block"] == COLOR])})
    if not used:
        return table, specs, {}
    pal = np.array([[255, 255, 255]], np.uint8) if palette is None else np.asarray(palette)
    base = specs[int(table[COLOR, 5])]
    out, tinted = list(specs), {}
    for c in used:
        rgb = pal[min(c, len(pal) - 1)]
        tinted[c] = len(out)
        out.append(MaterialSpec("color_%02x%02x%02x" % tuple(int(v) for v in rgb), base.texture,
                                base.layer, base.render, base.glow, base.double_sided,
                                tuple(float(v) / 255 for v in rgb)))
    # two palette entries of one colour share a material
    names = {}
    for c, i in list(tinted.items()):
        tinted[c] = names.setdefault(out[i].name, i)
    keep = sorted(set(tinted.values()))
    if len(keep) < len(used):
        remap = {old: len(specs) + k for k, old in enumerate(keep)}
        out = list(specs) + [out[i] for i in keep]
        tinted = {c: remap[i] for c, i in tinted.items()}
    return table, out, tinted


def bake_blocks(blocks: np.ndarray, origin=(0, 0, 0), **kw) -> Bake:
    """The whole bake at once (steps() run to the end)."""
    return run(steps(blocks, origin, **kw))


def run(gen):
    """Drive a steps() generator to its end and return its Bake."""
    while True:
        try:
            next(gen)
        except StopIteration as stop:
            return stop.value


def steps(blocks: np.ndarray, origin=(0, 0, 0), *, per: str = "region", method: str = "greedy",
          instances: bool = False, light: str = "atlas", backend: str | None = None,
          progress=None, tile: int = 64, data=None, palette=None, models=None,
          window=None):
    """The bake as a generator of short steps (yields (stage, fraction)) that returns
    the Bake: a modal operator runs one step per timer tick and can stop in between.
    per "tile" cuts the region into `tile`×`tile` objects. `data` (the region's small
    data) and `palette` ((n, 3) uint8, core.colors): `color` voxels get one material
    per colour (the texture tinted), so a .vox keeps its colours in Blender and glTF.
    `models` (bake.models.Models): Minecraft voxels the resource stack knows are baked
    from their models into a Part of their own and left out of the greedy path.
    `window` (x, y, w, h) in `blocks`: only that part becomes objects (and plants),
    the rest is context (its light and faces; bake.tiles: one tile of a big region)."""
    from .. import meshing
    if per not in ("region", "chunk", "tile"):
        raise VoxelError(f"per must be 'region', 'chunk' or 'tile', not {per!r}")
    if method not in meshing.METHODS:
        raise VoxelError(f"unknown meshing method {method!r} (known: {', '.join(meshing.METHODS)})")
    if light not in LIGHTS:
        raise VoxelError(f"light must be 'atlas' or 'vertex', not {light!r}")
    blocks = np.asarray(blocks, np.uint16)
    if blocks.ndim != 3 or blocks.shape[2] != C.HEIGHT:
        raise VoxelError(f"blocks must be (W, H, {C.HEIGHT}), got {blocks.shape}")
    W, H = blocks.shape[:2]
    ox, oy, oz = map(int, origin)
    say = progress or (lambda *_: None)

    def stage(name, frac):
        say(name, frac)
        return name, frac

    padded = C.empty(np.uint16, W + 2 * PAD, H + 2 * PAD)
    padded[PAD:PAD + W, PAD:PAD + H] = blocks
    lit = None
    seen = padded
    if models is not None:     # model blocks that are no whole cube pass light
        from . import models as MD
        seen = padded.copy(order="F")
        seen[PAD:PAD + W, PAD:PAD + H] = MD.light_blocks(models, blocks)
    for lit, frac in light_tiles(seen, backend):
        yield stage("light", frac)
    mat_table, specs = _materials()
    shape_ids = np.flatnonzero(REGISTRY.shape >= 2)  # x and hash

    mm = None
    if models is not None:
        from . import models as MD
        yield stage("models", 0.0)
        mm = MD.mesh(models, blocks, (ox, oy, oz))
        if mm.drawn.any():       # the greedy path leaves them out (light keeps them)
            padded = padded.copy(order="F")
            padded[PAD:PAD + W, PAD:PAD + H][mm.drawn] = 0
    ring = padded[PAD - 1:PAD + W + 1, PAD - 1:PAD + H + 1]  # region + 1-voxel air ring
    dring = None
    if data is not None:
        dring = np.zeros(ring.shape, np.uint16, order="F")
        dring[1:-1, 1:-1] = data
    if window is None:
        window = (0, 0, W, H)
    wx, wy, ww, wh = map(int, window)
    if not (0 <= wx and 0 <= wy and ww > 0 and wh > 0 and wx + ww <= W and wy + wh <= H):
        raise VoxelError(f"window {window} is not inside the {W}x{H} blocks")
    wins = [(n, x + wx, y + wy, w, h) for n, x, y, w, h in
            windows(per, ox + wx, oy + wy, ww, wh, tile)]
    meshed = []  # (name, quads, x, y, (the light near them, its offset))
    for i, (name, x, y, w, h) in enumerate(wins):
        yield stage("mesh", i / len(wins))
        q = meshing.quads(np.asfortranarray(ring[x:x + w + 2, y:y + h + 2]), border="context",
                          method=method, backend=backend or "numpy",
                          data=None if dring is None else dring[x:x + w + 2, y:y + h + 2])
        if instances:
            q = q[~np.isin(q["block"], shape_ids)]
        if not len(q):
            continue
        # the light q samples: its window, one voxel around (sample() unpacks it whole)
        z0 = max(int(q["z"].min()) - 1, 0)
        z1 = min(int((q["z"].astype(np.int64) + q["h"]).max()) + 2, C.HEIGHT)
        near = (lit[PAD + x - 1:PAD + x + w + 1, PAD + y - 1:PAD + y + h + 1, z0:z1], (1, 1, -z0))
        if light == "vertex":
            q = L.split_uneven(q, *near)
        meshed.append((name, q, x, y, near))
    texels = faces = None
    if light == "atlas":
        yield stage("atlas", 0.0)
        pw, ph = zip(*(A.sizes(m[1]) for m in meshed)) if meshed else ((), ())
        px, py, AW, AH = A.pack(np.concatenate(pw or [np.zeros(0, np.int64)]),
                                np.concatenate(ph or [np.zeros(0, np.int64)]))
        texels = np.zeros((AH, AW, 4), np.float32)
        faces = np.full((AH, AW), A.EMPTY, np.uint8)
        starts = np.cumsum([0] + [len(m[1]) for m in meshed])
    mat_table, specs, tinted = _tints(mat_table, specs, [m[1] for m in meshed], palette)
    parts = []
    for i, (name, q, x, y, near) in enumerate(meshed):
        yield stage("parts", i / len(meshed))
        p = _part(name, q, (ox + x, oy + y, oz), *near, mat_table)
        if tinted:
            sel = q["block"] == COLOR
            p.material[sel] = [tinted[int(c)] for c in q["color"][sel]]
        if texels is not None:
            sl = slice(starts[i], starts[i + 1])
            A.fill(texels, faces, q, px[sl], py[sl], *near)
            p.uv2 = A.uvs(q, p.positions - np.asarray((ox + x, oy + y, oz), np.float32),
                          px[sl], py[sl], AW, AH)
        parts.append(p)
    images = {}
    if mm is not None:
        v = mm.voxel
        mm = mm.subset((v[:, 0] >= wx) & (v[:, 0] < wx + ww) & (v[:, 1] >= wy) & (v[:, 1] < wy + wh))
    if mm is not None and mm.quads:
        near = (lit[PAD - 1:PAD + W + 1, PAD - 1:PAD + H + 1], (1, 1, 0))
        parts.append(MD.part_and_materials(mm, models.res, blocks, (ox, oy, oz), *near, specs, images))
    plants = {}
    if instances:
        for bid in shape_ids:
            xyz = np.argwhere(blocks[wx:wx + ww, wy:wy + wh] == bid)
            if len(xyz):
                plants[REGISTRY.blocks[bid].name] = (xyz + (ox + wx, oy + wy, oz)).astype(np.int32)
    yield stage("baked", 1.0)
    return Bake((ox + wx, oy + wy, ox + wx + ww, oy + wy + wh), parts, specs, plants, texels,
                faces, images)


LIGHT_TILE, REACH = 64, 16  # light travels < 16 voxels: a 16-column margin is exact


def light_tiles(blocks, backend=None, tile: int = LIGHT_TILE):
    """Light of `blocks` solved in tiles of `tile` columns plus a REACH margin (each
    exact inside, as light.solve is 15 columns in from its edges), so no single step
    holds the UI for the whole region. Yields (light so far, fraction); the last
    one is the whole light, equal to light.solve(blocks)."""
    from ..light import solve as light_solve
    W, H = blocks.shape[:2]
    if W <= tile + 2 * REACH and H <= tile + 2 * REACH:
        yield None, 0.0
        yield light_solve(blocks, backend), 1.0
        return
    out = C.empty(np.uint16, W, H)
    boxes = [(x, y) for y in range(0, H, tile) for x in range(0, W, tile)]
    for i, (x, y) in enumerate(boxes):
        yield out, i / len(boxes)
        a, b = max(x - REACH, 0), max(y - REACH, 0)
        part = light_solve(np.asfortranarray(blocks[a:x + tile + REACH, b:y + tile + REACH]),
                           backend)
        out[x:x + tile, y:y + tile] = part[x - a:x - a + tile, y - b:y - b + tile]
    yield out, 1.0


def windows(per, ox, oy, W, H, tile=64):
    """(name, x, y, w, h) of every object's window in region coordinates."""
    if per == "region":
        return [(f"voxels_{ox}_{oy}", 0, 0, W, H)]
    if per == "tile":
        return [(f"tile_{ox + x}_{oy + y}", x, y, min(tile, W - x), min(tile, H - y))
                for y in range(0, H, tile) for x in range(0, W, tile)]
    wins = []
    for cy in range(oy >> 4, ((oy + H - 1) >> 4) + 1):
        for cx in range(ox >> 4, ((ox + W - 1) >> 4) + 1):
            x, y = max(cx * 16 - ox, 0), max(cy * 16 - oy, 0)
            wins.append((f"chunk_{cx}_{cy}", x, y, min((cx + 1) * 16 - ox, W) - x,
                         min((cy + 1) * 16 - oy, H) - y))
    return wins


def _part(name, q, origin, light, offset, mat_table) -> Part:
    from .. import meshing
    to_mesh = getattr(meshing, "to_mesh", None)
    if to_mesh is None:  # until meshing/__init__ re-exports it (README API)
        from ..meshing.mesh import to_mesh
    m = to_mesh(q, origin=origin)
    local = m.positions - np.asarray(origin, np.float32)
    face = np.repeat(np.asarray(m.face), 4)
    pts = local.copy()
    nrm = m.normals.copy()
    shape = face >= 6  # plants: their own voxel's light (their planes cross the cell)
    if shape.any():
        cell = np.repeat(np.stack([q["x"], q["y"], q["z"]], 1).astype(np.float32), 4, 0)
        pts[shape] = cell[shape] + 0.5
        nrm[shape] = 0
    from ..light import sample
    s = sample(light, pts + np.asarray(offset, np.float32), nrm)
    return Part(name, m.positions.astype(np.float32), m.normals.astype(np.float32),
                m.uvs.astype(np.float32), np.ascontiguousarray(s[:, :3]),
                np.ascontiguousarray(s[:, 3]),
                mat_table[np.asarray(m.block), np.asarray(m.face)].astype(np.int32),
                np.asarray(m.block, np.uint16), np.asarray(m.face, np.uint8))


def shade_atlas(bk: Bake, hours: float = 12.0) -> np.ndarray:
    """(AH, AW, 3) light factor of the atlas at `hours` (as shade() per vertex)."""
    return A.shade(bk.atlas, bk.atlas_face, hours)


def shade(part: Part, hours: float = 12.0) -> np.ndarray:
    """(4N, 3) linear RGB light factor of eq. 4.1 at `hours` (light.shade with white
    albedo, no glow), clipped to 0..1 for a glTF COLOR_0."""
    from ..light import daytime, shade as eq41
    s = eq41(np.ones((len(part.daylight), 3), np.float32), part.light, np.zeros(len(part.daylight)),
             part.daylight, part.normals, daytime.at(hours))
    return np.clip(s, 0.0, 1.0).astype(np.float32)
