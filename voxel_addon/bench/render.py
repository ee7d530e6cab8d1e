"""Render bench: ms per frame at 640×360 on llvmpipe per reference scene and effect
(the analogue of thesis tables 6.10–6.14), triangles and draw calls, Python CPU ms."""
from __future__ import annotations

import time


def run(ctx):
    from ..meshing import scenes
    from ..render import Camera, Settings, sky, source
    from ..render.pipeline import Renderer
    gl = source.context()
    size = (320, 180) if ctx.quick else (640, 360)
    variants = [("default", {}), ("no_effects", {"effects": "none"}),
                ("no_shadows", {"effects": "-shadows"}), ("ssao", {"effects": "+ssao"}),
                ("peel0", {"effects": "peel0"}), ("msaa1", {"effects": "msaa1"})]
    if ctx.quick:
        variants = variants[:2]
    for name in scenes.SCENES:
        sc = scenes.SCENES[name]
        blocks, light, cx0, cy0 = source.scene_area(name)
        r = Renderer(gl, Settings())
        r.set_area(blocks, light, cx0, cy0, ring=True)
        hours = sky.parse_time(sc.time)
        for vname, v in variants:
            r.s = Settings().with_effects(v.get("effects"))
            cam = Camera(*sc.camera)
            r.render(cam, hours, size)  # compile + warm up
            n = 2
            t0 = time.perf_counter()
            cpu = 0.0
            for _ in range(n):
                r.render(cam, hours, size)
                cpu += r.stats["cpu_ms"]
            ms = (time.perf_counter() - t0) / n * 1e3
            yield (f"render_{name}_{vname}_ms", ms, "ms", f"{size[0]}x{size[1]} llvmpipe, frame incl. readback")
            if vname == "default":
                st = r.stats
                yield (f"render_{name}_triangles", st["triangles"], "", "incl. shadow + peel layers")
                yield (f"render_{name}_draw_calls", st["draw_calls"], "", "")
                yield (f"render_{name}_cpu_submit_ms", cpu / n, "ms",
                       "Python time until the last GL call returns (llvmpipe may block in it)")
        r.release()
    gl.release()
