"""Nothing lost in a sequence (issue 35, verification 5): a `cracklab run` of a sequence
streams to its store and checkpoints; kill -9 at any point and resume gives the run's
numbers bit for bit; the store holds what the in-memory run returns."""
import os
import signal
import subprocess
import sys
import time

import numpy as np
import xarray as xr

from same_output import assert_same_run
from spring_slider import scene as spring_slider


def _start(toml, out, *args, sleep=None):
    env = dict(os.environ)
    if sleep:
        env["CRACKLAB_TEST_CHECKPOINT_SLEEP"] = str(sleep)     # each checkpoint write lingers
    return subprocess.Popen([sys.executable, "-m", "cracklab.cli", "run", str(toml), "-o", str(out), *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)


def _checkpoint_n(out):
    from cracklab.output import checkpoint

    try:
        ck = checkpoint.read(out)
    except Exception:
        return None
    return None if ck is None else int(ck["run"]["n"])


def test_the_store_holds_the_in_memory_run_and_verifies(tmp_path, monkeypatch):
    import importlib
    import shutil

    import cracklab
    from cracklab.output.verify import verify

    scene = spring_slider(4e8)
    store = tmp_path / "s.zarr"
    ref = cracklab.simulate(scene)
    # three snapshots a chunk: flushes end inside chunks, which the next rewrites
    one = max(ref[f].isel(t=0).nbytes for f in ref.data_vars if ref[f].dims == ("t", "x1", "x3"))
    monkeypatch.setattr(importlib.import_module("cracklab.output.sequence"), "SNAPSHOT_CHUNK_BYTES", 3 * one)
    assert_same_run(cracklab.simulate(scene, store=store, checkpoint_every=100).load(), ref)
    report = verify(store)
    on_disk = sum(1 for p in store.rglob("*") if p.is_file() and p.relative_to(store).parts[1:2] == ("c",))
    assert report.ok and report.chunks == on_disk > 70, (report.first(), report.chunks, on_disk)
    shutil.rmtree(store / "max_slip_rate" / "c")           # a lost array's chunks are damage
    assert not verify(store).ok


def test_kill_9_and_resume_is_bit_identical(tmp_path):
    _kill_and_resume(tmp_path, spring_slider(1.2e9), every=150)


def test_kill_9_and_resume_of_a_fully_dynamic_sequence_is_bit_identical(tmp_path):
    """A BP1-FD on a coarse grid through its first earthquake: the history's rings and
    states are in the checkpoint."""
    import cracklab

    _kill_and_resume(tmp_path, cracklab.scenes.bp1(dz=1000.0, depth=80e3, years=230.0, dynamic=True), every=400)


def _kill_and_resume(tmp_path, scene, every):
    toml = tmp_path / "scene.toml"
    scene.to_toml(toml)
    ref_proc = _start(toml, tmp_path / "ref.zarr")
    _, err = ref_proc.communicate(timeout=300)
    assert ref_proc.returncode == 0, err.decode()[-2000:]
    ref = xr.open_zarr(tmp_path / "ref.zarr").load()
    out = tmp_path / "out.zarr"
    last, rng = -1, np.random.default_rng(1)
    for attempt in range(2):
        proc = _start(toml, out, "--checkpoint-every", str(every), *(["--resume"] if attempt else []), sleep=0.3)
        deadline = time.monotonic() + 120
        while (_checkpoint_n(out) or -1) <= last and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
        assert proc.poll() is None, proc.communicate()[1].decode()[-2000:]
        time.sleep(rng.uniform(0.0, 0.4))         # after a checkpoint, or in the middle of the next write
        proc.send_signal(signal.SIGKILL)
        assert proc.wait() == -signal.SIGKILL
        last = _checkpoint_n(out)
        assert last is not None and 0 < last < ref.attrs["accepted_steps"]
    proc = _start(toml, out, "--resume")
    outs, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err.decode()[-2000:]
    assert f"resumed after accepted step {last}," in (outs + err).decode()     # not started over
    res = xr.open_zarr(out).load()
    assert res.attrs["cracklab_resumed_from"] == last
    assert_same_run(res, ref)
    # a complete store of the scene is served as it is, not run again
    proc = _start(toml, out, "--resume")
    outs, err = proc.communicate(timeout=300)
    assert proc.returncode == 0 and "nothing to do" in (outs + err).decode(), err.decode()[-2000:]
    served = xr.open_zarr(out).load()
    assert served.attrs["cracklab_resumed_from"] == last          # the same store: not run again
    assert_same_run(served, ref)
