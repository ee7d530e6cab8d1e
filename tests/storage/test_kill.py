"""SIGKILL a writer mid-save: the file still opens and every edit it reported saved is there."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from voxel_addon.world import World

ROOT = Path(__file__).resolve().parents[2]

WRITER = textwrap.dedent("""
    import sys
    from voxel_addon.world import World
    w = World.create(sys.argv[1], seed=5, generator="flat", loader=False)
    i = 0
    while True:
        # Many chunks per flush so the kill very likely lands inside a write.
        for k in range(40):
            n = i * 40 + k
            w.set_block((n * 7) % 400, (n * 13) % 400, 64 + n % 150, 1 + n % 20)
        w.flush()
        print(i, flush=True)   # edits up to batch i are reported saved
        i += 1
""")


def test_kill_during_save_keeps_reported_edits(tmp_path):
    path = tmp_path / "killed.sqlite"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen([sys.executable, "-c", WRITER, str(path)], stdout=subprocess.PIPE,
                            text=True, env=env)
    reported = -1
    t0 = time.monotonic()
    while reported < 25 and time.monotonic() - t0 < 120:
        line = proc.stdout.readline()
        if not line:
            break
        reported = int(line)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert reported >= 25, "writer did not get going"
    with World.open(path, loader=False) as w:
        assert w.file.db.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        for n in range((reported + 1) * 40):
            x, y, z = (n * 7) % 400, (n * 13) % 400, 64 + n % 150
            assert w.get_block(x, y, z) == 1 + n % 20, (n, x, y, z)
