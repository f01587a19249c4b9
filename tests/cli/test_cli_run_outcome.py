"""`cracklab run` as a newcomer meets it: how a run ended, field files from other folders,
the disk check and its dry run, and messages that name only what the user typed."""
from __future__ import annotations

import json
import os

import numpy as np
import xarray as xr
from click.testing import CliRunner

import cracklab
from cracklab.cli import main
from cracklab.output import disk

from cli_process import cli, error_line
from field_scene import GRID, toml
from interrupt import interrupted_run


def small_scene(tmp_path, name="s.toml", **args):
    sc = cracklab.scenes.elliptical_crack(**{"n": 16, "a": 0.25, "b": 0.2, "t_end": 0.3, **args})
    return sc.to_toml(tmp_path / name), sc


# ---------------------------------------------------------------------------- how a run ended
def test_run_says_how_it_ended_on_stderr(tmp_path, monkeypatch):
    toml, sc = small_scene(tmp_path)
    out = tmp_path / "a.zarr"
    res = cli("run", toml, "-o", out, "--no-progress")
    assert res.returncode == 0, res.stderr
    unit = sc.units["time"]
    assert f"cracklab: complete: ran {sc.nsteps} steps (t = {sc.nsteps * sc.dt:.4g}" \
           f"{'' if unit == '1' else ' ' + unit} simulated) in " in res.stderr
    assert " wall" in res.stderr and f"cracklab: wrote {out}" in res.stdout
    # a run stopped after step 5 (checkpoints every 2 steps) goes on from its checkpoint
    part = interrupted_run(sc, tmp_path / "b.zarr", monkeypatch, stop=5, checkpoint_every=2)
    res = cli("run", toml, "-o", part, "--no-progress")
    assert res.returncode == 0, res.stderr
    assert f"complete: resumed from step 4, ran steps 5 to {sc.nsteps} " in res.stderr, res.stderr
    # a blow-up: the error, after how long, and where the record is kept
    bad, _ = small_scene(tmp_path, "bad.toml", p=1e308)
    # (the warnings of the blow-up are shown once: showing them once made the run loop on them)
    res = cli("run", bad, "-o", tmp_path / "bad.zarr", "--no-progress", timeout=120)
    assert res.returncode == 1 and "Traceback" not in res.stderr, res.stderr
    errors = [ln for ln in res.stderr.splitlines() if ln.startswith("Error: ")]
    assert len(errors) == 1, res.stderr
    line = errors[0]
    assert line.startswith("Error: the run failed after ") and " at step " in line
    assert line.endswith(f"what was recorded up to it is kept in {tmp_path / 'bad.zarr'} (status failed)")
    assert xr.open_zarr(tmp_path / "bad.zarr", consolidated=False).attrs["cracklab_status"] == "failed"


# ---------------------------------------------------------------------------- field files elsewhere
FIELD_SCENE = toml('tau_c = { file = "../data/tau.nc", var = "tau_c" }')


def test_allow_files_lets_run_and_sweep_read_a_field_from_another_folder(tmp_path):
    grid = GRID
    (tmp_path / "data").mkdir()
    (tmp_path / "case").mkdir()
    tau = 1.0 + np.arange(grid.n1 * grid.n3, dtype=float).reshape(grid.shape) / 100
    xr.Dataset({"tau_c": (("x1", "x3"), tau)}, coords={"x1": grid.x1, "x3": grid.x3}).to_netcdf(
        tmp_path / "data" / "tau.nc")
    toml = tmp_path / "case" / "s.toml"
    toml.write_text(FIELD_SCENE)
    line = error_line(cli("run", toml, "-o", tmp_path / "a.zarr"))
    assert "outside the scene file's folder" in line and "--allow-files" in line
    res = cli("run", toml, "-o", tmp_path / "a.zarr", "--no-progress", "--allow-files", tmp_path / "data")
    assert res.returncode == 0, res.stderr
    assert np.array_equal(cracklab.scene_of(xr.open_zarr(tmp_path / "a.zarr", consolidated=False)).law.tau_c, tau)
    study = tmp_path / "case" / "study.toml"
    study.write_text('[study]\nname = "files"\nscene = "s.toml"\n[sweep]\n"loading.tau0_2" = [0.5, 0.6]\n')
    line = error_line(cli("sweep", study, "--dry-run"))
    assert "outside the scene file's folder" in line
    res = cli("sweep", study, "--dry-run", "--allow-files", tmp_path / "data")
    assert res.returncode == 0, res.stderr
    assert "members   2" in res.stdout


# ---------------------------------------------------------------------------- the disk
def test_the_disk_check_is_reported_by_the_dry_run_and_skipped_on_request(tmp_path, monkeypatch):
    toml, sc = small_scene(tmp_path)
    out = tmp_path / "a.zarr"
    size = disk.output_size(sc)
    res = cli("run", toml, "--dry-run", "-o", out)
    assert res.returncode == 0, res.stderr
    assert f"  disk      output {size.describe()}; " in res.stdout and " free where " in res.stdout
    assert ": fits" in res.stdout.split("disk      ")[1].splitlines()[0]
    study = tmp_path / "study.toml"
    study.write_text('[study]\nname = "d"\nbuilder = "elliptical_crack"\n[base]\nn = 16\na = 0.25\nb = 0.2\n'
                     't_end = 0.3\n[sweep]\np = [1.0, 1.1, 1.2]\n')
    res = cli("sweep", study, "--dry-run", "--workers", "1")
    assert res.returncode == 0, res.stderr
    assert "  disk      3 members' output at most " in res.stdout and "free in the current directory" in res.stdout
    # a disk that is (made) nearly full: refused, said by the dry run, run with --no-disk-check
    monkeypatch.setattr(disk, "free_space", lambda path: 1000)
    runner = CliRunner()
    res = runner.invoke(main, ["run", str(toml), "-o", str(out), "--no-progress"])
    assert res.exit_code == 1 and "its file system has 1000 B free" in res.output, res.output
    assert "--no-disk-check" in res.output and not out.exists()
    res = runner.invoke(main, ["run", str(toml), "--dry-run", "-o", str(out)])
    assert res.exit_code == 1 and "does NOT fit: the run would be refused (--no-disk-check" in res.output
    res = runner.invoke(main, ["sweep", str(study), "-o", str(tmp_path / "e.zarr"), "--scheduler", "synchronous",
                               "--no-progress"])
    assert res.exit_code == 1 and "1000 B free" in res.output, res.output
    res = runner.invoke(main, ["run", str(toml), "-o", str(out), "--no-progress", "--no-disk-check"])
    assert res.exit_code == 0, res.output
    assert xr.open_zarr(out, consolidated=False).attrs["cracklab_status"] == "complete"
    res = runner.invoke(main, ["sweep", str(study), "-o", str(tmp_path / "e.zarr"), "--scheduler", "synchronous",
                               "--no-progress", "--no-disk-check"])
    assert res.exit_code == 0, res.output


# ---------------------------------------------------------------------------- messages
def test_overwrite_says_it_replaces_only_cracklab_stores(tmp_path):
    toml, _ = small_scene(tmp_path)
    notes = tmp_path / "notes.txt"
    notes.write_text("precious")
    plain = error_line(cli("run", toml, "-o", notes))
    assert "refusing to overwrite it" in plain and "--overwrite" not in plain
    line = error_line(cli("run", toml, "-o", notes, "--overwrite"))
    assert "--overwrite replaces only cracklab run stores" in line
    assert notes.read_text() == "precious"


def test_a_url_store_is_checkpointed_and_resumed_like_a_path(tmp_path):
    toml, sc = small_scene(tmp_path)
    url = f"memory://clirun-{os.getpid()}.zarr"
    runner = CliRunner()
    res = runner.invoke(main, ["run", str(toml), "-o", url, "--no-progress"])
    assert res.exit_code == 0, res.output
    assert "without checkpoints" not in res.output
    assert xr.open_zarr(url, consolidated=False).attrs["cracklab_status"] == "complete"
    res = runner.invoke(main, ["run", str(toml), "-o", url, "--resume"])
    assert res.exit_code == 0 and "holds this run, complete (checked); nothing to do" in res.output, res.output
    assert json.loads(xr.open_zarr(url, consolidated=False).attrs["scene"])["name"] == sc.name
