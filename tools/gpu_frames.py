"""Frame times on a real GPU (issue 29: measured when a task is lent a machine with one),
this tree against another revision's, alternating in fresh processes, plus the OpenCL
kernel rates and far 256 against far 0 of this tree.

    python tools/gpu_frames.py OUT_DIR [--base DIR] [--rounds N] [--small]

DIR holds another revision's package (`git archive 5ce3dff voxel_addon | tar -x -C DIR`).
Each round runs the frame measurement once per tree, a new process each, the order
swapped every round; OUT_DIR/frames.csv gets one row per metric: this tree's and the
base's medians and the median of the rounds' own ratios (new / base, lower is faster).
Then, for this tree only: `bench.far`'s frames (far 256 against far 0, the live view's
full and draft settings at its region size) and the bench areas generation, light and
meshing (OpenCL on the GPU against NumPy), each in its own process, their CSVs beside.

The frames are the CLI's pipeline (`render/pipeline.Renderer` on a moderngl standalone
EGL context): each reference scene with its default effects at 640x360, 1920x1080 and
3840x2160, the landscape's chunks tiled to view distance 16 and 32 at 1920x1080, and the
Python CPU of one frame at distance 32 (on a fast GPU the calling thread is what is
left). A frame is timed from glFinish to glFinish, fastest of 5 after a warm-up.
`--small` shrinks everything to check the script on a software renderer.
tools/gpu_device.sh prepares a bare GPU machine (drivers' libraries, wheels) and runs it.
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIZES = ((640, 360), (1920, 1080), (3840, 2160))


def _gl():
    try:
        from voxel_addon.render.device import mgl
        return mgl.context()
    except ImportError:  # older trees opened it in render.source
        from voxel_addon.render import source
        return source.context()


def _best(gl, r, cam, hours, size, n):
    """Fastest frame (ms, glFinish to glFinish) of n after one warm-up, and its Python
    CPU ms (the calling thread's CPU in draw(): on a fast GPU, most of the frame)."""
    r.draw(cam, hours, size)
    gl.finish()
    best = (1e9, 0.0)
    for _ in range(n):
        gl.finish()
        t, c = time.perf_counter(), time.thread_time()
        r.draw(cam, hours, size)
        cpu = time.thread_time() - c
        gl.finish()
        best = min(best, ((time.perf_counter() - t) * 1e3, cpu * 1e3))
    return best


def _label(prog) -> str:
    """A program's fragment shader file: found in the dict that caches it (both trees
    keep programs keyed by a tuple that names their files)."""
    import gc
    for d in gc.get_referrers(prog):
        if isinstance(d, dict):
            for k, v in d.items():
                if v is prog and isinstance(k, tuple):
                    return next((x.rsplit(".", 1)[0] for x in k
                                 if isinstance(x, str) and x.endswith(".frag")), "?")
    return "?"


class Passes:
    """GL time of each pass of a frame (timer queries around the leaf calls: a pass's
    run, a geometry pass's draw, the far ring's draw), by their order in the frame."""

    def __init__(self, gl):
        from voxel_addon.render import passes
        self.gl, self.log, self.names, self.undo = gl, [], {}, []
        self._wrap(passes.Pass, "run", lambda p, a: _label(p.prog) if p.prog else "?")
        self._wrap(passes.GeometryPass, "draw", lambda p, a: "geometry:" + "+".join(p.names))
        try:
            from voxel_addon.render.far import FarRing
            self._wrap(FarRing, "draw", lambda p, a: "far")
        except ImportError:
            pass

    def _wrap(self, cls, name, label):
        f, me = getattr(cls, name), self

        def timed(obj, *a, **k):
            q = me.gl.query(time=True)
            with q:
                r = f(obj, *a, **k)
            key = (cls.__name__, id(obj))
            if key not in me.names:
                me.names[key] = label(obj, a)
            me.log.append((me.names[key], q))
            return r
        setattr(cls, name, timed)
        self.undo.append((cls, name, f))

    def frame(self, draw) -> list:
        self.log = []
        draw()
        self.gl.finish()
        return [(n, q.elapsed / 1e6) for n, q in self.log]

    def close(self):
        for cls, name, f in self.undo:
            setattr(cls, name, f)


def _scene(gl, name: str):
    """(renderer, its settings maker, camera, hours) of a reference scene as each tree's
    CLI renders it (the generator's sea level where the tree has one; no sea where the
    area's edge is dry)."""
    from voxel_addon.light import daytime
    from voxel_addon.meshing import scenes
    from voxel_addon.render import Camera, Settings, source
    from voxel_addon.render.pipeline import Renderer
    sc, a = scenes.SCENES[name], source.scene_area(name)
    sea = source.scene_sea_level(name) if hasattr(source, "scene_sea_level") else None
    r = Renderer(gl, Settings() if sea is None else Settings(sea_level=sea))
    r.set_area(a.blocks, a.light, a.cx0, a.cy0, ring=True, light_at=a.light_at)
    if sea is not None and hasattr(source, "open_sea") and not source.open_sea(r):
        sea = -1

    def settings():
        return Settings() if sea is None else Settings(sea_level=sea)
    r.s = settings()
    return r, settings, Camera(*sc.camera), daytime.parse_time(sc.time)


def _profile(gl, rows: dict, small: bool) -> None:
    """Each pass's GL ms (median of 5 frames) and each effect switched off, at 1920x1080,
    on the ocean and the landscape scenes: where a frame's time goes."""
    from voxel_addon.bench.render import VARIANTS
    size, n = ((320, 180), 1) if small else ((1920, 1080), 5)
    for name in ("ocean", "landscape"):
        r, settings, cam, hours = _scene(gl, name)
        P = Passes(gl)
        try:
            r.draw(cam, hours, size)
            frames = [P.frame(lambda: r.draw(cam, hours, size)) for _ in range(n)]
        finally:
            P.close()
        seen: dict = {}
        for i, (label, _) in enumerate(frames[0]):  # the k-th pass of a program: label#k
            k = seen[label] = seen.get(label, -1) + 1
            rows[f"pass_{name}_{label}{f'#{k}' if k else ''}_ms"] = statistics.median(
                f[i][1] for f in frames)
        for vname, eff in VARIANTS:
            try:
                r.s = settings().with_effects(eff)
            except Exception:  # an effect this tree does not have
                continue
            rows[f"var_{name}_{vname}_ms"] = _best(gl, r, cam, hours, size, max(1, n - 2))[0]
        r.release()


def child(out: Path, small: bool) -> None:
    """One tree's frames (whichever voxel_addon is first on sys.path) into out (JSON)."""
    from voxel_addon.light import daytime
    from voxel_addon.meshing import build_chunk, scenes
    from voxel_addon.render import Camera, Settings, source
    from voxel_addon.render.pipeline import Renderer
    gl = _gl()
    rows = {"renderer": gl.info.get("GL_RENDERER", "?"), "version": gl.info.get("GL_VERSION")}
    sizes, n = (((160, 90), (320, 180)), 1) if small else (SIZES, 5)
    for name in scenes.SCENES:
        r, _, cam, hours = _scene(gl, name)
        for w, h in sizes:
            rows[f"gpu_{name}_{w}x{h}_ms"] = _best(gl, r, cam, hours, (w, h), n)[0]
        r.release()
    a = source.scene_area("landscape")
    tiles = [[build_chunk(a.blocks[16 * i:16 * i + 18, 16 * j:16 * j + 18], backend=None)
              for j in range(4)] for i in range(4)]
    size = (320, 180) if small else (1920, 1080)
    for d in ((4,) if small else (16, 32)):
        r = Renderer(gl, Settings(distance=d))
        t = time.perf_counter()
        r.set_meshes({(x, y): tiles[x % 4][y % 4]
                      for x in range(-d, d + 1) for y in range(-d, d + 1)})
        gl.finish()
        rows[f"gpu_d{d}_upload_all_ms"] = (time.perf_counter() - t) * 1e3
        r.set_light(a.light, a.cx0, a.cy0)
        for when, cam in (("12:00", Camera(8, 8, 100, 30, -12)),
                          ("18:30", Camera(8, 8, 100, 30, -12))):
            ms, py = _best(gl, r, cam, daytime.parse_time(when), size, n)
            tag = when.replace(":", "")
            rows[f"gpu_d{d}_{size[0]}x{size[1]}_{tag}_ms"] = ms
            rows[f"gpu_d{d}_{size[0]}x{size[1]}_{tag}_python_ms"] = py
        r.release()
    _profile(gl, rows, small)
    gl.release()
    out.write_text(json.dumps(rows))


def _run_tree(tree: Path, out: Path, small: bool) -> dict:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(tree)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", str(out)]
    subprocess.run(cmd + (["--small"] if small else []), env=env, check=True, cwd=tree)
    return json.loads(out.read_text())


def _area(out: Path, area: str, small: bool, log) -> None:
    """One bench area of this tree in its own process: its bench.csv as out/AREA.csv
    (its plots stay behind: a device run brings back few files)."""
    import shutil
    import tempfile
    tmp = Path(tempfile.mkdtemp(prefix=f"gpu-{area}-"))
    cmd = [sys.executable, "-m", "voxel_addon", "bench", "--area", area,
           "--out", str(tmp)] + (["--quick"] if small else [])
    t = time.perf_counter()
    rc = subprocess.run(cmd, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT).returncode
    if (tmp / "bench.csv").exists():
        shutil.copy(tmp / "bench.csv", out / f"{area}.csv")
    print(f"bench {area}: rc {rc} in {time.perf_counter() - t:.0f} s", flush=True)


def _far(out: Path, small: bool) -> None:
    """bench.far's frames alone (its GUI half needs Blender): far 256 against far 0."""
    import tempfile
    import psutil
    sys.path.insert(0, str(ROOT))
    from voxel_addon.bench import far

    class Ctx:
        quick, tmp = small, Path(tempfile.mkdtemp(prefix="gpu-far-"))
    with open(out / "far_frames.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["metric", "value", "unit", "note"])
        for row in far._frames(Ctx(), psutil.Process()):
            w.writerow(row)
            print(*row, sep="\t", flush=True)


def _frames(a, trees: dict, tmp: Path) -> None:
    """The rounds of frames, each tree in a fresh process, the order swapped each round."""
    runs: dict = {k: [] for k in trees}
    for i in range(a.rounds):
        order = list(trees) if i % 2 == 0 else list(trees)[::-1]
        for k in order:
            t = time.perf_counter()
            runs[k].append(_run_tree(trees[k], tmp / f"{k}{i}.json", a.small))
            print(f"round {i} {k}: {time.perf_counter() - t:.0f} s "
                  f"({runs[k][-1]['renderer']})", flush=True)
    with open(a.out / "frames.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["metric", "new_ms", "base_ms", "ratio", "ratio_min", "ratio_max",
                    "rounds"])
        for m in (m for m in runs["new"][0] if m.endswith("_ms")):
            new = statistics.median(r[m] for r in runs["new"])
            if "base" not in runs or m not in runs["base"][0]:
                w.writerow([m, f"{new:.3f}", "", "", "", "", a.rounds])
                continue
            base = statistics.median(r[m] for r in runs["base"])
            q = [n[m] / b[m] for n, b in zip(runs["new"], runs["base"])]
            w.writerow([m, f"{new:.3f}", f"{base:.3f}", f"{statistics.median(q):.3f}",
                        f"{min(q):.3f}", f"{max(q):.3f}", a.rounds])
    print((a.out / "frames.csv").read_text(), flush=True)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("out", type=Path)
    ap.add_argument("--base", type=Path, help="another revision's tree (holding voxel_addon/)")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--small", action="store_true")
    ap.add_argument("--child", action="store_true")
    ap.add_argument("--skip", nargs="*", default=[], help="parts to skip: frames far areas")
    a = ap.parse_args()
    if a.child:
        child(a.out, a.small)
        return 0
    a.out.mkdir(parents=True, exist_ok=True)
    import tempfile
    tmp = Path(tempfile.mkdtemp(prefix="gpu-frames-"))
    trees = {"new": ROOT} | ({"base": a.base.resolve()} if a.base else {})
    try:
        if "frames" not in a.skip:
            _frames(a, trees, tmp)
    except subprocess.CalledProcessError as e:  # far and the areas may still run
        print(f"frames failed: {e}", flush=True)
    if "far" not in a.skip:
        t = time.perf_counter()
        try:
            _far(a.out, a.small)
        except Exception as e:  # the frames above are already written
            print(f"far frames failed: {type(e).__name__}: {e}", flush=True)
        print(f"far frames in {time.perf_counter() - t:.0f} s", flush=True)
    if "areas" not in a.skip:
        with open(a.out / "areas.log", "w") as log:  # the areas' own progress lines
            for area in ("generation", "light", "meshing"):
                _area(a.out, area, a.small, log)
    return 0


if __name__ == "__main__":
    sys.exit(main())
