"""The Dataset that cracklab.simulate returns (API.md, "Output Dataset")."""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
import xarray as xr

import cracklab
from cracklab import (Grid, LinearCohesive, Loading, Material, Numerics, Record, Scene, SimulationError,
                      TractionFree, scene_of, simulate, stations)

MAT = Material(mu=1.0, cs=1.0, nu=0.25)
GRID = Grid(n1=16, n3=8, L1=1.0, L3=0.5)
X1, X3 = np.meshgrid(GRID.x1, GRID.x3, indexing="ij")
CRACK = np.abs(X1 - 0.5) < 0.1
BONDED = X3 > 0.4
FIELDS = ("delta_2", "v_2", "tau_2", "strength")
STATIONS = {"centre": (0.5, 0.25), "tip": (0.6875, 0.25), "near": (0.13, 0.01)}


def make_scene(record, *, t_end=0.3, **changes):
    law = LinearCohesive(tau_c=1.0, delta_c=0.02, initial_crack=CRACK, bonded=BONDED)
    return Scene(material=MAT, grid=GRID, law=law, loading=Loading(tau0_2=np.where(CRACK, 0.8, 0.5)),
                 t_end=t_end, beta=0.25, record=record, name="output-test", **changes)


@pytest.fixture(scope="module")
def every_step():
    """Every step, whole grid, stations: the reference the other recordings are cut from."""
    sc = make_scene(Record(fields=FIELDS, every=1, stations=STATIONS))
    return sc, simulate(sc)


# ---------------------------------------------------------------------------- layout and attrs
def test_dims_coords_and_cf_attrs(every_step):
    sc, res = every_step
    for dim in ("t", "x1", "x3"):
        assert dim in res.dims and dim in res.coords
        attrs = res[dim].attrs
        assert attrs.get("units") and attrs.get("long_name") and attrs.get("axis"), (dim, attrs)
    assert res["t"].attrs["axis"] == "T" and res["x1"].attrs["axis"] == "X"
    np.testing.assert_array_equal(res["x1"].values, GRID.x1)
    np.testing.assert_array_equal(res["x3"].values, GRID.x3)
    for name in FIELDS:
        assert res[name].dims == ("t", "x1", "x3")
        assert res[name].shape == (sc.nsteps + 1, 16, 8)


def test_every_variable_has_units_and_long_name(every_step):
    _, res = every_step
    # every data variable (grid fields, rupture time, station series, the scene's input
    # fields) and every numeric coordinate; the station names are labels without units
    names = list(res.data_vars) + [n for n in res.coords if res[n].dtype.kind == "f"]
    assert {"t", "x1", "x3", "rupture_time"} <= set(names)
    assert [n for n in names if n.startswith("input_")], "the scene's arrays are stored"
    for name in names:
        var = res[name]
        assert var.attrs.get("long_name"), name
        assert "units" in var.attrs and isinstance(var.attrs["units"], str), name
    units = {n: res[n].attrs["units"] for n in FIELDS}
    assert set(units.values()) == {"1"}   # dimensionless scene


def test_units_follow_the_scene_units():
    sc = make_scene(Record(fields=("delta_2", "v_2", "tau_2"), every=5), t_end=0.05,
                    units={"length": "m", "time": "s", "stress": "Pa"})
    res = simulate(sc)
    assert res["delta_2"].attrs["units"] == "m"
    assert res["tau_2"].attrs["units"] == "Pa"
    assert res["t"].attrs["units"] == "s" and res["x1"].attrs["units"] == "m"
    assert res["rupture_time"].attrs["units"] == "s"
    # velocity: length per time, whatever the spelling
    assert "m" in res["v_2"].attrs["units"] and "s" in res["v_2"].attrs["units"]


def test_only_requested_fields_are_present():
    sc = make_scene(Record(fields=("tau_2",), every=10), t_end=0.1)
    res = simulate(sc)
    grid_vars = [n for n in res.data_vars if "t" in res[n].dims]
    assert grid_vars == ["tau_2"]
    assert "rupture_time" in res.data_vars
    assert not [n for n in res.data_vars if n.startswith("station_")]
    with pytest.raises(ValueError, match="stations"):
        stations(res)


# ---------------------------------------------------------------------------- cadence and region
def test_every_gives_every_nth_step(every_step):
    ref_sc, ref = every_step
    sc = make_scene(Record(fields=("delta_2",), every=7))
    res = simulate(sc)
    n = np.arange(0, sc.nsteps + 1, 7)
    np.testing.assert_allclose(res["t"].values, n * sc.dt, rtol=1e-14, atol=0)
    np.testing.assert_array_equal(res["delta_2"].values, ref["delta_2"].values[n])


def test_default_cadence_keeps_about_twenty_snapshots():
    sc = make_scene(Record(fields=("delta_2",)))
    res = simulate(sc)
    assert 15 <= res.sizes["t"] <= 25
    assert res["t"].values[0] == 0.0
    steps = res["t"].values / sc.dt
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-9)
    assert np.ptp(np.diff(steps)) < 1e-9   # evenly spaced


def test_times_gives_the_nearest_steps(every_step):
    _, ref = every_step
    dt = 0.25 * GRID.dx_min / MAT.cs
    asked = np.array([0.0, 0.1, 10 * dt, 0.3])     # 0.1 and 0.3 fall between steps
    sc = make_scene(Record(fields=("delta_2",), times=tuple(asked)))
    assert sc.dt == dt
    res = simulate(sc)
    t = res["t"].values
    assert t.size == 4
    np.testing.assert_allclose(t, [0.0, 6 * dt, 10 * dt, 19 * dt], rtol=1e-14)
    assert np.all(np.abs(t - asked) <= dt / 2 + 1e-12)
    idx = np.rint(t / dt).astype(int)
    np.testing.assert_array_equal(res["delta_2"].values, ref["delta_2"].values[idx])
    with pytest.raises(cracklab.InputError, match="record.times"):
        make_scene(Record(fields=("delta_2",), times=(0.5,)))


def test_region_gives_the_sub_grid(every_step):
    _, ref = every_step
    sc = make_scene(Record(fields=FIELDS, every=1, region={"x1": (0.2, 0.6), "x3": (0.1, 0.3)}))
    res = simulate(sc)
    i = (GRID.x1 >= 0.2) & (GRID.x1 <= 0.6)
    k = (GRID.x3 >= 0.1) & (GRID.x3 <= 0.3)
    np.testing.assert_array_equal(res["x1"].values, GRID.x1[i])
    np.testing.assert_array_equal(res["x3"].values, GRID.x3[k])
    for name in FIELDS:
        np.testing.assert_array_equal(res[name].values, ref[name].values[:, i][:, :, k])
    np.testing.assert_array_equal(res["rupture_time"].values, ref["rupture_time"].values[i][:, k])
    assert res["rupture_time"].dims == ("x1", "x3")


# ---------------------------------------------------------------------------- stations
def test_stations_are_series_at_the_nearest_nodes_every_step(every_step):
    sc, res = every_step
    st = stations(res)
    assert st["delta_2"].dims == ("station", "t")
    assert list(st["station"].values) == list(STATIONS)
    np.testing.assert_allclose(st["t"].values, np.arange(sc.nsteps + 1) * sc.dt, rtol=1e-14)
    nearest = {name: (int(round(x1 / GRID.dx1)) % 16, int(round(x3 / GRID.dx3)) % 8)
               for name, (x1, x3) in STATIONS.items()}
    assert nearest["near"] == (2, 0)
    for j, (name, (i, k)) in enumerate(nearest.items()):
        assert st["x1"].values[j] == GRID.x1[i] and st["x3"].values[j] == GRID.x3[k]
        for f in FIELDS:
            np.testing.assert_array_equal(st[f].sel(station=name).values, res[f].values[:, i, k])
    for f in FIELDS:
        assert st[f].attrs["units"] and st[f].attrs["long_name"]
    assert "x1" in st.coords and "x3" in st.coords


def test_stations_without_grid_fields():
    sc = make_scene(Record(fields=(), stations={"a": (0.5, 0.25)}), t_end=0.1)
    res = simulate(sc)
    st = stations(res)
    assert st.sizes == {"station": 1, "t": sc.nsteps + 1}
    assert not [n for n in res.data_vars if "t" in res[n].dims]


# ---------------------------------------------------------------------------- rupture time
def test_rupture_time(every_step):
    sc, res = every_step
    rt = res["rupture_time"]
    assert rt.dims == ("x1", "x3")
    assert rt.attrs["units"] and rt.attrs["long_name"]
    v = res["v_2"].values
    moved = np.abs(v) > 0
    first = np.where(moved.any(axis=0), res["t"].values[np.argmax(moved, axis=0)], np.nan)
    np.testing.assert_array_equal(np.isnan(rt.values), np.isnan(first))
    np.testing.assert_allclose(rt.values[np.isfinite(first)], first[np.isfinite(first)], rtol=0, atol=0)
    # bonded points never fail; the initial crack fails at t = 0; something in between grows
    assert np.all(np.isnan(rt.values[BONDED]))
    assert np.all(rt.values[CRACK & ~BONDED] == 0.0)
    grown = np.isfinite(rt.values) & ~CRACK
    assert grown.any() and np.isnan(rt.values[~BONDED]).any()


def test_rupture_threshold():
    sc = make_scene(Record(fields=("v_2",), every=1), numerics=Numerics(rupture_threshold=0.3))
    res = simulate(sc)
    speed = np.abs(res["v_2"].values)
    over = speed > 0.3
    first = np.where(over.any(axis=0), res["t"].values[np.argmax(over, axis=0)], np.nan)
    np.testing.assert_array_equal(res["rupture_time"].values, first)


# ---------------------------------------------------------------------------- scene round trip
def assert_same_scene(a, b):
    assert a.material == b.material and a.grid == b.grid
    assert type(a.law) is type(b.law)
    for f in dataclasses.fields(a.law):
        x, y = getattr(a.law, f.name), getattr(b.law, f.name)
        if x is None or y is None:
            assert x is None and y is None, f.name
        else:
            assert np.array_equal(np.asarray(x), np.asarray(y)), f.name
            assert np.shape(x) == np.shape(y), f.name
    for f in dataclasses.fields(a.loading):
        assert np.array_equal(np.asarray(getattr(a.loading, f.name)), np.asarray(getattr(b.loading, f.name)))
    assert a.record == b.record and a.numerics == b.numerics
    assert (a.t_end, a.beta, a.units, a.name) == (b.t_end, b.beta, b.units, b.name)
    assert a.dt == b.dt and a.nsteps == b.nsteps and a.components == b.components


def test_global_attrs_and_scene_of(every_step):
    sc, res = every_step
    assert res.attrs["cracklab_version"] == cracklab.__version__
    data = json.loads(res.attrs["scene"])
    assert data["law"]["kind"] == "linear_cohesive"
    assert data["grid"] == {"n1": 16, "n3": 8, "L1": 1.0, "L3": 0.5}
    assert data["material"] == {"mu": 1.0, "cs": 1.0, "nu": 0.25}
    assert data["beta"] == 0.25 and data["t_end"] == 0.3
    again = scene_of(res)
    assert_same_scene(again, sc)
    # the rebuilt scene is runnable and gives the same run
    short = dataclasses.replace(again, t_end=0.05, record=Record(fields=("delta_2",), every=1))
    a = simulate(short)["delta_2"].values
    b = res["delta_2"].values[: a.shape[0]]
    np.testing.assert_array_equal(a, b)


def test_scene_of_with_scalar_fields_and_other_laws():
    sc = Scene(material=Material(mu=3.0, cs=2.0, nu=0.2), grid=Grid(n1=16, n3=1, L1=2.0, L3=1.0),
               law=cracklab.SlipWeakening(mu_s=0.6, mu_d=0.4, D_c=0.1, sigma_n=1.0),
               loading=Loading(tau0_3=0.61, time="ramp", ramp_time=0.2),
               t_end=0.1, beta=0.3, record=Record(fields=("v_3",), every=2),
               numerics=Numerics(formulation="velocity", rupture_threshold=1e-3))
    assert_same_scene(scene_of(simulate(sc)), sc)


# ---------------------------------------------------------------------------- zarr store
@pytest.mark.parametrize("record", [Record(fields=FIELDS, every=1, stations=STATIONS),
                                    Record(fields=("delta_2",), every=3, region={"x1": (0.3, 0.7)})],
                         ids=["every-step", "region"])
def test_store_is_lazy_and_equals_the_in_memory_run(tmp_path, record):
    import dask.array as da

    sc = make_scene(record)
    mem = simulate(sc)
    path = tmp_path / "run.zarr"
    lazy = simulate(sc, store=path)
    assert path.exists()
    for name in record.fields:
        assert isinstance(lazy[name].data, da.Array), name
    assert set(lazy.data_vars) == set(mem.data_vars)
    for name in mem.variables:
        np.testing.assert_array_equal(lazy[name].values, mem[name].values, err_msg=name)
        assert lazy[name].dims == mem[name].dims, name
        for key in ("units", "long_name", "axis"):
            assert lazy[name].attrs.get(key) == mem[name].attrs.get(key), (name, key)
    assert lazy.attrs["scene"] == mem.attrs["scene"]
    assert lazy.attrs["cracklab_version"] == cracklab.__version__
    assert_same_scene(scene_of(lazy), sc)
    if record.stations:
        xr.testing.assert_equal(stations(lazy).load(), stations(mem))
    opened = xr.open_zarr(path, consolidated=False)
    for name in record.fields:
        np.testing.assert_array_equal(opened[name].values, mem[name].values)
    np.testing.assert_array_equal(opened["t"].values, mem["t"].values)


# ---------------------------------------------------------------------------- blow-up
BAD_STEP, BAD_NODE = 13, (5, 3)


@pytest.fixture
def inject_nan(monkeypatch):
    """Make step (v) return NaN at one node of one step, as a blow-up would."""
    from cracklab.laws import Law

    real = Law.solve
    calls = {"n": 0}

    def faulty(*args, **kwargs):
        v, tau = real(*args, **kwargs)
        if calls["n"] == BAD_STEP:
            v[2] = v[2].copy()
            v[2][BAD_NODE] = np.nan
        calls["n"] += 1
        return v, tau

    monkeypatch.setattr(Law, "solve", faulty)


@pytest.mark.parametrize("use_store", [False, True], ids=["memory", "store"])
def test_blow_up_raises_and_keeps_what_was_recorded(inject_nan, tmp_path, use_store):
    sc = make_scene(Record(fields=("delta_2", "v_2"), every=2, stations=STATIONS))
    path = tmp_path / "run.zarr" if use_store else None
    with pytest.raises(SimulationError) as info:
        simulate(sc, store=path)
    msg = str(info.value)
    assert f"step {BAD_STEP}" in msg
    assert f"({BAD_NODE[0]}, {BAD_NODE[1]})" in msg
    assert f"x1 = {GRID.x1[BAD_NODE[0]]:g}" in msg and f"x3 = {GRID.x3[BAD_NODE[1]]:g}" in msg
    partial = info.value.partial
    # snapshots up to the last good step (12), station series for steps 0..12
    expected_t = np.arange(0, BAD_STEP, 2) * sc.dt
    np.testing.assert_allclose(partial["t"].values, expected_t, rtol=1e-14)
    assert np.all(np.isfinite(partial["delta_2"].values))
    st = stations(partial)
    assert st.sizes["t"] == BAD_STEP
    assert np.all(np.isfinite(st["v_2"].values))
    good = simulate(make_scene(Record(fields=("delta_2",), every=2), t_end=(BAD_STEP - 1) * sc.dt * 1.0000001))
    np.testing.assert_array_equal(partial["delta_2"].values, good["delta_2"].values[: expected_t.size])
    if use_store:
        back = xr.open_zarr(path, consolidated=False)
        np.testing.assert_allclose(back["t"].values, expected_t, rtol=1e-14)
        np.testing.assert_array_equal(back["delta_2"].values, partial["delta_2"].values)
        assert "scene" in back.attrs


@pytest.mark.filterwarnings("ignore:overflow:RuntimeWarning", "ignore:invalid value:RuntimeWarning")
def test_a_real_blow_up_is_reported():
    """An unstable time step (forced past the Scene's check) overflows and is reported."""
    g = Grid(n1=16, n3=1, L1=1.0, L3=1.0)
    rng = np.random.default_rng(1)
    sc = Scene(material=MAT, grid=g, law=TractionFree(), loading=Loading(tau0_1=rng.standard_normal(g.shape)),
               t_end=1.0, beta=0.05, record=Record(fields=("v_1",), every=1))
    with pytest.raises(cracklab.InputError, match="beta"):
        dataclasses.replace(sc, beta=3.0)
    object.__setattr__(sc, "beta", 3.0)   # bypass validation to make a genuine blow-up
    object.__setattr__(sc, "t_end", 3.0 * g.dx1 * 2000)
    with pytest.raises(SimulationError, match=r"step \d+ .* node \(\d+, 0\)") as info:
        simulate(sc)
    partial = info.value.partial
    assert partial.sizes["t"] >= 2
    assert np.all(np.isfinite(partial["v_1"].values))
