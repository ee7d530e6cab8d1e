"""The real Blender application for tests: Debian trixie's `blender` (4.3, Python 3.13)
unpacked into the checkout's git-ignored `.blender/` (used by build.py; plain Python).

The packages come from the Debian archive the system's apt already uses, resolved by
apt with a private state (own sources list, lists, cache and an EMPTY dpkg status, so
apt fetches the whole closure, glibc included) and never touch /etc/apt or the
system. The downloaded .debs stay in `$XDG_CACHE_HOME/voxel-worlds/apt` (default
~/.cache), so another clone of the repository does not fetch them again. Every .deb
is unpacked (as `dpkg -x` does) once into `$XDG_CACHE_HOME/voxel-worlds/unpacked`,
and `.blender/root` is a tree of hard links to it (a copy where they cannot be made); trixie's glibc is newer than the
system's, so everything starts through trixie's own dynamic loader (`patchelf` does
not help: the libraries carry absolute RUNPATHs).

    .blender/blender      the launcher (a shell script: loader, library path, env)
    .blender/python/      BLENDER_SYSTEM_PYTHON: lib -> root/usr/lib, bin/python3.13
                          (a loader wrapper too: Blender runs sys.executable to
                          install extensions' wheels)
    .blender/site/        pytest (+ the bundled wheels for 3.13) for tests/run.py
    .blender/user/        BLENDER_USER_RESOURCES, XDG_CONFIG_HOME, XDG_CACHE_HOME
                          (VOXEL_BLENDER_USER points a run at another folder)
    .blender/mesa-cache/  llvmpipe's compiled shaders, shared by all runs

Its end (`xserver`, `start`, `wait`, `run`, `gui_missing`) is the one way tests and
benches start the Blender GUI under a private Xvfb.
"""
from __future__ import annotations

import contextlib
import fcntl
import hashlib
import os
import re
import shutil
import signal
import subprocess
import tempfile
from pathlib import Path
from typing import NamedTuple

ROOT = Path(__file__).resolve().parent.parent
HOME = ROOT / ".blender"
LAUNCHER = HOME / "blender"
SUITE = "trixie"
# What Blender needs beyond its own dependencies: numpy for its Python, the GL/EGL
# stack with Mesa's llvmpipe, and the X cursor library the window asks for.
PACKAGES = ["blender", "python3-numpy", "libgl1", "libglx-mesa0", "libegl1", "libegl-mesa0",
            "libgl1-mesa-dri", "libxcursor1"]
PYVER = "3.13"
# Folders of the unpacked tree that hold shared libraries Blender loads.
LIB_DIRS = ["usr/lib/x86_64-linux-gnu", "usr/lib", "usr/lib/x86_64-linux-gnu/pulseaudio",
            "usr/lib/x86_64-linux-gnu/blas", "usr/lib/x86_64-linux-gnu/lapack"]
# Parts of the packages nobody reads here: skipped when unpacking (saves seconds).
SKIP = ["./usr/share/doc/*", "./usr/share/man/*", "./usr/share/locale/*", "./usr/share/info/*"]


def log(msg: str) -> None:
    print(f"[build] {msg}", flush=True)


def cache_dir() -> Path:
    """Outside the clone: the caller's XDG_CACHE_HOME (build.py's own default for
    children is inside the checkout, so this reads the caller's environment)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "voxel-worlds" / "apt"


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
    raise SystemExit("blender: no Debian archive (a 'main' component) in the apt sources")


def _apt_args(state: Path) -> list[str]:
    args = [f"-o=Dir::Etc::sourcelist={state / 'sources.list'}",
            f"-o=Dir::Etc::sourceparts={state / 'sources.list.d'}",
            f"-o=Dir::Etc::preferencesparts={state / 'preferences.d'}",
            f"-o=Dir::State={state / 'state'}", f"-o=Dir::State::status={state / 'status'}",
            f"-o=Dir::Cache={state / 'cache'}", "-o=Debug::NoLocking=1",
            "-o=APT::Get::Assume-Yes=1", "-q"]
    if os.geteuid() == 0:  # the cache may sit in a home _apt cannot enter
        args.append("-o=APT::Sandbox::User=root")
    return args


def _apt(state: Path, *cmd) -> str:
    r = subprocess.run(["apt-get", *_apt_args(state), *cmd], text=True,
                       capture_output=True, env=dict(os.environ, LC_ALL="C"))
    if r.returncode:
        print(r.stdout[-3000:] + r.stderr[-3000:], flush=True)
        raise subprocess.CalledProcessError(r.returncode, ["apt-get", *cmd], r.stdout, r.stderr)
    return r.stdout


def _prepare_state(state: Path) -> None:
    for d in ("sources.list.d", "preferences.d", "state/lists/partial", "cache/archives/partial"):
        (state / d).mkdir(parents=True, exist_ok=True)
    (state / "status").touch()
    uri, key = _mirror()
    opt = f"[signed-by={key}] " if key and Path(key).exists() else ""
    (state / "sources.list").write_text(f"deb {opt}{uri} {SUITE} main\n")


def _selection(state: Path) -> list[Path]:
    """The .deb files apt chose (simulated install over the empty status). Resolving
    takes apt seconds of CPU, so the answer is kept for the same lists and packages."""
    lists = sorted((state / "state" / "lists").glob("*_InRelease"))
    key = hashlib.sha256(f"{PACKAGES}".encode() + b"".join(f.read_bytes() for f in lists)).hexdigest()
    memo = state / "selection.txt"
    if memo.exists():
        head, *names = memo.read_text().split("\n")
        if head == key and names:
            return [state / "cache" / "archives" / n for n in names]
    out = _apt(state, "install", "-s", "--no-install-recommends", *PACKAGES)
    names = [f"{name}_{ver.replace(':', '%3a')}_{arch}.deb"
             for name, ver, arch in re.findall(r"^Inst (\S+) \((\S+) .*\[(\S+)\]\)", out, re.M)]
    if not names:
        raise SystemExit("blender: apt selected no packages:\n" + out[-2000:])
    memo.write_text("\n".join([key, *names]))
    return [state / "cache" / "archives" / n for n in names]


@contextlib.contextmanager
def _locked(path: Path):
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as f:
        fcntl.flock(f, fcntl.LOCK_EX)  # another clone may set up at the same time
        yield


def download() -> list[Path]:
    """The selected .debs, fetched into the cache unless already there."""
    state = cache_dir()
    with _locked(state / "lock"):
        _prepare_state(state)
        fresh = False
        if not list((state / "state" / "lists").glob(f"*_{SUITE}_InRelease")):
            log(f"apt-get update (private state in {state})")
            _apt(state, "update")
            fresh = True
        debs = _selection(state)
        if all(d.exists() for d in debs):
            return debs
        try:
            log(f"apt-get install --download-only ({len(debs)} packages, ~300 MB, once)")
            _apt(state, "install", "--download-only", "--no-install-recommends", *PACKAGES)
        except subprocess.CalledProcessError:
            if fresh:
                raise
            # stale lists name versions the archive dropped (point release): refresh
            log("download failed with cached package lists: apt-get update and retry")
            _apt(state, "update")
            debs = _selection(state)
            _apt(state, "install", "--download-only", "--no-install-recommends", *PACKAGES)
        missing = [d.name for d in debs if not d.exists()]
        if missing:
            raise SystemExit(f"blender: apt did not download {missing[:5]}")
        return debs


def _unpack(debs: list[Path], dest: Path) -> None:
    """dpkg -x every package into dest (docs, man pages and locales skipped)."""
    dest.mkdir(parents=True)
    excl = [f"--exclude={p}" for p in SKIP]

    def one(deb):
        deb_p = subprocess.Popen(["dpkg-deb", "--fsys-tarfile", str(deb)], stdout=subprocess.PIPE)
        tar = subprocess.run(["tar", "-x", "-C", str(dest), "--no-same-owner",
                              "--keep-directory-symlink", *excl], stdin=deb_p.stdout)
        deb_p.stdout.close()
        if deb_p.wait() or tar.returncode:
            raise SystemExit(f"blender: could not unpack {deb.name}")

    from concurrent.futures import ThreadPoolExecutor
    with ThreadPoolExecutor(os.cpu_count() or 2) as pool:
        list(pool.map(one, debs))


def _link_unpacked(key: str, debs: list[Path], dest: Path) -> bool:
    """dest as hard links to the unpacked tree kept next to the .debs (unpacked there
    once): another clone gets its Blender in seconds. False when the cache is on
    another file system (the caller unpacks into dest itself)."""
    cache = cache_dir().parent / "unpacked"
    tree = cache / key
    with _locked(cache / "lock"):
        if not (tree / ".complete").exists():
            for old in cache.glob("*"):
                if old.is_dir():
                    shutil.rmtree(old)  # an older package set: only one tree is kept
            tmp = cache / f"{key}.tmp"
            shutil.rmtree(tmp, ignore_errors=True)
            log(f"unpacking {len(debs)} packages into {tree}")
            _unpack(debs, tmp)
            (tmp / ".complete").touch()
            tmp.rename(tree)
        r = subprocess.run(["cp", "-al", str(tree), str(dest)], capture_output=True)
    if r.returncode:
        shutil.rmtree(dest, ignore_errors=True)
        return False
    (dest / ".complete").unlink()
    return True


def _lib_path(root: Path) -> str:
    return ":".join(str(root / d) for d in LIB_DIRS)


def _write_launchers(root: Path) -> None:
    loader = root / "usr/lib/x86_64-linux-gnu/ld-linux-x86-64.so.2"
    libs = _lib_path(root)
    py = HOME / "python"
    (py / "bin").mkdir(parents=True, exist_ok=True)
    if not (py / "lib").is_symlink():
        (py / "lib").symlink_to(Path("..") / "root" / "usr" / "lib")
    wrapper = py / "bin" / f"python{PYVER}"
    wrapper.write_text(f'#!/bin/sh\nexec "{loader}" --library-path "{libs}" '
                       f'"{root}/usr/bin/python{PYVER}" "$@"\n')
    wrapper.chmod(0o755)
    for alias in ("python3", "python"):
        link = py / "bin" / alias
        if not link.is_symlink():
            link.symlink_to(wrapper.name)
    fonts = HOME / "fonts.conf"
    fonts.write_text(
        '<?xml version="1.0"?>\n<!DOCTYPE fontconfig SYSTEM "urn:fontconfig:fonts.dtd">\n'
        f"<fontconfig><dir>{root}/usr/share/fonts</dir>"
        f"<cachedir>{HOME}/user/cache/fontconfig</cachedir></fontconfig>\n")
    LAUNCHER.write_text(f"""#!/bin/sh
# Debian {SUITE}'s Blender unpacked in this checkout (written by build.py setup).
# VOXEL_BLENDER_USER: the user folder (preferences, extensions); default .blender/user.
H="{HOME}"
R="$H/root"
U="${{VOXEL_BLENDER_USER:-$H/user}}"
export BLENDER_SYSTEM_RESOURCES="$R/usr/share/blender"
export BLENDER_SYSTEM_PYTHON="$H/python"
export BLENDER_USER_RESOURCES="$U" XDG_CONFIG_HOME="$U/config" XDG_CACHE_HOME="$U/cache"
export LIBGL_DRIVERS_PATH="$R/usr/lib/x86_64-linux-gnu/dri"
export __EGL_VENDOR_LIBRARY_DIRS="$R/usr/share/glvnd/egl_vendor.d"
export FONTCONFIG_FILE="$H/fonts.conf"
# llvmpipe compiles every shader Blender's UI uses (~20 s per start); kept across user
# folders, a start with fresh preferences takes a few seconds
export MESA_SHADER_CACHE_DIR="${{MESA_SHADER_CACHE_DIR:-$H/mesa-cache}}"
export POCL_CACHE_DIR="${{POCL_CACHE_DIR:-$U/cache/pocl}}"
export PYOPENCL_CACHE_DIR="${{PYOPENCL_CACHE_DIR:-$U/cache/pyopencl}}"
export VOXEL_BLENDER="{LAUNCHER}"
unset PYTHONPATH PYTHONHOME
exec "{loader}" --library-path "{libs}" "$R/usr/bin/blender" "$@"
""")
    LAUNCHER.chmod(0o755)


def _stamp_of(debs: list[Path]) -> str:
    return hashlib.sha256("\n".join(sorted(d.name for d in debs)).encode()).hexdigest()


def _config() -> str:
    return hashlib.sha256(f"{SUITE} {PACKAGES} {SKIP}".encode()).hexdigest()


def installed() -> bool:
    stamp = HOME / ".stamp"
    return (stamp.exists() and stamp.read_text().split("\n")[0] == _config()
            and (HOME / "root").is_dir())


def setup() -> None:
    """Install (once); later runs only rewrite the launchers (paths of this checkout)."""
    stamp, root = HOME / ".stamp", HOME / "root"
    if installed():
        _write_launchers(root)
        return
    missing = [t for t in ("apt-get", "dpkg-deb", "tar", "cp") if not shutil.which(t)]
    if missing:
        raise SystemExit(f"blender: {', '.join(missing)} not found (set-up needs a Debian "
                         "system to fetch Debian's Blender)")
    debs = download()
    want = _config() + "\n" + _stamp_of(debs)
    if not (stamp.exists() and stamp.read_text() == want and root.is_dir()):
        HOME.mkdir(exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix="root.", dir=HOME))
        shutil.rmtree(tmp)
        if not _link_unpacked(hashlib.sha256(want.encode()).hexdigest()[:16], debs, tmp):
            log(f"unpacking {len(debs)} packages into {root}")
            _unpack(debs, tmp)
        if root.exists():
            shutil.rmtree(root)
        tmp.rename(root)
    _write_launchers(root)
    stamp.write_text(want)


def site_packages() -> Path:
    return HOME / "site"


# -- running the GUI: a private X server, Blender in it, killed as a whole ---------------
# Tests and benches start the application only through these (one place for the
# flags, the environment, the user folder and the clean-up).
SIZE = (1280, 720)
GUI_TOOLS = ("Xvfb", "xwd", "xwdtopnm", "pnmtopng")  # X server and screenshots


class TimedOut(RuntimeError):
    pass


def gui_missing() -> str | None:
    """None when the Blender GUI can run here, else why not (one line)."""
    if not LAUNCHER.exists():
        return "no .blender/blender (run `python build.py setup`)"
    for tool in GUI_TOOLS:
        if not shutil.which(tool):
            return f"{tool} missing (Debian packages xvfb, x11-apps, netpbm)"
    return None


def app_env(user: Path | None = None, **extra) -> dict:
    """The caller's environment without Blender's and XDG variables (the launcher sets
    its own), VOXEL_BLENDER_USER pointing at USER (None: .blender/user), plus EXTRA."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("BLENDER_", "XDG_"))}
    if user is not None:
        env["VOXEL_BLENDER_USER"] = str(user)
    env.update(extra)
    return env


class Screen(NamedTuple):
    display: str  # ":N"
    pid: int


@contextlib.contextmanager
def xserver(size=SIZE):
    """A private Xvfb; it picks a free display itself (-displayfd) so parallel runs
    never meet. Killed on exit."""
    r, w = os.pipe()
    x = subprocess.Popen(["Xvfb", "-displayfd", str(w), "-screen", "0", f"{size[0]}x{size[1]}x24",
                          "-nolisten", "tcp", "-noreset"], pass_fds=(w,),
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         start_new_session=True)
    os.close(w)
    try:
        with os.fdopen(r) as f:
            num = f.readline().strip()
        if not num:
            raise RuntimeError("Xvfb did not start")
        yield Screen(f":{num}", x.pid)
    finally:
        kill(x)


def kill(p: subprocess.Popen) -> None:
    """SIGKILL to P's whole process group (started in a session of its own: what
    Blender started dies with it, even after Blender itself exited)."""
    try:
        os.killpg(p.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    p.wait()


@contextlib.contextmanager
def start(args, *, display: str, log: Path, user: Path | None = None, size=SIZE,
          simulate: bool = True, env: dict | None = None):
    """The Blender window (SIZE, at the screen's corner) on DISPLAY with ARGS after the
    common flags; stdout and stderr go to LOG. simulate: --enable-event-simulate
    (events come from the script, X input is ignored). Yields the Popen; its whole
    process group is killed on exit."""
    cmd = [str(LAUNCHER), "-p", "0", "0", str(size[0]), str(size[1]),
           *(["--enable-event-simulate"] if simulate else []), *map(str, args)]
    with open(log, "w") as f:
        p = subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT, cwd=ROOT,
                             env=app_env(user, DISPLAY=display, **(env or {})),
                             start_new_session=True)
    try:
        yield p
    finally:
        kill(p)


def wait(p: subprocess.Popen, timeout: float, log: Path | None = None) -> int:
    """P's exit status; past TIMEOUT seconds its process group is killed and TimedOut
    raised (with the end of LOG)."""
    try:
        return p.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        kill(p)
        raise TimedOut(f"Blender timed out after {timeout:.0f} s (killed):\n"
                       f"{tail(log) if log else ''}") from None


def run(args, *, log: Path, timeout: float, size=SIZE, **kw) -> int:
    """Blender with ARGS in an X server of its own until it exits (see start, wait)."""
    with xserver(size) as x, start(args, display=x.display, log=log, size=size, **kw) as p:
        return wait(p, timeout, log)


def tail(path: Path, n: int = 4000) -> str:
    try:
        return Path(path).read_text(errors="replace")[-n:]
    except OSError:
        return ""
