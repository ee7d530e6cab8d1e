"""Edits (issue 11 §3): set blocks, relight incrementally, remesh what changed, keep
an undo record, write one transaction per stroke.

`edit(world, changes, write=True)`: changes is one (x, y, z, block[, data]) or a
list of them (a brush stroke); block is a name or an id. Everything is checked before anything
changes (a VoxelError on one line). Returns (payloads, record): the new Payload of
every chunk whose light or mesh really changed (at most the 3x3 around each change:
light reaches 14 voxels; the chunks holding a changed voxel or a face neighbour of
one are remeshed and kept only if the mesh differs), and a Record holding the before
and after (id, data) of every voxel that really changed. `undo(world, record)` and
`redo(world, record)` apply it back or again the same way and return payloads.

Light: the chunks around the stroke must have final light; those that do not (not
streamed yet) are lit first in one batch (build.light_and_mesh) — for a one-voxel
stroke relit on its part only those its part and remesh read (_needed). Then each voxel is
relit with light.update on a window holding every voxel's relight box (a darkening
edit clears and refills only the light that moved), which equals a full solve
(tests); a one-voxel stroke without lamps first on the columns near it (_part).
With the world's resource stack the window holds the blocks as the full solve sees
them (world/models.Sight: a rail, door or slab passes light), and a
change of state alone is relit too. Meshes: a stroke of a few voxels without colours or
Minecraft models has only the slices through them meshed again, on this thread
(meshing.patch: no kernel launch); otherwise the render regions (64 layers) around the
changed voxels are meshed again and spliced in. The payloads are also queued on every Stream of the
world, so a consumer that only drains sees them as well.

Writing: edit(..., write=True) hands the stroke to the world's writer thread
(World.commit_behind: one transaction, started as it returns), so the payloads never
wait for SQLite; `world.settle()` waits for that write and raises its error (the
Blender strokes, undo and redo and a rescue settle before they report the stroke
saved; close writes it anyway). write=False holds it in memory (shown, but the file
unchanged) until `write(world)`, the next commit, a flush or close: a drag's parts,
one transaction when it ends.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..core import chunk as C
from ..core.blocks import REGISTRY
from ..core.errors import VoxelError, explain
from . import build, models as mcmodels
from .payload import Payload
from .remesh import remesh as _remesh
from .window import SCRATCH as _scratch  # noqa: F401  (tests garble its buffers)
from .window import gather as _gather

S = C.SIZE


class Record(NamedTuple):
    """One stroke's undo record: per voxel (x, y, z) and (id, data) before and after."""
    voxels: tuple[tuple[int, int, int], ...]
    before: tuple[tuple[int, int], ...]
    after: tuple[tuple[int, int], ...]


def edit(world, changes, write: bool = True):
    """Apply a stroke; returns (payloads, Record). write=False keeps the change in
    memory (shown, saved by the next `write`, flush or close): the parts of one
    drag, written together when it ends."""
    items = check(world, changes)
    try:
        world.refresh()  # another process's changes first (a pragma when there are none)
    except Exception as e:  # noqa: BLE001 - a damaged or vanished file: say nothing was applied
        err = explain(e, world.file.path, "reading")
        if err is None:
            raise
        raise VoxelError(f"{err}; nothing of this stroke was applied") from None
    return _stroke(world, items, write)


def write(world) -> None:
    """Write what edits with write=False held, in one transaction."""
    world.commit()


def undo(world, record: Record) -> list[Payload]:
    """Put back the values before the stroke, only where a voxel still holds the
    stroke's value: what another session (or process) put there since stays."""
    return _stroke(world, _still(world, record.voxels, record.after, record.before))[0]


def redo(world, record: Record) -> list[Payload]:
    return _stroke(world, _still(world, record.voxels, record.before, record.after))[0]


# A stroke whose voxels lie further apart than this (blocks; a box is at most 32, a
# brush 8) is applied in parts, one per TILE x TILE columns: one window over the
# whole bounding box (the undo of a long drag, a script's list) would light and
# gather every chunk in between, growing with the square of the distance.
SPAN, TILE = 64, 64


def _stroke(world, items, write=True):
    """_apply in parts when the stroke is wide: each part relit on its own window
    (exact: each is an incremental relight of the world as it is), held, then all
    written in one transaction; one Record, the payloads merged."""
    xs, ys = [it[0] for it in items], [it[1] for it in items]
    keys = {C.key_of(x, y) for x, y in zip(xs, ys)}
    # a damaged chunk is refused before any part changes anything, on one line (no
    # "shown as missing" warning: nothing goes on without it); its neighbours, lit
    # around the stroke, are shown as missing
    world.load(keys, warn=False)
    bad = sorted(keys & world.corrupt.keys())
    if bad:
        raise VoxelError(f"chunk {bad[0]} is damaged in the file; it cannot be edited")
    if not items or max(max(xs) - min(xs), max(ys) - min(ys)) <= SPAN:
        return _apply(world, items, write)
    parts: dict = {}
    for it in items:  # a voxel's changes stay in one part, in their order
        parts.setdefault((it[0] // TILE, it[1] // TILE), []).append(it)
    out: dict = {}
    recs = []
    for part in parts.values():
        payloads, rec = _apply(world, part, write=False)
        out.update((p.key, p) for p in payloads)  # a later part's payload is newer
        recs.append(rec)
    if write and world.held:
        world.commit_behind((), ())
    return sorted(out.values(), key=lambda p: p.key), Record(
        *(tuple(v for r in recs for v in getattr(r, f)) for f in Record._fields))


def _still(world, voxels, now, to) -> list:
    """(x, y, z, id, data) setting `to` for the voxels that hold `now` at present
    (after taking in what other processes wrote)."""
    world.writable()
    world.refresh()
    world.load({C.key_of(x, y) for x, y, _ in voxels}, warn=False)   # chunk_at refuses
    out = []
    with world.locked():
        for (x, y, z), n, t in zip(voxels, now, to):
            c = world.chunk_at(x >> 4, y >> 4)
            lx, ly = x & 15, y & 15
            if (int(c.blocks[lx, ly, z]), 0 if c.data is None else int(c.data[lx, ly, z])) \
                    == tuple(n):
                out.append((x, y, z, *t))
    return out


def check(world, changes) -> list[tuple[int, int, int, int, int]]:
    """(x, y, z, id, data) of every change, or a VoxelError before anything changes
    (World.set_block checks the same way)."""
    world.writable()
    if isinstance(changes, tuple) or (isinstance(changes, list) and changes
                                      and not isinstance(changes[0], (tuple, list))):
        changes = [changes]
    out = []
    for ch in changes:
        if len(ch) not in (4, 5):
            raise VoxelError(f"an edit is (x, y, z, block[, data]), got {ch!r}")
        x, y, z = (int(v) for v in ch[:3])
        b = ch[3]
        C.check_z(z)
        C.check_xy(x, y)
        if isinstance(b, str):
            b = REGISTRY.id(b)
        elif not 0 <= int(b) < len(REGISTRY):
            raise VoxelError(f"unknown block id {b}")
        d = int(ch[4]) if len(ch) == 5 else 0
        if not 0 <= d <= 0xFFFF:
            raise VoxelError(f"block data must be 0..65535, got {d}")
        k = C.key_of(x, y)
        if k in world.corrupt:
            raise VoxelError(f"chunk {k} is damaged in the file; it cannot be edited")
        out.append((x, y, z, int(b), d))
    return out


def _around(keys, r):
    return {(k[0] + i, k[1] + j) for k in keys for i in range(-r, r + 1) for j in range(-r, r + 1)}


def _ensure_lit(world, keys) -> list[Payload]:
    """Final light and mesh on every chunk of `keys` (lit in one batch if needed);
    returns the payloads of the chunks it lit."""
    out = []
    for _ in range(8):  # chunks may be unloaded meanwhile: try again
        with world.locked():
            todo = [k for k in keys if k not in world.corrupt and (
                world.chunks.get(k) is None or not world.chunks[k].has_light
                or world.chunks[k].mesh is None)]
        if not todo:
            return out
        xs, ys = [k[0] for k in todo], [k[1] for k in todo]
        payloads = build.light_and_mesh(world, min(xs), min(ys), max(xs) + 1, max(ys) + 1)
        for s in list(world.streams):
            s.offer(payloads)
        out += payloads
    raise VoxelError("could not light the chunks around the edit (they keep unloading)")


def _light_layers(world, items, sight=None):
    """Layers [z0, z1) that light.update may read or write for this stroke (call with
    the lock held). Its box reaches R + 1 above the voxel and R + 1 below the lowest
    voxel whose daylight changes, which lies above the highest opaque voxel under the
    column's lowest stroke voxel (daylight is 0 there before and after), as the light
    sees it (SIGHT: a world's resource stack, world/models.py)."""
    from ..light import incremental, model
    low: dict = {}
    for x, y, z, _, _ in items:
        low[(x, y)] = min(z, low.get((x, y), z))
    z0, z1 = C.HEIGHT, 0
    for (x, y), z in low.items():
        c = world.chunks[C.key_of(x, y)]
        if sight is None:   # a few layers down at the surface: walked in Python
            opaque, item, k = model.lists()[2], c.blocks.item, z - 1
            while k > 0 and not opaque[item(x & 15, y & 15, k)]:
                k -= 1
            z0 = min(z0, max(k, 0))
            continue
        col = c.blocks[x & 15, y & 15, :z]
        col = np.where(sight.opened(col, None if c.data is None
                                    else c.data[x & 15, y & 15, :z]), 0, col)
        below = np.flatnonzero(model.tables()[2][col])
        z0 = min(z0, int(below[-1]) if below.size else 0)
    z1 = max(z for _, _, z, _, _ in items) + incremental.R + 2
    return max(z0 - incremental.R - 1, 0), min(z1, C.HEIGHT)


class _Window(NamedTuple):
    """The voxel columns [x0, x1) x [y0, y1) the relight reads (every voxel's relight
    box with its rim), and the chunks an edit may remesh (`remesh`: a changed voxel's
    chunk and its face neighbours'; world/remesh.py reads them with their mesh ring)."""
    x0: int
    y0: int
    x1: int
    y1: int
    remesh: set


def _window(items) -> _Window:
    from ..light.incremental import R
    remesh = {C.key_of(x + i, y + j) for x, y, _, _, _ in items for i, j in
              ((0, 0), (-1, 0), (1, 0), (0, -1), (0, 1))}
    xs, ys = [it[0] for it in items], [it[1] for it in items]
    return _Window(min(xs) - R - 1, min(ys) - R - 1, max(xs) + R + 2, max(ys) + R + 2, remesh)


PART = 5   # columns on each side of a one-voxel stroke in its first relight window


def _part(world, items, win) -> _Window | None:
    """A one-voxel stroke that takes no lamp in or out is mostly relit near the voxel
    (light.update's local and sparse paths): its first relight window holds only
    the columns within PART of it (~1/9 of the whole window to copy, and of the
    packed sections to decode); None for other strokes."""
    if len(items) != 1:
        return None
    from ..light import incremental, model
    x, y, z, b, _ = items[0]
    emis = model.lists()[3]
    old = world.chunks[C.key_of(x, y)].blocks.item(x & 15, y & 15, z)
    if max(emis[b] + emis[old]) > incremental.SPARSE_EMISSION:
        return None
    return _Window(x - PART, y - PART, x + PART + 1, y + PART + 1, win.remesh)


def _apply(world, items, write=True):
    """The stroke in named steps, all under the world's lock once its 3x3 is lit
    (or what its part reads: _needed): set the voxels, relight, remesh, keep what
    changed, hand out payloads, write."""
    if not items:
        return [], Record((), (), ())
    near = _around({C.key_of(x, y) for x, y, _, _, _ in items}, 1)
    win = _window(items)
    sight = mcmodels.sight(world)   # None without a resource stack
    fresh: dict = {}
    need = _needed(world, items, win, near, sight)
    for _ in range(8):  # a chunk unloaded between lighting and locking: light again
        fresh.update({p.key: p for p in _ensure_lit(world, need)})
        with world.locked():
            if need is not near and any(k not in world.corrupt and world.chunks.get(k) is None
                                        for k in near):
                need = near   # (the remesh reads the 3x3's blocks)
                continue
            if any(k not in world.corrupt and (world.chunks.get(k) is None
                                               or not world.chunks[k].has_light)
                   for k in need):
                continue
            bad = sorted({C.key_of(x, y) for x, y, _, _, _ in items} & world.corrupt.keys())
            if bad:  # found damaged only now, loading it (check() knows loaded ones)
                raise VoxelError(f"chunk {bad[0]} is damaged in the file; it cannot be edited")
            # light.update reads and writes only layers [z0, z1) of the light and
            # blocks from z0 up (the daylight of a column comes from above)
            z0, z1 = _light_layers(world, items, sight)
            top = max(z for _, _, z, _, _ in items) + 1   # the stroke's writes, below
            part = None if sight is not None else _part(world, items, win)
            if part is None and need is not near:   # (the voxel changed meanwhile)
                need = near
                continue
            w0 = part or win
            blocks = _gather(world, w0.x0, w0.y0, w0.x1, w0.y1, "blocks", z0, writes=top,
                             name=part and "blocks_part")
            lit = _gather(world, w0.x0, w0.y0, w0.x1, w0.y1, "light", z0, z1)
            opened = None if sight is None else _opened(world, sight, blocks, win, items, z0)
            data = {C.key_of(x, y): world.chunks[C.key_of(x, y)].data for x, y, *_ in items}
            first, last, steps = _set_voxels(world, items)
            if not last:
                return sorted(fresh.values()), Record((), (), ())
            if opened is not None:   # the light sees the blocks the full solve sees
                blocks[opened] = 0
            relit = _relight(world, blocks, lit, steps, near, w0, (z0, z1), sight,
                             part is not None)
            if relit is None and need is not near and any(
                    k not in world.corrupt and (world.chunks.get(k) is None
                                                or not world.chunks[k].has_light)
                    for k in near):
                # the light leaves the part and the 3x3 is not all lit: the stroke
                # back out (nothing else changed yet), the 3x3 lit, then again
                for (x, y, z), (b, d) in first.items():
                    c = world.chunks[C.key_of(x, y)]
                    C.put(c.blocks, c.data, x & 15, y & 15, z, b, d)
                for k, a in data.items():
                    world.chunks[k].data = a
                need = near
                continue
            per: dict = {}
            for v in last:
                per.setdefault(C.key_of(v[0], v[1]), {})[v] = last[v]
            changed = set(per)
            t = world.tick()
            for k, vox in per.items():  # the rows go to the file through commit/hold
                world.blocks_changed(k, vox, edits=False, tick=t, relit=True)
            remeshed = _remesh(world, last, win, first)
            if relit is None:   # the light reads past the part: on the whole window
                blocks = _gather(world, win.x0, win.y0, win.x1, win.y1, "blocks", z0,
                                 writes=top)
                lit = _gather(world, win.x0, win.y0, win.x1, win.y1, "light", z0, z1)
                for (x, y, z), (b, _) in first.items():   # as before the stroke
                    blocks[x - win.x0, y - win.y0, z] = b
                relit = _relight(world, blocks, lit, steps, near, win, (z0, z1), sight)
            payloads = []
            for k in sorted(relit | remeshed):
                c = world.chunks[k]
                v = world.pver[k] = world.tick()
                payloads.append(Payload(k, c.mesh, c.light_kept(), v))
                fresh.pop(k, None)
        break
    else:
        raise VoxelError("could not light the chunks around the edit (they keep unloading)")
    rows = [(x, y, z, *last[(x, y, z)]) for x, y, z in last]
    # the changed chunks are written with their new light; relit neighbours' stored
    # light is dropped now and saved again with them later (marked changed)
    for s in list(world.streams):
        s.offer(payloads)
    (world.commit_behind if write else world.hold)(changed, rows, stale_light=relit - changed)
    voxels = [v for v in last if first[v] != last[v]]
    rec = Record(tuple(voxels), tuple(first[v] for v in voxels), tuple(last[v] for v in voxels))
    return sorted(payloads + list(fresh.values())), rec


def _needed(world, items, win, near, sight) -> set:
    """The chunks a stroke must find lit first: a one-voxel stroke relit on its part
    (_part) reads and writes only the light of the chunks its part covers and remeshes
    the chunks of `win.remesh`, so an edit next to chunks not lit yet (the edge of
    the streamed area) lights only those (4-9 ms less); the whole 3x3 (NEAR) where
    the light leaves the part (_apply then lights it and applies the stroke again),
    for other strokes, or while a chunk of the 3x3 is not loaded (the remesh reads
    its neighbours' blocks)."""
    if sight is not None or len(items) != 1:
        return near
    with world.locked():
        got = [world.chunks.get(k) for k in near]
        if None in got or all(c.has_light and c.mesh is not None for c in got):
            return near   # (all lit: nothing to leave out)
        part = _part(world, items, win)
    if part is None:
        return near
    return {(cx, cy) for cx in range(part.x0 >> 4, ((part.x1 - 1) >> 4) + 1)
            for cy in range(part.y0 >> 4, ((part.y1 - 1) >> 4) + 1)} | win.remesh


def _opened(world, sight, blocks, win, items, z0):
    """Window indices of the voxels the light passes although their project block
    holds it out (a rail stored as planks), over the columns the strokes' relight
    boxes read (their BLOCKS, the window, from layer Z0 up; call with the lock held,
    before the stroke is written)."""
    from ..light.incremental import R
    xs, ys = [it[0] for it in items], [it[1] for it in items]
    gx0, gy0 = max(min(xs) - R - 1, win.x0), max(min(ys) - R - 1, win.y0)
    gx1, gy1 = min(max(xs) + R + 2, win.x1), min(max(ys) + R + 2, win.y1)
    i, j = gx0 - win.x0, gy0 - win.y0
    data = _gather(world, gx0, gy0, gx1, gy1, "data", z0)
    got = np.nonzero(sight.opened(blocks[i:i + gx1 - gx0, j:j + gy1 - gy0, z0:],
                                  data[:, :, z0:]))
    return got[0] + i, got[1] + j, got[2] + z0


def _set_voxels(world, items):
    """Write the stroke into the chunks; returns ({voxel: (id, data) before},
    {voxel: (id, data) after}, [(x, y, z, id, data) of each change in order]) for
    the voxels that really changed."""
    first: dict = {}
    last: dict = {}
    steps = []
    for x, y, z, b, d in items:
        c = world.chunks[C.key_of(x, y)]
        lx, ly = x & 15, y & 15
        old = (int(c.blocks[lx, ly, z]), 0 if c.data is None else int(c.data[lx, ly, z]))
        if old == (b, d):
            continue
        first.setdefault((x, y, z), old)
        last[(x, y, z)] = (b, d)
        c.data = C.put(c.blocks, c.data, lx, ly, z, b, d)
        steps.append((x, y, z, b, d))   # data too: a state the light sees through
    return first, last, steps


def _relight(world, blocks, lit, steps, near, win, layers, sight=None,
             part=False) -> set | None:
    """Relight voxel by voxel (each update starts from the exact light of the blocks
    before it; `blocks` and `lit` are the window as the light sees it, changed in
    place; `lit` is the chunks' light over `layers`), then keep what changed inside
    the relit boxes on the chunks. Returns the keys relit; with `part` (the window is
    a _part) None where the light would read past it (nothing kept)."""
    from .. import light
    x0, y0 = win.x0, win.y0
    # the chunks' light as it was, for the compare below: lit's layers copied into a
    # scratch buffer (a chunk's own light may be packed: decoding it again cost more)
    za, zb = layers
    was = _gather(world, 0, 0, lit.shape[0], lit.shape[1], "light_was", fill=False)
    was[:, :, za:zb] = lit[:, :, za:zb]
    lo = [win.x1 - x0, win.y1 - y0, C.HEIGHT]  # union of the relit boxes
    hi = [0, 0, 0]
    seen = [b for _, _, _, b, _ in steps]
    if sight is not None and steps:   # a model block the light passes: air to it
        ids = np.array(seen, np.uint16)
        seen = np.where(sight.opened(ids, np.array([d for *_, d in steps], np.uint16)),
                        0, ids).tolist()
    for (x, y, z, _, _), b in zip(steps, seen):
        wx, wy = x - x0, y - y0
        old = int(blocks[wx, wy, z])
        if old == b:
            continue     # the same block to the light (a colour, a state it sees alike)
        blocks[wx, wy, z] = b
        box = light.update(blocks, lit, wx, wy, z, old, part)
        if box is None:
            return None
        lo = [min(v, sl.start) for v, sl in zip(lo, box)]
        hi = [max(v, sl.stop) for v, sl in zip(hi, box)]
    relit = set()
    if hi[0] <= lo[0]:
        return relit
    # only the relit boxes can differ (outside them lit holds the old light)
    for cx in range((lo[0] + x0) >> 4, ((hi[0] + x0 - 1) >> 4) + 1):
        for cy in range((lo[1] + y0) >> 4, ((hi[1] + y0 - 1) >> 4) + 1):
            c = world.chunks.get((cx, cy))
            if (cx, cy) not in near or c is None:
                continue
            i0, j0 = max(lo[0], cx * S - x0), max(lo[1], cy * S - y0)
            i1, j1 = min(hi[0], cx * S + S - x0), min(hi[1], cy * S + S - y0)
            box = (slice(i0 + x0 - cx * S, i1 + x0 - cx * S),
                   slice(j0 + y0 - cy * S, j1 + y0 - cy * S), slice(lo[2], hi[2]))
            new = lit[i0:i1, j0:j1, lo[2]:hi[2]]
            # changed, a new array (payloads out there keep theirs) rebuilt or
            # copied once
            if not np.array_equal(new, was[i0:i1, j0:j1, lo[2]:hi[2]]):
                a = c.light_copy()
                a[box] = new
                c.light = a
                c.dirty = True
                relit.add((cx, cy))
    return relit
