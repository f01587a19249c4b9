"""The disk a run's store needs, bounded before the run starts (cracklab.output.disk), and
the recorder's set-up counted in the memory estimate."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import cracklab
from cracklab import Record
from cracklab.errors import DiskBudgetError
from cracklab.output import disk
from cracklab.solver import budget

ROOT = Path(__file__).resolve().parents[2]

#: 256^2 cells, t_end 30000, four fields every 2 steps: 15.4 M steps, 7.68 M snapshots,
#: 2 MB each (8 bytes x 65536 nodes x 4 fields): 16 TB uncompressed
HUGE = textwrap.dedent("""
    import cracklab
    from cracklab import Record
    rec = Record(fields=("delta_2", "v_2", "tau_2", "strength"), every=2)
    scene = cracklab.scenes.lamb(n=256, t_end=30000.0, record=rec)
""")


def test_a_16_tb_output_is_refused_before_any_step_with_little_memory(tmp_path):
    """The scene is refused for its output, at once, and the refusal itself stays small in
    memory: less than 100 MB above the interpreter's peak before the call (the recorder's
    snapshot index once took 1 GB before anything was checked)."""
    code = HUGE + textwrap.dedent(f"""
        import json, resource
        from cracklab.errors import DiskBudgetError
        before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        try:
            cracklab.simulate(scene, store={str(tmp_path / 'huge.zarr')!r})
        except DiskBudgetError as exc:
            print(json.dumps({{"field": exc.field, "msg": str(exc), "before": before,
                               "rss": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}}))
    """)
    res = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout.strip().splitlines()[-1])
    assert out["field"] == "record"
    assert "TB (7.68e+06 snapshots of 4 fields" in out["msg"], out["msg"]
    shown = float(out["msg"].split("writes at most ")[1].split(" TB")[0]) * 2**40
    assert abs(shown / (7_680_001 * 4 * 65536 * 8) - 1) < 0.01          # 16.1e12 bytes = 14.7 TB (2^40)
    assert "refused before any step" in out["msg"] and "check_disk=False" in out["msg"]
    assert out["rss"] - out["before"] < 100 << 20, out       # the checks add little to the interpreter's peak
    assert not (tmp_path / "huge.zarr").exists()


def test_the_bound_of_the_16_tb_scene():
    """Counted by hand: 7,680,001 snapshots (steps 0, 2, ..., 15,360,000) of 4 fields of
    65,536 doubles."""
    scene = cracklab.scenes.lamb(n=256, t_end=30000.0,
                                 record=Record(fields=("delta_2", "v_2", "tau_2", "strength"), every=2))
    assert scene.nsteps == 15_360_000
    est = disk.output_size(scene)
    assert est.snapshots == 7_680_001
    frames = 7_680_001 * 4 * 65536 * 8
    assert frames < est.raw < frames * 1.001
    assert est.raw < est.bound < est.raw * 1.01       # zstd's bound: 1/256 more, and headers


def test_a_small_run_writes_no_more_than_its_bound(tmp_path):
    """A real run's store takes at most the bound on disk, and its arrays (uncompressed)
    are the estimate's raw bytes."""
    rec = Record(fields=("delta_2", "v_2"), every=4, stations={"A": (0.5, 0.5), "B": (0.25, 0.5)})
    scene = cracklab.scenes.lamb(n=32, t_end=0.5, record=rec)
    est = disk.output_size(scene)
    store = tmp_path / "r.zarr"
    ds = cracklab.simulate(scene, store=store, checkpoint_every=0)
    used = sum(os.lstat(os.path.join(d, f)).st_blocks * 512 for d, _, fs in os.walk(store) for f in fs)
    assert used <= est.bound, (used, est)
    arrays = sum(ds[v].nbytes for v in ds.data_vars) + ds["t"].nbytes
    assert est.raw == arrays, (est.raw, arrays)


def test_a_bound_beyond_the_free_space_is_refused(tmp_path):
    free = disk.free_space(tmp_path)
    fits = disk.OutputEstimate(snapshots=1, fields=1, raw=1 << 20, bound=1 << 20)
    assert disk.check_disk(fits, tmp_path / "a.zarr") >= free
    over = disk.OutputEstimate(snapshots=1, fields=1, raw=free + (1 << 30), bound=free + (1 << 30))
    with pytest.raises(DiskBudgetError) as err:
        disk.check_disk(over, tmp_path / "a.zarr")
    assert err.value.field == "record" and budget.fmt_bytes(free)[:3] in str(err.value)


def test_the_recorders_set_up_is_in_the_memory_estimate():
    """The snapshot index of millions of snapshots is counted in the estimate's records (8
    bytes a snapshot, four arrays of it), and the recorder builds it as such an array."""
    scene = cracklab.scenes.lamb(n=64, t_end=50000.0, record=Record(fields=("delta_2",), every=1))
    nsnap = scene.nsteps + 1
    assert nsnap > 6_000_000
    est = budget.run_memory(scene)
    assert est.records >= 4 * 8 * nsnap
    from cracklab.output.simulate import Recorder

    rec = Recorder(scene, None)
    assert rec.steps.dtype == np.int64 and rec.steps.size == nsnap
    assert rec.steps.nbytes + rec.snapshot_times().nbytes <= est.records


def test_a_sweep_whose_outputs_do_not_fit_is_refused_before_any_member(tmp_path):
    """Two members of the 16 TB scene (built here): refused before the store is made."""
    import cracklab.ensemble as E

    base = cracklab.scenes.lamb(n=256, t_end=30000.0,
                                record=Record(fields=("delta_2", "v_2", "tau_2", "strength"), every=2))
    store = tmp_path / "sweep.zarr"
    with pytest.raises(DiskBudgetError) as err:
        E.run(base, {"beta": [0.4, 0.5]}, store, scheduler="synchronous", progress=False)
    assert "the sweep's 2 members to run" in str(err.value) and "refused before any step" in str(err.value)
    assert not store.exists()
