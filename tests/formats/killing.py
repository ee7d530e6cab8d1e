"""A real `python -m voxel_addon import` process SIGKILLed at a commit point: inside
the Nth write of biome rows (storage/minecraft.py `put`), after the batch's chunk rows
and before its COMMIT, the moment a kill must not split a batch (`sig` SIGINT: a
Ctrl-C there instead, raised as KeyboardInterrupt right after `put`). CLUSTER: the
command's cluster writer (cluster/imports.py) with its tasks in the same process
(cluster.Serial, the workers' own functions), so no Dask cluster starts."""
from __future__ import annotations

import os
import re
import sqlite3
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

CHILD = r"""
import os, signal, sys
from contextlib import contextmanager
from voxel_addon import cluster
from voxel_addon.storage import minecraft as mcfile
at, calls, put = int(os.environ.get("KILL_AT", "0")), [0], mcfile.put
sig = getattr(signal, os.environ.get("KILL_SIG") or "SIGKILL")

def dying(db, rows):
    put(db, rows)
    calls[0] += 1
    if calls[0] == at:
        os.kill(os.getpid(), sig)

mcfile.put = dying
if os.environ.get("CLUSTER"):
    @contextmanager
    def session(args, say=None):
        yield cluster.Serial()
    cluster.session = session
from voxel_addon.cli import main
sys.exit(main(sys.argv[1:]))
"""


def run(world, src, *extra, kill_at=0, cluster=False, commit=2, sig="SIGKILL"):
    env = dict(os.environ, PYTHONPATH=str(ROOT), KILL_AT=str(kill_at), KILL_SIG=sig,
               VOXEL_COMMIT=str(commit), CLUSTER="1" if cluster else "")
    return subprocess.run([sys.executable, "-c", CHILD, "import", "--world", str(world),
                           "--from", str(src), *map(str, extra)],
                          capture_output=True, text=True, env=env, timeout=120)


def killed(world, src, *extra, kill_at=2, cluster=False):
    r = run(world, src, *extra, kill_at=kill_at, cluster=cluster)
    assert r.returncode == -9, (r.returncode, r.stderr)
    return r


def imported(stdout: str) -> int:
    m = re.search(r"^(\d+) chunks imported", stdout, re.M)
    assert m, stdout
    return int(m.group(1))


def table(path, sql) -> dict:
    with sqlite3.connect(path) as db:
        try:
            return {tuple(r[:2]): tuple(r[2:]) for r in db.execute(sql)}
        except sqlite3.OperationalError:   # no mc_biomes yet
            return {}


def chunks(path) -> dict:
    return table(path, "SELECT * FROM chunks")


def biomes(path) -> dict:
    return table(path, "SELECT * FROM mc_biomes")


def meta(path) -> dict:
    with sqlite3.connect(path) as db:
        return dict(db.execute("SELECT key, value FROM meta WHERE key != 'created'"))
