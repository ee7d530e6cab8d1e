"""Run in a fresh process by test_animation.py: Render Voxel Animation of a flat
world, the camera keyframed and the day cycle following the timeline.

    python tests/blender/anim_job.py OUT_DIR          # 3 PNG frames
    python tests/blender/anim_job.py OUT_DIR movie    # 6 frames as PNG and as MPEG-4

The movie mode also decodes the video again with Blender (a movie clip for its
length and size; a movie strip rendered to PNG for a frame's pixels).
"""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from flat_scene import flat_scene  # noqa: E402


def scene(out: Path, n: int):
    import bpy
    sc = flat_scene(out)
    vv = sc.voxel_view
    vv.follow_timeline, vv.frames_per_day, vv.hours = True, 4, 12.0  # noon, 18:00, midnight
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    sc.collection.objects.link(cam)
    sc.camera = cam
    cam.rotation_euler = (math.radians(80.0), 0.0, math.radians(-90.0))
    for f, x in ((1, 8.0), (n, 8.0 + 16.0 * (n - 1))):
        cam.location = (x, 8.0, 90.0)
        cam.keyframe_insert("location", frame=f)
    sc.frame_start, sc.frame_end = 1, n
    sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 64, 36, 100
    sc.render.filepath = str(out / "frames" / "f_")
    return sc


def decode(path: str, frames: list[int], out: Path, size) -> list[str]:
    """Frames of the movie at PATH as PNG files, decoded by Blender's movie strip."""
    import bpy
    sc = bpy.data.scenes.new("decode")
    r = sc.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = *size, 100
    r.image_settings.file_format = "PNG"
    sc.view_settings.view_transform = "Standard"
    se = sc.sequence_editor_create()
    strips = se.strips if hasattr(se, "strips") else se.sequences
    strips.new_movie("m", path, 1, 1)
    names = []
    for f in frames:
        sc.frame_set(f)
        bpy.context.scene.frame_current = f  # render.render(scene=) takes the frame from it
        r.filepath = str(out / f"decoded_{f}.png")
        assert bpy.ops.render.render(write_still=True, scene=sc.name) == {"FINISHED"}
        names.append(f"decoded_{f}.png")
    bpy.data.scenes.remove(sc)
    return names


def main():
    out = Path(sys.argv[1])
    movie = sys.argv[2:] == ["movie"]
    import bpy
    import voxel_addon
    sc = scene(out, 6 if movie else 3)
    res = bpy.ops.voxel.render_animation()
    files = sorted(p.name for p in (out / "frames").glob("*.png"))
    info = {"result": sorted(res), "files": files, "frame": sc.frame_current}
    if movie:
        r = sc.render
        im = r.image_settings
        if hasattr(im, "media_type"):
            im.media_type = "VIDEO"
        im.file_format = "FFMPEG"
        r.ffmpeg.format, r.ffmpeg.codec = "MPEG4", "H264"
        r.ffmpeg.constant_rate_factor = "HIGH"
        r.filepath = str(out / "video" / "fly_")
        res = bpy.ops.voxel.render_animation()
        video = Path(bpy.path.abspath(r.frame_path()))
        clip = bpy.data.movieclips.load(str(video))
        info["movie"] = {"result": sorted(res), "path": video.name,
                         "files": sorted(p.name for p in (out / "video").iterdir()),
                         "duration": clip.frame_duration, "size": list(clip.size),
                         "scenes": sorted(s.name for s in bpy.data.scenes),
                         "decoded": decode(str(video), [1, 3, 5], out, (64, 36))}
    (out / "anim.json").write_text(json.dumps(info))
    voxel_addon.unregister()


if __name__ == "__main__":
    main()
