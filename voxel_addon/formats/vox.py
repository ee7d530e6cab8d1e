"""MagicaVoxel .vox files: read (one model, or a scene graph of nTRN / nGRP / nSHP
nodes placing, rotating and mirroring models as MagicaVoxel does) and write.

RIFF-like: "VOX " + version, then chunks (id, content size, children size, content,
children). MAIN's children: [PACK] (SIZE, XYZI)* RGBA, scene nodes, materials, … A
model is at most 256 per axis; XYZI holds (x, y, z, colour index 1..255) bytes; RGBA
holds colours 1..255 (a file without it uses the default palette). Placement
(MagicaVoxel and ogt_vox): a model's pivot is floor(size / 2); voxel v lands at
R (v + 1/2 - pivot) - 1/2 + t for the rotations R and translations t of the nTRN
nodes above it, outermost last. Hidden nodes and layers are left out.

Hostile input: every size is checked against its parent chunk before anything is
allocated; nesting, node counts and voxel counts are bounded; the scene graph must be
a tree (a node reached twice, shared or in a cycle, is refused: 16 groups of two
children naming one node place 65,536 copies) and is walked once with budgets of
MAX_INSTANCES placed models and MAX_PLACED placed voxels before anything is placed;
a fault is a VoxError (ValueError) with a one-line reason.
"""
from __future__ import annotations

import struct
from typing import NamedTuple

import numpy as np

MAX_SIDE = 256
MAX_NODES = 1 << 16
MAX_INSTANCES = 1 << 15
MAX_CHUNKS = 1 << 18   # models (2 chunks each), nodes, materials, layers, ...
MAX_MODELS = 1 << 16
MAX_ENTRIES = 256      # one dictionary (node attributes, a frame: a handful)
MAX_ENTRIES_ALL = 1 << 20
# voxels over all instances. Placing one costs ~400 B in the world's edits
# (world.set_blocks: 1M voxels took 480 MB, 12 s); raise it when that is leaner
MAX_PLACED = 1 << 20
MAX_STORED = 4 * MAX_PLACED   # voxels over all models, placed or not
MAX_T = 1 << 24  # translations; a world is far smaller along z anyway
_I = struct.Struct("<i")
_HEAD = struct.Struct("<4sii")


class VoxError(ValueError):
    pass


def default_palette() -> np.ndarray:
    """(256, 4) RGBA of files without an RGBA chunk (index 0 unused): a 6-level colour
    cube from white down (black left out), then red, green, blue and grey ramps."""
    lv = [0xFF, 0xCC, 0x99, 0x66, 0x33, 0x00]
    ramp = [0xEE, 0xDD, 0xBB, 0xAA, 0x88, 0x77, 0x55, 0x44, 0x22, 0x11]
    cols = [(r, g, b) for r in lv for g in lv for b in lv][:-1]
    for axis in range(3):
        cols += [tuple(v if i == axis else 0 for i in range(3)) for v in ramp]
    cols += [(v, v, v) for v in ramp]
    out = np.zeros((256, 4), np.uint8)
    out[1:, :3] = cols
    out[1:, 3] = 255
    return out


class Model(NamedTuple):
    size: tuple          # (sx, sy, sz)
    xyzi: np.ndarray     # (n, 4) uint8: x, y, z, colour index


class Instance(NamedTuple):
    model: int
    rot: np.ndarray      # (3, 3) int: world = rot @ local
    t: np.ndarray        # (3,) int


class Scene(NamedTuple):
    models: list
    instances: list
    palette: np.ndarray  # (256, 4) uint8


# ---- reading -----------------------------------------------------------------
def _chunks(buf, pos, end):
    """(id, content start, content end, children start, children end) of the chunks
    in [pos, end), one at a time, at most MAX_CHUNKS."""
    k = 0
    while pos < end:
        if pos + 12 > end:
            raise VoxError(f"chunk header cut at byte {pos}")
        cid, n, m = _HEAD.unpack_from(buf, pos)
        c0 = pos + 12
        if n < 0 or m < 0 or c0 + n + m > end:
            raise VoxError(f"chunk {cid!r} at byte {pos} runs past its parent")
        k += 1
        if k > MAX_CHUNKS:
            raise VoxError(f"more than {MAX_CHUNKS:,} chunks")
        yield cid, c0, c0 + n, c0 + n, c0 + n + m
        pos = c0 + n + m


class _Cursor:
    def __init__(self, buf, pos, end, spent):
        self.buf, self.pos, self.end = buf, pos, end
        self.spent = spent   # [dictionary entries read so far in the file]

    def int(self):
        if self.pos + 4 > self.end:
            raise VoxError("chunk content ends early")
        v = _I.unpack_from(self.buf, self.pos)[0]
        self.pos += 4
        return v

    def string(self):
        n = self.int()
        if n < 0 or self.pos + n > self.end:
            raise VoxError("a string runs past its chunk")
        s = bytes(self.buf[self.pos:self.pos + n]).decode("utf-8", "replace")
        self.pos += n
        return s

    def dict(self):
        n = self.int()
        if n < 0 or n * 8 > self.end - self.pos:
            raise VoxError("a dictionary larger than its chunk")
        if n > MAX_ENTRIES:
            raise VoxError(f"a dictionary of {n} entries (more than {MAX_ENTRIES})")
        self.spent[0] += n
        if self.spent[0] > MAX_ENTRIES_ALL:
            raise VoxError(f"more than {MAX_ENTRIES_ALL:,} dictionary entries")
        return {self.string(): self.string() for _ in range(n)}

    def hidden(self):
        """A node's attributes, only what the reader uses of them kept."""
        return {"_hidden": "1"} if self.dict().get("_hidden") == "1" else {}


def rotation(bits: int) -> np.ndarray:
    """The 3x3 signed permutation of an nTRN `_r` byte (rows: the non-zero column of
    rows 0 and 1 in bits 0-1 and 2-3, row 2 the remaining one; signs in bits 4-6)."""
    r0, r1 = bits & 3, (bits >> 2) & 3
    if r0 > 2 or r1 > 2 or r0 == r1:
        raise VoxError(f"invalid rotation {bits}")
    r2 = 3 - r0 - r1
    m = np.zeros((3, 3), np.int64)
    for row, col in enumerate((r0, r1, r2)):
        m[row, col] = -1 if bits & (1 << (4 + row)) else 1
    return m


def rotation_bits(m: np.ndarray) -> int:
    cols = [int(np.flatnonzero(m[r])[0]) for r in range(3)]
    return cols[0] | cols[1] << 2 | sum(1 << (4 + r) for r in range(3) if m[r, cols[r]] < 0)


def read(data: bytes) -> Scene:
    buf = memoryview(data)
    if len(buf) < 8 or bytes(buf[:4]) != b"VOX ":
        raise VoxError("not a MagicaVoxel file (no 'VOX ' header)")
    top = next(_chunks(buf, 8, len(buf)), None)
    if top is None or top[0] != b"MAIN":
        raise VoxError("no MAIN chunk")
    _, _, _, k0, k1 = top
    models, sizes, nodes, layers = [], [], {}, {}
    palette = None
    spent = [0]
    stored = 0
    for cid, c0, c1, _, _ in _chunks(buf, k0, k1):
        cur = _Cursor(buf, c0, c1, spent)
        if cid == b"SIZE":
            s = (cur.int(), cur.int(), cur.int())
            if not all(1 <= v <= MAX_SIDE for v in s):
                raise VoxError(f"model size {s} outside 1..{MAX_SIDE}")
            sizes.append(s)
        elif cid == b"XYZI":
            if len(sizes) != len(models) + 1:
                raise VoxError("XYZI without its SIZE")
            if len(models) >= MAX_MODELS:
                raise VoxError(f"more than {MAX_MODELS:,} models")
            n = cur.int()
            if n < 0 or 4 * n > c1 - cur.pos:
                raise VoxError(f"{n} voxels do not fit their chunk")
            s = sizes[-1]
            if n > s[0] * s[1] * s[2]:
                raise VoxError(f"{n} voxels in a model of {s[0]}x{s[1]}x{s[2]}")
            stored += n
            if stored > MAX_STORED:
                raise VoxError(f"the models hold more than {MAX_STORED:,} voxels")
            a = np.frombuffer(buf, np.uint8, 4 * n, cur.pos).reshape(n, 4)
            if n and ((a[:, :3] >= np.array(s)).any()):
                raise VoxError(f"a voxel outside its model's size {s}")
            models.append(Model(s, a[a[:, 3] != 0]))
        elif cid == b"RGBA":
            if c1 - c0 < 1024:
                raise VoxError("palette chunk shorter than 256 colours")
            palette = np.zeros((256, 4), np.uint8)
            palette[1:] = np.frombuffer(buf, np.uint8, 1020, c0).reshape(255, 4)
        elif cid in (b"nTRN", b"nGRP", b"nSHP"):
            if len(nodes) >= MAX_NODES:
                raise VoxError("too many scene nodes")
            nid, attrs = cur.int(), cur.hidden()
            if cid == b"nTRN":
                child, _, layer, frames = cur.int(), cur.int(), cur.int(), cur.int()
                if frames < 1 or frames > 4096:
                    raise VoxError(f"nTRN with {frames} frames")
                f = cur.dict()
                try:
                    rot = rotation(int(f.get("_r", "4")))
                    t = [int(v) for v in f.get("_t", "0 0 0").split()]
                except ValueError:
                    raise VoxError("nTRN rotation or translation is not a number") from None
                if len(t) != 3 or max(abs(v) for v in t) > MAX_T:
                    raise VoxError(f"nTRN translation {t} is not three integers within "
                                   f"+-{MAX_T}")
                t = np.array(t, np.int64)
                nodes[nid] = ("T", attrs, child, layer, rot, t)
            elif cid == b"nGRP":
                n = cur.int()
                if n < 0 or 4 * n > c1 - cur.pos:
                    raise VoxError("nGRP children do not fit their chunk")
                if n > MAX_NODES:
                    raise VoxError(f"nGRP with {n} children (more than {MAX_NODES:,} nodes)")
                kids = np.frombuffer(buf, "<i4", n, cur.pos).tolist()
                cur.pos += 4 * n
                nodes[nid] = ("G", attrs, kids)
            else:
                n = cur.int()
                if n < 1 or n > c1 - cur.pos:
                    raise VoxError("nSHP without a model")
                m = cur.int()
                cur.dict()
                nodes[nid] = ("S", attrs, m)
        elif cid == b"LAYR":
            lid, attrs = cur.int(), cur.dict()
            if len(layers) >= MAX_NODES:
                raise VoxError("too many layers")
            layers[lid] = attrs.get("_hidden") == "1"
    if len(sizes) != len(models):
        raise VoxError("SIZE without its XYZI")
    if not models:
        raise VoxError("no models")
    if palette is None:
        palette = default_palette()
    return Scene(models, _instances(nodes, layers, models), palette)


def _instances(nodes, layers, models) -> list:
    """The placed models of the scene graph, walked once from node 0; a node reached
    twice is refused the moment it is reached again (nothing is copied first)."""
    if not nodes:  # a file without a scene: every model at the origin, unrotated
        out = [Instance(i, np.eye(3, dtype=np.int64), np.zeros(3, np.int64))
               for i in range(len(models))]
        _placed(sum(len(m.xyzi) for m in models), len(out))
        return out
    if 0 not in nodes:
        raise VoxError("scene graph without its root node 0")
    out = []
    placed = 0
    seen = {0}
    stack = [(0, np.eye(3, dtype=np.int64), np.zeros(3, np.int64), 0)]
    while stack:
        nid, rot, t, depth = stack.pop()
        if depth > 64:
            raise VoxError("scene graph nested deeper than 64 nodes")
        node = nodes.get(nid)
        if node is None:
            raise VoxError(f"scene graph refers to missing node {nid}")
        if node[1].get("_hidden") == "1":
            continue
        if node[0] == "T":
            _, _, child, layer, r, tt = node
            if layers.get(layer):
                continue
            kids = (child,)
        elif node[0] == "G":
            kids = node[2]
        else:
            if not 0 <= node[2] < len(models):
                raise VoxError(f"nSHP refers to missing model {node[2]}")
            placed += len(models[node[2]].xyzi)
            _placed(placed, len(out) + 1)
            out.append(Instance(node[2], rot, t))
            continue
        for c in kids:
            if c not in nodes:
                raise VoxError(f"scene graph refers to missing node {c}")
            if c in seen:
                raise VoxError(f"scene graph reaches node {c} twice (shared or cyclic; "
                               "MagicaVoxel writes a tree)")
            seen.add(c)
        if node[0] == "T":
            stack.append((child, rot @ r, rot @ tt + t, depth + 1))
        else:
            stack += [(c, rot, t, depth + 1) for c in reversed(kids)]
    return out


def _placed(voxels: int, instances: int) -> None:
    if instances > MAX_INSTANCES:
        raise VoxError(f"the scene places more than {MAX_INSTANCES:,} models")
    if voxels > MAX_PLACED:
        raise VoxError(f"the scene places more than {MAX_PLACED:,} voxels")


def voxels(scene: Scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(positions (n, 3) int64 with the scene's bounding box corner at 0, colour
    indices (n,) uint8, size (3,)): every instance placed; later instances win where
    two overlap."""
    parts, boxes = [], []
    for inst in scene.instances:
        m = scene.models[inst.model]
        size = np.array(m.size, np.int64)
        pivot = size // 2
        # doubled coordinates keep the half-voxel centre exact
        def place(v):
            return (inst.rot @ (2 * v.T + 1 - 2 * pivot[:, None]) - 1) // 2 + inst.t[:, None]
        corners = np.array([[x, y, z] for x in (0, size[0] - 1) for y in (0, size[1] - 1)
                            for z in (0, size[2] - 1)])
        c = place(corners)
        boxes.append((c.min(1), c.max(1)))
        parts.append((place(m.xyzi[:, :3].astype(np.int64)).T, m.xyzi[:, 3]))
    if not boxes:
        return np.zeros((0, 3), np.int64), np.zeros(0, np.uint8), np.zeros(3, np.int64)
    lo = np.min([b[0] for b in boxes], 0)
    hi = np.max([b[1] for b in boxes], 0)
    if (hi - lo).max() >= 1 << 20:
        raise VoxError(f"the scene spans {(hi - lo + 1).tolist()} voxels")
    xyz = np.concatenate([p[0] for p in parts]) - lo
    col = np.concatenate([p[1] for p in parts])
    # last instance wins: keep the last occurrence of each position
    key = (xyz[:, 0] * (1 << 21) + xyz[:, 1]) * (1 << 21) + xyz[:, 2]
    _, first_rev = np.unique(key[::-1], return_index=True)
    keep = np.sort(len(key) - 1 - first_rev)
    return xyz[keep], col[keep], hi - lo + 1


# ---- writing -----------------------------------------------------------------
def _chunk(cid: bytes, content: bytes, children: bytes = b"") -> bytes:
    return _HEAD.pack(cid, len(content), len(children)) + content + children


def _dict(d: dict) -> bytes:
    out = _I.pack(len(d))
    for k, v in d.items():
        for s in (k, v):
            b = s.encode()
            out += _I.pack(len(b)) + b
    return out


def write(grid: np.ndarray, palette: np.ndarray) -> bytes:
    """A .vox of a colour-index grid (X, Y, Z) uint8 (0 empty) and its palette
    (256, 3|4; index 0 unused). Boxes over 256 along an axis become several models,
    each placed by an nTRN so the grid's (0, 0, 0) is the scene's corner."""
    grid = np.asarray(grid, np.uint8)
    pal = np.zeros((256, 4), np.uint8)
    pal[:, :palette.shape[1]] = palette[:256]
    if palette.shape[1] == 3:
        pal[:, 3] = 255
    X, Y, Z = grid.shape
    pieces = []
    for x0 in range(0, X, MAX_SIDE):
        for y0 in range(0, Y, MAX_SIDE):
            for z0 in range(0, Z, MAX_SIDE):
                pieces.append(((x0, y0, z0), grid[x0:x0 + MAX_SIDE, y0:y0 + MAX_SIDE,
                                                  z0:z0 + MAX_SIDE]))
    body = bytearray()  # grows in place: bytes += copied the whole file per model
    for _, g in pieces:
        body += _chunk(b"SIZE", struct.pack("<3i", *g.shape))
        x, y, z = np.nonzero(g)
        xyzi = np.empty((len(x), 4), np.uint8)  # filled in place: a stack is 32 B/voxel
        xyzi[:, 0], xyzi[:, 1], xyzi[:, 2], xyzi[:, 3] = x, y, z, g[x, y, z]
        body += _chunk(b"XYZI", _I.pack(len(xyzi)) + xyzi.tobytes())
    # scene: root nTRN 0 -> nGRP 1 -> (nTRN, nSHP) per model
    n = len(pieces)
    body += _chunk(b"nTRN", _I.pack(0) + _dict({}) + struct.pack("<4i", 1, -1, -1, 1) + _dict({}))
    body += _chunk(b"nGRP", _I.pack(1) + _dict({}) + _I.pack(n)
                   + b"".join(_I.pack(2 + 2 * i) for i in range(n)))
    for i, ((x0, y0, z0), g) in enumerate(pieces):
        t = np.array([x0, y0, z0]) + np.array(g.shape) // 2
        body += _chunk(b"nTRN", _I.pack(2 + 2 * i) + _dict({}) +
                       struct.pack("<4i", 3 + 2 * i, -1, 0, 1) +
                       _dict({"_t": " ".join(str(int(v)) for v in t)}))
        body += _chunk(b"nSHP", _I.pack(3 + 2 * i) + _dict({}) + _I.pack(1) + _I.pack(i) + _dict({}))
    body += _chunk(b"RGBA", pal[1:].tobytes() + b"\0\0\0\0")
    return b"VOX " + _I.pack(150) + _chunk(b"MAIN", b"", body)


def quantise(rgb: np.ndarray, counts: np.ndarray, n: int = 255, iters: int = 8):
    """At most `n` colours for the distinct colours `rgb` (k, 3) seen `counts` times:
    themselves when they fit, else a weighted k-means started from the most frequent.
    Returns (palette (m, 3) uint8, index into it per colour)."""
    rgb = np.asarray(rgb, np.float64).reshape(-1, 3)
    if len(rgb) <= n:
        return rgb.astype(np.uint8), np.arange(len(rgb))
    w = np.asarray(counts, np.float64)
    centres = rgb[np.argsort(-w, kind="stable")[:n]].copy()
    for _ in range(iters):
        d = ((rgb[:, None, :] - centres[None]) ** 2).sum(-1)
        lab = d.argmin(1)
        tot = np.bincount(lab, w, n)
        for c in range(3):
            s = np.bincount(lab, w * rgb[:, c], n)
            centres[:, c] = np.where(tot > 0, s / np.maximum(tot, 1e-9), centres[:, c])
    d = ((rgb[:, None, :] - centres[None]) ** 2).sum(-1)
    return np.clip(np.rint(centres), 0, 255).astype(np.uint8), d.argmin(1)
