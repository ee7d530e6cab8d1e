"""World section: file path, new/open, the new world's seed and generator or the open
world's, recreate (SPEC F9)."""
from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, IntProperty, StringProperty


# A .blend stores the chosen generator as its item's number: never renumber one; a new
# generator takes the next free number (its place in the list does not matter).
NUMBERS = {"flat": 0, "overworld": 1, "empty": 2}


def _generators(self, context):
    from ...generation import GENERATORS
    return [(n, n.capitalize(), f"{n} generator", NUMBERS[n]) for n in GENERATORS]


def _default_generator() -> int:
    """Overworld (a callback's items take the item's number as default): a first world
    has hills, water and trees, not a green plane."""
    from ...generation import DEFAULT
    return NUMBERS[DEFAULT]


class VoxelWorldSettings(bpy.types.PropertyGroup):
    path: StringProperty(name="File", subtype="FILE_PATH", default="//world.sqlite",
                         description="SQLite world file (// = next to the .blend)")
    seed: IntProperty(name="Seed", default=2019, min=0)
    generator: EnumProperty(name="Generator", items=_generators, default=_default_generator(),
                            description="How the new world is generated")
    keep_edits: BoolProperty(name="Keep Edits", default=True,
                             description="Recreate keeps the blocks you placed or removed")


def _settings(context) -> VoxelWorldSettings:
    return context.scene.voxel


class VOXEL_OT_world_new(bpy.types.Operator):
    bl_idname = "voxel.world_new"
    bl_label = "New World"
    bl_description = "Create a world file at the path with the New World seed and generator"

    def execute(self, context):
        import os
        from .. import session
        s = _settings(context)
        path = bpy.path.abspath(s.path)
        if os.path.exists(path):
            self.report({"ERROR"}, f"{path} already exists (use Open, or pick a new name)")
            return {"CANCELLED"}
        try:
            session.world(s.path, create_seed=s.seed, generator=s.generator)
        except Exception as e:  # noqa: BLE001 - a full disk, a read-only folder: one line
            session.discard(s.path)  # created here: nothing half-made stays
            if not session.refused(self, e, path):
                raise
            return {"CANCELLED"}
        self.report({"INFO"}, f"created {path}")
        return {"FINISHED"}


class VOXEL_OT_world_open(bpy.types.Operator):
    bl_idname = "voxel.world_open"
    bl_label = "Open World"
    bl_description = "Open an existing world file"
    filepath: StringProperty(subtype="FILE_PATH")
    filter_glob: StringProperty(default="*.sqlite;*.db", options={"HIDDEN"})

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        from .. import session
        s = _settings(context)
        path = self.filepath or s.path
        try:
            w = session.world(path)
        except Exception as e:  # noqa: BLE001 - a locked or unreadable file: one line
            if not session.refused(self, e, bpy.path.abspath(path)):
                raise
            return {"CANCELLED"}
        s.path = path
        s.seed = int(w.seed)
        gen = getattr(w.generator, "name", None)
        if gen:
            s.generator = gen
        return {"FINISHED"}


class VOXEL_OT_world_recreate(bpy.types.Operator):
    bl_idname = "voxel.world_recreate"
    bl_label = "Recreate"
    bl_description = "Regenerate the world from its seed (optionally keeping your edits)"

    def invoke(self, context, event):
        return context.window_manager.invoke_confirm(self, event)

    def execute(self, context):
        from .. import session
        s = _settings(context)
        try:
            session.world(s.path).recreate(keep_edits=s.keep_edits)
        except Exception as e:  # noqa: BLE001 - a full disk or locked file: one line
            if not session.refused(self, e):
                raise
            return {"CANCELLED"}
        return {"FINISHED"}


BACKEND_NAMES = {"opencl": "OpenCL", "numpy": "NumPy (CPU)"}


def backend_line(backend: str | None = None) -> tuple:
    """("info", "Generates with", NAME): the open world's generator's backend, or
    (None) the one a new world would get, and why not OpenCL when it is NumPy."""
    from ... import opencl
    if backend is None:
        backend = opencl.pick(None)
    text = BACKEND_NAMES.get(backend, backend)
    if backend == "numpy" and opencl.why_not():
        text += ", no OpenCL"
    elif backend == "numpy" and opencl.warming():
        text += " until OpenCL is built"
    return ("info", "Generates with", text)


def lines(s: VoxelWorldSettings) -> list[tuple]:
    """What the panel shows under New / Open, by the state of the file at s.path:
    open: its own seed and generator (read-only), the backend it generates with and
    Recreate; missing: the settings New creates it with and the backend it would use;
    there but not open: a hint and Recreate."""
    import os
    from .. import session
    if session.is_open(s.path):
        w = session.world(s.path)
        gen = getattr(w.generator, "name", "?")
        return [("label", "Open", "CHECKMARK"), ("info", "Seed", str(w.seed)),
                ("info", "Generator", gen.capitalize()),
                backend_line(getattr(w.generator, "backend", None)), ("recreate",)]
    if not s.path or not os.path.exists(bpy.path.abspath(s.path)):
        return [("label", "New World:", "ADD"), ("prop", "seed"), ("prop", "generator"),
                backend_line()]
    return [("label", "Not open: Open it, or Show in Viewport", "INFO"), ("recreate",)]


class VOXEL_PT_world(bpy.types.Panel):
    bl_idname = "VOXEL_PT_world"
    bl_label = "World"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Voxel"
    bl_order = 0

    def draw(self, context):
        s = _settings(context)
        col = self.layout.column()
        col.prop(s, "path")
        row = col.row(align=True)
        row.operator(VOXEL_OT_world_new.bl_idname, icon="ADD")
        row.operator(VOXEL_OT_world_open.bl_idname, icon="FILE_FOLDER")
        for kind, *a in lines(s):
            if kind == "label":
                col.label(text=a[0], icon=a[1])
            elif kind == "info":  # the open world's own value: text, not a setting
                row = col.row()
                row.label(text=a[0])
                row.label(text=a[1])
            elif kind == "prop":
                col.prop(s, a[0])
            else:
                row = col.row(align=True)
                row.operator(VOXEL_OT_world_recreate.bl_idname, icon="FILE_REFRESH")
                row.prop(s, "keep_edits")


CLASSES = [VoxelWorldSettings, VOXEL_OT_world_new, VOXEL_OT_world_open,
           VOXEL_OT_world_recreate, VOXEL_PT_world]
SCENE_PROPS = {"voxel": VoxelWorldSettings}
