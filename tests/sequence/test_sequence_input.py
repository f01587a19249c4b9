"""Bad input of a sequence scene (issue 35): each a clear InputError naming the field,
raised when the Scene is built, before any work; a step that cannot meet its tolerance
stops with the time, the place and the values."""
import dataclasses

import numpy as np
import pytest

from spring_slider import scene as spring_slider


def base(**seq):
    from cracklab import Grid, Loading, Material, RateState, Scene, Sequence

    g = Grid(n1=32, n3=1, L1=32e3, L3=1.0)
    creep = np.zeros(g.shape, bool)
    creep[20:] = True
    law = RateState(a=0.01, b=0.015, L=0.008, V0=1e-6, f0=0.6, sigma_n=50e6, V_ini=1e-9)
    kw = {"plate_rate_3": 1e-9, "creep": creep, **seq}
    return Scene(material=Material(mu=32e9, cs=3464.0, nu=0.25), grid=g, law=law, loading=Loading(tau0_3=31e6),
                 t_end=3e9, sequence=Sequence(**kw))


def test_a_sane_scene_builds_and_round_trips_through_toml():
    from cracklab import Scene
    from cracklab.model.scene_io import scenes_equal

    s = base()
    assert scenes_equal(Scene.from_toml(s.to_toml()), s)
    assert scenes_equal(Scene.from_dataset(s.to_dataset()), s)
    # a scene without a sequence writes no [sequence] table (its TOML and digest as before)
    plain = s.replace(sequence=None, t_end=1.0)
    assert "[sequence]" not in plain.to_toml() and "[sequence]" in s.to_toml()


@pytest.mark.parametrize("change, field, words", [
    ({"plate_rate_3": 0.0}, "sequence.plate_rate_1", "plate rate must be > 0"),
    ({"plate_rate_3": -1e-9}, "sequence.plate_rate_3", ">= 0"),
    ({"dt_min": 10.0, "dt_max": 1.0}, "sequence.dt_min", "<= sequence.dt_max"),
    ({"dt_first": 100.0, "dt_max": 10.0}, "sequence.dt_first", "[dt_min, dt_max]"),
    ({"tolerance": 2.0}, "sequence.tolerance", "(0, 1)"),
    ({"response": "elastic"}, "sequence.response", "quasi_dynamic, dynamic"),
    ({"pair": "euler"}, "sequence.pair", "dormand_prince"),
    ({"station_every": 0}, "sequence.station_every", ">= 1"),
])
def test_bad_sequence_values_name_the_field(change, field, words):
    from cracklab import InputError

    with pytest.raises(InputError) as err:
        base(**change)
    assert err.value.field == field and words in str(err.value)


def test_a_creeping_region_over_the_whole_plane_is_refused():
    from cracklab import InputError

    with pytest.raises(InputError) as err:
        base(creep=np.ones((32, 1), bool))
    assert err.value.field == "sequence.creep" and "whole plane" in str(err.value)


def test_a_law_that_cannot_heal_is_refused():
    from cracklab import InputError, SlipWeakening

    s = base()
    with pytest.raises(InputError) as err:
        s.replace(law=SlipWeakening(mu_s=0.7, mu_d=0.6, D_c=0.1, sigma_n=50e6))
    assert err.value.field == "law.kind" and "cannot heal" in str(err.value)


def test_fixed_step_recording_is_refused():
    from cracklab import InputError, Record

    with pytest.raises(InputError) as err:
        base().replace(record=Record(fields=("delta_3",), every=10))
    assert err.value.field == "record.every"


def test_a_step_that_cannot_meet_its_tolerance_stops_with_time_place_and_values():
    from cracklab import SimulationError, Sequence, simulate

    s = spring_slider(1e9)
    rigid = dataclasses.replace(s.sequence, tolerance=1e-12, dt_min=1e6, dt_max=1e7, dt_first=1e6)
    assert isinstance(rigid, Sequence)
    with pytest.raises(SimulationError) as err:
        simulate(s.replace(sequence=rigid))
    text = str(err.value)
    for words in ("cannot meet its tolerance", "dt_min = 1e+06", "t = ", "node (", "x1 = ", "->"):
        assert words in text, text


def test_the_law_protocol_solves_and_evolves():
    """slide_rates solves T - eta V = sigma f(V, psi); the ageing law's state rate is b / theta
    d theta / dt with d theta / dt = 1 - V theta / L; the slip law's vanishes at steady state,
    psi_ss = a ln[(2 V0 / V) sinh(f_ss / a)]."""
    from cracklab import RateState
    from cracklab.laws.rate_state import friction_coefficient

    law = RateState(a=0.01, b=0.015, L=0.008, V0=1e-6, f0=0.6, sigma_n=50e6, V_ini=1e-9)
    T = np.array([30e6, 31e6, 35e6, 0.0])
    psi = np.array([0.7, 0.68, 0.6, 0.7])
    V, lnV, dpsi = law.slide_rates(T, psi, 50e6, 5e6)
    np.testing.assert_allclose(T - 5e6 * V, 50e6 * friction_coefficient(V, psi, 0.01, 1e-6), rtol=1e-9, atol=1e-3)
    assert V[-1] == 0.0
    theta = 0.008 / 1e-6 * np.exp((psi - 0.6) / 0.015)
    np.testing.assert_allclose(dpsi, 0.015 / theta * (1 - V * theta / 0.008), rtol=1e-12)
    slip = dataclasses.replace(law, evolution="slip")
    Vs = np.array([1e-9, 1e-3, 1.0])
    fss = 0.6 - 0.005 * np.log(Vs / 1e-6)
    pss = 0.01 * np.log(2e-6 / Vs * np.sinh(fss / 0.01))
    np.testing.assert_allclose(friction_coefficient(Vs, pss, 0.01, 1e-6), fss, rtol=1e-12)
    V, _, dpsi = slip.slide_rates(5e6 * Vs + 50e6 * fss, pss, 50e6, 5e6)     # sliding at Vs in steady state
    np.testing.assert_allclose(V, Vs, rtol=1e-9)
    # zero, but for the Newton solve's last 1e-10 of V: below 1e-9 of the rate scale V / L
    assert np.all(np.abs(dpsi) < 1e-9 * Vs / 0.008), dpsi


def test_cracklab_run_of_a_sequence_scene_reports_its_steps_and_events(tmp_path):
    import xarray as xr

    from cli_process import cli

    path = tmp_path / "slider.toml"
    spring_slider(4e8).to_toml(path)
    res = cli("run", path, "-o", tmp_path / "slider.zarr", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert "accepted steps of" in res.stdout + res.stderr and "1 events" in res.stdout + res.stderr
    ds = xr.open_zarr(tmp_path / "slider.zarr")
    assert ds.sizes["event"] == 1 and ds.attrs["accepted_steps"] > 100


def test_a_sequence_reports_its_wall_time_in_events_and_between_them():
    """The recorder adds each accepted step's wall time to the phase it was taken in: both
    phases counted, their sum within the run's own wall time (which adds the set-up and
    the end: a large part of so short a run)."""
    import time

    from cracklab.output.sequence import run_sequence

    scene = spring_slider(4e8)
    t0 = time.perf_counter()
    ds = run_sequence(scene)
    wall = time.perf_counter() - t0
    fast, slow = ds.attrs["wall_time_in_events"], ds.attrs["wall_time_between_events"]
    assert ds.sizes["event"] == 1 and fast > 0 and slow > 0
    assert 0.2 * wall < fast + slow <= wall, (fast, slow, wall)
