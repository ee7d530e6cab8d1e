"""Runs every area's benchmark, writes DIR/bench.csv (metric,value,unit,note) and plots.

Each area module `bench/<area>.py` defines `run(ctx)` returning an iterable of
(metric, value, unit, note) rows. Areas whose module is missing are skipped, so
the benchmark grows as the project does; an area that fails is reported and the
others still run.
"""
from __future__ import annotations

import csv
import importlib
import platform
import shutil
import sys
import tempfile
import time
import traceback
from pathlib import Path

AREAS = ["storage", "generation", "light", "meshing", "bake", "render", "world", "viewport", "edit",
         "far", "formats", "cluster"]


class Context:
    def __init__(self, out: Path, quick: bool):
        self.out = out
        self.quick = quick
        self.tmp = Path(tempfile.mkdtemp(prefix="voxel-bench-"))

    def say(self, msg: str) -> None:
        print(f"  {msg}", file=sys.stderr, flush=True)

    def plot(self, name: str, draw) -> Path:
        """Save a matplotlib figure drawn by draw(ax) as DIR/name.png."""
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 4), dpi=110)
        draw(ax)
        fig.tight_layout()
        path = self.out / f"{name}.png"
        fig.savefig(path)
        plt.close(fig)
        return path


def run(out: Path, areas: list[str] | None = None, quick: bool = False) -> Path:
    out.mkdir(parents=True, exist_ok=True)
    ctx = Context(out, quick)
    try:
        return _run(ctx, areas)
    finally:  # worlds and scratch files of every area: hundreds of MB per run
        shutil.rmtree(ctx.tmp, ignore_errors=True)


def _run(ctx: Context, areas: list[str] | None) -> Path:
    out = ctx.out
    rows = [("machine", 0, "", f"{platform.machine()} {platform.processor() or ''} "
             f"{__import__('os').cpu_count()} cores, Python {platform.python_version()}")]
    for area in areas or AREAS:
        try:
            mod = importlib.import_module(f".{area}", __package__)
        except ModuleNotFoundError as e:
            if e.name and e.name.endswith(f"bench.{area}"):
                continue
            raise
        print(f"bench: {area}", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        try:
            for row in mod.run(ctx):
                rows.append(tuple(row))
                print(f"  {row[0]} = {row[1]:.6g} {row[2]}  {row[3] if len(row) > 3 else ''}",
                      file=sys.stderr, flush=True)
        except Exception:  # a broken area must not hide the others' figures
            traceback.print_exc()
            rows.append((f"{area}_failed", 1, "", "see stderr"))
        rows.append((f"{area}_bench_seconds", time.perf_counter() - t0, "s", ""))
    path = out / "bench.csv"
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["metric", "value", "unit", "note"])
        for r in rows:
            w.writerow([r[0], f"{r[1]:.6g}" if isinstance(r[1], float) else r[1], r[2],
                        r[3] if len(r) > 3 else ""])
    return path
