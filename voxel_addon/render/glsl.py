"""Shader programs from shaders/: each file's interface is declared once, in `//@`
lines at its top (and in the files it includes), and every device builds its own
declarations from them: moderngl gets `in`/`out`/`uniform` text (`source`), Blender's
gpu module a GPUShaderCreateInfo (blender/liveview/device.py). The file bodies are
the same GLSL for both.

    //@ in uint in_v                       vertex input (a vertex file)
    //@ vary flat vec3 g_normal            vertex -> fragment (smooth, flat, noperspective,
                                           sample); declared in the vertex file
    //@ out 1 vec4 out_normal              fragment output at a location
    //@ sampler gdepth2D g_depth           a texture (types: SAMPLERS)
    //@ push mat4 host_vp                  a value set per draw (Blender: push constant)
    //@ push float glow_scale[64]
    //@ frame vec3 cam_pos                 a member of the frame block (include/frame.glsl)
    //@ depth_write                        the fragment shader writes gl_FragDepth

Any line may end with `if CONDITION`, a preprocessor expression over the program's
defines (`defined(X)`, `!`, `&&`, `||`, comparisons), evaluated here the way the
body's own `#if` lines see the same defines.

The frame block is one std140 uniform block of a struct (`FrameData frame`) of mat4s,
vec4s and vec4 arrays only: every other member lives in a vec4 slot (a vec3 and a float share
one, std140's own rule), ints and bools stored as floats, and the body reads it by
the member's name through a #define (`cam_pos` -> `frame.s4.xyz`). So the layout is
the same on every backend (Metal packs a struct's vec3 and bool differently from
std140) and the bodies keep their names. `frame.py` packs the values by `frame_layout`.
A bool or int member reads as a constant in a program built with the define
`CONST_name` (a bool's 0 or 1): the compiler drops what the constant switches off
(render/graph.py FIXED).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import lru_cache

from .. import resources

SAMPLERS = {  # annotation type -> (GLSL type with SAMPLES 1, with SAMPLES > 1, depth)
    "sampler2D": ("sampler2D", None, False), "sampler2DArray": ("sampler2DArray", None, False),
    "sampler3D": ("sampler3D", None, False), "usampler2D": ("usampler2D", None, False),
    "usampler3D": ("usampler3D", None, False), "depth2D": ("sampler2D", None, True),
    "gsampler2D": ("sampler2D", "sampler2DMS", False),   # multisampled under MSAA (moderngl)
    "gdepth2D": ("sampler2D", "sampler2DMS", True),
}
TYPES = {"float": 1, "int": 1, "uint": 1, "bool": 1, "vec2": 2, "ivec2": 2, "uvec2": 2,
         "vec3": 3, "ivec3": 3, "uvec3": 3, "vec4": 4, "ivec4": 4, "uvec4": 4, "mat4": 16}
QUALIFIERS = ("smooth", "flat", "noperspective", "sample")
FRAME_STRUCT = "FrameData"
FRAME_NAME = "frame"
FRAME_BLOCK = "Frame"  # the block's name on moderngl (its binding point: frame.BINDING)

_LINE = re.compile(r"^\s*//@\s*(\w+)(.*?)(?:\s+if\s+(.+?))?\s*(?://.*)?$")


@dataclass
class Interface:
    """What a program declares for the given defines (each list in file order)."""
    inputs: list = field(default_factory=list)     # (type, name)
    varyings: list = field(default_factory=list)   # (qualifier, type, name)
    outputs: list = field(default_factory=list)    # (location, type, name)
    samplers: list = field(default_factory=list)   # (annotation type, name)
    push: list = field(default_factory=list)       # (type, name, array size or 0)
    frame: bool = False                            # reads the frame block
    depth_write: bool = False

    def sampler_glsl(self, kind: str, samples: int) -> str:
        one, many, _ = SAMPLERS[kind]
        if samples > 1 and many:
            return many
        return one


@dataclass
class Program:
    """A program's stages (text with includes and #line marks, file list) and its
    interface for one set of defines."""
    vert: tuple
    frag: tuple | None
    defines: dict
    iface: Interface
    name: str

    def where(self, message: str) -> str:
        """A compiler message with the `#line` numbers as file:line (a section after
        a line naming the fragment stage uses that stage's files)."""
        files = self.vert[1]

        def at(line):
            k, n = divmod(int(line), resources.LINES)
            return f"{files[k]}:{n}" if 0 < n and k < len(files) else line

        out = []
        for ln in message.splitlines():
            if "fragment" in ln.lower() and self.frag:
                files = self.frag[1]
            elif "vertex" in ln.lower():
                files = self.vert[1]
            # Mesa "0:LINE(COL)", others "0(LINE)"
            out.append(re.sub(r"\b\d+(?::(\d+)\((\d+)\)|\((\d+)\))", lambda m: (
                f"{at(m.group(1))}({m.group(2)})" if m.group(1) else at(m.group(3))), ln))
        return "\n".join(out)


def condition(expr: str, defines: dict) -> bool:
    """A preprocessor condition over defines (absent names are 0, as in #if)."""
    e = re.sub(r"defined\s*\(\s*(\w+)\s*\)", lambda m: f" {int(m.group(1) in defines)} ", expr)
    e = e.replace("&&", " and ").replace("||", " or ")
    e = re.sub(r"!(?!=)", " not ", e)
    if re.search(r"[^\w\s()<>=!.+\-*/]", e):
        raise ValueError(f"cannot evaluate shader condition {expr!r}")

    def name(m):
        v = defines.get(m.group(0), 0)
        return str(int(v) if isinstance(v, bool) else v)
    e = re.sub(r"\b(?!and\b|or\b|not\b)[A-Za-z_]\w*", name, e)
    return bool(eval(e, {"__builtins__": {}}, {}))  # digits and operators only


def active(defines: dict) -> dict:
    """The defines a body sees: False/None dropped, True as 1 (NumPy scalars too)."""
    out = {}
    for k, v in defines.items():
        v = v.item() if hasattr(v, "item") else v
        if v is not False and v is not None:
            out[k] = 1 if v is True else v
    return out


def annotations(text: str, defines: dict):
    """(kind, fields) of each `//@` line whose condition holds."""
    for ln in text.splitlines():
        m = _LINE.match(ln)
        if not m:
            continue
        kind, rest, cond = m.group(1), m.group(2).split(), m.group(3)
        if cond and not condition(cond, defines):
            continue
        yield kind, rest


def interface(texts, defines: dict) -> Interface:
    """The interface declared by the texts of a program's stages (vertex first)."""
    d = active(defines)
    f = Interface()
    seen = set()
    for text in texts:
        for kind, a in annotations(text, d):
            key = (kind, a[-1] if a else "")
            if key in seen:  # (an include seen by both stages)
                continue
            seen.add(key)
            if kind == "in":
                f.inputs.append((a[0], a[1]))
            elif kind == "vary":
                if a[0] not in QUALIFIERS:
                    raise ValueError(f"vary {a}: qualifier one of {QUALIFIERS}")
                f.varyings.append((a[0], a[1], a[2]))
            elif kind == "out":
                f.outputs.append((int(a[0]), a[1], a[2]))
            elif kind == "sampler":
                if a[0] not in SAMPLERS:
                    raise ValueError(f"sampler {a}: type one of {list(SAMPLERS)}")
                f.samplers.append((a[0], a[1]))
            elif kind == "push":
                m = re.fullmatch(r"(\w+)(?:\[(\d+)\])?", a[1])
                f.push.append((a[0], m.group(1), int(m.group(2) or 0)))
            elif kind == "frame":
                f.frame = True
            elif kind == "depth_write":
                f.depth_write = True
            else:
                raise ValueError(f"unknown shader annotation //@ {kind}")
    return f


def program(vert: str, frag: str | None, defines: dict | None = None,
            texts: tuple[str | None, str | None] = (None, None)) -> Program:
    """A program of shader files (vertex, fragment) for these defines. `texts` stand
    in for the files' contents (tests write their own bodies; includes still resolve
    from shaders/)."""
    d = dict(defines or {})
    stages = []
    for name, text in ((vert, texts[0]), (frag, texts[1])):
        if name is None:
            stages.append(None)
        elif text is None:
            stages.append(resources.shader_stage(name))
        else:
            stages.append(resources.expand(resources.SHADERS, name, text, lines=True))
    iface = interface([s[0] for s in stages if s], d)
    return Program(stages[0], stages[1], d, iface, f"{vert}/{frag}")


# ---------------------------------------------------------------------- frame block
@lru_cache(maxsize=None)
def frame_layout() -> tuple[dict, int, str]:
    """({member: (float index, count, kind)}, size in bytes, the struct and its
    accessors as GLSL) from include/frame.glsl's `//@ frame` lines. kind: "f", "i"
    (ints and bools are stored as floats; "b" for bools), "a" for a vec4 array
    (`//@ frame vec4 NAME[N]`: N rows, set as an (N, 4) array)."""
    members, rows, defines = {}, [], []
    slot, fill = -1, 4
    for kind, a in annotations(resources.shader("include/frame.glsl"), {}):
        if kind != "frame":
            continue
        typ, name = a
        if typ not in TYPES or typ.startswith("u"):
            raise ValueError(f"frame.glsl: no frame member of type {typ}")
        n = TYPES[typ]
        m = re.fullmatch(r"(\w+)\[(\d+)\]", name)
        if m:  # vec4 NAME[N]: N rows of their own, read as NAME[i]
            if typ != "vec4":
                raise ValueError(f"frame.glsl: arrays are of vec4 only ({typ} {name})")
            name, count = m.group(1), int(m.group(2))
            members[name] = (4 * (slot + 1), 4 * count, "a")
            slot, fill = slot + count, 4
            rows.append(f"    vec4 a_{name}[{count}];")
            defines.append(f"#define {name} {FRAME_NAME}.a_{name}")
            continue
        k = "b" if typ == "bool" else "i" if typ.startswith("i") or typ == "int" else "f"
        if n == 16:
            slot, fill = slot + 4, 4
            members[name] = (4 * (slot - 3), 16, k)
            rows.append(f"    mat4 m_{name};")  # (not the name itself: no macro meets itself)
            defines.append(f"#define {name} {FRAME_NAME}.m_{name}")
            continue
        if fill + n > 4 or (n == 2 and fill % 2):
            slot, fill = slot + 1, 0
            rows.append(f"    vec4 s{slot};")  # (the name is its vec4 row)
        comp = "xyzw"[fill:fill + n]
        members[name] = (4 * slot + fill, n, k)
        fill += n
        ref = f"{FRAME_NAME}.s{slot}.{comp}"
        if k in "bi" and n == 1:  # a program built for one value reads a constant (CONST_name)
            const, read = ((f"(CONST_{name} != 0)", f"({ref} != 0.0)") if k == "b" else
                           (f"(CONST_{name})", f"{typ}({ref})"))
            defines.append(f"#ifdef CONST_{name}\n#define {name} {const}\n#else\n"
                           f"#define {name} {read}\n#endif")
            continue
        defines.append(f"#define {name} " + (f"{typ}({ref})" if k == "i" else ref))
    text = (f"struct {FRAME_STRUCT} {{\n" + "\n".join(rows) + "\n};\n")
    return members, 16 * (slot + 1), text + "\n".join(defines) + "\n"


# ---------------------------------------------------------------------- moderngl text
def source(prog: Program, stage: str, version: int = 410, samples: int = 1) -> str:
    """GLSL for a GL context (moderngl): `#version`, the defines, the declarations of
    the interface, then the stage's body."""
    f, d = prog.iface, active(prog.defines)
    out = [f"#version {version} core"]
    out += [f"#define {k} {v}" for k, v in sorted(d.items())]
    if f.frame:
        out.append(frame_layout()[2])
        out.append(f"layout(std140) uniform {FRAME_BLOCK} {{ {FRAME_STRUCT} {FRAME_NAME}; }};")
    for kind, name in f.samplers:
        out.append(f"uniform {f.sampler_glsl(kind, samples)} {name};")
    for typ, name, size in f.push:
        out.append(f"uniform {typ} {name}{f'[{size}]' if size else ''};")
    if stage == "vert":
        out += [f"layout(location = {i}) in {t} {n};" for i, (t, n) in enumerate(f.inputs)]
        out += [f"{_qual(q)}out {t} {n};" for q, t, n in f.varyings]
        body = prog.vert[0]
    else:
        out += [f"{_qual(q)}in {t} {n};" for q, t, n in f.varyings]
        out += [f"layout(location = {i}) out {t} {n};" for i, t, n in f.outputs]
        body = prog.frag[0]
    return "\n".join(out) + "\n" + body


def _qual(q: str) -> str:
    return "" if q == "smooth" else f"{q} "
