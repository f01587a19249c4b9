"""The summary of a fault run gives rupture measures, checked against numpy by hand."""
import dataclasses

import numpy as np
import pytest
import xarray as xr

import cracklab
from cracklab.analysis import summary


@pytest.fixture(scope="module")
def fault_run(tmp_path_factory):
    scene = cracklab.scenes.tpv3(dx=1500.0, t_end=3.0)
    scene = scene.replace(record=dataclasses.replace(scene.record, fields=("delta_1", "delta_3", "v_1", "v_3")))
    path = tmp_path_factory.mktemp("fault") / "tpv3.zarr"
    cracklab.simulate(scene, store=str(path))
    return path, scene


def test_fault_summary_measures(fault_run):
    path, scene = fault_run
    ds = xr.open_zarr(path, consolidated=False)
    row = summary(str(path))
    rt = ds["rupture_time"].values
    ok = np.isfinite(rt)
    cell = 1500.0 * 1500.0
    assert ok.sum() > 1
    assert float(row["rupture_area"]) == pytest.approx(ok.sum() * cell)
    slip = np.hypot(ds["delta_1"].isel(t=-1).values, ds["delta_3"].isel(t=-1).values)
    assert float(row["mean_slip"]) == pytest.approx(slip[ok].mean())
    assert float(row["moment"]) == pytest.approx(scene.material.mu * np.sum(slip[ok] * cell))
    peak = max(np.hypot(ds["station_v_1"].values, ds["station_v_3"].values).max(),
               np.hypot(ds["v_1"].values, ds["v_3"].values).max())
    assert float(row["peak_slip_rate"]) == pytest.approx(peak)
    assert "station" in row["peak_slip_rate"].attrs["source"] and "snapshots" in row["peak_slip_rate"].attrs["source"]
    assert float(row["first_rupture"]) == pytest.approx(rt[ok].min())
    assert float(row["median_rupture"]) == pytest.approx(np.median(rt[ok]))
    assert float(row["last_rupture_time"]) == pytest.approx(rt[ok].max())
    # the mode I crack measures do not apply to a fault
    assert np.isnan(float(row["front_position"])) and np.isnan(float(row["late_front_speed"]))


def test_fault_summary_without_slip_fields_is_nan(tmp_path):
    path = tmp_path / "tpv3.zarr"
    cracklab.simulate(cracklab.scenes.tpv3(dx=1500.0, t_end=3.0), store=str(path))
    row = summary(str(path))
    assert np.isnan(float(row["mean_slip"])) and np.isnan(float(row["moment"]))
    assert row["peak_slip_rate"].attrs["source"] == "station series"
    assert np.isfinite(float(row["rupture_area"]))
