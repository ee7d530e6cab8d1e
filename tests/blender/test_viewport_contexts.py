"""The live view's GPU set of a GL context that is not current (another window's, or
one gone with its window): viewgpu.Gpu.orphan() frees its textures, buffers and
programs through the current context (Blender's contexts share objects) and never
deletes a VAO or framebuffer name there, which would be the current context's own.

Two real EGL contexts sharing objects stand in for two Blender windows (on X11
Blender 4.3 draws every window with one GLX context, so the GUI test cannot make two).
"""
from __future__ import annotations

import ctypes
import ctypes.util

import pytest

EGL_CONFIG_ID, EGL_NONE = 0x3028, 0x3038
EGL_CONTEXT_MAJOR, EGL_CONTEXT_MINOR, EGL_PROFILE, EGL_CORE = 0x3098, 0x30FB, 0x30FD, 0x1


def _egl():
    egl = ctypes.CDLL(ctypes.util.find_library("EGL"))
    for f in ("eglGetCurrentDisplay", "eglGetCurrentContext", "eglCreateContext"):
        getattr(egl, f).restype = ctypes.c_void_p
    egl.eglQueryContext.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int,
                                    ctypes.POINTER(ctypes.c_int)]
    egl.eglChooseConfig.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_int),
                                    ctypes.POINTER(ctypes.c_void_p), ctypes.c_int,
                                    ctypes.POINTER(ctypes.c_int)]
    egl.eglCreateContext.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                                     ctypes.POINTER(ctypes.c_int)]
    egl.eglMakeCurrent.argtypes = [ctypes.c_void_p] * 4
    egl.eglDestroyContext.argtypes = [ctypes.c_void_p] * 2
    return egl


def _shared_context(egl):
    """A second context sharing objects with the current (moderngl's EGL) one."""
    dpy, ctx = egl.eglGetCurrentDisplay(), egl.eglGetCurrentContext()
    cid = ctypes.c_int()
    assert egl.eglQueryContext(dpy, ctx, EGL_CONFIG_ID, ctypes.byref(cid))
    want = (ctypes.c_int * 3)(EGL_CONFIG_ID, cid.value, EGL_NONE)
    cfg, n = ctypes.c_void_p(), ctypes.c_int()
    assert egl.eglChooseConfig(dpy, want, ctypes.byref(cfg), 1, ctypes.byref(n)) and n.value
    attrs = (ctypes.c_int * 7)(EGL_CONTEXT_MAJOR, 4, EGL_CONTEXT_MINOR, 1,
                               EGL_PROFILE, EGL_CORE, EGL_NONE)
    other = egl.eglCreateContext(dpy, cfg, ctx, attrs)
    if not other:
        pytest.skip("EGL cannot create a shared OpenGL 4.1 core context here")
    return dpy, ctx, other


def _current(egl, dpy, ctx):
    assert egl.eglMakeCurrent(dpy, None, None, ctx)


def test_orphan_frees_shared_objects_and_keeps_the_current_contexts_own(gl):
    from voxel_addon.blender import viewgpu
    egl = _egl()
    gl.__enter__()  # the moderngl fixture's context is current (it is "this window")
    dpy, mine, other = _shared_context(egl)
    try:
        _current(egl, dpy, other)  # "the other window" draws: its GPU set
        g = viewgpu.Gpu(other)
        prog = g.program(1, 0)  # as composite() makes them
        g._vao[prog.glo] = g.ctx.vertex_array(prog, [])
        names = _names(g)
        assert names["tex"] and names["buf"] and names["fbo"] and names["vao"], names
        _current(egl, dpy, mine)
        raw = _Is()
        # the same VAO / framebuffer numbers exist in this context as its own objects
        own_vao = [gl.vertex_array(gl.program(vertex_shader=_VS), []) for _ in range(8)]
        own_fbo = [gl.framebuffer(gl.renderbuffer((4, 4))) for _ in range(8)]
        assert all(raw.IsTexture(t) for t in names["tex"])  # shared: visible here
        # the other context's VAO / framebuffer numbers name objects of this one
        assert all(raw.IsVertexArray(v) for v in names["vao"]), (names, own_vao)
        assert all(raw.IsFramebuffer(f) for f in names["fbo"]), (names, own_fbo)
        g.orphan()
        assert not any(raw.IsTexture(t) for t in names["tex"])
        assert not any(raw.IsBuffer(b) for b in names["buf"])
        assert all(raw.IsVertexArray(v) for v in names["vao"])
        assert all(raw.IsFramebuffer(f) for f in names["fbo"])
        assert g.r is None
    finally:
        _current(egl, dpy, mine)
        egl.eglDestroyContext(dpy, other)


class _Is:
    """glIs* of the current context."""

    def __init__(self):
        from _moderngl import DefaultLoader
        load = DefaultLoader().load_opengl_function
        for n in ("Texture", "Buffer", "VertexArray", "Framebuffer"):
            setattr(self, f"Is{n}", ctypes.CFUNCTYPE(ctypes.c_ubyte, ctypes.c_uint)(load(f"glIs{n}")))


_VS = "#version 330\nvoid main() { gl_Position = vec4(0.0); }\n"


def _names(g) -> dict:
    """GL names of the set's objects by kind (found the way orphan finds them)."""
    import gc
    import moderngl as mgl
    kinds = {"tex": (mgl.Texture, mgl.Texture3D, mgl.TextureArray, mgl.TextureCube),
             "buf": (mgl.Buffer,), "vao": (mgl.VertexArray,), "fbo": (mgl.Framebuffer,)}
    out = {k: [] for k in kinds}
    for o in gc.get_objects():
        for k, types in kinds.items():  # type(): isinstance on a removed bpy struct raises
            if type(o) in types and o.ctx is g.ctx and o.glo > 0:
                out[k].append(o.glo)
    return out
