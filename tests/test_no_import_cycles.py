"""No two modules of voxel_addon import each other, directly or round a loop, lazy
imports inside functions included (they hide a circle, they do not remove it): a
NumPy reference and its OpenCL twin (meshing.faces / meshing.cl) once did. A
package's __init__ only re-exports, so edges into one do not count."""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent / "voxel_addon"


def _modules() -> dict:
    mods = {}
    for f in ROOT.rglob("*.py"):
        parts = list(f.relative_to(ROOT.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        mods[".".join(parts)] = f
    return mods


def _imports(name: str, f: Path, mods: dict) -> set:
    here = name.split(".") if f.name == "__init__.py" else name.split(".")[:-1]
    out = set()
    for node in ast.walk(ast.parse(f.read_text())):
        if isinstance(node, ast.ImportFrom):
            base = here[:len(here) - node.level + 1] if node.level else []
            base = ".".join(base + (node.module.split(".") if node.module else []))
            for a in node.names:
                sub = f"{base}.{a.name}"
                out.add(sub if sub in mods else base)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return {m for m in out if m in mods and m != name}


def cycles(mods: dict) -> set:
    packages = {m for m, f in mods.items() if f.name == "__init__.py"}
    edges = {m: _imports(m, f, mods) - packages for m, f in mods.items()}
    found = set()
    for a in set(mods) - packages:
        for b in edges[a]:
            seen, stack = {b}, [b]
            while stack:
                x = stack.pop()
                if x == a:
                    found.add(tuple(sorted((a, b))))
                    break
                for y in edges[x] - seen:
                    seen.add(y)
                    stack.append(y)
    return found


def test_no_import_cycles():
    mods = _modules()
    assert "voxel_addon.meshing.cl" in mods and len(mods) > 50
    assert cycles(mods) == set()


def test_the_check_finds_a_circle(tmp_path):
    pkg = tmp_path / "voxel_addon" / "m"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("def f():\n    from . import b\n")
    (pkg / "b.py").write_text("from .a import f\n")
    mods = {"voxel_addon.m": pkg / "__init__.py", "voxel_addon.m.a": pkg / "a.py",
            "voxel_addon.m.b": pkg / "b.py"}
    assert cycles(mods) == {("voxel_addon.m.a", "voxel_addon.m.b")}
