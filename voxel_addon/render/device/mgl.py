"""The device on moderngl (render/device/__init__.py): the CLI, tests and bench draw on
a standalone context (`context()`: EGL on Linux, headless; the platform's own
elsewhere). Every texture is nearest and clamped like the gpu module's, so both devices
sample alike."""
from __future__ import annotations

from contextlib import contextmanager

import numpy as np

from .. import glsl
from ..frame import BINDING
from . import FORMATS, Device, State, Target, Texture

_DTYPE = {"rgba8": "f1", "rgba16f": "f2", "rgba32f": "f4", "r8": "f1", "r16": "nu2",
          "r16f": "f2", "r32f": "f4"}
_DEPTH = {None: None, "less": "<", "lequal": "<=", "greater": ">"}
_READ = {"rgba8": np.uint8, "r8": np.uint8, "rgba16f": np.float16, "r16f": np.float16,
         "rgba32f": np.float32, "r32f": np.float32, "depth": np.float32, "r16": np.uint16}


def context():
    """A standalone moderngl context for the CLI, tests and bench: EGL on Linux (no
    display needed), the platform's default elsewhere (WGL, CGL: EGL is not there)."""
    import sys
    import moderngl
    from ...core.errors import VoxelError
    kw = {"backend": "egl"} if sys.platform.startswith("linux") else {}
    try:
        return moderngl.create_standalone_context(**kw)
    except Exception as e:  # no GL here: a clear one-liner beats a C traceback
        raise VoxelError(f"cannot open an OpenGL context ({kw.get('backend', 'default')}): "
                         f"{e}") from None


class MglDevice(Device):
    kind = "moderngl"
    backend = "OPENGL"

    def __init__(self, ctx):
        self.ctx = ctx
        self.max_samples = max(1, int(ctx.max_samples))
        r = ctx.info.get("GL_RENDERER", "").lower()
        self.software = any(k in r for k in ("llvmpipe", "softpipe", "swrast"))
        self.version = 430 if ctx.version_code >= 430 else 410
        self._progs: dict = {}
        self._fs: dict = {}         # program -> attribute-less VAO (fullscreen triangle)
        self._counters: dict = {}   # key -> samples-passed query (counter())
        self._ibo, self._ibo_q, self._ibos = None, 0, []
        self._block = ctx.buffer(reserve=glsl.frame_layout()[1])
        # moderngl binds its last bound framebuffer again after making one: that is
        # _idle, never one of ours that may be released by then
        self._none = ctx.detect_framebuffer(0)  # GL's framebuffer 0: always valid to bind
        self._none.use()
        self._idle = ctx.framebuffer(ctx.renderbuffer((1, 1)))
        self._prog = self._units = None
        self._state = None

    # ------------------------------------------------------------------ resources
    def texture(self, size, fmt, *, layers=0, samples=1, data=None):
        c, (w, h) = self.ctx, (int(size[0]), int(size[1]))
        raw = None if data is None else np.ascontiguousarray(data).tobytes()
        n = samples if samples > 1 else 0
        if fmt == "depth":
            t = c.depth_texture((w, h), raw, samples=n)
            if not n:  # a plain depth value (shadow tests are in the shaders)
                t.compare_func = ""
        elif layers:
            t = c.texture_array((w, h, layers), FORMATS[fmt][0], raw, dtype=_DTYPE[fmt])
        else:
            t = c.texture((w, h), FORMATS[fmt][0], raw, samples=n, dtype=_DTYPE[fmt])
        if not n:
            t.filter = (c.NEAREST, c.NEAREST)
            t.repeat_x = t.repeat_y = False
        return Texture(t, (w, h), fmt, layers, max(1, samples))

    def write_layer(self, tex, layer, data):
        w, h = tex.size
        tex.obj.write(np.ascontiguousarray(data).tobytes(), viewport=(0, 0, layer, w, h, 1))

    def target(self, colors, depth=None):
        colors = tuple(colors)
        self._idle.use()
        fbo = self.ctx.framebuffer([t.obj for t in colors], depth.obj if depth else None)
        return Target(fbo, colors, depth)

    def program(self, vert, frag, defines=None):
        d = glsl.active(defines or {})
        key = (vert, frag, tuple(sorted(d.items())))
        prog = self._progs.get(key)
        if prog is None:
            p = glsl.program(vert, frag, d)
            samples = int(p.defines.get("SAMPLES", 1) or 1)
            try:
                obj = self.ctx.program(vertex_shader=glsl.source(p, "vert", self.version, samples),
                                       fragment_shader=glsl.source(p, "frag", self.version, samples))
            except Exception as e:  # name the file: the driver's message has numbers
                raise RuntimeError(f"shader {p.name} {p.defines}: {p.where(str(e))}") from None
            if glsl.FRAME_BLOCK in obj:
                obj[glsl.FRAME_BLOCK].binding = BINDING
            units = {}
            for i, (_, name) in enumerate(p.iface.samplers):
                units[name] = i
                if name in obj:
                    obj[name].value = i
            prog = self._progs[key] = _Program(obj, p, units)
        return prog

    def mesh(self, words):
        words = np.ascontiguousarray(words, np.uint32)
        quads = len(words) // 4
        if quads > self._ibo_q:
            from ... import meshing
            self._ibo_q = max(quads, 2 * self._ibo_q, 1 << 14)
            self._ibo = self.ctx.buffer(meshing.quad_indices(self._ibo_q).tobytes())
            self._ibos.append(self._ibo)  # (older meshes keep drawing with the smaller ones)
        return _Mesh(self.ctx.buffer(words.tobytes()), self._ibo, quads)

    def trimesh(self, words, *indices):
        words = np.ascontiguousarray(words, np.uint32)
        ibos = [self.ctx.buffer(np.ascontiguousarray(i, np.uint32).tobytes()) for i in indices]
        return _TriMesh(self.ctx.buffer(words.tobytes()), ibos, words.shape[1],
                        [len(i) // 3 for i in indices])

    def frame(self, data):
        self._block.orphan()  # fresh storage: no wait for the previous frame's draws
        self._block.write(data)
        self._block.bind_to_uniform_block(BINDING)

    def release(self, *objs):
        for o in objs:
            if o is None:
                continue
            if isinstance(o, Target):
                self._idle.use()
                o.obj.release()
            elif isinstance(o, Texture):
                o.obj.release()
            else:
                o.release()

    def close(self):
        for p in self._progs.values():
            p.obj.release()
        self._progs.clear()
        for vao in self._fs.values():
            vao.release()
        self._fs.clear()
        self._none.use()
        for x in (*self._ibos, self._block, self._idle, *self._idle.color_attachments):
            x.release()
        self._ibo, self._ibos = None, []

    # ------------------------------------------------------------------ drawing
    def counter(self, key):
        q = self._counters.get(key)
        if q is None:
            q = self._counters[key] = self.ctx.query(samples=True)
        return q

    @contextmanager
    def counting(self, counter):
        if counter is None:
            yield
            return
        with counter:
            yield

    @contextmanager
    def only_if(self, counter):
        if counter is None:
            yield
            return
        with counter.crender:  # glBeginConditionalRender (no wait)
            yield

    @contextmanager
    def begin(self, target, state=State(), clear=False):
        fbo = target.obj if target is not None else self.ctx.detect_framebuffer()
        fbo.depth_mask = state.write or state.depth is None
        fbo.use()
        self.state(state)
        if clear:  # depth too where the mask lets it (OIT keeps the opaque depth)
            fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        yield

    def state(self, state):
        c = self.ctx
        flags = (c.DEPTH_TEST if state.depth else 0) | (c.CULL_FACE if state.cull else 0) \
            | (c.BLEND if state.blend else 0)
        c.enable_only(flags)
        if state.depth:
            c.depth_func = _DEPTH[state.depth]
        c.blend_func = (c.ONE, c.ONE) if state.blend == "add" else (c.ONE, c.ZERO)
        self._state = state

    def use(self, prog, textures, push=None):
        self._prog = prog
        for name, tex in textures.items():
            unit = prog.units.get(name)
            if unit is not None:
                tex.obj.use(unit)
        if push:
            self.push(push)

    def push(self, values):
        obj, cache = self._prog.obj, self._prog.last
        for k, v in values.items():
            u = obj.get(k, None)
            if u is None:  # (the compiler dropped an unused one)
                continue
            if isinstance(v, np.ndarray):
                data = np.asarray(v, np.float32).T.tobytes()  # matrices: GL's columns
                if cache.get(k) != data:
                    u.write(data)
                    cache[k] = data
            elif cache.get(k) != v:
                u.value = v
                cache[k] = v

    def draw(self, mesh=None, first=0, quads=0):
        prog = self._prog.obj
        if mesh is None:
            vao = self._fs.get(prog.glo)
            if vao is None:  # attribute-less: the vertex shader makes the corners
                vao = self._fs[prog.glo] = self.ctx.vertex_array(prog, [])
            vao.render(mode=self.ctx.TRIANGLES, vertices=3)
            return
        vao = mesh.vaos.get(prog.glo)
        if vao is None:
            vao = mesh.vaos[prog.glo] = self.ctx.vertex_array(
                prog, [(mesh.vbo, "2u4", "in_v")], index_buffer=mesh.ibo, index_element_size=4)
        vao.render(mode=self.ctx.TRIANGLES, vertices=6 * quads, first=6 * first)

    def draw_tris(self, mesh, part=0):
        prog = self._prog.obj
        vao = mesh.vaos.get((prog.glo, part))
        if vao is None:
            vao = mesh.vaos[prog.glo, part] = self.ctx.vertex_array(
                prog, [(mesh.vbo, f"{mesh.k}u4", "in_f")], index_buffer=mesh.ibos[part],
                index_element_size=4)
        if mesh.tris[part]:
            vao.render(mode=self.ctx.TRIANGLES, vertices=3 * mesh.tris[part])

    def read(self, tex):
        w, h = tex.size
        c = FORMATS[tex.fmt][0]
        a = np.frombuffer(tex.obj.read(), _READ[tex.fmt]).reshape(h, w, c)
        return a if a.dtype != np.float16 else a.astype(np.float32)

    def finish(self):
        self.ctx.finish()


class _Program:
    __slots__ = ("obj", "info", "units", "last")

    def __init__(self, obj, info, units):
        self.obj, self.info, self.units, self.last = obj, info, units, {}


class _Mesh:
    """A vertex buffer; its VAOs (one per program that drew it) are made when drawn."""
    __slots__ = ("vbo", "ibo", "quads", "vaos")

    def __init__(self, vbo, ibo, quads):
        self.vbo, self.ibo, self.quads, self.vaos = vbo, ibo, quads, {}

    @property
    def nbytes(self) -> int:
        return self.vbo.size

    def release(self):
        for vao in self.vaos.values():
            vao.release()
        self.vaos.clear()
        self.vbo.release()


class _TriMesh(_Mesh):
    """Triangles with their own index sets (far terrain: render/far.py)."""
    __slots__ = ("k", "tris", "ibos")

    def __init__(self, vbo, ibos, k, tris):
        super().__init__(vbo, None, 0)
        self.ibos, self.k, self.tris = ibos, k, tris

    @property
    def nbytes(self) -> int:
        return self.vbo.size + sum(i.size for i in self.ibos)

    def release(self):
        super().release()
        for i in self.ibos:
            i.release()
