"""Exclusivity of a sweep on object storage (``FsspecStore.lock``; docs/guide/reliability.md,
"Object storage"), against the S3 API server on loopback (tests/s3_server.py; no client
mocked): the lock object is created by a conditional write (If-None-Match: *), a second
sweep is refused with one line naming the holder, a heartbeat keeps the lock fresh, and a
stale lock (no heartbeat for LOCK_STALE_S, or its process gone on this host) is taken
over by exactly one contender."""
import json
import socket
import subprocess
import sys
import threading
import time

import pytest
from click.testing import CliRunner

from cracklab.cli import main
from cracklab.output.stores import StoreLocked, fsspecstore, store_for
from small_ensemble import STUDY
from test_object_store_input import one_error_line

LOCK = ".cracklab-sweep.lock"


def _client(server):
    import boto3

    from s3_server import KEYS

    return boto3.client("s3", endpoint_url=server.endpoint, region_name="us-east-1",
                        aws_access_key_id=KEYS["AWS_ACCESS_KEY_ID"], aws_secret_access_key=KEYS["AWS_SECRET_ACCESS_KEY"])


def _lock_doc(server, bucket, key=f"ens.zarr/{LOCK}"):
    return json.loads(_client(server).get_object(Bucket=bucket, Key=key)["Body"].read())


def _plant(server, bucket, **holder):
    """A lock object as another sweep left it."""
    doc = {"host": "elsewhere.example", "pid": 4242, "started": "2026-01-01T00:00:00+0000", "token": "f" * 16,
           **holder}
    _client(server).put_object(Bucket=bucket, Key=f"ens.zarr/{LOCK}", Body=json.dumps(doc).encode())


def test_the_s3_server_honours_conditional_writes(s3_env):
    """The lock relies on it: a PutObject with If-None-Match: * of a key that exists is
    refused (412 Precondition Failed); so is one with If-Match and another ETag."""
    from botocore.exceptions import ClientError

    bucket = s3_env.make_bucket()
    client = _client(s3_env)
    first = client.put_object(Bucket=bucket, Key="k", Body=b"1", IfNoneMatch="*")
    with pytest.raises(ClientError, match="PreconditionFailed"):
        client.put_object(Bucket=bucket, Key="k", Body=b"2", IfNoneMatch="*")
    with pytest.raises(ClientError, match="PreconditionFailed"):
        client.put_object(Bucket=bucket, Key="k", Body=b"3", IfMatch='"0123"')
    client.put_object(Bucket=bucket, Key="k", Body=b"4", IfMatch=first["ETag"])
    assert client.get_object(Bucket=bucket, Key="k")["Body"].read() == b"4"


def test_an_s3_store_is_held_by_one_sweep_at_a_time(s3_env):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    with store_for(url).lock() as held:
        assert held == f"{url}/{LOCK}"
        doc = _lock_doc(s3_env, bucket)
        assert doc["host"] == socket.gethostname() and isinstance(doc["pid"], int) and len(doc["token"]) == 16
        assert "cracklab-test" not in json.dumps(doc)          # no credentials in the lock
        with pytest.raises(StoreLocked) as info:
            with store_for(url).lock():
                pass
        line = str(info.value)
        assert "\n" not in line and f"{url} is in use by another sweep (pid {doc['pid']} on {doc['host']}" in line
        assert f"delete {url}/{LOCK}" in line, line
    assert [o["Key"] for o in _client(s3_env).list_objects_v2(Bucket=bucket).get("Contents", [])] == []
    with store_for(url).lock():          # released: taken again
        pass


def test_the_heartbeat_keeps_a_lock_fresh_and_a_stale_one_is_taken_over(s3_env, monkeypatch):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    monkeypatch.setattr(fsspecstore, "LOCK_HEARTBEAT_S", 0.3)
    monkeypatch.setattr(fsspecstore, "LOCK_STALE_S", 2.5)
    with store_for(url).lock():
        time.sleep(4.0)                  # longer than LOCK_STALE_S: only the heartbeat keeps it
        with pytest.raises(StoreLocked, match="is in use by another sweep"):
            with store_for(url).lock():
                pass
    _plant(s3_env, bucket)               # another host's sweep, beating
    with pytest.raises(StoreLocked, match=r"\(pid 4242 on elsewhere.example, since 2026-01-01"):
        with store_for(url).lock():
            pass
    time.sleep(4.0)                      # ... that stopped beating
    with store_for(url).lock():
        assert _lock_doc(s3_env, bucket)["host"] == socket.gethostname()


def test_a_lock_whose_process_is_gone_on_this_host_is_taken_over_at_once(s3_env):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    _plant(s3_env, bucket, host=socket.gethostname(), pid=gone.pid)
    with store_for(url).lock():
        assert _lock_doc(s3_env, bucket)["pid"] != gone.pid


def test_of_several_sweeps_taking_over_a_stale_lock_one_wins(s3_env, monkeypatch):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    # the winner's heartbeat keeps its own lock fresh: a contender that the host's load
    # delays must still find it held, not stale. The server's LastModified has a
    # resolution of one second (HTTP dates), so a fresh lock can look up to a second
    # older than it is: the stale age is kept well above that.
    monkeypatch.setattr(fsspecstore, "LOCK_STALE_S", 3.0)
    monkeypatch.setattr(fsspecstore, "LOCK_HEARTBEAT_S", 0.2)
    _plant(s3_env, bucket)
    time.sleep(4.5)
    barrier, won, refused = threading.Barrier(4), [], []
    release = threading.Event()

    def contend():
        barrier.wait()
        try:
            with store_for(url).lock():
                won.append(1)
                release.wait(10)
        except StoreLocked:
            refused.append(1)

    threads = [threading.Thread(target=contend) for _ in range(4)]
    for t in threads:
        t.start()
    deadline = time.time() + 30
    while len(won) + len(refused) < 4 and time.time() < deadline and not (won and len(refused) == 3):
        time.sleep(0.05)
    release.set()
    for t in threads:
        t.join(30)
    assert len(won) == 1 and len(refused) == 3, (won, refused)


def test_a_sweep_into_a_held_s3_store_is_refused_in_one_line(s3_env, tmp_path):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    with store_for(url).lock():
        line = one_error_line(["sweep", str(study), "--no-progress", "-o", url, "--scheduler", "synchronous"])
    assert f"{url} is in use by another sweep (pid " in line and socket.gethostname() in line, line
    assert "cracklab-test-secret" not in line
    keys = [o["Key"] for o in _client(s3_env).list_objects_v2(Bucket=bucket).get("Contents", [])]
    assert not any("/members/" in k for k in keys), keys          # no member ran
    res = CliRunner().invoke(main, ["sweep", str(study), "--no-progress", "-o", url, "--scheduler", "synchronous"])
    assert res.exit_code == 0, res.output                          # released: the sweep runs
    keys = [o["Key"] for o in _client(s3_env).list_objects_v2(Bucket=bucket).get("Contents", [])]
    assert f"ens.zarr/{LOCK}" not in keys and any("/members/" in k for k in keys)


def test_two_sweep_processes_started_at_once_on_one_s3_store(s3_env, tmp_path):
    """Two `cracklab sweep -o s3://...` processes started together: one holds the store
    and completes it, the other is refused in one line naming the holder, before any
    member runs; then the store is sound and the lock gone."""
    import os

    from cracklab.ensemble import member_status

    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    cmd = [sys.executable, "-m", "cracklab.cli", "sweep", str(study), "--no-progress", "-o", url,
           "--scheduler", "synchronous"]
    procs = [subprocess.Popen(cmd, env=dict(os.environ), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
             for _ in range(2)]
    outs = [p.communicate(timeout=600) for p in procs]
    codes = sorted(p.returncode for p in procs)
    errs = [o[1].decode() + o[0].decode() for o in outs]
    assert codes == [0, 1], errs      # (both 0 only if one ended before the other started: not seen)
    refused = errs[[p.returncode for p in procs].index(1)]
    lines = [line for line in refused.strip().splitlines() if line.startswith("Error:")]
    assert len(lines) == 1 and f"{url} is in use by another sweep (pid " in lines[0], refused
    assert "Traceback" not in refused and "cracklab-test-secret" not in refused
    status = member_status(url)
    assert len(status) == 2 and all(s["complete"] for s in status), status
    keys = [o["Key"] for o in _client(s3_env).list_objects_v2(Bucket=bucket).get("Contents", [])]
    assert f"ens.zarr/{LOCK}" not in keys
    winner = procs[[p.returncode for p in procs].index(0)].pid      # every member run by the winner alone
    workers = {json.loads(_client(s3_env).get_object(Bucket=bucket, Key=k)["Body"].read())["attributes"]["worker"]
               for k in keys if k.count("/") == 3 and k.startswith("ens.zarr/members/") and k.endswith("/zarr.json")}
    assert workers == {f"{socket.gethostname()}:{winner}"}, workers
