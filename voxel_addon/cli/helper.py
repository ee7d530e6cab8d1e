"""call(fn, *args): fn(*args) on the main thread of a helper process of this one.

bpy works only on a process's main thread (from another it crashes the process), and
a Dask worker runs its tasks on other threads. Its processes are daemons, which
multiprocessing may not give children, so the helper is a plain subprocess that
talks over a local connection (pickles: fn is sent by name). One helper per process,
kept for the next call; it ends when its parent goes (the connection closes), even
when the parent is killed. Calls from several threads are served one at a time."""
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
    """The helper, connected back to a one-use listener on 127.0.0.1 (any platform: no
    descriptors are inherited); the key it answers with comes on its stdin."""
    global _conn, _proc
    from multiprocessing.connection import Listener
    key = os.urandom(32)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    with Listener(("127.0.0.1", 0), authkey=key) as ls:
        host, port = ls.address
        _proc = subprocess.Popen([sys.executable, "-m", __name__, host, str(port)], env=env,
                                 stdin=subprocess.PIPE, stdout=subprocess.DEVNULL)
        _proc.stdin.write(key.hex().encode() + b"\n")
        _proc.stdin.close()
        got: list = []

        def accept():
            try:
                got.append(ls.accept())
            except (OSError, EOFError, ValueError):  # ended below, or not our helper
                pass
        t = threading.Thread(target=accept, daemon=True)
        t.start()
        while t.is_alive() and _proc.poll() is None:
            t.join(0.1)
        if not got:  # it died before it called back
            if t.is_alive():
                socket.create_connection((host, port)).close()  # end the accept
            raise RuntimeError(f"the helper process ended at its start ({_proc.poll()})")
        _conn = got[0]


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


def _serve(host: str, port: int) -> None:
    from multiprocessing.connection import Client
    key = bytes.fromhex(sys.stdin.readline().strip())
    conn = Client((host, port), authkey=key)
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
    _serve(sys.argv[1], int(sys.argv[2]))
