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
  fail, the sweep stops with one line, and the rerun completes the store.

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
from small_ensemble import BUILDER, SWEEP, member_ids

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
