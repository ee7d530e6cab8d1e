"""Every module's imports (lazy ones included) keep to the table in ARCHITECTURE.md."""
from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PKG = ROOT / "voxel_addon"


def table() -> dict[str, dict[str, str | None]]:
    """unit -> {allowed unit: the files it is limited to, or None}; a unit is a folder
    ("world") or a top-level module ("opencl")."""
    rules = {}
    for line in (ROOT / "ARCHITECTURE.md").read_text().splitlines():
        m = re.match(r"\|\s*`voxel_addon/([\w.]+?)(/|\.py)`\s*\|[^|]*\|([^|]*)\|", line)
        if not m:
            continue
        allowed = {}
        for item in m.group(3).split(","):
            item = item.strip()
            if not item or item == "—":
                continue
            im = re.fullmatch(r"`?(\w+)`?(?:\s*\((\w+\.py(?:; \w+\.py)*) only\))?", item)
            assert im, f"ARCHITECTURE.md: cannot read {item!r} in the row of {m.group(1)}"
            allowed[im.group(1)] = None if im.group(2) is None else im.group(2).split("; ")
        rules[m.group(1)] = allowed
    return rules


def imports(path: Path, text: str | None = None) -> set[str]:
    """Add-on units imported by one file (absolute or relative, anywhere in it)."""
    rel = path.relative_to(PKG)
    pkg = ["voxel_addon", *rel.parts[:-1]]
    out = set()
    for node in ast.walk(ast.parse(path.read_text() if text is None else text, str(path))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg[:len(pkg) - node.level + 1]
                mods = [base + node.module.split(".")] if node.module else \
                    [base + [a.name] for a in node.names]
            elif node.module and node.module.split(".")[0] == "voxel_addon":
                mods = [node.module.split(".")] if "." in node.module else \
                    [["voxel_addon", a.name] for a in node.names]
            else:
                continue
        elif isinstance(node, ast.Import):
            mods = [a.name.split(".") for a in node.names if a.name.startswith("voxel_addon.")]
        else:
            continue
        out.update(m[1] for m in mods if len(m) > 1)
    return out


def unit_of(path: Path) -> str:
    rel = path.relative_to(PKG)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


def test_imports_follow_the_table():
    rules = table()
    assert {"core", "world", "render", "storage", "opencl"} <= set(rules)
    bad = []
    for path in sorted(PKG.rglob("*.py")):
        unit = unit_of(path)
        if unit not in rules:
            bad.append(f"{path.relative_to(ROOT)}: {unit} has no row in ARCHITECTURE.md")
            continue
        for dep in sorted(imports(path) - {unit}):
            if dep not in rules[unit]:
                bad.append(f"{path.relative_to(ROOT)}: {unit} may not import {dep}")
            elif rules[unit][dep] is not None and path.name not in rules[unit][dep]:
                bad.append(f"{path.relative_to(ROOT)}: {unit} imports {dep} only in "
                           f"{', '.join(rules[unit][dep])}")
    assert not bad, "\n".join(bad)


def test_every_allowed_dependency_is_used():
    """The table lists only dependencies the code has: an allowed import nobody makes
    (or a `(x.py only)` file that does not make it) is a stale row."""
    rules = table()
    used: dict[str, dict[str, set]] = {}
    for path in sorted(PKG.rglob("*.py")):
        unit = unit_of(path)
        for dep in imports(path) - {unit}:
            used.setdefault(unit, {}).setdefault(dep, set()).add(path.name)
    stale = []
    for unit, allowed in rules.items():
        for dep, only in allowed.items():
            files = used.get(unit, {}).get(dep, set())
            if not files or (only is not None and not set(only) <= files):
                limit = f" ({'; '.join(only)} only)" if only else ""
                stale.append(f"{unit} may import {dep}{limit}: nothing does")
    assert not stale, "\n".join(stale)


def test_the_check_can_fail():
    """The reader sees relative, absolute and lazy imports."""
    text = ("def f():\n    from ..world import World\n    import voxel_addon.render.camera\n"
            "from voxel_addon import light\nfrom . import chunk\n")
    assert imports(PKG / "core" / "probe.py", text) == {"world", "render", "light", "core"}
    assert "world" not in table()["core"] and table()["cli"]["blender"] == ["bake.py", "animate.py"]


def test_only_cluster_imports_dask():
    """The Blender extension does not carry Dask: only voxel_addon/cluster/ imports it."""
    bad = []
    for path in sorted(PKG.rglob("*.py")):
        if unit_of(path) == "cluster":
            continue
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level
                     else [])
            if any(n.split(".")[0] in ("dask", "distributed") for n in names):
                bad.append(str(path.relative_to(ROOT)))
    assert not bad, f"only voxel_addon/cluster/ may import Dask: {bad}"


def test_minecraft_resources_stand_alone():
    """mcres reads the player's files for the import, the bake and the drawing alike:
    it may lean on core only, never on a world, a format or the GPU."""
    assert table()["mcres"] == {"core": None}
