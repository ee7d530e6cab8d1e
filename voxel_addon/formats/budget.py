"""What one import may spend on decoding: hostile files (compression bombs, millions of
tiny NBT tags) are refused as a whole once a budget is spent, with one line.

Per import, scaled with the input because a real world decodes to about 5-10x its
region files (chunk NBT compresses well but not a thousandfold): decompressed bytes
max(2 GiB, 64x the region files), NBT tags max(16M, 4 per byte of region files). Per
chunk the limits stay those of region.MAX_NBT and anvil.CHUNK_TAGS."""
from __future__ import annotations

BYTES_FLOOR = 2 << 30
BYTES_PER_INPUT = 64
TAGS_FLOOR = 16 << 20
TAGS_PER_INPUT = 4


class Exceeded(ValueError):
    """A budget is spent: the file is refused as a whole (no real one comes near)."""


class Budget:
    __slots__ = ("bytes", "tags", "_bytes0", "_tags0")

    def __init__(self, nbytes: int, tags: int):
        self.bytes, self.tags = self._bytes0, self._tags0 = int(nbytes), int(tags)

    @classmethod
    def of_input(cls, size: int) -> "Budget":
        """The budget of an import reading `size` bytes of region files."""
        return cls(max(BYTES_FLOOR, BYTES_PER_INPUT * size), max(TAGS_FLOOR, TAGS_PER_INPUT * size))

    def spend_bytes(self, n: int) -> None:
        self.bytes -= n
        if self.bytes < 0:
            raise Exceeded(f"more than {self._bytes0 >> 20} MiB decompressed in this import "
                           "(the region files inflate far beyond real ones)")

    def spend_tags(self, n: int) -> None:
        self.tags -= n
        if self.tags < 0:
            raise Exceeded(self.tags_message())

    def spent(self) -> tuple[int, int]:
        """(bytes, tags) charged so far: what a cluster worker reports for one chunk,
        so the writer charges the import's budget with it."""
        return self._bytes0 - self.bytes, self._tags0 - self.tags

    def tags_message(self) -> str:
        return (f"more than {self._tags0:,} NBT tags in this import (the region files hold "
                "far more tags than real ones)")
