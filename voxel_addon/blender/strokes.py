"""Voxel strokes inside Blender's own undo history (issue 13).

Blender's undo snapshots datablocks, never the world file. So each stroke gets a
serial number, and the scene property `voxel_edit.step` holds the serial of the
last stroke the world should show; undo and redo restore that property with the
rest of the scene. A journal (per world file, in memory) keeps every stroke's undo
record and its parent stroke, i.e. a tree: after an undo and a new stroke, the old
branch stays in the tree but Blender's history no longer reaches it. The
`undo_post` / `redo_post` handlers walk the tree from the stroke the file holds to
the one the restored scene names (undo records up to the common ancestor, redo
records down), so one Ctrl+Z, a jump in the undo history, or ten undos in a row all
end in the same place; ordinary Blender steps (moving an object) leave the property
as it is and cost nothing. The handlers write only the world file, never Blender
data (which must not change while Blender restores it). A stack of our own beside
Blender's would fall out of step with it (RetopoFlow #1494); one number inside
Blender's snapshots cannot.

Each stroke reaches the world file in one transaction before the operator returns,
so killing Blender right after a stroke loses nothing that was shown.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field


# ---- the world side: the one place that changes blocks ---------------------
@dataclass
class Record:
    """Before and after of every changed voxel: (x, y, z, block, data) tuples."""
    before: list = field(default_factory=list)
    after: list = field(default_factory=list)

    def __len__(self):
        return len(self.after)

    def extend(self, other: "Record") -> None:
        """Append a later part of the same stroke (undo replays befores in reverse)."""
        self.before += other.before
        self.after += other.after


def apply(world, changes) -> tuple[list, Record]:
    """Set `changes` ((x, y, z, block_id[, data]) tuples) in one transaction;
    returns (payloads for the viewport, undo record). Unchanged voxels are left out."""
    from ..core import chunk as C
    from ..core.errors import VoxelError
    for x, y, z, *_ in changes:
        C.check_z(z)  # refuse before anything changes
    if world.readonly:
        raise VoxelError(f"{world.file.path} is open read-only")
    rec = Record()
    for x, y, z, b, *d in changes:
        c = world.chunk_at(x >> 4, y >> 4)
        old = (c.get(x & 15, y & 15, z), 0 if c.data is None else int(c.data[x & 15, y & 15, z]))
        new = (int(b), int(d[0]) if d else 0)
        if old == new:
            continue
        world.set_block(x, y, z, *new)
        rec.before.append((x, y, z, *old))
        rec.after.append((x, y, z, *new))
    if rec.after:
        world.flush()
    return [], rec


def undo(world, rec: Record) -> list:
    return apply(world, list(reversed(rec.before)))[0]


def redo(world, rec: Record) -> list:
    return apply(world, rec.after)[0]


# ---- the journal -------------------------------------------------------------
class Journal:
    """Stroke tree of one world file: serial -> (parent serial, record)."""

    def __init__(self, root: int = 0):
        self.nodes: dict[int, tuple[int | None, Record | None]] = {root: (None, None)}
        self.applied = root      # the stroke whose state the world file holds
        self.next = root + 1

    def push(self, rec: Record) -> int:
        s = self.next
        self.next += 1
        self.nodes[s] = (self.applied, rec)
        self.applied = s
        return s

    def _chain(self, s):
        out = []
        while s is not None:
            out.append(s)
            s = self.nodes[s][0]
        return out

    def route(self, target: int) -> list[tuple[str, int]]:
        """Steps from `applied` to `target`: ("undo", s)… up, then ("redo", s)… down."""
        if target not in self.nodes:
            raise KeyError(target)
        up, down = self._chain(self.applied), self._chain(target)
        common = next(s for s in up if s in set(down))
        return [("undo", s) for s in up[:up.index(common)]] + \
            [("redo", s) for s in reversed(down[:down.index(common)])]

    def go(self, world, target: int) -> list:
        """Bring the world file to `target`; returns the payloads of every step."""
        payloads = []
        for op, s in self.route(target):
            rec = self.nodes[s][1]
            payloads += undo(world, rec) if op == "undo" else redo(world, rec)
            self.applied = self.nodes[s][0] if op == "undo" else s
        return payloads


_journals: dict[str, Journal] = {}


def journal(path: str, step: int) -> Journal:
    """The journal of world file `path`, started at the scene's current step."""
    key = os.path.realpath(path)
    j = _journals.get(key)
    if j is None:
        j = _journals[key] = Journal(step)
    return j


def forget() -> None:
    """A new .blend: its undo history starts afresh, so do the journals."""
    _journals.clear()


# ---- Blender side ------------------------------------------------------------
def stroke(context, changes) -> int:
    """Apply one stroke to the scene's world, record it, and move the scene's step;
    returns the number of voxels changed (0: nothing recorded)."""
    import bpy
    from . import session
    sc = context.scene
    world = session.world(sc.voxel.path)
    j = journal(bpy.path.abspath(sc.voxel.path), sc.voxel_edit.step)
    if j.applied != sc.voxel_edit.step:  # a script set the step: follow it first
        _reconcile(sc)
    payloads, rec = apply(world, changes)
    if not len(rec):
        return 0
    commit(sc, rec)
    show(payloads)
    return len(rec)


def begin(context):
    """Start a drag stroke: the world and its journal, reconciled with the scene."""
    import bpy
    from . import session
    sc = context.scene
    world = session.world(sc.voxel.path)
    j = journal(bpy.path.abspath(sc.voxel.path), sc.voxel_edit.step)
    if j.applied != sc.voxel_edit.step:
        _reconcile(sc)
    return world


def commit(scene, rec: Record) -> None:
    """Record a finished stroke: the scene's step names it (Blender's undo keeps that)."""
    import bpy
    j = journal(bpy.path.abspath(scene.voxel.path), scene.voxel_edit.step)
    scene.voxel_edit.step = j.push(rec)


def show(payloads) -> None:
    """Hand new chunk payloads to the live viewport and redraw it."""
    import bpy
    try:
        from . import viewport  # the live view (issue 12), when present
    except ImportError:
        viewport = None
    if viewport is not None and hasattr(viewport, "update"):
        viewport.update(payloads)
    for win in getattr(bpy.context.window_manager, "windows", ()):
        for area in win.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()


def _reconcile(scene) -> None:
    import bpy
    from . import session
    path = scene.voxel.path
    if not session.is_open(path):
        return
    j = _journals.get(os.path.realpath(bpy.path.abspath(path)))
    target = scene.voxel_edit.step
    if j is None or j.applied == target:
        return
    try:
        payloads = j.go(session.world(path), target)
    except KeyError:  # a step from before this session's history: nothing to replay
        print(f"voxel: undo step {target} is not in this session's history")
        j.nodes.setdefault(target, (None, None))
        j.applied = target
        return
    show(payloads)


def on_undo_redo(scene, *_):
    import bpy
    sc = scene if hasattr(scene, "voxel_edit") else bpy.context.scene
    if sc is not None and hasattr(sc, "voxel_edit"):
        _reconcile(sc)


def on_load(*_):
    forget()


def register_handlers() -> None:
    import bpy
    from bpy.app.handlers import persistent
    h = bpy.app.handlers
    for lst, fn in ((h.undo_post, on_undo_redo), (h.redo_post, on_undo_redo),
                    (h.load_post, on_load)):
        if fn not in lst:
            lst.append(persistent(fn))


def unregister_handlers() -> None:
    import bpy
    h = bpy.app.handlers
    for lst in (h.undo_post, h.redo_post, h.load_post):
        for fn in [f for f in lst if getattr(f, "__module__", None) == __name__]:
            lst.remove(fn)
