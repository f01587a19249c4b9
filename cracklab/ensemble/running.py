"""Running a sweep on dask.distributed: the client (given, a scheduler's, or an embedded
LocalCluster), ``run``, and the worker task that builds, runs and writes one member."""
from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import socket
import sys
import time
from pathlib import Path

from ..errors import InputError, SchedulerError, StoreError
from ..scenes.registry import builder_name, resolve_builder
from .identity import canonical, canonical_json, scene_digest
from .planning import as_sweep, build_scene, check_paths, check_section_keys, plan, split_params
from .spec import Builder, Member, Sweep, SweepResult
from .store import (MEMBERS, SWAP_TAG, check_store, damage_of, error_line, init_store, is_complete,
                    member_attrs, member_path, open_group, record_failure, store_str, swap_in,
                    traceback_summary)
from .members_table import write_member_table
from ..output.stores import SweepLockLost, guarded, is_url, store_for


def cores() -> int:
    """The cores this process may run on (the default number of local workers)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


#: seconds to reach a dask scheduler before the sweep gives up (nothing is written by then)
CONNECT_TIMEOUT = 5.0


def connect(address, *, where="scheduler", timeout=CONNECT_TIMEOUT):
    """A Client of the dask scheduler at ``address``; a SchedulerError within ``timeout``
    seconds when it cannot be reached (``where``: the option or variable that gave it)."""
    from distributed import Client

    from .store import error_line

    try:
        return Client(address, timeout=timeout)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise SchedulerError(where, f"cannot connect to the dask scheduler at {address!r} within {timeout:g} s "
                                    f"({error_line(exc)}); check the address (e.g. tcp://HOST:8786) and that the "
                                    f"scheduler runs, or leave it out to use a local cluster") from None


@contextlib.contextmanager
def _children_ignore_sigint():
    """Start processes that ignore Ctrl-C (SIGINT): the workers of an embedded cluster,
    whose interruption the client handles (no worker prints a traceback)."""
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


@contextlib.contextmanager
def dask_client(client=None, scheduler=None, workers=None, n_tasks=None, memory_limit="auto"):
    """The client to use: ``client``; else one connected to ``scheduler`` (or env
    DASK_SCHEDULER_ADDRESS); else an embedded LocalCluster of one-thread worker
    processes, one per core (at most one per task), that ignore Ctrl-C (the client
    handles it) and log only what is critical (a member's failure reaches the store through
    its future; a worker losing the scheduler as the cluster closes on Ctrl-C printed a
    traceback); ``memory_limit``: of each worker (dask's)."""
    if client is not None:
        yield client
        return
    import logging

    from distributed import Client, LocalCluster

    address = scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS")
    if address:
        c = connect(address, where="scheduler" if scheduler else "DASK_SCHEDULER_ADDRESS")
        try:
            yield c
        finally:
            c.close()
        return
    n = workers or cores()
    if n_tasks:
        n = max(1, min(n, n_tasks))
    env = {"CRACKLAB_FFT_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
           "OPENBLAS_NUM_THREADS": "1"}
    options = {} if memory_limit == "auto" else {"memory_limit": memory_limit}
    with _children_ignore_sigint():
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                               silence_logs=logging.CRITICAL, env=env, **options)
    c = Client(cluster)
    try:
        yield c
    finally:
        c.close()
        cluster.close()


def _where(key, sweep) -> str:
    """The study table a parameter comes from (for messages): sweep, base or members."""
    if sweep is not None and key in sweep.product:
        return "sweep"
    if sweep is not None and key in (sweep.base or {}):
        return "base"
    return "members"


def preflight(base_scene, members, *, fft_threads=1, sweep=None, outputs=None) -> dict:
    """Check every member before any work starts, in this process: its scene paths name
    keys of the scene's sections, with values of the right type (an unknown key, with the
    nearest one suggested, or text for a number raises InputError naming the key). The
    members of a base Scene or of cracklab's own builders (``scenes.BUILDERS``) are built
    here, and checked against their scene; other builders run on the workers only (they
    may be slow or need the worker), their law keys checked against every law's.
    Returns {member id: MemoryEstimate, or None when not built here or when the build
    fails on a bad value: such a member fails on its worker and is recorded}; ``outputs``,
    a dict, receives {member id: OutputEstimate} of the members built here."""
    from ..model.scene import Scene
    from ..solver.budget import run_memory
    from ..scenes.registry import own_builders

    own = own_builders()
    out, built = {}, {}
    for m in members:
        params = dict(m.params)
        name = params.pop("builder", None)
        if isinstance(base_scene, Scene):
            key, paths = "base", params
            make = lambda: base_scene  # noqa: E731
        else:
            func = resolve_builder(name)
            args, paths = split_params(func, params)
            if own.get(name) is not func:
                for k, v in paths.items():
                    check_section_keys(k, v, where=_where(k, sweep))
                out[m.id] = None
                continue
            key = canonical_json({"builder": name, **canonical(args)})
            make = lambda: func(**args)  # noqa: E731
        if key not in built:
            try:
                built[key] = make()
            except InputError:
                built[key] = None
        scene = built[key]
        if not isinstance(scene, Scene):
            for k, v in paths.items():
                check_section_keys(k, v, where=_where(k, sweep))
            out[m.id] = None
            continue
        for k in paths:
            check_paths(scene, {k: paths[k]}, where=_where(k, sweep))
        try:
            member = build_scene(scene, paths, fft_threads=fft_threads)
        except InputError:
            out[m.id] = None
            continue
        out[m.id] = run_memory(member)
        if outputs is not None:
            from ..output.disk import output_size

            outputs[m.id] = output_size(member)
    return out


def _workers_for(estimates, todo, workers, local):
    """The number of workers of an embedded cluster that fit in memory with the largest
    members (``workers`` given: refused when they do not fit); (n, dask memory limit)."""
    from ..solver.budget import PROCESS_BYTES, check_memory

    known = sorted((e for m in todo if (e := estimates.get(m.id)) is not None), key=lambda e: -e.total)
    if not known:
        return None, "auto"
    largest = known[0]
    hint = "pass --workers with fewer workers, make the grids coarser or the runs shorter, or --no-memory-check"
    if not local:
        check_memory(largest, what="the largest member", hint=hint)
        return None, "auto"
    n = max(1, min(workers or cores(), len(todo)))
    if workers is None:
        from ..solver.budget import available_memory

        avail, _ = available_memory()
        while n > 1 and n * (largest.total + PROCESS_BYTES) > avail:
            n -= 1
    check_memory(largest, processes=n, what=f"the sweep on {n} worker process{'es' if n > 1 else ''}", hint=hint)
    limit = int(1.5 * (largest.total + PROCESS_BYTES))
    total = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 0
    if total and limit <= total // n:
        return n, "auto"                   # dask's own limit (memory / workers) leaves room enough
    return n, limit


def run(base_scene, sweep, store, *, client=None, resume=True, scheduler=None, workers=None,
        progress=None, fft_threads=1, study_spec=None, overwrite=False, check_memory=True,
        check_disk=True, cluster=None, cluster_options=None) -> SweepResult:
    """Run every member of ``sweep`` over ``base_scene`` into the Zarr v3 ``store``.

    ``base_scene``: a Scene (parameters are scene paths), a ``Builder``, or a builder
    name. ``sweep``: a ``Sweep``, a dict of product axes, or a list of member dicts.
    With ``resume`` complete members are skipped; incomplete and failed ones are run
    again. Tasks go to ``client``, else to the scheduler at ``scheduler`` (or env
    DASK_SCHEDULER_ADDRESS), else to an embedded LocalCluster with ``workers`` one-thread
    processes (default: one per core); ``scheduler="synchronous"`` runs the members one
    after the other in this process (debugging, tiny sweeps). ``cluster``, a batch system
    (slurm, pbs, sge, lsf, htcondor, oar, moab): the workers are batch jobs submitted for
    this sweep, ``workers`` worker processes in all (default: one per member to run), with
    ``cluster_options`` (e.g. {"queue": "short", "walltime": "02:00:00"}) over dask's
    configuration (cracklab.ensemble.clusters; the store must be one the nodes reach: an
    object store URL, or a shared file system). A failing member does not
    stop the others: see ``SweepResult.failed`` (and the member's attrs error and
    traceback). ``progress``: a bar over members (default: when stderr is a terminal).
    ``fft_threads``: numerics.fft_threads of every member that does not set it (None: as
    built). Holds the store's sweep lock while it runs: a second sweep into the same
    store at the same time raises ``StoreLocked`` (see ``store_lock``).

    Before anything is written or any worker starts, every member is checked
    (``preflight``: scene paths and parameter types), the scheduler is reached (a
    ``SchedulerError`` within ``CONNECT_TIMEOUT`` seconds) and, with ``check_memory``,
    the members' memory is set against the memory available (``MemoryBudgetError``; an
    embedded cluster gets no more workers than fit). A store holding the ensemble of
    another study (another name or base) is refused unless ``overwrite``, which deletes
    its members first."""
    t0 = time.perf_counter()
    sweep = as_sweep(sweep)
    members = plan(base_scene, sweep)
    store = store_str(store)
    spec = study_spec or _spec_of(base_scene, sweep)
    check_store(store)                  # before the lock: a wrong path is left untouched
    replace = _check_same_study(store, spec, overwrite)
    outputs = {}
    estimates = preflight(base_scene, members, fft_threads=fft_threads, sweep=sweep, outputs=outputs)
    todo = [m for m in members if replace or not resume or not is_complete(store, m.id)]
    if check_disk and todo and not is_url(store):
        _check_sweep_disk(store, [outputs[m.id] for m in todo if m.id in outputs], len(todo))
    if cluster is not None:
        from .clusters import check_kind, check_options

        kind = check_kind(cluster)
        if client is not None or scheduler is not None:
            other = "client" if client is not None else "scheduler"
            raise InputError("cluster", f"give one of cluster ({kind}) and {other}, not both: the cluster's own "
                                        f"scheduler runs in this process")
        cluster_options = check_options(kind, cluster_options)
    synchronous = client is None and scheduler == "synchronous"
    address = None if client is not None or synchronous or cluster is not None else \
        (scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS"))
    memory_limit = "auto"
    if check_memory and todo:
        if synchronous:
            known = [e for m in todo if (e := estimates.get(m.id)) is not None]
            if known:
                from ..solver.budget import check_memory as fits

                fits(max(known, key=lambda e: e.total), what="the largest member",
                     hint="make the grids coarser or the runs shorter, or --no-memory-check")
        elif client is None and not address and cluster is None:
            n, memory_limit = _workers_for(estimates, todo, workers, local=True)
            if n is not None and workers is None and n < min(cores(), len(todo)):
                workers = n
                if progress is not False:
                    print(f"cracklab: {n} worker process{'es' if n > 1 else ''} (as many as the memory holds "
                          f"with the largest member)", file=sys.stderr, flush=True)
    with contextlib.ExitStack() as stack:
        if address:                         # reached before the store is touched
            client = stack.enter_context(contextlib.closing(
                connect(address, where="scheduler" if scheduler else "DASK_SCHEDULER_ADDRESS")))
            if check_memory and todo:
                _check_remote_memory(client, estimates, todo)
        elif cluster is not None and todo:  # the jobs submitted before the store is touched
            from .clusters import job_cluster

            known = [e.total for m in todo if (e := estimates.get(m.id)) is not None]
            n = max(1, min(workers or len(todo), len(todo)))
            client = stack.enter_context(job_cluster(cluster, cluster_options, workers=n,
                                                     member_bytes=max(known) if known and check_memory else None,
                                                     progress=progress is not False))
        where = store_for(store)
        lock = where.lock()             # the sweep lock (ensemble.lock.store_lock)
        with lock:
            return _run_locked(base_scene, sweep, members, store, spec, t0, client=client, resume=resume,
                               scheduler=scheduler, workers=workers, progress=progress,
                               fft_threads=fft_threads, replace=replace, memory_limit=memory_limit,
                               address=address, check_disk=check_disk,
                               batch=f"{kind} jobs" if cluster is not None else None, lock=lock,
                               guard=where.write_guard(lock))


def sweep_output(outputs):
    """The OutputEstimate of members together (``outputs``: theirs, at least one)."""
    from ..output.disk import OutputEstimate

    return OutputEstimate(snapshots=sum(o.snapshots for o in outputs), fields=max(o.fields for o in outputs),
                          raw=sum(o.raw for o in outputs), bound=sum(o.bound for o in outputs))


def _check_sweep_disk(store, outputs, ntodo):
    """Refuse a sweep whose members to run (those built here) write more than the store's
    file system has free (cracklab.output.disk)."""
    if not outputs:
        return
    from ..output.disk import check_disk

    total = sweep_output(outputs)
    what = f"the sweep's {len(outputs)} member{'s' if len(outputs) != 1 else ''} to run" + \
        (f" (of {ntodo}; the others are built on the workers)" if len(outputs) < ntodo else "")
    check_disk(total, store, what=what, reuse=False,
               hint="record fewer fields, less often or on a region, or write to a larger disk; or sweep anyway "
                    "with check_disk=False (cracklab sweep --no-disk-check)")


def _identity(spec: dict) -> tuple:
    """What makes two sweeps the same study: its name and its builder or base scene (the
    base arguments and the sweep axes may change: members of both are kept)."""
    study = spec.get("study") if isinstance(spec.get("study"), dict) else None
    if study is not None:
        return spec.get("name"), study.get("builder"), study.get("scene")
    return spec.get("name"), json.dumps(spec.get("base"), sort_keys=True)


def _check_same_study(store: str, spec: dict, overwrite: bool) -> bool:
    """True when ``store`` holds the ensemble of another study and ``overwrite`` lets it be
    replaced; InputError when it does and ``overwrite`` is not given."""
    from .store import open_group as group

    try:
        attrs = dict(group(store, "r").attrs)
    except Exception:  # noqa: BLE001 - no store yet
        return False
    if "cracklab_ensemble" not in attrs:
        return False
    try:
        old = json.loads(attrs.get("study", "{}"))
    except ValueError:
        old = {}
    if _identity(old) == _identity(spec):
        return False
    if not overwrite:
        name = old.get("name", "?")
        raise InputError("store", f"{store} holds the ensemble of another study ({name!r}: "
                                  f"{_identity(old)[1] or 'a base scene'}); refusing to mix or replace it: choose "
                                  f"another output path, or --overwrite (ensemble.run(overwrite=True)) to replace it")
    if is_url(store):
        raise InputError("store", f"{store}: --overwrite replaces local stores only; delete it first")
    return True


def _check_remote_memory(client, estimates, todo):
    """Refuse members larger than every worker's dask memory limit (when the workers have one)."""
    from ..errors import MemoryBudgetError
    from ..solver.budget import PROCESS_BYTES, fmt_bytes

    try:
        limits = [w.get("memory_limit") or 0 for w in client.scheduler_info().get("workers", {}).values()]
    except Exception:  # noqa: BLE001 - no information: the workers check their own runs
        return
    known = [e for m in todo if (e := estimates.get(m.id)) is not None]
    if not limits or not known or min(limits) == 0:
        return
    largest = max(known, key=lambda e: e.total)
    if largest.total + PROCESS_BYTES > max(limits):
        raise MemoryBudgetError("memory", f"the largest member needs {largest.describe()} (and its worker about "
                                          f"{fmt_bytes(PROCESS_BYTES)} more), but the scheduler's workers have at "
                                          f"most {fmt_bytes(max(limits))} each (dask memory_limit); refused before "
                                          f"any member runs")


def _clear(store: str):
    """Delete the members of an ensemble store and its list of them (``overwrite``)."""
    import shutil

    shutil.rmtree(Path(store) / MEMBERS, ignore_errors=True)
    from .store import open_group as group

    group(store, "a").update_attributes({"members": []})


def _lost(lock) -> bool:
    """Whether the sweep holding ``lock`` lost it (taken over by another sweep)."""
    return bool(getattr(lock, "lost", False))


def _stop_lost(store, lock):
    """The SweepLockLost of a sweep whose lock was taken over: it stops, writing nothing more."""
    raise SweepLockLost(store, f"the sweep lock {getattr(lock, 'url', '')} was taken over by another sweep while this "
                               f"one ran (its heartbeat could not be written in time); this sweep stopped and its "
                               f"members stop before their next write: when the other sweep ends, cracklab verify "
                               f"{store}, and rerun this sweep to complete it")


def _run_locked(base_scene, sweep, members, store, spec, t0, *, client, resume, scheduler, workers,
                progress, fft_threads, replace=False, memory_limit="auto", address=None,
                check_disk=True, batch=None, lock=None, guard=None) -> SweepResult:
    from ..model.scene import Scene

    if replace:
        _clear(store)
    init_store(store, spec, members, axes=list(sweep.product))
    todo, damaged = [], {}
    for m in members:
        if resume and is_complete(store, m.id):
            problem = damage_of(store, m)
            if problem is None:
                continue                    # complete and sound: skipped
            damaged[m.id] = problem         # marked incomplete: recomputed below
        todo.append(m)
    result = SweepResult(store, members, ran=[m.id for m in todo],
                         skipped=[m.id for m in members if m not in todo], damaged=damaged)
    if damaged and progress is not False:
        for mid, problem in damaged.items():
            print(f"cracklab: member {mid} is damaged ({problem}); it is run again", file=sys.stderr, flush=True)
    if progress is None:
        progress = sys.stderr.isatty()
    base = base_scene if isinstance(base_scene, Scene) else None
    # the builders were resolved by plan (only registered ones); each task carries its own
    funcs = {}
    for m in todo:
        name = m.params.get("builder")
        if name is not None and name not in funcs:
            funcs[name] = resolve_builder(name)

    def own(m):
        name = m.params.get("builder")
        return {name: funcs[name]} if name is not None else None

    if todo and client is None and scheduler == "synchronous":
        from tqdm import tqdm

        for m in tqdm(todo, desc="members", unit="member", disable=not progress, file=sys.stderr):
            if _lost(lock):
                _stop_lost(store, lock)
            r = _run_member(store, m, base, fft_threads, own(m), check_disk=check_disk, guard=guard)
            if r["status"] == "lost":
                _stop_lost(store, lock)
            if r["status"] != "complete":
                result.failed[m.id] = r.get("error", "failed")
    elif todo:
        from distributed import as_completed
        from tqdm import tqdm

        if progress and (client is None or address or batch):
            n = max(1, min(workers or cores(), len(todo)))
            print(f"cracklab: {len(todo)} member{'s' if len(todo) != 1 else ''} to run; " +
                  (f"on {batch}" if batch else f"on the scheduler at {address}" if address
                   else "on the given client" if client is not None
                   else f"starting a local cluster of {n} worker process{'es' if n > 1 else ''}"),
                  file=sys.stderr, flush=True)
        with dask_client(client, scheduler, workers, len(todo), memory_limit=memory_limit) as c:
            base_arg = c.scatter(base, broadcast=True) if base is not None else None
            futures = {c.submit(_run_member, store, m, base_arg, fft_threads, own(m), check_disk=check_disk,
                                guard=guard, pure=False,
                                key=f"cracklab-member-{m.id}-{os.urandom(3).hex()}"): m for m in todo}
            bar = tqdm(total=len(todo), desc="members", unit="member", disable=not progress,
                       file=sys.stderr, dynamic_ncols=True)
            if lock is not None and hasattr(lock, "on_lost"):       # lost: no member left to wait for
                lock.on_lost.append(lambda: [f.cancel() for f in futures])
            try:
                for fut in as_completed(futures):
                    m = futures[fut]
                    if _lost(lock):
                        _stop_lost(store, lock)
                    try:
                        r = fut.result()
                    except Exception as exc:  # noqa: BLE001 - the worker died, or the task was lost
                        r = {"id": m.id, "status": "failed", "error": error_line(exc),
                             "traceback": traceback_summary(exc)}
                        record_failure(store, m, r["error"], r["traceback"])
                    # forget the task at once: were the worker that holds its (small) result
                    # to die later, dask would otherwise run the member again and rewrite it
                    fut.release()
                    if r["status"] == "lost":       # its member found the lock taken over first
                        _stop_lost(store, lock)
                    if r["status"] != "complete":
                        result.failed[m.id] = r.get("error", "failed")
                    bar.update(1)
                    if result.failed:
                        bar.set_postfix(failed=len(result.failed))
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise
            finally:
                bar.close()
    if _lost(lock):
        _stop_lost(store, lock)
    failed = dict(result.failed)
    try:
        _record_end(store, members, todo, result, t0)
    except Exception as exc:
        if not is_url(store):
            raise
        raise _unreachable_at_end(store, members, result, failed, exc) from None
    return result


def _record_end(store, members, todo, result, t0) -> None:
    """Check that what the result says complete is complete in the store, and write the
    sweep's record (``last_run``), the member table and the consolidated metadata."""
    for m in todo:
        if m.id not in result.failed and not is_complete(store, m.id):
            error = "IncompleteMember: the member's group is not marked complete after the run"
            record_failure(store, m, error, "")
            result.failed[m.id] = error
    result.elapsed = time.perf_counter() - t0
    open_group(store, "a").update_attributes({"last_run": json.dumps({
        "members": len(members), "ran": len(todo), "skipped": len(result.skipped),
        "failed": result.failed, "damaged": result.damaged, "elapsed_s": round(result.elapsed, 3)})})
    write_member_table(store)          # and the store's consolidated metadata, last


def _unreachable_at_end(store, members, result, failed, exc):
    """The one-line StoreError of a sweep into a URL whose store could not be reached to
    record its end (a network error, the server down): what ran (``failed``: the members
    that failed as they ran), and what to do."""
    why = f"; the first failure: {next(iter(failed.values()))}" if failed else ""
    return StoreError(store, f"cannot be reached to record the end of the sweep ({error_line(exc)}); of "
                             f"{len(members)} members: {len(result.ran) - len(failed)} ran, {len(result.skipped)} "
                             f"already complete, {len(failed)} failed{why}; rerun the same command once the store "
                             f"is reachable: it checks and skips the complete members and runs the others")


def _spec_of(base_scene, sweep: Sweep) -> dict:
    from ..model.scene import Scene

    base = {"scene_digest": scene_digest(base_scene)} if isinstance(base_scene, Scene) else \
        {"builder": builder_name(base_scene.name if isinstance(base_scene, Builder) else base_scene),
         "args": canonical(base_scene.args if isinstance(base_scene, Builder) else {})}
    return {"name": "sweep", "base": base, "sweep": canonical(dataclasses.asdict(sweep))}


# ---------------------------------------------------------------------------- the worker task
def _run_member(store: str, member: Member, base, fft_threads=1, builders=None, check_disk=True,
                guard=None) -> dict:
    """Worker task: build, run and write one member; mark it complete last. Never raises
    for a member's own failure: the error goes to the member's attrs and the result.

    ``guard``: the sweep lock's write guard (``Store.write_guard``), checked before the
    member's writes (``guarded``) and always before it is marked complete: a member whose
    sweep lost the lock (killed, or taken over) stops and writes nothing more, not even
    its failure (status "lost" in the result).

    A member whose group is complete (a ``resume=False`` sweep) is replaced atomically
    for readers: the new run is written to a hidden sibling group and swapped in when
    complete (or failed), so that a reader never finds a group marked complete whose
    arrays are being rewritten. Other groups (absent, failed, interrupted, damaged:
    none marked complete) are cleared and written in place. ``builders``: {name: function}
    of the member's builder, resolved by the client (a worker has no registrations of its own).
    ``check_disk``: the member's own disk check (``simulate``; off with the sweep's)."""
    t0 = time.perf_counter()
    os.environ.setdefault("CRACKLAB_FFT_THREADS", "1")
    path = member_path(store, member.id)
    worker = f"{socket.gethostname()}:{os.getpid()}"
    meta = {"member_id": member.id, "member_params": canonical_json(member.params),
            "member_swept": json.dumps(list(member.swept)), "worker": worker}
    with guarded(guard):
        return _member_task(store, member, base, fft_threads, builders, check_disk, guard, t0, path, worker, meta)


def _member_task(store, member, base, fft_threads, builders, check_disk, guard, t0, path, worker, meta) -> dict:
    """The body of ``_run_member``, its writes guarded."""
    target = path
    try:
        from ..output.simulate import simulate

        if guard is not None:
            guard.check(force=True)          # a task started by a sweep that is gone: nothing written

        old = member_attrs(store, member.id)
        if old is not None and old.get("complete") is True:
            if is_url(store):      # no rename: mark it incomplete before any array is touched
                open_group(path, "a").update_attributes({"complete": False, "status": "running"})
            else:
                target = f"{store_str(store)}/{MEMBERS}/.{member.id}{SWAP_TAG}{os.urandom(4).hex()}"
        g = open_group(target, "w")          # clears whatever an earlier attempt left
        g.update_attributes({**meta, "status": "running", "complete": False})
        scene = build_scene(base, member.params, fft_threads=fft_threads, builders=builders)
        simulate(scene, store=target, check_disk=check_disk)
        g = open_group(target, "a")
        elapsed = time.perf_counter() - t0
        g.update_attributes({**meta, "status": "complete", "elapsed_s": round(elapsed, 3)})
        if guard is not None:
            guard.check(force=True)          # the sweep still holds the store: commit
        g.update_attributes({"complete": True})   # last: the member is complete only now
        if target != path:
            swap_in(target, path)
        return {"id": member.id, "status": "complete", "elapsed": elapsed, "worker": worker}
    except SweepLockLost as exc:        # orphaned: nothing more is written (the lock's holder runs it)
        return {"id": member.id, "status": "lost", "error": error_line(exc), "elapsed": time.perf_counter() - t0,
                "worker": worker}
    except Exception as exc:  # noqa: BLE001 - recorded, the sweep goes on
        elapsed = time.perf_counter() - t0
        error, tb = error_line(exc), traceback_summary(exc)
        if target != path and Path(target).is_dir():
            with contextlib.suppress(OSError):  # what this attempt wrote replaces the old run
                swap_in(target, path)
        record_failure(store, member, error, tb, elapsed)
        return {"id": member.id, "status": "failed", "error": error, "traceback": tb,
                "elapsed": elapsed, "worker": worker}
