"""An edit's remesh (world/edit.py): the window's chunks meshed again, only the render
regions (64 layers) that hold a changed voxel's faces; a few voxels without colours
or Minecraft models by meshing.patch (only the slices through them, on this thread),
the rest by the batched mesher (OpenCL when no stream batch holds it)."""
from __future__ import annotations

import numpy as np

from ..core import chunk as C
from ..meshing import tint
from . import build, models as mcmodels
from .window import cross as _cross, gather as _gather

S = C.SIZE


def remesh(world, last, win, first=None) -> set:
    """Mesh the window's chunks again, only the render regions (64 layers) that hold
    a changed voxel's faces; keep the meshes that differ (call after the stroke is
    in the chunks). A few voxels without colours or Minecraft models: only the slices
    through them, on this thread (meshing.patch: no kernel launch). Returns the keys
    whose mesh changed."""
    from .. import meshing
    remesh = win.remesh
    rx0, ry0 = min(k[0] for k in remesh), min(k[1] for k in remesh)
    rx1, ry1 = max(k[0] for k in remesh) + 1, max(k[1] for k in remesh) + 1
    gx, gy = rx0 * S - 1, ry0 * S - 1  # the chunks with their one-voxel ring
    zs = [z for _, _, z in last]
    r0 = max(min(zs) - 1, 0) // meshing.REGION_H
    r1 = min(max(zs) + 1, C.HEIGHT - 1) // meshing.REGION_H + 1
    whole = any(world.chunks.get(k) is not None and world.chunks[k].mesh is None
                for k in remesh)
    regions = None if whole else (r0, r1)
    stack = mcmodels.stack(world)
    # a region remesh reads its layers and one more on each side; the others stay stale
    za, zb = (0, C.HEIGHT) if whole or stack is not None else \
        (max(r0 * meshing.REGION_H - 1, 0), min(r1 * meshing.REGION_H + 1, C.HEIGHT))
    gx1, gy1 = rx1 * S + 1, ry1 * S + 1
    patched = None
    if regions is not None and stack is None and first is not None and len(last) <= PATCH_MAX:
        # meshing.patch reads only the slices through the changed voxels: gather
        # those (a coloured voxel's quads make it give up: then all, as below)
        sub = _cross(world, gx, gy, gx1, gy1, last, remesh, za, zb)
        patched = _patch(world, meshing, sub, last, first, remesh, rx0, ry0)
    if patched is not None:
        meshes = data = None
        models = {}
    else:
        sub = _gather(world, gx, gy, gx1, gy1, "blocks", za, zb, exact=True)
        meshes, data, models = _full(world, meshing, sub, gx, gy, rx0, ry0, remesh,
                                            regions, stack, za, zb)
    out = set()
    for k in remesh:
        c = world.chunks.get(k)
        if c is None or k in world.corrupt:
            continue
        if patched is not None:
            m = patched[k]
        else:
            m = meshes[k] if regions is None else meshing.splice(c.mesh, meshes[k], r0, r1)
        m.models = models.get(k)
        if _same(c.mesh, m) and m.models is None and getattr(c.mesh, "models", None) is None:
            continue  # e.g. a hidden face stayed hidden: no new payload
        c.mesh = m
        out.add(k)
    return out


def _full(world, meshing, sub, gx, gy, rx0, ry0, remesh, regions, stack, za, zb):
    """(meshes, data, models) of the remeshed chunks by the batched mesher."""
    data = None
    if (sub[:, :, za:zb] == tint.COLOR).any():  # coloured voxels: their colour is their data
        data = np.array(_gather(world, gx, gy, gx + sub.shape[0], gy + sub.shape[1], "data"),
                        order="F")
    models = {}
    if stack is not None:  # Minecraft model blocks: air for the mesher
        small = data if data is not None else np.array(
            _gather(world, gx, gy, gx + sub.shape[0], gy + sub.shape[1], "data"), order="F")
        models = mcmodels.build(world, sub, small, rx0, ry0)
    return _mesh(meshing, sub, (rx0, ry0), remesh, regions, data), data, models


PATCH_MAX = 3   # voxels a stroke may change for meshing.patch (more: the batched mesher;
# measured: about even at 4 clustered voxels, 0.42 vs 0.54 ms process CPU at 1)


def _patch(world, meshing, sub, last, first, remesh, rx0, ry0):
    """{key: mesh} of the remeshed chunks by meshing.patch, or None where it does not
    apply to one of them (then all are meshed in full)."""
    cells = list(last)
    before = [first[v][0] for v in cells]
    out = {}
    for k in remesh:
        c = world.chunks.get(k)
        if c is None or k in world.corrupt:
            continue
        ox, oy = k[0] * S, k[1] * S
        m = meshing.patch(c.mesh, sub, [(x - ox, y - oy, z) for x, y, z in cells], before,
                          ((k[0] - rx0) * S, (k[1] - ry0) * S))
        if m is None:
            return None
        out[k] = m
    return out


def _same(a, b) -> bool:
    # colours live beside the packed vertices: a recoloured voxel changes only them
    if a is b:
        return True     # meshing.patch found nothing to change
    return a is not None and np.array_equal(a.vertices, b.vertices) and \
        np.array_equal(a.ranges, b.ranges) and (a.colors is None) == (b.colors is None) \
        and (a.colors is None or np.array_equal(a.colors, b.colors))


def _mesh(meshing, blocks, origin, keys, regions=None, data=None):
    """build_chunks on OpenCL when no stream batch holds it, else NumPy (same output)."""
    blocks = np.asfortranarray(blocks)
    if build.backends()[1] == "opencl" and build.CL_LOCK.acquire(blocking=False):
        try:
            return meshing.build_chunks(blocks, origin, backend="opencl", keys=keys,
                                        regions=regions, data=data)
        finally:
            build.CL_LOCK.release()
    return meshing.build_chunks(blocks, origin, backend="numpy", keys=keys, regions=regions,
                                data=data)
