"""Faults of a sweep into object storage (issue 32, point 5; docs/guide/reliability.md,
"Object storage"), with real processes against the S3 API server on loopback
(tests/s3_server.py; no client mocked):

* a sweep whose lock is taken over stops with one line, and its members stop before their
  next write (the write guard of ``FsspecStore.write_guard``): nothing more is written by
  them, and the rerun completes the store, equal to an uninterrupted sweep;
* a member whose sweep's lock has had no heartbeat for ``LOCK_STALE_S / 2`` (its sweep
  was killed) stops before it writes, with one line;
* kill -9 of a sweep's driver in the middle of a member's writes: the rerun takes the
  lock over, reruns what is not complete, and the store is sound and, bit for bit, an
  uninterrupted local sweep's;
* the S3 server killed and restarted with its data in the middle of a sweep
  (``s3_restartable``): the client's retries carry the sweep over it;
* the store unreachable for longer than the client retries: the members that needed it
  fail, the sweep stops with one line, and the rerun completes the store;
* on a `dask scheduler` and `dask worker` processes started by hand (tests/dask_processes.py):
  kill -9 of the worker running a member (dask runs it again, or the sweep names it in one
  line; the rerun completes the store), and kill -9 of the driver, whose members run on in
  the living workers until their guard stops them (nothing more written; the rerun
  completes the store).

(A network error during a single run's checkpoint: tests/output/test_object_store_resume.py;
two sweeps started at once on one store: tests/output/test_object_store_lock.py.)"""
import importlib
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

import cracklab
from cracklab import ensemble as E
from cracklab.ensemble.verify import verify
from cracklab.errors import StoreError
from cracklab.output.stores import SweepLockLost, fsspecstore
from cracklab.output.stores.local import pid_alive
from small_ensemble import BUILDER, STUDY, SWEEP, member_ids

SIM = importlib.import_module("cracklab.output.simulate")
REAL_CALL = SIM.Recorder.__call__
HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
LOCK = ".cracklab-sweep.lock"


def _client(server):
    import boto3

    from s3_server import KEYS

    return boto3.client("s3", endpoint_url=server.endpoint, region_name="us-east-1",
                        aws_access_key_id=KEYS["AWS_ACCESS_KEY_ID"], aws_secret_access_key=KEYS["AWS_SECRET_ACCESS_KEY"])


def _objects(server, bucket, prefix="ens.zarr/"):
    """{key: ETag} of every object below ``prefix`` (what has been written, and how)."""
    out, token = {}, None
    client = _client(server)
    while True:
        kw = {"ContinuationToken": token} if token else {}
        page = client.list_objects_v2(Bucket=bucket, Prefix=prefix, **kw)
        out.update({o["Key"]: o["ETag"] for o in page.get("Contents", [])})
        if not page.get("IsTruncated"):
            return out
        token = page["NextContinuationToken"]


def _reference(tmp_path_factory):
    store = tmp_path_factory.mktemp("ref") / "ens.zarr"
    assert E.run(BUILDER, SWEEP, store, scheduler="synchronous", progress=False).ok
    return E.open_ensemble(store).load()


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    return _reference(tmp_path_factory)


def _same(ens, ref):
    assert list(ens.member.values) == list(ref.member.values)
    for name in ref.data_vars:
        np.testing.assert_array_equal(ens[name].values, ref[name].values, err_msg=name)


def _at_second_member(action):
    """A Recorder.__call__ that calls ``action()`` once, at step 6 of the second member a
    sweep runs; (the replacement, the members' ids in the order they started)."""
    real = SIM.Recorder.__call__
    seen, done = [], []

    def call(self, state):
        real(self, state)
        mid = self.kept_attrs.get("member_id")
        if mid not in seen:
            seen.append(mid)
        if len(seen) == 2 and state.n == 6 and not done:
            done.append(True)
            action()

    return call, seen


# ---------------------------------------------------------------------------- the lock taken over
def test_members_of_a_sweep_whose_lock_was_taken_over_stop_writing(s3_env, monkeypatch, reference):
    """Another sweep takes the lock over while the second member runs (as when this
    sweep's heartbeat could not reach the store for LOCK_STALE_S): that member stops at
    its next write, the sweep stops with one line, and nothing more is written into the
    store; the lock stays the other sweep's. Before, the sweep only warned and went on
    writing, mixed with the other sweep's members."""
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    monkeypatch.setattr(fsspecstore, "GUARD_EVERY_S", 0.5)          # a write reads the lock 0.5 s after the last
    client = _client(s3_env)
    after = {}
    real = SIM.Recorder.__call__

    def take_over():
        other = {"host": "elsewhere.example", "pid": 4242, "started": "2026-01-01T00:00:00+0000", "token": "e" * 16}
        client.put_object(Bucket=bucket, Key=f"ens.zarr/{LOCK}", Body=json.dumps(other).encode())
        after.update(_objects(s3_env, bucket))
        time.sleep(0.6)                                             # the next write reads the lock

    taken_over, seen = _at_second_member(take_over)
    monkeypatch.setattr(SIM.Recorder, "__call__", taken_over)
    with pytest.raises(SweepLockLost) as info:
        E.run(BUILDER, SWEEP, url, scheduler="synchronous", progress=False)
    monkeypatch.setattr(SIM.Recorder, "__call__", real)
    line = str(info.value)
    assert "\n" not in line and f"store {url}: " in line and "taken over by another sweep" in line, line
    assert after and _objects(s3_env, bucket) == after          # not one write since
    assert json.loads(client.get_object(Bucket=bucket, Key=f"ens.zarr/{LOCK}")["Body"].read())["token"] == "e" * 16
    status = {s["id"]: s for s in E.member_status(url)}
    first, second = seen
    assert status[first]["complete"] and not status[second]["complete"], status
    assert status[second]["status"] == "running"                  # not even its failure was written
    # the other sweep ends; this one's rerun completes the store
    client.delete_object(Bucket=bucket, Key=f"ens.zarr/{LOCK}")
    res = E.run(BUILDER, SWEEP, url, scheduler="synchronous", progress=False)
    assert res.ok and first in res.skipped and second in res.ran, res.summary()
    assert verify(url).ok
    _same(E.open_ensemble(url).load(), reference)


def test_a_member_whose_sweep_has_no_heartbeat_stops(s3_env, monkeypatch):
    """The guard's own rule: a lock whose heartbeat is older than LOCK_STALE_S / 2 means
    the sweep is gone (killed): its member stops before it writes, before any other
    sweep may take the lock over by its age."""
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    st = fsspecstore.FsspecStore(url)
    monkeypatch.setattr(fsspecstore, "LOCK_HEARTBEAT_S", 1000.0)     # the holder stops beating
    monkeypatch.setattr(fsspecstore, "LOCK_STALE_S", 4.0)
    with st.lock() as _:
        pass
    lock = st.lock()
    with lock:
        guard = st.write_guard(lock)
        guard.check(force=True)                                     # fresh: goes on
        time.sleep(3.0)
        with pytest.raises(SweepLockLost, match=r"has had no heartbeat for \d+ s: the sweep was killed") as info:
            guard.check(force=True)
        assert "\n" not in str(info.value) and str(info.value).startswith(f"store {url}: its sweep's lock")
    with pytest.raises(SweepLockLost, match="is gone"):               # released at the end
        guard.check(force=True)


# ---------------------------------------------------------------------------- the driver killed
def killing_crack(*, n=16, a=0.25, b=0.2, p=1.0, t_end=0.3, kill=""):
    """Test-only builder: the crack of small_ensemble's BUILDER; when the file ``kill``
    holds this member's p and the store's URL, this process kills itself (SIGKILL) as soon
    as the member's first chunk of delta_2 is on the server: a sweep driver killed in the
    middle of a member's writes (with --scheduler synchronous the driver runs them)."""
    scene = cracklab.scenes.elliptical_crack(n=n, a=a, b=b, p=p, t_end=t_end)
    if kill and os.path.exists(kill):
        at, url = Path(kill).read_text().split()
        if float(at) == p:
            os.remove(kill)
            before = _written(url)
            threading.Thread(target=_kill_when_written, args=(url, before), daemon=True).start()
    return scene


def _written(url):
    """The members of the store at ``url`` with a chunk of delta_2 on the server."""
    import s3fs

    fs = s3fs.S3FileSystem(skip_instance_cache=True, use_listings_cache=False)
    try:
        return {k.split("/members/")[1].split("/")[0] for k in fs.find(f"{url}/members/") if "/delta_2/c/" in k}
    except FileNotFoundError:
        return set()


def _kill_when_written(url, before):
    deadline = time.time() + 120
    while time.time() < deadline:
        if _written(url) - before:
            os.kill(os.getpid(), signal.SIGKILL)
        time.sleep(0.005)


E.register_builder("test_object_store_faults:killing_crack", killing_crack)

KILLED_STUDY = """
[study]
name = "killed"
builder = "test_object_store_faults:killing_crack"
[base]
kill = "%s"
record.every = 2
record.stations.c = [0.5, 0.5]
[sweep]
p = [1.0, 2.0, 3.0]
"""


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(HERE), str(HERE.parent), str(ROOT), env.get("PYTHONPATH", "")])
    return env


def _sweep_cmd(study, out):
    return [sys.executable, "-m", "cracklab.cli", "sweep", str(study), "-o", str(out), "--scheduler", "synchronous",
            "--no-progress", "--import", "test_object_store_faults"]


def test_kill_9_of_the_sweep_driver_mid_member_then_the_rerun_completes_the_store(s3_env, tmp_path, monkeypatch):
    """kill -9 of `cracklab sweep -o s3://...` while it writes its second member: the first
    member stays complete, the second is left incomplete (never served), the lock is left
    behind. The same command completes the store: it takes the lock of the gone process
    over, skips the complete member, reruns the others, and the store is sound and, bit for
    bit, the store of an uninterrupted local sweep."""
    from click.testing import CliRunner

    from cracklab.cli import main

    kill = tmp_path / "kill"
    study = tmp_path / "study.toml"
    study.write_text(KILLED_STUDY % kill)
    local = tmp_path / "ref.zarr"                     # the reference: uninterrupted, on the local disk
    res = CliRunner().invoke(main, ["sweep", str(study), "-o", str(local), "--scheduler", "synchronous",
                                    "--no-progress"])
    assert res.exit_code == 0, res.output
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    kill.write_text(f"2.0 {url}")
    proc = subprocess.run(_sweep_cmd(study, url), env=_env(), capture_output=True, text=True, timeout=300)
    assert proc.returncode == -signal.SIGKILL, (proc.returncode, proc.stderr[-2000:])
    ids = member_ids(local)
    status = {s["id"]: s for s in E.member_status(url)}
    assert status[ids[0]]["complete"] and not status[ids[1]]["complete"], status     # killed in the second
    assert ids[2] not in status or not status[ids[2]]["complete"]
    lock = json.loads(_client(s3_env).get_object(Bucket=bucket, Key=f"ens.zarr/{LOCK}")["Body"].read())
    assert lock["host"] == socket.gethostname() and not pid_alive(lock["pid"])     # left behind by the killed sweep
    assert list(E.open_ensemble(url).member.values) == ids[:1]                      # the complete one only
    monkeypatch.setattr(fsspecstore, "GUARD_EVERY_S", 0.2)         # the wait for orphaned members, shortened
    res = CliRunner().invoke(main, ["sweep", str(study), "-o", url, "--scheduler", "synchronous", "--no-progress"])
    assert res.exit_code == 0, res.output
    assert "3 members: 2 ran, 1 already complete, 0 failed" in res.output, res.output
    assert verify(url).ok
    assert LOCK not in "".join(_objects(s3_env, bucket))
    _same(E.open_ensemble(url).load(), E.open_ensemble(local).load())


# ---------------------------------------------------------------------------- the server restarted, unreachable
def _during_second_member(fault):
    """A Recorder.__call__ that starts ``fault()`` in a thread of its own at step 6 of the
    second member a sweep runs (once); (the replacement, the threads started)."""
    started = []

    def begin():
        t = threading.Thread(target=fault)
        t.start()
        started.append(t)
        time.sleep(0.3)                 # the fault has begun: the member's next writes meet it

    call, _ = _at_second_member(begin)
    return call, started


def test_the_s3_server_restarted_mid_sweep(s3_restartable, monkeypatch, reference):
    """The S3 server killed (SIGKILL) in the middle of the second member and started again
    on the same endpoint with the same data (tests/s3_server.py: its requests replayed),
    clients refused for 3 s: the client's retries (AWS_RETRY_MODE=standard,
    AWS_MAX_ATTEMPTS=10: backoff up to 20 s a retry) carry the sweep over it, no member
    fails, and the store is sound and, bit for bit, the uninterrupted local sweep's."""
    server = s3_restartable
    monkeypatch.setenv("AWS_RETRY_MODE", "standard")
    monkeypatch.setenv("AWS_MAX_ATTEMPTS", "10")
    bucket = server.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    first = server.proc.pid
    call, started = _during_second_member(lambda: server.restart(down_s=3.0))
    monkeypatch.setattr(SIM.Recorder, "__call__", call)
    res = E.run(BUILDER, SWEEP, url, scheduler="synchronous", progress=False)
    started[0].join()
    assert server.proc.pid != first                     # another server process
    assert res.ok and len(res.ran) == 3, res.summary()
    assert verify(url).ok
    _same(E.open_ensemble(url).load(), reference)
    assert LOCK not in "".join(_objects(server, bucket))


def test_the_store_unreachable_longer_than_the_retries_ends_the_sweep_in_one_line(s3_restartable, monkeypatch,
                                                                                   reference):
    """The server unreachable for 3 s from the middle of the second member, the client
    allowed one attempt per request (AWS_MAX_ATTEMPTS=1; botocore's default, 5 attempts
    with backoff, rides over a few seconds, as above): the members that needed the store
    fail, and the sweep, which cannot record its end, stops with one line saying what ran
    and what to do; the rerun, with the store back, takes over the lock the sweep could
    not delete and completes the store, bit for bit the uninterrupted local sweep's."""
    server = s3_restartable
    bucket = server.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    monkeypatch.setenv("AWS_MAX_ATTEMPTS", "1")
    call, started = _during_second_member(lambda: server.outage(3.0))
    monkeypatch.setattr(SIM.Recorder, "__call__", call)
    with pytest.raises(StoreError) as info:
        E.run(BUILDER, SWEEP, url, scheduler="synchronous", progress=False)
    started[0].join()
    monkeypatch.setattr(SIM.Recorder, "__call__", REAL_CALL)
    line = str(info.value)
    assert "\n" not in line, line
    assert line.startswith(f"store {url}: cannot be reached to record the end of the sweep ("), line
    assert "; of 3 members: 1 ran, 0 already complete, 2 failed; the first failure: StoreError: store " \
        f"{url}/members/" in line and ": cannot be reached while writing " in line, line
    assert server.endpoint in line and "rerun the same command once the store is reachable" in line, line
    monkeypatch.delenv("AWS_MAX_ATTEMPTS")
    monkeypatch.setattr(fsspecstore, "GUARD_EVERY_S", 0.2)         # the wait for orphaned members, shortened
    again = E.run(BUILDER, SWEEP, url, scheduler="synchronous", progress=False)
    assert again.ok and len(again.ran) == 2 and len(again.skipped) == 1, again.summary()
    assert verify(url).ok
    _same(E.open_ensemble(url).load(), reference)


# ---------------------------------------------------------------------------- a scheduler and workers of their own
def _study(tmp_path, t_end, ps):
    """small_ensemble's study of cracks with ``t_end`` and the loads ``ps``: on the S3
    server a member of t_end = 30 writes for about 4 s, one of t_end = 60 for 8 s (alone on
    an idle machine)."""
    study = tmp_path / "study.toml"
    study.write_text(STUDY.replace("t_end = 0.05", f"t_end = {t_end}").replace("p = [1.0, 1.2]", f"p = {ps}"))
    return study


def _local(study, tmp_path):
    """The store of the study swept uninterrupted on the local disk, synchronously."""
    from click.testing import CliRunner

    from cracklab.cli import main

    local = tmp_path / "ref.zarr"
    res = CliRunner().invoke(main, ["sweep", str(study), "-o", str(local), "--scheduler", "synchronous",
                                    "--no-progress"])
    assert res.exit_code == 0, res.output
    return local


def _on_scheduler(study, url, address, *more):
    return [sys.executable, "-m", "cracklab.cli", "sweep", str(study), "-o", url, "--no-progress",
            "--scheduler", address, *more]


def _mid_run(url):
    """{member id: pid of its worker} of the members of the store at ``url`` that are in the
    middle of their run: a chunk of delta_2 on the server, not complete."""
    import s3fs

    fs = s3fs.S3FileSystem(skip_instance_cache=True, use_listings_cache=False)
    try:
        keys = fs.find(f"{url}/members/")
    except FileNotFoundError:
        return {}
    out = {}
    for mid in {k.split("/members/")[1].split("/")[0] for k in keys if "/delta_2/c/" in k}:
        try:
            attrs = json.loads(fs.cat_file(f"{url}/members/{mid}/zarr.json"))["attributes"]
        except (FileNotFoundError, ValueError, KeyError):
            continue
        if attrs.get("complete") is False and "worker" in attrs:
            out[mid] = int(attrs["worker"].rsplit(":", 1)[1])
    return out


def _wait_for(what, proc, timeout=120.0):
    """``what()`` once it is true (polled), while ``proc`` runs."""
    deadline = time.monotonic() + timeout
    while not (got := what()):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.05)
    return got


def test_kill_9_of_a_dask_worker_mid_member_then_the_s3_store_is_complete(s3_env, tmp_path):
    """`cracklab sweep --scheduler ADDRESS -o s3://...` on a scheduler and two `dask worker`
    processes started by hand: the worker process that runs a member is killed (SIGKILL)
    once that member has a chunk on the server. Dask runs the member again (on the other
    worker, or on the one its nanny restarts): the sweep ends with every member complete,
    the killed one written by another process, or names the member it gave up on in one
    line. The same command then completes the store (skips what is complete), sound and,
    bit for bit, an uninterrupted local sweep's."""
    from distributed import Client

    from dask_processes import scheduler_and_workers

    study = _study(tmp_path, 30.0, [1.0, 1.2, 1.4])
    local = _local(study, tmp_path)
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    with scheduler_and_workers(tmp_path / "dask", 2) as address:
        with Client(address, timeout=60) as client:
            pids = set(client.run(os.getpid).values())
        driver = subprocess.Popen(_on_scheduler(study, url, address), cwd=tmp_path, env=_env(),
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            mid, pid = next(iter(_wait_for(lambda: _mid_run(url), driver).items()))
            assert pid in pids, (pid, pids)
            os.kill(pid, signal.SIGKILL)
            out, err = driver.communicate(timeout=300)
        finally:
            if driver.poll() is None:
                driver.kill()
                driver.wait()
        if driver.returncode == 0:          # run again by dask: written by another worker process
            assert "3 members: 3 ran, 0 already complete, 0 failed" in out, (out, err)
            assert int(E.open_member(url, mid).attrs["worker"].rsplit(":", 1)[1]) != pid
            ran = 0
        else:                               # given up: one line naming the member
            assert driver.returncode == 1, err
            assert [ln for ln in (out + err).splitlines() if mid in ln and "KilledWorker" in ln], (out, err)
            ran = 1
        rerun = subprocess.run(_on_scheduler(study, url, address), cwd=tmp_path, env=_env(), capture_output=True,
                               text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    assert f"3 members: {ran} ran, {3 - ran} already complete, 0 failed" in rerun.stdout, rerun.stdout
    assert verify(url).ok
    assert LOCK not in "".join(_objects(s3_env, bucket))
    _same(E.open_ensemble(url).load(), E.open_ensemble(local).load())


def test_kill_9_of_the_driver_on_a_dask_scheduler_its_orphaned_members_stop_writing(s3_env, tmp_path):
    """kill -9 of `cracklab sweep --scheduler ADDRESS -o s3://...` (its lock's heartbeat
    every 0.5 s, an orphan's after 3 s: tests/quick_lock.py) while its members run on two
    `dask worker` processes started by hand: the workers live on, and so do the members
    they were running (a thread cannot be stopped; dask only drops their results). Each
    stops at its next write once the lock has had no heartbeat for 3 s (its guard), long
    before its own end: nothing more is written into the store, no member is marked
    complete or failed. The same command, on the same workers, takes the lock over and
    completes the store, sound and, bit for bit, an uninterrupted local sweep's."""
    from distributed import Client

    from dask_processes import members_running, scheduler_and_workers

    study = _study(tmp_path, 60.0, [1.0, 1.2])
    local = _local(study, tmp_path)
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    with scheduler_and_workers(tmp_path / "dask", 2) as address, Client(address, timeout=60) as client:
        pids = client.run(os.getpid)
        driver = subprocess.Popen(_on_scheduler(study, url, address, "--import", "quick_lock"), cwd=tmp_path,
                                  env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            started = _wait_for(lambda: _mid_run(url), driver)
            driver.kill()
            assert driver.wait() == -signal.SIGKILL
        finally:
            if driver.poll() is None:
                driver.kill()
                driver.wait()
        killed = time.monotonic()
        assert sum(client.run(members_running).values()) >= 1          # orphaned, running on
        while sum(client.run(members_running).values()):
            assert time.monotonic() - killed < 60, "the orphaned members did not stop"
            time.sleep(0.1)
        stopped = time.monotonic() - killed
        after = _objects(s3_env, bucket)
        assert client.run(os.getpid) == pids                           # the same workers, alive
        status = {s["id"]: s for s in E.member_status(url)}
        assert not any(s["complete"] for s in status.values()), status
        assert all(status[mid]["status"] == "running" for mid in started), status   # not even a failure written
        time.sleep(1.0)
        assert _objects(s3_env, bucket) == after, f"written to after its members stopped ({stopped:.1f} s)"
        rerun = subprocess.run(_on_scheduler(study, url, address, "--import", "quick_lock"), cwd=tmp_path,
                               env=_env(), capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    assert "2 members: 2 ran, 0 already complete, 0 failed" in rerun.stdout, rerun.stdout
    assert verify(url).ok
    assert LOCK not in "".join(_objects(s3_env, bucket))
    _same(E.open_ensemble(url).load(), E.open_ensemble(local).load())
