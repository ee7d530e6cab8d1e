"""File › Import › Minecraft World and › MagicaVoxel (.vox), File › Export ›
MagicaVoxel (.vox) (issue 21). The imports write into the scene's world file (Voxel
panel › World; a new one beside the source when none is set) and run as modal jobs
like File › Import › Voxel World: progress in the status bar, Esc stops. A stopped
Minecraft import keeps the batches already in the file (as the command line does),
and the same import again resumes it (formats/job.py); a .vox goes in as one
transaction, so Esc before it leaves the world as it was."""
from __future__ import annotations

import os

import bpy
from bpy.props import BoolProperty, IntProperty, IntVectorProperty, StringProperty
from bpy_extras.io_utils import ExportHelper, ImportHelper

from ..job import FileJob


def target_world(context, source: str, explicit: str = "", op=None):
    """(world, path) the import writes into: `explicit`, else the scene's world
    file, else a new file named after the source beside it; an empty world (air
    around what is imported) when it is created here. The scene then shows it.
    OP (an _IntoWorld operator) remembers a file made here, which its failure
    removes (`_IntoWorld.failed`)."""
    from .. import session
    s = context.scene.voxel
    path = explicit
    if not path and s.path and (session.is_open(s.path)
                                or os.path.exists(bpy.path.abspath(s.path))):
        path = s.path
    if not path:
        base = source.rstrip("/\\")
        path = (os.path.splitext(base)[0] if os.path.isfile(base) else base) + ".sqlite"
    made = not session.is_open(path) and not os.path.exists(bpy.path.abspath(path))
    if op is not None:
        op._made = (path, s.path) if made else None
    world = session.world(path, create_seed=0, generator="empty")
    s.path = path
    return world, path


class _Job:
    """What ModalJob drives: steps() of (stage, fraction), cancel(), objects."""

    def __init__(self, gen, what):
        self.gen, self.what = gen, what
        self.objects: list = []
        self.note = ""

    def steps(self):
        yield from self.gen
        return self.objects

    def run(self, progress=None):
        for stage, frac in self.steps():
            if progress:
                progress(stage, frac)
        return self.objects

    def cancel(self):
        self.gen.close()


def _minecraft_steps(world, src, report, **kw):
    from ...formats import minecraft
    yield "read", 0.0
    for done, total in minecraft.steps(world, src, report, **kw):
        yield "import", done / max(total, 1)


class _IntoWorld:
    """The imports' target: a world file, or the scene's (target_world). A file
    the import created is removed when it fails; the scene's path goes back."""
    world: StringProperty(name="World File", subtype="FILE_PATH", default="",
                          description="World file to write (empty: the scene's world)")
    _made = None

    def failed(self, context):
        from .. import session
        if self._made:
            path, before = self._made
            session.discard(path)
            context.scene.voxel.path = before

    def kept(self) -> str:
        r = getattr(self, "_report", None)  # Minecraft: batch by batch
        if self._made:
            return f"nothing was kept ({os.path.basename(self._made[0])}, new, was removed)"
        return f"{r.chunks} chunks were written and kept" if r and r.chunks else \
            "nothing of this import was written; the world is unchanged"


class IMPORT_SCENE_OT_voxel_minecraft(_IntoWorld, FileJob, bpy.types.Operator, ImportHelper):
    bl_idname = "import_scene.voxel_minecraft"
    bl_label = "Import Minecraft World"
    bl_description = ("Import a Minecraft Java world (its level.dat or save folder) or region "
                      "files (.mca) into the scene's voxel world (Esc stops; finished "
                      "batches stay in the world file)")
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".mca"
    filter_glob: StringProperty(default="*.mca;level.dat", options={"HIDDEN"})
    use_y_min: BoolProperty(name="Custom Bottom", default=False)
    y_min: IntProperty(name="Bottom Y", default=-64,
                       description="Minecraft y that becomes z 0 (default -64 for 1.18+, else 0)")
    use_area: BoolProperty(name="Only an Area", default=False)
    area: IntVectorProperty(name="Area", size=4, default=(-256, -256, 256, 256),
                            description="Minecraft X0, Z0, X1, Z1 (chunks touching it)")
    replace: BoolProperty(name="Replace", default=False,
                          description="Overwrite chunks the world already has")
    resources: StringProperty(
        name="Resources", default="",
        description="Minecraft's client .jar ('minecraft': the newest in the launcher "
                    "folders) and resource packs (.zip or folders), separated by ';', each "
                    "laid over the ones before; kept in the world so bakes show the "
                    "world with their textures and models (empty: today's look)")

    def draw(self, context):
        col = self.layout.column()
        col.prop(self, "world")
        col.prop(self, "resources")
        col.prop(self, "use_y_min")
        if self.use_y_min:
            col.prop(self, "y_min")
        col.prop(self, "use_area")
        if self.use_area:
            col.prop(self, "area")
        col.prop(self, "replace")

    def source(self) -> str:
        p = bpy.path.abspath(self.filepath)
        if os.path.basename(p) == "level.dat" or os.path.isdir(p):
            return os.path.dirname(p) if os.path.isfile(p) else p
        return p

    def make_job(self, context):
        from ...formats import minecraft
        src = self.source()
        minecraft.regions_of(src)  # one clear line before anything is made
        specs = [bpy.path.abspath(p.strip()) if p.strip() != "minecraft" else p.strip()
                 for p in self.resources.split(";") if p.strip()]
        resources = None
        if specs:
            from ...mcres.stack import resolve
            resources = resolve(specs)
        self._report = minecraft.Report()
        world, _ = target_world(context, src, self.world, self)
        kw = dict(y_min=self.y_min if self.use_y_min else None,
                  area=tuple(self.area) if self.use_area else None, replace=self.replace,
                  resources=resources)
        return _Job(_minecraft_steps(world, src, self._report, **kw), "import")

    def finish(self, context, job):
        r = self._report
        self.report({"INFO"}, r.lines()[0] + (f", {len(r.damaged)} damaged" if r.damaged else "")
                    + (f", {sum(r.unfinished.values())} unfinished" if r.unfinished else ""))
        _redraw(context)


def _vox_steps(world, path, at, out):
    from ...formats import magica
    yield "read", 0.0
    scene = magica.read_file(path)
    yield "place", 0.5
    out.update(magica.place(world, scene, at))
    yield "done", 1.0


class IMPORT_SCENE_OT_voxel_vox(_IntoWorld, FileJob, bpy.types.Operator, ImportHelper):
    bl_idname = "import_scene.voxel_vox"
    bl_label = "Import MagicaVoxel"
    bl_description = ("Place a MagicaVoxel model (.vox) into the scene's voxel world, its "
                      "bounding box corner at Location (the 3D cursor), colours kept")
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".vox"
    filter_glob: StringProperty(default="*.vox", options={"HIDDEN"})
    location: IntVectorProperty(name="Location", size=3, default=(0, 0, 64),
                                description="Where the model's bounding box corner goes")

    def invoke(self, context, event):
        self.location = [round(v) for v in context.scene.cursor.location]
        return FileJob.invoke(self, context, event)

    def make_job(self, context):
        from ...formats import magica
        path = bpy.path.abspath(self.filepath)
        magica.read_file(path)  # a bad file is refused before the world opens
        world, _ = target_world(context, path, self.world, self)
        self._out: dict = {}
        return _Job(_vox_steps(world, path, tuple(self.location), self._out), "place")

    def finish(self, context, job):
        o = self._out
        self.report({"INFO"}, f"{o.get('voxels', 0)} voxels placed, box "
                    f"{' '.join(map(str, o.get('box', ())))}")
        _redraw(context)


class EXPORT_SCENE_OT_voxel_vox(bpy.types.Operator, ExportHelper):
    bl_idname = "export_scene.voxel_vox"
    bl_label = "Export MagicaVoxel"
    bl_description = "Write a box of the scene's voxel world as a MagicaVoxel model (.vox)"

    filename_ext = ".vox"
    filter_glob: StringProperty(default="*.vox", options={"HIDDEN"})
    box: IntVectorProperty(name="Box", size=6, default=(-16, -16, 0, 16, 16, 128),
                           description="X0, Y0, Z0, X1, Y1, Z1 (the far sides excluded); "
                           "(X0, Y0, Z0) becomes the model's origin")

    def execute(self, context):
        from ...formats import magica
        from .. import session
        try:
            world = session.world(context.scene.voxel.path)
            world.flush()  # what the scene shows, edits included
            r = magica.export_vox(world, tuple(self.box), bpy.path.abspath(self.filepath))
        except Exception as e:  # noqa: BLE001 - a full disk or locked file: one line too
            if not session.refused(self, e):
                raise
            return {"CANCELLED"}
        self.report({"INFO"}, f"{r['voxels']} voxels, {r['colors']} colours, {r['models']} "
                    f"models -> {self.filepath}")
        return {"FINISHED"}


def stamp_at(context, path: str, cell) -> int:
    """Place the .vox at `path` on the scene's world as one edit stroke (one undo
    step): centred on `cell` in x and y, its bottom at the cell's z. Returns the
    voxels changed."""
    import numpy as np
    from ...core import colors
    from ...formats import magica
    from .. import session, strokes
    world = session.world(context.scene.voxel.path)
    scene = magica.read_file(bpy.path.abspath(path))
    size = magica.vox.voxels(scene)[2]
    at = (cell[0] - int(size[0]) // 2, cell[1] - int(size[1]) // 2, cell[2])
    # the colours go to the file's palette first (not undone with the stroke), added
    # to what it holds now: another process may have added colours since this opened
    world.file.update_meta(colors.KEY, lambda raw: colors.dump(
        magica.stamp(scene, at, colors.parse({colors.KEY: raw}))[2]))
    xyz, data, _ = magica.stamp(scene, at, colors.parse(world.file.meta))
    color = np.full(len(xyz), magica.COLOR)
    return strokes.stroke(context, list(zip(*xyz.T.tolist(), color.tolist(), data.tolist())))


class VOXEL_OT_stamp(bpy.types.Operator):
    bl_idname = "voxel.stamp"
    bl_label = "Stamp MagicaVoxel Model"
    bl_description = ("Place a .vox model centred on a cell (its bottom at the cell's z), "
                      "one undo step: what a click of the Voxel Edit tool does with Stamp on")
    bl_options = {"REGISTER", "UNDO"}

    filepath: StringProperty(name="Model", subtype="FILE_PATH")
    location: IntVectorProperty(name="Location", size=3)

    def execute(self, context):
        from ..strokes import changed
        return changed(self, lambda: stamp_at(context, self.filepath, tuple(self.location)))


def _redraw(context):
    for area in getattr(context.screen, "areas", ()) if context.screen else ():
        if area.type == "VIEW_3D":
            area.tag_redraw()


def menu_import_mc(self, context):
    self.layout.operator(IMPORT_SCENE_OT_voxel_minecraft.bl_idname, text="Minecraft World")


def menu_import_vox(self, context):
    self.layout.operator(IMPORT_SCENE_OT_voxel_vox.bl_idname, text="MagicaVoxel (.vox)")


def menu_export_vox(self, context):
    self.layout.operator(EXPORT_SCENE_OT_voxel_vox.bl_idname, text="MagicaVoxel (.vox)")


CLASSES = [IMPORT_SCENE_OT_voxel_minecraft, IMPORT_SCENE_OT_voxel_vox, EXPORT_SCENE_OT_voxel_vox,
           VOXEL_OT_stamp]


def register():
    bpy.types.TOPBAR_MT_file_import.append(menu_import_mc)
    bpy.types.TOPBAR_MT_file_import.append(menu_import_vox)
    bpy.types.TOPBAR_MT_file_export.append(menu_export_vox)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(menu_import_mc)
    bpy.types.TOPBAR_MT_file_import.remove(menu_import_vox)
    bpy.types.TOPBAR_MT_file_export.remove(menu_export_vox)
