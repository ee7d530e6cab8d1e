"""The render device on Blender's own `gpu` module (render/device/__init__.py has the
interface): the live view and Render Voxel View/Animation draw with it on whatever
backend Blender runs, OpenGL, Vulkan or Metal, inside Blender's own state tracking
(no raw GL: nothing to save and restore behind Blender's back).

What the module lacks and how the pipeline does without:
- sampler state (filter, wrap, mipmaps, compare mode): `uniform_sampler` binds nearest
  and clamped, and the shaders filter, repeat and compare by hand;
- partial texture updates: a light-volume layer is drawn in (shaders/copy.frag) from a
  texture of that layer;
- uploads from anything but FLOAT buffers: data is converted to normalised floats
  (NumPy arrays wrap as gpu Buffers without a copy);
- multisampled textures: no MSAA (`max_samples` 1);
- storage buffers, indirect and multi-draw: region batches and CPU culling
  (render/geometry.py).

Blender frees a GPU object when its last Python reference goes, but on Vulkan the
draws that use it run later (the command buffer is submitted at the end of the
frame): a light-volume layer's source texture dropped right after its copy draw
crashed Blender 5.2 on lavapipe. So what is released stays referenced for RETIRE
frames (`_retired`).
"""
from __future__ import annotations

from contextlib import contextmanager

import numpy as np

from ...render import glsl
from ...render.device import FORMATS, Device, State, Target, Texture
from .. import compat

_FORMAT = {"rgba8": "RGBA8", "srgba8": "SRGB8_A8", "rgba16f": "RGBA16F", "rgba32f": "RGBA32F", "r8": "R8",
           "r16": "R16", "r16f": "R16F", "r32f": "R32F", "depth": "DEPTH_COMPONENT32F"}
_SAMPLER = {"sampler2D": "FLOAT_2D", "sampler2DArray": "FLOAT_2D_ARRAY", "sampler3D": "FLOAT_3D",
            "usampler2D": "UINT_2D", "usampler3D": "UINT_3D", "depth2D": "DEPTH_2D",
            "gsampler2D": "FLOAT_2D", "gdepth2D": "DEPTH_2D"}
_TYPE = {"float": "FLOAT", "vec2": "VEC2", "vec3": "VEC3", "vec4": "VEC4", "mat4": "MAT4",
         "int": "INT", "ivec2": "IVEC2", "ivec3": "IVEC3", "ivec4": "IVEC4", "uint": "UINT",
         "uvec2": "UVEC2", "uvec3": "UVEC3", "uvec4": "UVEC4", "bool": "BOOL"}
_DEPTH = {None: "NONE", "less": "LESS", "lequal": "LESS_EQUAL", "greater": "GREATER"}
_QUAL = {"smooth": "smooth", "flat": "flat", "noperspective": "no_perspective"}
SOFTWARE = ("llvmpipe", "lavapipe", "softpipe", "swiftshader", "swrast")
RETIRE = 4  # frames a released object stays referenced (draws may still use it)


class GpuDevice(Device):
    kind = "gpu"
    max_samples = 1

    def __init__(self):
        import gpu
        self.backend = gpu.platform.backend_type_get()
        r = gpu.platform.renderer_get().lower()
        self.software = any(k in r for k in SOFTWARE)
        self._progs: dict = {}
        self._ubo = None
        self._ubo_data = b""   # the bytes in _ubo
        self._ibo, self._ibo_q = None, 0
        self._fs = None          # a 3-vertex batch: the fullscreen triangle
        self._prog = None
        self._layer_fb: dict = {}  # (texture, layer) -> framebuffer (light volume uploads)
        self._frames = 0
        self._retired: list = []   # (frame, objects): kept until RETIRE frames later

    # ------------------------------------------------------------------ resources
    def texture(self, size, fmt, *, layers=0, samples=1, data=None):
        import gpu
        if samples > 1:
            raise ValueError("Blender's gpu module has no multisampled textures")
        w, h = int(size[0]), int(size[1])
        kw = {"format": _FORMAT[fmt]}
        if layers:
            kw["layers"] = layers
        if data is not None:
            f = _floats(data)
            kw["data"] = gpu.types.Buffer("FLOAT", f.size, f)
        return Texture(gpu.types.GPUTexture((w, h), **kw), (w, h), fmt, layers, 1)

    def write_layer(self, tex, layer, data):
        import gpu
        f = _floats(data)
        src = gpu.types.GPUTexture(tex.size, format=_FORMAT[tex.fmt],
                                   data=gpu.types.Buffer("FLOAT", f.size, f))
        key = (id(tex.obj), layer)
        fb = self._layer_fb.get(key)
        if fb is None:
            fb = self._layer_fb[key] = (compat.layer_target(tex.obj, layer), tex.obj)
        prog = self.program("fullscreen.vert", "copy.frag")
        with fb[0].bind():
            self.state(State())
            self.use(prog, {"src": Texture(src, tex.size, tex.fmt)})
            self.draw()
        self._retire(src)

    def target(self, colors, depth=None):
        import gpu
        colors = tuple(colors)
        kw = {"color_slots": tuple(t.obj for t in colors)} if colors else {}
        if depth is not None:
            kw["depth_slot"] = depth.obj
        return Target(gpu.types.GPUFrameBuffer(**kw), colors, depth)

    def program(self, vert, frag, defines=None):
        d = glsl.active(defines or {})
        key = (vert, frag, tuple(sorted(d.items())))
        prog = self._progs.get(key)
        if prog is None:
            prog = self._progs[key] = self._build(glsl.program(vert, frag, d))
        return prog

    def _build(self, p):
        import gpu
        f = p.iface
        info = gpu.types.GPUShaderCreateInfo()
        for k, v in sorted(p.defines.items()):
            info.define(k, str(v))
        head = ""
        if f.frame:
            members, size, text = glsl.frame_layout()
            struct, _, accessors = text.partition("};\n")
            info.typedef_source(struct + "};\n")
            info.uniform_buf(0, glsl.FRAME_STRUCT, glsl.FRAME_NAME)
            head = accessors
        for i, (t, n) in enumerate(f.inputs):
            info.vertex_in(i, _TYPE[t], n)
        if f.varyings:
            iface = gpu.types.GPUStageInterfaceInfo("vary_" + p.name.replace("/", "_").replace(".", "_"))
            for q, t, n in f.varyings:
                if q == "sample":
                    raise ValueError("per-sample interpolation needs MSAA (moderngl only)")
                getattr(iface, _QUAL[q])(_TYPE[t], n)
            info.vertex_out(iface)
        for loc, t, n in f.outputs:
            info.fragment_out(loc, _TYPE[t], n)
        for slot, (t, n) in enumerate(f.samplers):
            info.sampler(slot, _SAMPLER[t], n)
        for t, n, size in f.push:
            if size:
                info.push_constant(_TYPE[t], n, size)
            else:
                info.push_constant(_TYPE[t], n)
        if f.depth_write:
            compat.depth_write(info)
        info.vertex_source(head + p.vert[0])
        info.fragment_source(head + p.frag[0])
        try:
            shader = gpu.shader.create_from_info(info)
        except Exception as e:  # Blender prints the compiler log; name the program here
            raise RuntimeError(f"shader {p.name} {p.defines}: {p.where(str(e))}") from None
        return _Program(shader, p, {n: (t, size) for t, n, size in f.push})

    def mesh(self, words):
        import gpu
        from ... import meshing
        words = np.ascontiguousarray(words, np.uint32)
        quads = len(words) // 4
        if quads > self._ibo_q:
            self._ibo_q = max(quads, 2 * self._ibo_q, 1 << 14)
            idx = meshing.quad_indices(self._ibo_q, np.int32).reshape(-1, 3)
            self._ibo = gpu.types.GPUIndexBuf(type="TRIS", seq=idx)
        fmt = gpu.types.GPUVertFormat()
        fmt.attr_add(id="in_v", comp_type="U32", len=2, fetch_mode="INT")
        vbo = gpu.types.GPUVertBuf(fmt, len(words))
        vbo.attr_fill("in_v", words)
        return _Mesh(gpu.types.GPUBatch(type="TRIS", buf=vbo, elem=self._ibo), quads)

    def trimesh(self, words, *indices):
        import gpu
        words = np.ascontiguousarray(words, np.uint32)
        fmt = gpu.types.GPUVertFormat()
        fmt.attr_add(id="in_f", comp_type="U32", len=words.shape[1], fetch_mode="INT")
        vbo = gpu.types.GPUVertBuf(fmt, len(words))
        vbo.attr_fill("in_f", words)
        batches, n = [], words.nbytes
        for i in indices:
            idx = np.ascontiguousarray(i, np.int32).reshape(-1, 3)
            n += idx.nbytes
            batches.append(gpu.types.GPUBatch(type="TRIS", buf=vbo, elem=gpu.types.GPUIndexBuf(
                type="TRIS", seq=idx)) if len(idx) else None)
        return _TriMesh(batches, n)

    def frame(self, data):
        import gpu
        self._frames += 1
        while self._retired and self._retired[0][0] <= self._frames - RETIRE:
            self._retired.pop(0)
        if self._ubo is not None and data == self._ubo_data:
            return  # a still view's frame again: the block holds these bytes
        f = np.frombuffer(data, np.float32)
        buf = gpu.types.Buffer("FLOAT", f.size, f.copy())
        if self._ubo is None:
            self._ubo = gpu.types.GPUUniformBuf(buf)
        else:
            self._ubo.update(buf)
        self._ubo_data = bytes(data)

    def release(self, *objs):
        """Blender frees its GPU objects when nothing refers to them any more (in the
        context they belong to): ours go after RETIRE frames."""
        for o in objs:
            if isinstance(o, Texture):
                for k in [k for k, v in self._layer_fb.items() if v[1] is o.obj]:
                    self._retire(self._layer_fb.pop(k))
        self._retire(*objs)

    def _retire(self, *objs) -> None:
        objs = [o for o in objs if o is not None]
        if objs:
            self._retired.append((self._frames, objs))

    def close(self):
        self._progs.clear()
        self._layer_fb.clear()
        self._retired.clear()
        self._ubo = self._ibo = self._fs = self._prog = None

    # ------------------------------------------------------------------ drawing
    @contextmanager
    def begin(self, target, state=State(), clear=False):
        if target is None:  # the bound framebuffer (Blender's)
            self.state(state)
            yield
            return
        fb = target.obj
        with fb.bind():
            self.state(state)
            if clear:  # the depth only where the state writes it (OIT keeps the opaque one)
                kw = {"color": (0.0, 0.0, 0.0, 0.0)} if target.colors else {}
                if target.depth is not None and (state.write or state.depth is None):
                    kw["depth"] = 1.0
                fb.clear(**kw)
            yield

    def state(self, state):
        import gpu
        gpu.state.depth_test_set(_DEPTH[state.depth])
        gpu.state.depth_mask_set(bool(state.write and state.depth))
        gpu.state.face_culling_set("BACK" if state.cull else "NONE")
        gpu.state.blend_set("ADDITIVE_PREMULT" if state.blend == "add" else "NONE")

    def use(self, prog, textures, push=None):
        sh = prog.shader
        sh.bind()
        for name, tex in textures.items():
            if name in prog.samplers:
                sh.uniform_sampler(name, tex.obj)
        if prog.info.iface.frame:
            sh.uniform_block(glsl.FRAME_NAME, self._ubo)
        self._prog = prog
        if push:
            self.push(push)

    def push(self, values):
        prog = self._prog
        for k, v in values.items():
            f = prog.setters.get(k)
            if f is not None:
                f(v)

    def draw(self, mesh=None, first=0, quads=0):
        sh = self._prog.shader
        if mesh is None:
            if self._fs is None:
                import gpu
                fmt = gpu.types.GPUVertFormat()
                fmt.attr_add(id="unused", comp_type="F32", len=1, fetch_mode="FLOAT")
                vbo = gpu.types.GPUVertBuf(fmt, 3)
                vbo.attr_fill("unused", [0.0, 0.0, 0.0])
                self._fs = gpu.types.GPUBatch(type="TRIS", buf=vbo)
            self._fs.draw(sh)
            return
        mesh.batch.draw_range(sh, elem_start=6 * first, elem_count=6 * quads)

    def draw_tris(self, mesh, part=0):
        b = mesh.batches[part]
        if b is not None:
            b.draw(self._prog.shader)

    def read(self, tex):
        w, h = tex.size
        c, b = FORMATS[tex.fmt]
        buf = tex.obj.read()
        buf.dimensions = w * h * c  # (a Buffer's own shape exports reversed strides)
        a = np.asarray(buf)
        if b == 1:
            return a.astype(np.uint8).reshape(h, w, c)
        a = a.astype(np.float32).reshape(h, w, c)
        return np.rint(a * 65535.0).astype(np.uint16) if tex.fmt == "r16" else a

    def finish(self):
        import gpu
        gpu.state.active_framebuffer_get().read_color(0, 0, 1, 1, 4, 0, "UBYTE")


def _floats(data) -> np.ndarray:
    """Texture data as the FLOAT buffer the module takes: unorm formats normalised."""
    a = np.ascontiguousarray(data)
    if a.dtype == np.uint8:
        return (a.astype(np.float32) / 255.0).ravel()
    if a.dtype == np.uint16:
        return (a.astype(np.float32) / 65535.0).ravel()
    return a.astype(np.float32).ravel()


class _Program:
    __slots__ = ("shader", "info", "setters", "samplers")

    def __init__(self, shader, info, push):
        self.shader, self.info = shader, info
        self.samplers = {n for _, n in info.iface.samplers}
        self.setters = {n: _setter(shader, n, typ, size) for n, (typ, size) in push.items()}


def _setter(sh, name, typ, size):
    """How a per-draw value reaches the shader (a function per name: a geometry pass
    sets one per draw, hundreds a frame)."""
    import gpu
    if size:
        def f(v):
            a = np.ascontiguousarray(v, np.float32).ravel()
            sh.uniform_vector_float(sh.uniform_from_name(name), gpu.types.Buffer("FLOAT", a.size, a),
                                    1, size)
    elif typ == "mat4":
        def f(v):
            sh.uniform_float(name, np.asarray(v, np.float32).T.ravel().tolist())
    elif typ == "bool":
        def f(v):
            sh.uniform_bool(name, [bool(v)])
    elif typ in ("int", "ivec2", "ivec3", "ivec4"):
        def f(v):
            sh.uniform_int(name, int(v) if typ == "int" else tuple(int(x) for x in v))
    elif typ == "float":
        def f(v):
            sh.uniform_float(name, float(v))
    else:  # vecN: a tuple of floats as it comes (batch_origin, once per draw)
        def f(v):
            sh.uniform_float(name, v)
    return f


class _Mesh:
    __slots__ = ("batch", "quads")

    def __init__(self, batch, quads):
        self.batch, self.quads = batch, quads

    @property
    def nbytes(self) -> int:
        return 32 * self.quads


class _TriMesh:
    __slots__ = ("batches", "nbytes")

    def __init__(self, batches, nbytes):
        self.batches, self.nbytes = batches, nbytes
