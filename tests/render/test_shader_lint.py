"""The shader sources stay inside what every device can build: Blender's gpu module makes
their declarations from the `//@` lines (so the bodies declare nothing themselves),
and on macOS Blender cross-compiles GLSL to Metal Shading Language (C++14): MSL and
C++ keywords cannot be names, matrices are not built from one matrix or scalar
(`mat3(m4)`, `mat4(1.0)`), arrays are not global, and there is no sampler state to
lean on (shadow samplers, gathers, LOD and gradient lookups)."""
from __future__ import annotations

import re

import pytest

from voxel_addon import resources
from voxel_addon.render import glsl

FILES = sorted(p.relative_to(resources.SHADERS).as_posix()
               for p in resources.SHADERS.rglob("*") if p.suffix in (".glsl", ".vert", ".frag"))

# MSL's own words and the C++ keywords a GLSL program could otherwise use as names
RESERVED = set("""
vertex fragment kernel device constant threadgroup thread threadgroup_imageblock ray_data
object_data sampler texture array half atomic packed_float3 simd_sum visible stage_in
buffer access metal namespace template typename class public private protected virtual
friend operator this new delete using explicit mutable static_cast dynamic_cast
reinterpret_cast const_cast typeid throw try catch goto auto register signed unsigned long
short char wchar_t union enum extern static volatile and or not xor bitand bitor compl
and_eq or_eq xor_eq not_eq bool_t size_t ptrdiff_t nullptr alignas alignof decltype
noexcept static_assert thread_local constexpr export inline
""".split())
# lookups that need a sampler state (compare mode, filtering, mip levels) a device
# cannot set: devices bind every texture nearest and clamped, without mipmaps (a plain
# textureGather reads four texels unfiltered: it needs only the clamp)
SAMPLER_STATE = re.compile(r"\b(sampler\w*Shadow|textureLod\w*|textureGrad\w*|"
                           r"textureProj\w*|texture2D|shadow2D)\b")


def _code(name: str) -> str:
    """The file without comments."""
    text = (resources.SHADERS / name).read_text()
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def _names(code: str) -> set[str]:
    """Names the file declares: variables, parameters, functions, struct members."""
    types = r"(?:float|int|uint|bool|[iu]?vec[234]|mat[234]|void|Vertex|Frag|DayLight|" \
            r"sampler\w+|usampler\w+|isampler\w+|LIGHT_VOLUME|GSAMPLER)"
    return set(re.findall(rf"\b{types}\s+(\w+)", code))


@pytest.mark.parametrize("name", FILES)
def test_no_reserved_names(name):
    bad = _names(_code(name)) & RESERVED
    assert not bad, f"{name}: MSL/C++ keywords as names: {sorted(bad)}"


@pytest.mark.parametrize("name", FILES)
def test_no_matrix_from_one_value(name):
    code = _code(name)
    bad = []
    for m in re.finditer(r"\bmat[234](?:x[234])?\s*\(", code):
        depth, i, commas = 1, m.end(), 0
        while depth and i < len(code):
            c = code[i]
            depth += c == "("
            depth -= c == ")"
            commas += c == "," and depth == 1
            i += 1
        if commas == 0:
            bad.append(code[m.start():i])
    assert not bad, f"{name}: matrix constructors Metal does not take: {bad}"


@pytest.mark.parametrize("name", FILES)
def test_no_global_arrays(name):
    code = _code(name)
    depth, bad = 0, []
    for ln in code.splitlines():
        if depth == 0 and re.match(r"\s*(const\s+)?\w+\s+\w+\s*\[\s*\w*\s*\]\s*(=|;)", ln):
            bad.append(ln.strip())
        depth += ln.count("{") - ln.count("}")
    assert not bad, f"{name}: arrays at file scope (inside a function instead): {bad}"


@pytest.mark.parametrize("name", FILES)
def test_no_sampler_state(name):
    bad = SAMPLER_STATE.findall(_code(name))
    assert not bad, f"{name}: lookups that need sampler state: {bad}"


@pytest.mark.parametrize("name", FILES)
def test_declarations_are_annotations(name):
    """Every device writes the declarations from the //@ lines (glsl.py): a body's own
    `uniform`, `in`/`out` or `layout` would compile on moderngl only."""
    code = _code(name)
    if name == "include/light.glsl":  # a library that tests also use raw (its own sampler type)
        code = ""
    bad = re.findall(r"^\s*(?:layout\s*\(|uniform\s|in\s+\w+\s+\w+\s*;|out\s+\w+\s+\w+\s*;|"
                     r"(?:flat|smooth|sample)\s+(?:in|out)\s)", code, re.M)
    assert not bad, f"{name}: declarations outside //@ lines: {bad}"
    glsl.interface([(resources.SHADERS / name).read_text()], {})  # the //@ lines parse


def test_the_lint_can_fail():
    assert _names("vec3 vertex = p; float f(float kernel) { return kernel; }") & RESERVED \
        == {"vertex", "kernel"}
    assert SAMPLER_STATE.findall("textureLod(m, uv, 2.0); sampler2DShadow s;")
