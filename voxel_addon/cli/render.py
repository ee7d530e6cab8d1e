"""render: one frame of a world (or a reference scene) through the viewport pipeline to PNG."""
from __future__ import annotations

import math
from pathlib import Path

from ..core.errors import VoxelError


def add_parser(sub):
    from ..meshing import METHODS
    from ..meshing.scenes import SCENES
    from ..render.settings import DEBUG_VIEWS
    p = sub.add_parser("render", help="render a world view to a PNG (headless OpenGL)")
    p.add_argument("--world", type=Path, metavar="W.sqlite", help="world file (.sqlite)")
    p.add_argument("--camera", nargs=5, type=float, metavar=("X", "Y", "Z", "YAW", "PITCH"),
                   help="position in blocks; yaw deg CCW from +x; pitch deg, up positive")
    p.add_argument("--time", default=None, metavar="HH:MM", help="time of day (default 12:00)")
    p.add_argument("--size", nargs=2, type=int, default=(640, 360), metavar=("W", "H"))
    p.add_argument("--out", required=True, type=Path, metavar="F.png")
    p.add_argument("--distance", type=int, default=None, help="view distance in chunks")
    p.add_argument("--far", type=int, default=None, metavar="N",
                   help="far terrain out to N chunks beyond the view distance (0..256, 0: off; "
                        "a world only)")
    p.add_argument("--effects", default=None,
                   help="comma list: all, none, [+-]shadows, ssao, fog, dof, godrays, waving, "
                        "smooth_mag, fill_holes, msaa_alpha, per_sample, peel0..3 (depth peeling, "
                        "the default), oit (weighted blended OIT instead), msaa1/2/4/8")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="tune a setting, e.g. godray_strength=2, shadow_size=4096, fov=60, "
                        "shadow_fade=80, ssao_radius=1.5 (repeatable; see render/settings.py)")
    p.add_argument("--debug-view", default="none", choices=DEBUG_VIEWS)
    p.add_argument("--scene", choices=tuple(SCENES),
                   help="a reference scene (its terrain, camera and time; --camera/--time override)")
    p.add_argument("--aggregation", default="greedy",
                   choices=METHODS,
                   help="meshing method (face aggregation)")
    return p


def run(args):
    from ..render import Camera, Settings
    from ..light import daytime
    from ..render import source
    from ..render.device import mgl
    from ..render.pipeline import Renderer
    from ..textures import png_bytes
    import numpy as np

    from .common import out_file, write_out
    out_file(args.out, make_folder=True, world=args.world)
    w, h = args.size
    if not (8 <= w <= 8192 and 8 <= h <= 8192):
        raise VoxelError("--size must be between 8 and 8192 pixels per side")
    s = Settings(debug=args.debug_view).with_effects(args.effects).with_values(args.set)
    if args.distance is not None:
        s.distance = args.distance
    if args.far is not None:
        s.far = args.far
    s.check()
    if s.far and args.world is None:
        raise VoxelError("--far needs --world (a scene has no terrain beyond it)")
    cam_args, hhmm = args.camera, args.time
    if args.scene:
        from ..meshing import scenes
        sc = scenes.SCENES[args.scene]
        cam_args = cam_args or sc.camera
        hhmm = hhmm or sc.time
    elif args.world is None or cam_args is None:
        raise VoxelError("render needs --world and --camera (or --scene)")
    else:
        from ..storage import check_path
        check_path(args.world)
    # every cheap check before the slow part (loading, lighting, meshing)
    hours = daytime.parse_time(hhmm or "12:00")
    if not 0 <= cam_args[2] <= 400:
        raise VoxelError("camera z must be between 0 and 400")
    if not all(math.isfinite(v) for v in cam_args):
        raise VoxelError("--camera takes finite numbers")
    from ..core.chunk import REACH
    if not all(-REACH <= v < REACH for v in cam_args[:2]):
        raise VoxelError(f"camera x, y must lie inside the world (-{REACH}..{REACH})")
    far_meshes = []
    if args.scene:
        data = source.scene_area(args.scene)
        sea = source.scene_sea_level(args.scene)
    else:
        from ..world import World
        world = World.open(args.world, readonly=True, loader=False)
        try:
            data = source.world_area(world, cam_args[0], cam_args[1], s.distance,
                                     s.light_radius)
            if s.far:
                from ..far import ring
                far_meshes = ring(world.file, world.generator, cam_args[0], cam_args[1],
                                  s.far, _whole(world.file, cam_args[0], cam_args[1], s.distance))
            sea = source.sea_level(world.generator)
        finally:
            world.close()
    if not any(i.startswith("sea_level=") for i in args.set):
        s.sea_level = sea
    ctx = mgl.context()
    r = Renderer(ctx, s)
    r.set_area(data.blocks, data.light, data.cx0, data.cy0, ring=True, method=args.aggregation,
               light_at=data.light_at, data=data.data)
    if data.models:
        r.set_models(data.models)
    if data.palette is not None:
        r.set_palette(data.palette)
    r.update_far(far_meshes)
    asked = any(e.strip().lstrip("+-") == "sea" for e in (args.effects or "").split(","))
    if not asked and not source.open_sea(r):
        r.s.sea = False  # the area's edge is dry land: it fades into the haze
    img = r.render(Camera(*cam_args), hours, (w, h))
    rgba = np.dstack([img, np.full(img.shape[:2], 255, np.uint8)])
    write_out(args.out, png_bytes(rgba))
    st = r.stats
    print(f"{args.out}: {w}x{h}, {st['triangles']} triangles, {st['draw_calls']} draw calls")
    r.release()
    ctx.release()


def _whole(wf, x: float, y: float, distance: int) -> int:
    """The radius of the chunk square around (x, y) that the file has whole, up to the
    view distance: far tiles leave out only that square, so a world smaller than the
    view goes on in far terrain (the demo's beach beyond its 9 x 9 chunks was a gap
    down to the sea plane, its edge a line in the sand)."""
    keys = set(wf.chunk_keys())
    cx, cy = math.floor(x) // 16, math.floor(y) // 16
    for d in range(distance + 1):
        ring = [(cx + i, cy + j) for i in range(-d, d + 1) for j in range(-d, d + 1)
                if max(abs(i), abs(j)) == d]
        if any(k not in keys for k in ring):
            return max(d - 1, 0)
    return distance
