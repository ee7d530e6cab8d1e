"""What the interpreter's exit does for the add-on (atexit): the streams and far
builders still open stop after the batch under way, and the background threads that
run OpenCL (the warm-up, the far prebuild: opencl.background) end the step under way
and start no other. A process that ended while pocl compiled or ran a kernel in
another thread aborted ("terminate called without an active exception", exit status
134): a script, or a Blender quitting seconds after Show. Then the worlds still open
save what their user changed (world.World.at_exit): a script that set blocks and
ended without close() lost them."""
from __future__ import annotations

import atexit
import threading
import time
import weakref

WAIT_S = 60.0  # the longest the exit waits for background threads (a cold build: seconds)
_exiting = threading.Event()
_open: weakref.WeakSet = weakref.WeakSet()   # objects whose close() the exit calls
_threads: list = []                          # threads the exit waits for
_last: weakref.WeakSet = weakref.WeakSet()   # objects whose at_exit() runs after those
_kept: set = set()   # those of _last with something to save: alive until then


class Exiting(Exception):
    """Raised in a background thread's wait once the interpreter exits: it stops."""


def exiting() -> bool:
    """Whether the interpreter is exiting: background work starts nothing new."""
    return _exiting.is_set()


def close_at_exit(obj) -> None:
    """Call obj.close() at exit if obj is still alive then (its threads stop)."""
    _open.add(obj)


def save_at_exit(obj, keep: bool = False) -> None:
    """Call obj.at_exit() at exit if obj is still alive then, once the objects of
    close_at_exit are closed and the waited threads ended (nothing uses it any more).
    KEEP: obj holds something to save, so it stays alive until the exit even when
    its user drops it (a script's world opened in a loop without close()); False
    again once saved."""
    _last.add(obj)
    if keep:
        _kept.add(obj)
    else:
        _kept.discard(obj)


def wait_at_exit(thread: threading.Thread) -> None:
    """Wait for THREAD at exit (it checks `exiting()` between its steps)."""
    _threads[:] = [t for t in _threads if t.is_alive()] + [thread]


def _at_exit() -> None:
    _exiting.set()
    for obj in list(_open):
        try:
            obj.close()
        except Exception:  # noqa: BLE001 - the exit goes on; the rest still closes
            pass
    end = time.monotonic() + WAIT_S
    for t in list(_threads):
        t.join(max(0.0, end - time.monotonic()))
    for obj in list(_last):  # (the kept ones are in it too)
        try:
            obj.at_exit()
        except Exception:  # noqa: BLE001 - at_exit says what failed itself; the rest saves
            pass


atexit.register(_at_exit)
