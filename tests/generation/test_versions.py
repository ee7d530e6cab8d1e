"""Generator versions (issue 29): a world keeps generating with the version it was
created with, new worlds get the newest, a version this code does not know is one line.

data/overworld_v1_seed7.npz: two chunks of seed 7 made by the code before version 2
existed (commit 484df31), the oracle that version 1 still makes the same blocks."""
from __future__ import annotations

import sqlite3
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from voxel_addon.core.errors import VoxelError
from voxel_addon.generation import generator_class, make_generator
from voxel_addon.storage import WorldFile
from voxel_addon.world import World

DATA = Path(__file__).parent / "data" / "overworld_v1_seed7.npz"


def _old():
    d = np.load(DATA)
    return [tuple(int(v) for v in k) for k in d["keys"]], list(d["blocks"])


def _file(path, version):
    """A world file as an older add-on wrote it: version stored, or no version row."""
    WorldFile.create(path, seed=7, generator="overworld",
                     generator_version=1 if version is None else version).close()
    db = sqlite3.connect(path)
    with db:
        if version is None:
            db.execute("DELETE FROM meta WHERE key = 'generator_version'")
    db.close()


def _chunks(w, keys):
    return [np.array(w.chunk_at(*k).blocks) for k in keys]


@pytest.mark.parametrize("stored", [1, None])
def test_old_world_keeps_its_version(tmp_path, stored):
    assert generator_class("overworld").version > 1   # the default moved on
    keys, old = _old()
    path = tmp_path / "old.sqlite"
    _file(path, stored)
    with World.open(path, backend="numpy", loader=False) as w:
        assert w.generator.version == 1
        got = _chunks(w, keys)
    for k, a, b in zip(keys, got, old):
        assert np.array_equal(a, b), f"chunk {k}: {(a != b).sum()} voxels differ from version 1"


def test_new_world_gets_the_newest(tmp_path):
    keys, old = _old()
    newest = generator_class("overworld").version
    with World.create(tmp_path / "new.sqlite", seed=7, backend="numpy", loader=False) as w:
        assert w.generator.version == newest
        got = _chunks(w, keys)
    wf = WorldFile(tmp_path / "new.sqlite", readonly=True)
    assert wf.meta["generator_version"] == str(newest)
    wf.close()
    ref = make_generator("overworld", 7, None, "numpy").generate(keys)
    assert all(np.array_equal(a, b) for a, b in zip(got, ref))
    assert any(not np.array_equal(a, b) for a, b in zip(got, old))   # caves moved


@pytest.mark.parametrize("raw", ["99", "0", "two"])
def test_unknown_version_is_one_line(tmp_path, raw):
    path = tmp_path / "w.sqlite"
    _file(path, 1)
    db = sqlite3.connect(path)
    with db:
        db.execute("UPDATE meta SET value = ? WHERE key = 'generator_version'", (raw,))
    db.close()
    with pytest.raises(VoxelError) as e:
        World.open(path, loader=False)
    assert "\n" not in str(e.value) and "version" in str(e.value)
    if raw == "99":
        assert "newer" in str(e.value)
        r = subprocess.run([sys.executable, "-m", "voxel_addon", "generate", "--world", str(path),
                            "--radius", "0"], capture_output=True, text=True)
        assert r.returncode == 2 and "update" in r.stderr and "Traceback" not in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1
