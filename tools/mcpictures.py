"""The README's picture of a Minecraft import with and without a resource stack
(issue 30), through the CLI.

    python tools/mcpictures.py [OUT.jpg]      (default docs/images/minecraft_stack.jpg)
    python tools/mcpictures.py live [--backend opengl|vulkan] [--blender 5.2] [OUT.jpg]
                                              (default docs/images/minecraft_stack_live.jpg)

The first writes the tests' small build (tests/mcres/builds.py: stairs, slabs, a fence, a
glass pane row, doors, rails, a torch, a poppy, leaves, grass) and their resource pack
(tests/mcres/packfiles.py: textures drawn by code, never Minecraft's files) into a
temporary folder, imports the build twice (`import --resources client.jar` and
without), renders both from one camera with `python -m voxel_addon render` and puts
them side by side: with the stack on the left, today's look on the right.
`live` runs the GUI test tests/gui/test_minecraft_stack_view.py (the same build in
Blender's viewport, the live view at full quality) in the given Blender and GPU
backend and puts its two screenshots' 3D views side by side, half size.
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


def _side_by_side(imgs, out: Path) -> None:
    import numpy as np
    from PIL import Image
    gap = np.full((imgs[0].shape[0], 6, 3), 255, np.uint8)
    out.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.concatenate([imgs[0], gap, imgs[1]], axis=1)).save(out, quality=88)
    print(out, out.stat().st_size // 1024, "KB")


def live(out: Path, backend: str = "opengl", blender: str = "5.2") -> None:
    import json
    import numpy as np
    from PIL import Image
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, VOXEL_BLENDER_APP=blender, VOXEL_GPU_BACKEND=backend)
        r = subprocess.run([sys.executable, str(ROOT / "build.py"), "test",
                            "tests/gui/test_minecraft_stack_view.py", "-q", f"--basetemp={tmp}"],
                           cwd=ROOT, env=env, capture_output=True, text=True)
        if r.returncode:
            raise SystemExit(f"GUI test: {r.stdout.strip()[-800:]}")
        run = next(p for p in sorted(Path(tmp).glob("test_model_blocks_in_the_live*/out"))
                   if not p.parent.is_symlink())
        x, y, w, h = json.loads((run / "result.json").read_text())["result"]["rect"]
        imgs = []
        for name in ("with", "without"):
            a = np.asarray(Image.open(run / f"{name}.png").convert("RGB"))
            top = a.shape[0] - (y + h)
            # the 3D view without its header and toolbar, half size
            view = Image.fromarray(a[top + 60:top + h, x + 60:x + w - 12])
            imgs.append(np.asarray(view.resize((view.width // 2, view.height // 2), Image.LANCZOS)))
    _side_by_side(imgs, out)


def main(argv=None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["live"]:
        import argparse
        ap = argparse.ArgumentParser()
        ap.add_argument("out", nargs="?", type=Path,
                        default=ROOT / "docs" / "images" / "minecraft_stack_live.jpg")
        ap.add_argument("--backend", default="opengl", choices=("opengl", "vulkan"))
        ap.add_argument("--blender", default="5.2")
        a = ap.parse_args(argv[1:])
        return live(a.out, a.backend, a.blender)
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
    _side_by_side(imgs, out)


if __name__ == "__main__":
    main()
