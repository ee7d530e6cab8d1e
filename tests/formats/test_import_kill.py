"""A one-process import SIGKILLed between a batch's chunk rows and its biome rows
(formats/minecraft.py): the batch is in the file whole or not at all, so no chunk is
left without its biomes (their grass and leaf tints); imported again (--replace) the
file shows what an uninterrupted import's shows."""
from __future__ import annotations

import pytest

from voxel_addon.bench import mcsave
from tests.formats import killing as K
from tests.formats import mcfiles as mc

N = 9   # 81 chunks: three one-process batches (minecraft.BATCH 32)


@pytest.fixture(scope="module")
def ref(tmp_path_factory):
    d = tmp_path_factory.mktemp("kill1")
    save = mcsave.save(d / "save", N)
    w = d / "ref.sqlite"
    r = K.run(w, save)
    assert r.returncode == 0 and K.imported(r.stdout) == N * N, r.stderr
    return save, w, r.stdout


def test_a_killed_batch_leaves_no_chunk_without_biomes(ref, tmp_path):
    save, want, out = ref
    w = tmp_path / "w.sqlite"
    K.killed(w, save, kill_at=2)   # in the second batch's biome rows
    got, bio = K.chunks(w), K.biomes(w)
    assert 0 < len(got) < N * N
    assert set(bio) == set(got)    # the first batch whole, the second not at all
    full, fbio = K.chunks(want), K.biomes(want)
    assert got == {k: full[k] for k in got} and bio == {k: fbio[k] for k in bio}
    r = K.run(w, save, "--replace")
    assert r.returncode == 0, r.stderr
    # the kept chunks' blobs are made again with the defaults decided (data 0): the
    # same states, biomes and colours
    assert set(K.chunks(w)) == set(full) and K.biomes(w) == fbio
    got, exp = mc.shown(w, sorted(full)), mc.shown(want, sorted(full))
    for k in full:
        for g, e in zip(got[k], exp[k]):
            assert (g == e).all(), k
    assert K.meta(w) == K.meta(want)
    assert r.stdout.splitlines()[1:] == out.splitlines()[1:]   # the report, but the time
    assert K.imported(r.stdout) == N * N
