"""call(fn, *args): fn(*args) on the main thread of a helper process of this one.

bpy works only on a process's main thread (from another it crashes the process), and
a Dask worker runs its tasks on other threads. Its processes are daemons, which
multiprocessing may not give children, so the helper is a plain subprocess that
talks over a socket pair (pickles: fn is sent by name). One helper per process, kept
for the next call; it ends when its parent goes (the socket closes), even when the
parent is killed. Calls from several threads are served one at a time."""
from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading

_lock = threading.Lock()
_conn = None
_proc = None


def _start():
    global _conn, _proc
    from multiprocessing.connection import Connection
    mine, theirs = socket.socketpair()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    _proc = subprocess.Popen([sys.executable, "-m", __name__, str(theirs.fileno())],
                             pass_fds=(theirs.fileno(),), env=env, stdin=subprocess.DEVNULL,
                             stdout=subprocess.DEVNULL)
    theirs.close()
    _conn = Connection(mine.detach())


def call(fn, *args):
    """fn(*args) in the helper (fn: a module-level function); its exception is raised
    here. A helper that died is started again for the next call."""
    global _conn
    with _lock:
        if _conn is None or _proc.poll() is not None:
            _start()
        try:
            _conn.send((fn, args))
            ok, value = _conn.recv()
        except (EOFError, OSError):
            _conn = None
            raise RuntimeError("the helper process died") from None
    if not ok:
        raise value
    return value


def _serve(fd: int) -> None:
    from multiprocessing.connection import Connection
    conn = Connection(fd)
    while True:
        try:
            fn, args = conn.recv()
        except (EOFError, OSError):  # the parent is gone
            return
        try:
            out = (True, fn(*args))
        except Exception as e:  # noqa: BLE001 - handed to the caller
            out = (False, e)
        try:
            conn.send(out)
        except (EOFError, OSError):
            return


if __name__ == "__main__":
    _serve(int(sys.argv[1]))
