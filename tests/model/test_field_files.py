"""Fields in TOML scenes read from files (netCDF, Zarr, .npy), checked against the grid,
and the sidecar of ``Scene.to_toml(path)``: a short TOML plus one netCDF file, read back
bit for bit."""
from __future__ import annotations

import os

import numpy as np
import pytest
import xarray as xr

from cracklab import (Grid, InputError, LinearCohesive, Loading, Material, Record, Scene, scene_of, scenes,
                      simulate)
from cracklab.model.scene_io import scene_to_toml, scenes_equal
from field_scene import GRID, HEAD, toml

RNG = np.random.default_rng(7)
TAU_C = 1.0 + RNG.random(GRID.shape)
CRACK = np.zeros(GRID.shape, bool)
CRACK[:3] = True



def field_dataset(values=TAU_C, x1=None, x3=None, dims=("x1", "x3"), name="tau_c"):
    x1 = GRID.x1 if x1 is None else x1
    x3 = GRID.x3 if x3 is None else x3
    coords = {"x1": x1, "x3": x3}
    if dims == ("x3", "x1"):
        values = values.T
    return xr.Dataset({name: (dims, values)}, coords=coords)


def write(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def refused(path, field):
    with pytest.raises(InputError) as err:
        Scene.from_toml(path)
    assert err.value.field == field, str(err.value)
    return str(err.value)


# ------------------------------------------------------------------------ reading
@pytest.mark.parametrize("fmt", ["nc", "zarr", "npy"])
def test_a_field_is_read_from_each_format(tmp_path, fmt):
    data = tmp_path / "fields"
    data.mkdir()
    if fmt == "nc":
        field_dataset().to_netcdf(data / "toughness.nc")
        ref = '{ file = "fields/toughness.nc", var = "tau_c" }'
    elif fmt == "zarr":
        field_dataset().to_zarr(data / "toughness.zarr", consolidated=False)
        ref = '{ file = "fields/toughness.zarr", var = "tau_c" }'
    else:
        np.save(data / "toughness.npy", TAU_C)
        ref = '{ file = "fields/toughness.npy" }'
    path = write(tmp_path, toml(f"tau_c = {ref}"))
    sc = Scene.from_toml(path)
    assert sc.law.tau_c.dtype == np.float64 and np.array_equal(sc.law.tau_c, TAU_C)


def test_paths_are_relative_to_the_scene_file_not_the_current_directory(tmp_path, monkeypatch):
    case = tmp_path / "case"
    case.mkdir()
    field_dataset().to_netcdf(case / "toughness.nc")
    path = write(case, toml('tau_c = { file = "toughness.nc", var = "tau_c" }'))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    assert np.array_equal(Scene.from_toml(path).law.tau_c, TAU_C)
    assert np.array_equal(Scene.from_toml(os.path.relpath(path)).law.tau_c, TAU_C)   # a string path too
    # TOML text: relative to base (default: the current directory)
    text = path.read_text()
    assert np.array_equal(Scene.from_toml(text, base=case).law.tau_c, TAU_C)
    msg = refused_text(text)
    assert "no such file 'toughness.nc'" in msg and "the current directory" in msg


def refused_text(text, field="law.tau_c"):
    with pytest.raises(InputError) as err:
        Scene.from_toml(text)
    assert err.value.field == field, str(err.value)
    return str(err.value)


def test_dims_in_either_order_masks_and_loads(tmp_path):
    ds = field_dataset(dims=("x3", "x1"))
    ds["crack"] = (("x1", "x3"), CRACK.astype(np.int8))     # netCDF has no booleans: 0 and 1
    ds["load"] = (("x1", "x3"), np.full(GRID.shape, 0.5, np.float32))
    ds.to_netcdf(tmp_path / "f.nc")
    np.save(tmp_path / "bonded.npy", ~CRACK & (np.arange(16)[:, None] > 12))
    text = toml('tau_c = { file = "f.nc", var = "tau_c" }\ninitial_crack = { file = "f.nc", var = "crack" }\n'
                'bonded = { file = "bonded.npy" }').replace("tau0_2 = 0.5", 'tau0_2 = { file = "f.nc", var = "load" }')
    sc = Scene.from_toml(write(tmp_path, text))
    assert np.array_equal(sc.law.tau_c, TAU_C)
    assert sc.law.initial_crack.dtype == bool and np.array_equal(sc.law.initial_crack, CRACK)
    assert sc.law.bonded.dtype == bool and sc.law.bonded[13:].all() and not sc.law.bonded[:13].any()
    assert sc.loading.tau0_2.dtype == np.float32 and np.all(sc.loading.tau0_2 == 0.5)


def test_plane_problem_takes_a_line_and_free_surface_its_half_plane(tmp_path):
    plane = HEAD.replace("n3 = 8", "n3 = 1")
    g = Grid(n1=16, n3=1, L1=2.0, L3=1.0)
    xr.Dataset({"tau_c": (("x1",), TAU_C[:, 0])}, coords={"x1": g.x1}).to_netcdf(tmp_path / "line.nc")
    sc = Scene.from_toml(write(tmp_path, toml('tau_c = { file = "line.nc", var = "tau_c" }', plane)))
    assert sc.law.tau_c.shape == (16, 1) and np.array_equal(sc.law.tau_c[:, 0], TAU_C[:, 0])
    half = HEAD.replace("L3 = 1.0", "L3 = 1.0\nfree_surface = true")
    gs = Grid(n1=16, n3=8, L1=2.0, L3=1.0, free_surface=True)
    values = 1.0 + RNG.random(gs.shape)
    xr.Dataset({"tau_c": (("x1", "x3"), values)}, coords={"x1": gs.x1, "x3": gs.x3}).to_netcdf(tmp_path / "h.nc")
    sc = Scene.from_toml(write(tmp_path, toml('tau_c = { file = "h.nc", var = "tau_c" }', half)))
    assert np.array_equal(sc.law.tau_c, values)
    field_dataset().to_netcdf(tmp_path / "periodic.nc")    # (16, 8) on the half plane's (16, 9)
    msg = refused(write(tmp_path, toml('tau_c = { file = "periodic.nc", var = "tau_c" }', half)), "law.tau_c")
    assert "field shape must be (n1, n3 + 1) = (16, 9)" in msg and "got (16, 8)" in msg


# ------------------------------------------------------------------------ errors
def test_missing_file(tmp_path):
    msg = refused(write(tmp_path, toml('tau_c = { file = "nope.nc", var = "tau_c" }')), "law.tau_c")
    assert msg.startswith("law.tau_c: no such file 'nope.nc'") and str(tmp_path / "nope.nc") in msg
    assert "scene file's directory" in msg


def test_missing_variable_lists_what_the_file_has(tmp_path):
    field_dataset().to_netcdf(tmp_path / "t.nc")
    msg = refused(write(tmp_path, toml('tau_c = { file = "t.nc", var = "tauc" }')), "law.tau_c")
    assert "file 't.nc' has no variable 'tauc'; it has: tau_c" in msg
    field_dataset().to_zarr(tmp_path / "t.zarr", consolidated=False)
    msg = refused(write(tmp_path, toml('tau_c = { file = "t.zarr", var = "tauc" }')), "law.tau_c")
    assert "has no variable 'tauc'; it has: tau_c" in msg


def test_wrong_shape(tmp_path):
    g = Grid(n1=8, n3=8, L1=2.0, L3=1.0)
    xr.Dataset({"tau_c": (("x1", "x3"), np.ones(g.shape))}, coords={"x1": g.x1, "x3": g.x3}).to_netcdf(
        tmp_path / "small.nc")
    msg = refused(write(tmp_path, toml('tau_c = { file = "small.nc", var = "tau_c" }')), "law.tau_c")
    assert "field shape must be (n1, n3) = (16, 8), got (8, 8)" in msg and "'small.nc'" in msg
    np.save(tmp_path / "t.npy", TAU_C.T)
    msg = refused(write(tmp_path, toml('tau_c = { file = "t.npy" }')), "law.tau_c")
    assert "field shape must be (n1, n3) = (16, 8), got (8, 16)" in msg


def _save(ds, path):
    if path.suffix == ".zarr":
        ds.to_zarr(path, consolidated=False)
    else:
        ds.to_netcdf(path)


@pytest.mark.parametrize("ext", ["nc", "zarr"])
def test_wrong_coordinates(tmp_path, ext):
    """The same shape on another cell (L1 = 4) or shifted by half a cell is refused, from a
    netCDF file and from a Zarr store alike."""
    for name, x1 in (("wide", np.arange(16) * 0.25), ("shifted", GRID.x1 + 0.5 * GRID.dx1)):
        _save(field_dataset(x1=x1), tmp_path / f"{name}.{ext}")
        msg = refused(write(tmp_path, toml(f'tau_c = {{ file = "{name}.{ext}", var = "tau_c" }}')), "law.tau_c")
        assert f"the x1 coordinate of 'tau_c' in '{name}.{ext}' must be the grid's nodes x1 = 0, 0.125, ..., " \
               f"1.875" in msg and "it differs at index" in msg, msg
    _save(field_dataset(x3=GRID.x3 * 2), tmp_path / f"x3.{ext}")
    msg = refused(write(tmp_path, toml(f'tau_c = {{ file = "x3.{ext}", var = "tau_c" }}')), "law.tau_c")
    assert "the x3 coordinate" in msg and "differs at index 1: 0.25 instead of 0.125" in msg
    xr.Dataset({"tau_c": (("x1", "x3"), TAU_C)}).pipe(_save, tmp_path / f"bare.{ext}")     # no coordinates
    msg = refused(write(tmp_path, toml(f'tau_c = {{ file = "bare.{ext}", var = "tau_c" }}')), "law.tau_c")
    assert "has no x1 coordinate" in msg


def test_wrong_dims_and_no_coordinates(tmp_path):
    xr.Dataset({"tau_c": (("x", "y"), TAU_C)}).to_netcdf(tmp_path / "dims.nc")
    msg = refused(write(tmp_path, toml('tau_c = { file = "dims.nc", var = "tau_c" }')), "law.tau_c")
    assert "must lie on the dims (x1, x3), got ('x', 'y')" in msg
    xr.Dataset({"tau_c": (("x1", "x3"), TAU_C)}).to_netcdf(tmp_path / "bare.nc")
    msg = refused(write(tmp_path, toml('tau_c = { file = "bare.nc", var = "tau_c" }')), "law.tau_c")
    assert "has no x1 coordinate" in msg and ".npy" in msg


@pytest.mark.parametrize("ref, expected", [
    ('{ file = "t.npy", var = "tau_c" }', "holds one array: give no var"),
    ('{ file = "t.nc" }', "give the variable that holds the field"),
    ('{ file = "t.nc", var = "tau_c", units = "Pa" }', "unknown key 'units' in the file reference"),
    ('{ file = "t.csv" }', "unknown format '.csv'"),
    ('{ file = 3 }', "file must be the path of a file"),
    ('{ file = "t.txt" }', "is not a .npy file"),
])
def test_bad_references(tmp_path, ref, expected):
    field_dataset().to_netcdf(tmp_path / "t.nc")
    np.save(tmp_path / "t.npy", TAU_C)
    (tmp_path / "t.csv").write_text("1,2\n")
    (tmp_path / "t.txt").write_text("not numpy")
    if ".txt" in ref:   # a .npy name on a file that is not one
        os.replace(tmp_path / "t.txt", tmp_path / "bad.npy")
        ref = ref.replace("t.txt", "bad.npy")
    msg = refused(write(tmp_path, toml(f"tau_c = {ref}")), "law.tau_c")
    assert expected in msg, msg


def test_bad_values_and_a_reference_where_no_field_goes(tmp_path):
    ds = field_dataset()
    ds["holes"] = ds["tau_c"].where(ds["tau_c"] > 1.1)          # NaN where the file has no value
    ds["two"] = (("x1", "x3"), np.full(GRID.shape, 2, np.int8))
    ds["word"] = (("x1", "x3"), np.full(GRID.shape, "a"))
    ds.to_netcdf(tmp_path / "t.nc")
    msg = refused(write(tmp_path, toml('tau_c = { file = "t.nc", var = "holes" }')), "law.tau_c")
    assert "field values must be finite, got NaN" in msg
    msg = refused(write(tmp_path, toml('tau_c = 1.0\ninitial_crack = { file = "t.nc", var = "two" }')),
                  "law.initial_crack")
    assert "must be a boolean mask: booleans, or integers 0 and 1, got dtype int8" in msg
    msg = refused(write(tmp_path, toml('tau_c = { file = "t.nc", var = "word" }')), "law.tau_c")
    assert "must be a field of numbers" in msg
    np.save(tmp_path / "neg.npy", -TAU_C)
    msg = refused(write(tmp_path, toml('tau_c = { file = "neg.npy" }')), "law.tau_c")
    assert "must be > 0" in msg                                   # the law's own range check
    text = toml("tau_c = 1.0").replace("L1 = 2.0", 'L1 = { file = "t.nc", var = "tau_c" }')
    msg = refused(write(tmp_path, text), "grid.L1")
    assert "only fields" in msg and "are read from files" in msg


def test_cli_runs_a_scene_with_file_references_from_another_directory(tmp_path):
    """`cracklab run case/scene.toml` as a process started in the case's parent directory."""
    import subprocess
    import sys

    case = tmp_path / "case"
    case.mkdir()
    field_dataset().to_netcdf(case / "toughness.nc")
    write(case, toml('tau_c = { file = "toughness.nc", var = "tau_c" }'))

    def run(*args):
        return subprocess.run([sys.executable, "-m", "cracklab.cli", "run", *args], cwd=tmp_path,
                              capture_output=True, text=True, timeout=300)
    res = run("case/scene.toml", "-o", "out.zarr")
    assert res.returncode == 0, res.stderr
    result = xr.open_zarr(tmp_path / "out.zarr", consolidated=False)
    assert np.array_equal(scene_of(result).law.tau_c, TAU_C)      # the output carries the field itself
    write(case, toml('tau_c = { file = "toughness.nc", var = "nope" }'), "bad.toml")
    res = run("case/bad.toml", "-o", "bad.zarr")
    assert res.returncode != 0 and "Traceback" not in res.stderr
    assert res.stderr.strip().startswith("Error: law.tau_c: file 'toughness.nc' has no variable 'nope'"), res.stderr
    assert not (tmp_path / "bad.zarr").exists()


# ------------------------------------------------------------------------ the sidecar
def test_a_saved_random_toughness_scene_is_tens_of_lines_and_one_sidecar(tmp_path):
    sc = scenes.random_toughness(n1=128, n3=64, t_end=0.5)
    path = sc.to_toml(tmp_path / "scene.toml")
    assert path == tmp_path / "scene.toml"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.fields.nc", "scene.toml"]
    text = path.read_text()
    assert len(text.splitlines()) < 50, text            # docs/reference/scenes.md: fewer than 50 lines
    assert 'tau_c = { file = "scene.fields.nc", var = "law_tau_c" }' in text
    assert (tmp_path / "scene.fields.nc").stat().st_size < 100_000     # and a sidecar under 100 KB
    back = Scene.from_toml(path)
    assert scenes_equal(back, sc)
    for key in ("tau_c", "initial_crack", "bonded"):
        a, b = getattr(back.law, key), getattr(sc.law, key)
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes()          # bitwise
    side = xr.open_dataset(tmp_path / "scene.fields.nc")                  # plain xarray reads it
    assert set(side.data_vars) == {"law_tau_c", "law_initial_crack", "law_bonded"}
    assert np.array_equal(side.x1, sc.grid.x1) and side["law_tau_c"].attrs["units"] == "1"
    side.close()


@pytest.mark.parametrize("make", [
    lambda: scenes.asperity_row(n1=64, n3=32, t_end=0.5),
    lambda: scenes.tpv3(dx=2000.0, t_end=1.0),
    lambda: scenes.elliptical_crack(n=16, a=0.2, b=0.1, t_end=0.1),
    lambda: Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=GRID,
                  law=LinearCohesive(tau_c=TAU_C, delta_c=0.01 + 0.01 * RNG.random(GRID.shape), initial_crack=CRACK),
                  loading=Loading(tau0_2=RNG.random(GRID.shape).astype(np.float32)), t_end=0.05,
                  record=Record(fields=(), stations={"a": (0.5, 0.5)}), name="fields"),
])
def test_sidecar_round_trip_is_lossless(tmp_path, make):
    sc = make()
    path = sc.to_toml(tmp_path / "s.toml")
    back = Scene.from_toml(path)
    assert scenes_equal(back, sc)
    assert sc.to_toml() == scene_to_toml(sc)              # the text form is unchanged
    again = back.to_toml(tmp_path / "s.toml")             # saving over it
    assert scenes_equal(Scene.from_toml(again), sc)


def test_a_scene_without_arrays_writes_no_sidecar(tmp_path):
    sc = scenes.lamb(n=16, t_end=0.1).replace(loading=Loading(tau0_2=1.0))
    path = sc.to_toml(tmp_path / "plain.toml")
    assert [p.name for p in tmp_path.iterdir()] == ["plain.toml"]
    assert scenes_equal(Scene.from_toml(path), sc)


def test_a_run_of_a_saved_scene_carries_everything_to_rerun_it(tmp_path):
    sc = scenes.random_toughness(n1=32, n3=16, t_end=0.05)
    loaded = Scene.from_toml(sc.to_toml(tmp_path / "scene.toml"))
    result = simulate(loaded)
    assert scenes_equal(scene_of(result), sc)
    assert scenes_equal(Scene.from_dataset(result), sc)


def test_plain_data_and_datasets_do_not_read_files(tmp_path, monkeypatch):
    """A run's output holds its fields itself: a file reference in plain data (its JSON attr)
    is refused rather than read."""
    import tomllib

    from cracklab.model.scene_io import scene_from_data

    monkeypatch.chdir(tmp_path)
    field_dataset().to_netcdf(tmp_path / "t.nc")
    data = tomllib.loads(toml('tau_c = { file = "t.nc", var = "tau_c" }'))
    with pytest.raises(InputError) as err:
        scene_from_data(data)
    assert err.value.field == "law.tau_c" and "files are read only for a TOML scene" in str(err.value)
    assert np.array_equal(scene_from_data(data, base=tmp_path).law.tau_c, TAU_C)
