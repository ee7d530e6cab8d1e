"""Every name a function reads is defined somewhere: scripts that run only inside a
real Blender (GUI jobs, bench jobs) fail late and far from here when a module they
used is renamed (a merge once left `viewport.problem` in the GUI job and `LIVE`
unimported in the edit bench). Python's own symbol tables find those reads."""
from __future__ import annotations

import builtins
import symtable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODULE_NAMES = {"__file__", "__name__", "__doc__", "__spec__", "__builtins__", "__path__",
                "__loader__", "__package__", "__annotations__"}


def undefined(text: str, name: str = "<text>") -> set[tuple[str, str, int]]:
    """(name, scope, line) of each global name read but never bound or imported."""
    top = symtable.symtable(text, name, "exec")
    known = {s.get_name() for s in top.get_symbols()
             if s.is_assigned() or s.is_imported() or s.is_namespace()}
    known |= set(dir(builtins)) | MODULE_NAMES
    bad = set()

    def walk(t):
        for s in t.get_symbols():
            # (3.11's is_global is also true for a local whose name the module binds)
            if (s.is_referenced() and s.get_name() not in known
                    and (t.get_type() == "module" or (s.is_global() and not s.is_local()))):
                bad.add((s.get_name(), t.get_name(), t.get_lineno()))
        for c in t.get_children():
            walk(c)
    walk(top)
    return bad


def sources() -> list[Path]:
    return sorted([*ROOT.glob("voxel_addon/**/*.py"), *ROOT.glob("tests/**/*.py"),
                   *ROOT.glob("tools/*.py"), ROOT / "build.py"])


def test_no_undefined_names():
    bad = [f"{p.relative_to(ROOT)}:{line} {scope}: {n}"
           for p in sources() for n, scope, line in undefined(p.read_text(encoding="utf-8"), str(p))]
    assert not bad, "\n".join(sorted(bad))


def test_the_check_can_fail():
    text = ("import os\nfrom x import y\n\ndef f(a):\n    b = a + y\n    return viewport.problem(b, os)\n\n"
            "def g():\n    def h():\n        return LIVE\n    return h, [k for k in range(3)]\n")
    assert undefined(text) == {("viewport", "f", 4), ("LIVE", "h", 9)}
