"""A dask scheduler and worker processes started by hand (docs/guide/cluster.md, "workers
you start yourself"), for the sweeps of tests/ensemble/test_cluster_processes.py and
test_object_store_faults.py: `dask scheduler` on 127.0.0.1 and a free port, and `dask worker`
processes (each under its nanny, one thread), each in a directory of its own with its own
TMPDIR (nothing shared with the sweep or each other). The tests' folder is on the workers'
PYTHONPATH, so that ``client.run`` can call the functions of this module there.

``quick_lock`` (tests/quick_lock.py), given to a `cracklab sweep` process with
``--import quick_lock``, shortens its lock's heartbeat and orphan age."""
from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import time
from pathlib import Path

from s3_server import free_port

TESTS = Path(__file__).resolve().parent


def _start(args, cwd):
    cwd.mkdir(parents=True)
    path = os.pathsep.join(p for p in (str(TESTS), os.environ.get("PYTHONPATH", "")) if p)
    return subprocess.Popen([sys.executable, "-m", *args], cwd=cwd,
                            env={**os.environ, "TMPDIR": str(cwd), "PYTHONPATH": path},
                            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def _stop(procs, timeout=20.0):
    for p in reversed(procs):
        if p.poll() is None:
            p.terminate()
    deadline = time.monotonic() + timeout
    for p in reversed(procs):
        try:
            p.wait(timeout=max(0.1, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()


@contextlib.contextmanager
def scheduler_and_workers(where: Path, n: int = 2):
    """A scheduler and ``n`` workers under ``where`` (``where/scheduler``,
    ``where/worker1``, ...), up and connected; yields the scheduler's address. The
    processes are ended at the exit (those this started, by their pids)."""
    from distributed import Client

    address = f"tcp://127.0.0.1:{free_port()}"
    procs = [_start(["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1],
                     "--dashboard-address", ":0"], where / "scheduler")]
    try:
        for i in range(1, n + 1):
            procs.append(_start(["distributed.cli.dask_worker", address, "--nthreads", "1", "--local-directory", ".",
                                 "--name", f"w{i}"], where / f"worker{i}"))
        with Client(address, timeout=60) as client:
            client.wait_for_workers(n, timeout=120)
        yield address
    finally:
        _stop(procs)


def members_running(dask_worker) -> int:
    """How many tasks occupy a thread of this worker (dask's ``WorkerState.all_running_tasks``,
    cancelled ones included); called on a worker by ``client.run``, where only a sweep's
    members run: a task that dask has given up (its client gone) runs on in its thread
    until it returns."""
    return len(dask_worker.state.all_running_tasks)
