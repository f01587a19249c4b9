"""A sequence of earthquakes streamed to an object store (output/sequence.py through the
store protocol, ``cracklab.output.stores``), against the S3 API server on loopback
(tests/s3_server.py; no client mocked): the store holds what the in-memory run returns,
verifies sound, and a run stopped after a checkpoint resumes from the checkpoint kept in
the object store, bit for bit."""
import importlib

import pytest
import xarray as xr

import cracklab
from cracklab.output import checkpoint
from cracklab.output.verify import verify
from same_output import assert_same_run
from spring_slider import scene as spring_slider

SEQ = importlib.import_module("cracklab.output.sequence")


def test_a_sequence_into_s3_is_the_in_memory_run_and_resumes_bit_for_bit(s3_env, monkeypatch):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/seq.zarr"
    scene = spring_slider(4e8)
    ref = cracklab.simulate(scene)
    steps = int(ref.attrs["accepted_steps"])
    assert steps > 200
    # three snapshots a chunk: flushes end inside chunks, which the next rewrites
    one = max(ref[f].isel(t=0).nbytes for f in ref.data_vars if ref[f].dims == ("t", "x1", "x3"))
    monkeypatch.setattr(SEQ, "SNAPSHOT_CHUNK_BYTES", 3 * one)
    real = SEQ.SequenceRecorder.__call__
    stop = steps // 2 + 7

    def killed(self, state):
        real(self, state)
        if state.n == stop:
            raise KeyboardInterrupt      # as a kill: no clean-up runs

    monkeypatch.setattr(SEQ.SequenceRecorder, "__call__", killed)
    with pytest.raises(KeyboardInterrupt):
        cracklab.simulate(scene, store=url, checkpoint_every=150)
    monkeypatch.setattr(SEQ.SequenceRecorder, "__call__", real)
    ck = checkpoint.read(url)
    assert ck is not None and int(ck["run"]["n"]) == (stop // 150) * 150
    partial = xr.open_zarr(SEQ._zarr(checkpoint.as_store(url)), consolidated=False)
    assert partial.attrs["cracklab_status"] == "running"

    res = cracklab.simulate(scene, store=url, resume=True, checkpoint_every=150).load()
    assert_same_run(ref, res)
    assert res.attrs["cracklab_status"] == "complete"
    assert res.attrs["cracklab_resumed_from"] == (stop // 150) * 150
    assert checkpoint.read(url) is None             # removed once complete
    report = verify(url)
    assert report.ok and report.chunks > 50, report.first()
    again = cracklab.simulate(scene, store=url, resume=True)     # complete: returned as is
    assert_same_run(ref, again.load())
    # without resume the store is replaced by a fresh run
    assert_same_run(ref, cracklab.simulate(scene, store=url).load())
