"""Checkpoints and resume of a run into an object store (docs/guide/reliability.md, "Object
storage"), against the S3 API server on loopback (tests/s3_server.py; no client mocked):
the run checkpoints into the store through its ``Store`` (the state's bytes under a fresh
key, then a pointer with their SHA-256, last), and a rerun after a kill resumes from it, bit
for bit as the uninterrupted run; a checkpoint whose pointer was never written is never
used, nor one whose bytes do not match their pointer."""
import importlib
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

import cracklab
from cracklab import Numerics, Record
from cracklab.cli import main
from cracklab.errors import StoreError
from cracklab.model.scene_io import scene_to_toml
from cracklab.output import checkpoint as ck
from cracklab.output.stores import store_for
from interrupt import interrupted_run

SIM = importlib.import_module("cracklab.output.simulate")
ROOT = Path(__file__).resolve().parents[2]
STATIONS = {"centre": (0.5, 0.5), "edge": (0.75, 0.5)}


def _client(server):
    import boto3

    from s3_server import KEYS

    return boto3.client("s3", endpoint_url=server.endpoint, region_name="us-east-1",
                        aws_access_key_id=KEYS["AWS_ACCESS_KEY_ID"], aws_secret_access_key=KEYS["AWS_SECRET_ACCESS_KEY"])


def keys(server, bucket, prefix=""):
    out = _client(server).list_objects_v2(Bucket=bucket, Prefix=prefix).get("Contents", [])
    return sorted(o["Key"] for o in out)


def _scene(t_end=1.5):
    return cracklab.scenes.elliptical_crack(n=32, a=0.25, b=0.2, t_end=t_end, numerics=Numerics(engine="exponential"),
                                            record=Record(fields=("delta_2", "v_2"), every=3, stations=STATIONS))


def assert_same(ref, res):
    assert set(ref.data_vars) == set(res.data_vars)
    for name in list(ref.data_vars) + list(ref.coords):
        a, b = ref[name].values, res[name].values
        assert a.shape == b.shape, name
        if a.dtype.kind == "f":
            np.testing.assert_array_equal(a, b, err_msg=name)
        else:
            assert (a == b).all(), name


def _attrs(server, bucket, key="run.zarr/zarr.json"):
    body = _client(server).get_object(Bucket=bucket, Key=key)["Body"].read()
    return json.loads(body)["attributes"]


def test_an_interrupted_run_into_s3_resumes_bit_for_bit(s3_env, monkeypatch):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/run.zarr"
    scene = _scene()
    ref = cracklab.simulate(scene)
    stop = scene.nsteps // 2 + 1
    interrupted_run(scene, url, monkeypatch, stop=stop, checkpoint_every=9)
    attrs = _attrs(s3_env, bucket)
    assert attrs["cracklab_status"] == "running" and attrs["cracklab_checkpoint_step"] == (stop // 9) * 9
    held = keys(s3_env, bucket, "run.zarr/_checkpoint/")
    states = [k for k in held if k.rsplit("/", 1)[1].startswith("state-")]
    assert "run.zarr/_checkpoint/checkpoint.json" in held and len(states) == 1, held   # earlier ones deleted
    pointer = json.loads(_client(s3_env).get_object(Bucket=bucket, Key="run.zarr/_checkpoint/checkpoint.json")
                         ["Body"].read())
    assert states[0].endswith(pointer["object"]) and len(pointer["sha256"]) == 64
    assert ck.read_entry(url, "n") == (stop // 9) * 9
    killed = xr.open_zarr(url, consolidated=False)          # readable as it was left
    assert killed.attrs["cracklab_status"] == "running"

    res = cracklab.simulate(scene, store=url, resume=True).load()
    assert res.attrs["cracklab_status"] == "complete"
    assert keys(s3_env, bucket, "run.zarr/_checkpoint/") == []          # removed once complete
    assert_same(ref, res)
    again = cracklab.simulate(scene, store=url, resume=True)            # complete: returned as is
    assert_same(res, again.load())
    assert cracklab.output.verify.verify(url).ok
    everything = b"".join(_client(s3_env).get_object(Bucket=bucket, Key=k)["Body"].read()
                          for k in keys(s3_env, bucket) if k.endswith(".json"))
    assert b"cracklab-test-secret" not in everything and b"cracklab-test-key" not in everything


def test_a_checkpoint_killed_before_its_pointer_is_never_used(s3_env, monkeypatch):
    """A kill between the checkpoint's bytes and its pointer: the bytes are there under
    their fresh key, the pointer still names the previous checkpoint; the resume uses
    that one (bit for bit), and deletes the orphan."""
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/run.zarr"
    scene = _scene(t_end=1.0)
    ref = cracklab.simulate(scene)
    calls = []

    def killed_at_the_second_commit():
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt         # as a kill: the pointer is never written

    real = ck._sleep_hook
    monkeypatch.setattr(ck, "_sleep_hook", killed_at_the_second_commit)
    with pytest.raises(KeyboardInterrupt):
        cracklab.simulate(scene, store=url, checkpoint_every=10)
    monkeypatch.setattr(ck, "_sleep_hook", real)
    states = [k for k in keys(s3_env, bucket, "run.zarr/_checkpoint/") if "/state-" in k]
    assert len(states) == 2                 # the first checkpoint's and the orphan
    assert ck.read_entry(url, "n") == 10    # the pointer names the first
    res = cracklab.simulate(scene, store=url, resume=True).load()
    assert_same(ref, res)
    assert keys(s3_env, bucket, "run.zarr/_checkpoint/") == []


def test_a_checkpoint_whose_bytes_changed_is_refused_in_one_line(s3_env, monkeypatch):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/run.zarr"
    scene = _scene(t_end=1.0)
    interrupted_run(scene, url, monkeypatch, stop=25, checkpoint_every=10)
    client = _client(s3_env)
    state = next(k for k in keys(s3_env, bucket, "run.zarr/_checkpoint/") if "/state-" in k)
    data = bytearray(client.get_object(Bucket=bucket, Key=state)["Body"].read())
    data[len(data) // 2] ^= 0xFF
    client.put_object(Bucket=bucket, Key=state, Body=bytes(data))
    with pytest.raises(StoreError) as info:
        cracklab.simulate(scene, store=url, resume=True)
    line = str(info.value)
    assert line.startswith(f"store {url}: its checkpoint {url}/_checkpoint/state-") and "\n" not in line
    assert "SHA-256" in line and "run again without resume" in line
    assert ck.read_entry(url, "n") is None          # nor read by the command line's progress line
    res = cracklab.simulate(scene, store=url).load()     # without resume: starts over
    assert res.attrs["cracklab_status"] == "complete"


def test_the_store_keeps_checkpoints_through_the_protocol(s3_env):
    bucket = s3_env.make_bucket()
    store = store_for(f"s3://{bucket}/x.zarr")
    assert store.checkpoints and ck.read(store) is None
    state = {"n": 3, "a": np.arange(4.0), "nested": {1: np.ones((2, 2), np.complex128)}, "x": 0.1}
    ck.write(store, state)
    ck.write(store, {**state, "n": 4})
    back = ck.read(store)
    assert back["n"] == 4 and back["x"] == 0.1 and back["nested"][1].dtype == np.complex128
    assert len([k for k in keys(s3_env, bucket) if "/state-" in k]) == 1
    ck.remove(store)
    assert keys(s3_env, bucket) == [] and ck.read(store) is None


# ---------------------------------------------------------------------------- the command line
def _cli_run(toml, url, *extra):
    return CliRunner().invoke(main, ["run", str(toml), "-o", url, "--no-progress", *extra])


def _cli_case(server, tmp_path):
    """(a new bucket, its run.zarr URL, the short scene's TOML in tmp_path, its uninterrupted run)."""
    bucket = server.make_bucket()
    url = f"s3://{bucket}/run.zarr"
    scene = _scene(t_end=1.0)
    toml = tmp_path / "scene.toml"
    toml.write_text(scene_to_toml(scene))
    return bucket, url, toml, cracklab.simulate(scene)


def test_cracklab_run_into_s3_is_interrupted_then_resumed(s3_env, tmp_path, monkeypatch):
    _, url, toml, ref = _cli_case(s3_env, tmp_path)
    real = SIM.Recorder.__call__

    def interrupted(self, state):
        real(self, state)
        if state.n == 25:
            raise KeyboardInterrupt

    monkeypatch.setattr(SIM.Recorder, "__call__", interrupted)
    res = _cli_run(toml, url, "--checkpoint-every", "10")
    assert res.exit_code == 130, res.output
    assert "interrupted at step 20; rerun the same command to resume" in res.output, res.output
    monkeypatch.setattr(SIM.Recorder, "__call__", real)
    res = _cli_run(toml, url)
    assert res.exit_code == 0, res.output
    assert "resumed from step 20" in res.output and "without checkpoints" not in res.output, res.output
    assert_same(ref, xr.open_zarr(url, consolidated=False).load())
    res = _cli_run(toml, url)
    assert res.exit_code == 0 and "holds this run, complete (checked); nothing to do" in res.output, res.output
    assert "cracklab-test-secret" not in res.output


def _long_scene():
    return cracklab.scenes.elliptical_crack(
        n=64, a=0.25, b=0.2, t_end=1200 * 0.5 / 64, numerics=Numerics(engine="exponential"),
        record=Record(fields=("delta_2",), every=20, stations=STATIONS))


def _start(toml, out, *extra):
    cmd = [sys.executable, "-m", "cracklab.cli", "run", str(toml), "-o", str(out), "--no-progress", *extra]
    return subprocess.Popen(cmd, cwd=ROOT, env=dict(os.environ), stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def test_sigkill_of_cracklab_run_into_s3_then_resume(s3_env, tmp_path):
    """kill -9 of a `cracklab run -o s3://...` after a checkpoint; the same command resumes
    it to the store of an uninterrupted run in a fresh process, bit for bit."""
    bucket = s3_env.make_bucket()
    scene = _long_scene()
    toml = tmp_path / "scene.toml"
    toml.write_text(scene_to_toml(scene))
    ref_url, url = f"s3://{bucket}/ref.zarr", f"s3://{bucket}/run.zarr"
    proc = _start(toml, ref_url)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err.decode()[-2000:]

    def step():
        try:
            return _attrs(s3_env, bucket, "run.zarr/zarr.json").get("cracklab_checkpoint_step")
        except Exception:  # noqa: BLE001 - not written yet
            return None

    proc = _start(toml, url, "--checkpoint-every", "100")
    deadline = time.time() + 360
    while time.time() < deadline and proc.poll() is None and (step() or 0) < 100:
        time.sleep(0.05)
    assert proc.poll() is None, proc.communicate()[1].decode()[-2000:]
    proc.send_signal(signal.SIGKILL)
    assert proc.wait() == -signal.SIGKILL
    last = step()
    assert 100 <= last < scene.nsteps
    proc = _start(toml, url, "--checkpoint-every", "100")
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err.decode()[-2000:]
    # the attr follows the checkpoint (output/simulate.py: informational): a kill between
    # the two leaves it one checkpoint behind the checkpoint the run resumes from
    resumed = re.search(r"resumed from step (\d+)", err.decode())
    assert resumed and int(resumed.group(1)) in (last, last + 100), err.decode()
    assert_same(xr.open_zarr(ref_url, consolidated=False).load(), xr.open_zarr(url, consolidated=False).load())


# ---------------------------------------------------------------------------- the store unreachable
@pytest.mark.parametrize("client", ["retries", "one attempt"])
def test_the_store_unreachable_during_a_checkpoint(client, s3_restartable, tmp_path, monkeypatch):
    """The server unreachable for 3 s from the middle of the second checkpoint's write
    (its bytes stored, its pointer not yet; tests/s3_server.py, ``outage``). With a client
    that retries for long enough (AWS_RETRY_MODE=standard, AWS_MAX_ATTEMPTS=10) the run
    goes on and is the uninterrupted run, bit for bit; with one attempt per request
    (AWS_MAX_ATTEMPTS=1) `cracklab run` stops with one line naming the store, what it was
    doing and the checkpoint kept, and the same command, with the store back, resumes from
    the first checkpoint to the uninterrupted run, bit for bit."""
    server = s3_restartable
    bucket, url, toml, ref = _cli_case(server, tmp_path)
    if client == "retries":
        monkeypatch.setenv("AWS_RETRY_MODE", "standard")
        monkeypatch.setenv("AWS_MAX_ATTEMPTS", "10")
    else:
        monkeypatch.setenv("AWS_MAX_ATTEMPTS", "1")
    calls, outage = [], []

    def unreachable_at_the_second_commit():
        calls.append(1)
        if len(calls) == 2:
            outage.append(threading.Thread(target=server.outage, args=(3.0,)))
            outage[0].start()
            time.sleep(0.3)

    monkeypatch.setattr(ck, "_sleep_hook", unreachable_at_the_second_commit)
    res = _cli_run(toml, url, "--checkpoint-every", "10")
    outage[0].join()
    monkeypatch.setattr(ck, "_sleep_hook", lambda: None)
    if client == "retries":
        assert res.exit_code == 0, res.output
    else:
        lines = res.output.strip().splitlines()
        assert res.exit_code == 1 and len(lines) == 1 and "Traceback" not in res.output, res.output
        assert lines[0].startswith(f"Error: store {url}: cannot be reached while writing the checkpoint after step "
                                   f"20 (EndpointConnectionError: "), lines
        assert "the store keeps the run up to its checkpoint after step 10" in lines[0], lines
        monkeypatch.delenv("AWS_MAX_ATTEMPTS")
        res = _cli_run(toml, url, "--checkpoint-every", "10")
        assert res.exit_code == 0 and "resumed from step 10" in res.output, res.output
    assert_same(ref, xr.open_zarr(url, consolidated=False).load())
    assert cracklab.output.verify.verify(url).ok
    assert keys(server, bucket, "run.zarr/_checkpoint/") == []
