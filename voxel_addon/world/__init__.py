"""The living world (issue 11): World (chunk map, lifecycle, loader thread), Payload,
Stream (background loading, light and meshing around a moving view) and, in
world.edit, edits with undo records. Above storage, generation, light, meshing."""
from __future__ import annotations

from .world import World  # noqa: F401

_LAZY = {"Payload": "payload", "Stream": "stream"}   # meshing, OpenCL: not for a bare World


def __getattr__(name):
    if name in _LAZY:
        from importlib import import_module
        return getattr(import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
