"""Worlds opened from the UI, one per file path, shared by every panel and tool.

Opening is lazy and cached so the viewport, the edit tool and bake all see the same
World (and its chunk map). Closed on unregister and when the path changes.

A save that fails on closing (disk full, a file-size limit, a drive gone) is never
silent: it is reported in the status bar and the console, the world's unsaved edits
go into a file beside it (world/rescue.py; the temporary folder when that fails
too), and the next open applies them. When no rescue file can be written either, the
world stays open in memory (`unsaved`) so a later close retries. A save that fails
while the world is in use (a stroke's: its file deleted or moved away) goes the same
way at once (`save_failed`), and a world whose file is gone is let go.

Other processes may write the same file (another Blender, a command-line import):
a timer polls every open world about once a second (`World.refresh`: a pragma when
nothing changed) and redraws the viewports when it took in their chunks. The same
poll lets go of a world whose file was deleted, moved or replaced (a stat), or
found damaged (cut short, overwritten: the view stops drawing it and says so).
"""
from __future__ import annotations

import os
import time

_worlds: dict[str, object] = {}
unsaved: dict[str, object] = {}  # worlds whose save and rescue both failed (retried on close)
POLL_S = 1.0  # seconds between looks for other processes' writes


_keys: dict = {}  # (path, blend file, working folder) -> (_key, when) (asked on every redraw)
KEY_S = 1.0  # a symlink or folder changed meanwhile is seen within this


def _key(path: str) -> str:
    import bpy
    # realpath stats every folder of the path: ~0.1 ms, twice per viewport redraw
    k = (path, bpy.data.filepath, os.getcwd())
    now = time.monotonic()
    v = _keys.get(k)
    if v is None or now - v[1] > KEY_S:
        if len(_keys) > 64:
            _keys.clear()
        v = _keys[k] = (os.path.realpath(bpy.path.abspath(path)), now)
    return v[0]


def world(path: str, *, create_seed: int | None = None, generator: str | None = None):
    """The open World for `path`; created with `create_seed` if given and missing."""
    from ..core.errors import VoxelError
    from ..world import World
    if not path:
        raise VoxelError("no world file set (Voxel panel > World > File)")
    key = _key(path)
    w = _worlds.get(key)
    if w is not None:
        return w
    if create_seed is not None and not os.path.exists(key):
        os.makedirs(os.path.dirname(key) or ".", exist_ok=True)
        w = World.create(key, seed=create_seed, generator=generator or "overworld")
    else:
        if not os.path.exists(key):
            raise VoxelError(f"world file {key} does not exist (use New)")
        w = unsaved.pop(key, None)
        if w is None:
            w = World.open(key)
    _worlds[key] = w
    _restore(w, key)
    _start_polling()
    _warm(w)
    return w


def still_open(w) -> bool:
    """Whether the World w is still the open one of its path (a redraw's cheap check:
    no path resolved)."""
    return any(x is w for x in _worlds.values())


def _warm(w) -> None:
    """A fresh install's first kernel builds take ~4 s (issue 28): start them when a
    world opens (New, Open, a panel that needs it), so they are done by the time the
    user ticks Show; NumPy generates meanwhile. Not in background Blender (a script or
    a render wants no extra threads)."""
    import bpy
    if not bpy.app.background:
        from ..world.build import warm
        warm(w, opened=True)


def _start_polling() -> None:
    import bpy
    if not bpy.app.timers.is_registered(_poll):
        bpy.app.timers.register(_poll, first_interval=POLL_S, persistent=True)


_poll_told: dict[str, str] = {}  # path -> the poll's last failure (said once, not each second)
_suspect: dict[str, str] = {}  # path -> the damage its header showed at the last poll


def _poll():
    """Take in what other processes wrote to the open worlds; redraw if anything."""
    from ..core.errors import damaged
    got = False
    for key, w in list(_worlds.items()):
        try:
            if w.file.db is not None and w.file.gone():
                _let_go(key, w)
                got = True
                continue
            how = w.file.damage_seen() if w.file.db is not None else None
            if how is not None and _suspect.get(key) == how:  # (twice: see damage_seen)
                _let_go_damaged(key, w, how)
                got = True
                continue
            if how is None:
                _suspect.pop(key, None)
            else:
                _suspect[key] = how
            got |= bool(w.refresh())
            _poll_told.pop(key, None)
        except Exception as e:  # noqa: BLE001 - a poll must not kill the timer
            if damaged(e):
                _let_go_damaged(key, w, "cut short or overwritten")
                got = True
                continue
            if _poll_told.get(key) != str(e):
                _poll_told[key] = str(e)
                print(f"Voxel Worlds: could not look for changes in {key}: {e}")
    if got:
        from . import liveview
        liveview.redraw()
    return POLL_S if _worlds else None


def _let_go(key: str, w) -> None:
    """The poll found the file at KEY deleted, moved or replaced by another world
    (a copy over it): keeping ours open would show a world nobody can save to, and
    keep our old -wal beside a file it does not belong to. Its unsaved edits go to
    the rescue file (save_failed); the next look-up opens what is there now."""
    from ..core.errors import VoxelError
    try:
        w.file.check_path()
        return
    except VoxelError as e:
        if w.unsaved_edits():
            save_failed(w, e)
            return
        _worlds.pop(key, None)
        w.discard()
        tell(f"{e}; the view shows what is at that path now")


def _let_go_damaged(key: str, w, how: str) -> str:
    """The file at KEY was found damaged (HOW: cut short, overwritten): the view
    would draw on from memory a world that can be neither read nor saved. Its
    unsaved edits go to the rescue file (applied when a whole file is opened there
    again) and the world is let go: the next look-up opens the file anew and says
    it is not readable (the View panel, a stroke: one line). Returns the message."""
    from ..core.errors import VoxelError
    what = f"the file was damaged ({how}) while it was open; nothing more is written to it"
    msg = f"the world file {key}: {what}"
    _worlds.pop(key, None)
    _poll_told.pop(key, None)
    _suspect.pop(key, None)
    if w.unsaved_edits():
        msg = _save_failed(key, w, VoxelError(what))  # (says where they went)
        if unsaved.get(key) is w:  # not rescued: memory is all there is (close retries)
            return msg
        w.forget_unsaved()
    else:
        tell(msg)
    try:
        w.discard()
    except Exception:  # noqa: BLE001 - a damaged file may refuse even its close
        pass
    return msg


def broken(w, error: Exception) -> str | None:
    """A read or write of the open world W (the view's stream, a stroke) failed:
    when ERROR says its file is damaged, W is let go as the poll would
    (_let_go_damaged) and the one-line message returned; else None."""
    from ..core.errors import damaged
    if not damaged(error):
        return None
    key = next((k for k, x in _worlds.items() if x is w), None)
    if key is None:  # let go already (by the poll, another redraw)
        return (f"the world file {w.file.path}: the file was damaged (cut short or "
                "overwritten) while it was open; nothing more is written to it")
    return _let_go_damaged(key, w, "cut short or overwritten")


def save_failed(w, error: Exception) -> str:
    """A write of the open world W failed (a stroke's): as when closing fails, its
    unsaved edits go into the rescue file and the user is told; the edits rescued
    are not listed again. A world whose file is gone (deleted, moved away) is let
    go: nothing more can be written to it. Returns the message."""
    key = next((k for k, x in _worlds.items() if x is w), None) or \
        os.path.realpath(str(w.file.path))
    msg = _save_failed(key, w, error)
    if unsaved.get(key) is w:  # not rescued: memory is all there is, keep it open
        _worlds.pop(key, None)
        return msg
    w.forget_unsaved()
    if w.file.gone():
        _worlds.pop(key, None)
        w.discard()
    return msg


def _restore(w, key: str) -> None:
    """Apply the edits a failed save left beside the world (world/rescue.py)."""
    from ..world import rescue
    if not any(p.exists() for p in rescue.places(key)):
        return
    try:
        n, files = rescue.restore(w)
    except Exception as e:  # noqa: BLE001 - the world still opens; the file stays for later
        tell(f"could not apply the unsaved edits kept for {key}: {e}")
        return
    tell(f"{n} edits that could not be saved last time are back in {os.path.basename(key)} "
         f"(from {', '.join(str(f) for f in files)})", "INFO")


def close(path: str) -> str | None:
    """Close the world at PATH; when its save fails, what the user was told."""
    key = _key(path)
    w = _worlds.pop(key, None) or unsaved.pop(key, None)
    return None if w is None else _close(key, w)


def close_all() -> list[str]:
    """Close every world (unregister): one failing save does not stop the others,
    and none fails silently. What the user was told, one line per failed save."""
    import bpy
    if bpy.app.timers.is_registered(_poll):
        bpy.app.timers.unregister(_poll)
    todo = [*unsaved.items(), *_worlds.items()]
    unsaved.clear()
    _worlds.clear()
    told = [_close(key, w) for key, w in todo]  # one try each: a failure may go back to unsaved
    return [m for m in told if m]


def _close(key: str, w) -> str | None:
    try:
        w.close()
        return None
    except Exception as e:  # noqa: BLE001 - any failure to save must reach the user
        msg = _save_failed(key, w, e)
        if unsaved.get(key) is not w:  # rescued (or only terrain lost): closed unsaved,
            w.forget_unsaved()         # as the user was told (the interpreter's exit
            w.discard()                # would save it: World.at_exit)
        return msg


def _save_failed(key: str, w, error: Exception) -> str:
    from ..core.errors import cause
    from ..world import rescue
    n = len(w.unsaved_edits())
    msg = f"could not save {key}: {cause(error, key) or error}"
    if not n:  # generated chunks and light only: they come back from the seed
        msg += "; all your edits were saved before (only generated terrain was not)"
    else:
        try:
            where = rescue.write(w)
            msg += f"; its {n} unsaved edits are in {where} and come back when it is opened again"
        except OSError as e:
            unsaved[key] = w  # memory is all that is left: close again to retry
            msg += f"; its {n} unsaved edits could not be written anywhere ({e}): free space and save again"
    tell(msg)
    return msg


def tell(msg: str, kind: str = "ERROR") -> None:
    """MSG in the status bar (a report: also in the Info editor) and the console."""
    import sys
    print(f"Voxel Worlds: {msg}", file=sys.stderr, flush=True)
    try:
        import bpy
        bpy.ops.voxel.report(kind=kind, message=msg)
    except (RuntimeError, AttributeError):  # an ERROR report raises once it is filed;
        pass  # no operator (unregistered): the console line is what is left


def refused(op, e: Exception, path: str = "", kept: str = "") -> bool:
    """Report E on operator OP as one line when it is a user's or the file's failure
    (a VoxelError; a full disk, a read-only or locked file: core.errors.explain),
    and say True; False for anything else (a bug: the caller lets it raise)."""
    from ..core.errors import explain
    if not path:
        try:
            import bpy
            path = bpy.path.abspath(bpy.context.scene.voxel.path)
        except AttributeError:
            path = ""
    err = explain(e, path or None, "saving", kept)
    if err is None:
        return False
    op.report({"ERROR"}, str(err))
    return True


def discard(path: str) -> list[str]:
    """Close the world at PATH without saving and remove its file (and -wal, -shm):
    for a file an operator created and then failed to fill. The names removed."""
    key = _key(path)
    w = _worlds.pop(key, None) or unsaved.pop(key, None)
    if w is not None:
        try:
            if w.file.db is not None:
                w.file.close()  # first: close() then stops its threads without a save
            w.close()
        except Exception:  # noqa: BLE001 - the file goes anyway
            pass
    gone = []
    for p in (key, key + "-wal", key + "-shm", key + "-journal"):
        try:
            os.remove(p)
            gone.append(p)
        except OSError:
            pass
    return gone


def is_open(path: str) -> bool:
    return bool(path) and _key(path) in _worlds
