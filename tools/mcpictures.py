"""The README's picture of a Minecraft import with and without a resource stack
(issue 30), through the CLI.

    python tools/mcpictures.py [OUT.jpg]      (default docs/images/minecraft_stack.jpg)

It writes the tests' small build (tests/mcres/builds.py: stairs, slabs, a fence, a
glass pane row, doors, rails, a torch, a poppy, leaves, grass) and their resource pack
(tests/mcres/packfiles.py: textures drawn by code, never Minecraft's files) into a
temporary folder, imports the build twice (`import --resources client.jar` and
without), renders both from one camera with `python -m voxel_addon render` and puts
them side by side: with the stack on the left, today's look on the right.
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIZE = (560, 340)
# voxel frame (x east, y north, z up): south-east of the build, looking north-west
CAMERA = (12.5, -15.5, 68.5, 128, -25)
TIME = "10:30"


def render(world: Path, out: Path) -> None:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    r = subprocess.run([sys.executable, "-m", "voxel_addon", "render", "--world", str(world),
                        "--camera", *map(str, CAMERA), "--distance", "1", "--time", TIME,
                        "--size", *map(str, SIZE), "--out", str(out)],
                       capture_output=True, text=True, env=env)
    if r.returncode:
        raise SystemExit(f"render {world.name}: {r.stderr.strip()[-800:]}")


def main(argv=None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    out = Path(argv[0]) if argv else ROOT / "docs" / "images" / "minecraft_stack.jpg"
    sys.path.insert(0, str(ROOT))
    import numpy as np
    from PIL import Image
    from tests.mcres.builds import imported
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        worlds, _ = imported(root)
        imgs = []
        for name in ("with", "without"):
            render(worlds[name], root / f"{name}.png")
            imgs.append(np.asarray(Image.open(root / f"{name}.png").convert("RGB")))
    gap = np.full((SIZE[1], 6, 3), 255, np.uint8)
    out.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.concatenate([imgs[0], gap, imgs[1]], axis=1)).save(out, quality=88)
    print(out, out.stat().st_size // 1024, "KB")


if __name__ == "__main__":
    main()
