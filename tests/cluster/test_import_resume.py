"""The cluster import's writer (cluster/imports.py) SIGKILLed at a commit point and
run again: a batch's chunks, biome rows, palettes and note (meta `import_job`,
formats/job.py, the one-process import's too) are one
transaction, so the resumed import leaves every chunk with its biome rows and equals
an uninterrupted one; two imports into one world, both killed, both resume (one
note each; an older file's single note is read too)."""
from __future__ import annotations

import json
import re
import sqlite3

import pytest

from voxel_addon.bench import mcsave
from tests.formats import killing as K
from tests.formats import mcfiles as mc

N = 3   # 9 chunks a save; VOXEL_COMMIT 2: five commits


def _computed(stderr):
    return int(re.search(r"workers read (\d+) chunks", stderr).group(1))


def _note(path):
    with sqlite3.connect(path) as db:
        return db.execute("SELECT value FROM meta WHERE key='import_job'").fetchone()[0]


@pytest.fixture(scope="module")
def saves(tmp_path_factory):
    d = tmp_path_factory.mktemp("resume")
    a = mcsave.save(d / "a", N)
    b = d / "b" / "region"
    b.mkdir(parents=True)
    (b / "r.1.0.mca").write_bytes(mcsave.region(N, 1, 0))   # chunks beside a's
    return d, a, b.parent


def test_killed_then_resumed_keeps_every_chunks_biomes(saves, tmp_path):
    d, a, _ = saves
    want = d / "a.sqlite"
    if not want.exists():
        r = K.run(want, a, cluster=True)
        assert r.returncode == 0 and K.imported(r.stdout) == N * N, r.stderr
    w = tmp_path / "w.sqlite"
    K.killed(w, a, kill_at=2, cluster=True)   # inside the second commit
    done = len(K.chunks(w))
    assert 0 < done < N * N and set(K.biomes(w)) == set(K.chunks(w))
    notes = json.loads(_note(w))
    with sqlite3.connect(w) as db:   # as an older version wrote it: one object
        db.execute("UPDATE meta SET value=? WHERE key='import_job'",
                   (json.dumps(notes[0] if isinstance(notes, list) else notes),))
    r = K.run(w, a, cluster=True)
    assert r.returncode == 0, r.stderr
    assert _computed(r.stderr) == N * N - done and K.imported(r.stdout) == N * N - done
    assert f"resuming an interrupted import: {done} of {N * N} chunks" in r.stderr  # one process's
    assert K.chunks(w) == K.chunks(want) and K.biomes(w) == K.biomes(want)
    assert K.meta(w) == K.meta(want) and not _note(w)


def test_two_imports_into_one_world_both_killed_both_resume(saves, tmp_path):
    d, a, b = saves
    want = tmp_path / "want.sqlite"
    for src in (a, b):
        assert K.run(want, src, cluster=True).returncode == 0
    w = tmp_path / "w.sqlite"
    K.killed(w, a, kill_at=2, cluster=True)
    first = len(K.chunks(w))
    K.killed(w, b, kill_at=2, cluster=True)
    second = len(K.chunks(w)) - first
    assert 0 < first < N * N and 0 < second < N * N
    assert len(json.loads(_note(w))) == 2
    for src, done in ((a, first), (b, second)):
        r = K.run(w, src, cluster=True)
        assert r.returncode == 0, r.stderr
        assert K.imported(r.stdout) == N * N - done
    keys = sorted(K.chunks(want))
    assert sorted(K.chunks(w)) == keys and set(K.biomes(w)) == set(keys)
    got, exp = mc.shown(w, keys), mc.shown(want, keys)   # palettes numbered otherwise
    for k in keys:
        for g, e in zip(got[k], exp[k]):
            assert (g == e).all(), k
    assert not _note(w)
