"""What every generator provides; the world and the CLI only talk to this."""
from __future__ import annotations

import numpy as np


class Generator:
    """Turns chunk keys into block arrays, deterministically from (seed, params).

    Subclasses set `name` and `version`, accept `params` overrides (stored as JSON in
    the world file so a world always regenerates the same) and implement `generate`.
    """

    name = "?"
    version = 1
    defaults: dict = {}

    def __init__(self, seed: int, params: dict | None = None, backend: str | None = None):
        self.seed = int(seed)
        self.params = {**self.defaults, **(params or {})}
        self.backend = backend or "numpy"

    def generate(self, keys: list[tuple[int, int]]) -> list[np.ndarray]:
        """One (16, 16, 256) uint16 Fortran-ordered block array per key.

        The result for a key must not depend on which other keys are in the batch.
        """
        raise NotImplementedError
