"""Task runner for Voxel Worlds (plain Python 3.11, no bpy import).

    python build.py setup       install what is missing (apt when root, .venv, npm tools,
                                the real Blender applications in .blender/: Debian
                                sid's, the newest, and trixie's 4.3)
    python build.py blender [NAME] [-- ARGS]
                                run a real Blender with ARGS: the newest (Debian sid's,
                                5.2 today), or NAME: a version or suite (4.3 or trixie,
                                5.2 or sid)
    python build.py test [ARGS] setup, then every test layer: pytest under bpy, the
                                Blender-facing tests inside each real Blender (and
                                once without OpenCL), the GUI tests in each Blender
                                and backend (with ARGS: only pytest under bpy, with
                                ARGS)
    python build.py demo        setup, then generate a world, render a picture, bake a .glb
    python build.py bench [DIR] setup, then `python -m voxel_addon bench --out DIR`
    python build.py extension   setup, then one extension zip per platform into dist/
    python build.py dev         editor stubs (fake-bpy-module) in their own .venv-dev,
                                so they can never shadow the real bpy the tests use

Every task is idempotent; a stamp in .venv records what was installed, so a second
run starts in well under a second.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
PY = VENV / "bin" / "python"
STAMP = VENV / ".setup-stamp"
TOOLS = ROOT / ".tools"          # npm tools (git-ignored)
DEMO = ROOT / "demo_out"         # demo outputs (git-ignored)

APT_PACKAGES = ["libgl1", "libegl1", "libegl-mesa0", "libgl1-mesa-dri", "libgbm1", "binutils",
                "xvfb", "x11-apps", "netpbm"]  # the last three: GUI tests (X server, screenshots)
# Wanted only when the command is missing (a machine may have Node.js from elsewhere).
APT_FOR_COMMAND = {"node": "nodejs", "npm": "npm"}
NPM_PACKAGES = ["gltf-validator@2.0.0-dev.3.10"]


def log(msg: str) -> None:
    print(f"[build] {msg}", flush=True)


def run(cmd, **kw) -> None:
    subprocess.run([str(c) for c in cmd], check=True, **kw)


def env() -> dict:
    """Environment for every child: caches inside the checkout, never in ~."""
    e = dict(os.environ)
    cache = ROOT / ".cache"
    e.setdefault("XDG_CACHE_HOME", str(cache))
    e.setdefault("BLENDER_USER_RESOURCES", str(cache / "blender"))
    e.setdefault("POCL_CACHE_DIR", str(cache / "pocl"))
    e.setdefault("PYOPENCL_CACHE_DIR", str(cache / "pyopencl"))
    e.setdefault("MPLCONFIGDIR", str(cache / "matplotlib"))
    e["PATH"] = f"{VENV / 'bin'}{os.pathsep}{TOOLS / 'node_modules' / '.bin'}{os.pathsep}{e.get('PATH', '')}"
    e["PYTHONPATH"] = str(ROOT)
    return e


def _missing_debs() -> list[str]:
    if not shutil.which("dpkg-query"):
        return []
    missing = []
    for p in APT_PACKAGES:
        r = subprocess.run(["dpkg-query", "-W", "-f=${Status}", p],
                           capture_output=True, text=True)
        if "install ok installed" not in r.stdout:
            missing.append(p)
    missing += [p for cmd, p in APT_FOR_COMMAND.items() if not shutil.which(cmd)]
    return missing


def setup_apt() -> None:
    missing = _missing_debs()
    if not missing:
        return
    if os.geteuid() != 0:
        log(f"not root: please install Debian packages {' '.join(missing)}")
        return
    log(f"apt-get install {' '.join(missing)}")
    e = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    run(["apt-get", "update", "-q"], env=e)
    run(["apt-get", "install", "-y", "-q", "--no-install-recommends", *missing], env=e)


def _wanted() -> str:
    parts = [(ROOT / f).read_text() for f in ("requirements.txt",)]
    parts.append(" ".join(NPM_PACKAGES))
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()


def setup_venv() -> None:
    want = _wanted()
    if STAMP.exists() and STAMP.read_text() == want and PY.exists():
        return
    if not PY.exists():
        log(f"creating {VENV}")
        run([sys.executable, "-m", "venv", VENV])
    log("pip install -r requirements.txt (first time ~1 min: bpy is 374 MB)")
    run([PY, "-m", "pip", "install", "-q", "--disable-pip-version-check",
         "-r", ROOT / "requirements.txt"], env=env())
    if NPM_PACKAGES and shutil.which("npm"):
        TOOLS.mkdir(exist_ok=True)
        log(f"npm install {' '.join(NPM_PACKAGES)}")
        run(["npm", "install", "--silent", "--no-audit", "--no-fund", "--prefix", TOOLS,
             *NPM_PACKAGES], env=env())
    STAMP.write_text(want)


def _app():
    """tools/blender_app.py: the real Blender application (installed by setup)."""
    sys.path.insert(0, str(ROOT / "tools"))
    import blender_app
    return blender_app


def setup() -> None:
    if sys.version_info < (3, 11):
        sys.exit("Python 3.11 or newer is needed to run build.py")
    import time
    for step in (setup_apt, setup_venv, _app().setup, setup_wheels):
        t0 = time.monotonic()
        step()
        if time.monotonic() - t0 > 2:
            log(f"{step.__module__}.{step.__name__}: {time.monotonic() - t0:.0f} s")


def task_blender(args) -> int:
    """blender [NAME] [-- ARGS]: a real Blender (the newest, or NAME: "4.3", "trixie",
    "5.2", "sid") with ARGS, in the checkout."""
    name = None
    if args and args[0] != "--":
        name, args = args[0], args[1:]
    args = args[1:] if args[:1] == ["--"] else args
    setup()
    return subprocess.run([_app().get(name).launcher, *args], cwd=ROOT, env=env()).returncode


GUI_TESTS = "tests/gui"
# The GUI tests of what draws or moves with the GPU backend and the Blender version
# (the live view, the edit tool, the first minute) and the installed zip: these run in
# every real Blender and, in the newest, on Vulkan too; the rest of tests/gui runs in
# the newest Blender on OpenGL (CI time: see README, Tests).
GUI_EVERYWHERE = ["tests/gui/test_viewport.py", "tests/gui/test_edit_tool.py",
                  "tests/gui/test_first_minute.py", "tests/gui/test_installed.py"]
GUI_VULKAN = GUI_EVERYWHERE[:3] + ["tests/gui/test_minecraft_stack_view.py"]


def _blender_facing(app, user: Path, **extra) -> tuple[list, dict]:
    return ([app.launcher, "-b", "--factory-startup", "--python-exit-code", "1",
             "-P", ROOT / "tests" / "run.py"], {"VOXEL_BLENDER_USER": str(user), **extra})


def _layers(user: Path) -> list[tuple[str, list, dict]]:
    """The test layers: (name, command, extra environment); user: an empty folder for
    the real Blenders' preferences and extensions (one below it per run)."""
    apps = _app().apps()  # newest first
    newest = apps[0]
    gui = [PY, "-m", "pytest"]
    layers = [("pytest under the bpy module",
               [PY, "-m", "pytest", "tests", f"--ignore={GUI_TESTS}"], {})]
    for a in apps:
        layers.append((f"Blender-facing tests in Blender {a.version}",
                       *_blender_facing(a, user / a.suite)))
    layers.append((f"Blender-facing tests without OpenCL (VOXEL_OPENCL=0), Blender {newest.version}",
                   *_blender_facing(newest, user / "no-opencl", VOXEL_OPENCL="0")))
    layers.append((f"GUI tests in Blender {newest.version}, OpenGL", [*gui, GUI_TESTS],
                   {"VOXEL_BLENDER_APP": newest.suite, "VOXEL_GPU_BACKEND": "opengl"}))
    if "vulkan" in newest.backends:
        layers.append((f"GUI tests (live view, edit tool) in Blender {newest.version}, Vulkan",
                       [*gui, *_present(GUI_VULKAN)],
                       {"VOXEL_BLENDER_APP": newest.suite, "VOXEL_GPU_BACKEND": "vulkan"}))
    for a in apps[1:]:
        layers.append((f"GUI tests (live view, edit tool, installed zip) in Blender {a.version}, "
                       "OpenGL", [*gui, *_present(GUI_EVERYWHERE)],
                       {"VOXEL_BLENDER_APP": a.suite, "VOXEL_GPU_BACKEND": "opengl"}))
    return layers


def _present(paths: list[str]) -> list[str]:
    return [p for p in paths if (ROOT / p).exists()]


def task_test(args) -> int:
    """test [PYTEST_ARGS]: with arguments, pytest under bpy with them; without, every
    layer (each runs even when an earlier one failed), timed."""
    import time
    setup()
    if args:
        return subprocess.run([PY, "-m", "pytest", *args], cwd=ROOT, env=env()).returncode
    import tempfile
    results = []
    with tempfile.TemporaryDirectory(prefix="voxel-blender-user-") as user:
        for name, cmd, extra in _layers(Path(user)):
            log(f"layer: {name}")
            t0 = time.monotonic()
            code = subprocess.run([str(c) for c in cmd], cwd=ROOT, env={**env(), **extra}).returncode
            results.append((name, code, time.monotonic() - t0))
    for name, code, secs in results:
        log(f"{'ok    ' if code == 0 else 'FAILED'} {secs:6.0f} s  {name}")
    log(f"{sum(s for *_, s in results):.0f} s in all")
    return next((code for _, code, _ in results if code), 0)


def voxel(*args) -> None:
    log("python -m voxel_addon " + " ".join(map(str, args)))
    run([PY, "-m", "voxel_addon", *args], cwd=ROOT, env=env())


def task_demo(args) -> int:
    setup()
    DEMO.mkdir(exist_ok=True)
    world = DEMO / "demo.sqlite"
    voxel("generate", "--world", world, "--seed", "2019", "--center", "0", "0", "--radius", "4")
    voxel("info", "--world", world)
    for extra in DEMO_STEPS:
        extra(world)
    log(f"demo outputs are in {DEMO}")
    return 0


def _demo_render(world):
    # far terrain beyond the generated area: the world goes on (no haze wall over a sea)
    voxel("render", "--world", world, "--camera", "-40", "-40", "110", "45", "-20", "--far", "96",
          "--time", "10:30", "--size", "960", "540", "--out", DEMO / "demo.png")


def _demo_bake(world):
    voxel("bake", "--world", world, "--region", "-16", "-16", "16", "16", "--out", DEMO / "demo.glb")


def _cli_has(cmd: str) -> bool:
    return (ROOT / "voxel_addon" / "cli" / f"{cmd}.py").exists()


DEMO_STEPS = [step for cmd, step in (("render", _demo_render), ("bake", _demo_bake)) if _cli_has(cmd)]


def task_bench(args) -> int:
    setup()
    out = args[0] if args else str(ROOT / "bench_out")
    return subprocess.run([PY, "-m", "voxel_addon", "bench", "--out", out, *args[1:]],
                          cwd=ROOT, env=env()).returncode


# Wheels bundled into the extension (Blender ships numpy; Debian's Blenders do not ship
# zstandard, so it comes along): pyopencl (on Linux with its pocl CPU device; Windows
# and macOS have no pocl wheel: there pyopencl's loader finds the vendor's driver, else
# the NumPy path runs), moderngl, zstandard and lz4 (Minecraft's LZ4 chunks), with their dependencies. Per Blender
# platform, for the Pythons of the Blenders that run there: 3.11 (official 4.3-5.0),
# 3.13 (official 5.1+, Debian trixie's 4.3), 3.14 on Linux (Debian sid's 5.2) and
# whatever Python an installed real Blender has. No macos-x64: Intel Macs run Blender
# up to 4.5 LTS, but moderngl 5.13 has no x86_64 macOS wheel.
WHEELS = ["pyopencl==2026.1.4", "pytools", "platformdirs", "typing_extensions", "siphash24",
          "moderngl==5.13.0", "glcontext==3.1.0", "zstandard==0.25.0", "lz4==4.4.5"]
MAC_ARM = [f"macosx_{v}_0_arm64" for v in range(11, 16)] + \
    [f"macosx_10_{v}_universal2" for v in range(9, 16)] + [f"macosx_{v}_0_universal2" for v in range(11, 16)]
WHEEL_PLATFORMS = {  # Blender platform -> (pip platform tags, Pythons, its own extra wheels)
    "linux-x64": (["manylinux_2_17_x86_64", "manylinux2014_x86_64", "manylinux_2_28_x86_64"],
                  ["3.11", "3.13", "3.14"], ["pocl-binary-distribution==3.0"]),
    "windows-x64": (["win_amd64"], ["3.11", "3.13"], []),
    "macos-arm64": (MAC_ARM, ["3.11", "3.13"], []),
}
WHEEL_DIR = ROOT / ".cache" / "wheels"
# Test tools for the real Blender's Python (.blender/site), versions as in requirements.txt;
# with their dependencies but not numpy (Blender's own must be the one imported).
BLENDER_TEST_PACKAGES = ["pytest==9.2.0"]
BLENDER_TEST_NODEPS = ["matplotlib==3.11.2", "contourpy", "cycler", "fonttools", "kiwisolver",
                       "pillow", "pyparsing", "python-dateutil", "six"]


def _pip_for(python: str, tags, *args) -> None:
    run([PY, "-m", "pip", *args[:1], "-q", "--disable-pip-version-check", "--only-binary=:all:",
         "--python-version", python, "--implementation", "cp",
         *[a for t in tags for a in ("--platform", t)], *args[1:]], env=env())


def wheel_pythons(platform: str) -> list[str]:
    """The Pythons PLATFORM's wheels are for (on Linux also every installed real
    Blender's: Debian sid's moves)."""
    tags, pythons, _ = WHEEL_PLATFORMS[platform]
    if platform == "linux-x64":
        pythons = [*pythons, *(a.pyver for a in _app().apps())]
    return sorted(set(pythons), key=lambda v: tuple(map(int, v.split("."))))


def setup_wheels() -> None:
    """The extension's wheels in .cache/wheels/<platform> (downloaded once), and each
    real Blender's .blender/<suite>/site: pytest and the wheels for its Python."""
    targets = {p: wheel_pythons(p) for p in WHEEL_PLATFORMS}
    want = hashlib.sha256(f"{WHEELS} {targets} {WHEEL_PLATFORMS}".encode()).hexdigest()
    stamp = WHEEL_DIR / ".stamp"
    if not (stamp.exists() and stamp.read_text() == want):
        for platform, (tags, _, extra) in WHEEL_PLATFORMS.items():
            dest = WHEEL_DIR / platform
            shutil.rmtree(dest, ignore_errors=True)  # no stale versions next to new ones
            dest.mkdir(parents=True)
            for python in targets[platform]:
                log(f"pip download wheels for {platform}, Python {python}")
                _pip_for(python, tags, "download", "--no-deps", "-d", dest, *WHEELS, *extra)
        stamp.write_text(want)
    for app in _app().apps():
        _setup_site(app, want)


def _setup_site(app, wheels_stamp: str) -> None:
    site = app.site
    want_site = hashlib.sha256(f"{wheels_stamp} {BLENDER_TEST_PACKAGES} {BLENDER_TEST_NODEPS} "
                               f"{app.pyver}".encode()).hexdigest()
    if (site / ".stamp").exists() and (site / ".stamp").read_text() == want_site:
        return
    shutil.rmtree(site, ignore_errors=True)
    tags, _, extra = WHEEL_PLATFORMS["linux-x64"]
    log(f"pip install pytest, matplotlib and the extension's wheels into {site} "
        f"(Python {app.pyver})")
    _pip_for(app.pyver, tags, "install", "--target", site, *BLENDER_TEST_PACKAGES)
    _pip_for(app.pyver, tags, "install", "--target", site, "--no-deps", *BLENDER_TEST_NODEPS)
    _pip_for(app.pyver, tags, "install", "--target", site, "--no-deps", "--no-index",
             "--find-links", WHEEL_DIR / "linux-x64", *[w.split("=")[0] for w in WHEELS + extra])
    (site / ".stamp").write_text(want_site)


def task_extension(args) -> int:
    """extension [--no-wheels]: one zip per platform in dist/
    (voxel_worlds-<version>-<platform>.zip, that platform's wheels bundled), built and
    validated by the newest real Blender's own extension tool; --no-wheels: one zip
    without wheels."""
    setup()
    extra = ["--blender", _app().get().launcher]
    if "--no-wheels" not in args:
        for platform in WHEEL_PLATFORMS:
            extra += ["--wheels", WHEEL_DIR / platform, "--platform", platform]
    rest = [a for a in args if a != "--no-wheels"]
    r = subprocess.run([PY, ROOT / "tools" / "extension.py", *extra, *rest], cwd=ROOT,
                       env=env(), capture_output=True, text=True)
    sys.stderr.write(r.stderr)
    for line in r.stdout.split():
        z = Path(line)
        log(f"{z.relative_to(ROOT) if z.is_relative_to(ROOT) else z}: "
            f"{z.stat().st_size / 2**20:.1f} MiB")
    return r.returncode


def task_dev(args) -> int:
    dev = ROOT / ".venv-dev"
    if not (dev / "bin" / "python").exists():
        run([sys.executable, "-m", "venv", dev])
    run([dev / "bin" / "python", "-m", "pip", "install", "-q", "-r", ROOT / "requirements-dev.txt"])
    log(f"point your editor's interpreter or stub path at {dev}")
    return 0


TASKS = {"setup": lambda a: (setup(), 0)[1], "test": task_test, "demo": task_demo,
         "bench": task_bench, "extension": task_extension, "dev": task_dev,
         "blender": task_blender}


def main(argv) -> int:
    if not argv or argv[0] not in TASKS:
        print(__doc__)
        return 2
    try:
        return TASKS[argv[0]](argv[1:])
    except subprocess.CalledProcessError as e:
        log(f"failed: {' '.join(map(str, e.cmd))} (exit {e.returncode})")
        return e.returncode or 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
