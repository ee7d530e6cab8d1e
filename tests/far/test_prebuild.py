"""The far surface's OpenCL program built in the background as a world opens (issue 28:
far 128 to the horizon cold): far tiles run on NumPy's twin meanwhile (the same
values), the build takes neither the build lock nor the queue, and the world's
warm-up starts it once its own job has built the near view's kernels (pocl compiles
one thing at a time per process), not after the streams have all they want."""
from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from voxel_addon import opencl
from voxel_addon.generation import make_generator

XY = [(x * 37 - 500, 11 * x - 90) for x in range(60)]


def _within(seconds, fn, *args):
    """fn(*args) in a thread, failing if it has not returned after `seconds`."""
    out = []
    t = threading.Thread(target=lambda: out.append(fn(*args)), daemon=True)
    t.start()
    t.join(seconds)
    assert out, f"{fn.__name__} still running after {seconds} s"
    return out[0]


def _gated(g, monkeypatch) -> threading.Event:
    """G's warm-up job held in its generator step until the returned event is set
    (and its far surface's warm launch a no-op)."""
    gate = threading.Event()
    monkeypatch.setattr(g, "warm_opencl", lambda keys: gate.wait(120) and [])
    monkeypatch.setattr(g, "warm_surface", lambda: True)
    return gate


@pytest.fixture
def fresh(monkeypatch, cl_device):
    """A process that has not warmed up yet (warm runs once per process)."""
    monkeypatch.setattr(opencl, "_warm", dict.fromkeys(opencl._warm))


def test_numpy_while_the_far_program_builds_then_its_kernels(fresh):
    g = make_generator("overworld", 7)  # no backend asked: OpenCL once built
    assert g.backend_used == "opencl"
    g._surf_building = g._surf_held = True  # as while prebuild_surface's build runs
    during = _within(60, g.surface, XY)  # a surface that waited for the build: a failure, not a hang
    assert "opencl" not in g._surf and "numpy" in g._surf  # no build of its own
    g._surf_building = g._surf_held = False
    assert g.prebuild_surface()
    run = g._surf["opencl"]
    assert not g.prebuild_surface()  # built: nothing more to do
    held = g.surface(XY)  # built, not launched yet (the near view's kernels first)
    assert g._surf["opencl"] is run and g._surf_held
    assert g.warm_surface() and not g._surf_held  # launched once: OpenCL from now on
    after = g.surface(XY)
    assert g._surf["opencl"] is run  # the prebuild's kernel objects
    ref = make_generator("overworld", 7, None, "numpy").surface(XY)
    for k in ref:
        for got in (during, held, after):
            assert np.array_equal(got[k], ref[k]), k


def test_the_far_program_builds_while_another_build_holds_the_lock(fresh):
    """Another build (the near view's kernels) holding opencl's build lock does not
    hold the far program back, nor does the far build hold the lock."""
    opencl.build.cache_clear()  # (a program built earlier in this process: no build)
    g = make_generator("overworld", 11)
    done = []
    with opencl._lock:
        t = threading.Thread(target=lambda: done.append(g.prebuild_surface()), daemon=True)
        t.start()
        t.join(60)
        assert done == [True]


def test_the_warm_up_meshes_a_stored_view_first(fresh, tmp_path, monkeypatch):
    """build.warm on a file holding the chunks at the origin (an opened world: its
    view is stored): meshing's kernels first (all the stream needs: ready("meshing")),
    then the generator's at a lower priority; the far program after the whole job
    (the next test)."""
    from voxel_addon.core import chunk as C
    from voxel_addon.core.blocks import REGISTRY
    from voxel_addon.world import World, build
    blocks = np.zeros(C.SHAPE, np.uint16)
    blocks[:, :, :20] = REGISTRY.id("stone")
    with World.create(tmp_path / "w.sqlite", seed=7) as w:
        w.file.write_chunks([(k, blocks, None) for k in build.keys_of(-1, -1, 2, 2)])
        g, gate = w.generator, _gated(w.generator, monkeypatch)
        try:
            assert build.warm(w)
            end = time.monotonic() + 60
            while opencl.warming("meshing") and time.monotonic() < end:
                time.sleep(0.05)
            assert opencl.warming("generation") and not opencl.warming("meshing")
            assert opencl.pick(None, "meshing") == "opencl"
        finally:
            gate.set()
            opencl._warm["thread"].join(120)
        assert list(opencl.warm_state()["ready"]) == ["meshing", "generation"]
        end = time.monotonic() + 120  # the far build after the job: not into the next test
        while (g._surf or {}).get("opencl") is None and time.monotonic() < end:
            time.sleep(0.05)
        assert (g._surf or {}).get("opencl") is not None


def test_the_world_warm_up_builds_the_far_program_after_its_job(fresh, tmp_path, monkeypatch):
    """build.warm: far tiles run NumPy from the start (the far program is claimed),
    and its build waits until the warm-up's own job (the near view's kernels) has
    ended: pocl compiles one thing at a time per process, so the generator's build
    waited behind the whole far build (issue 28). Then far tiles use it."""
    from voxel_addon.world import World, build
    seen = []
    real = opencl.build

    def build_(source, options=(), alone=False):
        if alone:  # the far program's (generation.cl.Runner of 1-column domains)
            seen.append(opencl.warming())
        return real(source, options, alone)
    monkeypatch.setattr(opencl, "build", build_)
    with World.create(tmp_path / "w.sqlite", seed=7) as w:
        g, gate = w.generator, _gated(w.generator, monkeypatch)
        try:
            assert build.warm(w)
            end = time.monotonic() + 60
            while not g._surf_held and time.monotonic() < end:
                time.sleep(0.01)
            assert g._surf_held and opencl.warming()  # claimed: far tiles on NumPy
            time.sleep(1.0)  # (time enough for a build that would not wait)
            assert seen == [] and (g._surf or {}).get("opencl") is None
        finally:
            gate.set()
            opencl._warm["thread"].join(120)
        end = time.monotonic() + 120
        while (g._surf or {}).get("opencl") is None and time.monotonic() < end:
            time.sleep(0.05)
        assert (g._surf or {}).get("opencl") is not None and seen == [False]
    assert not build.prebuild(object())  # a generator without a far surface


def test_far_tiles_alone_ask_for_a_redraw(tmp_path):
    """Feed.far_news: far tiles made while the near stream has nothing new are worth a
    redraw of their own (the ring's last ones, or FAR_NEWS of them); drained: none.
    Feed.far_made: the builder has made the whole ring (then no frame's wait)."""
    from voxel_addon.blender.liveview import feed as F
    from voxel_addon.world import World
    with World.create(tmp_path / "w.sqlite", seed=7) as w:
        f = F.Feed(str(tmp_path / "w.sqlite"), w, 2)
        try:
            assert not f.far_news() and not f.far_made()  # no far ring
            f.set_far(8)
            f._at = (8.0, 8.0)
            with w.gen_lock:  # (the builder builds under it: nothing made meanwhile)
                f._far.set_view(8.0, 8.0, 8, 2)
                time.sleep(0.2)
                assert not f.far_made()
            assert f._far.wait_ready(120)
            w_, r = f._far.counts
            assert 0 < w_ < F.FAR_NEWS and r == w_ and f.far_news()  # the ring's last
            assert f.far_made()  # the builder is done: the view redraws at once
            f._update_far(1e9)
            assert not f.far_news() and f.far_made()  # taken in
        finally:
            f.close()
