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

from .builders import builder_name, resolve_builder
from .identity import canonical, canonical_json, scene_digest
from .lock import store_lock
from .planning import as_sweep, build_scene, plan
from .spec import Builder, Member, Sweep, SweepResult
from .store import (MEMBERS, SWAP_TAG, check_store, damage_of, error_line, init_store, is_complete,
                    member_attrs, member_path, open_group, record_failure, store_str, swap_in,
                    traceback_summary, write_member_table)


def cores() -> int:
    """The cores this process may run on (the default number of local workers)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


@contextlib.contextmanager
def dask_client(client=None, scheduler=None, workers=None, n_tasks=None):
    """The client to use: ``client``; else one connected to ``scheduler`` (or env
    DASK_SCHEDULER_ADDRESS); else an embedded LocalCluster of one-thread worker
    processes, one per core (at most one per task)."""
    if client is not None:
        yield client
        return
    import logging

    from distributed import Client, LocalCluster

    address = scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS")
    if address:
        c = Client(address)
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
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                           silence_logs=logging.ERROR, env=env)
    c = Client(cluster)
    try:
        yield c
    finally:
        c.close()
        cluster.close()


def run(base_scene, sweep, store, *, client=None, resume=True, scheduler=None, workers=None,
        progress=None, fft_threads=1, study_spec=None) -> SweepResult:
    """Run every member of ``sweep`` over ``base_scene`` into the Zarr v3 ``store``.

    ``base_scene``: a Scene (parameters are scene paths), a ``Builder``, or a builder
    name. ``sweep``: a ``Sweep``, a dict of product axes, or a list of member dicts.
    With ``resume`` complete members are skipped; incomplete and failed ones are run
    again. Tasks go to ``client``, else to the scheduler at ``scheduler`` (or env
    DASK_SCHEDULER_ADDRESS), else to an embedded LocalCluster with ``workers`` one-thread
    processes (default: one per core); ``scheduler="synchronous"`` runs the members one
    after the other in this process (debugging, tiny sweeps). A failing member does not
    stop the others: see ``SweepResult.failed`` (and the member's attrs error and
    traceback). ``progress``: a bar over members (default: when stderr is a terminal).
    ``fft_threads``: numerics.fft_threads of every member that does not set it (None: as
    built). Holds the store's sweep lock while it runs: a second sweep into the same
    store at the same time raises ``StoreLocked`` (see ``store_lock``)."""
    t0 = time.perf_counter()
    sweep = as_sweep(sweep)
    members = plan(base_scene, sweep)
    store = store_str(store)
    spec = study_spec or _spec_of(base_scene, sweep)
    check_store(store)                  # before the lock: a wrong path is left untouched
    with store_lock(store):
        return _run_locked(base_scene, sweep, members, store, spec, t0, client=client, resume=resume,
                           scheduler=scheduler, workers=workers, progress=progress,
                           fft_threads=fft_threads)


def _run_locked(base_scene, sweep, members, store, spec, t0, *, client, resume, scheduler, workers,
                progress, fft_threads) -> SweepResult:
    from ..model.scene import Scene

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
            r = _run_member(store, m, base, fft_threads, own(m))
            if r["status"] != "complete":
                result.failed[m.id] = r.get("error", "failed")
    elif todo:
        from distributed import as_completed
        from tqdm import tqdm

        if progress and client is None:
            address = scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS")
            n = max(1, min(workers or cores(), len(todo)))
            print(f"cracklab: {len(todo)} member{'s' if len(todo) != 1 else ''} to run; " +
                  (f"connecting to {address}" if address else
                   f"starting a local cluster of {n} worker process{'es' if n > 1 else ''}"),
                  file=sys.stderr, flush=True)
        with dask_client(client, scheduler, workers, len(todo)) as c:
            base_arg = c.scatter(base, broadcast=True) if base is not None else None
            futures = {c.submit(_run_member, store, m, base_arg, fft_threads, own(m), pure=False,
                                key=f"cracklab-member-{m.id}-{os.urandom(3).hex()}"): m for m in todo}
            bar = tqdm(total=len(todo), desc="members", unit="member", disable=not progress,
                       file=sys.stderr, dynamic_ncols=True)
            try:
                for fut in as_completed(futures):
                    m = futures[fut]
                    try:
                        r = fut.result()
                    except Exception as exc:  # noqa: BLE001 - the worker died, or the task was lost
                        r = {"id": m.id, "status": "failed", "error": error_line(exc),
                             "traceback": traceback_summary(exc)}
                        record_failure(store, m, r["error"], r["traceback"])
                    # forget the task at once: were the worker that holds its (small) result
                    # to die later, dask would otherwise run the member again and rewrite it
                    fut.release()
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
    for m in todo:      # what the result says complete is complete in the store
        if m.id not in result.failed and not is_complete(store, m.id):
            error = "IncompleteMember: the member's group is not marked complete after the run"
            record_failure(store, m, error, "")
            result.failed[m.id] = error
    result.elapsed = time.perf_counter() - t0
    open_group(store, "a").update_attributes({"last_run": json.dumps({
        "members": len(members), "ran": len(todo), "skipped": len(result.skipped),
        "failed": result.failed, "damaged": result.damaged, "elapsed_s": round(result.elapsed, 3)})})
    write_member_table(store)          # and the store's consolidated metadata, last
    return result


def _spec_of(base_scene, sweep: Sweep) -> dict:
    from ..model.scene import Scene

    base = {"scene_digest": scene_digest(base_scene)} if isinstance(base_scene, Scene) else \
        {"builder": builder_name(base_scene.name if isinstance(base_scene, Builder) else base_scene),
         "args": canonical(base_scene.args if isinstance(base_scene, Builder) else {})}
    return {"name": "sweep", "base": base, "sweep": canonical(dataclasses.asdict(sweep))}


# ---------------------------------------------------------------------------- the worker task
def _run_member(store: str, member: Member, base, fft_threads=1, builders=None) -> dict:
    """Worker task: build, run and write one member; mark it complete last. Never raises
    for a member's own failure: the error goes to the member's attrs and the result.

    A member whose group is complete (a ``resume=False`` sweep) is replaced atomically
    for readers: the new run is written to a hidden sibling group and swapped in when
    complete (or failed), so that a reader never finds a group marked complete whose
    arrays are being rewritten. Other groups (absent, failed, interrupted, damaged:
    none marked complete) are cleared and written in place. ``builders``: {name: function}
    of the member's builder, resolved by the client (a worker has no registrations of its own)."""
    t0 = time.perf_counter()
    os.environ.setdefault("CRACKLAB_FFT_THREADS", "1")
    path = member_path(store, member.id)
    worker = f"{socket.gethostname()}:{os.getpid()}"
    meta = {"member_id": member.id, "member_params": canonical_json(member.params),
            "member_swept": json.dumps(list(member.swept)), "worker": worker}
    target = path
    try:
        from ..output.simulate import simulate

        old = member_attrs(store, member.id)
        if old is not None and old.get("complete") is True:
            if "://" in store:      # no rename: mark it incomplete before any array is touched
                open_group(path, "a").update_attributes({"complete": False, "status": "running"})
            else:
                target = f"{store_str(store)}/{MEMBERS}/.{member.id}{SWAP_TAG}{os.urandom(4).hex()}"
        g = open_group(target, "w")          # clears whatever an earlier attempt left
        g.update_attributes({**meta, "status": "running", "complete": False})
        scene = build_scene(base, member.params, fft_threads=fft_threads, builders=builders)
        simulate(scene, store=target)
        g = open_group(target, "a")
        elapsed = time.perf_counter() - t0
        g.update_attributes({**meta, "status": "complete", "elapsed_s": round(elapsed, 3)})
        g.update_attributes({"complete": True})   # last: the member is complete only now
        if target != path:
            swap_in(target, path)
        return {"id": member.id, "status": "complete", "elapsed": elapsed, "worker": worker}
    except Exception as exc:  # noqa: BLE001 - recorded, the sweep goes on
        elapsed = time.perf_counter() - t0
        error, tb = error_line(exc), traceback_summary(exc)
        if target != path and Path(target).is_dir():
            with contextlib.suppress(OSError):  # what this attempt wrote replaces the old run
                swap_in(target, path)
        record_failure(store, member, error, tb, elapsed)
        return {"id": member.id, "status": "failed", "error": error, "traceback": tb,
                "elapsed": elapsed, "worker": worker}
