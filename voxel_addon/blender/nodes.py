"""Blender data the bake's materials share: packed block images and sprites, the
"Voxel Shade" node group with its Hours value (set_hours), the glTF exporter's
occlusion group, and small node-building helpers."""
from __future__ import annotations

import math

import bpy
import numpy as np

GROUP = "Voxel Shade"


# ---------------------------------------------------------------- images

def image(name: str, kind: str = "color") -> bpy.types.Image:
    """The packed 16×16 image of texture `name` (kind "color" or "glow": rgb × mask)."""
    from .. import textures
    key = f"voxel_{name}" if kind == "color" else f"voxel_{name}_glow"
    img = bpy.data.images.get(key)
    if img is not None:
        return img
    rgba, glow = textures.image(name)
    px = rgba.astype(np.float32) / 255.0
    if kind == "glow":
        px[..., :3] *= (glow.astype(np.float32) / 255.0)[..., None]
        px[..., 3] = 1.0
    img = bpy.data.images.new(key, textures.SIZE, textures.SIZE, alpha=True)
    img.pixels.foreach_set(px[::-1].ravel())  # Blender rows start at the bottom
    img.file_format = "PNG"
    img.pack()
    return img


def sprite(name: str, rgba: np.ndarray) -> bpy.types.Image:
    """The packed image of a Minecraft sprite (bake.Bake.images: the player's pack)."""
    key = f"voxel_mc_{name}"
    img = bpy.data.images.get(key)
    if img is None:
        h, w = rgba.shape[:2]
        img = bpy.data.images.new(key, w, h, alpha=True)
        img.pixels.foreach_set((rgba.astype(np.float32) / 255.0)[::-1].ravel())
        img.file_format = "PNG"
        img.pack()
    return img


# ---------------------------------------------------------------- node helpers

def node(tree, kind, x, y, **props):
    n = tree.nodes.new(kind)
    n.location = (x, y)
    for k, v in props.items():
        setattr(n, k, v)
    return n


def op(tree, op, a, b=None, x=0, y=0):
    n = node(tree, "ShaderNodeMath", x, y, operation=op)
    for i, v in enumerate((a, b)):
        if v is None:
            continue
        if isinstance(v, (int, float)):
            n.inputs[i].default_value = v
        else:
            tree.links.new(v, n.inputs[i])
    return n.outputs[0]


def ramp(tree, fac, keys, x, y):
    """A Color Ramp over hours/24 through (hours, rgb) keys, eased like daytime.at."""
    n = node(tree, "ShaderNodeValToRGB", x, y)
    cr = n.color_ramp
    cr.interpolation = "EASE"
    keys = list(keys) + [(24.0, keys[0][1])]
    while len(cr.elements) < len(keys):
        cr.elements.new(0.5)
    for e, (h, rgb) in zip(cr.elements, keys):
        e.position = h / 24.0
        e.color = (*rgb, 1.0)
    tree.links.new(fac, n.inputs[0])
    return n.outputs[0]


def shade_group() -> bpy.types.ShaderNodeTree:
    """The shared node group: light factor (eq. 4.1) from its Light (block RGB) and
    Daylight inputs (colour attributes or the light atlas) and its internal "Hours"
    value (0..24)."""
    from ..light import daytime
    g = bpy.data.node_groups.get(GROUP)
    if g is not None:
        return g
    g = bpy.data.node_groups.new(GROUP, "ShaderNodeTree")
    g.interface.new_socket("Shade", in_out="OUTPUT", socket_type="NodeSocketColor")
    g.interface.new_socket("Light", in_out="INPUT", socket_type="NodeSocketColor")
    g.interface.new_socket("Daylight", in_out="INPUT", socket_type="NodeSocketColor")
    out = node(g, "NodeGroupOutput", 1400, 0)
    gin = node(g, "NodeGroupInput", 250, 400)
    hours = node(g, "ShaderNodeValue", -1000, 0, name="Hours", label="Hours")
    hours.outputs[0].default_value = 12.0
    h = hours.outputs[0]
    fac = op(g, "DIVIDE", h, 24.0, -800, 200)
    amb = ramp(g, fac, [(k[0], k[1]) for k in daytime.KEYS], -600, 400)
    direct = ramp(g, fac, [(k[0], k[2]) for k in daytime.KEYS], -600, 150)
    u = ramp(g, fac, [(k[0], (k[3],) * 3) for k in daytime.KEYS], -600, -100)
    # light direction: the sun (daytime.sun_direction), or the moon below the horizon
    a = op(g, "MULTIPLY", op(g, "SUBTRACT", h, 6.0, -800, -300), math.pi / 12, -650, -300)
    t = math.radians(daytime.TILT)
    sz = op(g, "MULTIPLY", op(g, "SINE", a, None, -500, -420), math.cos(t), -350, -420)
    sy = op(g, "MULTIPLY", op(g, "SINE", a, None, -500, -520), -math.sin(t), -350, -520)
    sx = op(g, "COSINE", a, None, -350, -320)
    sun = node(g, "ShaderNodeCombineXYZ", -200, -400)
    for i, s in enumerate((sx, sy, sz)):
        g.links.new(s, sun.inputs[i])
    sign = op(g, "SIGN", sz, None, -200, -560)
    ldir = node(g, "ShaderNodeVectorMath", -50, -400, operation="SCALE")
    g.links.new(sun.outputs[0], ldir.inputs[0])
    g.links.new(sign, ldir.inputs["Scale"])
    geo = node(g, "ShaderNodeNewGeometry", -200, -150)
    dot = node(g, "ShaderNodeVectorMath", 100, -300, operation="DOT_PRODUCT")
    g.links.new(geo.outputs["Normal"], dot.inputs[0])
    g.links.new(ldir.outputs[0], dot.inputs[1])
    ndl = op(g, "MAXIMUM", dot.outputs["Value"], 0.0, 250, -300)
    # light.shade (eq. 4.1) with white albedo: light*(1 - u*day) + day*(ambient + ndl*direct)
    lit_rgb, day_rgb = gin.outputs["Light"], gin.outputs["Daylight"]

    def mix(op, a, b, x, y, fac=1.0):
        n = node(g, "ShaderNodeMix", x, y, data_type="RGBA", blend_type=op)
        n.inputs["Factor"].default_value = fac
        for sock, v in ((n.inputs[6], a), (n.inputs[7], b)):
            if isinstance(v, tuple):
                sock.default_value = v
            else:
                g.links.new(v, sock)
        return n.outputs[2]

    ndl_rgb = node(g, "ShaderNodeCombineColor", 400, -300)
    for i in range(3):
        g.links.new(ndl, ndl_rgb.inputs[i])
    sky = mix("ADD", amb, mix("MULTIPLY", direct, ndl_rgb.outputs[0], 550, 0), 700, 300)
    dayterm = mix("MULTIPLY", day_rgb, sky, 1000, 400)
    keep = mix("SUBTRACT", (1, 1, 1, 1), mix("MULTIPLY", u, day_rgb, 550, -150),
               700, -100)
    art = mix("MULTIPLY", lit_rgb, keep, 1000, 100)
    total = mix("ADD", dayterm, art, 1200, 200)
    g.links.new(total, out.inputs[0])
    return g


def set_hours(hours: float) -> None:
    """Time of day for every baked material (style "blender")."""
    shade_group().nodes["Hours"].outputs[0].default_value = float(hours) % 24.0


GLTF_GROUP = "glTF Material Output"  # the glTF exporter reads Occlusion from this group


def gltf_group() -> bpy.types.ShaderNodeTree:
    """The node group Blender's glTF exporter (and importer) uses for the occlusion map."""
    g = bpy.data.node_groups.get(GLTF_GROUP)
    if g is None:
        g = bpy.data.node_groups.new(GLTF_GROUP, "ShaderNodeTree")
        s = g.interface.new_socket("Occlusion", in_out="INPUT", socket_type="NodeSocketFloat")
        s.default_value = 1.0
    return g


def linear(c: float) -> float:
    """sRGB 0..1 -> linear (node colours are scene-linear)."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4
