"""A real Dask cluster on 127.0.0.1: `dask scheduler` and two `dask worker` processes
(each one thread, under a nanny that restarts a killed worker), this checkout on
their PYTHONPATH."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DASK = Path(sys.executable).with_name("dask")


class Cluster:
    def __init__(self, address, procs):
        self.address, self.procs = address, procs

    def client(self):
        from distributed import Client
        return Client(self.address, timeout="10s", set_as_default=False)

    def worker(self, name, tmp, pythonpath=True):
        """One more worker, its process for the test to stop; without `pythonpath` it
        cannot import voxel_addon (started in `tmp`, not in this checkout)."""
        env = dict(os.environ)
        env.pop("PYTHONPATH", None)
        if pythonpath:
            env["PYTHONPATH"] = str(ROOT)
        return subprocess.Popen([DASK, "worker", self.address, "--nthreads", "1",
                                 "--no-dashboard", "--host", "127.0.0.1", "--name", name,
                                 "--local-directory", tmp / name], env=env, cwd=tmp,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True)

    def wait_workers(self, n=2, timeout=60.0):
        """Until the scheduler has exactly N workers (a killed one back, an extra gone)."""
        with self.client() as c:
            end = time.monotonic() + timeout
            while len(c.scheduler_info()["workers"]) != n:
                assert time.monotonic() < end, f"the cluster did not reach {n} workers"
                time.sleep(0.1)


@pytest.fixture(scope="session")
def cluster(tmp_path_factory):
    d = tmp_path_factory.mktemp("dask")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    sched_file = d / "scheduler.json"
    common = dict(env=env, cwd=d, stdout=subprocess.DEVNULL, stderr=open(d / "log", "w"),
                  start_new_session=True)
    procs = [subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port", "0",
                               "--no-dashboard", "--scheduler-file", sched_file], **common)]
    try:
        t0 = time.monotonic()
        while not sched_file.is_file() or not sched_file.read_text().strip():
            assert time.monotonic() - t0 < 60 and procs[0].poll() is None, \
                (d / "log").read_text()
            time.sleep(0.1)
        address = json.loads(sched_file.read_text())["address"]
        for i in range(2):
            procs.append(subprocess.Popen(
                [DASK, "worker", address, "--nthreads", "1", "--no-dashboard",
                 "--host", "127.0.0.1", "--name", f"w{i}", "--local-directory", d / f"w{i}"],
                **common))
        c = Cluster(address, procs)
        c.wait_workers(2)
        yield c
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
