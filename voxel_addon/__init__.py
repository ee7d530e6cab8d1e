"""Voxel Worlds for Blender. Importing this package stays cheap: the bpy side
(voxel_addon.blender) is imported only when Blender registers the add-on."""


def register():
    from . import blender
    blender.register()


def unregister():
    from . import blender
    blender.unregister()
