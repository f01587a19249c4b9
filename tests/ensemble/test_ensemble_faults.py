"""Ensemble faults (issue 6): a dask worker killed (SIGKILL) in the middle of a member,
two sweeps into the same store at the same time, a sweep process killed -9 (stale lock),
and the kernel tables shared between runs in one process."""
import dataclasses
import glob
import hashlib
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import zarr

import cracklab
from cracklab import ensemble as E
from cracklab.ensemble import running

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]


def _small(n, p, t_end, every=2):
    """A small elliptical crack on the direct (reference) engine: runs in different
    processes agree to round-off."""
    scene = cracklab.scenes.elliptical_crack(n=n, a=0.25, b=0.2, p=p, t_end=t_end,
                                             record=cracklab.Record(fields=("delta_2",), every=every))
    return scene.replace(numerics=dataclasses.replace(scene.numerics, engine="direct"))


def _kill_me_when_writing(watch, tag):
    """SIGKILL this process once the member it runs (the run titled ``tag``) has written
    its first chunk of delta_2: the kill lands in the middle of the run and its writes."""
    me = f"cracklab run: {tag}"

    def mine():
        for g in glob.glob(f"{watch}/members/*/zarr.json"):
            try:
                attrs = json.loads(Path(g).read_text()).get("attributes", {})
            except (OSError, ValueError):
                continue
            if attrs.get("title") == me and glob.glob(f"{Path(g).parent}/delta_2/c/*"):
                return True
        return False

    def watcher():
        deadline = time.time() + 60
        while time.time() < deadline:
            if mine():
                os.kill(os.getpid(), signal.SIGKILL)
            time.sleep(0.002)

    threading.Thread(target=watcher, daemon=True).start()


def killer_crack(*, n=32, p=1.0, t_end=4.0, kills="", watch=""):
    """Test-only builder: while the counter file ``kills`` holds k > 0, decrement it and
    arm a SIGKILL of this worker process for the middle of the run."""
    scene = _small(n, p, t_end)
    if kills and os.path.exists(kills):
        k = int(Path(kills).read_text() or 0)
        if k > 0:
            Path(kills).write_text(str(k - 1))
            scene = scene.replace(name=f"killer-{socket.gethostname()}-{os.getpid()}")
            _kill_me_when_writing(watch, scene.name)
    return scene


def slow_crack(*, n=16, p=1.0, t_end=0.1, wait_for=""):
    """Test-only builder that waits until the file ``wait_for`` exists (a long member)."""
    deadline = time.time() + 120
    while wait_for and not os.path.exists(wait_for) and time.time() < deadline:
        time.sleep(0.02)
    return _small(n, p, t_end)


# study files name only registered builders (a `cracklab sweep` process registers these
# with --import test_ensemble_faults)
E.register_builder("test_ensemble_faults:killer_crack", killer_crack)
E.register_builder("test_ensemble_faults:slow_crack", slow_crack)


def _reference(scene):
    return cracklab.simulate(scene)


# ---------------------------------------------------------------------------- worker killed
@pytest.fixture(scope="module")
def fragile_client():
    """2-worker LocalCluster; a task is retried once after its worker dies
    (allowed-failures = 1), and a worker holds one task at a time (no task is lost
    with a worker it was only queued on)."""
    import dask
    from distributed import Client, LocalCluster

    with dask.config.set({"distributed.scheduler.allowed-failures": 1,
                          "distributed.scheduler.worker-saturation": 1.0}):
        cluster = LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0")
        c = Client(cluster)
    yield c
    c.close()
    cluster.close()


def test_worker_killed_mid_member_is_retried_or_marked_failed_then_resumed(fragile_client, tmp_path):
    store = tmp_path / "ens.zarr"
    once, always = tmp_path / "once.kills", tmp_path / "always.kills"
    once.write_text("1")            # killed once: dask retries it on a fresh worker
    always.write_text("5")          # killed on every attempt: recorded as failed
    sweep = E.Sweep(members=[{"p": 1.0}, {"p": 2.0, "kills": str(once)}, {"p": 3.0, "kills": str(always)}],
                    base={"watch": str(store)})
    builder = E.Builder("test_ensemble_faults:killer_crack")
    first = E.run(builder, sweep, store, client=fragile_client, progress=False)
    ok, retried, dead = first.members
    assert once.read_text() == "0" and always.read_text() == "3"          # 1 + 2 workers killed
    assert list(first.failed) == [dead.id], first.summary()
    assert "KilledWorker" in first.failed[dead.id]
    status = {s["id"]: s for s in E.member_status(store)}
    assert status[dead.id]["status"] == "failed" and status[dead.id]["complete"] is False
    assert status[ok.id]["complete"] and status[retried.id]["complete"], (first.summary(), status)
    # the store is consistent: readable, the complete members hold the same data as an
    # uninterrupted run (the retried one included), the failed one is not in the ensemble
    ens = E.open_ensemble(store)
    assert list(ens.member.values) == [ok.id, retried.id]
    for m in (ok, retried):
        ref = _reference(E.build_scene(builder, {**m.params, "kills": ""}))
        np.testing.assert_allclose(ens.delta_2.sel(member=m.id).values, ref.delta_2.values, rtol=0, atol=1e-12)

    always.write_text("0")          # the cause is gone: a rerun completes the failed member
    second = E.run(builder, sweep, store, client=fragile_client, progress=False)
    assert second.ok and second.ran == [dead.id] and set(second.skipped) == {ok.id, retried.id}
    assert sorted(zarr.open_group(str(store), mode="r")["members"].group_keys()) == sorted(m.id for m in first.members)
    ens = E.open_ensemble(store)
    assert ens.sizes["member"] == 3
    ref = _reference(E.build_scene(builder, {**dead.params, "kills": ""}))
    np.testing.assert_allclose(ens.delta_2.sel(member=dead.id).values, ref.delta_2.values, rtol=0, atol=1e-12)
    assert not (store / E.LOCK_NAME).exists()


# ---------------------------------------------------------------------------- concurrent sweeps
STUDY = """
[study]
name = "locked"
builder = "test_ensemble_faults:slow_crack"
[sweep]
p = [1.0, 2.0, 3.0]
[base]
wait_for = "%s"
"""


def _sweep_cmd(study, store):
    return [sys.executable, "-m", "cracklab.cli", "sweep", str(study), "-o", str(store),
            "--scheduler", "synchronous", "--no-progress", "--import", "test_ensemble_faults"]


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(HERE), str(ROOT), env.get("PYTHONPATH", "")])
    return env


def _wait_until(condition, proc, timeout=120):
    deadline = time.time() + timeout
    while not condition():
        assert proc.poll() is None, proc.communicate()
        assert time.time() < deadline, "timed out"
        time.sleep(0.02)


def _complete_ids(store):
    try:
        return sorted(s["id"] for s in E.member_status(store) if s["complete"])
    except (cracklab.InputError, FileNotFoundError, KeyError):     # not created yet
        return []


def test_two_sweeps_into_one_store_the_second_is_refused(tmp_path):
    release = tmp_path / "release"
    study = tmp_path / "study.toml"
    study.write_text(STUDY % release)       # the first sweep's members wait for this file
    store = tmp_path / "ens.zarr"
    lock = store / E.LOCK_NAME
    first = subprocess.Popen(_sweep_cmd(study, store), env=_env(), stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    try:
        _wait_until(lock.exists, first)
        holder = json.loads(lock.read_text())
        assert holder["pid"] == first.pid and holder["host"] == socket.gethostname()
        second = subprocess.run(_sweep_cmd(study, store), env=_env(), capture_output=True, text=True,
                                timeout=120)
        assert first.poll() is None            # the first is still running: a real overlap
        assert second.returncode == 1
        assert f"in use by another sweep (pid {first.pid} on {socket.gethostname()}" in second.stderr
        assert "Traceback" not in second.stderr and second.stderr.count("Error") == 1
        release.write_text("go")
        out, err = first.communicate(timeout=120)
    finally:
        if first.poll() is None:
            first.kill()
            first.communicate()
    assert first.returncode == 0, err
    assert "3 members: 3 ran" in out
    assert not lock.exists()
    s = E.load_study(study)
    assert _complete_ids(store) == sorted(m.id for m in E.plan(s.base, s.sweep))
    ens = E.open_ensemble(store)
    assert ens.sizes["member"] == 3 and np.isfinite(ens.delta_2.values).all()
    assert json.loads(zarr.open_group(str(store), mode="r").attrs["last_run"])["ran"] == 3


KILLED_STUDY = """
[study]
name = "killed"
builder = "test_ensemble_faults:slow_crack"
[[members]]
p = 1.0
[[members]]
p = 2.0
wait_for = "%s"
[[members]]
p = 3.0
wait_for = "%s"
"""


def test_sweep_killed_leaves_a_stale_lock_that_the_next_sweep_takes_over(tmp_path):
    release = tmp_path / "release"
    study = tmp_path / "study.toml"
    study.write_text(KILLED_STUDY % (release, release))
    store = tmp_path / "ens.zarr"
    lock = store / E.LOCK_NAME
    first = subprocess.Popen(_sweep_cmd(study, store), env=_env(), stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    try:
        _wait_until(lambda: len(_complete_ids(store)) == 1, first)    # member 1 done, 2 waiting
    finally:
        first.send_signal(signal.SIGKILL)                             # kill -9 the sweep
        first.communicate()
    assert lock.exists() and json.loads(lock.read_text())["pid"] == first.pid     # left behind
    s = E.load_study(study)
    one, two, three = E.plan(s.base, s.sweep)
    assert _complete_ids(store) == [one.id]
    release.write_text("go")
    again = subprocess.run(_sweep_cmd(study, store), env=_env(), capture_output=True, text=True, timeout=120)
    assert again.returncode == 0, again.stderr
    assert "2 ran, 1 already complete, 0 failed" in again.stdout
    assert not lock.exists() and len(_complete_ids(store)) == 3
    assert E.open_ensemble(store).sizes["member"] == 3


def _tree_digest(path):
    h = hashlib.sha256()
    for p in sorted(Path(path).rglob("*")):
        h.update(str(p.relative_to(path)).encode())
        if p.is_file():
            h.update(p.read_bytes())
    return h.hexdigest()


def test_lock_held_elsewhere_is_refused_and_the_store_left_alone(tmp_path):
    store = tmp_path / "ens.zarr"
    builder = E.Builder("test_ensemble_faults:slow_crack")
    assert E.run(builder, {"p": [1.0]}, store, scheduler="synchronous", progress=False).ok
    lock = store / E.LOCK_NAME
    lock.write_text(json.dumps({"host": "another-host", "pid": 1, "started": "2026-01-01T00:00:00"}))
    before = _tree_digest(store)
    with pytest.raises(E.StoreLocked, match=r"store: .* in use by another sweep \(pid 1 on another-host"):
        E.run(builder, {"p": [1.0, 2.0]}, store, scheduler="synchronous", progress=False)
    assert _tree_digest(store) == before
    # same host, no such process: stale, taken over
    lock.write_text(json.dumps({"host": socket.gethostname(), "pid": 2**22 + 12345}))
    res = E.run(builder, {"p": [1.0, 2.0]}, store, scheduler="synchronous", progress=False)
    assert res.ok and len(res.skipped) == 1 and not lock.exists()
    # an empty lock (a sweep killed while creating it) is stale once older than the grace time
    lock.write_text("")
    with pytest.raises(E.StoreLocked, match="another process"):
        E.run(builder, {"p": [1.0]}, store, scheduler="synchronous", progress=False)
    old = time.time() - E.LOCK_GRACE_S - 1
    os.utime(lock, (old, old))
    assert E.run(builder, {"p": [1.0]}, store, scheduler="synchronous", progress=False).ok


def test_paths_that_are_not_ensemble_stores_are_refused_untouched(tmp_path):
    builder = E.Builder("test_ensemble_faults:slow_crack")
    afile = tmp_path / "file.zarr"
    afile.write_text("not a store")
    other = tmp_path / "mydata"
    other.mkdir()
    (other / "notes.txt").write_text("keep me")
    run_store = tmp_path / "run.zarr"
    cracklab.simulate(_small(16, 1.0, 0.05), store=str(run_store))
    newer = tmp_path / "newer.zarr"
    E.run(builder, {"p": [1.0]}, newer, scheduler="synchronous", progress=False)
    zarr.open_group(str(newer), mode="a").attrs["cracklab_ensemble"] = E.FORMAT + 1
    for path, message in ((afile, "is a file"), (other, "directory with other content"),
                          (run_store, "single cracklab run"), (newer, "another cracklab version")):
        before = _tree_digest(path) if path.is_dir() else path.read_bytes()
        with pytest.raises(cracklab.InputError, match=message) as err:
            E.run(builder, {"p": [2.0]}, path, scheduler="synchronous", progress=False)
        assert err.value.field == "store"
        assert (_tree_digest(path) if path.is_dir() else path.read_bytes()) == before


# ---------------------------------------------------------------------------- kernel tables
def test_kernel_tables_are_computed_once_per_process(monkeypatch):
    """A second run with the same grid and material takes every kernel table of the
    direct engine from cracklab.history.tables: no table is computed again (for the
    displacement scheme: no kernel evaluation at all)."""
    from cracklab.elastic import weights
    from cracklab.history import tables

    calls = {"n": 0}
    original = weights.convolution_weights

    def counted(*a, **k):
        calls["n"] += 1
        return original(*a, **k)

    monkeypatch.setattr(weights, "convolution_weights", counted)
    tables.clear()
    def direct(scene):
        return scene.replace(numerics=dataclasses.replace(scene.numerics, engine="direct"))

    mode_i = direct(cracklab.scenes.asperity_row(n1=32, n3=16, t_end=0.6))      # displacement scheme
    first = cracklab.simulate(mode_i)
    assert calls["n"] == tables.stats["computed"] > 0          # every table came through the cache
    n_calls, computed = calls["n"], tables.stats["computed"]
    again = cracklab.simulate(mode_i.replace(name="again", t_end=0.5))
    assert calls["n"] == n_calls and tables.stats["computed"] == computed and tables.stats["hits"] > 0
    np.testing.assert_array_equal(first.delta_2.isel(t=slice(0, again.sizes["t"])).values, again.delta_2.values)

    shear = direct(cracklab.scenes.tpv3(dx=2000.0, t_end=1.0))            # product scheme, 2 kernels
    cracklab.simulate(shear)
    computed = tables.stats["computed"]
    hits = tables.stats["hits"]
    cracklab.simulate(shear.replace(name="again"))
    assert tables.stats["computed"] == computed and tables.stats["hits"] >= hits + 2
    assert tables.stats["bytes"] > 0 and all(not w.flags.writeable for w in tables.cached_tables())

    # the cache is bounded by bytes: with a 0 MB bound nothing is kept
    monkeypatch.setenv("CRACKLAB_KERNEL_CACHE_MB", "0")
    tables.clear()
    cracklab.simulate(mode_i)
    n = tables.stats["computed"]
    cracklab.simulate(mode_i)
    assert tables.stats["computed"] == 2 * n and tables.stats["bytes"] == 0
    # and least recently used tables go first when the bound is reached
    monkeypatch.setenv("CRACKLAB_KERNEL_CACHE_MB", str(1.5 * 256 * 108 * 8 / 2**20))
    tables.clear()
    g1, g2 = np.linspace(0.1, 1, 108), np.linspace(0.2, 1, 108)
    tables.weight_table("I", g1, 0, 256, nu=0.25)
    tables.weight_table("I", g2, 0, 256, nu=0.25)          # evicts g1's table
    assert tables.stats["entries"] == 1
    tables.weight_table("I", g2, 0, 256, nu=0.25)
    assert tables.stats["hits"] == 1 and tables.stats["computed"] == 2
    tables.clear()


def test_no_monkeypatching_of_the_engine():
    from cracklab.history import direct
    from cracklab.elastic.weights import convolution_weights

    assert not hasattr(E, "share_kernel_tables")
    assert direct.convolution_weights is convolution_weights


def test_full_disk_and_read_only_locations_give_one_clear_error(tmp_path, monkeypatch):
    """A sweep or an export that cannot write ends with one `Error:` line, no traceback
    (simulated: running as root, permissions cannot make a real read-only directory)."""
    import errno

    from click.testing import CliRunner

    from cracklab.cli import main

    study = tmp_path / "study.toml"
    study.write_text('[study]\nbuilder = "test_ensemble_faults:slow_crack"\n[sweep]\np = [1.0]\n')
    store = tmp_path / "ens.zarr"
    runner = CliRunner()

    def full(*a, **k):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    with monkeypatch.context() as m:
        m.setattr(running, "init_store", full)
        res = runner.invoke(main, ["sweep", str(study), "-o", str(store), "--scheduler", "synchronous"])
    assert res.exit_code == 1 and res.output.strip() == f"Error: store: cannot write {store}: No space left on device"
    assert not (store / E.LOCK_NAME).exists()                 # the lock is released
    assert runner.invoke(main, ["sweep", str(study), "-o", str(store), "--scheduler", "synchronous"]).exit_code == 0

    def read_only(self, *a, **k):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS))

    monkeypatch.setattr(xr.Dataset, "to_netcdf", read_only)
    out = tmp_path / "ro" / "ens.nc"
    res = runner.invoke(main, ["export", str(store), "--netcdf", str(out)])
    assert res.exit_code == 1 and res.output.strip() == f"Error: --netcdf: cannot write {out}: Read-only file system"
