"""The one place that opens OpenCL: platform choice, queue, cached program builds.

pyopencl is imported lazily so the add-on registers where it is missing. The pip
"pocl-binary-distribution" platform vectorizes our kernels far better than Debian's
pocl ICD, and `create_some_context()` would pick whichever comes first, so the
platform is chosen explicitly: VOXEL_CL_PLATFORM (substring) if set, else a pocl
platform that is not the distro one, else the first with a device.

VOXEL_OPENCL=0 (or off, no, false) makes this module report no device, as on a Mac
or a Windows machine without an OpenCL driver: everything runs the NumPy path.

Warming up (`warm`): a first build of our programs takes seconds (pocl compiles each
kernel with LLVM, and again per work-group size at its first launch), which a
fresh install would spend before its first picture. `warm(job)` runs JOB (builds and
runs the kernels a caller will want) in a background thread; until it ends the
default backend (`pick(None)`) is NumPy, so the first results come from the NumPy
twins (bit-identical by design) while the kernels build, then OpenCL takes over;
a job that builds several kernel families hands each over once built (`ready`).

The interpreter's exit waits for those background threads' step under way and they
start no other (`background`, core/ending.py).
"""
from __future__ import annotations

import os
import threading
from functools import lru_cache

from . import resources

_lock = threading.Lock()


class NoOpenCL(RuntimeError):
    """No usable OpenCL device (pyopencl missing, no platform, no device)."""


def _platform_rank(p) -> int:
    want = os.environ.get("VOXEL_CL_PLATFORM")
    text = f"{p.name} {p.version}".lower()
    if want:
        return 0 if want.lower() in text else 9
    if "pocl" in text or "portable computing" in text:
        return 2 if "distro" in text and "reloc" not in text else 1
    return 3


def _bundled_pocl_for_host_loader(cl) -> None:
    """Linux distributions' Blender links its own OpenCL ICD loader (ocl-icd), and
    pyopencl's calls bind to that one, which never looks next to pyopencl for the pocl
    its wheel bundles (found only through PYOPENCL_HOME by the wheel's own loader):
    no platform at all. Name that pocl to the host's loader (OCL_ICD_VENDORS) before
    the first query; a process without a foreign loader is left alone. Linux only
    (ocl-icd, /proc, .so names): Windows and macOS have no pocl wheel, their loader
    finds the vendor's driver."""
    import sys
    if os.environ.get("OCL_ICD_VENDORS") or not sys.platform.startswith("linux"):
        return
    from pathlib import Path
    libs = Path(cl.__file__).parent / ".libs"
    pocl = sorted(libs.glob("libpocl*.so*"))
    try:
        maps = Path("/proc/self/maps").read_text()
    except OSError:
        return
    loaders = {line.split()[-1] for line in maps.splitlines() if "libOpenCL.so" in line}
    if not pocl or not loaders or all(p.startswith(str(libs)) for p in loaders):
        return
    import hashlib
    import tempfile
    key = hashlib.sha1(str(pocl[0]).encode()).hexdigest()[:12]
    vendors = Path(tempfile.gettempdir()) / f"voxel-icd-{os.getuid()}-{key}"
    vendors.mkdir(exist_ok=True)
    (vendors / "pocl.icd").write_text(f"{pocl[0]}\n")
    os.environ["OCL_ICD_VENDORS"] = str(vendors)


SWITCH = "VOXEL_OPENCL"


def switched_off() -> bool:
    """Whether VOXEL_OPENCL turns OpenCL off (0, off, no, false)."""
    return os.environ.get(SWITCH, "").strip().lower() in ("0", "off", "no", "false")


def context():
    """(context, queue, device) of the chosen platform; raises NoOpenCL."""
    if switched_off():  # read on every call: the switch holds after a first context
        raise NoOpenCL(f"OpenCL is switched off ({SWITCH}={os.environ[SWITCH]})")
    with _ctx_lock:  # one context, also when a warm-up thread asks at the same time
        return _context()


_ctx_lock = threading.Lock()


@lru_cache(maxsize=1)
def _context():
    try:
        import pyopencl as cl
    except ImportError as e:  # pragma: no cover - depends on the machine
        raise NoOpenCL(f"pyopencl is not installed ({e})") from None
    _bundled_pocl_for_host_loader(cl)
    try:
        platforms = sorted(cl.get_platforms(), key=_platform_rank)
    except cl.Error as e:
        raise NoOpenCL(f"no OpenCL platform ({e})") from None
    for p in platforms:
        try:
            devices = p.get_devices()
        except cl.Error:
            continue
        if devices:
            ctx = cl.Context(devices[:1])
            return ctx, cl.CommandQueue(ctx), devices[0]
    raise NoOpenCL("no OpenCL device found")


def available() -> bool:
    try:
        context()
        return True
    except NoOpenCL:
        return False


def on_cpu() -> bool:
    """Whether the OpenCL device is the CPU itself (pocl): there a NumPy twin that does
    less work can beat its kernel (the light's flood: light.full.backend)."""
    try:
        context()  # raises while switched off, whatever was cached
    except NoOpenCL:
        return False
    return _device_is_cpu()


@lru_cache(maxsize=1)
def _device_is_cpu() -> bool:
    """Asked once: light and meshing ask per solve and per launch (hot paths)."""
    import pyopencl as cl
    return bool(context()[2].type & cl.device_type.CPU)


BACKENDS = ("opencl", "numpy")  # every kernel's OpenCL twin and its NumPy reference


def usable() -> list[str]:
    """The backends this machine can run, the NumPy reference first (benches, tests)."""
    return ["numpy"] + (["opencl"] if available() else [])


def pick(backend: str | None = None, what: str = "") -> str:
    """The one backend choice of generation, light and meshing: None means OpenCL when
    a device is present and WHAT's kernels are not still warming up (`warming`), else
    NumPy; a name is checked (VoxelError for an unknown one, or for "opencl" without
    a device). `what` names the caller in the message."""
    from .core.errors import VoxelError
    if backend is None:
        return "opencl" if available() and not warming(what) else "numpy"
    if backend not in BACKENDS:
        raise VoxelError(f"unknown {what + ' ' if what else ''}backend {backend!r} "
                         f"(known: {', '.join(BACKENDS)})")
    if backend == "opencl" and not available():
        raise VoxelError("backend opencl asked for, but no OpenCL device is available")
    return backend


def describe() -> str:
    ctx, _, dev = context()
    return f"{dev.platform.name.strip()} / {dev.name.strip()}"


def why_not() -> str:
    """Why there is no OpenCL device ("" when there is one)."""
    try:
        context()
        return ""
    except NoOpenCL as e:
        return str(e)


@lru_cache(maxsize=None)
def program(name: str, options: tuple[str, ...] = ()):
    """Build gpu/<name> (with #includes resolved) once per process and options."""
    import pyopencl as cl
    from .core import trace
    ctx, _, _ = context()
    with _lock, trace.span("cl.program", name=name):
        return cl.Program(ctx, resources.kernel(name)).build(options=list(options))


@lru_cache(maxsize=16)
def build(source: str, options: tuple[str, ...] = (), alone: bool = False):
    """Build generated source (e.g. a compiled generator program) once per process.
    ALONE: without the lock that serialises builds (a background build nothing on
    the way to the first picture waits for, e.g. the far surface's: the near view's
    kernels must not queue behind its seconds; pocl builds programs concurrently)."""
    import pyopencl as cl
    from contextlib import nullcontext
    from .core import trace
    ctx, _, _ = context()
    with nullcontext() if alone else _lock, trace.span("cl.build", chars=len(source)):
        return cl.Program(ctx, source).build(options=list(options))


# ---- building in another process -----------------------------------------------------
def helper(module: str, fn: str, *args, nice: int = 0):
    """Start `<this package>.MODULE.FN(*ARGS)` (ARGS: JSON values) in a fresh Python
    process (at niceness NICE where the platform has one) and return its Popen, or
    None where none is worth starting (a platform other than pocl, whose on-disk
    kernel cache this relies on) or none can be (no Python interpreter as
    sys.executable, e.g. a Blender without one). pocl (3.0, LLVM 14) compiles one
    program or kernel work-group function at a time in a whole process (other
    cl.Contexts included), so a second core helps a cold build only from another
    process: what FN builds and launches lands in pocl's on-disk kernel cache
    (the same POCL_CACHE_DIR: the environment is inherited), and this process's own
    build and first launch of the same source and options then load it (meshing's:
    ~0.85 s of CPU down to ~0.03 s; world.build.warm). The caller waits for it or not;
    its failure costs nothing but the time (the build happens here as before)."""
    import json
    import subprocess
    import sys
    from pathlib import Path
    exe = sys.executable or ""
    if not Path(exe).name.lower().startswith("python") or not _is_pocl():
        return None
    here = Path(__file__).resolve().parent
    code = ("import importlib, json, os, sys; sys.path.insert(0, sys.argv[1]); "
            "hasattr(os, 'nice') and os.nice(int(sys.argv[5])); "
            "getattr(importlib.import_module(sys.argv[2]), sys.argv[3])(*json.loads(sys.argv[4]))")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    try:
        return subprocess.Popen([exe, "-c", code, str(here.parent), f"{here.name}.{module}", fn,
                                 json.dumps(args), str(int(nice))], env=env,
                                stdin=subprocess.DEVNULL,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                creationflags=getattr(subprocess, "CREATE_NO_WINDOW", 0))
    except OSError:
        return None


def _is_pocl() -> bool:
    try:
        p = context()[2].platform
    except NoOpenCL:
        return False
    text = f"{p.name} {p.version}".lower()
    return "pocl" in text or "portable computing" in text


# ---- background threads ---------------------------------------------------------------
def background(target, name: str) -> threading.Thread:
    """Start TARGET in a daemon thread that uses OpenCL on its own; the interpreter's
    exit waits for it (core/ending.py: it checks `ending.exiting()` between steps)."""
    from .core import ending
    t = threading.Thread(target=target, daemon=True, name=name)
    ending.wait_at_exit(t)
    t.start()
    return t


# ---- warming up in the background ---------------------------------------------------
_warm = {"thread": None, "took": None, "error": None, "ended_at": None,
         "later_took": None, "later_error": None, "ready": {}}


def warm(job, name: str = "voxel-opencl-warm", later=None) -> bool:
    """Run JOB() (which asks for backend "opencl" explicitly) in a daemon thread; while
    it runs, pick(None) answers NumPy. Then LATER() (if given) in the same thread, with
    OpenCL already the default: builds nothing waits for yet (e.g. the far surface's
    program), kept off the path to OpenCL taking over; its time and error in
    `warm_state` ("later_took", "later_error"). False (nothing started) without a device or
    while a warm-up runs (callers say what needs one: world.build.warm, once per
    generator). A failing JOB is kept (`warm_state`) and
    OpenCL is used afterwards all the same: its own errors then surface where they
    happen. pyopencl lets go of the GIL while pocl compiles, so the NumPy work on
    other threads goes on (2 cores: they share the CPU)."""
    import time
    from .core import ending
    if warming() or not available():
        return False

    def run():
        from .core import trace
        t0 = time.perf_counter()
        try:
            with trace.span("warm.job"):
                job()
        except Exception as e:  # noqa: BLE001 - reported by warm_state, not fatal
            _warm["error"] = f"{type(e).__name__}: {e}"
        finally:
            _warm["took"] = time.perf_counter() - t0
            _warm["ended_at"] = time.monotonic()
        if later is not None and not ending.exiting():
            t0 = time.perf_counter()
            _yield_cpu()
            try:
                with trace.span("warm.later"):
                    later()
            except Exception as e:  # noqa: BLE001 - likewise
                _warm["later_error"] = f"{type(e).__name__}: {e}"
            finally:
                _warm["later_took"] = time.perf_counter() - t0

    with _ctx_lock:
        if warming() or ending.exiting():
            return False
        _warm.update(thread=None, took=None, error=None, ended_at=None, later_took=None,
                     later_error=None, ready={})
        _warm["thread"] = background(run, name)
    return True


def _yield_cpu() -> None:
    """This thread at a lower priority (Linux: a thread's own nice value), so what
    warm's LATER builds takes the CPU that the stream's threads leave (blender/README:
    the first minute)."""
    import os
    import sys
    if not sys.platform.startswith("linux"):  # elsewhere the id would name a process
        return
    try:
        os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), 10)
    except (AttributeError, OSError):  # not Linux, or not allowed: run as it is
        pass


def ready(what: str) -> None:
    """From a warm-up's JOB: WHAT's kernels are built (e.g. "generation"), so
    pick(None, WHAT) answers OpenCL while the job builds the rest: each kernel family
    is used as soon as it exists (issue 28)."""
    import time
    _warm["ready"] = {**(_warm["ready"] or {}), what: time.monotonic()}


def warming(what: str = "") -> bool:
    """Whether a warm-up (`warm`) is running now (its LATER part does not count); with
    WHAT, whether WHAT still waits for it (`ready` not called for WHAT yet)."""
    t = _warm["thread"]
    return t is not None and t.is_alive() and _warm["ended_at"] is None and \
        not (what and what in _warm["ready"])


def warm_state() -> dict:
    """{"started", "running", "took" (seconds, None until done), "ended_at"
    (time.monotonic() then), "error", "later_took", "later_error" (warm's LATER),
    "ready" ({what: time.monotonic()} of `ready` calls)}."""
    t = _warm["thread"]
    return {"started": t is not None, "running": warming(), "took": _warm["took"],
            "ended_at": _warm["ended_at"], "error": _warm["error"],
            "later_took": _warm["later_took"], "later_error": _warm["later_error"],
            "ready": dict(_warm["ready"] or {})}
