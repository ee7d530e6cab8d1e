"""Chunk rows (SPEC 3's blobs) in one file's block numbering: what WorldFile.encoder
gives writers that encode away from the file (the Dask workers, a save's batch)."""
from __future__ import annotations

import threading

import numpy as np

from ..core import chunk as C
from . import codecs


class Encoder:
    """Chunk rows in one file's block numbering (WorldFile.encoder)."""

    def __init__(self, codec: str, to_file=None):
        self.codec, self.to_file = codec, to_file  # to_file None: ids are the registry's

    def row(self, key, blocks, data=None, light=None) -> tuple:
        codec = self.codec
        if self.to_file is not None:
            ids = self.to_file[blocks.unpack() if isinstance(blocks, C.Packed) else blocks]
        else:
            ids = blocks
        lblob = None if light is None else codecs.encode(codec, _linear(light))
        return (int(key[0]), int(key[1]), codec, codecs.encode(codec, _linear(ids)),
                self.data(data), lblob)

    def data(self, data):
        """A row's data blob (None when there are no data values)."""
        return None if data is None or not data.any() else \
            codecs.encode(self.codec, _linear(data))


_scratch = threading.local()


def _linear(a):
    """C.to_linear's bytes, as a view of the array's memory when it holds them
    already (uint16, Fortran order, a little-endian machine): no copy to compress.
    A Packed one (a save's snapshot) is decoded into this thread's one buffer,
    valid until the next call (each blob is compressed before the next)."""
    if isinstance(a, C.Packed):
        buf = getattr(_scratch, "buf", None)
        if buf is None or buf.shape != a.shape or buf.dtype != a.dtype:
            buf = _scratch.buf = np.empty(a.shape, a.dtype, order="F")
        a = a.unpack(buf)
    if a.dtype == np.uint16 and a.flags.f_contiguous and codecs.LITTLE:
        return memoryview(a.reshape(-1, order="F")).cast("B")
    return C.to_linear(a)
