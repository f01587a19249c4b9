"""Scenes as data: lossless round trips through xarray, Zarr, netCDF and TOML, and
one clear InputError for bad input at the boundary."""
import math
import tomllib

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

from cracklab import (Grid, InputError, LinearCohesive, Loading, Material, Numerics, PrescribedRupture,
                      Record, Scene, SlipWeakening, TractionFree, scene_of, scenes, simulate)
from cracklab.cli import main
from cracklab.model.scene_io import (scene_from_data, scene_from_dataset, scene_from_toml, scene_to_data,
                         scene_to_dataset, scene_to_toml, scenes_equal)

MAT = Material(mu=1.0, cs=1.0, nu=0.25)


def prescribed():
    """inf strength, a tuple origin, times, region, stations, ramp, window, SI units."""
    grid = Grid(n1=16, n3=8, L1=2.0, L3=1.0)
    law = PrescribedRupture(speed=0.7, origin=(1.0, 0.5), residual=0.1, strength_before=np.inf,
                            weakening_time=0.05)
    return Scene(material=Material(mu=3.0e10, cs=3464.0, nu=0.25), grid=grid, law=law,
                 loading=Loading(tau0_1=0.3, tau0_3=0.1 + 0.2, time="smooth", ramp_time=0.1),
                 t_end=1e-4, beta=0.05, record=Record(fields=("delta_1", "v_3"), times=(0.0, 5e-5),
                                                     region={"x1": (0.5, 1.5)},
                                                     stations={"a": (0.25, 0.5), "b.c": (1.0, 0.0)}),
                 numerics=Numerics(window=40.0, rupture_threshold=1e-3),
                 units={"length": "m", "time": "s", "stress": "Pa"}, name="prescribed")


def cohesive_fields(dtype=np.float64):
    """Every law parameter a field, and the load."""
    grid = Grid(n1=16, n3=16, L1=1.0, L3=1.0)
    rng = np.random.default_rng(3)
    crack = rng.random(grid.shape) < 0.2
    law = LinearCohesive(tau_c=1.0 + rng.random(grid.shape), delta_c=0.01 + 0.01 * rng.random(grid.shape),
                         initial_crack=crack, bonded=rng.random(grid.shape) < 0.05)
    return Scene(material=MAT, grid=grid, law=law, loading=Loading(tau0_2=rng.random(grid.shape).astype(dtype)),
                 t_end=0.1, record=Record(fields=(), stations={}), name="fields")


SCENES = {
    "elliptical": lambda: scenes.elliptical_crack(n=16, a=0.2, b=0.1, t_end=0.1),
    "tpv3": lambda: scenes.tpv3(dx=2000.0, t_end=1.0),
    "plane-slip": lambda: Scene(material=MAT, grid=Grid(n1=32, n3=1, L1=1.0, L3=1.0),
                                law=SlipWeakening(mu_s=0.6, mu_d=0.5, D_c=0.01, sigma_n=1.0),
                                loading=Loading(tau0_3=0.55), t_end=0.2, beta=0.4,
                                record=Record(fields=("v_3",), every=3),
                                numerics=Numerics(formulation="velocity")),
    "traction-free": lambda: Scene(material=MAT, grid=Grid(n1=16, n3=16, L1=1.0, L3=1.0),
                                   law=TractionFree(contact=True), loading=Loading(tau0_2=1),
                                   t_end=0.1),
    "prescribed": prescribed,
    "fields": cohesive_fields,
    "asperities": lambda: scenes.asperity_row(n1=64, n3=32, t_end=0.5),
    "random-Gc": lambda: scenes.random_toughness(n1=64, n3=32, quantity="Gc", t_end=0.5),
}


@pytest.fixture(params=sorted(SCENES))
def scene(request):
    return SCENES[request.param]()


def test_dataset_roundtrip_is_lossless(scene):
    ds = scene_to_dataset(scene)
    again = scene_from_dataset(ds)
    assert scenes_equal(again, scene)
    assert scenes_equal(Scene.from_dataset(scene.to_dataset()), scene)


def test_toml_roundtrip_is_lossless(scene):
    text = scene_to_toml(scene)
    tomllib.loads(text)                      # plain TOML
    assert scenes_equal(scene_from_toml(text), scene)
    assert scenes_equal(Scene.from_toml(scene.to_toml()), scene)


def test_data_roundtrip_is_lossless(scene):
    data, arrays = scene_to_data(scene)
    assert scenes_equal(scene_from_data(data, arrays), scene)


def test_toml_field_dtype_becomes_float64():
    """TOML has one float type: a float32 field comes back as float64, same values
    (the Dataset keeps the dtype)."""
    sc = cohesive_fields(np.float32)
    assert scenes_equal(scene_from_dataset(scene_to_dataset(sc)), sc)
    again = scene_from_toml(scene_to_toml(sc))
    assert again.loading.tau0_2.dtype == np.float64
    np.testing.assert_array_equal(again.loading.tau0_2, sc.loading.tau0_2)
    assert scenes_equal(again.law, sc.law)


@pytest.mark.parametrize("fmt", ["zarr", "netcdf"])
def test_dataset_survives_the_store(tmp_path, fmt, scene):
    ds = scene_to_dataset(scene)
    if fmt == "zarr":
        ds.to_zarr(tmp_path / "s.zarr", mode="w", consolidated=False)
        back = xr.open_zarr(tmp_path / "s.zarr", consolidated=False).load()
    else:
        ds.to_netcdf(tmp_path / "s.nc")
        back = xr.open_dataset(tmp_path / "s.nc").load()
    assert scenes_equal(scene_from_dataset(back), scene)


def test_bits_inf_and_booleans_survive():
    sc = prescribed()
    sc = sc.replace(loading=Loading(tau0_1=0.1 + 0.2, tau0_3=1e-300, time="smooth", ramp_time=1 / 3))
    for again in (scene_from_dataset(scene_to_dataset(sc)), scene_from_toml(scene_to_toml(sc))):
        assert again.law.strength_before == math.inf
        assert again.loading.tau0_1 == 0.30000000000000004 and again.loading.tau0_3 == 1e-300
        assert again.loading.ramp_time.hex() == (1 / 3).hex()
        assert again.loading.constant_K is False
        assert again.record.stations == {"a": (0.25, 0.5), "b.c": (1.0, 0.0)}
        assert again.record.region == {"x1": (0.5, 1.5)} and again.record.times == (0.0, 5e-5)
        assert isinstance(again.law.origin, tuple)
    tf = SCENES["traction-free"]()
    assert scene_from_toml(scene_to_toml(tf)).law.contact is True
    assert scene_from_dataset(scene_to_dataset(tf)).law.contact is True
    assert "inf" in scene_to_toml(sc)


def test_dataset_layout():
    sc = scenes.asperity_row(n1=64, n3=32, t_end=0.5)
    ds = scene_to_dataset(sc)
    assert ds.attrs["material.mu"] == 1.0 and ds.attrs["grid.n1"] == 64
    assert ds.attrs["law.kind"] == "linear_cohesive" and ds.attrs["scene"] == sc.name
    assert ds.attrs["loading.constant_K"] == "true" and ds.attrs["t_end"] == 0.5
    assert ds.attrs["units.length"] == "1"
    for name in ("law_tau_c", "law_initial_crack", "law_bonded"):
        assert ds[name].dims == ("x1", "x3")
        assert ds[name].attrs["long_name"] and "units" in ds[name].attrs
    assert ds["law_bonded"].dtype == bool and ds["law_tau_c"].dtype == np.float64
    np.testing.assert_array_equal(ds["x1"].values, sc.grid.x1)
    np.testing.assert_array_equal(ds["x3"].values, sc.grid.x3)
    assert "law.tau_c" not in ds.attrs and "law.delta_c" in ds.attrs
    # transposed variables read the same
    t = ds.transpose("x3", "x1")
    assert scenes_equal(scene_from_dataset(t), sc)


def test_scene_from_a_run_output_equals_scene_of(tmp_path):
    sc = scenes.asperity_row(n1=64, n3=32, t_end=0.05, record=Record(fields=("delta_2",), every=2,
                                                                     region={"x1": (0.2, 0.6)}))
    res = simulate(sc, store=tmp_path / "run.zarr")
    assert scenes_equal(scene_of(res), sc)
    assert scenes_equal(scene_from_dataset(res), sc)
    assert scenes_equal(scene_from_dataset(xr.open_zarr(tmp_path / "run.zarr", consolidated=False)), sc)


# ---------------------------------------------------------------------------- validation
BASE = """
t_end = 0.05
beta = 0.5
name = "v"

[material]
mu = 1.0
cs = 1.0
nu = 0.25

[grid]
n1 = 16
n3 = 16
L1 = 1.0
L3 = 1.0

[law]
kind = "linear_cohesive"
tau_c = 1.0
delta_c = 0.01

[loading]
tau0_2 = 1.2

[record]
fields = ["delta_2"]
every = 2

[numerics]
formulation = "displacement"
"""


def test_base_is_valid():
    sc = scene_from_toml(BASE)
    assert sc.grid.n1 == 16 and sc.law.tau_c == 1.0


def edit(old, new):
    assert old in BASE, old
    return BASE.replace(old, new, 1)


ROW16 = "[" + ", ".join(["1.0"] * 16) + "]"
BAD = [
    # unknown keys, at every level
    (edit("name = \"v\"", "name = \"v\"\ncolour = 1"), "colour", "unknown key; accepted"),
    (edit("n3 = 16", "n3 = 16\nspacing = 2"), "grid.spacing", "unknown key"),
    (edit("tau_c = 1.0", "tau_c = 1.0\nmu_s = 0.5"), "law.mu_s", "unknown key; accepted"),
    (edit("every = 2", "every = 2\nstride = 2"), "record.stride", "unknown key"),
    (edit("formulation = \"displacement\"", "formulation = \"displacement\"\nthreads = 2"),
     "numerics.threads", "unknown key"),
    (BASE + "\n[record.region]\nx2 = [0.0, 0.5]\n", "record.region.x2", "accepted: x1, x3"),
    (BASE + "\n[units]\nlength = \"m\"\ntime = \"s\"\nstress = \"Pa\"\nmass = \"kg\"\n", "units.mass",
     "unknown key"),
    # wrong types
    (edit("n1 = 16", "n1 = 16.0"), "grid.n1", "must be an integer, got 16.0"),
    (edit("mu = 1.0", "mu = \"1.0\""), "material.mu", "must be a number, got '1.0'"),
    (edit("t_end = 0.05", "t_end = \"0.05\""), "t_end", "must be a number"),
    (edit("beta = 0.5", "beta = true"), "beta", "must be a number, got True"),
    (edit("tau_c = 1.0", "tau_c = \"big\""), "law.tau_c", "must be a number or an (n1, n3) array"),
    (edit("tau_c = 1.0", "tau_c = [[1.0, 2.0], [3.0]]"), "law.tau_c", "array of numbers"),
    (edit("tau_c = 1.0", "tau_c = 1.0\ninitial_crack = [" + ", ".join([ROW16] * 16) + "]"),
     "law.initial_crack", "array of booleans"),
    (edit("tau0_2 = 1.2", "tau0_2 = 1.2\nconstant_K = 1"), "loading.constant_K", "must be a boolean"),
    (edit("every = 2", "every = 2.5"), "record.every", "must be an integer"),
    (edit("fields = [\"delta_2\"]", "fields = [2]"), "record.fields", "must be a list of strings"),
    (BASE + "\n[record.stations]\na = [0.1, 0.2, 0.3]\n", "record.stations.a", "must be [x1, x3]"),
    (BASE + "\n[record.stations]\na = \"here\"\n", "record.stations.a", "list of numbers"),
    (BASE + "\n[units]\nlength = 1\ntime = \"s\"\nstress = \"Pa\"\n", "units.length", "must be a string"),
    (edit("name = \"v\"", "name = 3"), "name", "must be a string"),
    (edit("[grid]", "grid = 3\n[gridx]"), "gridx", "unknown key"),
    # out of range, with the accepted range in the message
    (edit("nu = 0.25", "nu = 0.6"), "material.nu", "must be in (-1, 0.5)"),
    (edit("L1 = 1.0", "L1 = -1.0"), "grid.L1", "must be > 0"),
    (edit("n1 = 16", "n1 = 17"), "grid.n1", "even fast FFT size"),
    (edit("delta_c = 0.01", "delta_c = 0.0"), "law.delta_c", "must be > 0"),
    (edit("beta = 0.5", "beta = 0.9"), "beta", "must be in (0, "),
    (edit("tau0_2 = 1.2", "tau0_2 = 1.2\nconstant_K = true\nl0 = -0.5"), "loading.l0", "must be > 0"),
    (edit("tau0_2 = 1.2", "tau0_2 = 1.2\ntime = \"jump\""), "loading.time", "must be one of"),
    (edit("every = 2", "every = 0"), "record.every", "integer >= 1"),
    (edit("fields = [\"delta_2\"]", "fields = [\"opening\"]"), "record.fields", "accepted: delta_1"),
    (edit("every = 2", "every = 2\ntimes = [0.0]"), "record.times", "either record.every or record.times"),
    (BASE + "\n[record.region]\nx1 = [0.7, 0.3]\n", "record.region.x1", "lo <= hi"),
    (edit("formulation = \"displacement\"", "formulation = \"displacement\"\nengine = \"magic\""),
     "numerics.engine", "must be one of ['auto', 'direct'"),
    (edit("formulation = \"displacement\"", "formulation = \"displacement\"\nfft_threads = 0"),
     "numerics.fft_threads", "integer >= 1"),
    (edit("formulation = \"displacement\"", "formulation = \"implicit\""), "numerics.formulation",
     "must be one of"),
    (BASE + "\n[units]\nlength = \"m\"\n", "units.time", "is required"),
    (edit("tau_c = 1.0", "tau_c = [" + ", ".join([ROW16] * 8) + "]"), "law.tau_c",
     "field shape must be (n1, n3) = (16, 16)"),
    (edit("[law]\nkind = \"linear_cohesive\"", "[law]\nkind = \"glue\""), "law.kind", "must be one of"),
    (edit("delta_c = 0.01", ""), "law.delta_c", "is required"),
]


@pytest.mark.parametrize("text, field, message", BAD, ids=[f"{i}-{b[1]}" for i, b in enumerate(BAD)])
def test_bad_toml_names_the_field(text, field, message):
    with pytest.raises(InputError) as err:
        scene_from_toml(text)
    assert err.value.field == field, str(err.value)
    assert str(err.value).startswith(field + ": ")
    assert message in str(err.value), str(err.value)


def test_bad_dataset_names_the_field():
    sc = scenes.asperity_row(n1=64, n3=32, t_end=0.5)
    ds = scene_to_dataset(sc)
    cases = [
        (ds.assign_attrs({"grid.spacing": 2}), "grid.spacing"),
        (ds.assign_attrs({"grid.n1": 64.0}), "grid.n1"),
        (ds.assign_attrs({"material.nu": "0.25"}), "material.nu"),
        (ds.assign(law_colour=ds["law_tau_c"]), "law.colour"),
        (ds.assign(law_tau_c=ds["law_tau_c"].isel(x1=slice(0, 32))), "law.tau_c"),
        (ds.assign(law_bonded=ds["law_tau_c"]), "law.bonded"),
        (ds.assign_attrs({"law.tau_c": 1.0}), "law.tau_c"),
        (ds.assign_attrs({"units.colour": "red"}), "units.colour"),
    ]
    for bad, field in cases:
        with pytest.raises(InputError) as err:
            scene_from_dataset(bad)
        assert err.value.field == field, str(err.value)


def test_python_constructors_close_the_same_gaps():
    with pytest.raises(InputError, match="loading.l0: must be > 0"):
        Loading(tau0_2=1.0, constant_K=True, l0=-1.0)
    with pytest.raises(InputError, match="loading.constant_K"):
        Loading(tau0_2=1.0, constant_K="yes")
    with pytest.raises(InputError, match="numerics.engine"):
        Numerics(engine="magic")
    with pytest.raises(InputError, match="numerics.fft_threads"):
        Numerics(fft_threads=1.5)
    with pytest.raises(InputError, match="numerics.engine_threads: must be None"):
        Numerics(engine_threads=0)
    with pytest.raises(InputError, match="record.stations.a"):
        Record(stations={"a": 0.5})
    with pytest.raises(InputError, match="record.region.x1"):
        Record(region={"x1": (0.5,)})
    with pytest.raises(InputError, match="units"):
        SCENES["traction-free"]().replace(units={"length": "m"})
    with pytest.raises(InputError, match="law.bonded: must be a boolean mask"):
        SCENES["traction-free"]().replace(law=TractionFree(bonded=np.zeros((16, 16))))


def test_cli_rejects_a_bad_type_before_any_work(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(edit("L1 = 1.0", "L1 = \"one\""))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "x.zarr")])
    assert res.exit_code != 0
    assert "grid.L1: must be a number, got 'one'" in res.output
    assert not (tmp_path / "x.zarr").exists()


def test_cli_runs_a_written_scene(tmp_path):
    sc = scenes.asperity_row(n1=32, n3=16, t_end=0.05, cohesive_zone=0.2)
    path = tmp_path / "scene.toml"
    path.write_text(sc.to_toml())
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "a.zarr")])
    assert res.exit_code == 0, res.output
    assert scenes_equal(scene_of(xr.open_zarr(tmp_path / "a.zarr", consolidated=False)), sc)


def test_docs_scenes_examples_run(tmp_path, monkeypatch):
    """The python blocks of docs/reference/scenes.md run, in order, in one namespace."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "reference" / "scenes.md").read_text()
    code = [body for tag, body in re.findall(r"^```([\w-]*)[ \t]*\n(.*?)^```[ \t]*$", text, re.S | re.M)
            if tag == "python" and "=" in body and "(*," not in body]
    assert len(code) >= 2
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__docs__"}
    for body in code:
        exec(compile(body, "docs/reference/scenes.md", "exec"), namespace)


def test_engine_threads_reach_the_engine_and_round_trip():
    """numerics.engine_threads sets the history engine's threads apart from the FFTs'
    (None: as fft_threads), survives the TOML round trip, and does not change the result."""
    import cracklab
    from cracklab.model.scene_io import scene_from_toml, scene_to_toml
    from cracklab.solver.interfaces import for_scene as interface_for_scene

    base = SCENES["traction-free"]()
    sc = base.replace(numerics=Numerics(engine="exponential", fft_threads=1, engine_threads=2))
    assert sc.numerics.history_threads == 2 and base.numerics.history_threads == base.numerics.fft_threads
    back = scene_from_toml(scene_to_toml(sc))
    assert back.numerics.engine_threads == 2 and back.numerics.fft_threads == 1
    assert scene_from_toml(scene_to_toml(base)).numerics.engine_threads is None
    resp = interface_for_scene(sc)
    assert {ch.engine.threads for ch in resp.channels.values()} == {2} and resp.fft.workers == 1
    short = dict(t_end=5 * sc.dt)
    a = cracklab.simulate(sc.replace(**short))
    b = cracklab.simulate(base.replace(numerics=Numerics(engine="exponential"), **short))
    assert np.array_equal(a["delta_2"].values, b["delta_2"].values)


def test_the_default_record_is_the_slip_of_the_active_components(tmp_path):
    """Without ``fields`` a scene records the slip of every component it activates:
    the opening in mode I (as before), both slips in 3D shear, where ``delta_2`` is not
    computed (an error when asked for explicitly); a TOML without [record] runs too."""
    import cracklab
    from cracklab import Record
    from cracklab.errors import InputError

    shear = cracklab.scenes.tpv3(dx=1000.0, t_end=0.05)
    assert shear.replace(record=Record()).record.fields == ("delta_1", "delta_3")
    assert shear.replace(record=Record(every=2)).record.every == 2
    assert cracklab.scenes.lamb(n=32, t_end=0.1).replace(record=Record()).record.fields == ("delta_2",)
    with pytest.raises(InputError, match="record.fields: 'delta_2' is not computed"):
        shear.replace(record=Record(fields=("delta_2",)))
    path = tmp_path / "shear.toml"
    path.write_text(_without_section(shear.to_toml(), "record"))
    loaded = cracklab.Scene.from_toml(path)
    assert loaded.record.fields == ("delta_1", "delta_3")
    ds = cracklab.simulate(loaded)
    assert "delta_1" in ds and "delta_3" in ds and "delta_2" not in ds


def _without_section(toml, name):
    """``toml`` without its table [name] and its sub-tables [name.*]."""
    out, skip = [], False
    for line in toml.splitlines():
        if line.startswith("["):
            head = line.strip("[] ")
            skip = head == name or head.startswith(name + ".")
        if not skip:
            out.append(line)
    return "\n".join(out) + "\n"
