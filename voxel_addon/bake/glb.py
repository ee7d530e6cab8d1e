"""Reading and touching up glTF binaries (.glb) without Blender.

Light atlases are sampled without mipmaps (`touch_up(..., plain=prefix)`):
Blender's exporter gives Linear images LINEAR_MIPMAP_LINEAR, and mip levels would
blend neighbouring patches of the atlas into each other at a distance.

Blender's exporter warns "More than one shader node tex image used for a texture"
for every material whose Base Color and Alpha both come from an image, even the
same image node (it counts sockets, not nodes). The bake's glTF materials therefore
leave Alpha unlinked and `touch_up` writes alphaMode into the file afterwards:
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


LINEAR, CLAMP = 9729, 33071


def touch_up(path, modes: dict[str, str], plain: str | None = None) -> int:
    """Set alphaMode ("MASK" cut at 0.5 or "BLEND") of the materials named in
    `modes`, and plain LINEAR sampling (no mipmaps, clamped) for the images whose
    name starts with `plain`; returns how many things were changed."""
    doc, binary = read(path)
    n = 0
    for m in doc.get("materials", []):
        mode = modes.get(m.get("name"))
        if mode and m.get("alphaMode") != mode:
            m["alphaMode"] = mode
            n += 1
    if plain:
        want = {"magFilter": LINEAR, "minFilter": LINEAR, "wrapS": CLAMP, "wrapT": CLAMP}
        images = doc.get("images", [])
        for t in doc.get("textures", []):
            src = t.get("source")
            if src is None or not images[src].get("name", "").startswith(plain):
                continue
            samplers = doc.setdefault("samplers", [])
            if want not in samplers:
                samplers.append(dict(want))
            t["sampler"] = samplers.index(want)
            n += 1
        used = {t.get("sampler") for t in doc.get("textures", [])}
        if doc.get("samplers") and len(used) < len(doc["samplers"]):  # drop unused ones
            keep = [i for i in range(len(doc["samplers"])) if i in used]
            remap = {old: new for new, old in enumerate(keep)}
            doc["samplers"] = [doc["samplers"][i] for i in keep]
            for t in doc["textures"]:
                if t.get("sampler") is not None:
                    t["sampler"] = remap[t["sampler"]]
    if n:
        write(path, doc, binary)
    return n
