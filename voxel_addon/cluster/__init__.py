"""Big work on a Dask cluster (issue 27): `--workers N` (an embedded local cluster) or
`--scheduler tcp://HOST:PORT` (an existing one). Workers compute, the command's own
process is the one writer. Dask is imported here only, lazily: the Blender extension
does not carry it and never reaches this module."""
from __future__ import annotations

import sys
from contextlib import contextmanager
from pathlib import Path

from ..core.errors import VoxelError

CONNECT_TIMEOUT = 10  # seconds to reach a scheduler and to see its first worker

# Dask settings of an embedded local cluster (`--workers`; the nanny hands them to its
# worker). Workers forked from a forkserver (see session). The rest are diagnostics
# for a dashboard that a local cluster does not show: event-loop ticks every 20 ms,
# a worker's statistical profiler sampling the task thread every 10 ms, memory and
# system monitors several times a second; together 80 ms of CPU a second with 2 idle
# workers, 10 ms without (the memory limits are still watched, twice a second).
LOCAL = {
    "distributed.worker.multiprocessing-method": "forkserver",
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.profile.enabled": False,
    "distributed.worker.memory.monitor-interval": "500ms",
    "distributed.admin.system-monitor.interval": "5s",
    # the scheduler queues tasks until a worker has a free thread (worker-saturation),
    # so there is little to steal between 1-thread workers; stealing still tracks
    # every task's transitions in this process (the writer's)
    "distributed.scheduler.work-stealing": False,
}


def knob(name: str, default: int) -> int:
    """A tuning value the environment may set (VOXEL_<NAME>): commit sizes, the
    connect timeout on a slow network; tests use small ones."""
    import os
    try:
        return max(1, int(os.environ.get(f"VOXEL_{name}", default)))
    except ValueError:
        return default


def add_arguments(parser) -> None:
    g = parser.add_mutually_exclusive_group()
    g.add_argument("--workers", type=int, metavar="N",
                   help="run on an embedded local Dask cluster of N worker processes")
    g.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help="run on an existing Dask cluster (dask scheduler / dask worker)")


def check_writable(args, path=None) -> None:
    """Before a cluster starts: a world file (or, for a new one, its folder) this
    process cannot write is refused now, with nothing started or changed."""
    import os
    if getattr(args, "workers", None) is None and not getattr(args, "scheduler", None):
        return  # one process: the command's own checks, as before
    path = Path(path or args.world)
    folder = path.parent if str(path.parent) else Path(".")
    if path.exists() and not os.access(path, os.W_OK):
        raise VoxelError(f"{path} is not writable")
    if folder.is_dir() and not os.access(folder, os.W_OK | os.X_OK):
        raise VoxelError(f"folder {folder} is not writable (the world file needs its "
                         "journal beside it)")


def version() -> str:
    """The code as the workers must share it: a digest of every module's source and
    of the NumPy and zstandard versions (bit-identical results need identical code,
    not just a version number, and the same compressor)."""
    import numpy
    from ..storage import codecs
    import hashlib
    h = hashlib.sha256()
    root = Path(__file__).resolve().parent.parent
    for p in sorted(root.rglob("*.py")):
        h.update(p.relative_to(root).as_posix().encode() + b"\0" + p.read_bytes() + b"\0")
    zstd = getattr(codecs, "_zstd", None)
    h.update(f"numpy {numpy.__version__} zstandard {getattr(zstd, '__version__', None)}".encode())
    return h.hexdigest()[:12]


# Sent by value (defined outside any importable module), so it runs on a worker that
# lacks voxel_addon and says so instead of failing to unpickle.
_PROBE = '''
def probe():
    try:
        from voxel_addon import cluster
    except ImportError as e:
        return "no voxel_addon (" + str(e) + ")"
    return cluster.version()
'''


def _probe():
    ns: dict = {}
    exec(_PROBE, ns)
    return ns["probe"]


def _say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


@contextmanager
def session(args, say=_say):
    """A Pool on the cluster ARGS names (args.workers / args.scheduler), closed on exit;
    None when neither was given: the caller runs in its own process as before."""
    workers, address = getattr(args, "workers", None), getattr(args, "scheduler", None)
    if workers is None and not address:
        yield None
        return
    if workers is not None and not 1 <= workers <= 512:
        raise VoxelError(f"--workers must be between 1 and 512 (got {workers})")
    import logging
    from contextlib import ExitStack
    cluster = client = None
    stack = ExitStack()
    try:
        if not address:
            _forkserver()   # first: it imports Dask while this process does the same
        from distributed import Client
        if address:
            client = _connect(Client, address)
        else:
            import dask
            from distributed import LocalCluster
            # Workers forked from one fresh server process that imported Dask and NumPy
            # once, not each spawned anew importing them again: the start and the close
            # take ~0.6 s less for 2 workers, and each worker ~0.5 s less CPU. The
            # server is clean (no threads, no open world file), unlike this process,
            # and workers a nanny restarts later come from it too.
            stack.enter_context(dask.config.set(LOCAL))
            try:
                with _children_ignore_sigint():
                    cluster = LocalCluster(n_workers=workers, threads_per_worker=1,
                                           processes=True, dashboard_address=":0",
                                           silence_logs=logging.CRITICAL)
            except Exception as e:  # noqa: BLE001 - no workers to run on: say why, once
                raise VoxelError(f"cannot start {workers} local Dask workers: {e}") from None
            client = Client(cluster, direct_to_workers=True)
        _check_versions(client, address or "the local cluster")
        if address:
            info = client.scheduler_info()
            board = (client.dashboard_link if "dashboard" in info.get("services", {})
                     else "none (the scheduler runs without one)")
            say(f"cluster {address}: {len(info['workers'])} workers, dashboard {board}")
        yield Pool(client, local=not address)
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
        stack.close()


def warm(args) -> None:
    """Call first in a command (after its argument checks, before its heavy imports):
    for `--workers`, the server the workers are forked from starts now, so its import
    of Dask and NumPy runs on another core while this process imports the rest (the
    session would start it anyway, later). Starts nothing else, changes no file."""
    if getattr(args, "workers", None) is not None and not getattr(args, "scheduler", None) \
            and 1 <= args.workers <= 512:
        _forkserver()


def _forkserver() -> None:
    """Start the server the local cluster's workers are forked from now, before this
    process imports Dask (~0.3 s): its own import of Dask and NumPy runs meanwhile on
    another core, not after ours (the start of a `--workers` command ~0.3 s shorter
    on a quiet machine). The modules are those Dask preloads (distributed.utils.
    get_mp_context, whose later call finds the server running); it ignores SIGINT as
    the workers do."""
    import importlib.util
    import multiprocessing
    from multiprocessing import forkserver
    pre = ["distributed", "dask", "msgpack", "cloudpickle", "tornado", "toolz", "numpy"]
    pre += [m for m in ("lz4",) if importlib.util.find_spec(m) is not None]
    multiprocessing.get_context("forkserver").set_forkserver_preload(pre)
    with _children_ignore_sigint():
        forkserver.ensure_running()


@contextmanager
def _children_ignore_sigint():
    """Worker processes started meanwhile ignore SIGINT: Ctrl-C on a terminal reaches
    the whole process group, and the command, not each worker, stops the cluster
    (otherwise every worker prints a traceback)."""
    import signal
    import threading
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def _connect(Client, address: str):
    import asyncio
    import logging
    if not address.startswith("tcp://") or ":" not in address[6:]:
        raise VoxelError(f"--scheduler wants tcp://HOST:PORT (got {address!r})")
    # distributed logs every failed connection attempt; the one-line error says it all
    logging.getLogger("distributed").setLevel(logging.CRITICAL)
    # Handshake once by hand first: a Client that fails to start lingers and logs for
    # 20 s more while it is collected, and a port that is no scheduler breaks it oddly.
    try:
        wait = knob("CONNECT_TIMEOUT", CONNECT_TIMEOUT)
        asyncio.run(asyncio.wait_for(_reach(address, wait), wait + 2))
        client = Client(address, timeout=f"{wait}s", set_as_default=False)
    except Exception as e:  # noqa: BLE001 - whatever answered, it is not a scheduler we can use
        msg = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise VoxelError(f"cannot reach a Dask scheduler at {address}: {msg}") from None
    try:
        client.wait_for_workers(1, timeout=wait)
    except (TimeoutError, OSError):
        client.close()
        raise VoxelError(f"the Dask scheduler at {address} has no workers "
                         f"(start some with `dask worker {address}`)") from None
    return client


async def _reach(address: str, wait: int) -> None:
    from distributed.comm import connect
    comm = await connect(address, timeout=wait)
    await comm.close()


def _check_versions(client, where: str) -> None:
    mine = version()
    try:
        theirs = client.run(_probe(), on_error="return")
    except Exception as e:  # noqa: BLE001 - any failure here means the workers cannot run us
        client.close()
        raise VoxelError(f"cannot ask the workers of {where} for their version: {e}") from None
    bad = {w: v for w, v in theirs.items() if v != mine}
    if bad:
        client.close()
        w, v = sorted(bad.items())[0]
        v = v if isinstance(v, str) else f"{type(v).__name__}: {v}"
        what = v if v.startswith("no voxel_addon") else \
            f"other code (voxel_addon sources, NumPy or zstandard: {v}, here {mine})"
        raise VoxelError(f"{len(bad)} of {len(theirs)} workers of {where} cannot run this "
                         f"command: worker {w} has {what} (install the same voxel_addon or "
                         "put its checkout on the worker's PYTHONPATH)")


def task_size(n: int, workers: int, most: int = 32) -> int:
    """Items per task for N items: about 8 tasks per worker (a killed worker's share
    is small and the last tasks balance), never more than MOST items (a worker's
    results arrive in steps), never under 1. Bigger tasks cost the scheduler and
    the writer's process less per item (see README: scale)."""
    return max(1, min(most, n // (8 * max(1, workers))))


def tail(left: int, step: int, workers: int) -> int:
    """Items in the next task when LEFT items are left: STEP, but a quarter of it over
    the last 2 tasks per worker, so the workers finish together (the last big task
    would leave the others idle for up to its whole length; a task costs the writer's
    process ~4 ms, a few more of them are cheap)."""
    return step if left > 2 * max(1, workers) * step else max(1, step // 4)


class Pool:
    """Tasks on a Dask client; results come back to the caller (the one writer)."""

    def __init__(self, client, local=False):
        self.client = client
        self.local = local  # workers on this machine (--workers): they see its files

    @property
    def size(self) -> int:
        """Worker threads (each worker runs one task at a time here). A round trip to
        the scheduler (~1.5 ms of this process's CPU): ask once per job, not per task."""
        return max(1, sum(w.get("nthreads", 1)
                          for w in self.client.scheduler_info()["workers"].values()))

    def map(self, fn, items, *, shared=None, progress=None, window=None):
        """Run fn(item, shared) on the workers for each item (fn: a module-level function
        importable from voxel_addon on the workers); `shared`: a dict broadcast once to
        every worker; yields (item, result) as tasks complete. ITEMS may be a lazy
        iterable (read as tasks go out; progress then needs len). At most WINDOW tasks are
        in flight (default 4 per worker thread), so results never pile up faster than the
        caller consumes them. A worker killed mid-job costs only its tasks (Dask re-runs
        them elsewhere); leaving the loop early (an error, Ctrl-C) cancels the rest."""
        from distributed import as_completed
        total = len(items) if hasattr(items, "__len__") else None
        if progress and total is not None:
            progress(0, total)
        c = self.client
        share = c.scatter([shared], broadcast=True, hash=False)[0] if shared is not None else None
        window = window or 4 * self.size
        todo = iter(enumerate(items))
        of = {}  # future -> item
        # keys unique across processes: id() repeats from one run of a command to the
        # next, and a scheduler that still knows a key cancels or answers the new task
        # as the old one ("already forgotten", or another command's result)
        import uuid   # here: uuid imports platform (a start's few ms)
        tag = uuid.uuid4().hex
        ac = as_completed(loop=c.loop)
        done = 0

        def submit(n):
            for _ in range(n):
                nxt = next(todo, None)
                if nxt is None:
                    return
                i, item = nxt
                f = c.submit(_call, fn, _Item(item), share, pure=False,
                             key=f"{fn.__name__}-{tag}-{i}")
                of[f] = item
                ac.add(f)

        try:
            submit(window)
            for batch in ac.batches():
                results = _gather(c, batch)
                for f, r in zip(batch, results):
                    item = of.pop(f)
                    f.release()
                    done += 1
                    yield item, r
                if progress and total is not None:
                    progress(done, total)
                submit(len(batch))
        finally:
            if of:
                c.cancel(list(of))
            if share is not None:
                share.release()


class _Item:
    """A task's item, opaque to Dask: submit walks a task's arguments (each tuple,
    list and dict, looking for futures), thousands of nodes for an import's task."""
    __slots__ = ("item",)

    def __init__(self, item):
        self.item = item

    def __reduce__(self):
        return _Item, (self.item,)


_tuned = False


def _call(fn, item, shared):
    """A task on a worker: fn(item, shared), the process tuned first."""
    global _tuned
    if not _tuned:
        _tuned = True
        _malloc()
    return fn(item.item if isinstance(item, _Item) else item, shared)


def _malloc() -> None:
    """Dask starts workers with MALLOC_TRIM_THRESHOLD_=65536, which also fixes glibc's
    mmap threshold at 128 KiB: every chunk-sized NumPy temporary is then mapped and
    unmapped again, and generation costs twice the CPU (measured: 1.9 s against
    1.07 s for 81 chunks). Large thresholds bring it back (0.77 s)."""
    import ctypes
    import sys
    if not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(-3, 1 << 25)  # M_MMAP_THRESHOLD: 32 MiB
        libc.mallopt(-1, 1 << 27)  # M_TRIM_THRESHOLD: 128 MiB
    except (OSError, AttributeError):
        pass  # not glibc: nothing to undo


def scratch() -> str:
    """A folder for a task's temporary files: on a worker its own local directory (Dask
    removes it with the worker, or, for a killed one, when the next worker starts),
    elsewhere the system's."""
    try:
        from distributed import get_worker
        return get_worker().local_directory
    except (ImportError, ValueError):
        import tempfile
        return tempfile.gettempdir()


class Serial:
    """Pool.map in this process, one item after another (the commands' one-process
    path where it shares the cluster's code: the same tasks, the same results)."""

    size = 1

    def map(self, fn, items, *, shared=None, progress=None, window=None):
        total = len(items) if hasattr(items, "__len__") else None
        for done, item in enumerate(items, 1):
            yield item, fn(item, shared)
            if progress and total is not None:
                progress(done, total)


def _gather(client, futures):
    from distributed import KilledWorker
    try:
        return client.gather(futures)
    except KilledWorker as e:
        raise VoxelError(f"a task killed several workers in a row ({e}); giving up") from None
