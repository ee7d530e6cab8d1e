"""Where an edit click's time goes (issue 29): the bench's 120 clicks (`world` area,
VOXEL_BENCH_EDITS_ONLY: a view-8 world, the same edits) with the editing thread's CPU
and its minor page faults timed around each step of world/edit.py, medians over the
80 non-lamp clicks and the 40 lamps, then the non-lamp clicks sorted (the bench's
median sits at their ~75th percentile).

    PYTHONPATH=. .venv/bin/python tools/edit_profile.py

A page fault (a fresh page's first write) costs ~2-3 us of thread CPU here: count
them. Compare trees in fresh processes, old and new alternating, CPU not wall.
"""
from __future__ import annotations

import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from voxel_addon import light  # noqa: E402
from voxel_addon.bench import world as bw  # noqa: E402
from voxel_addon.world import World  # noqa: E402
from voxel_addon.world import edit as E  # noqa: E402
from voxel_addon.world import remesh as RM  # noqa: E402
from voxel_addon.world import saving  # noqa: E402

STEPS: dict = {}   # label -> [(thread CPU s, minor faults) per call]


def _faults() -> int:
    return resource.getrusage(resource.RUSAGE_THREAD).ru_minflt


def timed(owner, name, label):
    f = getattr(owner, name)

    def g(*a, **k):
        c, p = time.thread_time(), _faults()
        try:
            return f(*a, **k)
        finally:
            STEPS.setdefault(label, []).append((time.thread_time() - c, _faults() - p))
    setattr(owner, name, g)


for n in ("_needed", "_ensure_lit", "_light_layers", "_part", "_gather", "_set_voxels",
          "_remesh", "_relight", "check"):
    timed(E, n, n)
for n in ("_cross", "_patch"):
    timed(RM, n, "remesh." + n)
timed(light, "update", "light.update")
for n in ("refresh", "commit_behind"):
    timed(saving.Saving, n, n)


def main() -> None:
    tmp = Path(tempfile.mkdtemp())
    bw._warm(tmp / "warm.sqlite")
    rows = []
    with World.create(tmp / "edits.sqlite", seed=bw.SEED) as w:
        s, _, _ = bw._stream(w, 8)
        for i, change in enumerate(bw.clicks(w, 120)):  # the bench's clicks
            kind = i % 3
            mark = {k: len(v) for k, v in STEPS.items()}
            c0, p0 = time.thread_time(), _faults()
            E.edit(w, change)
            t, p = time.thread_time() - c0, _faults() - p0
            steps = {k: np.sum(v[mark.get(k, 0):], axis=0) for k, v in STEPS.items()
                     if len(v) > mark.get(k, 0)}
            rows.append((kind == 1, t, p, steps, i))
            w.settle()
        s.close()
    for lamp, what in ((False, "non-lamp clicks"), (True, "lamp clicks")):
        sel = [r for r in rows if r[0] == lamp]
        print(f"{what}: {len(sel)}, thread CPU median {np.median([r[1] for r in sel]) * 1e3:.3f} "
              f"ms, page faults median {np.median([r[2] for r in sel]):.0f}")
        for k in sorted(STEPS):
            v = np.array([r[3].get(k, (0, 0)) for r in sel], float)
            print(f"  {k:22s} {np.median(v[:, 0]) * 1e3:7.3f} ms (mean {v[:, 0].mean() * 1e3:.3f})"
                  f"  faults {v[:, 1].mean():5.1f}")
    print("non-lamp clicks sorted: rank, ms, click, remesh / relight / gathers ms")
    for r, (_, t, _, st, i) in enumerate(sorted((r for r in rows if not r[0]),
                                                key=lambda r: r[1])):
        part = [st.get(k, (0, 0))[0] * 1e3 for k in ("_remesh", "_relight", "_gather")]
        print(f"  {r:2d} {t * 1e3:.3f} {i:3d} " + " / ".join(f"{v:.3f}" for v in part))


if __name__ == "__main__":
    main()
