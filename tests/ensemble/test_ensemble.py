"""Ensembles: sweeps on a 2-worker LocalCluster into one Zarr v3 store, failures, resume,
stable member ids, open_ensemble and the netCDF export."""
import dataclasses
import json
import os
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import zarr
from click.testing import CliRunner

import cracklab
from cracklab import ensemble as E
from cracklab.cli import main
from cracklab.ensemble import running
from cracklab.errors import InputError


def flaky_crack(*, n=16, p=1.0, t_end=0.06, fail_flag=""):
    """A small elliptical crack; raises while the file ``fail_flag`` exists (a transient
    failure inside the worker, fixed by deleting the file)."""
    if fail_flag and os.path.exists(fail_flag):
        raise RuntimeError(f"injected failure: {fail_flag} exists")
    scene = cracklab.scenes.elliptical_crack(n=n, a=0.25, b=0.2, p=p, t_end=t_end,
                                             record=cracklab.Record(fields=("delta_2",), every=2))
    # the direct (reference) engine: no fits or JIT compilation in every fresh worker
    return scene.replace(numerics=dataclasses.replace(scene.numerics, engine="direct"))


FLAKY = "test_ensemble:flaky_crack"
E.register_builder(FLAKY, flaky_crack)      # study files name only registered builders


@pytest.fixture(scope="module")
def client():
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0")
    c = Client(cluster)
    yield c
    c.close()
    cluster.close()


def _member_attrs(store, mid):
    return dict(zarr.open_group(f"{store}/members/{mid}", mode="r").attrs)


def test_failure_recorded_then_resumed_on_the_cluster(client, tmp_path):
    flag = tmp_path / "fail.flag"
    flag.write_text("fail")
    store = tmp_path / "ens.zarr"
    sweep = E.Sweep(product={"p": [1.0, 2.0]}, members=[{"p": 1.5, "fail_flag": str(flag)}])
    first = E.run(E.Builder(FLAKY), sweep, store, client=client, progress=False)
    assert len(first.members) == 3 and len(first.ran) == 3
    bad = first.members[2].id
    assert list(first.failed) == [bad] and "injected failure" in first.failed[bad]
    attrs = _member_attrs(store, bad)
    assert attrs["status"] == "failed" and attrs["complete"] is False
    assert "RuntimeError: injected failure" in attrs["error"] and "flaky_crack" in attrs["traceback"]
    for m in first.members[:2]:
        assert _member_attrs(store, m.id)["complete"] is True

    flag.unlink()                                  # fix the cause, resume
    second = E.run(E.Builder(FLAKY), sweep, store, client=client, progress=False)
    assert second.ok and second.ran == [bad] and set(second.skipped) == {m.id for m in first.members[:2]}
    assert [m.id for m in second.members] == [m.id for m in first.members]   # stable ids
    groups = sorted(zarr.open_group(str(store), mode="r")["members"].group_keys())
    assert groups == sorted(m.id for m in first.members)                      # each member once
    for m in second.members:
        a = _member_attrs(store, m.id)
        assert a["complete"] is True and a["status"] == "complete" and "error" not in a
        ds = xr.open_zarr(store, group=f"members/{m.id}", consolidated=False)
        assert ds.delta_2.sizes["t"] > 1 and np.isfinite(ds.delta_2.values).all()
        assert cracklab.scene_of(ds).loading.tau0_2.max() == m.params["p"]
    assert zarr.open_group(str(store), mode="r").metadata.zarr_format == 3

    before = {m.id: _member_attrs(store, m.id) for m in second.members}
    third = E.run(E.Builder(FLAKY), sweep, store, progress=False)   # no client: none is started
    assert third.ok and third.ran == [] and len(third.skipped) == 3
    assert {m.id: _member_attrs(store, m.id) for m in second.members} == before


def test_runtime_and_validation_failures_do_not_stop_the_others(client, tmp_path, monkeypatch):
    base = cracklab.scenes.elliptical_crack(n=16, a=0.25, b=0.25, t_end=0.05)
    # 1e308 is a valid (finite) load but the velocity overflows at the first step:
    # a SimulationError inside the run; beta = 10 fails the scene's validation on the worker
    sweep = E.Sweep(product={"loading.tau0_2": [1.0, 1e308]}, members=[{"beta": 10.0}])
    store = tmp_path / "ens.zarr"
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", client.scheduler.address)   # an existing scheduler
    res = E.run(base, sweep, store, progress=False)
    assert len(res.failed) == 2
    errors = {res.members[i].id: res.failed.get(res.members[i].id) for i in range(3)}
    assert errors[res.members[0].id] is None
    assert errors[res.members[1].id].startswith("SimulationError: non-finite v_2")
    assert errors[res.members[2].id].startswith("InputError: beta")
    status = {s["id"]: s for s in E.member_status(store)}
    assert status[res.members[1].id]["status"] == "failed" and "Traceback" in status[res.members[1].id]["traceback"]
    assert "must be in (0," in status[res.members[2].id]["error"]
    ens = E.open_ensemble(store)
    assert ens.sizes["member"] == 1 and "loading_tau0_2" in ens.coords


def test_member_ids_are_canonical():
    b = E.Builder(FLAKY)
    one = E.plan(b, E.Sweep(product={"p": [1.0, 2.0], "n": [16, 32]}))
    two = E.plan(b, E.Sweep(product={"n": [16, 32], "p": [1.0, 2.0]}))
    assert {m.id: m.params for m in one} == {m.id: m.params for m in two}
    a = E.plan(b, E.Sweep(members=[{"p": 2.0, "n": 32, "t_end": 0.1}]))[0]
    c = E.plan(b, E.Sweep(members=[{"t_end": 0.1, "n": 32, "p": 2.0}]))[0]
    assert a.id == c.id and len(a.id) == 16
    assert E.plan(b, [{"p": 2.0}])[0].id == E.plan(b, {"p": [np.float64(2.0)]})[0].id
    # the id is a pure function of the parameters: pinned, so it stays the same across versions
    assert E.plan(E.Builder("lamb"), [{"n": 16, "t_end": 0.1}])[0].id == E.member_id(
        "builder", {"builder": "lamb", "n": 16, "t_end": 0.1})
    assert E.member_id("builder", {"builder": "lamb", "n": 16, "t_end": 0.1}) == "47ca0175518c4fa0"
    # different base scenes, different ids
    s1 = cracklab.scenes.elliptical_crack(n=16, a=0.25, b=0.25, t_end=0.05)
    s2 = s1.replace(t_end=0.06)
    assert E.plan(s1, [{"beta": 0.4}])[0].id != E.plan(s2, [{"beta": 0.4}])[0].id
    with pytest.raises(InputError, match="sweep.nope"):
        E.plan(b, {"nope": [1]})
    with pytest.raises(InputError, match="same parameters"):
        E.plan(b, {"p": [1.0, 1.0]})


def test_seeds_are_reproducible_independent_and_order_free():
    b = E.Builder("random_toughness", n1=32, n3=16, t_end=0.1)
    sw = E.Sweep(product={"cov": [0.1, 0.2]}, entropy=42, replicates=3)
    ms = E.plan(b, sw)
    assert len(ms) == 6 and len({m.params["seed"] for m in ms}) == 6
    assert [m.params["seed"] for m in ms] == [m.params["seed"] for m in E.plan(b, sw)]
    rev = E.plan(b, E.Sweep(product={"cov": [0.2, 0.1]}, entropy=42, replicates=3))
    assert {m.id: m.params["seed"] for m in rev} == {m.id: m.params["seed"] for m in ms}
    assert all(0 <= m.params["seed"] < 2**53 and "seed" in m.swept for m in ms)
    longer = E.plan(E.Builder("random_toughness", n1=32, n3=16, t_end=0.2), sw)   # same field
    assert [m.params["seed"] for m in longer] == [m.params["seed"] for m in ms]
    assert not {m.id for m in longer} & {m.id for m in ms}
    other = E.plan(b, E.Sweep(product={"cov": [0.1, 0.2]}, entropy=43, replicates=3))
    assert not {m.params["seed"] for m in other} & {m.params["seed"] for m in ms}
    with pytest.raises(InputError, match="replicates"):
        E.plan(E.Builder(FLAKY), E.Sweep(product={"p": [1.0]}, replicates=2))


STUDY = """
[study]
name = "cli-study"
builder = "test_ensemble:flaky_crack"

[base]
n = 16
t_end = 0.25
record.every = 2

[sweep]
p = [1.0, 2.0]
loading.time = ["step", "ramp"]
loading.ramp_time = [0.1]

[[members]]
p = 3.0
fail_flag = "%s"
"""


def test_cli_sweep_open_ensemble_groupby_and_netcdf(client, tmp_path):
    import netCDF4

    flag = tmp_path / "flag"
    flag.write_text("x")
    study = tmp_path / "study.toml"
    study.write_text(STUDY % flag)
    store = tmp_path / "cli.zarr"
    runner = CliRunner()
    args = ["sweep", str(study), "-o", str(store), "--scheduler", client.scheduler.address]
    res = runner.invoke(main, args)
    assert res.exit_code == 1, res.output
    assert "5 members: 4 ran" in res.output and "FAILED" in res.output and "injected failure" in res.output
    flag.unlink()
    res = runner.invoke(main, args)
    assert res.exit_code == 0, res.output
    assert "1 ran, 4 already complete, 0 failed" in res.output

    ens = cracklab.ensemble.open_ensemble(store)
    assert ens.sizes["member"] == 5 and ens.delta_2.dims[0] == "member"
    for name in ("p", "loading_time", "loading_ramp_time", "fail_flag"):
        assert name in ens.coords and ens[name].dims == ("member",)
    assert ens.loading_time.attrs["parameter"] == "loading.time"
    assert list(ens.p.values) == [1.0, 1.0, 2.0, 2.0, 3.0]
    mean = ens.rupture_time.groupby("loading_time").mean()
    assert set(mean.loading_time.values) == {"step", "ramp", ""}
    peak = ens.delta_2.isel(t=-1).max(["x1", "x3"]).groupby("p").max()
    assert peak.sel(p=2.0) > peak.sel(p=1.0)
    sel = ens.set_xindex("p").sel(p=2.0)
    assert sel.sizes["member"] == 2 and set(sel.loading_time.values) == {"step", "ramp"}
    scene = E.member_scene(ens, ens.member.values[2])
    assert scene.loading.tau0_2.max() == 2.0 and scene.loading.time == "step"
    tree = E.open_ensemble(store, tree=True)
    assert len(tree["members"].children) == 5

    out = tmp_path / "ens.nc"
    res = runner.invoke(main, ["export", str(store), "--netcdf", str(out)])
    assert res.exit_code == 0, res.output
    with netCDF4.Dataset(out) as nc:
        assert list(nc["member"][:]) == list(ens.member.values)
        np.testing.assert_array_equal(nc["delta_2"][:].filled(np.nan), ens.delta_2.values)
        np.testing.assert_array_equal(nc["rupture_time"][:].filled(np.nan), ens.rupture_time.values)
        np.testing.assert_array_equal(nc["p"][:], ens.p.values)
        assert list(nc["loading_time"][:]) == list(ens.loading_time.values)
        assert json.loads(nc.getncattr("swept")) == json.loads(ens.attrs["swept"])
    one = tmp_path / "one.nc"
    mid = str(ens.member.values[1])
    res = runner.invoke(main, ["export", str(store), "--netcdf", str(one), "--member", mid])
    assert res.exit_code == 0, res.output
    with netCDF4.Dataset(one) as nc:
        np.testing.assert_array_equal(nc["delta_2"][:], ens.delta_2.sel(member=mid).values)
        assert nc.getncattr("member_id") == mid
    back = xr.open_dataset(one, engine="netcdf4")
    assert cracklab.scene_of(back).loading.time == "ramp"


def test_store_layout_and_bad_store(tmp_path):
    # synchronous: in this process, no cluster (debugging and tiny sweeps)
    store = tmp_path / "s.zarr"
    res = E.run(E.Builder(FLAKY), {"p": [1.0]}, store, scheduler="synchronous", progress=False)
    assert res.ok
    root = zarr.open_group(str(store), mode="r")
    assert root.attrs["cracklab_ensemble"] == 1 and root.attrs["members"] == [res.members[0].id]
    assert json.loads(root.attrs["axes"]) == ["p"]
    a = _member_attrs(store, res.members[0].id)
    assert json.loads(a["member_params"]) == {"builder": FLAKY, "p": 1.0}
    assert a["scene"].startswith("{") and a["worker"]
    # a single run's store is not an ensemble store
    run_store = tmp_path / "run.zarr"
    cracklab.simulate(flaky_crack(), store=str(run_store))
    with pytest.raises(InputError, match="single cracklab run"):
        E.run(E.Builder(FLAKY), {"p": [1.0]}, run_store, scheduler="synchronous")
    assert not E.is_ensemble(run_store) and E.is_ensemble(store)


def test_study_toml_errors(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text('[study]\nbuilder = "asperity_row"\n[sweep]\nnot_an_arg = [1]\n')
    with pytest.raises(InputError, match="sweep.not_an_arg"):
        E.plan(E.load_study(p).base, E.load_study(p).sweep)
    p.write_text('[study]\nbuilder = "no_such_builder"\n')
    with pytest.raises(InputError, match="not a scene builder"):
        E.load_study(p)
    p.write_text('[study]\nbuilder = "lamb"\n[extra]\n')
    with pytest.raises(InputError, match="unknown table"):
        E.load_study(p)
    p.write_text('[study]\nbuilder = "lamb"\n[sweep]\nlaw.nope.deeper = [1]\n')
    with pytest.raises(InputError):
        s = E.load_study(p)
        E.plan(s.base, s.sweep)


def test_demo_study_plans_on_the_asperity_builders():
    study = E.load_study(Path(__file__).resolve().parents[2] / "studies" / "asperity_ensemble" / "study.toml")
    members = E.plan(study.base, study.sweep)
    assert 7 <= len(members) <= 9
    names = {E.build_scene(study.base, m.params).name for m in members}
    assert names == {"asperity_row", "random_toughness"}
    scene = E.build_scene(study.base, members[0].params)
    assert scene.grid.shape == (128, 64) and scene.numerics.fft_threads == 1 and scene.record.every == 16


# ---------------------------------------------------------------------------- progress, workers
def test_progress_bars_over_members_and_steps_quiet_off_a_terminal(tmp_path, capsys):
    # a sweep: one bar over the members when asked ...
    res = E.run(E.Builder(FLAKY), {"p": [1.0, 2.0]}, tmp_path / "a.zarr", scheduler="synchronous", progress=True)
    err = capsys.readouterr().err
    assert res.ok and "members: 100%" in err and "2/2" in err
    # ... and none by default when stderr is not a terminal (as under pytest)
    res = E.run(E.Builder(FLAKY), {"p": [1.0, 2.0]}, tmp_path / "b.zarr", scheduler="synchronous")
    assert res.ok and capsys.readouterr().err == ""
    # a single run: one bar over the steps
    scene = flaky_crack()
    cracklab.simulate(scene, progress=True)
    err = capsys.readouterr().err
    assert f"{scene.name}: 100%" in err and f"{scene.nsteps + 1}/{scene.nsteps + 1}" in err and "step" in err
    cracklab.simulate(scene)
    assert capsys.readouterr().err == ""
    # the commands: quiet when the output is not a terminal, a bar with --progress
    path = tmp_path / "scene.toml"
    path.write_text(scene.to_toml())
    runner = CliRunner()
    quiet = runner.invoke(main, ["run", str(path), "-o", str(tmp_path / "r1.zarr")])
    assert quiet.exit_code == 0 and "%|" not in quiet.output, quiet.output
    loud = runner.invoke(main, ["run", str(path), "-o", str(tmp_path / "r2.zarr"), "--progress"])
    assert loud.exit_code == 0 and "100%|" in loud.output, loud.output
    study = tmp_path / "study.toml"
    study.write_text(f'[study]\nbuilder = "{FLAKY}"\n[sweep]\np = [1.0, 2.0]\n')
    quiet = runner.invoke(main, ["sweep", str(study), "-o", str(tmp_path / "s1.zarr"), "--scheduler", "synchronous"])
    assert quiet.exit_code == 0 and "%|" not in quiet.output, quiet.output
    loud = runner.invoke(main, ["sweep", str(study), "-o", str(tmp_path / "s2.zarr"), "--scheduler", "synchronous",
                                "--progress"])
    assert loud.exit_code == 0 and "members: 100%" in loud.output, loud.output


def test_cli_workers_sizes_the_embedded_local_cluster(tmp_path, monkeypatch):
    """--workers N: an embedded LocalCluster of N one-thread worker processes (here 1:
    both members run in the same worker process, not in this one), FFT threads 1."""
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    study = tmp_path / "study.toml"
    study.write_text(f'[study]\nbuilder = "{FLAKY}"\n[sweep]\np = [1.0, 2.0]\n')
    store = tmp_path / "w.zarr"
    res = CliRunner().invoke(main, ["sweep", str(study), "-o", str(store), "--workers", "1"])
    assert res.exit_code == 0, res.output
    workers = {s["id"]: _member_attrs(store, s["id"])["worker"] for s in E.member_status(store)}
    assert len(workers) == 2 and len(set(workers.values())) == 1
    assert not next(iter(workers.values())).endswith(f":{os.getpid()}")
    ens = E.open_ensemble(store)
    assert {E.member_scene(ens, m).numerics.fft_threads for m in ens.member.values} == {1}


def test_embedded_cluster_is_sized_to_the_machine(monkeypatch):
    """Default: one single-threaded worker process per core (never more than members),
    FFT / BLAS threads 1 in the workers."""
    import distributed

    made = {}

    class FakeCluster:
        def __init__(self, **kwargs):
            made.update(kwargs)

        def close(self):
            made["closed"] = True

    class FakeClient:
        def __init__(self, cluster):
            self.cluster = cluster

        def close(self):
            pass

    monkeypatch.setattr(distributed, "LocalCluster", FakeCluster)
    monkeypatch.setattr(distributed, "Client", FakeClient)
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    cores = running.cores()
    with running.dask_client(n_tasks=100):
        pass
    assert made["n_workers"] == cores and made["threads_per_worker"] == 1 and made["processes"] is True
    assert made["env"]["CRACKLAB_FFT_THREADS"] == "1" and made["env"]["OMP_NUM_THREADS"] == "1"
    assert made["closed"]
    with running.dask_client(n_tasks=1):
        pass
    assert made["n_workers"] == 1
    with running.dask_client(workers=3, n_tasks=100):
        pass
    assert made["n_workers"] == 3
