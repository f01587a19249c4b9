"""The netCDF export: compressed (zlib in chunks through netCDF4) and CF-clean (a
dimensionless time is not a CF time; every dimension has coordinate values)."""
import os
import warnings

import netCDF4
import numpy as np
import pytest
import xarray as xr

import cracklab
from cracklab.output.netcdf import export_netcdf


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
        for dim in nc.dimensions:                       # a coordinate variable on every dimension
            assert dim in nc.variables, dim
        np.testing.assert_allclose(nc["input_x1"][:], np.arange(64) * 2.0 / 64)
        np.testing.assert_allclose(nc["input_x3"][:], np.arange(32) * 1.0 / 32)
    back = xr.open_dataset(out, engine="netcdf4")
    np.testing.assert_array_equal(back.delta_2.values, ds.delta_2.values)
    np.testing.assert_array_equal(back.rupture_time.values, ds.rupture_time.values)
    assert cracklab.scene_of(back).grid.n1 == 64
    back.close()


def test_a_time_in_seconds_keeps_its_standard_name(tmp_path):
    from cracklab.output.netcdf import netcdf_ready

    ds = xr.Dataset({"a": (("t", "k"), np.zeros((2, 3)))},
                    coords={"t": ("t", [0.0, 1.0], {"units": "s", "standard_name": "time"})})
    out = netcdf_ready(ds)
    assert out.t.attrs["standard_name"] == "time" and list(out.k.values) == [0, 1, 2]
    ds["t"].attrs["units"] = "1"
    assert "standard_name" not in netcdf_ready(ds).t.attrs
