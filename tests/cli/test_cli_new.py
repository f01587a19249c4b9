"""`cracklab new`: a scene TOML from a registered builder and key=value arguments, and
`cracklab run BUILDER --set KEY=VALUE`, as processes."""
from __future__ import annotations

import dataclasses

import xarray as xr

import cracklab
from cracklab.model.scene_io import scenes_equal

from cli_process import cli, error_line


# ---------------------------------------------------------------------------- cracklab new
def test_new_writes_the_scene_of_a_builder_with_its_arguments_and_scene_paths(tmp_path):
    out = tmp_path / "tpv3.toml"
    res = cli("new", "tpv3", "dx=4000", "domain=[64000.0, 32000.0]", "t_end=1.5", "record.every=10", "-o", out)
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "tpv3.fields.nc").is_file()             # its fields in the sidecar
    want = cracklab.scenes.tpv3(dx=4000.0, domain=(64000.0, 32000.0), t_end=1.5)
    want = want.replace(record=dataclasses.replace(want.record, every=10))
    back = cracklab.Scene.from_toml(out)
    assert (back.grid.n1, back.grid.n3) == (16, 8) and back.record.every == 10
    assert scenes_equal(back, want)
    assert str(out) in res.stdout
    # an existing file is not replaced but with --overwrite
    line = error_line(cli("new", "tpv3", "dx=2000", "-o", out))
    assert "exists" in line and "--overwrite" in line
    assert cracklab.Scene.from_toml(out).grid.n1 == 16
    assert cli("new", "tpv3", "dx=2000", "-o", out, "--overwrite").returncode == 0
    assert cracklab.Scene.from_toml(out).grid.n1 == 24


def test_new_names_an_unknown_builder_or_argument_and_lists_the_accepted(tmp_path):
    out = tmp_path / "x.toml"
    line = error_line(cli("new", "tpv33", "dx=400", "-o", out))
    assert "'tpv33' is not a scene builder" in line and "tpv3, tpv5" in line
    line = error_line(cli("new", "tpv3", "dxx=400", "-o", out))
    assert "tpv3 takes no argument 'dxx'" in line and "dx, t_end, beta, record, numerics, domain" in line
    line = error_line(cli("new", "tpv3", "dx", "-o", out))
    assert "'dx' is not key=value" in line
    line = error_line(cli("new", "tpv3", "dx=fine", "-o", out))
    assert "dx: not a TOML value, taken as text" in line
    assert not out.exists()


def test_new_list_shows_every_builder_with_its_first_sentence():
    res = cli("new", "--list")
    assert res.returncode == 0, res.stderr
    names = [ln.split()[0] for ln in res.stdout.splitlines()]
    assert set(cracklab.scenes.BUILDERS) <= set(names)
    tpv3 = next(ln for ln in res.stdout.splitlines() if ln.startswith("tpv3 "))
    assert "SCEC TPV3" in tpv3
    asperity = next(ln for ln in res.stdout.splitlines() if ln.startswith("asperity_row "))
    assert asperity.endswith("(section 4, Figs. 12-13).")      # a sentence, not cut at "Figs."


def test_run_takes_a_builder_name_with_its_arguments(tmp_path):
    out = tmp_path / "lamb.zarr"
    res = cli("run", "lamb", "--set", "n=16", "--set", "t_end=0.2", "--set", "record.every=3", "-o", out,
              "--no-progress")
    assert res.returncode == 0, res.stderr
    got = cracklab.scene_of(xr.open_zarr(out, consolidated=False))
    want = cracklab.scenes.lamb(n=16, t_end=0.2)
    assert scenes_equal(got, want.replace(record=dataclasses.replace(want.record, every=3)))
    line = error_line(cli("run", "lamb_typo", "-o", tmp_path / "x.zarr"))
    assert "'lamb_typo': no such file or store, nor a scene builder" in line
    toml = tmp_path / "s.toml"
    assert cli("new", "lamb", "n=16", "t_end=0.2", "-o", toml).returncode == 0
    res = cli("run", toml, "--set", "n=32", "-o", tmp_path / "y.zarr")
    assert res.returncode == 2 and "--set is for a builder's arguments" in res.stderr
    assert not (tmp_path / "x.zarr").exists() and not (tmp_path / "y.zarr").exists()
