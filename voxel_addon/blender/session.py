"""Worlds opened from the UI, one per file path, shared by every panel and tool.

Opening is lazy and cached so the viewport, the edit tool and bake all see the same
World (and its chunk map). Closed on unregister and when the path changes.
"""
from __future__ import annotations

import os

_worlds: dict[str, object] = {}


def _key(path: str) -> str:
    import bpy
    return os.path.realpath(bpy.path.abspath(path))


def world(path: str, *, create_seed: int | None = None, generator: str | None = None):
    """The open World for `path`; created with `create_seed` if given and missing."""
    from ..core.errors import VoxelError
    from ..world import World
    if not path:
        raise VoxelError("no world file set (Voxel panel > World > File)")
    key = _key(path)
    w = _worlds.get(key)
    if w is not None:
        return w
    if create_seed is not None and not os.path.exists(key):
        os.makedirs(os.path.dirname(key) or ".", exist_ok=True)
        w = World.create(key, seed=create_seed, generator=generator or "overworld")
    else:
        if not os.path.exists(key):
            raise VoxelError(f"world file {key} does not exist (use New)")
        w = World.open(key)
    _worlds[key] = w
    return w


def close(path: str) -> None:
    w = _worlds.pop(_key(path), None)
    if w is not None:
        w.close()


def close_all() -> None:
    while _worlds:
        _, w = _worlds.popitem()
        try:
            w.close()
        except Exception:  # closing on unregister must not stop the others closing
            pass


def is_open(path: str) -> bool:
    return bool(path) and _key(path) in _worlds
