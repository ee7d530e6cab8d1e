"""A one-process import (formats/minecraft.py) stopped at a commit point: SIGKILLed
between a batch's chunk rows and its biome rows, or Ctrl-C'd there. The batch is in
the file whole or not at all (no chunk is left without its biomes), and the same
command run again resumes (formats/job.py, meta `import_job`): it says so, imports
only the chunks missing and leaves the file an uninterrupted import leaves, row for
row (chunks, biome rows, palettes). With other options it meets the unfinished import
and says so on one line."""
from __future__ import annotations

import shutil
import sqlite3

import pytest

from voxel_addon.bench import mcsave
from tests.formats import killing as K

N = 9   # 81 chunks: three one-process batches (minecraft.BATCH 32)


@pytest.fixture(scope="module")
def ref(tmp_path_factory):
    d = tmp_path_factory.mktemp("kill1")
    save = mcsave.save(d / "save", N)
    w = d / "ref.sqlite"
    r = K.run(w, save)
    assert r.returncode == 0 and K.imported(r.stdout) == N * N, r.stderr
    return save, w, r.stdout


def _note(path):
    with sqlite3.connect(path) as db:
        got = db.execute("SELECT value FROM meta WHERE key='import_job'").fetchone()
    return got and got[0]


def _resumed(w, save, done, *extra):
    """The same command again: it says it resumes and imports the rest only."""
    r = K.run(w, save, *extra)
    assert r.returncode == 0, r.stderr
    assert f"resuming an interrupted import: {done} of {N * N} chunks already imported" \
        in r.stderr, r.stderr
    assert K.imported(r.stdout) == N * N - done and f"resumed: {done} chunks" in r.stdout
    assert not _note(w)


def _same(w, want):
    assert K.chunks(w) == K.chunks(want) and K.biomes(w) == K.biomes(want)
    assert K.meta(w) == K.meta(want)


def test_a_killed_import_keeps_whole_batches_and_resumes(ref, tmp_path):
    save, want, out = ref
    w = tmp_path / "w.sqlite"
    K.killed(w, save, kill_at=2)   # in the second batch's biome rows
    got, bio = K.chunks(w), K.biomes(w)
    assert 0 < len(got) < N * N and _note(w)
    assert set(bio) == set(got)    # the first batch whole, the second not at all
    full, fbio = K.chunks(want), K.biomes(want)
    assert got == {k: full[k] for k in got} and bio == {k: fbio[k] for k in bio}
    _resumed(w, save, len(got))
    _same(w, want)   # the same rows: it goes on from the palettes the first batch wrote


def test_ctrl_c_keeps_its_batches_and_resumes(ref, tmp_path):
    save, want, _ = ref
    w = tmp_path / "w.sqlite"
    r = K.run(w, save, kill_at=2, sig="SIGINT")
    assert r.returncode == 130 and "Traceback" not in r.stderr, r.stderr
    done = len(K.chunks(w))
    assert 0 < done < N * N and set(K.biomes(w)) == set(K.chunks(w)) and _note(w)
    assert f"{done} chunks were written and kept; the same command again imports the " \
        "rest" in r.stderr and r.stderr.rstrip().endswith("interrupted"), r.stderr
    _resumed(w, save, done)
    _same(w, want)


def _copy(src, dst):
    with sqlite3.connect(src) as a, sqlite3.connect(dst) as b:
        a.backup(b)
    a.close()
    b.close()
    return dst


def test_replace_resumes_and_other_options_meet_the_unfinished_import(ref, tmp_path):
    """--replace over a world holding the chunks (imported with another y_min):
    killed, then run again, it resumes after the batches it replaced (not over the
    world's own chunks). A run with other options is another import: here it would
    overwrite the unfinished one's chunks, and says so."""
    save, want, _ = ref
    opts = ("--replace", "--y-min", -60)
    full = _copy(want, tmp_path / "full.sqlite")
    assert K.run(full, save, *opts).returncode == 0
    w = _copy(want, tmp_path / "w.sqlite")
    K.killed(w, save, *opts, kill_at=2)
    before = K.chunks(w)
    r = K.run(w, save, "--y-min", -60)
    line = r.stderr.strip()
    assert r.returncode == 2 and "\n" not in line, r.stderr
    assert "unfinished import of these region files with --y-min -60 --replace:" in line, line
    assert K.chunks(w) == before
    _resumed(w, save, 32, *opts)
    _same(w, full)
