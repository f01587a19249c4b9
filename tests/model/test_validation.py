"""Bad input ends with one clear error naming the field (issue: bad input)."""
import numpy as np
import pytest

from cracklab import Grid, InputError, Loading, Material, Record, Scene, TractionFree
from cracklab import LinearCohesive, scenes
from cracklab.model.scene_io import scene_from_data, scene_to_data


def small_scene(**changes):
    grid = Grid(n1=16, n3=16, L1=1.0, L3=1.0)
    base = dict(material=Material(mu=1, cs=1, nu=0.25), grid=grid, law=TractionFree(),
                loading=Loading(tau0_2=1.0), t_end=0.1)
    base.update(changes)
    return Scene(**base)


def test_valid_scene_roundtrip_through_data():
    scene = scenes.elliptical_crack(n=32, a=0.2, b=0.1, t_end=0.1)
    data, arrays = scene_to_data(scene)
    again = scene_from_data(data, arrays)
    assert again.grid == scene.grid and again.material == scene.material
    assert np.array_equal(again.law.bonded, scene.law.bonded)
    assert np.array_equal(again.loading.tau0_2, scene.loading.tau0_2)


@pytest.mark.parametrize("mutate, field", [
    (lambda d: d.update(colour="red"), "colour"),
    (lambda d: d["grid"].update(spacing=2), "grid.spacing"),
    (lambda d: d["law"].update(tau_c=1), "law.tau_c"),
    (lambda d: d["grid"].update(n1=-16), "grid.n1"),
    (lambda d: d["grid"].update(L3=-1.0), "grid.L3"),
    (lambda d: d["grid"].update(n1=17), "grid.n1"),
    (lambda d: d.update(t_end=-1.0), "t_end"),
    (lambda d: d.update(beta=0.9), "beta"),
    (lambda d: d["law"].update(kind="glue"), "law.kind"),
    (lambda d: d["record"].update(fields=["opening"]), "record.fields"),
])
def test_bad_scene_data(mutate, field):
    data, arrays = scene_to_data(small_scene())
    mutate(data)
    with pytest.raises(InputError) as err:
        scene_from_data(data, arrays)
    assert str(err.value).startswith(field + ":")


def test_wrong_field_shape_is_named():
    with pytest.raises(InputError, match=r"loading.tau0_2: field shape must be \(n1, n3\) = \(16, 16\)"):
        small_scene(loading=Loading(tau0_2=np.ones((8, 8))))
    with pytest.raises(InputError, match="law.tau_c: field shape"):
        small_scene(law=LinearCohesive(tau_c=np.ones((4, 4)), delta_c=1.0))


def test_negative_law_parameter_is_named():
    with pytest.raises(InputError, match="law.tau_c: must be > 0, got -1"):
        LinearCohesive(tau_c=-1, delta_c=1.0)


def test_unstable_beta_names_range():
    with pytest.raises(InputError) as err:
        small_scene(beta=0.8)
    assert str(err.value).startswith("beta: must be in (0, 0.5")


def test_load_on_component_law_cannot_carry():
    with pytest.raises(InputError, match="loading.tau0_1"):
        small_scene(law=LinearCohesive(tau_c=1.0, delta_c=1.0), loading=Loading(tau0_1=1.0, tau0_2=1.0))


def test_record_outside_grid():
    with pytest.raises(InputError, match="record.stations.far"):
        small_scene(record=Record(stations={"far": (2.0, 0.5)}))


def test_constant_K_needs_a_length():
    with pytest.raises(InputError, match="loading.l0"):
        small_scene(law=LinearCohesive(tau_c=1.0, delta_c=1.0), loading=Loading(tau0_2=1.0, constant_K=True))


# ---------------------------------------------------------------------------- never a crash
# The crash classes a fuzzer found (each was a traceback with exit status 1), now each one
# InputError naming the field and the accepted range; tests/model/test_fuzz_scene.py keeps the
# fuzzer in CI.
def _toml_with(section, key, value, scene=None):
    import tomllib

    import tomli_w

    data = tomllib.loads((scene or scenes.elliptical_crack(n=16, a=0.25, b=0.2, t_end=0.1)).to_toml())
    (data if section is None else data[section])[key] = value
    return tomli_w.dumps(data)


def _one_error(text):
    from cracklab.model.scene_io import scene_from_toml

    with pytest.raises(InputError) as err:
        scene_from_toml(text)
    e = err.value
    assert e.__cause__ is None and (e.__context__ is None or e.__suppress_context__)
    return e


@pytest.mark.parametrize("section, key", [("material", "cs"), ("material", "mu"), ("grid", "L1"),
                                          ("grid", "L3"), (None, "t_end"), (None, "beta"),
                                          ("numerics", "window"), ("numerics", "rupture_threshold"),
                                          ("loading", "l0"), ("loading", "ramp_time")])
@pytest.mark.parametrize("value", [1.7e308, 1e300, 1e-300, 5e-324, 1e101, 9e-101])
def test_huge_and_tiny_scales_name_the_accepted_range(section, key, value):
    text = _toml_with(section, key, value)
    if key == "l0":
        text = text.replace("constant_K = false", "constant_K = true")
    e = _one_error(text)
    field = key if section is None else f"{section}.{key}"
    assert e.field == field, str(e)
    assert "in [1e-100, 1e100]" in str(e) and f"got {value!r}" in str(e), str(e)


def test_overflow_in_material_is_an_input_error():
    """material.cs = 1.7e308 overflowed in cs**2 (OverflowError in material.py)."""
    for kw in (dict(mu=1.0, cs=1.7e308), dict(mu=1.7e308, cs=1.0), dict(mu=1.0, cs=5e-324),
               dict(mu=10**400, cs=1.0), dict(mu=1.0, cs=2**1100), dict(mu=1.0, cs=-1e-300)):
        with pytest.raises(InputError) as err:
            Material(nu=0.25, **kw)
        assert err.value.field in ("material.mu", "material.cs"), str(err.value)
        assert "must be" in str(err.value) and "got" in str(err.value)
    # the ends of the range: density, wave speeds and damping are finite normal floats
    for mu in (1e-100, 1e100):
        for cs in (1e-100, 1e100):
            for nu in (-0.9999999999999999, 0.0, 0.49999999999999994):
                m = Material(mu=mu, cs=cs, nu=nu)
                for x in (m.rho, m.cd, m.cR, m.eta(1), m.eta(2)):
                    assert np.isfinite(x) and x >= np.finfo(float).tiny, (mu, cs, nu, x)


def test_grid_lengths_that_divided_by_zero_are_input_errors():
    """grid.L1 = 1e300 or 5e-324 ended in ZeroDivisionError (stability.py, numpy's fftfreq),
    L1 = 1e-300 in "beta: must be in (0, 0.0000]"."""
    for L in (1e300, 5e-324, 1e-300, 1.7e308):
        for name, kw in (("grid.L1", dict(L1=L, L3=1.0)), ("grid.L3", dict(L1=1.0, L3=L))):
            with pytest.raises(InputError, match=rf"^{name}: must be in \[1e-100, 1e100\]"):
                Grid(n1=16, n3=16, **kw)
        e = _one_error(_toml_with("grid", "L1", L))
        assert e.field == "grid.L1" and "0.0000]" not in str(e)
    # the ends of the range: every derived length and wave number is a finite normal float
    for L in (1e-100, 1e100):
        for n1, n3 in ((65536, 1), (2, 2), (1024, 1024)):
            g = Grid(n1=n1, n3=n3, L1=L, L3=L)
            q = g.q_max()
            assert np.isfinite(q) and q > 0 and g.dx_min >= np.finfo(float).tiny
    for L in (1e-98, 1e98):      # scaled together, the scene is the same problem
        sc = small_scene(grid=Grid(n1=16, n3=16, L1=L, L3=L), t_end=0.1 * L,
                         material=Material(mu=1, cs=1.0, nu=0.25))
        assert sc.nsteps == small_scene().nsteps


def test_a_time_step_of_zero_is_an_input_error():
    """beta = 5e-324 gave dt = 0 and a ZeroDivisionError in Scene."""
    with pytest.raises(InputError, match=r"^beta: must be in \[1e-100, 1e100\], got 5e-324"):
        small_scene(beta=5e-324)
    # scales each in range but far apart: too many steps, or none at all
    with pytest.raises(InputError, match=r"^t_end: must be at most 1e\+08 time steps .*\(inf steps\)"):
        small_scene(t_end=1e100, beta=1e-100, grid=Grid(n1=16, n3=16, L1=1e-100, L3=1e-100),
                    material=Material(mu=1, cs=1e100, nu=0.25))
    with pytest.raises(InputError, match=r"^t_end: must hold at least one time step, t_end >= dt = "):
        small_scene(t_end=1e-100, material=Material(mu=1, cs=1e-100, nu=0.25))


def test_record_times_beyond_t_end_are_named_with_the_right_t_end():
    """t_end = 0.5 with a tiny cs was reported as "record.times: must lie in [0, t_end = 0]"
    (the run had no step at all); now t_end itself is refused, and a time after t_end
    is reported with t_end to 6 digits."""
    crack = scenes.elliptical_crack(n=16, a=0.25, b=0.2, t_end=0.5)
    e = _one_error(_toml_with("material", "cs", 1e-30, crack).replace(
        "[record]", "[record]\ntimes = [0.1]"))
    assert e.field == "t_end" and "at least one time step" in str(e)
    with pytest.raises(InputError) as err:
        crack.replace(record=Record(times=(0.7,)))
    assert str(err.value).startswith("record.times: must lie in [0, t_end = 0.5") and "got 0.7" in str(err.value)
    tiny = small_scene(grid=Grid(n1=16, n3=16, L1=1e-6, L3=1e-6), t_end=1.23456789e-7)
    with pytest.raises(InputError, match=r"t_end = 1\.25e-07\] .* got 1\.3e-07"):
        tiny.replace(record=Record(times=(1.3e-7,)))


def test_a_binary_file_is_one_input_error(tmp_path):
    """A binary file given as a scene or a study ended in UnicodeDecodeError."""
    from click.testing import CliRunner

    from cracklab import ensemble
    from cracklab.cli import main

    png = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00\x00\x10"
    for name in ("scene.toml", "study.toml"):
        path = tmp_path / name
        path.write_bytes(png)
    e = _one_error(png)
    assert e.field == "toml" and "not UTF-8 text (byte 0x89 at offset 0)" in str(e)
    store = tmp_path / "out.zarr"
    for args in (["run", str(tmp_path / "scene.toml"), "-o", str(store)],
                 ["sweep", str(tmp_path / "study.toml"), "-o", str(store), "--scheduler", "synchronous"]):
        res = CliRunner().invoke(main, args)
        assert res.exit_code == 1 and isinstance(res.exception, SystemExit), res.output
        lines = res.output.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"Error: {args[1]}: not valid TOML: not UTF-8 text")
        assert not store.exists()
    with pytest.raises(InputError, match="not UTF-8"):
        ensemble.load_study(tmp_path / "study.toml")
    # a directory named like a scene file, and a scene file of a study that is binary
    (tmp_path / "dir.toml").mkdir()
    res = CliRunner().invoke(main, ["run", str(tmp_path / "dir.toml"), "-o", str(store)])
    assert res.exit_code == 1 and "cannot be read" in res.output and not store.exists()
    (tmp_path / "s2.toml").write_text('[study]\nscene = "scene.toml"\n')
    with pytest.raises(InputError, match="^study.scene: not valid TOML: not UTF-8"):
        ensemble.load_study(tmp_path / "s2.toml")


@pytest.mark.parametrize("depth", [33, 200, 1000, 5000])
def test_deeply_nested_arrays_are_one_input_error(tmp_path, depth):
    """5000-deep nested arrays ended in RecursionError (in the TOML parser)."""
    from click.testing import CliRunner

    from cracklab import ensemble
    from cracklab.cli import main

    text = _toml_with(None, "t_end", 0.1).replace("t_end = 0.1", "t_end = " + "[" * depth + "0.1" + "]" * depth)
    e = _one_error(text)
    assert e.field in ("t_end", "toml"), str(e)
    assert "nest" in str(e) and "32 levels" in str(e)
    if depth <= 200:        # the parser reads it: the field is named
        assert e.field == "t_end"
    path = tmp_path / "deep.toml"
    path.write_text(text)
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "o.zarr")])
    assert res.exit_code == 1 and len(res.output.strip().splitlines()) == 1 and "nest" in res.output
    assert not (tmp_path / "o.zarr").exists()
    study = tmp_path / "study.toml"
    study.write_text('[study]\nbuilder = "lamb"\n[sweep]\nn = ' + "[" * depth + "16" + "]" * depth + "\n")
    with pytest.raises(InputError, match="nest"):
        ensemble.load_study(study)
    # from Python too (plain data)
    from cracklab.model.scene_io import scene_from_data, scene_to_data

    data, arrays = scene_to_data(small_scene())
    v = 0.1
    for _ in range(depth):
        v = [v]
    data["t_end"] = v
    with pytest.raises(InputError, match="^t_end: must not nest arrays or tables deeper than 32 levels"):
        scene_from_data(data, arrays)
    # and the Python constructors (a message showing the value recursed through it)
    loop = []
    loop.append(loop)
    for value in (v, loop):
        for field, make in (("law.tau_c", lambda x: LinearCohesive(tau_c=x, delta_c=1.0)),
                            ("loading.tau0_2", lambda x: Loading(tau0_2=x)),
                            ("record.stations.a", lambda x: Record(stations={"a": x})),
                            ("material.nu", lambda x: Material(mu=1.0, cs=1.0, nu=x)),
                            ("units.length", lambda x: small_scene(units={"length": x, "time": "1", "stress": "1"}))):
            with pytest.raises(InputError) as err:
                make(value)
            assert str(err.value) == f"{field}: must not nest arrays or tables deeper than 32 levels"


def test_a_huge_window_is_refused_before_the_store_and_a_long_one_runs(tmp_path):
    """numerics.window = 1e300 passed validation and crashed the run (a history buffer of
    1e300 steps) after the store was created."""
    import dataclasses

    import xarray as xr
    from click.testing import CliRunner

    import cracklab
    from cracklab.cli import main

    crack = scenes.elliptical_crack(n=16, a=0.25, b=0.2, t_end=0.3)
    path = tmp_path / "w.toml"
    path.write_text(_toml_with("numerics", "window", 1e300, crack).replace('engine = "auto"', 'engine = "direct"'))
    store = tmp_path / "w.zarr"
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(store)])
    assert res.exit_code == 1, res.output
    assert res.output.strip() == "Error: numerics.window: must be in [1e-100, 1e100], got 1e+300"
    assert not store.exists()
    # a window longer than the run truncates nothing: the same numbers as the full history
    direct = crack.replace(numerics=dataclasses.replace(crack.numerics, engine="direct"))
    full = cracklab.simulate(direct)
    for window in (1e100, 1e12):
        w = cracklab.simulate(direct.replace(numerics=dataclasses.replace(direct.numerics, window=window)))
        assert np.array_equal(w.delta_2.values, full.delta_2.values)
    path.write_text(direct.replace(numerics=dataclasses.replace(direct.numerics, window=1e100)).to_toml())
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(store)])
    assert res.exit_code == 0, res.output
    assert np.array_equal(xr.open_zarr(store, consolidated=False).delta_2.values, full.delta_2.values)


def test_a_huge_odd_grid_size_is_refused_at_once():
    """grid.n1 = 2^63 - 1 (found by the fuzzer) searched for the next fast FFT size
    near 2^63, which does not end in any reasonable time."""
    import time

    t0 = time.perf_counter()
    for n in (2**63 - 1, 2**62 + 2, 10**18 + 1, 65537, 65538):
        for name, kw in (("grid.n1", dict(n1=n, n3=16)), ("grid.n3", dict(n1=16, n3=n))):
            with pytest.raises(InputError, match=rf"^{name}: must be an even fast FFT size .*, got {n}; at most 65536"):
                Grid(L1=1.0, L3=1.0, **kw)
        e = _one_error(_toml_with("grid", "n1", n))
        assert e.field == "grid.n1"
    assert time.perf_counter() - t0 < 5
    with pytest.raises(InputError, match=r"got 65534; nearest larger is 65536"):
        Grid(n1=65534, n3=1, L1=1.0, L3=1.0)


def test_a_damaged_scene_attr_of_a_store_is_one_input_error(tmp_path):
    """`cracklab run STORE` of a run store whose scene attr is not JSON (or nested too
    deeply for the JSON decoder) gives one error line, not a JSONDecodeError."""
    import zarr
    from click.testing import CliRunner

    import cracklab
    from cracklab.cli import main

    store = tmp_path / "run.zarr"
    cracklab.simulate(small_scene(t_end=0.02), store=str(store))
    for bad in ("{not json", "[" * 100000 + "]" * 100000, "[1, 2]"):
        zarr.open_group(str(store), mode="a").attrs["scene"] = bad
        res = CliRunner().invoke(main, ["run", str(store), "-o", str(tmp_path / "again.zarr")])
        assert res.exit_code == 1 and isinstance(res.exception, SystemExit), res.output
        lines = res.output.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("Error: scene: must be the scene as"), res.output
        assert not (tmp_path / "again.zarr").exists()
