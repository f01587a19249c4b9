"""The command line as a user meets it, each through a `python -m cracklab.cli` process:
help, -o everywhere, errors in terms of the options typed, outputs of another scene not
replaced, Ctrl-C, an unreachable scheduler, bad input files, the memory budget and the
dry runs, unfinished and failed results in plots and exports."""
from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import zarr

ROOT = Path(__file__).resolve().parents[2]

SCENE = """
t_end = {t_end}
beta = 0.5
name = "{name}"

[material]
mu = 1.0
cs = 1.0
nu = 0.25

[grid]
n1 = {n}
n3 = {n}
L1 = 1.0
L3 = 1.0

[law]
kind = "linear_cohesive"
tau_c = {tau_c}
delta_c = 0.01

[loading]
tau0_2 = 1.2

[record]
fields = ["delta_2"]
every = {every}
{extra}
"""


def scene_toml(path, *, n=16, t_end=0.05, tau_c=1.0, name="manners", every=2, extra="", engine=None):
    text = SCENE.format(n=n, t_end=t_end, tau_c=tau_c, name=name, every=every, extra=extra)
    if engine:
        text += f'\n[numerics]\nengine = "{engine}"\n'
    path.write_text(text)
    return path


def cli(*args, env=None, timeout=600, **kwargs):
    return subprocess.run([sys.executable, "-m", "cracklab.cli", *map(str, args)], cwd=ROOT,
                          env={**os.environ, **(env or {})}, capture_output=True, text=True, timeout=timeout,
                          **kwargs)


def one_error_line(res):
    """The stderr of a failed command: one line, 'Error: ...', no traceback."""
    assert res.returncode != 0, res.stdout
    assert "Traceback" not in res.stderr, res.stderr
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("Error: "), res.stderr
    return lines[0]


STUDY = """
[study]
name = "{name}"
builder = "elliptical_crack"
[base]
n = {n}
a = 0.25
b = 0.2
t_end = {t_end}
record.every = {every}
"""


def study_toml(path, *, name="manners", t_end=0.05, sweep="[sweep]\np = [1.0, 1.2]", n=16, every=2):
    path.write_text(STUDY.format(name=name, t_end=t_end, n=n, every=every) + "\n" + sweep + "\n")
    return path


# ---------------------------------------------------------------------------- help and -o
def test_every_command_takes_h_and_o():
    from cracklab.cli import main

    assert set(main.commands) == {"new", "run", "sweep", "plot", "export", "summary", "verify", "bench", "demo"}
    for command in main.commands:
        res = cli(command, "-h")
        assert res.returncode == 0 and "Usage:" in res.stdout and "-h, --help" in res.stdout, (command, res.stderr)
        if command != "verify":                 # verify writes nothing
            assert "-o, --" in res.stdout, command
    top = cli("-h")
    assert top.returncode == 0 and "Commands:" in top.stdout


def test_bench_options_have_help_choices_and_flag_errors(tmp_path):
    res = cli("bench", "-h")
    for text in ("Nodes along x1", "History engine", "Steps of the run", "[exponential|direct|auto]"):
        assert text in res.stdout, text
    bad = cli("bench", "--engine", "fast")
    assert bad.returncode == 2 and "Invalid value for '--engine'" in bad.stderr and "'fast'" in bad.stderr
    assert "Traceback" not in bad.stderr
    odd = one_error_line(cli("bench", "--n1", "97", "--n3", "16", "--steps", "4"))
    assert odd.startswith("Error: --n1 (grid.n1):"), odd           # the option typed, and the scene field
    law = one_error_line(cli("bench", "--n1", "16", "--n3", "16", "--steps", "4", "--law", "slip_weakening",
                             "--mode", "I"))
    assert law.startswith("Error: --mode: the slip_weakening bench is a shear rupture"), law
    out = tmp_path / "bench.json"
    ok = cli("bench", "--n1", "16", "--n3", "16", "--steps", "10", "-o", out)
    assert ok.returncode == 0, ok.stderr
    assert json.loads(out.read_text())["ms_per_step"] > 0


def test_export_takes_o_and_the_old_netcdf_flag(tmp_path):
    store = tmp_path / "a.zarr"
    assert cli("run", scene_toml(tmp_path / "s.toml", t_end=0.4), "-o", store).returncode == 0
    for flag, name in (("-o", "a.nc"), ("--output", "b.nc"), ("--netcdf", "c.nc")):
        res = cli("export", store, flag, tmp_path / name)
        assert res.returncode == 0, res.stderr
        assert xr.open_dataset(tmp_path / name).delta_2.sizes["t"] == 7      # 13 steps, every 2


# ---------------------------------------------------------------------------- outputs of another scene
def test_run_refuses_to_replace_another_scenes_run_unless_overwrite(tmp_path):
    out = tmp_path / "out.zarr"
    a = scene_toml(tmp_path / "a.toml", tau_c=1.0, name="a")
    b = scene_toml(tmp_path / "b.toml", tau_c=1.1, name="b")
    assert cli("run", a, "-o", out).returncode == 0
    before = xr.open_zarr(out, consolidated=False).delta_2.values
    line = one_error_line(cli("run", b, "-o", out))
    assert "holds the run of another scene (scene 'a', status complete); refusing to replace it" in line
    assert "--overwrite" in line
    after = xr.open_zarr(out, consolidated=False)
    assert after.attrs["cracklab_status"] == "complete" and json.loads(after.attrs["scene"])["name"] == "a"
    np.testing.assert_array_equal(after.delta_2.values, before)
    again = cli("run", a, "-o", out)                 # the same scene: nothing to do
    assert again.returncode == 0 and "nothing to do" in again.stdout
    res = cli("run", b, "-o", out, "--overwrite")
    assert res.returncode == 0, res.stderr
    assert json.loads(xr.open_zarr(out, consolidated=False).attrs["scene"])["name"] == "b"


def test_export_refuses_to_replace_another_file_unless_overwrite(tmp_path):
    a, b = tmp_path / "a.zarr", tmp_path / "b.zarr"
    assert cli("run", scene_toml(tmp_path / "a.toml", name="a"), "-o", a).returncode == 0
    assert cli("run", scene_toml(tmp_path / "b.toml", name="b", tau_c=1.1), "-o", b).returncode == 0
    nc = tmp_path / "x.nc"
    nc.write_text("precious notes")
    line = one_error_line(cli("export", a, "-o", nc))
    assert line.startswith("Error: -o (output):") and "--overwrite" in line
    assert nc.read_text() == "precious notes"
    assert cli("export", a, "-o", nc, "--overwrite").returncode == 0
    assert cli("export", a, "-o", nc).returncode == 0              # the same scene again: replaced
    one_error_line(cli("export", b, "-o", nc))                      # another scene's export: refused
    assert json.loads(xr.open_dataset(nc).attrs["scene"])["name"] == "a"


def test_sweep_refuses_another_study_in_the_store_unless_overwrite(tmp_path):
    out = tmp_path / "ens.zarr"
    first = study_toml(tmp_path / "one.toml", name="one")
    assert cli("sweep", first, "-o", out, "--scheduler", "synchronous", "--no-progress").returncode == 0
    other = study_toml(tmp_path / "two.toml", name="two", sweep="[sweep]\np = [1.4]")
    line = one_error_line(cli("sweep", other, "-o", out, "--scheduler", "synchronous"))
    assert "another study ('one'" in line and "--overwrite" in line
    assert len(zarr.open_group(str(out), mode="r").attrs["members"]) == 2
    res = cli("sweep", other, "-o", out, "--scheduler", "synchronous", "--overwrite", "--no-progress")
    assert res.returncode == 0, res.stderr
    root = zarr.open_group(str(out), mode="r")
    assert len(root.attrs["members"]) == 1 and sorted(root["members"].group_keys()) == root.attrs["members"]


# ---------------------------------------------------------------------------- Ctrl-C
def _until(cond, proc, timeout=300):
    deadline = time.time() + timeout
    while time.time() < deadline:
        if cond():
            return True
        if proc.poll() is not None:
            return False
        time.sleep(0.05)
    return False


def test_ctrl_c_stops_a_run_at_a_step_and_the_same_command_resumes(tmp_path):
    toml = scene_toml(tmp_path / "s.toml", n=64, t_end=40.0, every=50, engine="exponential")
    out = tmp_path / "out.zarr"
    cmd = [sys.executable, "-m", "cracklab.cli", "run", str(toml), "-o", str(out), "--no-progress"]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        assert _until(lambda: (out / "delta_2").is_dir(), proc)
        time.sleep(1.0)
        os.killpg(proc.pid, signal.SIGINT)          # as the terminal does: the whole process group
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("cracklab: interrupted at step "), err
    assert lines[0].endswith("; rerun the same command to resume")
    step = int(lines[0].split("at step ")[1].split(";")[0])
    attrs = json.loads((out / "zarr.json").read_text())["attributes"]
    assert attrs["cracklab_status"] == "running" and attrs["cracklab_checkpoint_step"] == step
    # the same command goes on from there (a shorter end keeps the test quick)
    res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert xr.open_zarr(out, consolidated=False).attrs["cracklab_status"] == "complete"


def test_ctrl_c_stops_a_sweep_without_worker_tracebacks(tmp_path):
    study = study_toml(tmp_path / "s.toml", t_end=40.0, n=64, every=100, sweep="[sweep]\np = [1.0, 1.1, 1.2]")
    out = tmp_path / "ens.zarr"
    proc = subprocess.Popen([sys.executable, "-m", "cracklab.cli", "sweep", str(study), "-o", str(out),
                             "--workers", "2", "--no-progress"], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)

    def running():
        d = out / "members"
        return d.is_dir() and any((m / "delta_2").is_dir() for m in d.iterdir())
    try:
        assert _until(running, proc)
        time.sleep(1.0)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    # one line; how many members finished before the signal depends on the machine's speed
    assert len(lines) == 1 and re.fullmatch(r"cracklab: interrupted with [0-2] of 3 members complete; rerun the "
                                            r"same command to resume", lines[0]), err


# ---------------------------------------------------------------------------- scheduler, bad files, stations
def test_an_unreachable_scheduler_fails_fast_and_writes_nothing(tmp_path):
    with socket.socket() as s:          # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "ens.zarr"
    t0 = time.perf_counter()
    res = cli("sweep", study_toml(tmp_path / "s.toml"), "-o", out, "--scheduler", f"tcp://127.0.0.1:{port}")
    elapsed = time.perf_counter() - t0
    line = one_error_line(res)
    assert line.startswith(f"Error: --scheduler: cannot connect to the dask scheduler at 'tcp://127.0.0.1:{port}'")
    assert "store" not in line.split("(")[0]
    assert elapsed < 20, elapsed                    # 5 s of connection attempts, and the imports
    assert not out.exists()


def test_binary_and_empty_input_files_are_one_line(tmp_path):
    garbage = bytes(range(256)) * 4
    for name in ("garbage.toml", "garbage.bin"):
        (tmp_path / name).write_bytes(b"\x89PNG" + garbage)
        line = one_error_line(cli("run", tmp_path / name, "-o", tmp_path / "x.zarr"))
        assert "not valid TOML: not UTF-8 text" in line, line
    empty = tmp_path / "empty.toml"
    empty.write_text("# nothing here\n\n")
    assert "is empty: no TOML tables or keys (expected a scene" in one_error_line(
        cli("run", empty, "-o", tmp_path / "x.zarr"))
    assert "is empty: no TOML tables or keys (expected a study" in one_error_line(
        cli("sweep", empty, "-o", tmp_path / "e.zarr"))
    (tmp_path / "garbage.study").write_bytes(garbage)
    assert "not UTF-8" in one_error_line(cli("sweep", tmp_path / "garbage.study", "-o", tmp_path / "e.zarr"))
    assert not (tmp_path / "x.zarr").exists() and not (tmp_path / "e.zarr").exists()


def test_a_station_with_one_coordinate_on_a_3d_grid_is_refused(tmp_path):
    toml = scene_toml(tmp_path / "s.toml", extra="stations = { A = [0.5] }")
    line = one_error_line(cli("run", toml, "-o", tmp_path / "x.zarr"))
    assert line.startswith("Error: record.stations.A: (0.5,) gives x1 only: on a 3D grid (n3 = 16)"), line
    import cracklab

    plane = cracklab.scenes.lamb(n=16, t_end=0.05)
    g = plane.grid
    ok = cracklab.Record(fields=(), stations={"A": (0.5,)})
    ok.station_nodes(cracklab.Grid(n1=g.n1, n3=1, L1=g.L1, L3=1.0))      # the plane problem: x1 alone


# ---------------------------------------------------------------------------- plot options
@pytest.fixture(scope="module")
def ensemble(tmp_path_factory):
    d = tmp_path_factory.mktemp("ens")
    study = study_toml(d / "s.toml", sweep="[sweep]\np = [1.0, 1.2]\n\n[[members]]\nbeta = 10.0\n\n"
                                           "[[members]]\np = 1e308")
    out = d / "ens.zarr"
    res = cli("sweep", study, "-o", out, "--scheduler", "synchronous", "--no-progress")
    assert res.returncode == 1          # two members failed: a bad value, a blow-up
    from cracklab.ensemble import member_status

    status = member_status(out)
    return out, {("ok" if s["complete"] else "build" if "InputError" in s["error"] else "blowup"): s["id"]
                 for s in status}


def test_plot_member_by_and_time_errors(tmp_path, ensemble):
    store, ids = ensemble
    line = one_error_line(cli("plot", store, "--kind", "snapshot", "--member", "99"))
    assert "--member 99: no such member; the store has 4 members (positions 0 to 3" in line
    line = one_error_line(cli("plot", store, "--kind", "snapshot", "--member", "abc"))
    assert "--member abc: not a member id of this store" in line
    line = one_error_line(cli("plot", store, "--kind", "summary", "--by", "nope"))
    assert line.startswith("Error: --by nope: not a swept parameter of this ensemble; choose one of: p"), line
    line = one_error_line(cli("plot", store, "--kind", "snapshot", "--member", ids["ok"], "--time", "99"))
    assert "--time 99: outside the snapshots, t = 0 to" in line
    run = tmp_path / "r.zarr"
    assert cli("run", scene_toml(tmp_path / "s.toml"), "-o", run).returncode == 0
    assert "--member: " in one_error_line(cli("plot", run, "--member", "1"))
    assert "--field v_3: not recorded in this result; recorded: delta_2" in one_error_line(
        cli("plot", run, "--kind", "snapshot", "--field", "v_3"))
    ok = cli("plot", run, "--kind", "snapshot", "--time", "0.02", "-o", tmp_path / "snap.png")
    assert ok.returncode == 0 and (tmp_path / "snap.png").stat().st_size > 0


def test_summary_prints_the_table_or_writes_csv(tmp_path, ensemble):
    """`cracklab summary` as a process: one row per member (the failed ones with their
    status and error), the parameters first; -o writes the same table as CSV."""
    import pandas as pd

    store, ids = ensemble
    res = cli("summary", store)
    assert res.returncode == 0 and res.stderr == "", res.stderr
    lines = res.stdout.splitlines()
    header = lines[0].split()
    assert header.index("p") < header.index("status") < header.index("crack_length"), lines[0]
    rows = {ln.split()[0]: ln for ln in lines[1:] if ln.strip() and ln.split()[0] in ids.values()}
    assert len(rows) == 3 and "failed" in rows[ids["build"]] and "failed" in rows[ids["blowup"]]
    assert "complete" in rows[ids["ok"]]
    csv = tmp_path / "t.csv"
    res = cli("summary", store, "-o", csv)
    assert res.returncode == 0 and res.stdout.strip() == f"cracklab: wrote {csv} (4 rows)", res.stdout
    table = pd.read_csv(csv, index_col="member")
    assert len(table) == 4 and set(table.loc[list(ids.values()), "status"]) == {"complete", "failed"}
    assert table.loc[ids["ok"], "crack_length"] > 0 and np.isnan(table.loc[ids["build"], "crack_length"])
    assert table.loc[ids["build"], "error"].startswith("InputError: beta")
    line = one_error_line(cli("summary", tmp_path))
    assert line.startswith("Error: store:"), line


# ---------------------------------------------------------------------------- failed and unfinished results
def test_a_failed_member_is_refused_unless_allow_partial(tmp_path, ensemble):
    store, ids = ensemble
    for key in ("build", "blowup"):
        nc = tmp_path / f"{key}.nc"
        line = one_error_line(cli("export", store, "--member", ids[key], "-o", nc))
        assert line.startswith(f"Error: --member: member {ids[key]} ") and "failed (" in line, line
        assert not nc.exists()
        line = one_error_line(cli("plot", store, "--member", ids[key], "-o", tmp_path / key))
        assert "failed (" in line and "--allow-partial" in line
    # a member that failed before it ran holds no data, even with --allow-partial
    line = one_error_line(cli("export", store, "--member", ids["build"], "-o", tmp_path / "b.nc", "--allow-partial"))
    assert "holds no data" in line and not (tmp_path / "b.nc").exists()
    # the blow-up recorded its first snapshots: exported and drawn when asked
    res = cli("export", store, "--member", ids["blowup"], "-o", tmp_path / "p.nc", "--allow-partial")
    assert res.returncode == 0, res.stderr
    assert "is failed (non-finite v_2 at step 2" in res.stderr and xr.open_dataset(tmp_path / "p.nc").sizes["t"] >= 1
    res = cli("plot", store, "--member", ids["blowup"], "--kind", "snapshot", "-o", tmp_path / "p.png",
              "--allow-partial")
    assert res.returncode == 0 and (tmp_path / "p.png").exists(), res.stderr
    # the whole ensemble: the complete members, the others named
    res = cli("plot", store, "--kind", "summary", "-o", tmp_path / "sum.png")
    assert res.returncode == 0 and "2 failed of 4 members" in res.stderr and "the figures show 2 members" in res.stderr


def test_plot_and_export_of_an_unfinished_run_show_what_exists(tmp_path, monkeypatch):
    """A run stopped after step 300 of 384 (checkpoint after step 200): the figures and the
    export show its complete snapshots (those flushed: the checkpoint's 51, then 8 at a
    time), equal to an uninterrupted run's, and the rupture times of its checkpoint."""
    import cracklab
    from tests.interrupt import interrupted_run

    scene = cracklab.scenes.elliptical_crack(n=32, a=0.25, b=0.2, t_end=6.0,
                                             record=cracklab.Record(fields=("delta_2", "v_2"), every=4))
    store = tmp_path / "unfinished.zarr"
    interrupted_run(scene, store, monkeypatch, stop=300, checkpoint_every=100)
    full = cracklab.simulate(scene)
    res = cli("plot", store, "-o", tmp_path / "figs")
    assert res.returncode == 0, res.stderr
    assert "is unfinished (status running): 75 of 97 snapshots written, checkpoint after step 200" in res.stderr
    written = {p.name for p in (tmp_path / "figs").iterdir()}
    assert {"delta_2.png", "rupture_time.png", "crack_length.png", "delta_2.gif"} <= written
    # --kind snapshot draws the last complete snapshot (the 75th), not an empty frame of the last time
    res = cli("plot", store, "--kind", "snapshot", "-o", tmp_path / "snap.png")
    assert res.returncode == 0 and "is unfinished" in res.stderr, res.stderr
    from PIL import Image

    from cracklab import plots as P

    P.snapshot(full.isel(t=slice(0, 75)), "delta_2", path=tmp_path / "expected.png")
    P.snapshot(full, "delta_2", path=tmp_path / "last.png")                 # the run's last time
    P.snapshot(full.where(full.t < 0), "delta_2", path=tmp_path / "empty.png")   # an empty (all-NaN) frame
    drawn, expected, last, empty = (np.asarray(Image.open(tmp_path / n).convert("L"), dtype=float)
                                    for n in ("snap.png", "expected.png", "last.png", "empty.png"))
    assert drawn.shape == expected.shape

    def differ(a, b):
        return np.mean(np.abs(a - b) > 8)          # the fraction of pixels that differ
    assert differ(drawn, expected) < 0.002         # the same figure (measured: 0)
    assert differ(last, expected) > 0.005 and differ(empty, expected) > 0.1      # (measured: 0.010, 0.42)
    nc = tmp_path / "u.nc"
    res = cli("export", store, "-o", nc)
    assert res.returncode == 0 and "exported 75 snapshots" in res.stderr, res.stderr
    ds = xr.open_dataset(nc)
    assert ds.sizes["t"] == 75 and np.isfinite(ds.delta_2.values).all()
    np.testing.assert_allclose(ds.delta_2.values, full.delta_2.values[:75], rtol=1e-12, atol=0)


@pytest.fixture(scope="module")
def big_store(tmp_path_factory):
    """A 1024 x 1024 run of 240 snapshots (1.9 GB of delta_2 in memory) left unfinished
    with 100 of them written (800 MB)."""
    import cracklab
    from cracklab.output.simulate import Recorder

    scene = cracklab.scenes.lamb(n=1024, t_end=239 * 0.5 / 1024 * (1 - 1e-9),
                                 record=cracklab.Record(fields=("delta_2",), every=1))
    store = tmp_path_factory.mktemp("big") / "big.zarr"
    rec = Recorder(scene, str(store), store)
    rec.create()
    g = zarr.open_group(str(store), mode="a")
    assert g["delta_2"].shape == (240, 1024, 1024)
    x = np.linspace(0.0, 1.0, 1024)
    for k in range(100):
        g["delta_2"][k] = (k + 1) * 1e-3 * np.add.outer(x, x)
    assert g.attrs["cracklab_status"] == "running"
    return store


#: `cracklab ARGS` in a process that reports its own peak resident memory (VmHWM) as it exits:
#: the rusage of a child is no measure, since Linux counts into it the parent's peak at the
#: exec (the test process's, when subprocess spawns by vfork)
PEAK = ("import atexit, sys\n"
        "def peak():\n"
        "    with open('/proc/self/status') as fh:\n"
        "        kb = next(line.split()[1] for line in fh if line.startswith('VmHWM'))\n"
        "    print('VmHWM', kb, file=sys.stderr)\n"
        "atexit.register(peak)\n"
        "from cracklab.cli import main\n"
        "main(prog_name='cracklab')\n")


def _peak_mb(*args):
    """Run ``cracklab ARGS`` as a process; (its stderr without the peak, its peak resident
    memory in MB)."""
    res = subprocess.run([sys.executable, "-c", PEAK, *map(str, args)], cwd=ROOT, capture_output=True, text=True,
                         timeout=600)
    assert res.returncode == 0, res.stderr
    err, _, kb = res.stderr.rpartition("VmHWM ")
    return err, int(kb) / 1024


def test_plot_of_a_large_unfinished_store_stays_in_bounded_memory(tmp_path, big_store):
    """All figures of the large unfinished store in a process whose peak resident memory
    stays below 700 MB (the figures read one thinned frame at a time)."""
    out = tmp_path / "figs"
    err, peak_mb = _peak_mb("plot", big_store, "-o", out)
    assert "100 of 240 snapshots written" in err
    assert (out / "delta_2.png").exists() and (out / "delta_2.gif").exists()
    assert peak_mb < 700, peak_mb


def test_export_of_a_large_unfinished_store_stays_in_bounded_memory(tmp_path, big_store):
    """Its netCDF export (800 MB of snapshots) takes less than 400 MB more resident memory
    than the export of a small run in the same conditions (measured alone: 305 and 290 MB
    peaks): read and written chunk by chunk."""
    small = tmp_path / "small.zarr"
    assert cli("run", scene_toml(tmp_path / "s.toml"), "-o", small).returncode == 0
    _, base_mb = _peak_mb("export", small, "-o", tmp_path / "small.nc")
    nc = tmp_path / "big.nc"
    err, peak_mb = _peak_mb("export", big_store, "-o", nc)
    assert "exported 100 snapshots" in err, err
    assert peak_mb - base_mb < 400, (peak_mb, base_mb)
    import netCDF4

    with netCDF4.Dataset(nc) as ds:
        assert ds["delta_2"].shape == (100, 1024, 1024)
        x = np.linspace(0.0, 1.0, 1024)
        np.testing.assert_allclose(ds["delta_2"][99], 0.1 * np.add.outer(x, x), rtol=1e-12)


def test_an_unfinished_member_is_named_and_shown_up_to_what_it_wrote(tmp_path, monkeypatch):
    """A sweep stopped (as by a kill) during its second member: the figures of the whole
    ensemble show the complete one and name the other, the member's own figures and export
    say it is unfinished and hold only its written snapshots, and the ensemble export
    leaves it out with a note."""
    from cracklab import ensemble as E
    from tests.interrupt import SIM

    real, calls = SIM.Recorder.__call__, []

    def stopped(self, state):
        real(self, state)
        if state.n == 0:
            calls.append(1)
        if len(calls) == 2 and state.n == 300:
            raise KeyboardInterrupt
    monkeypatch.setattr(SIM.Recorder, "__call__", stopped)
    store = tmp_path / "ens.zarr"
    base = E.Builder("elliptical_crack", n=32, a=0.25, b=0.2, t_end=6.0)
    with pytest.raises(KeyboardInterrupt):
        E.run(base, E.Sweep(product={"p": [1.0, 1.2]}, base={"record.every": 4}), store, scheduler="synchronous",
              progress=False)
    monkeypatch.setattr(SIM.Recorder, "__call__", real)
    status = E.member_status(store)
    assert [s["status"] for s in status] == ["complete", "running"]
    done, left = status[0]["id"], status[1]["id"]

    res = cli("plot", store, "-o", tmp_path / "figs")
    assert res.returncode == 0, res.stderr
    assert f"1 unfinished of 2 members ({left}); the figures show 1 member\n" in res.stderr, res.stderr
    assert (tmp_path / "figs" / "crack_length.png").exists()
    res = cli("plot", store, "--member", "1", "--kind", "snapshot", "-o", tmp_path / "m.png")
    assert res.returncode == 0 and (tmp_path / "m.png").exists(), res.stderr
    note = re.search(rf"member {left} is unfinished \(status running\): (\d+) of 97 snapshots written", res.stderr)
    assert note, res.stderr
    written = int(note.group(1))
    assert 0 < written < 97
    res = cli("export", store, "--member", left, "-o", tmp_path / "m.nc")
    assert res.returncode == 0 and f"exported {written} snapshots" in res.stderr, res.stderr
    ds = xr.open_dataset(tmp_path / "m.nc")
    assert ds.sizes["t"] == written and np.isfinite(ds.delta_2.values).all()
    res = cli("export", store, "-o", tmp_path / "all.nc")
    assert res.returncode == 0 and f"1 member not complete left out: {left}" in res.stderr, res.stderr
    assert list(xr.open_dataset(tmp_path / "all.nc").member.values) == [done]
