"""Scene units are UDUNITS units of their quantity (or "1"), and a field read from a file
with a ``units`` attr is converted to the scene's unit; unknown units and dimension
mismatches are refused, naming the field."""
from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from cracklab import InputError, Scene, scenes
from cracklab.model.scene_io import scenes_equal
from field_scene import GRID, HEAD

TAU_C = 1.0 + np.random.default_rng(3).random(GRID.shape)



def scene_toml(tmp_path, units=None, law='tau_c = { file = "f.nc", var = "v" }\ndelta_c = 0.01'):
    text = HEAD
    if units is not None:
        text += "\n[units]\n" + "".join(f'{k} = "{v}"\n' for k, v in units.items())
    text += f"\n[law]\nkind = \"linear_cohesive\"\n{law}\n"
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return path


def field_file(tmp_path, units, values=TAU_C, name="f.nc"):
    attrs = {} if units is None else {"units": units}
    ds = xr.Dataset({"v": (("x1", "x3"), values, attrs)}, coords={"x1": GRID.x1, "x3": GRID.x3})
    if name.endswith(".zarr"):
        ds.to_zarr(tmp_path / name, consolidated=False)
    else:
        ds.to_netcdf(tmp_path / name)


SI = {"length": "m", "time": "s", "stress": "Pa"}


def refused(path, field):
    with pytest.raises(InputError) as err:
        Scene.from_toml(path)
    assert err.value.field == field, str(err.value)
    assert "\n" not in str(err.value)
    return str(err.value)


# ------------------------------------------------------------------------ the scene's units
@pytest.mark.parametrize("key, bad, why", [
    ("stress", "banana", "unknown unit 'banana'"),
    ("length", "parsec of bananas", "unknown unit"),
    ("stress", "m", "not a unit of stress"),        # a length where a stress goes
    ("length", "Pa", "not a unit of length"),
    ("time", "m", "not a unit of time"),
    ("time", "seconds since 2000-01-01", "a date"),
    ("stress", "", "unknown unit"),
    ("stress", "-1 Pa", "not a positive multiple of 'Pa'"),
    ("length", "m @ 5", "not a positive multiple of 'm'"),      # an offset unit
])
def test_a_scene_unit_that_is_not_a_unit_of_its_quantity_is_refused(tmp_path, key, bad, why):
    path = scene_toml(tmp_path, {**SI, key: bad}, law="tau_c = 1.0\ndelta_c = 0.01")
    msg = refused(path, f"units.{key}")
    assert why in msg and "accepted: a UDUNITS unit of " + key in msg and '"1"' in msg, msg
    with pytest.raises(InputError, match=f"^units.{key}: "):        # from Python as well
        scenes.asperity_row(n1=16, n3=8, t_end=0.1).replace(units={**SI, key: bad})


@pytest.mark.parametrize("units", [
    {"length": "1", "time": "1", "stress": "1"},
    {"length": "km", "time": "ms", "stress": "MPa"},
    {"length": "furlong", "time": "fortnight", "stress": "bar"},   # units of their quantities, in UDUNITS
    {"length": "m", "time": "1", "stress": "GPa"},
])
def test_units_of_their_quantity_and_dimensionless_ones_are_accepted(tmp_path, units):
    scene = Scene.from_toml(scene_toml(tmp_path, units, law="tau_c = 1.0\ndelta_c = 0.01"))
    assert scene.units == units


# ------------------------------------------------------------------------ fields in files
@pytest.mark.parametrize("scene_stress, file_units, factor", [
    ("Pa", "MPa", 1e6),
    ("Pa", "kPa", 1e3),
    ("MPa", "Pa", 1e-6),
    ("MPa", "MPa", 1.0),
    ("Pa", None, 1.0),           # no units attr: taken as in the scene's unit
    ("1", None, 1.0),
    ("1", "1", 1.0),
])
def test_a_stress_field_is_converted_to_the_scene_unit(tmp_path, scene_stress, file_units, factor):
    field_file(tmp_path, file_units)
    scene = Scene.from_toml(scene_toml(tmp_path, {**SI, "stress": scene_stress}))
    np.testing.assert_allclose(scene.law.tau_c, TAU_C * factor, rtol=1e-12)


def test_a_zarr_field_and_a_loading_and_a_length_are_converted(tmp_path):
    field_file(tmp_path, "mm", name="d.zarr")
    field_file(tmp_path, "kPa", values=np.full(GRID.shape, 0.25), name="t.nc")
    text = scene_toml(tmp_path, SI, law='tau_c = 1.0\ndelta_c = { file = "d.zarr", var = "v" }').read_text()
    path = tmp_path / "scene.toml"
    path.write_text(text.replace("tau0_2 = 0.5", 'tau0_2 = { file = "t.nc", var = "v" }'))
    scene = Scene.from_toml(path)
    np.testing.assert_allclose(scene.law.delta_c, TAU_C * 1e-3, rtol=1e-12)
    np.testing.assert_allclose(scene.loading.tau0_2, 250.0, rtol=1e-12)


@pytest.mark.parametrize("scene_stress, file_units, why", [
    ("Pa", "m", "does not convert to the scene's unit 'Pa'"),     # a stress field in metres
    ("Pa", "1", "does not convert to the scene's unit 'Pa'"),
    ("Pa", "banana", "UDUNITS does not know"),
    ("1", "MPa", "dimensionless"),                                # no scale to convert to
    ("1", "m", "dimensionless"),
])
def test_a_field_in_a_unit_of_another_dimension_is_refused(tmp_path, scene_stress, file_units, why):
    field_file(tmp_path, file_units)
    msg = refused(scene_toml(tmp_path, {**SI, "stress": scene_stress}), "law.tau_c")
    assert why in msg and "'v' of 'f.nc'" in msg and repr(file_units) in msg, msg


def test_a_scene_in_mpa_round_trips_through_its_sidecar(tmp_path):
    scene = scenes.asperity_row(n1=16, n3=8, t_end=0.1).replace(units={"length": "km", "time": "s",
                                                                          "stress": "MPa"})
    scene.to_toml(tmp_path / "s.toml")
    with xr.open_dataset(tmp_path / "s.fields.nc") as ds:
        assert ds["law_tau_c"].attrs["units"] == "MPa"
    back = Scene.from_toml(tmp_path / "s.toml")
    assert scenes_equal(back, scene)
