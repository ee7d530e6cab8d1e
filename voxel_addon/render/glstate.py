"""Save, reset and restore the GL state of a context we share with a host (Blender).

Blender's GPU module caches what it believes is bound (program, framebuffer, the
texture and sampler of each unit, blend/depth/cull state) and skips binds it thinks
are redundant, so whatever the pipeline changes on Blender's context must be put
back exactly. The pipeline in turn assumes a fresh context (no blending, no sampler
objects overriding its textures' filters, no pixel-unpack buffer): `kept()` gives it
that and restores the host's state afterwards.

Raw GL through ctypes (moderngl's own loader finds the functions on every platform);
moderngl has no generic glGet. No bpy here.
"""
from __future__ import annotations

import ctypes
from contextlib import contextmanager

from .frame import BINDING

# glIsEnabled caps -> value in a fresh moderngl context (GL's defaults, plus what
# moderngl enables when it creates a context: primitive restart, seamless cube maps)
CAPS = {
    0x0BE2: 0,  # BLEND
    0x0B44: 0,  # CULL_FACE
    0x0B71: 0,  # DEPTH_TEST
    0x0C11: 0,  # SCISSOR_TEST
    0x0B90: 0,  # STENCIL_TEST
    0x0BD0: 1,  # DITHER
    0x8037: 0,  # POLYGON_OFFSET_FILL
    0x2A02: 0,  # POLYGON_OFFSET_LINE
    0x2A01: 0,  # POLYGON_OFFSET_POINT
    0x809D: 1,  # MULTISAMPLE
    0x809E: 0,  # SAMPLE_ALPHA_TO_COVERAGE
    0x809F: 0,  # SAMPLE_ALPHA_TO_ONE
    0x80A0: 0,  # SAMPLE_COVERAGE
    0x8C36: 0,  # SAMPLE_SHADING
    0x8E51: 0,  # SAMPLE_MASK
    0x8642: 0,  # PROGRAM_POINT_SIZE
    0x8F9D: 1,  # PRIMITIVE_RESTART
    0x8D69: 0,  # PRIMITIVE_RESTART_FIXED_INDEX
    0x8C89: 0,  # RASTERIZER_DISCARD
    0x8DB9: 0,  # FRAMEBUFFER_SRGB
    0x884F: 1,  # TEXTURE_CUBE_MAP_SEAMLESS
    0x864F: 0,  # DEPTH_CLAMP
    0x0B20: 0,  # LINE_SMOOTH
    0x0B41: 0,  # POLYGON_SMOOTH
    0x0BF2: 0,  # COLOR_LOGIC_OP
    **{0x3000 + i: 0 for i in range(8)},  # CLIP_DISTANCE0..7
}
# glGetIntegerv values restored by one setter call: name -> (enums, setter, fresh value)
INTS = {
    "viewport": ((0x0BA2,), None, None),          # fresh value: the framebuffer's size
    "scissor": ((0x0C10,), None, None),
    "depth_func": ((0x0B74,), "glDepthFunc", (0x0201,)),              # LESS
    "cull_mode": ((0x0B45,), "glCullFace", (0x0405,)),                # BACK
    "front_face": ((0x0B46,), "glFrontFace", (0x0901,)),              # CCW
    "provoking": ((0x8E4F,), "glProvokingVertex", (0x8E4E,)),         # LAST_VERTEX
    "restart_index": ((0x8F9E,), "glPrimitiveRestartIndex", (0xFFFFFFFF,)),
    "blend_func": ((0x80C9, 0x80C8, 0x80CB, 0x80CA), "glBlendFuncSeparate", (770, 771, 770, 771)),
    "blend_eq": ((0x8009, 0x883D), "glBlendEquationSeparate", (0x8006, 0x8006)),  # ADD
}
FLOATS = {
    "clear_color": (0x0C22, 4, "glClearColor", (0.0, 0.0, 0.0, 0.0)),
    "blend_color": (0x8005, 4, "glBlendColor", (0.0, 0.0, 0.0, 0.0)),
    "offset": ((0x8038, 0x2A00), 1, "glPolygonOffset", (0.0, 0.0)),  # factor, units
    "line_width": (0x0B21, 1, "glLineWidth", (1.0,)),
    "point_size": (0x0B11, 1, "glPointSize", (1.0,)),
    "min_sample_shading": (0x8C37, 1, "glMinSampleShading", (0.0,)),
}
PIXEL_STORE = {  # glPixelStorei name -> fresh value
    0x0D05: 4, 0x0CF5: 4,  # PACK/UNPACK_ALIGNMENT
    0x0D02: 0, 0x0D03: 0, 0x0D04: 0, 0x806C: 0, 0x806B: 0,  # PACK row length, skips...
    0x0CF2: 0, 0x0CF3: 0, 0x0CF4: 0, 0x806E: 0, 0x806D: 0,  # UNPACK ...
    0x0D00: 0, 0x0CF0: 0, 0x0D01: 0, 0x0CF1: 0,  # PACK/UNPACK_SWAP_BYTES, LSB_FIRST
}
# generic buffer bindings: target -> binding query
BUFFERS = {0x8892: 0x8894, 0x8F3F: 0x8F43, 0x88EB: 0x88ED, 0x88EC: 0x88EF,  # array, indirect, pack, unpack
           0x8A11: 0x8A28, 0x90D2: 0x90D3, 0x8F36: 0x8F36, 0x8F37: 0x8F37,  # uniform, storage, copy r/w
           0x90EE: 0x90EF}                                                  # dispatch indirect
# texture targets the pipeline binds (2D, 2D array, 3D, 2D multisample) -> binding query
TEX_TARGETS = {0x0DE1: 0x8069, 0x8C1A: 0x8C1D, 0x806F: 0x806A, 0x9100: 0x9104}
# indexed buffer binding points the pipeline binds: the frame block (uniform), and
# cull.comp's commands and boxes (storage); target -> (binding query, points)
INDEXED = {0x8A11: (0x8A28, (BINDING,)), 0x90D2: (0x90D3, (0, 1))}
# GL 4.3 state (storage and dispatch-indirect buffers, fixed-index restart): a 4.1
# context (macOS) answers INVALID_ENUM, so older contexts leave it out
GL43 = {0x8D69, 0x90D2, 0x90EE}

_SIGS = {
    "glGetIntegerv": (None, ctypes.c_uint, ctypes.c_void_p),
    "glGetIntegeri_v": (None, ctypes.c_uint, ctypes.c_uint, ctypes.c_void_p),
    "glGetInteger64i_v": (None, ctypes.c_uint, ctypes.c_uint, ctypes.c_void_p),
    "glGetFloatv": (None, ctypes.c_uint, ctypes.c_void_p),
    "glGetDoublev": (None, ctypes.c_uint, ctypes.c_void_p),
    "glGetBooleanv": (None, ctypes.c_uint, ctypes.c_void_p),
    "glIsEnabled": (ctypes.c_ubyte, ctypes.c_uint),
    "glIsProgram": (ctypes.c_ubyte, ctypes.c_uint),
    "glEnable": (None, ctypes.c_uint),
    "glDisable": (None, ctypes.c_uint),
    "glGetError": (ctypes.c_uint,),
    "glBindFramebuffer": (None, ctypes.c_uint, ctypes.c_uint),
    "glBindRenderbuffer": (None, ctypes.c_uint, ctypes.c_uint),
    "glUseProgram": (None, ctypes.c_uint),
    "glBindVertexArray": (None, ctypes.c_uint),
    "glBindBuffer": (None, ctypes.c_uint, ctypes.c_uint),
    "glBindBufferBase": (None, ctypes.c_uint, ctypes.c_uint, ctypes.c_uint),
    "glBindBufferRange": (None, ctypes.c_uint, ctypes.c_uint, ctypes.c_uint, ctypes.c_ssize_t,
                          ctypes.c_ssize_t),
    "glActiveTexture": (None, ctypes.c_uint),
    "glBindTexture": (None, ctypes.c_uint, ctypes.c_uint),
    "glBindSampler": (None, ctypes.c_uint, ctypes.c_uint),
    "glViewport": (None, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int),
    "glScissor": (None, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int),
    "glColorMask": (None, ctypes.c_ubyte, ctypes.c_ubyte, ctypes.c_ubyte, ctypes.c_ubyte),
    "glDepthMask": (None, ctypes.c_ubyte),
    "glDepthRange": (None, ctypes.c_double, ctypes.c_double),
    "glClearDepth": (None, ctypes.c_double),
    "glPolygonMode": (None, ctypes.c_uint, ctypes.c_uint),
    "glPixelStorei": (None, ctypes.c_uint, ctypes.c_int),
    "glClipControl": (None, ctypes.c_uint, ctypes.c_uint),
    "glStencilMask": (None, ctypes.c_uint),
    "glClearStencil": (None, ctypes.c_int),
    **{n: (None, ctypes.c_uint) for n in ("glDepthFunc", "glCullFace", "glFrontFace",
                                          "glProvokingVertex", "glPrimitiveRestartIndex")},
    "glBlendFuncSeparate": (None,) + (ctypes.c_uint,) * 4,
    "glBlendEquationSeparate": (None, ctypes.c_uint, ctypes.c_uint),
    **{n: (None,) + (ctypes.c_float,) * 4 for n in ("glClearColor", "glBlendColor")},
    "glPolygonOffset": (None, ctypes.c_float, ctypes.c_float),
    **{n: (None, ctypes.c_float) for n in ("glLineWidth", "glPointSize", "glMinSampleShading")},
}


class GL:
    """The few GL entry points this module needs, loaded for the current context."""

    def __init__(self):
        import sys
        from _moderngl import DefaultLoader  # moderngl's own per-platform loader
        load = DefaultLoader().load_opengl_function
        proto = ctypes.WINFUNCTYPE if sys.platform.startswith("win") else ctypes.CFUNCTYPE
        for name, (res, *args) in _SIGS.items():
            ptr = load(name)
            setattr(self, name[2:], proto(res, *args)(ptr) if ptr else None)

    _i = (ctypes.c_int * 16)()  # one scratch array: a ctypes allocation per query costs more

    def ints(self, enum, n=4):
        self.GetIntegerv(enum, self._i)
        return tuple(self._i[:n])

    def int(self, enum):
        self.GetIntegerv(enum, self._i)
        return self._i[0]

    def floats(self, enum, n=4):
        a = (ctypes.c_float * 16)()
        self.GetFloatv(enum, a)
        return tuple(a[:n])

    def bools(self, enum, n=4):
        a = (ctypes.c_ubyte * 16)()
        self.GetBooleanv(enum, a)
        return tuple(a[:n])


_gl: GL | None = None


def gl() -> GL:
    """The loaded functions (once per process: the pointers of one driver stay valid
    for all of its contexts)."""
    global _gl
    if _gl is None:
        _gl = GL()
    return _gl


def saved_units() -> list[int]:
    """The units the pipeline binds (a program's samplers take units 0, 1, ... in
    their order: device/mgl.py) and the last one, where moderngl binds a texture to
    write it."""
    n = gl().int(0x8B4D)  # MAX_COMBINED_TEXTURE_IMAGE_UNITS
    return sorted(set(range(16)) | {n - 1})


def snapshot(units: list[int] | None = None) -> dict:
    """Everything restore() puts back, as plain values (comparable with ==)."""
    g = gl()
    known = _known(g)
    s = {"caps": {c: g.IsEnabled(c) for c in CAPS if known(c)}}
    s["fb"] = (g.int(0x8CA6), g.int(0x8CAA))  # draw, read framebuffer
    s["renderbuffer"] = g.int(0x8CA7)
    s["program"] = g.int(0x8B8D)
    s["vao"] = g.int(0x85B5)
    s["buffers"] = {t: g.int(q) for t, q in BUFFERS.items() if known(t)}
    for name, (enums, _, _) in INTS.items():
        s[name] = tuple(v for e in enums for v in g.ints(e)[:4 if name in ("viewport", "scissor") else 1])
    for name, (enum, n, _, _) in FLOATS.items():
        s[name] = tuple(g.floats(e, n)[0] for e in enum) if isinstance(enum, tuple) else g.floats(enum, n)
    s["color_mask"] = g.bools(0x0C23, 4)
    s["depth_mask"] = g.bools(0x0B72, 1)[0]
    d = (ctypes.c_double * 2)()
    g.GetDoublev(0x0B70, d)
    s["depth_range"] = tuple(d)
    g.GetDoublev(0x0B73, d)
    s["clear_depth"] = d[0]
    s["stencil"] = (g.int(0x0B98), g.int(0x0B91))  # write mask, clear value
    s["polygon_mode"] = g.ints(0x0B40, 2)[0]
    s["pixel_store"] = {p: g.int(p) for p in PIXEL_STORE}
    s["clip"] = (g.int(0x935C), g.int(0x935D)) if g.ClipControl else None
    active = g.int(0x84E0)
    tex = {}
    for u in units or saved_units():
        g.ActiveTexture(0x84C0 + u)
        tex[u] = (tuple(g.int(q) for q in TEX_TARGETS.values()), g.int(0x8919))
    g.ActiveTexture(active)
    s["active_texture"], s["textures"] = active, tex
    s["indexed"] = {t: {i: _indexed(g, t, q, i) for i in points}
                    for t, (q, points) in INDEXED.items() if known(t)}
    return s


def _known(g):
    """Whether the current context knows an enum of CAPS / BUFFERS / INDEXED."""
    new = (g.int(0x821B), g.int(0x821C)) >= (4, 3)  # MAJOR, MINOR_VERSION
    return lambda e: new or e not in GL43


def _indexed(g, target, query, i):
    buf = (ctypes.c_int * 4)()
    g.GetIntegeri_v(query, i, buf)
    if not buf[0]:
        return (0, 0, 0)
    r = (ctypes.c_int64 * 2)()
    g.GetInteger64i_v(query + 1, i, r)          # ..._START
    g.GetInteger64i_v(query + 2, i, ctypes.byref(r, 8))  # ..._SIZE
    return (buf[0], r[0], r[1])


def restore(s: dict) -> None:
    g = gl()
    for c, on in s["caps"].items():
        (g.Enable if on else g.Disable)(c)
    g.BindFramebuffer(0x8CA9, s["fb"][0])
    g.BindFramebuffer(0x8CA8, s["fb"][1])
    g.BindRenderbuffer(0x8D41, s["renderbuffer"])
    # a program deleted while current stays current until replaced, then it is gone
    g.UseProgram(s["program"] if g.IsProgram(s["program"]) else 0)
    for t, bufs in s["indexed"].items():  # indexed binds also set the generic binding
        for i, (b, off, size) in bufs.items():
            if b and size:
                g.BindBufferRange(t, i, b, off, size)
            else:
                g.BindBufferBase(t, i, b)
    g.BindVertexArray(s["vao"])  # before the buffers: ELEMENT_ARRAY is the VAO's
    for t, b in s["buffers"].items():
        g.BindBuffer(t, b)
    _values(g, s)
    for u, (binds, sampler) in s["textures"].items():
        g.ActiveTexture(0x84C0 + u)
        for t, b in zip(TEX_TARGETS, binds):
            g.BindTexture(t, b)
        g.BindSampler(u, sampler)
    g.ActiveTexture(s["active_texture"])


def _values(g, s):
    g.Viewport(*s["viewport"])
    g.Scissor(*s["scissor"])
    for name, (_, setter, _) in INTS.items():
        if setter:
            getattr(g, setter[2:])(*s[name])
    for name, (_, _, setter, _) in FLOATS.items():
        getattr(g, setter[2:])(*s[name])
    g.ColorMask(*s["color_mask"])
    g.DepthMask(s["depth_mask"])
    g.DepthRange(*s["depth_range"])
    g.ClearDepth(s["clear_depth"])
    g.StencilMask(s["stencil"][0])
    g.ClearStencil(s["stencil"][1])
    g.PolygonMode(0x0408, s["polygon_mode"])  # FRONT_AND_BACK
    for p, v in s["pixel_store"].items():
        g.PixelStorei(p, v)
    if s["clip"] and g.ClipControl:
        g.ClipControl(*s["clip"])


def reset(units: list[int] | None = None) -> None:
    """The state of a fresh moderngl context for everything snapshot() covers, except
    what the pipeline sets itself before use (framebuffer, viewport, scissor)."""
    g = gl()
    known = _known(g)
    for c, on in CAPS.items():
        if known(c):
            (g.Enable if on else g.Disable)(c)
    g.BindRenderbuffer(0x8D41, 0)
    g.UseProgram(0)
    g.BindVertexArray(0)
    for t in filter(known, BUFFERS):
        g.BindBuffer(t, 0)
    for t, (_, points) in INDEXED.items():
        for i in points if known(t) else ():
            g.BindBufferBase(t, i, 0)
    for name, (_, setter, fresh) in INTS.items():
        if setter:
            getattr(g, setter[2:])(*fresh)
    for name, (_, _, setter, fresh) in FLOATS.items():
        getattr(g, setter[2:])(*fresh)
    g.ColorMask(1, 1, 1, 1)
    g.DepthMask(1)
    g.DepthRange(0.0, 1.0)
    g.ClearDepth(1.0)
    g.StencilMask(0xFF)
    g.ClearStencil(0)
    g.PolygonMode(0x0408, 0x1B02)  # FILL
    for p, v in PIXEL_STORE.items():
        g.PixelStorei(p, v)
    if g.ClipControl:
        g.ClipControl(0x8CA1, 0x935E)  # LOWER_LEFT, NEGATIVE_ONE_TO_ONE
    for u in units or saved_units():  # a host's sampler object would override our filters
        g.ActiveTexture(0x84C0 + u)
        for t in TEX_TARGETS:
            g.BindTexture(t, 0)
        g.BindSampler(u, 0)
    g.ActiveTexture(0x84C0)


@contextmanager
def kept(units: list[int] | None = None):
    """Run GL work on a shared context: the host's state is saved, the GL defaults
    set for the work, and the host's state put back afterwards (also on errors)."""
    units = units or saved_units()
    s = snapshot(units)
    reset(units)
    try:
        yield s
    finally:
        restore(s)


def errors() -> list[int]:
    """Drain glGetError (tests: our save/restore itself must raise no GL error)."""
    g, out = gl(), []
    for _ in range(32):
        e = g.GetError()
        if not e:
            break
        out.append(e)
    return out
