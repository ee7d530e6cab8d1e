"""The empty generator: air everywhere. Worlds made by an import use it, so the
file holds exactly the imported chunks and nothing grows around them."""
from __future__ import annotations

from ..core import chunk
from .base import Generator


class EmptyGenerator(Generator):
    name = "empty"
    version = 1
    defaults: dict = {}

    def generate(self, keys):
        return [chunk.empty() for _ in keys]
