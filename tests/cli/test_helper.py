"""cli.helper: fn on a helper process's main thread (bpy's rule) from any thread; its
errors come back; it goes when its parent is killed."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def main_thread() -> tuple[int, bool]:
    return os.getpid(), threading.current_thread() is threading.main_thread()


def test_calls_run_on_the_helpers_main_thread_and_errors_come_back():
    from voxel_addon.cli import helper
    got = []
    ts = [threading.Thread(target=lambda: got.append(helper.call(main_thread))) for _ in range(3)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    assert len(set(got)) == 1 and got[0][0] != os.getpid() and got[0][1]
    with pytest.raises(ValueError, match="invalid literal"):
        helper.call(int, "x")
    assert helper.call(main_thread) == got[0]  # the same helper, still there


PARENT = """
import os, sys
from voxel_addon.cli import helper
print(helper.call(os.getpid), flush=True)
sys.stdin.read()
"""


def test_the_helper_goes_with_its_killed_parent():
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.Popen([sys.executable, "-c", PARENT],
                         stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
    child = int(p.stdout.readline())
    os.kill(child, 0)  # alive
    p.kill()
    p.wait()
    t0 = time.monotonic()
    while True:
        try:
            os.kill(child, 0)
        except ProcessLookupError:
            break
        # a zombie until reaped by init counts as gone
        stat = Path(f"/proc/{child}/stat")
        if stat.exists() and stat.read_text().split(") ")[1].startswith("Z"):
            break
        assert time.monotonic() - t0 < 10, "the helper outlived its parent"
        time.sleep(0.05)
