"""The README's pictures and the before/after sheets (issue 20), through the CLI.

    python tools/pictures.py render OUT [--only NAME ...] [--times 07:00,12:00 ...]
    python tools/pictures.py sheet BEFORE AFTER OUT.png [--only NAME ...]
    python tools/pictures.py grid DIR OUT.png

`render` draws the four reference scenes (meshing.scenes) and three generated seed-7
worlds (a coast with hills, a desert, a mountain range: the bench's biome windows) at
dawn, noon, dusk and night into OUT/<view>_<HHMM>.png, 640x360. It runs
`python -m voxel_addon render` in a subprocess, from the current directory: run it
from an older checkout (`cd old && python NEW/tools/pictures.py render OUT`) to render
the same views with that code (the "before" side). The world files
are generated once into OUT/../worlds. Cameras of the worlds are aimed from ground
heights (`aim`), so they need no retuning when the generator changes a little.
`sheet` puts before and after side by side, one row per picture; `grid` puts a
folder's pictures on one page (views as rows, times as columns).
"""
from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TIMES = ("07:00", "12:00", "18:30", "23:30")
SIZE = (640, 360)
# name -> (seed, centre block (x, y)); eye (x, y, metres above ground), target (x, y,
# above), view distance (chunks: the mountains stand at the edge of 8)
WORLDS = {
    "coast": (7, (0, -192), (45, -330, 22), (-90, -215, 10), 8),
    "desert": (7, (4096, -2400), (4150, -2330, 20), (4000, -2470, 0), 8),
    "mountains": (7, (4768, -3328), (4775, -3320, 45), (4690, -3440, 0), 12),
}
SCENES = ("ocean", "desert", "landscape", "cave")


def cli(*args, env=None) -> None:
    env = dict(env or os.environ, PYTHONPATH=os.getcwd())  # the checkout it runs in
    r = subprocess.run([sys.executable, "-m", "voxel_addon", *map(str, args)],
                       capture_output=True, text=True, env=env)
    if r.returncode:
        raise SystemExit(f"voxel_addon {' '.join(map(str, args[:3]))}: {r.stderr.strip()[-800:]}")


def ground(path: Path, x: float, y: float) -> int:
    """The highest non-air block's z at column (x, y) of a world file."""
    sys.path.insert(0, str(ROOT))
    from voxel_addon.world import World
    from voxel_addon.generation import topview
    w = World.open(path, readonly=True, loader=False)
    try:
        cx, cy = math.floor(x) >> 4, math.floor(y) >> 4
        b = w.region_blocks(cx, cy, cx + 1, cy + 1)
        _, z = topview.surface(b)
        return int(z[math.floor(x) - 16 * cx, math.floor(y) - 16 * cy])
    finally:
        w.close()


def aim(path: Path, eye, target) -> tuple[float, ...]:
    """CLI camera (x, y, z, yaw, pitch) at eye[2] above the ground at eye, looking at
    target[2] above the ground at target."""
    ex, ey = eye[:2]
    tx, ty = target[:2]
    ez = ground(path, ex, ey) + eye[2]
    tz = ground(path, tx, ty) + target[2]
    dx, dy, dz = tx - ex, ty - ey, tz - ez
    yaw = math.degrees(math.atan2(dy, dx))
    pitch = math.degrees(math.atan2(dz, math.hypot(dx, dy)))
    return (ex, ey, ez, round(yaw, 2), round(pitch, 2))


def worlds(folder: Path) -> dict:
    folder.mkdir(parents=True, exist_ok=True)
    out = {}
    for name, (seed, (x, y), eye, target, dist) in WORLDS.items():
        path = folder / f"{name}.sqlite"
        if not path.exists():
            cli("generate", "--world", path, "--seed", seed, "--center", x, y, "--radius", 14)
        out[name] = (path, aim(path, eye, target), dist)
    return out


def render(out: Path, only=(), times=TIMES, extra=()) -> None:
    out.mkdir(parents=True, exist_ok=True)
    ws = worlds(out.parent / "worlds")
    for t in times:
        tag = t.replace(":", "")
        for name in SCENES:
            if not only or f"scene_{name}" in only:
                cli("render", "--scene", name, "--time", t, "--size", *SIZE,
                    "--out", out / f"scene_{name}_{tag}.png", *extra)
        for name, (path, cam, dist) in ws.items():
            if not only or f"world_{name}" in only:
                cli("render", "--world", path, "--camera", *cam, "--time", t, "--size", *SIZE,
                    "--distance", dist, "--out", out / f"world_{name}_{tag}.png", *extra)
        print(f"rendered {t}", flush=True)


def _load(p: Path):
    from matplotlib.image import imread
    return imread(str(p))[..., :3]


def _save(img, path: Path) -> None:
    import numpy as np
    sys.path.insert(0, str(ROOT))
    from voxel_addon.textures import png_bytes
    a = (np.clip(img, 0, 1) * 255).round().astype(np.uint8)
    a = np.dstack([a, np.full(a.shape[:2], 255, np.uint8)])
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(png_bytes(a))


def sheet(before: Path, after: Path, out: Path, only=()) -> None:
    """Before | after per row, a 4-pixel white gap, every picture both sides have."""
    import numpy as np
    names = sorted(p.name for p in after.glob("*.png") if (before / p.name).exists()
                   and (not only or any(p.name.startswith(o) for o in only)))
    rows = []
    for n in names:
        a, b = _load(before / n), _load(after / n)
        gap = np.ones((a.shape[0], 4, 3))
        rows += [np.concatenate([a, gap, b], 1), np.ones((4, 2 * a.shape[1] + 4, 3))]
    _save(np.concatenate(rows[:-1], 0), out)
    print(out, len(names), "rows")


def grid(folder: Path, out: Path, scale: int = 2) -> None:
    """Views as rows, times as columns, each picture shrunk by `scale`."""
    import numpy as np
    names = sorted(folder.glob("*.png"))
    views = sorted({p.stem.rsplit("_", 1)[0] for p in names})
    times = sorted({p.stem.rsplit("_", 1)[1] for p in names})
    rows = []
    for v in views:
        cells = []
        for t in times:
            p = folder / f"{v}_{t}.png"
            img = _load(p)[::scale, ::scale] if p.exists() else np.zeros((SIZE[1] // scale, SIZE[0] // scale, 3))
            cells += [img, np.ones((img.shape[0], 2, 3))]
        rows += [np.concatenate(cells[:-1], 1)]
        rows += [np.ones((2, rows[-1].shape[1], 3))]
    _save(np.concatenate(rows[:-1], 0), out)
    print(out, f"{len(views)} views x {len(times)} times")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("render")
    r.add_argument("out", type=Path)
    r.add_argument("--only", nargs="*", default=())
    r.add_argument("--times", default=",".join(TIMES))
    r.add_argument("--extra", nargs=argparse.REMAINDER, default=[])
    s = sub.add_parser("sheet")
    s.add_argument("before", type=Path)
    s.add_argument("after", type=Path)
    s.add_argument("out", type=Path)
    s.add_argument("--only", nargs="*", default=())
    g = sub.add_parser("grid")
    g.add_argument("folder", type=Path)
    g.add_argument("out", type=Path)
    a = ap.parse_args(argv)
    if a.cmd == "render":
        render(a.out, a.only, a.times.split(","), a.extra)
    elif a.cmd == "sheet":
        sheet(a.before, a.after, a.out, a.only)
    else:
        grid(a.folder, a.out)


if __name__ == "__main__":
    main()
