"""opencl.warm: kernels built in a background thread while the default backend is
NumPy (issue 28: a fresh install's first picture does not wait for pocl)."""
from __future__ import annotations

import threading

import pytest

from voxel_addon import opencl


@pytest.fixture
def fresh(monkeypatch, cl_device):
    """A process that has not warmed up yet (warm runs once per process)."""
    monkeypatch.setattr(opencl, "_warm", dict.fromkeys(opencl._warm))  # never warmed


def test_numpy_until_the_warm_up_ends_then_opencl(fresh):
    from voxel_addon.generation import make_generator
    gen = make_generator("overworld", 7)          # made before: decides per batch
    gate, ran = threading.Event(), []
    assert opencl.pick(None) == gen.backend_used == "opencl"
    assert opencl.warm(lambda: ran.append(gate.wait(30)))
    assert not opencl.warm(lambda: None)          # one at a time
    assert opencl.warming() and opencl.pick(None) == "numpy" == gen.backend_used
    assert opencl.pick("opencl") == "opencl"      # asked for by name: the warm-up's own
    assert make_generator("overworld", 7, None, "opencl").backend_used == "opencl"
    gate.set()
    opencl._warm["thread"].join(30)
    assert ran == [True] and not opencl.warming()
    assert opencl.pick(None) == gen.backend_used == "opencl"
    st = opencl.warm_state()
    assert st["started"] and not st["running"] and st["took"] > 0 and st["error"] is None


def test_a_failing_warm_up_is_kept_and_opencl_used_after(fresh):
    def bad():
        raise RuntimeError("build failed")
    assert opencl.warm(bad)
    opencl._warm["thread"].join(30)
    assert opencl.warm_state()["error"] == "RuntimeError: build failed"
    assert opencl.pick(None) == "opencl"


def test_no_warm_up_without_a_device(monkeypatch):
    monkeypatch.setattr(opencl, "_warm", dict.fromkeys(opencl._warm))  # never warmed
    monkeypatch.setenv(opencl.SWITCH, "0")
    assert not opencl.warm(lambda: None) and not opencl.warm_state()["started"]
    assert opencl.pick(None) == "numpy"


def test_a_generators_warm_up_runs_its_own_kernels_and_equals_numpy(fresh):
    """PassGenerator.warm_opencl: OpenCL with the generator's own kernel objects (pocl
    compiles again per kernel object), whatever the default; the NumPy twin's blocks."""
    import numpy as np
    from voxel_addon.generation import make_generator
    gen = make_generator("overworld", 7)
    keys = [(3, -2), (4, -2)]
    assert opencl.warm(lambda: None)
    opencl._warm["thread"].join(30)
    got = gen.warm_opencl(keys)
    assert gen._runner is not None  # the runner the default backend uses next
    ref = make_generator("overworld", 7, None, "numpy").generate(keys)
    assert all(np.array_equal(a, b) for a, b in zip(got, ref))


def test_the_later_part_runs_with_opencl_already_the_default(fresh):
    """warm(job, later=...): LATER (the far surface's build) runs once JOB is done, and
    does not hold the stream on NumPy meanwhile."""
    gate, seen = threading.Event(), []
    assert opencl.warm(lambda: None, later=lambda: seen.append(
        (opencl.warming(), opencl.pick(None), gate.wait(30))))
    for _ in range(3000):
        if opencl.warm_state()["ended_at"] is not None:
            break
        threading.Event().wait(0.01)
    assert not opencl.warming() and opencl.pick(None) == "opencl"
    gate.set()
    opencl._warm["thread"].join(30)
    assert seen == [(False, "opencl", True)]
    st = opencl.warm_state()
    assert st["later_took"] > 0 and st["later_error"] is None and st["error"] is None


def test_the_world_warm_up_prebuilds_the_far_surface(fresh, tmp_path):
    """world.build.warm builds the far surface's OpenCL program after the stream's
    kernels (issue 28: Show to horizon does not wait for pocl); far tiles then use
    that runner, whose columns equal the NumPy twin's."""
    import numpy as np
    from voxel_addon.generation import make_generator
    from voxel_addon.world import World, build
    with World.create(tmp_path / "w.sqlite", seed=7) as w:
        g = w.generator
        assert build.warm(w)
        opencl._warm["thread"].join(120)
        st = opencl.warm_state()
        assert st["error"] is None and st["later_error"] is None and st["later_took"] > 0
        run = (g._surf or {}).get("opencl")
        assert run is not None
        xy = [(x * 37 - 500, 11 * x) for x in range(50)]
        got = g.surface(xy)
        assert g._surf["opencl"] is run  # the warm-up's kernel objects, not new ones
    ref = make_generator("overworld", 7, None, "numpy").surface(xy)
    assert all(np.array_equal(got[k], ref[k]) for k in ref)


def test_a_kernel_family_is_used_as_soon_as_the_warm_up_says_it_is_ready(fresh):
    """opencl.ready(what) from the job: pick(None, what) answers OpenCL while the job
    builds the rest; every other caller waits for the end (issue 28: the stream
    generates with OpenCL while meshing's kernels build)."""
    gate, went = threading.Event(), threading.Event()

    def job():
        opencl.ready("generation")
        went.set()
        gate.wait(30)
    assert opencl.warm(job) and went.wait(30)
    assert opencl.pick(None, "generation") == "opencl" and not opencl.warming("generation")
    assert opencl.pick(None, "meshing") == opencl.pick(None) == "numpy"
    assert opencl.warming("meshing") and opencl.warming()
    gate.set()
    opencl._warm["thread"].join(30)
    assert opencl.pick(None, "meshing") == "opencl"
    assert set(opencl.warm_state()["ready"]) == {"generation"}


def test_the_far_prebuild_waits_for_the_streams_of_the_world(fresh, tmp_path, monkeypatch):
    """world.build.warm's later part (the far surface's first batch) and its prebuild
    (the far program) start only once every stream of the world has all its chunks:
    pocl runs one in-order queue, and the far batch and its build queued before the
    stream's kernels held the view back ~2 s; the build's CPU came from the near
    view's last batches."""
    import time
    from voxel_addon.world import Stream, World, build
    built, real = [], opencl.build

    def build_(source, options=(), alone=False):
        if alone:  # the far program's
            built.append([s.idle for s in w.streams])
        return real(source, options, alone)
    monkeypatch.setattr(opencl, "build", build_)
    with World.create(tmp_path / "w.sqlite", seed=7) as w:
        seen = []
        monkeypatch.setattr(w.generator, "warm_surface",
                            lambda: seen.append([s.idle for s in w.streams]) or True)
        with Stream(w, 3) as s:
            s.set_view(8.0, 8.0)
            assert build.warm(w)
            assert s.wait_ready(120)
            opencl._warm["thread"].join(120)
            end = time.monotonic() + 120
            while not built and time.monotonic() < end:
                time.sleep(0.05)
        st = opencl.warm_state()
        assert st["error"] is None and st["later_error"] is None, st
        assert seen == [[True]], seen
        assert built == [[True]], built
        # the stream generated with OpenCL once the generator's kernels were ready,
        # before the warm-up had built meshing's
        assert st["ready"]["generation"] < st["ended_at"]


def test_a_helper_process_puts_meshings_kernels_into_pocls_cache(cl_device, tmp_path, monkeypatch):
    """opencl.helper runs meshing.vertex.warm_cache in a process of its own (pocl
    compiles one thing at a time per process): the mesher's program with this
    process's options and both greedy kernels' work-group code land in the kernel
    cache, under the key this process's own build of that program then finds (no
    second program folder), so world.build.warm's meshing step only loads them."""
    from voxel_addon import resources
    from voxel_addon.meshing import cl as mcl
    monkeypatch.setenv("POCL_CACHE_DIR", str(tmp_path))  # (the helper's environment)
    opts = list(mcl._options())
    p = opencl.helper("meshing.vertex", "warm_cache", opts)
    assert p is not None and p.wait(120) == 0
    progs = {f.parent for f in tmp_path.rglob("program.bc")}
    assert len(progs) == 1, progs
    built = {f.name for f in next(iter(progs)).rglob("*.so")}
    assert {"layers.so", "tile.so"} <= built, built
    # pocl reads POCL_CACHE_DIR once per process: a process of its own builds here too
    import subprocess
    import sys
    code = ("import sys, pyopencl as cl; from voxel_addon import opencl, resources; "
            "cl.Program(opencl.context()[0], resources.kernel('mesh_greedy.cl'))"
            ".build(options=sys.argv[1:])")
    subprocess.run([sys.executable, "-c", code, *opts], check=True, timeout=120,
                   env=dict(__import__("os").environ, PYTHONPATH=str(resources.ROOT)))
    assert {f.parent for f in tmp_path.rglob("program.bc")} == progs


def test_a_helper_that_cannot_start_is_none(monkeypatch):
    import sys
    monkeypatch.setattr(sys, "executable", "/nonexistent/blender")
    assert opencl.helper("meshing.vertex", "warm_cache", []) is None


def test_the_warm_up_ends_a_helper_that_takes_too_long(monkeypatch):
    """build._finish: a stuck helper is waited for HELPER_WAIT_S at most, then killed
    (the warm-up then builds meshing itself, the stream no longer held on NumPy)."""
    import subprocess
    import sys
    import time
    from voxel_addon.world import build
    monkeypatch.setattr(build, "HELPER_WAIT_S", 0.3)  # (2 s by default)
    p = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    t0 = time.monotonic()
    build._finish(p)
    assert p.poll() is not None and time.monotonic() - t0 < 10
    build._finish(None)  # no helper: nothing to wait for


_EXIT_CHILD = r'''
import sys, time
from pathlib import Path
from voxel_addon import opencl
out = Path(sys.argv[1])

def job():  # a step under way when the interpreter ends: a real build, then a launch
    time.sleep(0.5)
    import numpy as np, pyopencl as cl
    ctx, q, _ = opencl.context()
    prg = opencl.build("__kernel void twice(__global int *a) "
                       "{ a[get_global_id(0)] *= 2; }")
    a = np.arange(64, dtype=np.int32)
    buf = cl.Buffer(ctx, cl.mem_flags.READ_WRITE | cl.mem_flags.COPY_HOST_PTR, hostbuf=a)
    prg.twice(q, a.shape, None, buf)
    cl.enqueue_copy(q, a, buf)
    out.write_text(f"job {int(a[-1])}")

def later():
    out.write_text(out.read_text() + ", later")

assert opencl.warm(job, later=later)
print("main ends", flush=True)
'''


def test_the_exit_waits_for_the_warm_up_step_and_starts_no_other(cl_device, tmp_path):
    """A process that ends while a warm-up builds or runs a kernel in its thread
    aborted in pocl ("terminate called ...", status 134: a script or a Blender quitting
    seconds after Show). The exit now waits for the step under way (the job) and
    starts no other (its later part)."""
    import subprocess
    import sys
    out = tmp_path / "out.txt"
    r = subprocess.run([sys.executable, "-c", _EXIT_CHILD, str(out)], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0 and "terminate" not in r.stderr, r.stderr[-2000:]
    assert r.stdout.strip() == "main ends"
    assert out.read_text() == "job 126"  # the job ended; the later part never began
