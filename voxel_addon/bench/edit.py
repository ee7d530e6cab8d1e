"""Edit bench (issue 13): the Voxel Edit tool in the real Blender GUI under Xvfb at
1280x720 on llvmpipe, driven by simulated events (tools/edit_bench_job.py, started
through bench/gui.py), with the voxel view shown.

Rows: click -> the voxel frame that shows the edit (median, p90); stroke done -> that
frame (and whether it is the next one); the stroke path's own time per click (world
edit: relight, remesh, one transaction); the frame time beside it; a fast paint
drag: voxels per second of wall time and of stroke path alone.
Needs `python build.py setup` (.blender/, Xvfb); without them the area yields a note.
"""
from __future__ import annotations

from . import gui


def run(ctx):
    why = gui.missing()
    if why:
        yield ("edit_skipped", 1, "", why)
        return
    out = ctx.tmp / "edit"
    out.mkdir(exist_ok=True)
    ctx.say("Blender GUI: clicks and a paint drag with the voxel view shown")
    R = gui.run_job("edit", [out, "6" if ctx.quick else "20"], out / "edit.json",
                    out / "blender.log", timeout=1200, simulate=True)
    if R.get("error"):
        raise RuntimeError(R["error"])
    n, size = R["clicks"], "x".join(map(str, R["region"]))
    yield ("edit_click_to_pixels_ms", R["click_median_ms"], "ms",
           f"median of {n} clicks: press queued -> the voxel frame showing the edit (a frame "
           f"in flight, the stroke, the next frame), region {size}, distance 3")
    yield ("edit_click_to_pixels_p90_ms", R["click_p90_ms"], "ms", f"p90 of {n} clicks")
    yield ("edit_applied_to_pixels_ms", R["edit_to_frame_ms"], "ms",
           f"median: stroke done -> frame showing it; the first frame after the stroke showed "
           f"it in {R['first_frame_shows']} of {n} clicks")
    yield ("edit_stroke_ms", R["stroke_median_ms"], "ms",
           "median stroke path per click (world edit: relight, remesh, one transaction)")
    yield ("edit_frame_ms", R["frame_ms"], "ms", "a voxel view frame beside it (full quality)")
    yield ("edit_paint_edits_per_s", R["paint_wall"], "voxels/s",
           f"fast drag of {R['paint_voxels']} voxels, press -> stroke recorded (frames included)")
    yield ("edit_paint_stroke_path_edits_per_s", R["paint_path"], "voxels/s",
           "the same drag, stroke path time only")
