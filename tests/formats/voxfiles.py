"""MagicaVoxel files written by the tests themselves (a RIFF writer independent of
voxel_addon.formats.vox.write)."""
from __future__ import annotations

import struct

import numpy as np


def chunk(cid: bytes, content: bytes = b"", children: bytes = b"") -> bytes:
    return cid + struct.pack("<ii", len(content), len(children)) + content + children


def string(s: str) -> bytes:
    return struct.pack("<i", len(s)) + s.encode()


def dict_(d: dict) -> bytes:
    return struct.pack("<i", len(d)) + b"".join(string(k) + string(v) for k, v in d.items())


def model(size, voxels) -> bytes:
    """voxels: [(x, y, z, colour index)]"""
    return (chunk(b"SIZE", struct.pack("<3i", *size))
            + chunk(b"XYZI", struct.pack("<i", len(voxels)) + bytes(np.array(voxels, np.uint8)
                                                                    .reshape(-1))))


def rgba(colors) -> bytes:
    """colors: (255, 3|4) for indices 1..255"""
    c = np.zeros((256, 4), np.uint8)
    c[:, 3] = 255
    a = np.asarray(colors, np.uint8)
    c[:len(a), :a.shape[1]] = a
    return chunk(b"RGBA", c.tobytes())


def trn(nid, child, t=(0, 0, 0), r=None, layer=0, attrs=None) -> bytes:
    frame = {"_t": " ".join(map(str, t))}
    if r is not None:
        frame["_r"] = str(r)
    return chunk(b"nTRN", struct.pack("<i", nid) + dict_(attrs or {})
                 + struct.pack("<4i", child, -1, layer, 1) + dict_(frame))


def grp(nid, children) -> bytes:
    return chunk(b"nGRP", struct.pack("<i", nid) + dict_({}) + struct.pack("<i", len(children))
                 + b"".join(struct.pack("<i", c) for c in children))


def shp(nid, model_id) -> bytes:
    return chunk(b"nSHP", struct.pack("<i", nid) + dict_({}) + struct.pack("<ii", 1, model_id)
                 + dict_({}))


def file(body: bytes, version=150) -> bytes:
    return b"VOX " + struct.pack("<i", version) + chunk(b"MAIN", b"", body)
