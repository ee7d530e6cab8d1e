"""generate, import and far on a real Dask cluster (issue 27): a `dask scheduler` and
two `dask worker` processes on 127.0.0.1, the commands as real subprocesses. Every
output is compared with the one-process run of the same command (chunk blobs, far
tiles, the colour palette, the import report), also when a worker is SIGKILLed
mid-job and when the command itself is SIGKILLed (or stopped with Ctrl-C) and run
again (then the second run must compute only what the first did not commit). Bad
addresses, an unreachable scheduler, a worker without the package and an unwritable
world: one line, exit 2, no change."""
from __future__ import annotations

import os
import re
import shutil
import signal
import socket
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tests.formats import mcfiles as mc
from tests.formats.test_minecraft import column

ROOT = Path(__file__).resolve().parents[2]
SEED, R = 11, 5           # generate: 121 chunks, NumPy backend
FAR = ("--center", 40, -20, "--far", 8)


def cli(*args, env=None, wait=True, prefix=()):
    e = dict(os.environ, PYTHONPATH=str(ROOT), **(env or {}))
    cmd = [*prefix, sys.executable, "-m", "voxel_addon", *map(str, args)]
    if not wait:  # its own process group: killing it kills a --workers cluster too
        return subprocess.Popen(cmd, env=e, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, start_new_session=True)
    return subprocess.run(cmd, capture_output=True, text=True, env=e, timeout=300)


def _stop(p):
    try:
        os.killpg(p.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    p.wait(10)


# the cluster fixture: conftest.py (one cluster per test run, shared with the render tasks)


# ---- inputs and the one-process outputs --------------------------------------
def prepared_world(path: Path) -> Path:
    """A world with one stored edit whose chunk is not in the file (regenerated: the
    edit must be applied by the writer)."""
    from voxel_addon.world import World
    with World.create(path, seed=SEED, generator="overworld", backend="numpy",
                      loader=False) as w:
        w.set_block(20, -30, 120, "glass")
        w.flush()
        w.recreate(keep_edits=True)
    return path


def save_folder(path: Path) -> Path:
    """A 1.18+ save: 8 x 6 chunks (colour blocks among them), an unfinished and a
    damaged one."""
    rng = np.random.default_rng(3)
    wool = [f"minecraft:{c}_wool" for c in ("red", "blue", "lime", "cyan", "pink", "gray")]
    chunks = {}
    for cx in range(-4, 4):
        for cz in range(-3, 3):
            secs = column(rng, cx, cz)[0]
            for name in rng.permutation(wool)[:3]:  # colours met in another order per chunk
                secs[0][tuple(rng.integers(0, 16, 3))] = name
            chunks[(cx, cz)] = mc.chunk_nbt(cx, cz, secs)
    chunks[(1, 7)] = mc.chunk_nbt(1, 7, column(rng, 1, 7)[0], status="minecraft:features")
    chunks[(2, 7)] = b"\x0a\x00\x00\x08not NBT"  # damaged: skipped with its reason
    mc.write_region(path / "region", chunks)
    mc.level_dat(path, 3953)
    return path


@pytest.fixture(scope="module")
def ref(tmp_path_factory):
    """Inputs and what one process makes of them."""
    d = tmp_path_factory.mktemp("ref")
    base = prepared_world(d / "base.sqlite")
    gen = d / "gen.sqlite"
    shutil.copy(base, gen)
    r = cli("generate", "--world", gen, "--radius", R, "--backend", "numpy")
    assert r.returncode == 0, r.stderr
    far = d / "far.sqlite"
    shutil.copy(gen, far)
    r = cli("far", "--world", far, *FAR, "--backend", "numpy")
    assert r.returncode == 0, r.stderr
    save = save_folder(d / "save")
    imp = d / "imp.sqlite"
    r = cli("import", "--world", imp, "--from", save)
    assert r.returncode == 0, r.stderr
    return {"base": base, "gen": gen, "far": far, "save": save, "imp": imp,
            "imp_report": report(r.stdout)}


def chunks(p: Path):
    with sqlite3.connect(p) as db:
        return sorted(db.execute("SELECT cx, cy, codec, blocks, data FROM chunks"))


def tiles(p: Path):
    with sqlite3.connect(p) as db:
        return sorted(db.execute("SELECT * FROM far_tiles"))


def meta(p: Path, key: str):
    with sqlite3.connect(p) as db:
        row = db.execute("SELECT value FROM meta WHERE key=?", (key,)).fetchone()
    return row and row[0]


def report(out: str) -> str:
    return re.sub(r" in [0-9.]+ s \([0-9]+ chunks/s\)", "", out)


def count(p: Path) -> int:
    try:
        with sqlite3.connect(f"file:{p}?mode=ro", uri=True, timeout=1) as db:
            return db.execute("SELECT COUNT(*) FROM chunks").fetchone()[0]
    except sqlite3.Error:
        return 0


# Watches the file from a process of its own: this test process's own background
# threads (a cold kernel cache's builds) can hold its GIL past a whole small job.
WATCH = r"""
import os, sqlite3, sys, time
path, group, total, sig, timeout = sys.argv[1:]
end = time.monotonic() + float(timeout)
def count():
    try:
        with sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=1) as db:
            return db.execute("SELECT COUNT(*) FROM chunks").fetchone()[0]
    except sqlite3.Error:
        return 0
def gone():  # the command's process ended (a zombie until the test reaps it)
    try:
        with open(f"/proc/{group}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] in "ZX"
    except OSError:
        return True
while time.monotonic() < end:
    n = count()
    if not n and gone():
        n = count()
        if not n:
            sys.exit(print("gone"))
    if n:
        if n < int(total):
            os.killpg(int(group), int(sig))
        sys.exit(print("signalled" if n < int(total) else "ended", n))
    time.sleep(0.002)
print("timeout")
"""


def computed(stderr: str, what: str) -> int:
    m = re.search(rf"workers {what} (\d+) chunks", stderr)
    assert m, stderr
    return int(m.group(1))


def kill_after_first_commit(proc, path, total, sig=signal.SIGKILL, timeout=120):
    """Wait until the command committed some but not all chunks, then signal it
    (its process group); returns the chunks committed, None when the job ended
    before the signal reached it (start it again: `interrupted`)."""
    w = subprocess.run([sys.executable, "-c", WATCH, str(path), str(proc.pid), str(total),
                        str(int(sig)), str(timeout)], capture_output=True, text=True,
                       timeout=timeout + 60)
    what = w.stdout.split()
    if what[:1] == ["gone"]:
        pytest.fail(f"ended before a commit: {proc.communicate()}")
    assert what and what[0] in ("signalled", "ended"), (w.stdout, w.stderr, proc.poll())
    out, err = proc.communicate(timeout=60)
    if proc.returncode == 0 and count(path) == total:
        return None  # it ended before the signal
    if sig == signal.SIGINT:  # a clean stop: one line, no worker's traceback, none left
        assert proc.returncode == 130 and err.strip().splitlines()[-1] == "interrupted", err
        assert "Traceback" not in err, err
        end = time.monotonic() + 15
        while time.monotonic() < end:  # the workers and helpers go away with it
            try:
                os.killpg(proc.pid, 0)
            except ProcessLookupError:
                break
            time.sleep(0.1)
        else:
            os.killpg(proc.pid, signal.SIGKILL)
            pytest.fail("processes of the interrupted command stayed")
    return count(path)


# ---- through --scheduler ----------------------------------------------------
def test_generate_with_a_worker_killed_mid_job(cluster, ref, tmp_path):
    w = tmp_path / "gen.sqlite"
    shutil.copy(ref["base"], w)
    with cluster.client() as c:
        pids = c.run(os.getpid)
    p = cli("generate", "--world", w, "--radius", R, "--backend", "numpy",
            "--scheduler", cluster.address, env={"VOXEL_COMMIT": "4"}, wait=False)
    end = time.monotonic() + 120
    while count(w) == 0:
        assert p.poll() is None and time.monotonic() < end, p.communicate()
        time.sleep(0.005)
    assert p.poll() is None, "the job ended before a worker could be killed"
    os.kill(next(iter(pids.values())), signal.SIGKILL)  # its nanny starts a new one
    out, err = p.communicate(timeout=120)
    assert p.returncode == 0, err
    assert f"dashboard" in err and cluster.address in err
    assert chunks(w) == chunks(ref["gen"])
    cluster.wait_workers(2)


def test_import_and_far_equal_one_process(cluster, ref, tmp_path):
    w = tmp_path / "imp.sqlite"
    r = cli("import", "--world", w, "--from", ref["save"], "--scheduler", cluster.address)
    assert r.returncode == 0, r.stderr
    assert chunks(w) == chunks(ref["imp"])
    assert meta(w, "colors") == meta(ref["imp"], "colors") and meta(w, "colors")
    assert report(r.stdout) == ref["imp_report"]  # counts, skipped chunks, names
    assert computed(r.stderr, "read") == 50
    assert "damaged: 1" in r.stdout and "not finished by Minecraft: 1" in r.stdout
    f = tmp_path / "far.sqlite"
    shutil.copy(ref["gen"], f)
    r = cli("far", "--world", f, *FAR, "--backend", "numpy", "--scheduler", cluster.address)
    assert r.returncode == 0, r.stderr
    assert tiles(f) == tiles(ref["far"]) and len(tiles(f)) > 20
    # the Blender builder's tiles (far.ring), the oracle of the one-process run
    from voxel_addon.far import ring
    from voxel_addon.world import World
    b = tmp_path / "builder.sqlite"
    shutil.copy(ref["gen"], b)
    with World.open(b, backend="numpy", loader=False) as world:
        ring(world.file, world.generator, FAR[1], FAR[2], FAR[4])
    assert tiles(b) == tiles(f)
    r = cli("far", "--world", f, *FAR, "--backend", "numpy", "--scheduler", cluster.address)
    assert r.returncode == 0 and r.stderr.splitlines()[-1].startswith("0 tiles built"), r.stderr


def interrupted(start, path, total, sig=signal.SIGKILL, tries=3):
    """kill_after_first_commit on the process START() makes (it makes PATH afresh),
    again when the job ended before the signal reached it."""
    for _ in range(tries):
        kept = kill_after_first_commit(start(), path, total, sig)
        if kept is not None:
            return kept
    pytest.fail(f"the job ended before its signal {tries} times")


def test_import_killed_then_resumed(cluster, ref, tmp_path):
    w = tmp_path / "imp.sqlite"

    def start():
        w.unlink(missing_ok=True)
        return cli("import", "--world", w, "--from", ref["save"], "--scheduler",
                   cluster.address, env={"VOXEL_COMMIT": "1"}, wait=False)
    kept = interrupted(start, w, 48)
    assert 0 < kept < 48
    r = cli("import", "--world", w, "--from", ref["save"], "--scheduler", cluster.address)
    assert r.returncode == 0, r.stderr
    # only what is missing: the chunks not committed, the unfinished and damaged again
    assert computed(r.stderr, "read") == 50 - kept
    assert chunks(w) == chunks(ref["imp"])
    assert meta(w, "colors") == meta(ref["imp"], "colors")
    assert not meta(w, "import_job")
    again = cli("import", "--world", w, "--from", ref["save"], "--scheduler", cluster.address)
    assert again.returncode == 2 and "already in" in again.stderr  # finished: as before


# ---- through --workers --------------------------------------------------------
def test_local_workers_import_equal_one_process(ref, tmp_path):
    """--workers: the workers read the region files themselves (tasks carry the
    chunks' places, not their bytes), results come back pickled once per task."""
    w = tmp_path / "imp.sqlite"
    r = cli("import", "--world", w, "--from", ref["save"], "--workers", 2)
    assert r.returncode == 0, r.stderr
    assert chunks(w) == chunks(ref["imp"])
    assert meta(w, "colors") == meta(ref["imp"], "colors") and meta(w, "colors")
    assert report(r.stdout) == ref["imp_report"]
    assert computed(r.stderr, "read") == 50


def test_local_workers_interrupted_then_resumed(ref, tmp_path):
    w = tmp_path / "gen.sqlite"
    args = ("generate", "--world", w, "--radius", R, "--backend", "numpy", "--workers", 2)

    def start():
        shutil.copy(ref["base"], w)
        return cli(*args, env={"VOXEL_COMMIT": "2"}, wait=False)
    kept = interrupted(start, w, (2 * R + 1) ** 2, signal.SIGINT)
    r = cli(*args)
    assert r.returncode == 0, r.stderr
    assert computed(r.stderr, "computed") == (2 * R + 1) ** 2 - kept
    assert chunks(w) == chunks(ref["gen"])


# ---- refused, with nothing changed ----------------------------------------------
def _refused(r, *words):
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and lines[0].startswith("error:"), r.stderr
    for word in words:
        assert word in lines[0], lines[0]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_bad_addresses_and_unwritable_worlds(cluster, ref, tmp_path):
    w = tmp_path / "w.sqlite"
    shutil.copy(ref["gen"], w)
    before = w.read_bytes()
    new = tmp_path / "new.sqlite"
    quick = {"VOXEL_CONNECT_TIMEOUT": "2"}
    bad = ("127.0.0.1:8786", "tcp://127.0.0.1:notaport", f"tcp://127.0.0.1:{_free_port()}")
    _refused(cli("generate", "--world", w, "--radius", 1, "--scheduler", bad[0]), bad[0])
    _refused(cli("generate", "--world", new, "--seed", 1, "--scheduler", bad[1]), bad[1])
    _refused(cli("far", "--world", w, *FAR, "--scheduler", bad[2], env=quick), bad[2])
    _refused(cli("import", "--world", new, "--from", ref["save"], "--workers", 0), "--workers")
    _refused(cli("far", "--world", w, "--center", 0, 0, "--far", 0), "--far")
    _refused(cli("far", "--world", new, *FAR), "no world file")
    assert not new.exists() and w.read_bytes() == before
    # a world file this user may not write (root: without the capability to ignore modes)
    os.chmod(w, 0o444)
    prefix = ("setpriv", "--bounding-set=-dac_override,-dac_read_search") \
        if os.geteuid() == 0 else ()
    for args in (("generate", "--world", w, "--radius", 1),
                 ("import", "--world", w, "--from", ref["save"], "--replace")):
        _refused(cli(*args, "--scheduler", cluster.address, prefix=prefix), "not writable")
    os.chmod(w, 0o644)
    assert w.read_bytes() == before and not Path(f"{w}-wal").exists()


def test_a_worker_without_the_package(cluster, ref, tmp_path):
    bad = cluster.worker("bare", tmp_path, pythonpath=False)
    try:
        cluster.wait_workers(3)
        w = tmp_path / "w.sqlite"
        shutil.copy(ref["gen"], w)
        before = w.read_bytes()
        r = cli("far", "--world", w, *FAR, "--scheduler", cluster.address)
        _refused(r, "no voxel_addon", "PYTHONPATH")
        r = cli("generate", "--world", tmp_path / "new.sqlite", "--seed", 1,
                "--scheduler", cluster.address)
        _refused(r, "1 of 3 workers")
        assert w.read_bytes() == before and not (tmp_path / "new.sqlite").exists()
    finally:
        _stop(bad)
    cluster.wait_workers(2)
