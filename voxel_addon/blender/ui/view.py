"""View section: the world live in every 3D viewport (scene.voxel_view, issue 12),
and rendering it from the scene camera (Render Voxel View, Render Animation)."""
from __future__ import annotations

import math

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty

IMAGE = "Voxel View"


def _redraw(self, context):
    from .. import liveview
    liveview.sync(context)


# The viewport is where people build: a distance blur hides what they point at, so it
# starts off here (the CLI's renders keep Settings' default).
VIEWPORT_OFF = ("dof",)
LABELS = {"ssr": "Screen Space Reflections"}  # (as Eevee names it; others: the name, titled)
def _effects():
    """One bool per effect (defaults from Settings(), but VIEWPORT_OFF)."""
    from ...render.settings import Settings
    from ..liveview.options import effects
    s = Settings()
    return {e: BoolProperty(name=LABELS.get(e, e.replace("_", " ").title()),
                            default=getattr(s, e) and e not in VIEWPORT_OFF,
                            update=_redraw) for e in effects()}


def _debug_items(self, context):
    from ...render.settings import DEBUG_VIEWS
    return [(d, d.title(), f"debug view: {d}") for d in DEBUG_VIEWS]


VoxelViewSettings = type("VoxelViewSettings", (bpy.types.PropertyGroup,), {"__annotations__": {
    "show": BoolProperty(name="Show in Viewport", default=False, update=_redraw,
                         description="Draw the open world in every 3D viewport of the scene"),
    "distance": IntProperty(name="Distance", default=8, min=1, max=32, update=_redraw,
                            description="View distance in chunks (16 blocks)"),
    "far": IntProperty(name="Far", default=0, min=0, max=256, update=_redraw,
                       description="Far terrain beyond Distance out to this many chunks, in "
                                   "coarser levels of detail (256 = 4 km; 0 = off)"),
    "hours": FloatProperty(name="Time of Day", default=12.0, min=0.0, max=24.0, update=_redraw,
                           description="Hours (0 midnight, 12 noon); animatable"),
    "follow_timeline": BoolProperty(name="Follow Timeline", default=False, update=_redraw,
                                    description="The day cycle follows the current frame (Time of Day at the first frame)"),
    "frames_per_day": IntProperty(name="Frames per Day", default=240, min=1, update=_redraw,
                                  description="Frames of one day when following the timeline"),
    "quality": EnumProperty(name="Quality", default="auto", update=_redraw, items=[
        ("auto", "Auto", "Draft while the view moves, full when it is still"),
        ("draft", "Draft", "Half resolution, no shadows, SSAO or distance blur"),
        ("full", "Full", "Every chosen effect at full resolution")]),
    **_effects(),
    "transparency": EnumProperty(name="Transparency", default="peel", update=_redraw, items=[
        ("peel", "Depth Peeling", "Exact, up to 3 layers"),
        ("oit", "Weighted OIT", "One pass, approximate order")]),
    "sky": BoolProperty(name="Sky", default=True, update=_redraw,
                        description="The pipeline's sky where Blender drew nothing"),
    "exposure": FloatProperty(name="Exposure", default=0.0, min=-10.0, max=10.0, update=_redraw,
                              description="Stops over the time of day's own exposure"),
    "haze": FloatProperty(name="Haze", default=1.0, min=0.0, max=20.0, update=_redraw,
                          description="Density of the haze (the Fog effect), thinning with altitude"),
    "cloud_cover": FloatProperty(name="Cloud Cover", default=0.45, min=0.0, max=1.0,
                                 update=_redraw, description="0 clear sky, 1 overcast"),
    "debug_view": EnumProperty(name="Debug View", items=_debug_items, update=_redraw),
}})


def camera_of(obj):
    """A render Camera at a Blender camera object (1 block = 1 unit, z up), and its
    vertical field of view in degrees."""
    from ...render import Camera
    m = obj.matrix_world
    f = -m.col[2].xyz.normalized()  # cameras look down their local -z
    yaw = math.degrees(math.atan2(f.y, f.x))
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, f.z))))
    p = m.translation
    return Camera(p.x, p.y, p.z, yaw, pitch), math.degrees(obj.data.angle_y)


def chunks_line(st: dict) -> str:
    """The View panel's progress line from LIVE.stats: "loading…" until every wanted
    chunk was drawn in a frame, and while no chunk is wanted yet (the stream not
    started: 0 / 0 is not a finished view of sky)."""
    done = st["wanted"] > 0 and st["drawn"] >= st["wanted"]
    return f"chunks {st['drawn']} / {st['wanted']}" + ("" if done else "  loading…")


class VOXEL_OT_render_view(bpy.types.Operator):
    bl_idname = "voxel.render_view"
    bl_label = "Render Voxel View"
    bl_description = ("Render the world from the scene camera with the voxel pipeline "
                      f"into the image '{IMAGE}' (time of day and effects of the View panel)")

    def execute(self, context):
        from .. import session
        from ..liveview import hours_of, settings_of
        from ..liveview.still import Still, image_pixels
        from ...core.errors import VoxelError
        from ...render import source
        sc = context.scene
        try:
            if sc.camera is None or sc.camera.type != "CAMERA":
                raise VoxelError("the scene has no camera")
            cam, fov = camera_of(sc.camera)
            r = sc.render
            w = max(8, r.resolution_x * r.resolution_percentage // 100)
            h = max(8, r.resolution_y * r.resolution_percentage // 100)
            s = settings_of(sc.voxel_view, render=True)
            s.fov = fov
            world = session.world(sc.voxel.path)
            area = source.world_area(world, cam.x, cam.y, s.distance, s.light_radius)
            view = Still(s)
            try:
                view.set_area(area)
                if s.far:  # waits for the far builder (tiles kept in the file: quick again)
                    from ...far import ring
                    view.set_far(ring(world.file, world.generator, cam.x, cam.y, s.far,
                                      s.distance, lock=world.gen_lock))
                img = view.render(cam, hours_of(sc), (w, h))
            finally:
                view.release()
        except VoxelError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        im = bpy.data.images.get(IMAGE)
        if im is None or tuple(im.size) != (w, h):
            if im is not None:
                bpy.data.images.remove(im)
            im = bpy.data.images.new(IMAGE, w, h, alpha=False)
        im.pixels.foreach_set(image_pixels(img))
        im.update()
        self.report({"INFO"}, f"rendered {w}x{h} into image '{IMAGE}'")
        return {"FINISHED"}


def problem_lines(context, text: str) -> list[str]:
    """The live view's problem as the View panel shows it: the world file's folder
    left out (the File field names it) and wrapped to the sidebar's width (Blender
    cuts a long label in its middle: a damaged file's message lost what went wrong)."""
    import os
    import textwrap
    path = context.scene.voxel.path
    if path:
        for p in (bpy.path.abspath(path), os.path.realpath(bpy.path.abspath(path))):
            text = text.replace(os.path.dirname(p) + os.sep, "")
    scale = context.preferences.system.ui_scale
    region = context.region
    width = region.width / scale if region is not None and region.width > 1 else 300
    return textwrap.wrap(text, max(24, int((width - 60) / 6.5))) or [text]


class VOXEL_PT_view(bpy.types.Panel):
    bl_idname = "VOXEL_PT_view"
    bl_label = "View"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Voxel"
    bl_order = 20

    def draw(self, context):
        from ..liveview import LIVE
        v = context.scene.voxel_view
        col = self.layout.column()
        col.prop(v, "show", icon="HIDE_OFF" if v.show else "HIDE_ON")
        col.operator("voxel.frame_world", icon="WORLD")
        if v.show:
            problem = LIVE.problem(context)
            if problem:
                for i, line in enumerate(problem_lines(context, problem)):
                    col.label(text=line, icon="ERROR" if i == 0 else "BLANK1")
            else:
                st = LIVE.stats
                col.label(text=chunks_line(st))
                if LIVE.warming():
                    col.label(text="building OpenCL kernels (NumPy meanwhile)")
                if v.far:
                    col.label(text=f"far tiles {st['far_drawn']} / {st['far_wanted']}")
                col.label(text=f"last frame {st['ms']:.0f} ms ({st['quality']})")
        row = col.row(align=True)
        row.prop(v, "distance")
        row.prop(v, "far")
        row = col.row(align=True)
        row.prop(v, "hours")
        col.prop(v, "follow_timeline")
        if v.follow_timeline:
            col.prop(v, "frames_per_day")
        col.prop(v, "quality")
        col.separator()
        col.operator(VOXEL_OT_render_view.bl_idname, icon="RENDER_STILL")
        col.operator("voxel.render_animation", icon="RENDER_ANIMATION")


class VOXEL_PT_view_effects(bpy.types.Panel):
    bl_idname = "VOXEL_PT_view_effects"
    bl_label = "Effects"
    bl_parent_id = "VOXEL_PT_view"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Voxel"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        from ..liveview.options import effects
        v = context.scene.voxel_view
        col = self.layout.column(align=True)
        for e in effects():
            col.prop(v, e)
        col.label(text="MSAA: command-line renders only", icon="INFO")
        col.prop(v, "sky")
        for k in ("exposure", "haze", "cloud_cover"):
            col.prop(v, k)
        col.prop(v, "transparency")
        col.prop(v, "debug_view")


CLASSES = [VoxelViewSettings, VOXEL_OT_render_view, VOXEL_PT_view, VOXEL_PT_view_effects]
SCENE_PROPS = {"voxel_view": VoxelViewSettings}
