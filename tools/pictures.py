"""The README's pictures and the before/after sheets (issue 20), through the CLI.

    python tools/pictures.py render OUT [--only NAME ...] [--times 07:00,12:00 ...]
    python tools/pictures.py sheet BEFORE AFTER OUT.png [--only NAME ...]
    python tools/pictures.py grid DIR OUT.png
    python tools/pictures.py readme BEFORE AFTER      (docs/images: heroes, grid, sheets)

`render` draws the four reference scenes (meshing.scenes) and three generated seed-7
worlds (a coast with hills, a desert, a mountain range: the bench's biome windows) at
dawn, noon, dusk and night into OUT/<view>_<HHMM>.png, 640x360. It runs
`python -m voxel_addon render` in a subprocess, from the current directory: run it
from an older checkout (`cd old && python NEW/tools/pictures.py render OUT`) to render
the same views with that code (the "before" side). The world files
are generated once into OUT/../worlds. Cameras of the worlds are aimed from ground
heights (`aim`), so they need no retuning when the generator changes a little.
`sheet` puts before and after side by side, one row per picture; `grid` puts a
folder's pictures on one page (views as rows, times as columns). `readme` renders the
README's pictures into docs/images (the coast at noon and dusk, at night with lamps
placed by `edit` in a copy of the world, the desert and the mountains at dawn) and
puts the `render` folders AFTER (this code) and BEFORE (older code) into
docs/images/times.jpg (every view at every time) and before_after.jpg.
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
# far terrain (chunks) beyond the view distance: the world goes on past the generated
# area instead of ending at a haze wall
FAR = ("--far", 96)


def cli(*args, env=None) -> None:
    env = dict(env or os.environ, PYTHONPATH=os.getcwd())  # the checkout it runs in
    r = subprocess.run([sys.executable, "-m", "voxel_addon", *map(str, args)],
                       capture_output=True, text=True, env=env)
    if r.returncode:
        raise SystemExit(f"voxel_addon {' '.join(map(str, args[:3]))}: {r.stderr.strip()[-800:]}")


def ground(path: Path, x: float, y: float, dry: bool = False) -> int:
    """The highest non-air block's z at column (x, y) of a world file (dry: -1 where
    that is water)."""
    sys.path.insert(0, str(ROOT))
    from voxel_addon.core.blocks import REGISTRY
    from voxel_addon.world import World
    from voxel_addon.generation import topview
    w = World.open(path, readonly=True, loader=False)
    try:
        cx, cy = math.floor(x) >> 4, math.floor(y) >> 4
        b = w.region_blocks(cx, cy, cx + 1, cy + 1)
        top, z = topview.surface(b)
        i, j = math.floor(x) - 16 * cx, math.floor(y) - 16 * cy
        if dry and top[i, j] == REGISTRY.id("water"):
            return -1
        return int(z[i, j])
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
                    "--distance", dist, *FAR, "--out", out / f"world_{name}_{tag}.png", *extra)
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


def _shrink(img, scale: int):
    """Box-filtered down by an integer factor."""
    h, w = img.shape[0] // scale * scale, img.shape[1] // scale * scale
    return img[:h, :w].reshape(h // scale, scale, w // scale, scale, 3).mean((1, 3))


def _write(img, out: Path) -> None:
    if out.suffix == ".jpg":  # the big sheets: a tenth of the PNG's size
        from matplotlib.image import imsave
        import numpy as np
        out.parent.mkdir(parents=True, exist_ok=True)
        imsave(str(out), np.clip(img, 0, 1), pil_kwargs={"quality": 88})
    else:
        _save(img, out)


def grid(folder: Path, out: Path, scale: int = 2, before: Path | None = None) -> None:
    """Views as rows, times as columns, each picture shrunk by `scale`; with `before`,
    each cell is before | after."""
    import numpy as np
    names = sorted(folder.glob("*.png"))
    views = sorted({p.stem.rsplit("_", 1)[0] for p in names})
    times = sorted({p.stem.rsplit("_", 1)[1] for p in names})
    blank = np.zeros((SIZE[1] // scale, SIZE[0] // scale, 3))
    rows = []
    for v in views:
        cells = []
        for t in times:
            for d in ((before, folder) if before else (folder,)):
                p = d / f"{v}_{t}.png"
                img = _shrink(_load(p), scale) if p.exists() else blank
                cells += [img, np.ones((img.shape[0], 2, 3))]
            if before:
                cells += [np.ones((img.shape[0], 6, 3))]
        rows += [np.concatenate(cells[:-1], 1)]
        rows += [np.ones((2 if not before else 6, rows[-1].shape[1], 3))]
    _write(np.concatenate(rows[:-1], 0), out)
    print(out, f"{len(views)} views x {len(times)} times")


LAMPS = ("lamp_yellow", "lamp_red", "lamp_green", "lamp_blue", "lamp_white")


def readme(before: Path, after: Path, images: Path = ROOT / "docs" / "images") -> None:
    import shutil
    ws = worlds(after.parent / "worlds")
    path, cam, dist = ws["coast"]
    for t, name in (("10:30", "day.png"), ("17:45", "dusk.png")):
        cli("render", "--world", path, "--camera", *cam, "--time", t, "--size", *SIZE,
            "--distance", dist, *FAR, "--out", images / name)
    lit = after.parent / "worlds" / "coast_lamps.sqlite"
    shutil.copy(path, lit)
    # lamps along the beach and up the hill, in view of the coast's camera
    ex, ey, _, yaw, _ = cam
    a = math.radians(yaw)
    spots = [(d, side) for d in range(12, 84, 9) for side in (-34, -22, -10, 2)]
    for i, (d, side) in enumerate(spots):
        x = round(ex + d * math.cos(a) - side * math.sin(a) + (i * 7) % 5 - 2)
        y = round(ey + d * math.sin(a) + side * math.cos(a) + (i * 3) % 5 - 2)
        z = ground(lit, x, y, dry=True)
        if z >= 0:  # not on the water
            cli("edit", "--world", lit, "--set", x, y, z + 1, LAMPS[i % len(LAMPS)])
    cli("render", "--world", lit, "--camera", *cam, "--time", "22:30", "--size", *SIZE,
        "--distance", dist, *FAR, "--out", images / "night_lamps.png")
    for name, world in (("desert.png", "desert"), ("mountains.png", "mountains")):
        p, c, dd = ws[world]
        cli("render", "--world", p, "--camera", *c, "--time", "07:00", "--size", *SIZE,
            "--distance", dd, *FAR, "--out", images / name)
    grid(after, images / "times.jpg", scale=2)
    grid(after, images / "before_after.jpg", scale=3, before=before)


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
    m = sub.add_parser("readme")
    m.add_argument("before", type=Path)
    m.add_argument("after", type=Path)
    a = ap.parse_args(argv)
    if a.cmd == "render":
        render(a.out, a.only, a.times.split(","), a.extra)
    elif a.cmd == "sheet":
        sheet(a.before, a.after, a.out, a.only)
    elif a.cmd == "readme":
        readme(a.before, a.after)
    else:
        grid(a.folder, a.out)


if __name__ == "__main__":
    main()
