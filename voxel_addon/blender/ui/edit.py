"""Voxel Edit: the `voxel.edit` operator, the toolbar tool `voxel.edit_tool` (hover
outline, click / Shift-click / Alt-click, drag strokes, box mode) and its settings
with the block palette (issue 13). Undo is Blender's own: see blender/strokes.py."""
from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, IntProperty, IntVectorProperty, StringProperty

TOOL = "voxel.edit_tool"
PAINT_STEP_PX = 4  # a drag is sampled at least this densely along the mouse's path
SHAPE_ITEMS = [("CUBE", "Cube", "A cube of size³ blocks"),
               ("SPHERE", "Sphere", "A ball of diameter size")]

_previews = None
_items: list = []  # Blender keeps no reference to dynamic enum items: we must


def palette_icons():
    """One preview icon per block from the project's own textures (side face)."""
    global _previews
    if _previews is None:
        import bpy.utils.previews
        import numpy as np
        from ...core.blocks import REGISTRY
        from ... import textures
        _previews = bpy.utils.previews.new()
        for b in REGISTRY.blocks[1:]:
            rgba = textures.image(b.texture("-y"))[0]
            px = (np.repeat(np.repeat(rgba[::-1], 2, 0), 2, 1).astype(np.float32) / 255.0)
            p = _previews.new(b.name)
            p.icon_size = p.image_size = (32, 32)
            flat = px.ravel().tolist()
            p.icon_pixels_float = flat
            p.image_pixels_float = flat
    return _previews


def _palette(self, context):
    if not _items:
        from ...core.blocks import REGISTRY
        icons = palette_icons()
        _items.extend((b.name, b.name.replace("_", " ").capitalize(), f"Place {b.name}",
                       icons[b.name].icon_id, i) for i, b in enumerate(REGISTRY.blocks) if i)
    return _items


class VoxelEditSettings(bpy.types.PropertyGroup):
    # The stroke the world file should show; Blender's undo restores it (strokes.py).
    step: IntProperty(name="Stroke", default=0, options={"HIDDEN"})
    block: EnumProperty(name="Block", items=_palette, description="Block placed by a click")
    size: IntProperty(name="Size", default=1, min=1, max=8, description="Brush size in blocks")
    shape: EnumProperty(name="Shape", items=SHAPE_ITEMS, default="CUBE")
    remove: BoolProperty(name="Remove", default=False,
                         description="A click removes blocks, Shift-click places them")
    box: BoolProperty(name="Box", default=False,
                      description="Click one corner, then the opposite one: fills (or, with "
                                  "Shift, clears) the box between them")
    use_stamp: BoolProperty(name="Stamp", default=False,
                            description="A click places the .vox model (ui/formats.py)")
    stamp: StringProperty(name="Model", subtype="FILE_PATH", description="MagicaVoxel model")


def _changes(cells, bid):
    return [(x, y, z, bid) for x, y, z in cells]


class VOXEL_OT_edit(bpy.types.Operator):
    bl_idname = "voxel.edit"
    bl_label = "Voxel Edit"
    bl_description = "Set blocks around a cell (air clears): what a click of the Voxel Edit tool does"
    bl_options = {"REGISTER", "UNDO"}

    location: IntVectorProperty(name="Location", size=3)
    block: StringProperty(name="Block", default="stone", description="Block name; air clears")
    size: IntProperty(name="Size", default=1, min=1, max=8)
    shape: EnumProperty(name="Shape", items=SHAPE_ITEMS, default="CUBE")
    remove: BoolProperty(name="Remove", default=False,
                         description="Clear the cells (air) instead of placing the block")
    box: BoolProperty(name="Box", default=False, description="Fill the box location..corner")
    corner: IntVectorProperty(name="Corner", size=3)

    def execute(self, context):
        from ..strokes import changed
        return changed(self, lambda: self._stroke(context))

    def _stroke(self, context) -> int:
        from .. import strokes
        from ...core import brush, chunk
        from ...core.blocks import REGISTRY
        bid = 0 if self.remove else REGISTRY.id(self.block)
        chunk.check_z(self.location[2])
        cells = brush.box(self.location, self.corner) if self.box else \
            brush.cells(self.location, self.size, self.shape)
        return strokes.stroke(context, _changes(cells, bid))


class _Hover:
    """What the tool points at, for the outline (updated on mouse moves)."""
    hit = None
    message = ""
    corner = None       # box mode: the first corner, until the second click

    @classmethod
    def clear(cls):
        cls.hit, cls.message, cls.corner = None, "", None


def _target(context, world, event, ignore=frozenset()):
    from .. import pick
    return pick.target(context, world, (event.mouse_region_x, event.mouse_region_y), ignore)


class VOXEL_OT_edit_stroke(bpy.types.Operator):
    bl_idname = "voxel.edit_stroke"
    bl_label = "Voxel Stroke"
    bl_description = "Place (or remove) blocks on the face under the mouse; drag to paint"
    bl_options = {"REGISTER", "UNDO"}

    mode: EnumProperty(items=[("PLACE", "Place", ""), ("REMOVE", "Remove", "")], default="PLACE")

    @classmethod
    def poll(cls, context):
        return context.area is not None and context.area.type == "VIEW_3D"

    def invoke(self, context, event):
        from .. import strokes
        from ...core import brush
        from ...core.blocks import REGISTRY
        s = context.scene.voxel_edit
        if s.remove:  # the tool setting swaps what a click and a Shift-click do
            self.mode = "PLACE" if self.mode == "REMOVE" else "REMOVE"
        try:
            self.world = strokes.begin(context)
            self.bid = 0 if self.mode == "REMOVE" else REGISTRY.id(s.block)
            t = _target(context, self.world, event)
            if t.hit is None:
                self.report({"WARNING"}, t.message)
                return {"CANCELLED"}
            cell = self._cell(t.hit)
            if s.use_stamp and self.mode == "PLACE":  # a .vox model, one stroke
                from .formats import stamp_at
                return {"FINISHED"} if stamp_at(context, s.stamp, cell) else {"CANCELLED"}
            if s.box:
                if _Hover.corner is None:
                    _Hover.corner = cell
                    self.report({"INFO"}, "box: now click the opposite corner")
                    return {"CANCELLED"}
                a, _Hover.corner = _Hover.corner, None
                n = strokes.stroke(context, _changes(brush.box(a, cell), self.bid))
                return {"FINISHED"} if n else {"CANCELLED"}
            self.rec = strokes.empty()
            self.xy = (event.mouse_region_x, event.mouse_region_y)
            self.placed: set = set()
            self.last = None
            self._paint(context, [cell])
        except Exception as e:  # noqa: BLE001 - a full disk or locked file: one line too
            if not strokes.refused(self, e):
                raise
            return {"CANCELLED"}
        context.window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _cell(self, hit):
        from ...core import chunk
        cell = hit.before if self.mode == "PLACE" else hit.cell
        chunk.check_z(cell[2])
        return cell

    def _paint(self, context, centres):
        """One world edit for the brushes at every new centre (a drag's samples since
        the last event are batched: one relight and remesh for all of them)."""
        from .. import strokes
        from ...core import brush
        s = context.scene.voxel_edit
        cells: dict = {}
        for c in centres:
            if c != self.last:
                self.last = c
                cells.update(dict.fromkeys(brush.cells(c, s.size, s.shape)))
        if not cells:
            return
        # held in memory (shown now), written in one transaction when the stroke ends
        payloads, rec = strokes.apply(self.world, _changes(cells, self.bid), write=False)
        self.rec = strokes.merge(self.rec, rec)
        if self.mode == "PLACE":  # paint along the surface, not up a tower of our own
            self.placed.update(cells)
        strokes.show(payloads)

    def modal(self, context, event):
        from .. import pick
        from ...core.errors import VoxelError
        if event.type in {"MOUSEMOVE", "INBETWEEN_MOUSEMOVE"}:
            # Blender merges fast mouse moves: walk the segment since the last sample
            # in steps of a few pixels so a quick drag leaves no gap.
            x1, y1 = event.mouse_region_x, event.mouse_region_y
            x0, y0 = self.xy
            n = max(1, int(max(abs(x1 - x0), abs(y1 - y0)) / PAINT_STEP_PX))
            centres = []
            for i in range(1, n + 1):
                co = (x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * i / n)
                t = pick.target(context, self.world, co, self.placed)
                if t.hit is not None:
                    try:
                        centres.append(self._cell(t.hit))
                    except VoxelError:
                        pass  # off the world's top or bottom mid-drag: skip that sample
            self._paint(context, centres)
            self.xy = (x1, y1)
            return {"RUNNING_MODAL"}
        if (event.type == "LEFTMOUSE" and event.value == "RELEASE") or \
                event.type in {"ESC", "RIGHTMOUSE"}:
            return self._finish(context)
        return {"RUNNING_MODAL"}

    def _finish(self, context):
        from .. import strokes
        try:
            strokes.finish(self.world)
        except Exception as e:  # noqa: BLE001 - not written: said; still shown and undoable
            if not strokes.refused(self, e):
                raise
        if not self.rec.voxels:
            return {"CANCELLED"}
        strokes.commit(context.scene, self.rec, self.world)
        return {"FINISHED"}

    def cancel(self, context):
        """Blender ends the drag (its window or file closes): keep what was shown."""
        self._finish(context)


class VOXEL_OT_pick_block(bpy.types.Operator):
    bl_idname = "voxel.pick_block"
    bl_label = "Pick Block"
    bl_description = "Take the block under the mouse as the block to place"

    def invoke(self, context, event):
        from .. import session
        from ...core.blocks import REGISTRY
        from ...core.errors import VoxelError
        try:
            t = _target(context, session.world(context.scene.voxel.path), event)
        except VoxelError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if t.hit is None:
            self.report({"WARNING"}, t.message)
            return {"CANCELLED"}
        context.scene.voxel_edit.block = REGISTRY[t.hit.block].name
        self.report({"INFO"}, f"block: {REGISTRY[t.hit.block].name}")
        return {"FINISHED"}


# ---- hover outline ---------------------------------------------------------
def outline(hit, corner=None, size: int = 1):
    """Line segment end points (pairs) outlining the hovered face (grown to the
    brush's footprint on that face), or the box from `corner` to the hovered cell,
    pushed a little toward the eye so depth tests pass."""
    if corner is not None:
        c = hit.before if hit.before is not None else hit.cell
        lo = [min(a, b) for a, b in zip(corner, c)]
        hi = [max(a, b) + 1 for a, b in zip(corner, c)]
        pts = [(x, y, z) for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])]
        edges = [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7),
                 (0, 4), (1, 5), (2, 6), (3, 7)]
        return [pts[i] for e in edges for i in e]
    ax = next(i for i in range(3) if hit.normal[i])
    u, v = [i for i in range(3) if i != ax]
    base = [float(c) for c in hit.cell]
    base[ax] += (1.0 if hit.normal[ax] > 0 else 0.0) + 0.004 * hit.normal[ax]
    lo, hi = -((size - 1) // 2), size // 2 + 1   # core.brush's extent
    quad = []
    for du, dv in ((lo, lo), (hi, lo), (hi, hi), (lo, hi)):
        p = list(base)
        p[u] += du
        p[v] += dv
        quad.append(tuple(p))
    return [quad[i] for k in range(4) for i in (k, (k + 1) % 4)]


def draw_hover(context) -> None:
    import gpu
    from gpu_extras.batch import batch_for_shader
    if _Hover.hit is None or _Hover.hit.normal is None or context.region is None:
        return
    s = context.scene.voxel_edit
    pts = outline(_Hover.hit, _Hover.corner, 1 if s.box else s.size)
    region_size = (context.region.width, context.region.height)
    sh = gpu.shader.from_builtin("POLYLINE_UNIFORM_COLOR")
    batch = batch_for_shader(sh, "LINES", {"pos": pts})
    depth, blend = gpu.state.depth_test_get(), gpu.state.blend_get()
    gpu.state.depth_test_set("LESS_EQUAL")
    gpu.state.blend_set("ALPHA")
    sh.bind()
    sh.uniform_float("viewportSize", region_size)
    sh.uniform_float("lineWidth", 2.0)
    sh.uniform_float("color", (1.0, 1.0, 1.0, 0.9))
    batch.draw(sh)
    gpu.state.blend_set(blend)  # Blender's state as it was
    gpu.state.depth_test_set(depth)


class VOXEL_GT_hover(bpy.types.Gizmo):
    """Never selectable: Blender calls test_select on every mouse move, which is
    where the hovered face is found; draw outlines it."""
    bl_idname = "VOXEL_GT_hover"

    def setup(self):
        pass

    def test_select(self, context, location):
        from .. import session
        from ...core.errors import VoxelError
        try:
            w = session.world(context.scene.voxel.path)
            from .. import pick
            t = pick.target(context, w, tuple(location))
        except VoxelError as e:
            t = None
            msg = str(e)
        else:
            msg = t.message
        hit = None if t is None else t.hit
        if (hit and (hit.cell, hit.normal)) != (_Hover.hit and (_Hover.hit.cell, _Hover.hit.normal)) \
                or msg != _Hover.message:
            context.area.tag_redraw()  # the outline and the tool header's label
        _Hover.hit, _Hover.message = hit, msg
        return -1

    def draw(self, context):
        vv = getattr(context.scene, "voxel_view", None)
        if vv is None or not vv.show:  # else the voxel view's overlay hook draws it
            draw_hover(context)


class VOXEL_GGT_hover(bpy.types.GizmoGroup):
    bl_idname = "VOXEL_GGT_hover"
    bl_label = "Voxel Edit Hover"
    bl_space_type = "VIEW_3D"
    bl_region_type = "WINDOW"
    bl_options = {"3D"}

    @classmethod
    def poll(cls, context):
        tool = context.workspace.tools.from_space_view3d_mode(context.mode, create=False)
        return tool is not None and tool.idname == TOOL

    def setup(self, context):
        self.gizmos.new(VOXEL_GT_hover.bl_idname)


class VoxelEditTool(bpy.types.WorkSpaceTool):
    bl_space_type = "VIEW_3D"
    bl_context_mode = "OBJECT"
    bl_idname = TOOL
    bl_label = "Voxel Edit"
    bl_description = ("Click: place the block on the face under the mouse; Shift: remove; "
                      "Alt: pick the block; drag paints one stroke")
    bl_icon = "ops.generic.select_paint"
    bl_widget = VOXEL_GGT_hover.bl_idname
    bl_keymap = (
        (VOXEL_OT_edit_stroke.bl_idname, {"type": "LEFTMOUSE", "value": "PRESS"},
         {"properties": [("mode", "PLACE")]}),
        (VOXEL_OT_edit_stroke.bl_idname, {"type": "LEFTMOUSE", "value": "PRESS", "shift": True},
         {"properties": [("mode", "REMOVE")]}),
        (VOXEL_OT_pick_block.bl_idname, {"type": "LEFTMOUSE", "value": "PRESS", "alt": True}, None),
    )

    def draw_settings(context, layout, tool):
        s = context.scene.voxel_edit
        layout.template_icon_view(s, "block", show_labels=True, scale=1.0, scale_popup=4.0)
        layout.prop(s, "size")
        layout.prop(s, "shape", text="")
        layout.prop(s, "remove")
        layout.prop(s, "box")
        layout.prop(s, "use_stamp")
        if s.use_stamp:
            layout.prop(s, "stamp", text="")
        # what the mouse points at (updated by the hover gizmo)
        h = _Hover.hit
        if h is not None:
            from ...core.blocks import REGISTRY
            x, y, z = h.cell
            layout.label(text=f"{REGISTRY[h.block].name} ({x}, {y}, {z})"
                         + ("  corner set" if _Hover.corner is not None else ""))
        elif _Hover.message:
            layout.label(text=_Hover.message, icon="INFO")


CLASSES = [VoxelEditSettings, VOXEL_OT_edit, VOXEL_OT_edit_stroke, VOXEL_OT_pick_block,
           VOXEL_GT_hover, VOXEL_GGT_hover]
SCENE_PROPS = {"voxel_edit": VoxelEditSettings}


def _overlay(context):
    """Drawn by the voxel view right after its frame (voxel depth in the buffer)."""
    tool = context.workspace.tools.from_space_view3d_mode(context.mode, create=False)
    if tool is not None and tool.idname == TOOL:
        draw_hover(context)


def register():
    from .. import liveview, strokes
    strokes.register_handlers()
    bpy.utils.register_tool(VoxelEditTool, separator=True)
    if _overlay not in liveview.LIVE.overlays:
        liveview.LIVE.overlays.append(_overlay)


def unregister():
    global _previews
    from .. import liveview, strokes
    if _overlay in liveview.LIVE.overlays:
        liveview.LIVE.overlays.remove(_overlay)
    bpy.utils.unregister_tool(VoxelEditTool)
    strokes.unregister_handlers()
    strokes.forget()
    _Hover.clear()
    _items.clear()
    if _previews is not None:
        bpy.utils.previews.remove(_previews)
        _previews = None
