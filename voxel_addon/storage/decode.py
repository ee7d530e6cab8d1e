"""Stored chunk rows -> arrays in registry ids (or the stored frame kept packed),
every block id checked; a row that cannot be decoded raises CorruptChunk."""
from __future__ import annotations

import numpy as np

from ..core import chunk as C
from ..core.errors import VoxelError
from . import codecs

_ZYX = (C.HEIGHT, C.SIZE, C.SIZE)  # linear order as C order: .T is the chunk's shape
# the largest id as a Python int: argmax and item (a ufunc reduce costs ~0.8 us of
# set-up, and comparing its NumPy scalar with an int ~1 us more: issue 29)
_ARGMAX = np.ndarray.argmax
_LAYER = C.SIZE * C.SIZE
_N, _BYTES = C.VOLUME, 2 * C.VOLUME
_u16, _tail, _ours = codecs.decode_u16, codecs.zero_tail, codecs.decode_ours


def _scratch() -> np.ndarray:
    """This thread's scratch chunk array as (HEIGHT, SIZE, SIZE) in C order (a frame
    kept as read decodes here only to be checked: no fresh 128 KB, no page faults)."""
    return C.scratch(C.SHAPE, np.dtype(np.uint16)).T


class CorruptChunk(VoxelError):
    """A chunk row that cannot be decoded; it is left as it is in the file."""


class Decoding:
    """WorldFile's decoding half: needs `path`, `_identity` (the file's ids are the
    registry's), `_to_reg` (file id -> registry id) and `_unnamed` (None, or True
    for the file ids below its largest that have no name)."""

    def _fetched(self, key, row, packed: bool = False):
        _, _, v, codec, blob, dblob, lcodec, lblob = row  # (cx, cy, ...)
        if codec is None:
            return None, None, None, v
        blocks, data = self._decode(key, codec, blob, dblob, packed)
        return blocks, data, self._decode_light(lcodec, lblob, packed), v

    def _decode(self, key, codec, blob, dblob, packed: bool = False, out=None):
        # PACKED: keep the frame as read (what it decodes to is the chunk's blocks as
        # is: the file's ids are the registry's); decoded only to check it. OUT: a
        # (HEIGHT, SIZE, SIZE) uint16 C-order array nobody else holds (read_many's)
        frame = packed and self._identity and codecs.framed(codec, blob, _BYTES)
        blocks = _scratch() if frame else np.empty(_ZYX, np.uint16) if out is None else out
        try:  # into new (HEIGHT, SIZE, SIZE) C-order arrays: .T is the chunk's shape
            zeros = _ours(blob, _N, blocks) if codec == "zstd" else -1
            if zeros < 0:  # not encode()'s frame: the general path
                blocks = _u16(codec, blob, _N, blocks)
                zeros = _tail(blob) if codec == "zstd" else 0
            data = None if dblob is None else _u16(codec, dblob, _N).reshape(_ZYX).T
        except ValueError as e:
            raise CorruptChunk(f"chunk ({key[0]}, {key[1]}) in {self.path} is damaged ({e}); "
                               "it was left untouched") from None
        # checked always: tables are indexed by id (the lookup checks what it maps);
        # not the layers of zeros (air) a frame says it ends with: ~70 % of a chunk
        if self._identity:
            layers = -(-(_N - (zeros >> 1)) // _LAYER)
            below = blocks[:layers]
            ok = layers == 0 or below.item(_ARGMAX(below)) < len(self._to_reg)
        else:
            try:
                ok = self._unnamed is None or not self._unnamed[blocks].any()
                blocks = self._to_reg[blocks]
            except IndexError:
                ok = False
        if not ok:
            raise CorruptChunk(f"chunk ({key[0]}, {key[1]}) in {self.path} has block ids "
                               "missing from block_types; it was left untouched")
        if frame:
            return C.Packed.frame(blob, C.SHAPE, np.uint16, layers), data
        return blocks.T, data  # (16, 16, 256) in F order: a view

    def decode_row(self, row):
        """(blocks, data-or-None) in registry ids of a row from encode_chunk."""
        return self._decode((row[0], row[1]), row[2], row[3], row[4])

    @staticmethod
    def _decode_light(codec, blob, packed: bool = False):
        if blob is None:
            return None
        try:
            got = codecs.decode_u16(codec, blob, C.VOLUME).reshape(C.SHAPE, order="F")
        except (ValueError, VoxelError):  # derived data: recomputed, never a failure
            return None
        if packed and codecs.framed(codec, blob, 2 * C.VOLUME):
            n = C.VOLUME - (codecs.zero_tail(blob) >> 1)
            return got, C.Packed.frame(blob, C.SHAPE, np.uint16, -(-n // _LAYER))
        return got
