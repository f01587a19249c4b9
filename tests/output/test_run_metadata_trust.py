"""A run store's metadata is not taken on trust (docs/guide/reliability.md, "Stored data:
checksums, verification and the order of writes"): an array shape, a data type or a
variable's units changed in its zarr.json, a changed ``scene`` attribute, and
consolidated metadata out of step with the arrays are each named by ``cracklab verify``
in one line with the store path and the remedy; ``export`` refuses such a store, and
``--resume`` recomputes it (before, verify said "sound", export wrote the changed scene,
and the resume served the store or ended in a traceback)."""
import json
import shutil

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

import cracklab
from cracklab import Record
from cracklab.cli import main
from cracklab.model.scene_io import scene_to_toml
from cracklab.output import verify as V


def _scene():
    return cracklab.scenes.elliptical_crack(n=32, a=0.25, b=0.2, t_end=0.5,
                                            record=Record(fields=("delta_2",), every=2, stations={"c": (0.5, 0.5)}))


@pytest.fixture(scope="module")
def sound(tmp_path_factory):
    """A complete run store, its scene as TOML, and its data."""
    d = tmp_path_factory.mktemp("trust")
    store = d / "run.zarr"
    cracklab.simulate(_scene(), store=store)
    toml = d / "scene.toml"
    toml.write_text(scene_to_toml(_scene()))
    return store, toml, xr.open_zarr(store, consolidated=False).load()


@pytest.fixture
def store(sound, tmp_path):
    out = tmp_path / "run.zarr"
    shutil.copytree(sound[0], out)
    return out


def _edit(path, change):
    doc = json.loads(path.read_text())
    change(doc)
    path.write_text(json.dumps(doc))


def _cli(*args):
    res = CliRunner().invoke(main, [str(a) for a in args])
    assert not res.exception or isinstance(res.exception, SystemExit), repr(res.exception)   # no traceback
    return res.exit_code, res.output


def _remedy(store):
    return f"; remedy: cracklab run SCENE.toml -o {store} --resume recomputes the run"


def _repaired(store, sound, message):
    """``cracklab run SCENE.toml --resume`` says the store is damaged, recomputes it, and
    leaves it sound and equal to the run."""
    code, out = _cli("run", sound[1], "-o", store, "--resume", "--no-progress")
    assert code == 0 and message in out and "done again from the start" in out, out
    assert V.verify(store).ok
    got = xr.open_zarr(store, consolidated=False).load()
    for name in sound[2].data_vars:
        np.testing.assert_array_equal(got[name].values, sound[2][name].values, err_msg=name)
    assert got.attrs["scene"] == sound[2].attrs["scene"]
    plain = xr.open_zarr(store)                        # plain xarray: the consolidated metadata
    assert plain["delta_2"].shape == sound[2]["delta_2"].shape and plain["delta_2"].attrs["units"] == "1"


def _refused_by_export(store, meta, tmp_path):
    code, out = _cli("export", store, "-o", tmp_path / "out.nc")
    assert code == 1 and len(out.strip().splitlines()) == 1 and str(meta) in out, out
    assert not (tmp_path / "out.nc").exists()


def test_a_changed_array_shape_is_named_refused_and_recomputed(store, sound, tmp_path):
    meta = store / "delta_2" / "zarr.json"
    _edit(meta, lambda doc: doc.update(shape=[doc["shape"][0] - 5, *doc["shape"][1:]]))
    line = (f"  DAMAGED {meta}: array delta_2 has shape (12, 32, 32) along ('t', 'x1', 'x3'), but the run's scene "
            f"gives t = 17: its metadata was changed after the run{_remedy(store)}")
    for quick in ((), ("--quick",)):
        code, out = _cli("verify", store, *quick)
        assert code == 1 and line in out.splitlines(), out
    _refused_by_export(store, meta, tmp_path)
    _repaired(store, sound, f"{meta}: array delta_2 has shape (12, 32, 32)")    # once a ValueError traceback


def test_a_changed_scene_attribute_is_named_never_exported_and_recomputed(store, sound, tmp_path):
    meta = store / "zarr.json"

    def nu(doc):
        scene = json.loads(doc["attributes"]["scene"])
        assert scene["material"]["nu"] == 0.25
        scene["material"]["nu"] = 0.3
        doc["attributes"]["scene"] = json.dumps(scene)

    _edit(meta, nu)
    code, out = _cli("verify", store, "--quick")
    assert code == 1, out
    assert (f"  DAMAGED {meta}: the run's scene (its 'scene' attribute and input arrays) does not match the digest "
            f"cracklab_scene_digest written with the run: changed after the run{_remedy(store)}") in out.splitlines()
    assert "  what to do: run it again from its scene file with --resume" in out and "not the store itself" in out
    _refused_by_export(store, meta, tmp_path)          # once: wrote nu = 0.3 next to the data of nu = 0.25
    # once: "holds this run, complete (checked); nothing to do"
    _repaired(store, sound, f"{meta}: the run's scene (its 'scene' attribute and input arrays) does not match")
    assert json.loads(xr.open_zarr(store, consolidated=False).attrs["scene"])["material"]["nu"] == 0.25


@pytest.mark.parametrize("change", ["units", "data type"])
def test_changed_units_or_data_type_are_named_and_recomputed(change, store, sound):
    name = "delta_2" if change == "units" else "x1"
    meta = store / name / "zarr.json"
    if change == "units":
        _edit(meta, lambda doc: doc["attributes"].update(units="m"))
        what = "variable delta_2 has units 'm', but the run's scene gives '1'"
    else:
        _edit(meta, lambda doc: doc.update(data_type="float32"))
        what = "array x1 has data type 'float32', but cracklab writes it as float64 (its chunks hold float64)"
    code, out = _cli("verify", store, "--quick")
    assert code == 1, out
    assert f"  DAMAGED {meta}: {what}: its metadata was changed after the run{_remedy(store)}" in out.splitlines()
    _repaired(store, sound, f"{meta}: {what}")


def test_consolidated_metadata_out_of_step_is_named_and_rewritten(store, sound):
    """Plain xarray reads the consolidated copy of the metadata, cracklab each node's own:
    a copy that differs, an array it lists that is gone, an array it does not list."""
    root = store / "zarr.json"

    def stale(doc):
        listed = doc["consolidated_metadata"]["metadata"]
        listed["delta_2"]["attributes"]["units"] = "m"
        listed["old_field"] = dict(listed["rupture_time"])

    _edit(root, stale)
    shutil.copytree(store / "rupture_time", store / "extra")
    assert xr.open_zarr(store)["delta_2"].attrs["units"] == "m"        # what plain xarray serves
    code, out = _cli("verify", store, "--quick")
    assert code == 1, out
    lines = out.splitlines()
    assert (f"  DAMAGED {store / 'delta_2' / 'zarr.json'}: differs from its copy in the consolidated metadata of "
            f"{root} (attribute units): changed after the store was written; plain xarray reads the copy"
            f"{_remedy(store)}") in lines
    assert (f"  DAMAGED {store / 'old_field'}: listed in the consolidated metadata of {root} but not in the store: "
            f"plain xarray (xr.open_zarr, xr.open_datatree) reads it as fill values (NaN){_remedy(store)}") in lines
    assert (f"  DAMAGED {store / 'extra' / 'zarr.json'}: not in the consolidated metadata of {root}: plain xarray "
            f"does not see it{_remedy(store)}") in lines
    _repaired(store, sound, "differs from its copy in the consolidated metadata")
    assert not (store / "extra").exists()


def test_a_sound_store_says_sound_and_is_served_untouched(store):
    code, out = _cli("verify", store)
    assert code == 0 and out.splitlines() == [
        f"cracklab verify: {store}: run (status complete), 15 arrays, 17 chunks read: sound"], out
    before = {p: p.stat().st_mtime_ns for p in store.rglob("*") if p.is_file()}
    cracklab.simulate(_scene(), store=store, resume=True)
    assert {p: p.stat().st_mtime_ns for p in store.rglob("*") if p.is_file()} == before


def test_the_consolidated_metadata_describes_no_removed_checkpoint(tmp_path, monkeypatch):
    """A run that wrote checkpoints removes them before its consolidated metadata is
    written (plain xarray showed a `_checkpoint` node that was gone); one killed between
    its status and that clean-up has both rewritten by the resume."""
    from cracklab.output import checkpoint as ck

    store = tmp_path / "run.zarr"
    cracklab.simulate(_scene(), store=store, checkpoint_every=10)
    assert not (store / ck.GROUP).exists()
    assert list(xr.open_datatree(store, engine="zarr").children) == []
    killed = tmp_path / "killed.zarr"
    monkeypatch.setattr(ck, "remove", lambda path: None)         # killed before the clean-up
    cracklab.simulate(_scene(), store=killed, checkpoint_every=10)
    monkeypatch.undo()
    assert (killed / ck.GROUP).exists() and V.verify(killed).ok
    cracklab.simulate(_scene(), store=killed, resume=True)
    assert not (killed / ck.GROUP).exists() and list(xr.open_datatree(killed, engine="zarr").children) == []
    assert V.verify(killed).ok


def test_the_store_as_its_own_scene_file(store, sound):
    """``cracklab run STORE -o STORE --resume`` takes the scene from the store's attrs and
    input arrays, past an array changed by hand (once: "cannot open ... conflicting sizes
    for dimension 't'"), and refuses a scene that is not the one the run recorded."""
    meta = store / "delta_2" / "zarr.json"
    _edit(meta, lambda doc: doc.update(shape=[doc["shape"][0] + 3, *doc["shape"][1:]]))
    code, out = _cli("run", store, "-o", store, "--resume", "--no-progress")
    assert code == 0 and f"{meta}: array delta_2 has shape (20, 32, 32)" in out, out
    assert V.verify(store).ok

    def nu(doc):
        scene = json.loads(doc["attributes"]["scene"])
        scene["material"]["nu"] = 0.3
        doc["attributes"]["scene"] = json.dumps(scene)

    _edit(store / "zarr.json", nu)
    code, out = _cli("run", store, "-o", store, "--resume", "--no-progress")
    assert code == 1 and out.strip().splitlines() == [
        f"Error: store {store}: its scene does not match the digest cracklab_scene_digest written with the run "
        f"(changed after the run); give the scene file: cracklab run SCENE.toml -o STORE --resume"], out
    _repaired(store, sound, "does not match the digest")
