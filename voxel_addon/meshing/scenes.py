"""The four reference scenes of thesis table 6.3 (ocean, desert, landscape, cave) as fixed
presets of the real Overworld generator, shared by the meshing bench, tests and renderer.

Each preset is a seed, an area of chunks and a camera (world coordinates, CLI `render`
order x, y, z, yaw, pitch). Areas were picked by block counts (README.md, bench):
ocean is a shallow sea, desert is dunes with cacti, landscape is grass with trees and
plants, cave has a large cavern below the ground and its camera stands inside it.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..core import chunk
from ..core.errors import VoxelError

GENERATOR = "overworld"
VERSION = 1  # the scenes stay those of the golden images and benches whatever the newest


@dataclass(frozen=True)
class Scene:
    seed: int
    chunks: tuple[int, int, int, int]   # cx0, cy0, cx1, cy1 (half-open)
    camera: tuple[float, float, float, float, float]  # x, y, z, yaw, pitch (CLI `render`)
    time: str
    note: str


SCENES = {
    "ocean": Scene(1, (-96, -72, -92, -68), (-1504, -1160, 90, 90, -25), "10:00",
                   "shallow sea (sand floor z 45..57 under water to z 62): many transparent blocks"),
    "desert": Scene(1, (12, -96, 16, -92), (224, -1544, 100, 90, -20), "14:00",
                    "sand dunes with cacti: mostly cubes, no transparency"),
    "landscape": Scene(1, (36, 0, 40, 4), (608, -8, 100, 90, -25), "09:00",
                       "grass, trees (leaves: alpha test, inner leaf faces drawn), plants"),
    "cave": Scene(1, (-24, 12, -20, 16), (-338.5, 245.5, 45, 270, -30), "12:00",
                  "inside a cavern (air z 31..47, ground ~z 69), looking down; no transparency"),
}


def scene(name: str) -> Scene:
    if name not in SCENES:
        raise VoxelError(f"unknown scene {name!r} (known: {', '.join(SCENES)})")
    return SCENES[name]


def sea_level(name: str) -> int:
    """The water level of the scene's generator (-1: none)."""
    from ..generation import make_generator
    return int(make_generator(GENERATOR, scene(name).seed, version=VERSION).params.get("sea_level", -1))


@lru_cache(maxsize=4)
def _area(name: str) -> np.ndarray:
    from ..generation import make_generator
    sc = scene(name)
    gen = make_generator(GENERATOR, sc.seed, version=VERSION)
    cx0, cy0, cx1, cy1 = sc.chunks
    keys = [(cx, cy) for cy in range(cy0 - 1, cy1 + 1) for cx in range(cx0 - 1, cx1 + 1)]
    full = chunk.paste(zip(keys, gen.generate(keys)), cx0 - 1, cy0 - 1, cx1 + 1, cy1 + 1)
    out = np.asfortranarray(full[15:-15, 15:-15])
    out.flags.writeable = False
    return out


def blocks(name: str) -> np.ndarray:
    """The scene's area plus a one-voxel ring: (16*nx + 2, 16*ny + 2, 256) uint16, a
    fresh copy (generated once per process)."""
    return _area(name).copy(order="F")


def chunk_windows(area: np.ndarray):
    """Yield ((i, j), (18, 18, 256) window) for every chunk of a scene area."""
    nx, ny = (area.shape[0] - 2) // 16, (area.shape[1] - 2) // 16
    for j in range(ny):
        for i in range(nx):
            yield (i, j), area[16 * i:16 * i + 18, 16 * j:16 * j + 18]
