"""bench --baseline REV: the same areas at another revision, alternating with this tree.

Absolute times mean little on a shared machine; a ratio of two runs made side by side
does. REV is checked out as a temporary detached git worktree (removed after) and both
trees run under this interpreter (same venv), each area in a fresh subprocess, the
order swapped every round (A B, B A, ...) so that a drift in the machine's load hits
both sides alike. DIR/bench.csv gets one row per metric: both medians, the median of
the per-round ratios new/base and their spread, and which way is better.
"""
from __future__ import annotations

import csv
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ..core.errors import VoxelError

ROOT = Path(__file__).resolve().parents[2]   # this tree: voxel_addon/ lives here
# --quick without --area: a minute's worth that still sees the paths a user waits on.
QUICK_AREAS = ["storage", "world"]
# Rows that describe the run, not the code: never compared.
_SKIP = ("_bench_seconds", "_failed")
_LOWER = ("s", "ms", "us", "ns", "B", "KiB", "MiB", "GiB", "B/voxel", "B/chunk", "%")


def better(metric: str, unit: str) -> str:
    """'higher' for rates, 'lower' for times and sizes, '' when the row does not say."""
    if "/s" in unit or "per_s" in metric or unit.endswith("x") or unit == "fps":
        return "higher"
    if unit in _LOWER or metric.endswith(("_s", "_ms", "_us", "_bytes", "_per_voxel")):
        return "lower"
    return ""


def _git(*args, cwd=ROOT) -> str:
    r = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True)
    if r.returncode:
        why = (r.stderr.strip().splitlines() or [f"exit {r.returncode}"])[-1]
        raise VoxelError(f"git {args[0]}: {why}")
    return r.stdout.strip()


def _read(path: Path) -> dict:
    """metric -> (value, unit, note) from one side's bench.csv."""
    rows = {}
    with path.open(newline="") as f:
        for r in csv.DictReader(f):
            if r["metric"] == "machine" or r["metric"].endswith(_SKIP):
                continue
            try:
                rows[r["metric"]] = (float(r["value"]), r["unit"], r["note"])
            except ValueError:
                pass
    return rows


def _side(tree: Path, area: str, quick: bool, out: Path) -> dict:
    """One area in a fresh interpreter with tree first on the path; {} when it failed
    (an area the baseline does not have, or a crash: its rows count as missing)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(tree)
    cmd = [sys.executable, "-m", "voxel_addon", "bench", "--out", str(out), "--area", area]
    if quick:
        cmd.append("--quick")
    shutil.rmtree(out, ignore_errors=True)  # never read an earlier invocation's CSV
    r = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
    out.mkdir(parents=True, exist_ok=True)
    (out / "stderr.txt").write_text(r.stdout + r.stderr)
    if r.returncode or not (out / "bench.csv").exists():
        print(f"  {area} at {tree.name}: failed (exit {r.returncode}), see {out / 'stderr.txt'}",
              file=sys.stderr, flush=True)
        return {}
    return _read(out / "bench.csv")


def run(out: Path, rev: str, areas: list[str] | None, quick: bool, rounds: int) -> Path:
    from .runner import AREAS
    if rounds < 1:
        raise VoxelError("--rounds must be at least 1")
    try:
        sha = _git("rev-parse", "--verify", "--quiet", f"{rev}^{{commit}}")
    except VoxelError:
        raise VoxelError(f"--baseline {rev}: not a revision of this repository") from None
    areas = areas or (QUICK_AREAS if quick else AREAS)
    out.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix="voxel-baseline-"))
    base = tmp / "tree"
    _git("worktree", "add", "--detach", "--quiet", str(base), sha)
    per = {"base": {}, "new": {}}       # side -> metric -> [value per round]
    meta = {}                           # metric -> (unit, note), the new side's when it has one
    try:
        t0 = time.perf_counter()
        for i in range(rounds):
            for area in areas:
                order = ("base", "new") if i % 2 == 0 else ("new", "base")
                for side in order:
                    tree = base if side == "base" else ROOT
                    print(f"bench: round {i + 1}/{rounds} {area} {side}", file=sys.stderr, flush=True)
                    rows = _side(tree, area, quick, out / "runs" / f"{area}-{side}-{i + 1}")
                    for m, (v, unit, note) in rows.items():
                        per[side].setdefault(m, [None] * rounds)[i] = v
                        if side == "new" or m not in meta:
                            meta[m] = (unit, note)
        seconds = time.perf_counter() - t0
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT,
                       capture_output=True)
        shutil.rmtree(tmp, ignore_errors=True)
    rows = compare(per, meta)
    path = out / "bench.csv"
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["metric", "unit", "base", "new", "ratio", "ratio_min", "ratio_max",
                    "spread_pct", "rounds", "better", "note"])
        w.writerow(["baseline", "", "", "", "", "", "", "", rounds, "",
                    f"{rev} ({sha[:10]}) vs the working tree at {ROOT.name}, areas "
                    f"{' '.join(areas)}{' (quick)' if quick else ''}, {seconds:.0f} s"])
        for r in rows:
            w.writerow([_fmt(x) for x in r])
    _plot(out, rows, rev)
    return path


def compare(per: dict, meta: dict) -> list[tuple]:
    """(metric, unit, base median, new median, ratio, min, max, spread %, rounds, better,
    note) per metric: ratio = new / base, the median of the rounds' own ratios (each
    round's two runs were side by side); missing values are None."""
    rows = []
    for m in sorted(set(per["new"]) | set(per["base"])):
        unit, note = meta[m]
        b = [v for v in per["base"].get(m, []) if v is not None]
        n = [v for v in per["new"].get(m, []) if v is not None]
        pairs = [nv / bv for bv, nv in zip(per["base"].get(m, []), per["new"].get(m, []))
                 if bv is not None and nv is not None and bv != 0]
        bm = statistics.median(b) if b else None
        nm = statistics.median(n) if n else None
        if not b:
            note = "new metric (not in the baseline); " + note
        elif not n:
            note = "gone (only in the baseline); " + note
        if pairs:
            ratio, lo, hi = statistics.median(pairs), min(pairs), max(pairs)
            spread = 100 * (hi - lo) / 2 / ratio if ratio else None
        else:
            ratio = lo = hi = spread = None
        rows.append((m, unit, bm, nm, ratio, lo, hi, spread, len(pairs), better(m, unit), note))
    return rows


def _fmt(x):
    return f"{x:.6g}" if isinstance(x, float) else ("" if x is None else x)


def _plot(out: Path, rows: list, rev: str) -> None:
    """Ratios as 'times better' (>1 is better whichever way the metric goes), with the
    rounds' spread, in DIR/baseline.png."""
    shown = [r for r in rows if r[4] and r[9]]
    if not shown:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    gain = [(r[4] if r[9] == "higher" else 1 / r[4]) for r in shown]
    lo = [(r[5] if r[9] == "higher" else 1 / r[6]) for r in shown]
    hi = [(r[6] if r[9] == "higher" else 1 / r[5]) for r in shown]
    fig, ax = plt.subplots(figsize=(8, 0.28 * len(shown) + 1.2), dpi=110)
    y = range(len(shown))
    ax.barh(y, gain, color=["tab:green" if g >= 1 else "tab:red" for g in gain],
            xerr=[[g - a for g, a in zip(gain, lo)], [b - g for g, b in zip(gain, hi)]])
    ax.axvline(1.0, color="k", lw=0.8)
    ax.set_yticks(list(y), [r[0] for r in shown], fontsize=7)
    ax.set_xlabel(f"times better than {rev} (median of rounds, bars: min-max)")
    fig.tight_layout()
    fig.savefig(out / "baseline.png")
    plt.close(fig)
