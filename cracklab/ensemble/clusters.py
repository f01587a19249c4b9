"""Sweeps on a batch queue: a dask cluster whose workers are jobs of Slurm, PBS, SGE, LSF,
HTCondor, OAR or Moab (dask-jobqueue), for ``run(cluster=KIND)`` and ``cracklab sweep
--cluster KIND``.

The scheduler runs in the sweep's own process; each batch job starts one or more
one-thread worker processes that connect to it, build their members and write them
straight into the store (an object store URL, or a file system all nodes share). The
job's resources come, in this order, from the options given (``cluster_options``,
``--cluster-option KEY=VALUE``), from dask's configuration (``jobqueue.<kind>.*``:
~/.config/dask/jobqueue.yaml, or variables such as DASK_JOBQUEUE__SLURM__QUEUE), and
else from the sweep: one core and one worker per job, with the memory the largest member
needs (1.5 times its estimate and a worker process's own). See docs/guide/cluster.md."""
from __future__ import annotations

import contextlib
import inspect
import json
import math
import re
import shutil
import sys

from ..errors import InputError, MemoryBudgetError, SchedulerError

#: the batch systems: --cluster KIND -> dask_jobqueue's cluster class
KINDS = {"slurm": "SLURMCluster", "pbs": "PBSCluster", "sge": "SGECluster", "lsf": "LSFCluster",
         "htcondor": "HTCondorCluster", "oar": "OARCluster", "moab": "MoabCluster"}

#: what the cluster classes take that is not an option here: set by the sweep (or through
#: --workers), Python objects, dask-jobqueue's deprecated names (extra, env_extra, job_extra,
#: project), and the scheduler's host and dashboard (scheduler_options={"host": ...})
NOT_OPTIONS = ("n_workers", "job_cls", "loop", "asynchronous", "scheduler", "name", "config_name", "job_name",
               "scheduler_cls", "silence_logs", "security", "extra", "env_extra", "job_extra", "project", "host",
               "dashboard_address")

#: a worker runs one member at a time on one thread: no library starts threads of its own
ONE_THREAD = "export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 CRACKLAB_FFT_THREADS=1"


def check_kind(kind: str, field: str = "cluster") -> str:
    """``kind`` in lower case when it is one of ``KINDS``; InputError naming ``field`` otherwise."""
    if not isinstance(kind, str) or kind.lower() not in KINDS:
        raise InputError(field, f"unknown batch system {kind!r}; accepted: {', '.join(KINDS)}")
    return kind.lower()


def parse_value(text: str, key: str, field: str = "--cluster-option"):
    """A --cluster-option value: JSON for a list or table ([...], {...}), true/false/null,
    an integer or a number; any other text as it is (a queue name, 2GB, 01:00:00)."""
    t = text.strip()
    if t[:1] in "[{":
        try:
            return json.loads(t)
        except ValueError as exc:
            raise InputError(field, f"{key}={text}: a list or table must be JSON ({exc})") from None
    if t in ("true", "false", "null"):
        return {"true": True, "false": False, "null": None}[t]
    if re.fullmatch(r"[+-]?\d+", t):
        return int(t)
    if re.fullmatch(r"[+-]?(\d+\.\d*|\.\d+|\d+)([eE][+-]?\d+)?", t):
        return float(t)
    return text


def parse_options(pairs, field: str = "--cluster-option") -> dict:
    """{key: value} of KEY=VALUE texts (keys with - or _; see ``parse_value``)."""
    out = {}
    for pair in pairs or ():
        key, sep, value = str(pair).partition("=")
        key = key.strip().replace("-", "_")
        if not sep or not key:
            raise InputError(field, f"expected KEY=VALUE (e.g. queue=short, memory=4GB), got {pair!r}")
        out[key] = parse_value(value, key, field)
    return out


def jobqueue():
    """The dask_jobqueue module, imported with Python's Ctrl-C handler kept: dask_jobqueue
    (0.9) replaces it on import with one that calls sys.exit(), which ended a sweep on
    Ctrl-C with status 0, no message and the store's lock and the jobs left to the
    interpreter's exit."""
    import signal
    import threading

    if "dask_jobqueue" in sys.modules:
        return sys.modules["dask_jobqueue"]
    main = threading.current_thread() is threading.main_thread()
    handler = signal.getsignal(signal.SIGINT) if main else None
    try:
        import dask_jobqueue
    finally:
        if handler is not None:
            signal.signal(signal.SIGINT, handler)
    return dask_jobqueue


def cluster_class(kind: str):
    """dask_jobqueue's cluster class for ``kind``."""
    return getattr(jobqueue(), KINDS[check_kind(kind)])


def accepted_options(kind: str) -> list[str]:
    """The options a ``kind`` cluster takes for its jobs and its scheduler (sorted)."""
    cls = cluster_class(kind)
    from dask_jobqueue.core import Job, JobQueueCluster

    names = set()
    for f in (cls.job_cls.__init__, Job.__init__, JobQueueCluster.__init__):
        names |= {p.name for p in inspect.signature(f).parameters.values()
                  if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}
    return sorted(names - {"self", *NOT_OPTIONS})


def check_options(kind: str, options: dict, field: str = "cluster_options") -> dict:
    """``options`` with its keys checked against what a ``kind`` cluster takes; one
    InputError naming the key and the accepted ones otherwise."""
    if options is None:
        return {}
    if not isinstance(options, dict):
        raise InputError(field, f"must be a dict of options of the {kind} cluster, got {options!r}")
    accepted = accepted_options(kind)
    for key in options:
        if key not in accepted:
            from difflib import get_close_matches

            near = get_close_matches(str(key), accepted, n=1)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            raise InputError(field, f"{key!r} is not an option of a {kind} cluster{hint}; accepted: "
                                    f"{', '.join(accepted)}")
    return dict(options)


def _configured(kind: str, key: str):
    import dask

    return dask.config.get(f"jobqueue.{kind}.{key.replace('_', '-')}", None)


def job_options(kind: str, options: dict, member_bytes: int | None, field: str = "cluster_options") -> dict:
    """The options the cluster is built with: ``options``, then dask's configuration, then
    the sweep's defaults (one core and one worker process per core; memory for the largest
    member, ``member_bytes`` with a worker's own, times 1.5); refused (MemoryBudgetError)
    when a worker's share of the job's memory is below what the largest member needs."""
    from dask.utils import format_bytes, parse_bytes

    from ..solver.budget import PROCESS_BYTES

    opts = check_options(kind, options, field)
    get = lambda k: opts.get(k, _configured(kind, k))  # noqa: E731
    cores = get("cores")
    processes = get("processes")
    for key, value in (("cores", cores), ("processes", processes)):
        if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 1):
            raise InputError(field, f"{key}={value!r}: must be a whole number >= 1")
    if cores is None:
        cores = opts["cores"] = processes or 1
    if processes is None:
        opts["processes"] = processes = cores      # one-thread workers: a member runs on one thread
    need = None if member_bytes is None else member_bytes + PROCESS_BYTES
    memory = get("memory")
    if memory is None:
        per = int(1.5 * need) if need else 2 * 2**30
        opts["memory"] = memory = format_bytes(math.ceil(per / 2**28) * 2**28 * processes).replace(" ", "")
    try:
        total = parse_bytes(memory) if isinstance(memory, str) else int(memory)
    except (ValueError, TypeError):
        raise InputError(field, f"memory={memory!r}: not an amount of memory (e.g. 4GB, 16GiB)") from None
    if need and total / processes < need:
        raise MemoryBudgetError(field, f"memory={memory} gives each of the job's {processes} worker "
                                       f"process{'es' if processes > 1 else ''} {format_bytes(total / processes)}, but "
                                       f"the largest member needs {format_bytes(need)} with its worker; give more "
                                       f"memory, or fewer processes per job")
    prologue = get("job_script_prologue") or []
    if not isinstance(prologue, list) or not all(isinstance(line, str) for line in prologue):
        raise InputError(field, f"job_script_prologue={prologue!r}: must be a list of shell lines, e.g. "
                                f'["module load python", "source ~/venv/bin/activate"]')
    opts["job_script_prologue"] = [ONE_THREAD, *prologue]
    scheduler = dict(get("scheduler_options") or {})
    scheduler.setdefault("dashboard_address", ":0")         # a free port: print where it is
    opts["scheduler_options"] = scheduler
    return opts


@contextlib.contextmanager
def job_cluster(kind: str, options=None, *, workers: int, member_bytes: int | None = None,
                progress: bool = True, field: str = "cluster"):
    """A dask Client of a ``kind`` cluster whose batch jobs hold ``workers`` worker
    processes in all (see ``job_options``); the jobs are submitted before it is yielded
    (a refused submission is a SchedulerError naming the batch system's message) and
    cancelled when it closes."""
    kind = check_kind(kind, field)
    opts = job_options(kind, options or {}, member_bytes)
    cls = cluster_class(kind)
    submit = cls.job_cls.submit_command.split()[0]
    if shutil.which(submit) is None:
        raise SchedulerError(field, f"{submit} not found: --cluster {kind} submits its workers with {submit}; run "
                                    f"the sweep where the {kind} commands are (a login node), or start a dask "
                                    f"scheduler and workers yourself and give --scheduler")
    import logging

    from distributed import Client

    try:
        cluster = cls(**opts, silence_logs=logging.ERROR)
    except (ValueError, TypeError) as exc:
        raise InputError("cluster_options", f"the {kind} cluster refused the options "
                                            f"({str(exc).splitlines()[0]})") from None
    try:
        client = Client(cluster)
        jobs = math.ceil(workers / opts["processes"])
        # the jobs submitted here and now, as the cluster does for the workers it is made with
        # (cluster.scale would submit them in the background, where a refusal is only logged
        # and the sweep would wait for workers that never come)
        while len(cluster.worker_spec) < jobs:
            cluster.worker_spec.update(cluster.new_worker_spec())
        try:
            cluster.sync(cluster._correct_state)
        except RuntimeError as exc:
            from distributed.core import Status

            for job in cluster.workers.values():
                if getattr(job, "job_id", None) is None:    # never submitted: nothing to cancel
                    job.status = Status.failed
            text = str(exc)
            said = [ln for ln in text.split("stderr:", 1)[-1].strip().splitlines() if ln.strip()]
            raise SchedulerError(field, f"{submit} refused the worker jobs: {said[0] if said else text}; "
                                        f"check the options (queue, account, walltime, memory) against "
                                        f"{submit}'s manual and your site's limits") from None
        if progress:
            print(f"cracklab: {jobs} {kind} job{'s' if jobs != 1 else ''} submitted for {workers} worker"
                  f"{'s' if workers != 1 else ''} ({opts['processes']} per job, memory={opts['memory']} per job); "
                  f"dashboard {cluster.dashboard_link}", file=sys.stderr, flush=True)
        try:
            yield client
        finally:
            client.close()
    finally:
        cluster.close()
