"""Blender side of the add-on: every module in ui/ exports CLASSES (registered in
module order, PropertyGroups first within a module) and may export SCENE_PROPS, a
dict attribute-name -> PropertyGroup class attached to bpy.types.Scene (so settings
are saved with the .blend), MENUS, menu class name -> draw function appended to
that menu (e.g. File › Import), and register()/unregister() for what is not a
class (tools, handlers), called after its classes and before they go. New
panels/tools only add a module to ui/."""
from __future__ import annotations

import importlib
import pkgutil

from . import ui

_registered: list = []
_scene_props: list[str] = []
_hooked: list = []
_menus: list = []


def modules():
    names = sorted(m.name for m in pkgutil.iter_modules(ui.__path__))
    return [importlib.import_module(f".{n}", ui.__name__) for n in names]


def register():
    import bpy
    mods = modules()
    for m in mods:
        for cls in getattr(m, "CLASSES", ()):
            bpy.utils.register_class(cls)
            _registered.append(cls)
    for m in mods:
        for attr, group in getattr(m, "SCENE_PROPS", {}).items():
            setattr(bpy.types.Scene, attr, bpy.props.PointerProperty(type=group))
            _scene_props.append(attr)
    for m in mods:
        if hasattr(m, "register"):
            m.register()
            _hooked.append(m)
        for menu, fn in getattr(m, "MENUS", {}).items():
            getattr(bpy.types, menu).append(fn)
            _menus.append((menu, fn))


def unregister():
    import bpy
    from . import liveview, session
    while _hooked:
        _hooked.pop().unregister()
    liveview.shutdown()
    session.close_all()
    for menu, fn in reversed(_menus):
        getattr(bpy.types, menu).remove(fn)
    _menus.clear()
    for attr in reversed(_scene_props):
        if hasattr(bpy.types.Scene, attr):
            delattr(bpy.types.Scene, attr)
    _scene_props.clear()
    for cls in reversed(_registered):
        bpy.utils.unregister_class(cls)
    _registered.clear()
