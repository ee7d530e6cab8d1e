"""The resource stack: the game's client jar at the bottom, resource packs (zips or
folders) over it, each laid over the ones before (the order of options.txt's
`resourcePacks`: the last one wins). A file is looked up from the top down.

Read bounded: a hostile zip cannot make us allocate more than `MAX_FILE` per file.
"""
from __future__ import annotations

import os
import re
import sys
import zipfile
from pathlib import Path

from ..core.errors import VoxelError

MAX_FILE = 32 << 20          # bytes of one file (a 4096² PNG is ~16 MiB at most)
AUTO = "minecraft"           # the spec that means: the newest jar in the launcher folders


def launcher_dirs(home: Path | None = None, environ=None, platform: str | None = None) -> list[Path]:
    """The usual `.minecraft` folders of the official launcher on this platform."""
    home = Path.home() if home is None else Path(home)
    environ = os.environ if environ is None else environ
    platform = sys.platform if platform is None else platform
    if platform.startswith("win"):
        base = environ.get("APPDATA")
        return [Path(base) / ".minecraft"] if base else [home / "AppData" / "Roaming" / ".minecraft"]
    if platform == "darwin":
        return [home / "Library" / "Application Support" / "minecraft"]
    return [home / ".minecraft", home / ".var" / "app" / "com.mojang.Minecraft" / ".minecraft"]


def _version_key(path: Path):
    """Releases newest first (1.21.4 > 1.9), then anything else (snapshots, loaders) by
    modification time."""
    name = path.parent.name
    if re.fullmatch(r"\d+(\.\d+)+", name):
        return (1, tuple(int(p) for p in name.split(".")), 0.0)
    return (0, (), path.stat().st_mtime)


def discover(home: Path | None = None, environ=None, platform: str | None = None) -> list[Path]:
    """Client jars in the launcher folders (`versions/<v>/<v>.jar`), newest first."""
    jars = []
    for d in launcher_dirs(home, environ, platform):
        versions = d / "versions"
        if versions.is_dir():
            jars += [j for v in versions.iterdir() if (j := v / f"{v.name}.jar").is_file()]
    return sorted(jars, key=_version_key, reverse=True)


class Source:
    """One layer: a jar, a zip or a folder. `root` is the prefix inside it where
    `assets/` lives (a pack zipped with its folder around it still reads)."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.zip = None
        if self.path.is_dir():
            names = None
        elif self.path.is_file():
            try:
                self.zip = zipfile.ZipFile(self.path)
            except (zipfile.BadZipFile, OSError) as e:
                raise VoxelError(f"{self.path}: not a zip, jar or folder ({e})") from None
            names = {i.filename: i for i in self.zip.infolist() if not i.is_dir()}
        else:
            raise VoxelError(f"{self.path}: no such resource pack or jar")
        self.names = names
        self.root = self._find_root()
        self.jar = self.path.suffix.lower() == ".jar" or self._has("net/minecraft/client/Minecraft.class")

    def _has(self, name: str) -> bool:
        if self.names is None:
            return (self.path / name).is_file()
        return name in self.names

    def _find_root(self) -> str:
        if self.names is None:
            if (self.path / "assets").is_dir() or (self.path / "pack.mcmeta").is_file():
                return ""
            subs = [p for p in self.path.iterdir() if p.is_dir() and (p / "pack.mcmeta").is_file()]
        else:
            if any(n.startswith("assets/") for n in self.names) or "pack.mcmeta" in self.names:
                return ""
            subs = sorted({n.split("/")[0] for n in self.names
                           if n.count("/") == 1 and n.endswith("/pack.mcmeta")})
            subs = [Path(s) for s in subs]
        if len(subs) == 1:
            return subs[0].name + "/"
        raise VoxelError(f"{self.path}: not a resource pack or Minecraft jar "
                         "(no assets/ folder, no pack.mcmeta)")

    def read(self, name: str) -> bytes | None:
        """The bytes of NAME (a path under the pack's root), None when absent."""
        name = self.root + name
        if self.names is None:
            p = self.path / name
            if not p.is_file():
                return None
            if p.stat().st_size > MAX_FILE:
                raise VoxelError(f"{p}: over {MAX_FILE >> 20} MiB")
            return p.read_bytes()
        info = self.names.get(name)
        if info is None:
            return None
        if info.file_size > MAX_FILE:
            raise VoxelError(f"{self.path}: {name} is over {MAX_FILE >> 20} MiB")
        try:
            with self.zip.open(info) as f:
                data = f.read(MAX_FILE + 1)
        except (zipfile.BadZipFile, OSError, EOFError, NotImplementedError) as e:
            raise VoxelError(f"{self.path}: cannot read {name} ({e})") from None
        if len(data) > MAX_FILE:   # the header lied about the size
            raise VoxelError(f"{self.path}: {name} is over {MAX_FILE >> 20} MiB")
        return data

    def close(self):
        if self.zip is not None:
            self.zip.close()


class Stack:
    """Sources bottom first; `read` looks from the top down. Jars go to the bottom
    whatever their place in SPECS (a pack is always laid over the game)."""

    def __init__(self, sources: list[Source]):
        self.sources = sorted(sources, key=lambda s: not s.jar)
        self.cache: dict[str, bytes | None] = {}

    @classmethod
    def open(cls, specs, home=None, environ=None, platform=None) -> "Stack":
        """SPECS: paths of jars, zips or folders, or `minecraft` for the newest jar of
        the launcher folders."""
        sources = []
        for spec in specs:
            spec = str(spec)
            if spec == AUTO and not Path(spec).exists():
                jars = discover(home, environ, platform)
                if not jars:
                    dirs = ", ".join(str(d) for d in launcher_dirs(home, environ, platform))
                    raise VoxelError(f"no Minecraft jar found in the launcher folders ({dirs}); "
                                     "give the client .jar's path")
                spec = jars[0]
            sources.append(Source(Path(spec).expanduser()))
        return cls(sources)

    def read(self, name: str) -> bytes | None:
        if name not in self.cache:
            self.cache[name] = next((d for s in reversed(self.sources)
                                     if (d := s.read(name)) is not None), None)
        return self.cache[name]

    @property
    def paths(self) -> list[str]:
        return [str(s.path) for s in self.sources]

    def close(self):
        for s in self.sources:
            s.close()


def resolve(specs) -> list[str]:
    """The absolute paths of a stack (bottom first) from SPECS, each source opened
    once so that a bad pack is refused in one line before anything is written; what
    the import keeps in the world (formats/mcstate.py)."""
    stack = Stack.open(specs)
    try:
        return [str(Path(p).resolve()) for p in stack.paths]
    finally:
        stack.close()
