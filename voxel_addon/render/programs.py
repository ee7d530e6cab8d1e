"""GLSL programs from shaders/: #include via resources, #define injection, one cache per context.

A program is named by its files plus a defines dict; the same source compiles into
several variants (the thesis's face contexts: opaque / alpha test / peel / shadow).
"""
from __future__ import annotations

import numpy as np

from .. import resources
from .frame import BINDING

# Every sampler name has one texture unit in all programs, set when a program is
# built: a pass binds its textures to these units (a moderngl scope) and no frame
# writes a sampler uniform.
UNITS = {"g_depth": 0, "g_albedo": 1, "g_normal": 2, "shadow_map": 3, "light_vol": 4,
         "tex": 6, "glow_tex": 7, "opaque_depth": 8, "prev_depth": 9, "front": 10,
         "opaque": 11, "layer0": 12, "layer1": 13, "layer2": 14, "ao": 15,
         "src": 0, "sharp": 0, "blurred": 1, "accum": 0, "reveal": 1}


def source(name: str, defines: dict | None = None, version: int = 410) -> str:
    """Shader text with `#version` first and the defines right after it."""
    lines = [f"#version {version} core"]
    for k, v in sorted((defines or {}).items()):
        if v is False or v is None:
            continue
        lines.append(f"#define {k} {int(v) if v is True else v}")
    body = resources.shader(name)
    # A file may carry its own #version (editor tooling); ours wins.
    body = "\n".join(ln for ln in body.splitlines() if not ln.lstrip().startswith("#version"))
    return "\n".join(lines) + "\n#line 1\n" + body


class Programs:
    """Compiles and caches (vertex, fragment, defines) -> moderngl.Program."""

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
            kw = {"vertex_shader": source(vert, d, self.version)}
            if frag:
                kw["fragment_shader"] = source(frag, d, self.version)
            try:
                prog = self.ctx.program(**kw)
            except Exception as e:  # name the file: moderngl's message only has line numbers
                raise RuntimeError(f"shader {vert}/{frag} {d}: {e}") from None
            if "Frame" in prog:
                prog["Frame"].binding = BINDING
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
