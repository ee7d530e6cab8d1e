"""What the world hands to a renderer for one chunk (the contract with render)."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..meshing import ChunkMesh


class Payload(NamedTuple):
    """`mesh`: the chunk meshed with its one-voxel ring of neighbours (greedy, as
    meshing.build_chunks makes it); `light`: its final (16, 16, 256) uint16 packed
    light; `version`: larger whenever the chunk's blocks or light changed."""
    key: tuple[int, int]
    mesh: ChunkMesh
    light: np.ndarray
    version: int
