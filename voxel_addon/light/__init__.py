"""Cellular light (SPEC F6, issue 4): model, full solves (NumPy + OpenCL), incremental
relight, sampler + eq. 4.1, and the time-of-day table (daytime).

Public API:
  solve(blocks, backend=None) -> packed light of a (W, H, 256) array (dark air outside)
  chunk_light(blocks3x3, backend=None) -> exact (16, 16, 256) light of the centre chunk
  region_light(blocks, backend=None) -> exact light of the interior of a chunk region
  world_region(world, cx0, cy0, cx1, cy1, backend=None) -> light of those chunks
  update(blocks, light, x, y, z, old) / edit(blocks, light, x, y, z, block) -> box
  sample(light, points, normals, origin) / shade(albedo, rgb, glow, day, n, params)
  daytime.at(hours) -> DayParams, daytime.parse_time("HH:MM") -> hours
"""
from . import daytime
from .sampler import sample, shade
from .full import chunk_light, region_light, solve, world_region
from .incremental import edit, update

__all__ = ["daytime", "sample", "shade", "chunk_light", "region_light", "solve",
           "world_region", "edit", "update"]
