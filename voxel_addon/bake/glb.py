"""Reading and touching up glTF binaries (.glb) without Blender.

Blender's exporter warns "More than one shader node tex image used for a texture"
for every material whose Base Color and Alpha both come from an image, even the
same image node (it counts sockets, not nodes). The bake's glTF materials therefore
leave Alpha unlinked and `set_alpha` writes alphaMode into the file afterwards:
the base colour texture already carries the alpha channel.
"""
from __future__ import annotations

import json
import struct
from pathlib import Path

MAGIC, JSON_CHUNK, BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942


def read(path) -> tuple[dict, bytes]:
    """(the JSON document, the BIN chunk) of a .glb."""
    data = Path(path).read_bytes()
    magic, version, _ = struct.unpack_from("<III", data, 0)
    if magic != MAGIC or version != 2:
        raise ValueError(f"{path} is not a glTF 2 binary")
    off, doc, binary = 12, None, b""
    while off < len(data):
        n, kind = struct.unpack_from("<II", data, off)
        body = data[off + 8:off + 8 + n]
        if kind == JSON_CHUNK:
            doc = json.loads(body)
        elif kind == BIN_CHUNK:
            binary = body
        off += 8 + n
    return doc, binary


def write(path, doc: dict, binary: bytes) -> None:
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    binary += b"\0" * (-len(binary) % 4)
    chunks = struct.pack("<II", len(js), JSON_CHUNK) + js
    if binary:
        chunks += struct.pack("<II", len(binary), BIN_CHUNK) + binary
    Path(path).write_bytes(struct.pack("<III", MAGIC, 2, 12 + len(chunks)) + chunks)


def set_alpha(path, modes: dict[str, str]) -> int:
    """Set alphaMode ("MASK" cut at 0.5 or "BLEND") of the materials named in
    `modes`; returns how many were changed."""
    doc, binary = read(path)
    n = 0
    for m in doc.get("materials", []):
        mode = modes.get(m.get("name"))
        if mode and m.get("alphaMode") != mode:
            m["alphaMode"] = mode
            n += 1
    if n:
        write(path, doc, binary)
    return n
