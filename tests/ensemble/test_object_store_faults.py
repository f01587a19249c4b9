"""Faults of a sweep into object storage (issue 32, point 5; docs/guide/reliability.md,
"Object storage"), with real processes against the S3 API server on loopback
(tests/s3_server.py; no client mocked):

* a sweep whose lock is taken over stops with one line, and its members stop before their
  next write (the write guard of ``FsspecStore.write_guard``): nothing more is written by
  them, and the rerun completes the store, equal to an uninterrupted sweep;
* a member whose sweep's lock has had no heartbeat for ``LOCK_STALE_S / 2`` (its sweep
  was killed) stops before it writes, with one line."""
import importlib
import json
import time

import numpy as np
import pytest

from cracklab import ensemble as E
from cracklab.ensemble.verify import verify
from cracklab.output.stores import SweepLockLost, fsspecstore
from small_ensemble import BUILDER, SWEEP

SIM = importlib.import_module("cracklab.output.simulate")
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
    seen, after = [], {}
    real = SIM.Recorder.__call__

    def taken_over(self, state):
        real(self, state)
        mid = self.kept_attrs.get("member_id")
        if mid not in seen:
            seen.append(mid)
        if len(seen) == 2 and state.n == 6 and not after:
            other = {"host": "elsewhere.example", "pid": 4242, "started": "2026-01-01T00:00:00+0000",
                     "token": "e" * 16}
            client.put_object(Bucket=bucket, Key=f"ens.zarr/{LOCK}", Body=json.dumps(other).encode())
            after.update(_objects(s3_env, bucket))
            time.sleep(0.6)                                         # the next write reads the lock

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
