"""What every generator provides; the world and the CLI only talk to this."""
from __future__ import annotations

import numpy as np

from ..core.errors import VoxelError


class Generator:
    """Turns chunk keys into block arrays, deterministically from (seed, params).

    Subclasses set `name` and `version`, accept `params` overrides (stored as JSON in
    the world file so a world always regenerates the same) and implement `generate`.
    A change that alters what a stored world would generate is a new version: the
    class's `version` (what new worlds get) goes up, the old one stays in `versions`
    and the instance's `version` picks (a world file names its own: for_file).
    """

    name = "?"
    version = 1       # the newest: new worlds are made with it
    versions = (1,)   # every version this code still makes
    defaults: dict = {}

    def __init__(self, seed: int, params: dict | None = None, backend: str | None = None,
                 version: int | None = None):
        v = type(self).version if version is None else int(version)
        if v not in self.versions:
            newer = v > max(self.versions)
            raise VoxelError(f"generator {self.name!r} version {v} is unknown to this add-on "
                             f"(it knows {', '.join(map(str, self.versions))})"
                             + ("; the world was made by a newer add-on: update it" if newer else ""))
        self.version = v
        self.seed = int(seed)
        self.params = {**self.defaults, **(params or {})}
        self.backend = backend or "numpy"

    def generate(self, keys: list[tuple[int, int]]) -> list[np.ndarray]:
        """One (16, 16, 256) uint16 Fortran-ordered block array per key.

        The result for a key must not depend on which other keys are in the batch.
        """
        raise NotImplementedError

    def surface(self, xy: np.ndarray) -> dict | None:
        """The surface at block columns xy ((n, 2) ints) without making chunks, for far
        terrain: {"height": top solid z, "top": its block id, "water": water surface z
        or -1, "trees": canopy cover 0..1}, (n,) arrays each; None when this
        generator cannot tell (far terrain then comes from stored chunks only).
        Must agree with `generate` (the same height and block at those columns)."""
        return None
