"""Debian packages for tools/blender_app.py: resolved by apt with a private state per
suite (own sources list, lists, cache and an EMPTY dpkg status, so apt fetches the
whole closure, glibc included) from the Debian archive the system's apt already
uses, never touching /etc/apt or the system; downloaded once into
`$XDG_CACHE_HOME/voxel-worlds/<suite>/apt` and unpacked once (as `dpkg -x` does) into
`.../<suite>/unpacked`, which checkouts hard-link. Plain Python, Debian only.
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import re
import shutil
import subprocess
from pathlib import Path

try:
    import fcntl
except ImportError:  # not on Windows: set-up needs Debian's apt anyway
    fcntl = None

# Parts of the packages nobody reads here: skipped when unpacking (saves seconds).
SKIP = ["./usr/share/doc/*", "./usr/share/man/*", "./usr/share/locale/*", "./usr/share/info/*"]


class SetupError(SystemExit):
    """A one-line set-up failure naming its cause."""


def log(msg: str) -> None:
    print(f"[build] {msg}", flush=True)


def cache_base() -> Path:
    """Outside the clone: the caller's XDG_CACHE_HOME (build.py's own default for
    children is inside the checkout, so this reads the caller's environment)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "voxel-worlds"


def _mirror() -> tuple[str, str]:
    """(URI, signed-by keyring) of the Debian archive in the system's apt sources."""
    files = [Path("/etc/apt/sources.list"), *sorted(Path("/etc/apt/sources.list.d").glob("*"))]
    for f in files:
        if not f.is_file() or not f.name.endswith((".list", ".sources")):
            continue
        text = f.read_text(errors="replace")
        if f.name.endswith(".sources"):
            for stanza in re.split(r"\n\s*\n", text):
                fields = dict(re.findall(r"^([\w-]+):\s*(.*)$", stanza, re.M))
                suites = fields.get("Suites", "").split()
                if "main" in fields.get("Components", "").split() and \
                        any("-" not in s for s in suites) and "security" not in fields.get("URIs", ""):
                    return fields["URIs"].split()[0], fields.get("Signed-By", "")
        else:
            for line in text.splitlines():
                m = re.match(r"\s*deb\s+(\[[^]]*\]\s+)?(\S+)\s+(\S+)\s+(.*)", line)
                if m and "-" not in m.group(3) and "main" in m.group(4).split() \
                        and "security" not in m.group(2):
                    key = re.search(r"signed-by=(\S+?)[\s\]]", m.group(1) or "")
                    return m.group(2), key.group(1) if key else ""
    raise SetupError("blender: no Debian archive (a 'main' component) in the apt sources")


def cause(text: str) -> str:
    """The line of apt's output that says why it failed."""
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    for pick in (lambda ln: ln.startswith("E:") and "Unable to correct" not in ln,
                 lambda ln: " Depends: " in ln or "has no installation candidate" in ln,
                 lambda ln: ln.startswith(("E:", "W:", "Err:"))):
        hit = [ln for ln in lines if pick(ln)]
        if hit:
            return hit[0]
    return lines[-1] if lines else "no output"


@contextlib.contextmanager
def _locked(path: Path):
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as f:
        if fcntl:
            fcntl.flock(f, fcntl.LOCK_EX)  # another clone may set up at the same time
        yield


def unpack(debs: list[Path], dest: Path) -> None:
    """dpkg -x every package into dest (docs, man pages and locales skipped)."""
    dest.mkdir(parents=True)
    excl = [f"--exclude={p}" for p in SKIP]

    def one(deb):
        deb_p = subprocess.Popen(["dpkg-deb", "--fsys-tarfile", str(deb)], stdout=subprocess.PIPE)
        tar = subprocess.run(["tar", "-x", "-C", str(dest), "--no-same-owner",
                              "--keep-directory-symlink", *excl], stdin=deb_p.stdout)
        deb_p.stdout.close()
        if deb_p.wait() or tar.returncode:
            raise SetupError(f"blender: could not unpack {deb.name}")

    from concurrent.futures import ThreadPoolExecutor
    with ThreadPoolExecutor(os.cpu_count() or 2) as pool:
        list(pool.map(one, debs))


def write(path: Path, text: str, mode: int = 0o644) -> None:
    """A new file at PATH (never written in place: a running Blender may read the old
    one, and a copy of .blender made with hard links must not change with this one)."""
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.unlink(missing_ok=True)
    tmp.write_text(text)
    tmp.chmod(mode)
    os.replace(tmp, path)


class Archive:
    """One suite's packages: the apt state, the downloaded .debs, the unpacked tree."""

    def __init__(self, suite: str, packages):
        self.suite = suite
        self.packages = tuple(packages)

    def cache(self) -> Path:
        return cache_base() / self.suite / "apt"

    def _apt_args(self) -> list[str]:
        state = self.cache()
        args = [f"-o=Dir::Etc::sourcelist={state / 'sources.list'}",
                f"-o=Dir::Etc::sourceparts={state / 'sources.list.d'}",
                f"-o=Dir::Etc::preferencesparts={state / 'preferences.d'}",
                f"-o=Dir::State={state / 'state'}", f"-o=Dir::State::status={state / 'status'}",
                f"-o=Dir::Cache={state / 'cache'}", "-o=Debug::NoLocking=1",
                "-o=APT::Get::Assume-Yes=1", "-q"]
        if os.geteuid() == 0:  # the cache may sit in a home _apt cannot enter
            args.append("-o=APT::Sandbox::User=root")
        return args

    def _apt(self, *cmd) -> str:
        r = subprocess.run(["apt-get", *self._apt_args(), *cmd], text=True,
                           capture_output=True, env=dict(os.environ, LC_ALL="C"))
        if r.returncode:
            raise subprocess.CalledProcessError(r.returncode, ["apt-get", *cmd], r.stdout, r.stderr)
        return r.stdout

    def _prepare_state(self) -> None:
        state = self.cache()
        legacy = cache_base() / "apt"  # before the suites sat side by side: trixie's
        if not state.exists() and (legacy / "sources.list").exists() and \
                f" {self.suite} main" in (legacy / "sources.list").read_text():
            state.parent.mkdir(parents=True, exist_ok=True)
            subprocess.run(["cp", "-al", str(legacy), str(state)], check=False)
            old = cache_base() / "unpacked"
            if old.is_dir():
                subprocess.run(["cp", "-al", str(old), str(state.parent / "unpacked")], check=False)
        for d in ("sources.list.d", "preferences.d", "state/lists/partial", "cache/archives/partial"):
            (state / d).mkdir(parents=True, exist_ok=True)
        (state / "status").touch()
        uri, key = _mirror()
        opt = f"[signed-by={key}] " if key and Path(key).exists() else ""
        write(state / "sources.list", f"deb {opt}{uri} {self.suite} main\n")

    def _selection(self) -> list[Path]:
        """The .deb files apt chose (simulated install over the empty status). Resolving
        takes apt seconds of CPU, so the answer is kept for the same lists and packages."""
        state = self.cache()
        lists = sorted((state / "state" / "lists").glob("*_InRelease"))
        key = hashlib.sha256(f"{list(self.packages)}".encode()
                             + b"".join(f.read_bytes() for f in lists)).hexdigest()
        memo = state / "selection.txt"
        if memo.exists():
            head, *names = memo.read_text().split("\n")
            if head == key and names:
                return [state / "cache" / "archives" / n for n in names]
        out = self._apt("install", "-s", "--no-install-recommends", *self.packages)
        names = [f"{name}_{ver.replace(':', '%3a')}_{arch}.deb"
                 for name, ver, arch in re.findall(r"^Inst (\S+) \((\S+) .*\[(\S+)\]\)", out, re.M)]
        if not names:
            raise SetupError(f"blender ({self.suite}): apt selected no packages")
        write(memo, "\n".join([key, *names]))
        return [state / "cache" / "archives" / n for n in names]

    def download(self) -> list[Path]:
        """The selected .debs, fetched into the cache unless already there. A failure
        is one line naming apt's reason."""
        try:
            return self._download()
        except subprocess.CalledProcessError as e:
            raise SetupError(f"blender ({self.suite}): {' '.join(e.cmd[:2])} failed: "
                             f"{cause((e.stdout or '') + (e.stderr or ''))}") from None

    def _download(self) -> list[Path]:
        state = self.cache()
        with _locked(state.parent / "lock"):
            self._prepare_state()
            fresh = False
            if not list((state / "state" / "lists").glob(f"*_{self.suite}_InRelease")):
                log(f"apt-get update for {self.suite} (private state in {state})")
                self._apt("update")
                fresh = True
                if not list((state / "state" / "lists").glob(f"*_{self.suite}_InRelease")):
                    raise SetupError(f"blender ({self.suite}): apt-get update fetched no "
                                     f"package list for {self.suite}")
            try:
                debs = self._selection()
            except subprocess.CalledProcessError:
                if fresh:
                    raise
                log(f"{self.suite}: cached package lists do not resolve: apt-get update")
                self._apt("update")
                fresh = True
                debs = self._selection()
            if all(d.exists() for d in debs):
                return debs
            try:
                log(f"apt-get install --download-only for {self.suite} "
                    f"({len(debs)} packages, ~300 MB, once)")
                self._apt("install", "--download-only", "--no-install-recommends",
                          *self.packages)
            except subprocess.CalledProcessError:
                if fresh:
                    raise
                # stale lists name versions the archive dropped (sid daily, a point release)
                log("download failed with cached package lists: apt-get update and retry")
                self._apt("update")
                debs = self._selection()
                self._apt("install", "--download-only", "--no-install-recommends",
                          *self.packages)
            missing = [d.name for d in debs if not d.exists()]
            if missing:
                raise SetupError(f"blender ({self.suite}): apt did not download {missing[:3]}")
            return debs

    def link_unpacked(self, key: str, debs: list[Path], dest: Path) -> bool:
        """dest as hard links to the unpacked tree kept next to the .debs (unpacked there
        once): another clone gets its Blender in seconds. False when the cache is on
        another file system (the caller unpacks into dest itself)."""
        cache = self.cache().parent / "unpacked"
        tree = cache / key
        with _locked(cache / "lock"):
            if not (tree / ".complete").exists():
                for old in cache.glob("*"):
                    if old.is_dir():
                        shutil.rmtree(old)  # an older package set: only one tree is kept
                tmp = cache / f"{key}.tmp"
                shutil.rmtree(tmp, ignore_errors=True)
                log(f"unpacking {len(debs)} packages into {tree}")
                unpack(debs, tmp)
                (tmp / ".complete").touch()
                tmp.rename(tree)
            r = subprocess.run(["cp", "-al", str(tree), str(dest)], capture_output=True)
        if r.returncode:
            shutil.rmtree(dest, ignore_errors=True)
            return False
        (dest / ".complete").unlink()
        return True

