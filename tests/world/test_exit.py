"""A script's world left open at the interpreter's exit (World.at_exit, core/ending.py):
the blocks it set are saved (they were lost without close() or flush()); a save that
fails says so in one line and keeps the edits (world/rescue.py); a world whose folder
was cleaned away, or a process killed mid-way, leave no traceback and no damaged file.
Real child processes, real files."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import numpy as np

from voxel_addon.core.blocks import REGISTRY
from voxel_addon.world import World
from voxel_addon.world import rescue

_HEAD = r'''
import os, shutil, sys, numpy as np
from voxel_addon.world import Stream, World
path, how = sys.argv[1], sys.argv[2]
w = World.create(path, seed=3, backend="numpy", idle_timeout=60)
if how == "stream":  # a stream at work too: it stops first, then the world saves
    s = Stream(w, 1)
    s.set_view(8.0, 8.0)
w.load([(0, 0), (2, -1)])
w.flush()  # stored chunks: their own changes are written as chunks, not only as edits
w.set_blocks([[1, 2, 100], [40, -3, 101]], [STONE, STONE])
w.set_block(5, 5, 120, "glass")
'''
_TAILS = {
    "plain": "",
    "stream": "",  # still at work when the script ends
    "gone": "shutil.rmtree(os.path.dirname(path))\n",
    "full": ("import resource, signal\nsignal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
             "resource.setrlimit(resource.RLIMIT_FSIZE, (4096, resource.RLIM_INFINITY))\n"),
    "kill": "w.flush()\nw.set_block(6, 6, 130, 'glass')\nprint('set', flush=True)\n"
            "import time\ntime.sleep(60)\n",
}
_SET = {(1, 2, 100): "stone", (40, -3, 101): "stone", (5, 5, 120): "glass"}


def _child(tmp_path, how, path=None):
    path = path or tmp_path / "w.sqlite"
    code = (_HEAD + _TAILS[how]).replace("STONE", str(REGISTRY.id("stone")))
    env = dict(os.environ, TMPDIR=str(tmp_path / "tmp"))  # a rescue there is seen
    (tmp_path / "tmp").mkdir(exist_ok=True)
    return path, [sys.executable, "-c", code, str(path), how], env


def _blocks(path) -> dict:
    with World.open(path, backend="numpy", loader=False) as w:
        return {v: REGISTRY[w.get_block(*v)].name for v in _SET}


def test_blocks_set_without_close_are_saved_at_exit(tmp_path):
    for how in ("plain", "stream"):
        path, cmd, env = _child(tmp_path, how, tmp_path / f"{how}.sqlite")
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env)
        assert r.returncode == 0 and not r.stderr, r.stderr[-2000:]
        assert _blocks(path) == _SET, how
        assert not os.listdir(tmp_path / "tmp")


def test_a_save_that_fails_at_exit_keeps_the_edits_and_says_so(tmp_path):
    path, cmd, env = _child(tmp_path, "full")
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr[-2000:]
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "could not save" in lines[0], r.stderr
    kept = rescue.places(path)[0]
    assert str(kept) in lines[0]
    edits = {tuple(e[:3]): e[3] for e in json.loads(kept.read_text())["edits"]}
    assert all(edits[v] == name for v, name in _SET.items())
    assert len(edits) == 3


def test_a_world_whose_folder_was_cleaned_away_exits_quietly(tmp_path):
    path, cmd, env = _child(tmp_path, "gone", tmp_path / "gone" / "w.sqlite")
    path.parent.mkdir()
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr[-2000:]
    assert len(r.stderr.strip().splitlines()) == 1 and "folder is gone" in r.stderr
    assert not os.listdir(tmp_path / "tmp")  # no rescue file nobody will open


def test_a_process_killed_after_setting_blocks_leaves_a_file_that_opens(tmp_path):
    path, cmd, env = _child(tmp_path, "kill")
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        assert p.stdout.readline().strip() == "set", p.stderr.read()
        p.send_signal(signal.SIGKILL)
    finally:
        p.wait(30)
    assert _blocks(path) == _SET  # flushed before the kill: all there
    with World.open(path, backend="numpy", loader=False) as w:
        assert w.get_block(6, 6, 130) in (0, REGISTRY.id("glass"))
        assert np.all(w.region_blocks(-1, -1, 3, 1)[:, :, 0] > 0)  # chunks decode


def test_a_script_that_changed_nothing_exits_without_waiting_for_another_writer(tmp_path):
    import sqlite3
    path = tmp_path / "w.sqlite"
    World.create(path, seed=3, backend="numpy", loader=False).close()
    db = sqlite3.connect(path, isolation_level=None)
    db.execute("BEGIN IMMEDIATE")  # another program's long write (a generate, an import)
    try:
        code = ("import sys\nfrom voxel_addon.world import World\n"
                "w = World.open(sys.argv[1], backend='numpy')\nprint(w.get_block(3, 3, 2))\n")
        r = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True,
                           text=True, timeout=20, env=dict(os.environ, VOXEL_LOCK_TIMEOUT="60"))
    finally:
        db.execute("ROLLBACK")
        db.close()
    assert r.returncode == 0 and not r.stderr, r.stderr[-2000:]  # generated chunks: not saved


_FORK = r'''
import os, sqlite3, sys
from voxel_addon.world import World
w = World.create(sys.argv[1], seed=3, backend="numpy", loader=False)  # (no thread: no
w.set_block(5, 5, 120, "glass")                   # warning about forking one on 3.12)
pid = os.fork()
if pid == 0:
    sys.exit(0)  # a forked child's normal exit runs the atexit handlers it inherited
os.waitpid(pid, 0)
db = sqlite3.connect(sys.argv[1])
print("edits after the child:", db.execute("SELECT COUNT(*) FROM edits").fetchone()[0], flush=True)
db.close()
'''


def test_a_forked_childs_exit_leaves_its_parents_world_alone(tmp_path):
    # the child would write with its parent's SQLite connection (unsafe across a
    # fork) or wait forever on a lock another thread held at the fork
    path = tmp_path / "w.sqlite"
    r = subprocess.run([sys.executable, "-c", _FORK, str(path)], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0 and not r.stderr, r.stderr[-2000:]
    assert "edits after the child: 0" in r.stdout, r.stdout
    with World.open(path, backend="numpy", loader=False) as w:  # the parent's own exit saved
        assert REGISTRY[w.get_block(5, 5, 120)].name == "glass"


_DROPPED = r'''
import sys
from voxel_addon.world import World
for i, p in enumerate(sys.argv[1:]):  # each world dropped unclosed when the next opens
    w = World.create(p, seed=3, backend="numpy", loader=False)
    w.set_blocks([[1, 2, 100], [40, -3, 101]], [1, 1])
    w.set_block(5, 5, 120, "glass")
    if i == 0:
        w.flush()  # saved: nothing keeps it alive any more
        w.set_block(5, 5, 121, "glass")
del w
import gc
gc.collect()
'''


def test_worlds_dropped_without_close_are_saved_at_exit(tmp_path):
    # without a loader thread nothing kept a dropped world alive: garbage-collected,
    # its blocks were gone before the exit could save them
    paths = [tmp_path / f"w{i}.sqlite" for i in range(3)]
    r = subprocess.run([sys.executable, "-c", _DROPPED, *map(str, paths)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and not r.stderr, r.stderr[-2000:]
    for p in paths:
        with World.open(p, backend="numpy", loader=False) as w:
            names = [REGISTRY[w.get_block(*v)].name for v in [(1, 2, 100), (40, -3, 101),
                                                               (5, 5, 120)]]
            assert names == ["stone", "stone", "glass"], (p, names)
            if p == paths[0]:
                assert REGISTRY[w.get_block(5, 5, 121)].name == "glass"


def test_a_saved_world_is_not_kept_alive():
    import gc
    import weakref
    import tempfile
    from voxel_addon.core import ending
    with tempfile.TemporaryDirectory() as d:
        w = World.create(f"{d}/w.sqlite", seed=3, backend="numpy", loader=False)
        w.set_block(1, 1, 100, "glass")
        assert w in ending._kept
        w.flush()
        assert w not in ending._kept
        w.set_block(1, 1, 101, "glass")
        w.close()
        ref = weakref.ref(w)
        del w
        gc.collect()
        assert ref() is None  # closed: nothing holds it
