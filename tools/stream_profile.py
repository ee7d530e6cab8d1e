"""Where a stream's seconds go (issue 29): one view streamed from an empty file, then
reloaded from it, as the bench's `world` area does (its _warm and _stream), with
VOXEL_TRACE's spans summed per worker (wall and thread CPU of each batch phase) and
the process's CPU split by thread (the workers, pocl's threads, the consumer).

    PYTHONPATH=. .venv/bin/python tools/stream_profile.py [DISTANCE=32]

Run it in a fresh process per tree (old and new alternating) and compare CPU, not wall.
"""
from __future__ import annotations

import os
import sys
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path

os.environ["VOXEL_TRACE"] = "1"  # before the add-on reads it

PHASES = ("batch", "batch.load", "batch.snapshot", "batch.light", "batch.mesh",
          "batch.pack", "batch.store", "batch.compact")


def thread_cpu() -> dict:
    """{thread id: (name, CPU seconds)} from /proc (pocl's threads have no Python name)."""
    names = {t.native_id: t.name for t in threading.enumerate()}
    tick, out = os.sysconf("SC_CLK_TCK"), {}
    for tid in os.listdir("/proc/self/task"):
        try:
            st = open(f"/proc/self/task/{tid}/stat").read()
        except OSError:
            continue
        f = st[st.rindex(")") + 2:].split()
        out[int(tid)] = (names.get(int(tid), "pocl/other"), (int(f[11]) + int(f[12])) / tick)
    return out


def report(what, dt, cpu, before, after, events) -> None:
    print(f"{what}: wall {dt:.2f} s, process CPU {cpu:.2f} s")
    by = Counter()
    for tid, (name, c) in after.items():
        by[name] += c - before.get(tid, (name, 0.0))[1]
    print("  CPU by thread: " + ", ".join(f"{n} {c:.2f}" for n, c in by.most_common() if c > 0))
    for th in sorted({e[3] for e in events if e[3].startswith("voxel-stream")}):
        rows = []
        for ph in PHASES:
            xs = [e for e in events if e[3] == th and e[4] == ph]
            rows.append(f"{ph.split('.')[-1]} {sum(e[1] for e in xs):.2f}/{sum(e[2] for e in xs):.2f}")
        n = sum(1 for e in events if e[3] == th and e[4] == "batch")
        print(f"  {th} ({n} batches, wall/CPU s): " + ", ".join(rows))


def main() -> None:
    dist = int(sys.argv[1]) if len(sys.argv) > 1 else 32
    from voxel_addon.bench.world import _stream, _warm
    from voxel_addon.core import trace
    from voxel_addon.world import World
    tmp = Path(tempfile.mkdtemp())
    _warm(tmp / "warm.sqlite")
    for what in ("create", "reload"):
        trace.events.clear()
        t0, before = time.monotonic(), thread_cpu()
        w = World.create(tmp / "w.sqlite", seed=7) if what == "create" else World.open(tmp / "w.sqlite")
        s, dt, cpu = _stream(w, dist)
        after = thread_cpu()
        s.close()
        report(f"{what} view {dist}", dt, cpu, before, after, trace.since(t0))
        w.close()


if __name__ == "__main__":
    main()
