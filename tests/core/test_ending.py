"""core/ending.py: at the interpreter's exit the streams and far builders still open
stop (their workers join after the batch under way). A worker left running in a
kernel when the process ended aborted it in pocl ("terminate called without an active
exception", status 134: a script that did not close its stream, 1 of 5 exits)."""
from __future__ import annotations

import subprocess
import sys

_CHILD = r'''
import atexit, sys, tempfile, time
from pathlib import Path
seen = {}
# registered first, so it runs last: after the add-on's exit handler
atexit.register(lambda: print("alive after exit:", {k: any(t.is_alive() for t in v)
                                                    for k, v in seen.items()}, flush=True))
from voxel_addon.far import Builder
from voxel_addon.world import Stream, World
w = World.create(Path(tempfile.mkdtemp()) / "w.sqlite", seed=5, generator="overworld")
s = Stream(w, 3)
s.set_view(8.0, 8.0)
b = Builder(w.file, w.generator)
b.set_view(8.0, 8.0, far=16, near=3)
seen["stream"], seen["far"] = s._threads, [b._thread]
time.sleep(0.3)  # both at work; the script ends without closing anything
'''


def test_open_streams_and_far_builders_stop_at_exit(tmp_path):
    r = subprocess.run([sys.executable, "-c", _CHILD], capture_output=True, text=True,
                       timeout=120, cwd=tmp_path)
    assert r.returncode == 0 and "terminate" not in r.stderr, r.stderr[-2000:]
    assert "alive after exit: {'stream': False, 'far': False}" in r.stdout, r.stdout
