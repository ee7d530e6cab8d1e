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
so killing Blender right after a stroke loses nothing. When the world file was
deleted or moved away while open, the stroke's edits go into the rescue file at
once (`saved`, session.save_failed) and the operator reports it as an error. A drag
keeps its parts in memory (shown at once) and writes them together when it ends: on
release, on Esc or right-click, when Blender cancels the operator (the window or
file closes) and, at the latest, when the world closes. The journal forgets what
Blender's own history can no longer reach (`Journal.trim`).
"""
from __future__ import annotations


# ---- the world side: world/edit.py does the work -----------------------------
STATS = {"edits": 0, "voxels": 0, "ms": 0.0, "last_ms": 0.0, "done": 0.0,
         "stroke_ms": 0.0}  # the stroke path's own time: edits and the write at its end


def apply(world, changes, write: bool = True):
    """Set `changes` ((x, y, z, block[, data]) tuples), relit and remeshed; returns
    (payloads for the viewport, world.edit.Record). write=True: one transaction now
    (a whole stroke); False: a part of a drag, written by `finish`."""
    import time
    from ..world import edit
    t = time.perf_counter()
    out = saved(world, lambda: edit.edit(world, list(changes), write))
    done = time.perf_counter()
    ms = (done - t) * 1e3
    STATS.update(edits=STATS["edits"] + 1, voxels=STATS["voxels"] + len(out[1].voxels),
                 ms=STATS["ms"] + ms, done=done, stroke_ms=STATS["stroke_ms"] + ms)
    if write:
        _stroke_done()
    return out


def finish(world) -> None:
    """Write a drag's held parts in one transaction (nothing held: nothing to do)."""
    import time
    from ..world import edit
    t = time.perf_counter()
    if world.held:
        saved(world, lambda: edit.write(world))
    ms = (time.perf_counter() - t) * 1e3
    STATS.update(ms=STATS["ms"] + ms, stroke_ms=STATS["stroke_ms"] + ms)
    _stroke_done()


def _stroke_done():
    STATS.update(last_ms=STATS["stroke_ms"], stroke_ms=0.0)


def undo(world, rec) -> list:
    from ..world import edit
    return saved(world, lambda: edit.undo(world, rec))


def redo(world, rec) -> list:
    from ..world import edit
    return saved(world, lambda: edit.redo(world, rec))


def saved(world, fn):
    """fn(), a change of `world` that writes it. When the write fails because the
    world file was deleted or moved away, the edits go to the rescue file at once
    and the world is let go (session.save_failed), raised as a VoxelError saying so;
    other failures (a full disk: saved later) go to the caller (session.refused)."""
    from . import session
    from ..core.errors import VoxelError
    try:
        out = fn()
        world.settle()  # a stroke is in the file before the operator returns
        return out
    except Exception as e:
        if world.file.db is None or not world.file.gone():
            raise
        raise VoxelError(session.save_failed(world, e)) from None


def merge(a, b):
    """One record for two parts of the same stroke (a drag): each voxel's first
    before and last after; voxels that ended as they began drop out."""
    from ..world.edit import Record
    first, last = dict(zip(a.voxels, a.before)), dict(zip(a.voxels, a.after))
    for v, bf, af in zip(b.voxels, b.before, b.after):
        first.setdefault(v, bf)
        last[v] = af
    vs = tuple(v for v in first if first[v] != last[v])
    return Record(vs, tuple(first[v] for v in vs), tuple(last[v] for v in vs))


def empty():
    from ..world.edit import Record
    return Record((), (), ())


# ---- the journal -------------------------------------------------------------
class Journal:
    """Stroke tree: serial -> (parent serial, world file path, record). One tree for
    every world, so undoing past a change of the scene's world file still undoes
    the strokes made in the file it named before."""

    def __init__(self, root: int = 0):
        self.nodes: dict[int, tuple] = {root: (None, None, None)}
        self.files: dict[int, object] = {}  # serial -> the file's identity when made
        self.applied = root      # the stroke whose state the world files hold
        self.next = root + 1

    def push(self, rec, path: str | None = None, file=None) -> int:
        s = self.next
        self.next += 1
        self.nodes[s] = (self.applied, path, rec)
        if file is not None:
            self.files[s] = file
        self.applied = s
        return s

    def trim(self, depth: int) -> None:
        """Forget strokes Blender's history can no longer reach: ancestors more than
        `depth` strokes above the applied one (its undo stack holds fewer steps), and
        dead branches (a new step after an undo drops Blender's redo tail, so the
        only redo path left is the newest child chain)."""
        keep = self._chain(self.applied)[:depth + 1]
        kids: dict = {}
        for s, (parent, _, _) in self.nodes.items():
            kids.setdefault(parent, []).append(s)
        s = self.applied
        while kids.get(s):
            s = max(kids[s])
            keep.append(s)
        keep = set(keep)
        self.nodes = {s: n for s, n in self.nodes.items() if s in keep}
        self.files = {s: f for s, f in self.files.items() if s in keep}
        for s, (parent, path, rec) in list(self.nodes.items()):
            if parent is not None and parent not in keep:
                self.nodes[s] = (None, path, rec)

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

    def go(self, world_of, target: int) -> list:
        """Bring the world files to `target` (world_of(path) -> World); returns the
        payloads of every step."""
        from ..core.errors import VoxelError
        payloads = []
        for op, s in self.route(target):
            parent, path, rec = self.nodes[s]
            w = world_of(path)
            made = self.files.get(s)
            if made is not None and getattr(w.file, "identity", made) != made:
                # another file was moved to the path since: the stroke's voxels
                # mean nothing there, and undoing them would write into it
                raise VoxelError(f"{path} is not the file this stroke was made in "
                                 "(replaced since): its undo is not applied there")
            payloads += undo(w, rec) if op == "undo" else redo(w, rec)
            self.applied = parent if op == "undo" else s
        return payloads


_journal: Journal | None = None


def journal(step: int) -> Journal:
    """The session's journal, started at the scene's current step."""
    global _journal
    if _journal is None:
        _journal = Journal(step)
    return _journal


def forget() -> None:
    """A new .blend: its undo history starts afresh, so does the journal."""
    global _journal
    _journal = None


# ---- Blender side ------------------------------------------------------------
def stroke(context, changes) -> int:
    """Apply one stroke to the scene's world, record it, and move the scene's step;
    returns the number of voxels changed (0: nothing recorded)."""
    sc = context.scene
    world = begin(context)
    payloads, rec = apply(world, changes)
    show(payloads)
    if not rec.voxels:
        return 0
    commit(sc, rec, world)
    return len(rec.voxels)


def begin(context):
    """Start a drag stroke: the world and its journal, reconciled with the scene."""
    from . import session
    sc = context.scene
    world = session.world(sc.voxel.path)
    if journal(sc.voxel_edit.step).applied != sc.voxel_edit.step:
        _reconcile(sc)  # a script set the step: follow it first
    return world


def commit(scene, rec, world=None) -> None:
    """Record a finished stroke made in WORLD: the scene's step names it (Blender's
    undo keeps that), the journal the file it was made in."""
    import bpy
    j = journal(scene.voxel_edit.step)
    scene.voxel_edit.step = j.push(rec, bpy.path.abspath(scene.voxel.path),
                                   None if world is None else world.file.identity)
    j.trim(max(32, bpy.context.preferences.edit.undo_steps) + 8)


def show(payloads) -> None:
    """Redraw the live viewport: world.edit already queued the payloads on every
    Stream of the world, so the viewport's next drain takes them in."""
    from . import liveview
    liveview.redraw()


def _reconcile(scene) -> None:
    from . import session
    j, target = _journal, scene.voxel_edit.step
    if j is None or j.applied == target:
        return
    from ..core.errors import explain
    try:
        payloads = j.go(session.world, target)
    except KeyError:  # a step from before this session's history: nothing to replay
        print(f"voxel: undo step {target} is not in this session's history")
        j.nodes.setdefault(target, (None, None, None))
        j.applied = target
        return
    except Exception as e:  # noqa: BLE001 - the file was deleted, is full, locked: say so,
        err = explain(e, scene.voxel.path)  # keep Blender's undo going
        if err is None:
            raise
        print(f"voxel: cannot follow undo in the world file: {err}")
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


NOT_SAVED = ("the stroke is shown but not in the file; the world saves it when it "
             "can, at the latest on closing (or keeps it beside the file)")


def refused(op, e: Exception) -> bool:
    """A stroke's failure on OP as one line (session.refused, saying the stroke stays
    shown and pending); False for a bug."""
    from . import session
    return session.refused(op, e, kept=NOT_SAVED)


def changed(op, edit) -> set:
    """An edit operator's result: edit() -> number of blocks changed; a VoxelError or
    a file's failure (session.refused) is the operator's one-line error, nothing
    changed cancels (no undo step)."""
    try:
        n = edit()
    except Exception as e:  # noqa: BLE001 - a full disk or locked file: one line too
        if not refused(op, e):
            raise
        return {"CANCELLED"}
    if not n:
        op.report({"INFO"}, "nothing changed")
        return {"CANCELLED"}
    return {"FINISHED"}
