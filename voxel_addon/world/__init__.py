"""The living world (issue 11): World (chunk map, lifecycle, loader thread), Payload,
Stream (background loading, light and meshing around a moving view) and, in
world.edit, edits with undo records. Above storage, generation, light, meshing."""
from __future__ import annotations

from .payload import Payload  # noqa: F401
from .stream import Stream  # noqa: F401
from .world import World  # noqa: F401
