"""What differs between the Blender versions the extension supports (the manifest's
blender_version_min up to the newest), in one place: the rest of the add-on calls
these instead of testing versions or attributes itself.

Each difference is found by looking at the API (a property there or not), not by
comparing version numbers, so a build that backports or drops a change still works;
the comment says in which release it changed.
"""
from __future__ import annotations


def node_tree(material):
    """MATERIAL's shader node tree. Before 5.0 a new material had none until
    use_nodes was set; 5.0 always gives one and deprecates use_nodes."""
    if material.node_tree is None:
        material.use_nodes = True
    return material.node_tree


def video_output(image_settings) -> None:
    """Make IMAGE_SETTINGS write a movie through FFmpeg. 5.0 added media_type (the
    kind of output first, then its format); before, FFMPEG was one file format."""
    if hasattr(image_settings, "media_type"):
        image_settings.media_type = "VIDEO"
    image_settings.file_format = "FFMPEG"


def strips(sequence_editor):
    """The sequencer's top-level strips: `strips` since 5.0, `sequences` before."""
    se = sequence_editor
    return se.strips if hasattr(se, "strips") else se.sequences


def panel_back(theme) -> tuple:
    """The RGB of a sidebar panel's background: since 5.0 one colour for every editor
    (user_interface.panel_back), before per editor (view_3d.space.panelcolors)."""
    ui = theme.user_interface
    if hasattr(ui, "panel_back"):
        return tuple(ui.panel_back[:3])
    return tuple(theme.view_3d.space.panelcolors.back[:3])



def layer_target(texture, layer: int):
    """A gpu.types.GPUFrameBuffer of one LAYER of an array TEXTURE. Blender 4.3 reads
    an attachment dict's keys inverted (a value goes to the first field whose name
    does not match: 'texture' to the layer, 'layer' to the texture), fixed later; the
    documented form is tried first."""
    import gpu
    try:
        return gpu.types.GPUFrameBuffer(color_slots=({"texture": texture, "layer": layer},))
    except TypeError:
        return gpu.types.GPUFrameBuffer(color_slots=({"layer": texture, "texture": layer},))


def depth_write(info) -> None:
    """Let the fragment shader of create INFO write gl_FragDepth. GPUShaderCreateInfo.
    depth_write came after 4.3, where OpenGL writes it without being told."""
    if hasattr(info, "depth_write"):
        info.depth_write("ANY")
