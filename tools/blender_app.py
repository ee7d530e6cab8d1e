"""The real Blender applications for tests: Debian's `blender` from two suites side by
side, each unpacked into the checkout's git-ignored `.blender/<suite>/` (used by
build.py; plain Python):

    sid     the newest (5.2.x LTS today, Python 3.14), with Mesa's Vulkan driver
            (lavapipe) besides llvmpipe: `--gpu-backend opengl` or `vulkan`
    trixie  Debian 13's 4.3 (Python 3.13), OpenGL

Nothing is pinned: sid moves, and whatever Blender and Python it carries is what the
tests run (the Python version is read from the unpacked Blender). `get(NAME)` picks an
application by suite ("sid", "trixie") or by the version its Blender has ("5.2",
"4.3"); without NAME, $VOXEL_BLENDER_APP, else the newest. GUI starts use the GPU
backend $VOXEL_GPU_BACKEND ("opengl", the default, or "vulkan").

The packages come from tools/debian_apt.py (apt with a private state per suite, the
.debs and their unpacked tree cached in `$XDG_CACHE_HOME/voxel-worlds/<suite>/`, so
another clone does not fetch them again); `.blender/<suite>/root` is a tree of hard
links to the unpacked packages (a copy where they cannot be made). The suites' glibc
is newer than the system's, so everything starts through the suite's own dynamic
loader (`patchelf` does not help: the libraries carry absolute RUNPATHs).

    .blender/blender              the newest application's launcher
    .blender/<suite>/blender      the launcher (a shell script: loader, library path, env)
    .blender/<suite>/python/      BLENDER_SYSTEM_PYTHON: lib -> root/usr/lib, bin/python3.X
                                  (a loader wrapper too: Blender runs sys.executable to
                                  install extensions' wheels)
    .blender/<suite>/site/        pytest and the extension's wheels for that Python
                                  ($VOXEL_BLENDER_SITE inside Blender; build.py fills it)
    .blender/<suite>/user/        BLENDER_USER_RESOURCES, XDG_CONFIG_HOME, XDG_CACHE_HOME
                                  (VOXEL_BLENDER_USER points a run at another folder)
    .blender/<suite>/mesa-cache/  Mesa's compiled shaders, shared by all runs
    .blender/<suite>/app.json     {"version": "5.2.2", "python": "3.14"} of the install

Its end (`xserver`, `start`, `wait`, `run`, `gui_missing`) is the one way tests and
benches start the Blender GUI under a private Xvfb.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import mmap
import os
import re
import shutil
import signal
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple


def _sibling(name: str):
    """tools/NAME.py, loaded by path: this module is imported as tools.blender_app, as
    blender_app, or from its file (bench), and a plain `import` would miss in one."""
    import importlib.util
    import sys
    mod = sys.modules.get(f"voxel_{name}")
    if mod is None:
        spec = importlib.util.spec_from_file_location(f"voxel_{name}", Path(__file__).with_name(f"{name}.py"))
        mod = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = mod
        spec.loader.exec_module(mod)
    return mod


debian = _sibling("debian_apt")  # apt's private state, downloads, the unpacked trees
SetupError, log, _write = debian.SetupError, debian.log, debian.write
ROOT = Path(__file__).resolve().parent.parent
HOME = ROOT / ".blender"
APP_ENV = "VOXEL_BLENDER_APP"       # which application (suite or version)
BACKEND_ENV = "VOXEL_GPU_BACKEND"   # which GPU backend a GUI start asks for
BACKENDS = ("opengl", "vulkan")
# What Blender needs beyond its own dependencies: numpy for its Python, the GL/EGL
# stack with Mesa's llvmpipe, and the X cursor library the window asks for.
BASE = ("blender", "python3-numpy", "libgl1", "libglx-mesa0", "libegl1", "libegl-mesa0",
        "libgl1-mesa-dri", "libxcursor1")
VULKAN = ("mesa-vulkan-drivers", "libvulkan1")  # lavapipe and the Vulkan loader
# Blender 5.x's extension manager (bl_pkg) imports these on register; Debian's package
# does not depend on them, and without them Blender cannot install an extension.
EXT_MANAGER = ("python3-cattr", "python3-requests")
# Folders of the unpacked tree that hold shared libraries Blender loads.
LIB_DIRS = ["usr/lib/x86_64-linux-gnu", "usr/lib", "usr/lib/x86_64-linux-gnu/pulseaudio",
            "usr/lib/x86_64-linux-gnu/blas", "usr/lib/x86_64-linux-gnu/lapack"]


@dataclass(frozen=True)
class Spec:
    suite: str
    packages: tuple
    backends: tuple = ("opengl",)


# Newest first: the first installed one is the default.
SPECS = (Spec("sid", BASE + VULKAN + EXT_MANAGER, BACKENDS), Spec("trixie", BASE))


def _python_of(binary: Path) -> str:
    """The Python version the Blender binary links (its libpython3.X)."""
    with open(binary, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as m:
        hit = re.search(rb"libpython(3\.\d+)\.so", m)
        found = hit.group(1).decode() if hit else ""
    if not found:
        raise SetupError(f"blender: no libpython named in {binary}")
    return found


def _version_of(launcher: Path) -> str:
    """Blender's version (e.g. "5.2.2") as the installed application reports it."""
    r = subprocess.run([str(launcher), "--version"], capture_output=True, text=True, timeout=120)
    m = re.search(r"Blender (\d+\.\d+(?:\.\d+)?)", r.stdout)
    if not m:
        raise SetupError(f"blender: {launcher} --version failed: "
                         f"{debian.cause(r.stdout + r.stderr)}")
    return m.group(1)


class App:
    """One suite's Blender: where it lives in the checkout and how it is installed."""

    def __init__(self, spec: Spec):
        self.spec = spec
        self.suite = spec.suite
        self.home = HOME / spec.suite
        self.launcher = self.home / "blender"
        self.root = self.home / "root"
        self.site = self.home / "site"
        self.gui_user = self.home / "gui-user"  # preferences template of the GUI tests
        self.backends = spec.backends

    def __repr__(self) -> str:
        return f"<Blender {self.version} ({self.suite}, Python {self.pyver})>"

    # -- what is installed --
    def info(self) -> dict:
        try:
            return json.loads((self.home / "app.json").read_text())
        except (OSError, ValueError):
            return {}

    @property
    def version(self) -> str:
        """Blender's version (e.g. "5.2.2"), "" before set-up."""
        return self.info().get("version", "")

    @property
    def pyver(self) -> str:
        """Its Python's X.Y (e.g. "3.14"), "" before set-up."""
        return self.info().get("python", "")

    def config(self) -> str:
        return hashlib.sha256(f"{self.suite} {list(self.spec.packages)} {debian.SKIP}"
                              .encode()).hexdigest()

    def installed(self) -> bool:
        stamp = self.home / ".stamp"
        return (stamp.exists() and stamp.read_text().split("\n")[0] == self.config()
                and self.root.is_dir())

    # -- set-up --
    def archive(self):
        return debian.Archive(self.suite, self.spec.packages)

    def setup(self) -> None:
        """Install (once); later runs only rewrite the launchers (paths of this checkout)."""
        if self.installed():
            if self.version:
                self._write_launchers()
            else:
                self._describe()  # moved here from the one-Blender layout
            return
        missing = [t for t in ("apt-get", "dpkg-deb", "tar", "cp") if not shutil.which(t)]
        if missing:
            raise SetupError(f"blender: {', '.join(missing)} not found (set-up needs a Debian "
                             "system to fetch Debian's Blender)")
        archive = self.archive()
        debs = archive.download()
        stamp = self.home / ".stamp"
        want = self.config() + "\n" + hashlib.sha256(
            "\n".join(sorted(d.name for d in debs)).encode()).hexdigest()
        if not (stamp.exists() and stamp.read_text() == want and self.root.is_dir()):
            self.home.mkdir(parents=True, exist_ok=True)
            tmp = Path(tempfile.mkdtemp(prefix="root.", dir=self.home))
            shutil.rmtree(tmp)
            if not archive.link_unpacked(hashlib.sha256(want.encode()).hexdigest()[:16], debs, tmp):
                log(f"unpacking {len(debs)} packages into {self.root}")
                debian.unpack(debs, tmp)
            if self.root.exists():
                shutil.rmtree(self.root)
            tmp.rename(self.root)
        self._describe()
        _write(stamp, want)

    def _describe(self) -> None:
        """app.json: the Python the binary links, then the version it reports."""
        info = {"suite": self.suite, "python": _python_of(self.root / "usr/bin/blender")}
        _write(self.home / "app.json", json.dumps(info))
        self._write_launchers()
        info["version"] = _version_of(self.launcher)
        _write(self.home / "app.json", json.dumps(info))
        self._write_launchers()

    def _write_launchers(self) -> None:
        root, home, pyver = self.root, self.home, self.pyver
        loader = root / "usr/lib/x86_64-linux-gnu/ld-linux-x86-64.so.2"
        libs = ":".join(str(root / d) for d in LIB_DIRS)
        py = home / "python"
        (py / "bin").mkdir(parents=True, exist_ok=True)
        if not (py / "lib").is_symlink():
            (py / "lib").symlink_to(Path("..") / "root" / "usr" / "lib")
        wrapper = py / "bin" / f"python{pyver}"
        _write(wrapper, f'#!/bin/sh\nexec "{loader}" --library-path "{libs}" '
                        f'"{root}/usr/bin/python{pyver}" "$@"\n', 0o755)
        for alias in ("python3", "python"):
            link = py / "bin" / alias
            if link.is_symlink():
                link.unlink()
            link.symlink_to(wrapper.name)
        _write(home / "fonts.conf",
            '<?xml version="1.0"?>\n<!DOCTYPE fontconfig SYSTEM "urn:fontconfig:fonts.dtd">\n'
            f"<fontconfig><dir>{root}/usr/share/fonts</dir>"
            f"<cachedir>{home}/user/cache/fontconfig</cachedir></fontconfig>\n")
        vulkan = ""
        if "vulkan" in self.backends:
            icd = self._lavapipe_icd()
            vulkan = ("# Vulkan: Mesa's lavapipe from the unpacked tree only (no system ICDs)\n"
                      f'export VK_DRIVER_FILES="{icd}" VK_ICD_FILENAMES="{icd}"\n')
        _write(self.launcher, f"""#!/bin/sh
# Debian {self.suite}'s Blender {self.version} unpacked in this checkout (written by build.py setup).
# VOXEL_BLENDER_USER: the user folder (preferences, extensions); default {home.name}/user.
H="{home}"
R="$H/root"
U="${{VOXEL_BLENDER_USER:-$H/user}}"
export BLENDER_SYSTEM_RESOURCES="$R/usr/share/blender"
export BLENDER_SYSTEM_PYTHON="$H/python"
export BLENDER_USER_RESOURCES="$U" XDG_CONFIG_HOME="$U/config" XDG_CACHE_HOME="$U/cache"
export LIBGL_DRIVERS_PATH="$R/usr/lib/x86_64-linux-gnu/dri"
export __EGL_VENDOR_LIBRARY_DIRS="$R/usr/share/glvnd/egl_vendor.d"
export FONTCONFIG_FILE="$H/fonts.conf"
{vulkan}# llvmpipe compiles every shader Blender's UI uses (~20 s per start); kept across user
# folders, a start with fresh preferences takes a few seconds
export MESA_SHADER_CACHE_DIR="${{MESA_SHADER_CACHE_DIR:-$H/mesa-cache}}"
export POCL_CACHE_DIR="${{POCL_CACHE_DIR:-$U/cache/pocl}}"
export PYOPENCL_CACHE_DIR="${{PYOPENCL_CACHE_DIR:-$U/cache/pyopencl}}"
export VOXEL_BLENDER="{self.launcher}" VOXEL_BLENDER_SITE="{self.site}"
unset PYTHONPATH PYTHONHOME
exec "{loader}" --library-path "{libs}" "$R/usr/bin/blender" "$@"
""", 0o755)

    def _lavapipe_icd(self) -> Path:
        """lavapipe's ICD file with its library as an absolute path into the unpacked
        tree (Debian's names the system path, which the loader would try first)."""
        src = self.root / "usr/share/vulkan/icd.d/lvp_icd.json"
        data = json.loads(src.read_text())
        lib = Path(data["ICD"]["library_path"])
        data["ICD"]["library_path"] = str(self.root / "usr/lib/x86_64-linux-gnu" / lib.name)
        dest = self.home / "lvp_icd.json"
        _write(dest, json.dumps(data, indent=1))
        return dest


def _migrate() -> None:
    """The one-Blender layout (.blender/root, .blender/blender, ...) was trixie's: move it
    into .blender/trixie/ rather than unpack it again."""
    if not (HOME / ".stamp").exists():
        return
    dest = HOME / "trixie"
    dest.mkdir(parents=True, exist_ok=True)
    for name in ("root", "python", "site", "user", "mesa-cache", "gui-user", "fonts.conf", ".stamp"):
        if (HOME / name).exists() or (HOME / name).is_symlink():
            if (dest / name).exists():
                _remove(HOME / name)
            else:
                (HOME / name).rename(dest / name)
    (HOME / "blender").unlink(missing_ok=True)
    (HOME / ".stamp").unlink(missing_ok=True)


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


def all_apps() -> list[App]:
    """Every application the set-up installs, newest suite first."""
    return [App(s) for s in SPECS]


def apps() -> list[App]:
    """The installed applications, newest Blender first."""
    found = [a for a in all_apps() if a.launcher.exists() and a.version]
    return sorted(found, key=lambda a: tuple(int(x) for x in a.version.split(".")), reverse=True)


def get(name: str | App | None = None) -> App:
    """The application NAME (a suite or a Blender version, e.g. "sid", "4.3"); None:
    $VOXEL_BLENDER_APP, else the newest installed (sid's before set-up)."""
    if isinstance(name, App):
        return name
    name = name or os.environ.get(APP_ENV) or ""
    known = apps()
    if not name or name == "newest":
        return known[0] if known else all_apps()[0]
    for a in [*known, *all_apps()]:
        if name == a.suite or (a.version and (name == a.version or a.version.startswith(name + "."))):
            return a
    names = ", ".join(f"{a.suite} ({a.version})" for a in known) or "none installed"
    raise SetupError(f"blender: no application {name!r} (there are: {names})")


def setup() -> None:
    """Install every suite's Blender (once) and point .blender/blender at the newest."""
    HOME.mkdir(exist_ok=True)
    _migrate()
    for a in reversed(all_apps()):  # the older first: it is what a machine already has
        a.setup()
    newest = get("newest")
    launcher = HOME / "blender"
    _write(launcher, f'#!/bin/sh\n# The newest Blender here: {newest.suite}\'s '
                     f'{newest.version}\nexec "{newest.launcher}" "$@"\n', 0o755)


def site_packages(app=None) -> Path:
    return get(app).site


def __getattr__(name):  # LAUNCHER, PYVER: of the application chosen by $VOXEL_BLENDER_APP
    if name == "LAUNCHER":
        return get().launcher
    if name == "PYVER":
        return get().pyver
    raise AttributeError(name)


# -- running the GUI: a private X server, Blender in it, killed as a whole ---------------
# Tests and benches start the application only through these (one place for the
# flags, the environment, the user folder and the clean-up).
SIZE = (1280, 720)
GUI_TOOLS = ("Xvfb", "xwd", "xwdtopnm", "pnmtopng")  # X server and screenshots


class TimedOut(RuntimeError):
    pass


def gui_missing(app=None) -> str | None:
    """None when the Blender GUI (of APP, see get) can run here, else why not (one line)."""
    try:
        a = get(app)
    except SystemExit as e:
        return str(e)
    if not a.launcher.exists():
        return f"no .blender/{a.suite}/blender (run `python build.py setup`)"
    for tool in GUI_TOOLS:
        if not shutil.which(tool):
            return f"{tool} missing (Debian packages xvfb, x11-apps, netpbm)"
    return None


def backend_name() -> str:
    """The GPU backend GUI starts ask for by default: $VOXEL_GPU_BACKEND, else opengl."""
    return os.environ.get(BACKEND_ENV) or "opengl"


def backend(name: str | None = None, app=None) -> str:
    """The GPU backend a GUI start asks for: NAME, else $VOXEL_GPU_BACKEND, else opengl."""
    name = name or backend_name()
    a = get(app)
    if name not in a.backends:
        raise SetupError(f"blender: backend {name!r} is not set up for {a.suite}'s Blender "
                         f"(it has {', '.join(a.backends)})")
    return name


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
          simulate: bool = True, env: dict | None = None, app=None, gpu: str | None = None):
    """The Blender window (SIZE, at the screen's corner) on DISPLAY with ARGS after the
    common flags; stdout and stderr go to LOG. simulate: --enable-event-simulate
    (events come from the script, X input is ignored). APP (see get) and GPU (see
    backend): which Blender, which GPU backend. Yields the Popen; its whole process
    group is killed on exit."""
    a = get(app)
    cmd = [str(a.launcher), "--gpu-backend", backend(gpu, a), "-p", "0", "0", str(size[0]), str(size[1]),
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
