"""The live view: the world drawn in Blender's 3D viewports and in renders, on Blender's
own gpu module (any backend). `LIVE` is the one LiveView (view.py); `sync` installs it
when a scene shows the view, `shutdown` removes everything it made, `redraw` asks the
viewports to draw again. Still frames into images: still.py. Whether and with what
we can draw: host.py."""
from __future__ import annotations

from .options import hours_of, settings_of, view_camera  # noqa: F401
from .view import LiveView, redraw  # noqa: F401

LIVE = LiveView()


def sync(context=None) -> None:
    """Install the draw handler when a scene shows the view (and the file handlers
    that drop it on File > New / Open); redraw viewports."""
    import bpy
    LIVE.sync()
    if LIVE.handle is not None and _load_pre not in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.append(bpy.app.handlers.persistent(_load_pre))
    if LIVE.handle is not None:
        for hs in _touched_by():
            if _touch not in hs:
                hs.append(bpy.app.handlers.persistent(_touch))


def _touched_by():
    """What may change the View panel's values without their update callbacks (which
    call sync): undo, redo, animation (a frame change, drivers), other edits of the
    scene. A redraw reads the panel only after one of them (LiveView.touch)."""
    import bpy
    h = bpy.app.handlers
    return (h.depsgraph_update_post, h.frame_change_post, h.undo_post, h.redo_post)


def _touch(*_):
    LIVE.touch()


def _load_pre(*_):
    """File > New / Open: drop the world's chunks and this file's state; the handler
    comes back when the new file shows the view (load_post)."""
    import bpy
    LIVE.close()
    if _load_post not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(bpy.app.handlers.persistent(_load_post))


def _load_post(*_):
    import bpy
    if _load_post in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_load_post)
    sync()


def shutdown() -> None:
    """Unregister: every handler, timer, thread (the stream's) and GPU object goes."""
    import bpy
    LIVE.close()
    for hs, fn in ((bpy.app.handlers.load_pre, _load_pre), (bpy.app.handlers.load_post, _load_post),
                   *((h, _touch) for h in _touched_by())):
        while fn in hs:
            hs.remove(fn)
    LIVE.stop_timers()
    LIVE.overlays.clear()
