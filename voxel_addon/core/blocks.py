"""The block registry: every block type and its properties (SPEC F1, thesis table 6.2).

Ids are the position in BLOCKS, so they are stable as long as new blocks are only
appended. A world file stores its own id <-> name table; storage remaps on load.
NumPy lookup tables (indexed by block id) let generation, light and meshing work on
whole arrays without touching Block objects.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import VoxelError

SHAPES = ("none", "cube", "x", "hash")
RENDERS = ("none", "opaque", "alpha_test", "blend")
ANIMATIONS = ("none", "wave_top", "wave", "water")
FACES = ("-x", "+x", "-y", "+y", "-z", "+z")  # face index = 2*axis + (positive side)


@dataclass(frozen=True)
class Block:
    name: str
    shape: str = "cube"
    render: str = "opaque"
    light_opaque: bool = True
    emission: tuple[int, int, int] = (0, 0, 0)
    attenuation: int = 0
    # Texture name per face; "side" covers the four horizontal faces.
    textures: dict[str, str] = field(default_factory=dict)
    animation: str = "none"
    collision: bool = True
    # Self-lit texture share 0..1 (ore is visible in darkness: thesis table 6.2).
    glow: float = 0.0
    # For "hash" shapes: how far the planes sit inside the cell (1/16 units).
    inset: int = 4
    double_sided: bool = False

    def texture(self, face: str) -> str:
        """Texture name for a face in FACES order names ('-x' … '+z')."""
        t = self.textures
        if face == "+z":
            return t.get("top", t.get("all", self.name))
        if face == "-z":
            return t.get("bottom", t.get("all", self.name))
        return t.get("side", t.get("all", self.name))


def _plant(name, **kw):
    kw.setdefault("animation", "wave_top")
    return Block(name, shape="x", render="alpha_test", light_opaque=False,
                 collision=False, double_sided=True, **kw)


BLOCKS: tuple[Block, ...] = (
    Block("air", shape="none", render="none", light_opaque=False, collision=False),
    Block("stone"),
    Block("dirt"),
    Block("grass", textures={"top": "grass_top", "side": "grass_side", "bottom": "dirt"}),
    Block("snow", textures={"top": "snow", "side": "snow_side", "bottom": "dirt"}),
    Block("sand"),
    Block("ore", emission=(3, 2, 1), glow=0.6),
    Block("log", textures={"top": "log_top", "bottom": "log_top", "side": "log_side"}),
    Block("leaves", render="alpha_test", light_opaque=False, attenuation=1, animation="wave"),
    _plant("flowers"),
    _plant("tall_grass"),
    Block("wheat", shape="hash", render="alpha_test", light_opaque=False, collision=False,
          animation="wave_top", inset=4, double_sided=True),
    _plant("mushroom", animation="none"),
    _plant("glowing_mushroom", animation="none", emission=(2, 6, 14), glow=1.0),
    Block("cactus", shape="hash", render="alpha_test", light_opaque=False, inset=1,
          textures={"top": "cactus_top", "side": "cactus_side", "bottom": "cactus_top"}),
    Block("glass", render="blend", light_opaque=False),
    Block("water", render="blend", light_opaque=False, attenuation=2, animation="water",
          collision=False),
    Block("lamp_red", emission=(15, 0, 0), glow=1.0),
    Block("lamp_green", emission=(0, 15, 0), glow=1.0),
    Block("lamp_blue", emission=(0, 0, 15), glow=1.0),
    Block("lamp_white", emission=(15, 15, 15), glow=1.0),
    Block("lamp_yellow", emission=(15, 12, 0), glow=1.0),
    # building materials for imported Minecraft worlds (issue 21)
    Block("planks"),
    Block("cobblestone"),
    Block("stone_bricks"),
    Block("bricks"),
    Block("deepslate"),
    Block("gravel"),
    Block("clay"),
    Block("sandstone"),
    Block("obsidian"),
    Block("lava", emission=(15, 9, 3), glow=0.9),
    _plant("torch", animation="none", emission=(14, 11, 6), glow=1.0),
    # a voxel whose colour is its small data: an index into the world's colour
    # palette (core.colors); .vox models and Minecraft's dyed blocks
    Block("color"),
)


class Registry:
    """Name/id lookups plus per-id NumPy tables for array code."""

    def __init__(self, blocks: tuple[Block, ...]):
        self.blocks = blocks
        self._ids = {b.name: i for i, b in enumerate(blocks)}
        n = len(blocks)
        self.shape = np.array([SHAPES.index(b.shape) for b in blocks], np.uint8)
        self.render = np.array([RENDERS.index(b.render) for b in blocks], np.uint8)
        self.light_opaque = np.array([b.light_opaque for b in blocks], bool)
        self.emission = np.array([b.emission for b in blocks], np.uint8).reshape(n, 3)
        self.attenuation = np.array([b.attenuation for b in blocks], np.uint8)
        self.collision = np.array([b.collision for b in blocks], bool)
        self.glow = np.array([b.glow for b in blocks], np.float32)
        # Texture layers: one list of unique names, and per (id, face) the layer.
        names: list[str] = []
        for b in blocks:
            for f in FACES:
                if b.shape != "none" and b.texture(f) not in names:
                    names.append(b.texture(f))
        self.texture_names = tuple(names)
        self.face_texture = np.zeros((n, 6), np.uint16)
        for i, b in enumerate(blocks):
            if b.shape != "none":
                for k, f in enumerate(FACES):
                    self.face_texture[i, k] = names.index(b.texture(f))

    def __len__(self):
        return len(self.blocks)

    def __getitem__(self, key: int | str) -> Block:
        return self.blocks[self.id(key) if isinstance(key, str) else key]

    def id(self, name: str) -> int:
        try:
            return self._ids[name]
        except KeyError:
            raise VoxelError(f"unknown block name {name!r} "
                             f"(known: {', '.join(self._ids)})") from None

    def names(self) -> list[str]:
        return [b.name for b in self.blocks]

    def describe(self) -> list[dict]:
        """The block table as `info` prints it."""
        return [{"id": i, "name": b.name, "shape": b.shape, "render": b.render,
                 "light_opaque": b.light_opaque, "emission": list(b.emission),
                 "attenuation": b.attenuation} for i, b in enumerate(self.blocks)]


REGISTRY = Registry(BLOCKS)
AIR = 0
