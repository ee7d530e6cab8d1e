"""GLSL programs from shaders/ on a moderngl context: render/glsl.py writes their text, one cache per context.

A program is named by its files plus a defines dict; the same source compiles into
several variants (the thesis's face contexts: opaque / alpha test / peel / shadow).
"""
from __future__ import annotations

import numpy as np

from . import glsl
from .frame import BINDING

# Every sampler name has one texture unit in all programs, set when a program is
# built: a pass binds its textures to these units (a moderngl scope) and no frame
# writes a sampler uniform.
UNITS = {"g_depth": 0, "g_albedo": 1, "g_normal": 2, "shadow_map": 3, "light_vol": 4,
         "tex": 6, "glow_tex": 7, "opaque_depth": 8, "prev_depth": 9, "front": 10,
         "opaque": 11, "layer0": 12, "layer1": 13, "layer2": 14, "ao": 15,
         "src": 0, "sharp": 0, "blurred": 1, "accum": 0, "reveal": 1}


class Programs:
    """Compiles and caches (vertex, fragment, defines) -> moderngl.Program (shader
    text from render/glsl.py)."""

    def __init__(self, ctx):
        self.ctx = ctx
        self.version = 430 if ctx.version_code >= 430 else 410
        self._cache: dict = {}

    def get(self, vert: str, frag: str | None, defines: dict | None = None):
        key = (vert, frag, tuple(sorted((defines or {}).items())))
        prog = self._cache.get(key)
        if prog is None:
            d = dict(defines or {})
            d.setdefault("GLSL_VERSION", self.version)
            p = glsl.program(vert, frag, d)
            samples = int(d.get("SAMPLES", 1) or 1)
            kw = {"vertex_shader": glsl.source(p, "vert", self.version, samples)}
            if frag:
                kw["fragment_shader"] = glsl.source(p, "frag", self.version, samples)
            try:
                prog = self.ctx.program(**kw)
            except Exception as e:  # name the file: the driver's message has numbers
                raise RuntimeError(f"shader {p.name} {d}: {p.where(str(e))}") from None
            if glsl.FRAME_BLOCK in prog:
                prog[glsl.FRAME_BLOCK].binding = BINDING
            for name, unit in UNITS.items():
                if name in prog:
                    prog[name].value = unit
            self._cache[key] = prog
        return prog

    def release(self):
        for p in self._cache.values():
            p.release()
        self._cache.clear()


def pack(v) -> bytes:
    """A float vector or matrix as uniform bytes (column-major for GL); pack once
    what several programs get in a frame."""
    return np.asarray(v, np.float32).T.tobytes()


def set_uniforms(prog, **kw):
    """Set the uniforms the program has (the optimiser drops unused ones).

    Per program (in its `extra`) the uniform objects and the last value written are
    kept, so a frame skips the lookups and re-writing values that did not change
    (texture units, sky colours of a still hour): GL keeps uniforms per program."""
    c = prog.extra
    if c is None:
        c = prog.extra = {}
    for k, v in kw.items():
        e = c.get(k)
        if e is None:
            e = c[k] = [prog.get(k, None), None]
        u = e[0]
        if u is None:
            continue
        if isinstance(v, np.ndarray):
            v = pack(v)
        if type(v) is bytes:  # packed float vectors and 4x4 matrices
            if v != e[1]:
                u.write(v)
                e[1] = v
        elif type(v) is not type(e[1]) or v != e[1]:
            u.value = v
            e[1] = v
