"""An ensemble as one tidy xarray object, on a real store: parameter coordinates in their
own types, a status per member, the scenes out of the variables, every analysis function
per member, the summary table (Python and ``cracklab summary``), and plain xarray
opening every store without warnings."""
import json
import warnings

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from click.testing import CliRunner

import cracklab
from cracklab import analysis as A
from cracklab import ensemble as E
from cracklab.cli import main


BASE = E.Builder("asperity_row", n1=32, n3=16, t_end=0.6, diameter=0.25)


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """4 asperity members (contrast x record.every: a float and an integer), one seeded
    random-toughness member and one member that fails its validation (beta = 10)."""
    path = tmp_path_factory.mktemp("tidy") / "ens.zarr"
    sweep = E.Sweep(product={"contrast": [1.5, 3.0], "record.every": [2, 4]},
                    members=[{"builder": "random_toughness", "cov": 0.1, "correlation_length": 0.25},
                             {"beta": 10.0}],
                    entropy=7)
    res = E.run(BASE, sweep, path, scheduler="synchronous", progress=False)
    assert len(res.failed) == 1, res.summary()
    path.with_suffix(".sweep").write_text(json.dumps({"product": sweep.product, "members": sweep.members}))
    return path, res


def _finite_count(a):
    return int(np.isfinite(np.asarray(a)).sum())


def test_parameters_are_coordinates_in_their_own_types(store):
    path, res = store
    ens = E.open_ensemble(path)
    ids = [m.id for m in res.members if m.id not in res.failed]
    assert list(ens.member.values) == ids
    assert ens["contrast"].dtype == np.float64 and list(ens.contrast.values[:4]) == [1.5, 1.5, 3.0, 3.0]
    assert ens["record_every"].dtype == np.int64 and list(ens.record_every.values[:4]) == [2, 4, 2, 4]
    seeded = res.members[4]
    assert ens["seed"].dtype == np.int64
    assert int(ens.seed.values[4]) == seeded.params["seed"] and seeded.params["seed"] > 2**40
    assert list(ens.seed.values[:4]) == [E.NO_INTEGER] * 4
    assert list(ens.builder.values) == ["asperity_row"] * 4 + ["random_toughness"]
    assert list(ens.status.values) == ["complete"] * 5
    # the scenes are neither variables nor coordinates, yet every member's scene is there
    assert "scene" not in ens.variables
    assert set(json.loads(ens.attrs["scenes"])) == set(ids)
    assert E.member_scene(ens, ids[3]).record.every == 4
    assert E.member_scene(ens, ids[2]).law.tau_c.max() == pytest.approx(3.0)
    # the table a user asks for: parameters and the final crack length, nothing else
    df = A.crack_length(ens).isel(t=-1).to_dataframe()
    assert set(df.columns) == {"t", "crack_length", "contrast", "record_every", "builder", "cov",
                               "correlation_length", "seed", "status", "scene_name"}
    assert df["seed"].dtype == np.int64 and df.index.name == "member"
    # one line per parameter: select and group by them
    assert ens.set_xindex("record_every").sel(record_every=4).sizes["member"] == 2
    assert set(ens.rupture_time.groupby("contrast").mean().contrast.values[:2]) == {1.5, 3.0}


def test_a_datatree_has_the_member_coordinates_at_its_root(store):
    path, res = store
    tree = E.open_ensemble(path, tree=True)
    assert list(tree.dataset.record_every.values[:4]) == [2, 4, 2, 4]
    assert tree.dataset.seed.dtype == np.int64 and len(tree["members"].children) == 5


def _same(a, b):
    """The ensemble result of one member against the single run's result."""
    assert isinstance(a, type(b))
    if isinstance(b, xr.Dataset):
        assert set(a.data_vars) == set(b.data_vars)
        for k in b.data_vars:
            _same(a[k], b[k])
        return
    assert a.dims == b.dims
    for d in b.dims:
        if d in b.coords:
            np.testing.assert_array_equal(a[d].values, b[d].values)
    np.testing.assert_allclose(a.values, b.values, rtol=0, atol=0, equal_nan=True)


def test_every_analysis_function_works_per_member(store):
    path, res = store
    ens = E.open_ensemble(path)
    front = A.front_position(ens)
    opening = A.front_position(ens, method="opening")
    length = A.mean_crack_length(front)
    results = {
        "front": front, "opening": opening, "length": length, "speed": A.front_speed(length),
        "front_speed": A.front_speed(front), "zone": A.cohesive_zone(ens), "roughness": A.roughness(front),
        "structure": A.structure_function(front), "crack_length": A.crack_length(ens, t=[0.0, 0.3, 0.6]),
        "statistics": A.rupture_statistics(ens),
    }
    for name, r in results.items():
        assert r.sizes["member"] == 5, name
        assert list(r.member.values) == list(ens.member.values) and "contrast" in r.coords, name
    for i, mid in enumerate(ens.member.values):
        one = E.open_member(path, mid)
        f1 = A.front_position(one)
        l1 = A.mean_crack_length(f1)
        single = {
            "front": f1, "opening": A.front_position(one, method="opening"), "length": l1,
            "speed": A.front_speed(l1), "front_speed": A.front_speed(f1), "zone": A.cohesive_zone(one),
            "roughness": A.roughness(f1), "structure": A.structure_function(f1),
            "crack_length": A.crack_length(one, t=[0.0, 0.3, 0.6]), "statistics": A.rupture_statistics(one),
        }
        for name, r in results.items():      # members with other snapshot times: padded with NaN
            mine = A.member_view(r, i) if name != "zone" else r.isel(member=i).sel(t=single[name].t)
            _same(mine.drop_vars([c for c in mine.coords if mine[c].dims == ()]), single[name])
    # an independent count: the final crack length is the failed area over L3
    rt = E.open_member(path, ens.member.values[0]).rupture_time.values
    expected = _finite_count(rt) * (2.0 / 32) * (1.0 / 16) / 1.0
    assert float(results["statistics"].crack_length[0]) == pytest.approx(expected)
    assert float(results["statistics"].ruptured_fraction[0]) == pytest.approx(_finite_count(rt) / rt.size)
    # the opening front lags the rupture-time front (the crack tip trails the cohesive zone)
    both = np.isfinite(opening.values) & np.isfinite(front.values)
    assert both.sum() > 100 and np.all(opening.values[both] <= front.values[both] + 1e-12)


def test_summary_table_of_every_member(store, tmp_path):
    path, res = store
    table = E.summary(path)
    ids = [m.id for m in res.members]
    assert list(table.member.values) == ids
    bad = res.members[5].id
    assert table.status.sel(member=bad).item() == "failed"
    assert table.error.sel(member=bad).item().startswith("InputError: beta")
    assert np.isnan(table.crack_length.sel(member=bad).item())
    assert table.record_every.dtype == np.int64 and table.seed.dtype == np.int64
    for m in res.members[:5]:
        rt = E.open_member(path, m.id).rupture_time.values
        assert table.crack_length.sel(member=m.id).item() == pytest.approx(_finite_count(rt) * (2 / 32) / 16)
        assert table.elapsed_s.sel(member=m.id).item() > 0
    assert table.crack_length.attrs["long_name"].startswith("final mean crack length")
    df = table.to_dataframe()
    assert len(df) == 6 and df.index.name == "member"
    assert {"contrast", "record_every", "seed", "status", "crack_length", "front_position"} <= set(df.columns)
    # complete members only, from the Dataset too
    only = E.summary(path, complete_only=True)
    assert only.sizes["member"] == 5
    xr.testing.assert_allclose(A.summary(E.open_ensemble(path)).crack_length.reset_coords(drop=True),
                               only.crack_length.reset_coords(drop=True))

    runner = CliRunner()
    out = runner.invoke(main, ["summary", str(path)])
    assert out.exit_code == 0, out.output
    lines = out.output.splitlines()
    assert "contrast" in lines[0] and "crack_length" in lines[0]
    assert sum(any(line.startswith(i) for i in ids) for line in lines) == 6
    csv = tmp_path / "table.csv"
    out = runner.invoke(main, ["summary", str(path), "-o", str(csv)])
    assert out.exit_code == 0 and "wrote" in out.output and "6 rows" in out.output, out.output
    back = pd.read_csv(csv, index_col="member")
    assert list(back.index) == ids
    np.testing.assert_allclose(back["crack_length"].values, table.crack_length.values, equal_nan=True)
    assert back.loc[res.members[4].id, "seed"] == res.members[4].params["seed"]
    out = runner.invoke(main, ["summary", str(tmp_path)])
    assert out.exit_code == 1 and out.output.startswith("Error: store:"), out.output


def test_plain_xarray_opens_every_store_without_warnings(store, tmp_path):
    path, res = store
    spec = json.loads(path.with_suffix(".sweep").read_text())
    again = E.run(BASE, E.Sweep(**spec, entropy=7), path, scheduler="synchronous", progress=False)
    assert again.ran == [res.members[5].id]         # the rerun: only the failed member, again
    run_store = tmp_path / "run.zarr"
    cracklab.simulate(cracklab.scenes.lamb(n=16, t_end=0.05), store=str(run_store))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        root = xr.open_zarr(path)
        tree = xr.open_datatree(path, engine="zarr")
        member = xr.open_zarr(path, group=f"members/{res.members[0].id}")
        run = xr.open_zarr(run_store)
        run_tree = xr.open_datatree(run_store, engine="zarr")
    assert list(root.member.values) == [m.id for m in res.members]
    assert {"contrast", "record_every", "seed", "status", "builder"} <= set(root.coords)
    assert root.record_every.dtype == np.int64 and root.seed.dtype == np.int64
    assert list(root.status.values) == ["complete"] * 5 + ["failed"]
    assert root.attrs["cracklab_ensemble"] == 1 and "members" in root.attrs
    assert len(tree["members"].children) == 6
    assert tree.dataset.contrast.values[0] == 1.5
    assert member.delta_2.sizes["t"] > 1 and "scene" in member.attrs
    assert run.delta_2.sizes == {"t": run.sizes["t"], "x1": 16, "x3": 16}
    assert run_tree.dataset.delta_2.sizes == run.delta_2.sizes
    # our own readers see what is on disk, not the consolidated copy
    assert E.open_ensemble(path).sizes["member"] == 5
    assert cracklab.output.verify.verify(path).ok and cracklab.output.verify.verify(run_store).ok


def test_counts_in_the_singular():
    one = E.SweepResult("s.zarr", [E.Member(0, "a" * 16, {}, ())], ran=["a" * 16])
    assert one.summary().startswith("1 member: 1 ran")
    two = E.SweepResult("s.zarr", [E.Member(0, "a" * 16, {}, ()), E.Member(1, "b" * 16, {}, ())])
    assert two.summary().startswith("2 members: 0 ran")
    from cracklab.plots import plural

    assert (plural(1, "member"), plural(3, "member")) == ("1 member", "3 members")
