"""An ensemble store's metadata is not taken on trust (docs/guide/reliability.md, "Stored
data: checksums, verification and the order of writes"): a member group deleted by hand,
a member's parameters, scene or array shape changed in its zarr.json, and a member table
at the root that no longer says what the member groups say are each named by ``cracklab
verify`` in one line with the store path and the remedy; cracklab's readers refuse such
members, and the rerun of the sweep recomputes them and rewrites the member table and
the consolidated metadata that plain xarray reads (before, verify said "sound", plain
xarray served a deleted member as complete and all NaN, and the rerun said "0 ran, 3
already complete" under the changed parameters)."""
import json
import shutil

import numpy as np
import pytest
import xarray as xr
import zarr
from click.testing import CliRunner

from cracklab import ensemble as E
from small_ensemble import copy_of, member_ids, sound_ensemble, sweep
from cracklab.cli import main
from cracklab.errors import StoreError

@pytest.fixture(scope="module")
def sound(tmp_path_factory):
    return sound_ensemble(tmp_path_factory, "trust")


@pytest.fixture
def store(sound, tmp_path):
    return copy_of(sound, tmp_path)


def _edit(path, change):
    doc = json.loads(path.read_text())
    change(doc)
    path.write_text(json.dumps(doc))


def _verify(store, *extra):
    res = CliRunner().invoke(main, ["verify", str(store), *extra])
    assert not res.exception or isinstance(res.exception, SystemExit), repr(res.exception)
    return res.exit_code, res.output.splitlines()


def _member_remedy(store):
    return f"; remedy: cracklab sweep STUDY.toml -o {store} recomputes the member"


def _store_remedy(store):
    return (f"; remedy: cracklab sweep STUDY.toml -o {store} runs the members that are not there and rewrites the "
            f"member table and the consolidated metadata")


def _repaired(store, sound, ran, damaged=()):
    """The rerun of the sweep runs ``ran`` (``damaged`` of them reported damaged) and
    leaves a sound store that plain xarray and open_ensemble read as the reference."""
    res = sweep(store)
    assert res.ok and res.ran == ran and sorted(res.damaged) == sorted(damaged), res.summary()
    assert _verify(store)[0] == 0
    ens = E.open_ensemble(store).load()
    assert list(ens.member.values) == list(sound[1].member.values)
    np.testing.assert_allclose(ens["delta_2"].values, sound[1]["delta_2"].values, rtol=0, atol=1e-12)
    assert ens.attrs["scenes"] == sound[1].attrs["scenes"]
    table = xr.open_zarr(store)                          # plain xarray: the consolidated metadata
    assert list(table.status.values) == ["complete"] * 3 and list(table.p.values) == [1.0, 2.0, 3.0]
    tree = xr.open_datatree(store, engine="zarr")
    for mid in ens.member.values:
        node = tree["members"][mid]
        assert node.attrs["complete"] is True and np.isfinite(node["delta_2"].values).all()


def test_a_deleted_member_is_named_and_run_again(store, sound):
    a = member_ids(store)[0]
    shutil.rmtree(store / "members" / a)
    tree = xr.open_datatree(store, engine="zarr")        # plain xarray reads the consolidated metadata
    assert tree["members"][a].attrs["complete"] is True and np.isnan(tree["members"][a]["delta_2"].values).all()
    code, lines = _verify(store)                         # once: "sound"
    assert code == 1, lines
    assert (f"  DAMAGED {store / 'members' / a}: listed in the consolidated metadata of {store / 'zarr.json'} but "
            f"not in the store: plain xarray (xr.open_zarr, xr.open_datatree) reads it as fill values "
            f"(NaN){_store_remedy(store)}") in lines
    assert (f"  DAMAGED {store / 'member'}: the member table lists 1 member(s) not in the store ({a}): that is what "
            f"plain xarray (xr.open_zarr) shows{_store_remedy(store)}") in lines
    assert E.open_ensemble(store).sizes["member"] == 2   # cracklab's readers never served it
    _repaired(store, sound, ran=[a])


def test_changed_member_parameters_are_named_refused_and_recomputed(store, sound, tmp_path):
    b = member_ids(store)[1]
    meta = store / "members" / b / "zarr.json"

    def params(doc):
        p = json.loads(doc["attributes"]["member_params"])
        assert p["p"] == 2.0
        doc["attributes"]["member_params"] = json.dumps({**p, "p": 5.0})

    _edit(meta, params)
    code, lines = _verify(store, "--quick")
    assert code == 1, lines
    assert (f"  DAMAGED member {b}: {meta}: its parameters (attribute member_params) do not give its id {b} (an id "
            f"is the digest of the parameters): changed after the run{_member_remedy(store)}") in lines
    assert not [line for line in lines if f"{store / 'p'}" in line]     # the table is not blamed for the member
    with pytest.raises(StoreError, match=f"member {b} is damaged: {meta}: its parameters"):
        E.open_ensemble(store)
    res = CliRunner().invoke(main, ["export", str(store), "-o", str(tmp_path / "e.nc")])
    assert res.exit_code == 1 and str(meta) in res.output and not (tmp_path / "e.nc").exists()
    _repaired(store, sound, ran=[b], damaged=[b])        # once: "0 ran, 3 already complete"
    assert json.loads(json.loads(meta.read_text())["attributes"]["member_params"])["p"] == 2.0


def test_a_changed_scene_path_parameter_is_named(store):
    b = member_ids(store)[1]
    meta = store / "members" / b / "zarr.json"
    mdoc = json.loads(meta.read_text())
    params = json.loads(mdoc["attributes"]["member_params"])
    # the id of a member over a builder is the digest of its parameters: a forged id for
    # record.every = 4 is still caught, by the member's scene
    forged = E.member_id("builder", {**params, "record.every": 4})
    shutil.move(store / "members" / b, store / "members" / forged)
    meta = store / "members" / forged / "zarr.json"
    _edit(meta, lambda doc: doc["attributes"].update(member_id=forged, member_params=E.canonical_json(
        {**params, "record.every": 4})))
    code, lines = _verify(store, "--quick")
    assert code == 1, lines
    assert (f"  DAMAGED member {forged}: {meta}: its parameter record.every = 4 (attribute member_params) is not its "
            f"scene's record.every = 2: changed after the run{_member_remedy(store)}") in lines


def test_a_changed_member_scene_is_named_and_recomputed(store, sound):
    c = member_ids(store)[2]
    meta = store / "members" / c / "zarr.json"

    def nu(doc):
        scene = json.loads(doc["attributes"]["scene"])
        scene["material"]["nu"] = 0.3
        doc["attributes"]["scene"] = json.dumps(scene)

    _edit(meta, nu)
    code, lines = _verify(store, "--quick")
    assert code == 1, lines
    assert (f"  DAMAGED member {c}: {meta}: the run's scene (its 'scene' attribute and input arrays) does not match "
            f"the digest cracklab_scene_digest written with the run: changed after the run"
            f"{_member_remedy(store)}") in lines
    with pytest.raises(StoreError, match=f"member {c} is damaged: {meta}: the run's scene"):
        E.open_member(store, c)
    _repaired(store, sound, ran=[c], damaged=[c])


def test_a_changed_member_array_shape_is_named_and_recomputed(store, sound):
    c = member_ids(store)[2]
    meta = store / "members" / c / "delta_2" / "zarr.json"
    _edit(meta, lambda doc: doc.update(shape=[doc["shape"][0] - 2, *doc["shape"][1:]]))
    code, lines = _verify(store, "--quick")
    assert code == 1, lines
    assert (f"  DAMAGED member {c}: {meta}: array delta_2 has shape (4, 16, 16) along ('t', 'x1', 'x3'), but the "
            f"run's scene gives t = 6: its metadata was changed after the run{_member_remedy(store)}") in lines
    with pytest.raises(StoreError, match=f"member {c} is damaged: {meta}: array delta_2 has shape"):
        E.open_ensemble(store)                           # once: "conflicting sizes for dimension 't'"
    _repaired(store, sound, ran=[c], damaged=[c])


@pytest.mark.parametrize("change", ["status", "parameter", "deleted"])
def test_a_member_table_out_of_step_is_named_and_rewritten(change, store, sound):
    b = member_ids(store)[1]
    root = zarr.open_group(str(store), mode="a", use_consolidated=False)
    if change == "deleted":
        shutil.rmtree(store / "status")
        line = f"  DAMAGED {store / 'status'}: the member table has no coordinate status"
    else:
        name, value = ("status", "failed") if change == "status" else ("p", 9.0)
        values = root[name][:]
        values[1] = value
        root[name][:] = values
        was = "'complete'" if change == "status" else "2.0"
        line = (f"  DAMAGED {store / name}: the member table gives {name} = {value!r} for member {b}, but its group "
                f"gives {was}")
    code, lines = _verify(store)                         # once: "sound"
    assert code == 1 and f"{line}: that is what plain xarray (xr.open_zarr) shows{_store_remedy(store)}" in lines, lines
    _repaired(store, sound, ran=[])
