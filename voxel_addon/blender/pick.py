"""What the mouse points at in a 3D viewport: a voxel face, a Blender object in front
of it, the sky or a chunk that is not loaded (issue 13). The walk itself is
core/ray.py; this adds the view's ray and the scene's objects."""
from __future__ import annotations

from typing import NamedTuple

MESSAGES = {
    "sky": "nothing to edit there (sky)",
    "below": "nothing to edit there (below the world)",
    "unloaded": "that part of the world is not loaded yet",
    "object": "a Blender object is in the way",
    "inside": "the view is inside a block",
}


class Target(NamedTuple):
    hit: object            # core.ray.Hit, or None
    message: str = ""      # why there is nothing to edit ("" when hit is usable)


def view_ray(region, rv3d, coord):
    """Origin and unit direction of the ray under region pixel `coord` (perspective,
    orthographic and camera views alike)."""
    from bpy_extras import view3d_utils
    o = view3d_utils.region_2d_to_origin_3d(region, rv3d, coord)
    d = view3d_utils.region_2d_to_vector_3d(region, rv3d, coord)
    return tuple(o), tuple(d.normalized())


def loaded_blocks(world):
    """chunk(cx, cy) -> blocks of a resident chunk, None otherwise (never loads)."""
    def get(cx, cy):
        c = world.maybe_chunk_at(cx, cy)
        return None if c is None else c.blocks
    return get


def target(context, world, coord, ignore=frozenset(), max_dist: float | None = None) -> Target:
    from ..core import ray
    region, rv3d = context.region, context.region_data
    origin, direction = view_ray(region, rv3d, coord)
    if max_dist is None:
        max_dist = context.space_data.clip_end if context.space_data else 2000.0
        if not rv3d.is_perspective:  # the orthographic eye sits half the clip range back
            max_dist *= 1.5
    hit = ray.cast(origin, direction, loaded_blocks(world), max_dist=max_dist, ignore=ignore)
    if hit.status != ray.HIT:
        return Target(None, MESSAGES[hit.status])
    if hit.normal == (0, 0, 0):
        return Target(None, MESSAGES["inside"])
    dg = context.evaluated_depsgraph_get()
    found, loc, *_ = context.scene.ray_cast(dg, origin, direction, distance=hit.t)
    if found:
        return Target(None, MESSAGES["object"])
    return Target(hit)
