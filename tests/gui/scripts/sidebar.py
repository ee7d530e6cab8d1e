"""GUI test script (runs inside Blender, see tests/gui/runner.py): open the 3D
viewport's sidebar with N, install and enable the extension zip, click the new tab
(found in the screenshot's pixels) and take the screenshots test_sidebar.py checks."""
import bpy
import pixels


def voxel_panels():
    """Top-level panels of the Voxel tab whose poll passes (what the tab must show)."""
    out = []
    for cls in bpy.types.Panel.__subclasses__():
        if getattr(cls, "bl_category", "") == "Voxel" and not getattr(cls, "bl_parent_id", "") \
                and getattr(cls, "bl_region_type", "") == "UI" and cls.is_registered:
            if not hasattr(cls, "poll") or cls.poll(bpy.context):
                out.append((getattr(cls, "bl_order", 0), cls.bl_label))
    return [label for _, label in sorted(out)]


def run(gui):
    area = gui.area("VIEW_3D")
    view = gui.region(area)
    gui.move(*gui.center(view))
    gui.key("N")  # toggle the sidebar, as a person would
    yield 0.5
    ui = gui.region(area, "UI")
    rect, scale = gui.rect(ui), bpy.context.preferences.system.ui_scale
    gui.result.update(ui=rect, scale=scale)
    yield from gui.screenshot("before")
    before = pixels.sidebar_tabs(gui.pixels("before"), rect, scale)

    r = bpy.ops.extensions.package_install_files(
        filepath=gui.params["zip"], repo="user_default", enable_on_install=True)
    gui.result["install"] = sorted(r)
    gui.result["enabled"] = "bl_ext.user_default.voxel_worlds" in bpy.context.preferences.addons
    from bl_ext.user_default.voxel_worlds.voxel_addon.blender import compat
    theme = bpy.context.preferences.themes[0]
    gui.result["back"] = [round(c * 255) for c in compat.panel_back(theme)]
    yield 0.3
    yield from gui.screenshot("installed")
    after = pixels.sidebar_tabs(gui.pixels("installed"), rect, scale)
    gui.result.update(tabs_before=before, tabs_after=after)
    new = [t for t in after if not any(t[0] < b[1] and b[0] < t[1] for b in before)]
    assert len(new) == 1, f"expected one new tab, before {before}, after {after}"
    row = (new[0][0] + new[0][1]) // 2
    x = rect[0] + rect[2] - round(12 * scale)
    gui.click(x, gui.size[1] - 1 - row)  # image row -> window y
    gui.move(*gui.center(view))  # away, so no tab is drawn hovered
    yield 0.5
    yield from gui.screenshot("voxel")
    gui.result["panels"] = voxel_panels()
    gui.result["category"] = getattr(ui, "active_panel_category", None)
