"""A sweep on a real batch system: ``cracklab sweep --cluster slurm`` submits its dask
workers as jobs of a one-node Slurm started by the tests (tests/slurm.py), and the
workers write their members straight into an S3 store on loopback (tests/s3_server.py);
nothing is mocked. The store is complete, verifies, and its members are those of a local
run to the bit."""
import contextlib
import os
import re
import signal
import subprocess
import sys
import threading
import time
import urllib.request

import fsspec
import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

import s3_server
from cli_process import ROOT, error_line
from cracklab.cli import main
from cracklab.ensemble import member_status, open_member
from small_ensemble import CLUSTER_STUDY as STUDY


#: each job runs in a directory of its own (no working or temporary directory shared with
#: the sweep or the other jobs) and says which
PROLOGUE = '["cd \\"$(mktemp -d)\\"", "export TMPDIR=\\"$PWD\\"", "echo cracklab-job-dir $PWD"]'


def _job_pids(slurm) -> dict[int, str]:
    """{pid: job id} of the processes of the running jobs (scontrol listpids)."""
    out = slurm.run("scontrol", "listpids", check=False)
    pids = {}
    for line in out.splitlines()[1:]:
        parts = line.split()
        if len(parts) >= 2 and parts[0].isdigit():
            pids[int(parts[0])] = parts[1]
    return pids


def test_a_sweep_on_slurm_jobs_writes_straight_to_s3_and_matches_a_local_run(s3_env, slurm_env, tmp_path):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    logs = tmp_path / "jobs"
    cmd = [sys.executable, "-m", "cracklab.cli", "sweep", str(study), "-o", url, "--progress",
           "--cluster", "slurm", "--workers", "2", "--cluster-option", "interface=lo",
           "--cluster-option", f"log_directory={logs}", "--cluster-option", "local_directory=.",
           "--cluster-option", f"job_script_prologue={PROLOGUE}", "--cluster-option", "walltime=00:10:00"]
    assert slurm_env.jobs_end(), "jobs of an earlier test are still in the queue"
    driver = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines = []
    reader = threading.Thread(target=lambda: lines.extend(driver.stderr), daemon=True)
    reader.start()
    seen, jobs_seen, dashboard = {}, set(), None
    deadline = time.monotonic() + 600
    try:
        while driver.poll() is None:       # the processes of the jobs, while they run
            assert time.monotonic() < deadline, f"the sweep did not end within 600 s: {''.join(lines)}"
            pids = _job_pids(slurm_env)
            seen.update(pids)
            jobs_seen |= set(slurm_env.jobs())
            link = next((m.group(1) for ln in list(lines) if (m := re.search(r"dashboard (http://\S+)", ln))), None)
            if link and dashboard is None:     # the dask dashboard answers while the sweep runs
                with contextlib.suppress(OSError):
                    with urllib.request.urlopen(link, timeout=10) as page:
                        dashboard = (page.status, b"bokeh" in page.read().lower())
            time.sleep(0.2)
        out = driver.stdout.read()
        driver.wait(timeout=60)
        reader.join(timeout=10)
    finally:
        if driver.poll() is None:
            driver.kill()
            driver.wait()
    err = "".join(lines)
    assert driver.returncode == 0, err
    assert "2 slurm jobs submitted for 2 workers" in err, err
    assert dashboard == (200, True), dashboard
    assert "4 ran" in out, out
    assert len(jobs_seen) == 2, jobs_seen
    assert slurm_env.active() == []                   # the jobs are cancelled at the end
    assert slurm_env.jobs_end()

    # every member was written by a worker process of a Slurm job, none by the sweep's own
    # process (it only made the store and its member table); how many each job ran depends on
    # which started first
    status = member_status(url)
    assert len(status) == 4 and all(s["complete"] for s in status), status
    writers = {}
    for s in status:
        attrs = open_member(url, s["id"]).attrs
        host, pid = attrs["worker"].rsplit(":", 1)
        assert int(pid) in seen, (attrs["worker"], sorted(seen))
        assert int(pid) != driver.pid
        writers[s["id"]] = seen[int(pid)]
    assert set(writers.values()) <= jobs_seen, (writers, jobs_seen)

    # each job worked in its own directory, none the sweep's
    dirs = set()
    for log in logs.glob("*.err"):
        dirs |= set(re.findall(r"cracklab-job-dir (\S+)", log.read_text()))
    for log in logs.glob("*.out"):
        dirs |= set(re.findall(r"cracklab-job-dir (\S+)", log.read_text()))
    assert len(dirs) == 2 and str(tmp_path) not in dirs, dirs

    # the credentials are in no object of the store, no job's output and nothing the sweep printed
    secret = s3_server.KEYS["AWS_SECRET_ACCESS_KEY"].encode()
    fs, path = fsspec.core.url_to_fs(url)
    objects = fs.find(path)
    assert len(objects) > 20 and not [k for k in objects if secret in fs.cat_file(k)]
    assert not [p for p in logs.iterdir() if secret in p.read_bytes()] and secret.decode() not in err + out

    # sound, as `cracklab verify` sees it: on the object store where it verifies ensembles there
    # (until then it says so in one line), and a copy of it on the local disk
    verify = _verify(url)
    assert verify.returncode == 0 or "checks ensembles on a local disk only" in verify.stderr, \
        verify.stdout + verify.stderr
    copy = tmp_path / "copy.zarr"
    fs.get(path, str(copy), recursive=True)
    verify = _verify(copy)
    assert verify.returncode == 0 and "sound" in verify.stdout, verify.stdout + verify.stderr

    # the same study on this machine, one member after the other: the same numbers to the bit
    local = tmp_path / "local.zarr"
    res = CliRunner().invoke(main, ["sweep", str(study), "-o", str(local), "--no-progress", "--scheduler",
                                    "synchronous"])
    assert res.exit_code == 0, res.output
    for s in status:
        a = open_member(url, s["id"]).load()
        b = open_member(str(local), s["id"]).load()
        assert set(a.data_vars) == set(b.data_vars) and a.data_vars, (list(a.data_vars), list(b.data_vars))
        for name in a.variables:
            assert np.array_equal(a[name].values, b[name].values, equal_nan=a[name].dtype.kind == "f"), name
        assert a.attrs["scene"] == b.attrs["scene"]


def test_slurm_refusing_the_jobs_is_one_line_naming_the_option(s3_env, slurm_env, tmp_path):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    assert slurm_env.jobs_end(), "jobs of an earlier test are still in the queue"
    res = subprocess.run([sys.executable, "-m", "cracklab.cli", "sweep", str(study), "-o", url, "--no-progress",
                          "--cluster", "slurm", "--cluster-option", "queue=nosuch", "--cluster-option",
                          "interface=lo"], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    line = error_line(res)
    assert line.startswith("Error: --cluster: sbatch refused the worker jobs: "), line
    assert "partition" in line, line
    assert slurm_env.jobs() == []                     # none was submitted
    assert not _exists(url), "the store was touched before the jobs were refused"


def _verify(store):
    return subprocess.run([sys.executable, "-m", "cracklab.cli", "verify", str(store)], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)


def _exists(url) -> bool:
    fs, path = fsspec.core.url_to_fs(url)
    return fs.exists(path)


@pytest.mark.parametrize("args, expected", [
    (["--cluster", "nosuch"], "Invalid value for '--cluster': 'nosuch' is not one of 'slurm', 'pbs'"),
    (["--cluster", "slurm", "--cluster-option", "queue"], "--cluster-option: expected KEY=VALUE"),
    (["--cluster", "slurm", "--cluster-option", "quee=short"],
     "--cluster-option: 'quee' is not an option of a slurm cluster (did you mean 'queue'?); accepted: "),
    (["--cluster-option", "queue=short"], "--cluster-option is for the jobs of --cluster; give --cluster KIND"),
    (["--cluster", "slurm", "--scheduler", "tcp://127.0.0.1:1"], "give one of --cluster and --scheduler"),
    (["--cluster", "slurm", "--cluster-option", "job_extra_directives=[--exclusive"],
     "--cluster-option: job_extra_directives=[--exclusive: a list or table must be JSON"),
    (["--cluster", "slurm", "--cluster-option", "memory=lots"],
     "--cluster-option: memory='lots': not an amount of memory"),
    (["--cluster", "slurm", "--cluster-option", "processes=0"], "--cluster-option: processes=0: must be a whole "
                                                                 "number >= 1"),
    (["--cluster", "slurm", "--cluster-option", "cores=two"], "--cluster-option: cores='two': must be a whole number"),
    (["--cluster", "slurm", "--cluster-option", "job_script_prologue=module load python"],
     "--cluster-option: job_script_prologue='module load python': must be a list of shell lines"),
    (["--cluster", "slurm", "--cluster-option", "memory=10MB"],
     "--cluster-option: memory=10MB gives each of the job's 1 worker process 9.54 MiB, but the largest member "
     "needs"),
])
def test_bad_cluster_input_is_one_line_before_anything_runs(tmp_path, args, expected):
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    store = tmp_path / "ens.zarr"
    res = CliRunner().invoke(main, ["sweep", str(study), "-o", str(store), "--no-progress", *args])
    assert res.exit_code != 0
    lines = [ln for ln in res.output.splitlines() if ln.startswith("Error:")]
    assert len(lines) == 1 and expected in lines[0], res.output
    assert not store.exists()


def test_no_sbatch_here_is_one_line_naming_the_option(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path / "no-commands"))
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    store = tmp_path / "ens.zarr"
    res = CliRunner().invoke(main, ["sweep", str(study), "-o", str(store), "--no-progress", "--cluster", "slurm"])
    assert res.exit_code == 1
    assert res.output.strip().splitlines()[-1].startswith(
        "Error: --cluster: sbatch not found: --cluster slurm submits its workers with sbatch"), res.output
    assert not store.exists()


def test_ctrl_c_of_a_sweep_on_slurm_cancels_its_jobs(s3_env, slurm_env, tmp_path):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    assert slurm_env.jobs_end(), "jobs of an earlier test are still in the queue"
    driver = subprocess.Popen([sys.executable, "-m", "cracklab.cli", "sweep", str(study), "-o", url, "--no-progress",
                               "--cluster", "slurm", "--workers", "2", "--cluster-option", "interface=lo",
                               "--cluster-option", f"log_directory={tmp_path / 'jobs'}"],
                              cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while len(slurm_env.jobs()) < 2 and driver.poll() is None and time.monotonic() < deadline:
            time.sleep(0.1)
        assert len(slurm_env.jobs()) == 2, "the jobs were not submitted"
        driver.send_signal(signal.SIGINT)
        out, err = driver.communicate(timeout=120)
    finally:
        if driver.poll() is None:
            driver.kill()
            driver.wait()
    assert driver.returncode == 130, err
    assert "rerun the same command to resume" in err, err
    assert "Traceback" not in err, err
    assert slurm_env.active() == []        # no job left holding the node
    assert slurm_env.jobs_end()


RECIPE = """
import sys
from cracklab import ensemble
from dask_jobqueue import SLURMCluster
from distributed import Client

study = ensemble.load_study(sys.argv[1])
with SLURMCluster(cores=1, processes=1, memory="1GB", walltime="00:10:00", interface="lo",
                  log_directory=sys.argv[3]) as cluster, Client(cluster) as client:
    cluster.scale(jobs=2)
    result = ensemble.run_study(study, sys.argv[2], client=client, progress=False)
print(result.summary())
"""


def test_the_python_recipe_a_jobqueue_cluster_of_your_own_and_client(s3_env, slurm_env, tmp_path):
    """docs/guide/cluster.md's recipe: a SLURMCluster made by the user, its Client given to
    the sweep (run(client=...)), in a process of its own."""
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    assert slurm_env.jobs_end(), "jobs of an earlier test are still in the queue"
    res = subprocess.run([sys.executable, "-c", RECIPE, str(study), url, str(tmp_path / "jobs")], cwd=tmp_path,
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert "4 ran" in res.stdout, res.stdout
    status = member_status(url)
    assert len(status) == 4 and all(s["complete"] for s in status), status
    workers = {open_member(url, s["id"]).attrs["worker"] for s in status}
    assert all(int(w.rsplit(":", 1)[1]) != os.getpid() for w in workers), workers
    assert slurm_env.jobs_end()


def test_a_dry_run_shows_the_jobs_it_would_submit_and_submits_none(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path / "no-commands"))      # no sbatch: nothing could be submitted
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    res = CliRunner().invoke(main, ["sweep", str(study), "--dry-run", "--cluster", "slurm", "--workers", "3",
                                    "--cluster-option", "processes=2", "--cluster-option", "queue=short"])
    assert res.exit_code == 0, res.output
    line = next(ln for ln in res.output.splitlines() if ln.strip().startswith("cluster"))
    assert "2 slurm jobs for 3 workers (cores=2, memory=" in line and "processes=2, queue=short); not submitted" \
        in line, line
    res = CliRunner().invoke(main, ["sweep", str(study), "--dry-run", "--cluster", "slurm", "--cluster-option",
                                    "memory=10MB"])
    assert res.exit_code == 1 and "Error: --cluster-option: memory=10MB gives each" in res.output, res.output


@pytest.mark.parametrize("kwargs, expected", [
    ({"cluster": "nosuch"}, "cluster: unknown batch system 'nosuch'; accepted: slurm, pbs, sge, lsf, htcondor, oar, "
                            "moab"),
    ({"cluster": "slurm", "scheduler": "tcp://127.0.0.1:1"}, "cluster: give one of cluster (slurm) and scheduler, "
                                                              "not both"),
    ({"cluster": "pbs", "cluster_options": {"partition": "x"}}, "cluster_options: 'partition' is not an option of a "
                                                                "pbs cluster"),
    ({"cluster": "slurm", "cluster_options": ["queue=short"]}, "cluster_options: must be a dict of options"),
])
def test_bad_cluster_arguments_of_run_are_one_input_error(tmp_path, kwargs, expected):
    from cracklab import ensemble
    from cracklab.errors import InputError

    store = tmp_path / "ens.zarr"
    with pytest.raises(InputError) as info:
        ensemble.run(ensemble.Builder("elliptical_crack", n=16, a=0.25, b=0.2, t_end=0.05), {"p": [1.0]}, store,
                     progress=False, **kwargs)
    assert str(info.value).startswith(expected), str(info.value)
    assert not store.exists()
