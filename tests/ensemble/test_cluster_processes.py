"""A sweep on dask processes started by hand (docs/guide/cluster.md, "workers you start
yourself"): a `dask scheduler` and two `dask worker` processes (tests/dask_processes.py),
each in a directory of its own with its own TMPDIR (nothing shared with the sweep or each
other), and `cracklab sweep --scheduler` into the S3 server on loopback. Every member is
written by one of the workers; the store is complete."""
import os
import subprocess
import sys

from distributed import Client

from cracklab.ensemble import member_status, open_member
from dask_processes import scheduler_and_workers
from small_ensemble import CLUSTER_STUDY as STUDY


def test_a_sweep_on_a_dask_scheduler_and_workers_started_by_hand(s3_env, tmp_path):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    with scheduler_and_workers(tmp_path, 2) as address:
        with Client(address, timeout=60) as client:
            pids = set(client.run(os.getpid).values())
            dirs = set(client.run(os.getcwd).values())
        assert dirs == {str(tmp_path / "worker1"), str(tmp_path / "worker2")}, dirs
        res = subprocess.run([sys.executable, "-m", "cracklab.cli", "sweep", str(study), "-o", url, "--no-progress",
                              "--scheduler", address], cwd=tmp_path, capture_output=True, text=True, timeout=600)
        assert res.returncode == 0, res.stderr
        assert "4 ran" in res.stdout, res.stdout
        status = member_status(url)
        assert len(status) == 4 and all(s["complete"] for s in status), status
        for s in status:
            pid = int(open_member(url, s["id"]).attrs["worker"].rsplit(":", 1)[1])
            assert pid in pids, (pid, pids)
