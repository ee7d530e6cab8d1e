"""Meshing (SPEC F7): face visibility, aggregation, X/# shapes, bake meshes, packed viewport vertices. See README.md."""
from __future__ import annotations

from ..opencl import BACKENDS  # noqa: F401
from .faces import METHODS, QUAD  # noqa: F401
from .run import quads  # noqa: F401
from .mesh import Mesh, to_mesh  # noqa: F401
from .slices import patch  # noqa: F401
from .vertex import (BYTES_PER_VERTEX, PASSES, REGION_H, ChunkMesh, build_chunk, build_chunks, splice,  # noqa: F401,E501
                     pack, quad_indices, unpack)
