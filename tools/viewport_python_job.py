"""Our Python per live-view redraw in the real Blender GUI (issue 29): thread CPU of
the handler's Python (Frame.python_ms) at distance 16 with the pipeline every redraw
(full, draft), orbiting (a new view every redraw) and still (the kept frame); the
orbiting draft frame's own time (wall with the GPU finished, and process CPU); with
--parts the thread CPU per redraw of the calls that make it up.

    python tools/viewport_python_job.py OUT.json WORLD [N] [--parts] [--app 5.2]

WORLD: a file with the distance-16 area generated (`generate --radius 18`). Run the
old and the new checkout alternately (each its own copy of this script) and compare
medians: the machine's load moves single runs. Inside Blender it is the job itself
(tools/viewport_bench_job.py's helpers).
"""
from __future__ import annotations

import collections
import functools
import json
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
T: dict = collections.defaultdict(float)
R: dict = {}


def _wrap(obj, name, label):
    f = getattr(obj, name)

    @functools.wraps(f)
    def w(*a, **k):
        c = time.thread_time()
        try:
            return f(*a, **k)
        finally:
            T[label] += time.thread_time() - c
    setattr(obj, name, w)


def _parts():
    from voxel_addon.blender.liveview import device, feed, view
    from voxel_addon.render import frame, geometry, pipeline, shadow
    for obj, name in ((view, "settings_of"), (view, "view_camera"), (view.LiveView, "_feed_for"),
                      (feed.Feed, "update"), (view.Pane, "sync"), (pipeline.Renderer, "prepare"),
                      (geometry.Geometry, "cull"), (geometry.Geometry, "batches"),
                      (frame.FrameBlock, "pack"), (device.GpuDevice, "frame"), (shadow, "fit"),
                      (pipeline, "sky_values"), (pipeline, "_sun_on_screen")):
        _wrap(obj, name, f"{getattr(obj, '__name__', obj)}.{name}")


def _took(n):
    out = {k: round(v / n * 1e3, 4) for k, v in sorted(T.items(), key=lambda kv: -kv[1])}
    T.clear()
    return out


def job(world, n, parts):
    import viewport_bench_job as V
    from voxel_addon.blender.liveview import LIVE
    _, vv = V.aim(world, 16)
    vv.show = True
    yield from V.all_drawn(900)
    R["chunks"] = LIVE.stats["wanted"]
    if parts:
        _parts()
    LIVE.finish, LIVE.reuse = True, False
    for q in ("full", "draft"):
        vv.quality = q
        yield from V.frames(2)
        T.clear()
        fr = yield from V.frames(n)
        R[f"{q}_python"] = [f.python_ms for f in fr]
        # the frame itself at rest (the pipeline every redraw, GPU finished): against the
        # old moderngl path's frame (issue 28), process CPU is what compares under load
        R[f"{q}_frame"], R[f"{q}_cpu"] = [f.ms for f in fr], [f.cpu_ms for f in fr]
        R[f"{q}_parts"] = _took(n)
    vv.quality, orb = "auto", []
    for i in range(n + 2):
        V.look(30 + 0.7 * i)
        orb += yield from V.frames(1)
        if i == 1:
            T.clear()
    R["orbit_python"] = [f.python_ms for f in orb[2:]]
    # the draft frame itself while orbiting (GPU finished in each): wall and the
    # process's CPU (llvmpipe's threads too: what counts on a loaded machine)
    R["orbit_frame"] = [f.ms for f in orb[2:]]
    R["orbit_cpu"] = [f.cpu_ms for f in orb[2:]]
    R["orbit_parts"] = _took(n)
    V.look(30)
    vv.quality, LIVE.reuse = "full", True
    for i in range(3):  # a frame that keeps itself (the hour nudged: the pipeline runs)
        vv.hours = 12.0 + 0.001 * (i % 2)
        yield from V.frames(1)
    vv.hours = 12.0
    yield from V.frames(1)
    T.clear()
    R["still_python"] = [f.python_ms for f in (yield from V.frames(n)) if f.reused]
    R["still_parts"] = _took(n)
    for k in ("full", "draft", "orbit", "still"):
        R[f"{k}_ms"] = statistics.median(R[f"{k}_python"])
    for k in ("full", "draft", "orbit"):
        R[f"{k}_frame_ms"] = statistics.median(R[f"{k}_frame"])
        R[f"{k}_cpu_ms"] = statistics.median(R[f"{k}_cpu"])
    import voxel_addon
    voxel_addon.unregister()


def host(argv):
    """Start Blender (tools/blender_app.py, its own Xvfb) with this job; print medians."""
    sys.path.insert(0, str(ROOT))
    from voxel_addon.bench import gui
    app = argv[argv.index("--app") + 1] if "--app" in argv else "5.2"
    args = [a for a in argv if not a.startswith("--") and a != app]
    out, world, n = Path(args[0]).resolve(), str(Path(args[1]).resolve()), args[2] if len(args) > 2 else "12"
    out.unlink(missing_ok=True)
    gui.app().run(["--factory-startup", "-P", __file__, "--", str(out), world, n,
                   "1" if "--parts" in argv else "0"],
                  log=out.with_suffix(".log"), timeout=1500, simulate=False, app=app, gpu="opengl")
    r = json.loads(out.read_text())
    if not r.get("ok"):
        raise SystemExit(r.get("error"))
    print({k: round(r[f"{k}_ms"], 3) for k in ("full", "draft", "orbit", "still", "full_frame",
                                                 "full_cpu", "draft_frame", "draft_cpu",
                                                 "orbit_frame", "orbit_cpu")})
    if "--parts" in argv:
        print({k: r["orbit_parts"][k] for k in list(r["orbit_parts"])[:16]})


if __name__ == "__main__":
    if "--" not in sys.argv:  # (the venv's bpy module imports too: ask the arguments)
        host(sys.argv[1:])
    else:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        import viewport_bench_job as V
        a = sys.argv[sys.argv.index("--") + 1:]
        V.drive(V.report(job(a[1], int(a[2]), a[3] == "1"), R, Path(a[0])))
