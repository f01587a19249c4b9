"""The netCDF export: compressed (zlib in chunks through netCDF4) and CF-clean (CF 1.10,
checked offline by tests/cf_rules.py, for a run in dimensionless and in SI units and for
an ensemble: the elapsed time t is a plain coordinate, every dimension has coordinate
values, every numeric variable has units)."""
import os
import warnings

import netCDF4
import numpy as np
import pytest
import xarray as xr

import cracklab
from cf_rules import cf_problems
from cracklab import ensemble as E
from cracklab.ensemble.netcdf import export_netcdf

SI = {"length": "m", "time": "s", "stress": "Pa"}


def _bytes(path):
    return sum(os.path.getsize(os.path.join(r, f)) for r, _, fs in os.walk(path) for f in fs)


@pytest.fixture(scope="module")
def run_store(tmp_path_factory):
    store = tmp_path_factory.mktemp("nc") / "run.zarr"
    scene = cracklab.scenes.asperity_row(n1=64, n3=32, t_end=1.0, diameter=0.25,
                                         record=cracklab.Record(fields=("delta_2", "v_2"), every=2))
    cracklab.simulate(scene, store=str(store))
    return store


def test_export_is_compressed_and_cf_clean(run_store, tmp_path):
    out = tmp_path / "run.nc"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        export_netcdf(run_store, out)
    ds = xr.open_zarr(run_store, consolidated=False)
    raw = sum(v.nbytes for v in ds.data_vars.values())
    size = os.path.getsize(out)
    # 1.1 MB of fields: a few % of it, and not far from Zarr's zstd chunks (the HDF5 headers
    # of a dozen variables are most of the difference on a run this small)
    assert size < 0.08 * raw and size < 2.2 * _bytes(run_store), (size, raw, _bytes(run_store))
    with netCDF4.Dataset(out) as nc:
        for name in ("delta_2", "v_2", "rupture_time", "input_law_tau_c"):
            assert nc[name].filters()["zlib"] is True and nc[name].chunking() != "contiguous", name
        assert "standard_name" not in nc["t"].ncattrs() and nc["t"].getncattr("units") == "1"
        assert "axis" not in nc["t"].ncattrs()              # elapsed time, not a CF time (4.4)
        assert nc["input_x1"].getncattr("units") == "1" and nc["input_x3"].getncattr("units") == "1"
        for dim in nc.dimensions:                       # a coordinate variable on every dimension
            assert dim in nc.variables, dim
        np.testing.assert_allclose(nc["input_x1"][:], np.arange(64) * 2.0 / 64)
        np.testing.assert_allclose(nc["input_x3"][:], np.arange(32) * 1.0 / 32)
    back = xr.open_dataset(out, engine="netcdf4")
    np.testing.assert_array_equal(back.delta_2.values, ds.delta_2.values)
    np.testing.assert_array_equal(back.rupture_time.values, ds.rupture_time.values)
    assert cracklab.scene_of(back).grid.n1 == 64
    back.close()
    assert cf_problems(out) == []


def test_axis_t_and_standard_name_time_stay_only_on_a_time_with_a_reference_time(tmp_path):
    """CF 1.10 section 4.4: a variable with axis T or standard_name time is a time
    coordinate, whose units need a reference time; a run's elapsed t ("s", "1") loses both."""
    from cracklab.ensemble.netcdf import netcdf_ready

    ds = xr.Dataset({"a": (("t", "k"), np.zeros((2, 3)))},
                    coords={"t": ("t", [0.0, 1.0], {"units": "s since 2000-01-01", "standard_name": "time",
                                                    "axis": "T"})})
    out = netcdf_ready(ds)
    assert out.t.attrs["standard_name"] == "time" and out.t.attrs["axis"] == "T" and list(out.k.values) == [0, 1, 2]
    assert out.k.attrs["units"] == "1"
    for units in ("s", "1"):
        ds["t"].attrs["units"] = units
        out = netcdf_ready(ds)
        assert "standard_name" not in out.t.attrs and "axis" not in out.t.attrs, units
        assert out.t.attrs["units"] == units
    assert ds.t.attrs["axis"] == "T"                        # the input is not changed


def test_a_run_in_si_units_is_cf_clean(tmp_path):
    scene = cracklab.scenes.asperity_row(n1=32, n3=16, t_end=0.5, diameter=0.25,
                                         record=cracklab.Record(fields=("delta_2", "v_2"), every=4,
                                                                stations={"c": (1.0, 0.5)})).replace(units=SI)
    store = tmp_path / "si.zarr"
    cracklab.simulate(scene, store=str(store))
    assert xr.open_zarr(store, consolidated=False).t.attrs["axis"] == "T"      # the store keeps its axes
    out = export_netcdf(store, tmp_path / "si.nc")
    with netCDF4.Dataset(out) as nc:
        t = nc["t"]
        assert t.getncattr("units") == "s" and "axis" not in t.ncattrs() and "standard_name" not in t.ncattrs()
        assert nc["input_x1"].getncattr("units") == "m" and nc["v_2"].getncattr("units") == "m s-1"
        assert nc["station"].getncattr("long_name") == "station name"
    assert cf_problems(out) == []


def test_an_ensemble_is_cf_clean(tmp_path):
    """A sweep of a builder argument and a scene key over dimensionless scenes, and of a
    scene key over a scene in SI units: the swept parameters carry their units."""
    base = E.Builder("asperity_row", n1=32, n3=16, t_end=0.3, diameter=0.25)
    E.run(base, E.Sweep(product={"contrast": [1.5, 3.0], "material.mu": [1.0, 2.0]}), tmp_path / "a.zarr",
          scheduler="synchronous", progress=False)
    out = export_netcdf(tmp_path / "a.zarr", tmp_path / "a.nc")
    with netCDF4.Dataset(out) as nc:
        assert nc.dimensions["member"].size == 4
        assert nc["contrast"].getncattr("units") == "1" and nc["material_mu"].getncattr("units") == "1"
        assert "axis" not in nc["t"].ncattrs()
    assert cf_problems(out) == []

    scene = cracklab.scenes.asperity_row(n1=32, n3=16, t_end=0.3, diameter=0.25).replace(units=SI)
    E.run(scene, E.Sweep(product={"material.mu": [1.0, 2.0], "material.cs": [1.0]}), tmp_path / "b.zarr",
          scheduler="synchronous", progress=False)
    out = export_netcdf(tmp_path / "b.zarr", tmp_path / "b.nc")
    with netCDF4.Dataset(out) as nc:
        assert nc["material_mu"].getncattr("units") == "Pa" and nc["material_cs"].getncattr("units") == "m s-1"
        assert nc["input_x1"].getncattr("units") == "m" and nc["t"].getncattr("units") == "s"
    assert cf_problems(out) == []


def test_the_cf_check_finds_what_the_export_used_to_get_wrong(run_store, tmp_path):
    """The check can fail: the old export's faults (a dimensionless t with axis T, a t in
    seconds with standard_name time, input_x1 without units) and others, put back into a
    clean export, are each reported under their section."""
    import shutil

    clean = export_netcdf(run_store, tmp_path / "clean.nc")
    cases = [
        (lambda nc: nc["t"].setncattr("axis", "T"), "4.4 t:"),
        (lambda nc: (nc["t"].setncattr("units", "s"), nc["t"].setncattr("standard_name", "time")), "4.4 t:"),
        (lambda nc: nc["input_x1"].delncattr("units"), "3.1 input_x1:"),
        (lambda nc: nc["delta_2"].setncattr("units", "banana"), "3.1 delta_2:"),
        (lambda nc: nc["delta_2"].setncattr("standard_name", "air_temperature"), "3.3 delta_2:"),
        (lambda nc: nc["x3"].setncattr("axis", "X"), "4 delta_2:"),
        (lambda nc: nc["station"].delncattr("long_name") if "station" in nc.variables else
         nc["delta_2"].delncattr("long_name"), "3 "),
        (lambda nc: nc.setncattr("Conventions", "CF-1.8"), "2.6.1"),
    ]
    for i, (spoil, expected) in enumerate(cases):
        path = tmp_path / f"spoilt{i}.nc"
        shutil.copy(clean, path)
        with netCDF4.Dataset(path, "a") as nc:
            spoil(nc)
        problems = cf_problems(path)
        assert any(p.startswith(expected) for p in problems), (expected, problems)
