"""The forced nucleation of SCEC TPV101-104 as a loading option (cracklab/model/loading.py):
dtau_c F(r) G(t) added to the shear load, through TOML and Dataset attrs, in step (v)."""
import math

import numpy as np
import pytest

import cracklab
from cracklab import Grid, InputError, Loading, Material, Record, Scene
from cracklab.laws import ConstantFriction
from cracklab.model.scene_io import scene_to_data, scenes_equal

NUC = dict(nucleation_dtau_1=25e6, nucleation_radius=3000.0, nucleation_time=1.0, nucleation_x1=5000.0,
           nucleation_x3=4000.0)


def F(r, R):
    return math.exp(r * r / (r * r - R * R)) if r < R else 0.0


def G(t, T):
    if t <= 0:
        return 0.0
    return math.exp((t - T) ** 2 / (t * (t - 2 * T))) if t < T else 1.0


def test_G_is_the_tpv_time_function():
    load = Loading(tau0_1=75e6, **NUC)
    for t in (-1.0, 0.0, 1e-3, 0.1, 0.5, 0.9, 0.999, 1.0, 2.0):
        assert load.nucleation_factor(t) == pytest.approx(G(t, 1.0), rel=1e-15, abs=0), t
    assert load.nucleation_factor(0.5) == math.exp(-1.0 / 3.0) and load.nucleation_factor(1e-6) == 0.0
    assert abs(load.nucleation_factor(1 - 1e-6) - 1) < 1e-11      # continuous at T


def test_F_is_the_tpv_patch_on_the_grid_nodes():
    grid = Grid(n1=100, n3=80, L1=10000.0, L3=8000.0)
    P = Loading(tau0_1=75e6, **NUC).nucleation_field(grid)
    assert set(P) == {1}
    x1, x3 = np.meshgrid(grid.x1, grid.x3, indexing="ij")
    r = np.hypot(x1 - 5000.0, x3 - 4000.0)
    want = 25e6 * np.vectorize(F)(r, 3000.0)
    np.testing.assert_allclose(P[1], want, rtol=1e-11, atol=0)    # F is ill-conditioned near r = R
    assert P[1][50, 40] == 25e6 and P[1].max() == 25e6 and np.all(P[1][r >= 3000.0] == 0)


def test_the_perturbation_is_added_in_step_v_and_in_at():
    """A plane that cannot slide (mu_f sigma_n far above the load): tau_1 = tau0 + dtau F(r) G(t)
    at every node and step, exactly (tau = tau* with v = 0); tau_3 the same with dtau_3."""
    grid = Grid(n1=16, n3=16, L1=16000.0, L3=16000.0)
    load = Loading(tau0_1=75e6, **{**NUC, "nucleation_dtau_3": -5e6, "nucleation_x1": 8000.0,
                                   "nucleation_x3": 8000.0})
    mat = Material(mu=3.2e10, cs=3464.0, nu=0.25)
    sc = Scene(material=mat, grid=grid, law=ConstantFriction(mu_f=10.0, sigma_n=120e6), loading=load, t_end=1.5,
               beta=0.5, record=Record(fields=("tau_1", "tau_3", "v_1"), every=1),
               units={"length": "m", "time": "s", "stress": "Pa"})
    assert sc.components == (1, 3)
    ds = cracklab.simulate(sc)
    x1, x3 = np.meshgrid(grid.x1, grid.x3, indexing="ij")
    f = np.vectorize(F)(np.hypot(x1 - 8000.0, x3 - 8000.0), 3000.0)
    Gt = np.array([G(t, 1.0) for t in ds.t.values])[:, None, None]
    assert np.all(ds.v_1.values == 0.0) and 0 < Gt[3, 0, 0] < 1 and Gt[-1, 0, 0] == 1
    np.testing.assert_allclose(ds.tau_1.values, 75e6 + 25e6 * f * Gt, rtol=1e-15, atol=1e-4)
    np.testing.assert_allclose(ds.tau_3.values, -5e6 * f * Gt, rtol=1e-11, atol=1e-9)
    at = load.at(0.5, (1, 3), grid=grid)
    np.testing.assert_allclose(at[1], 75e6 + 25e6 * f * G(0.5, 1.0), rtol=1e-15, atol=1e-4)
    assert load.at(0.0, (1,), grid=grid) == {1: 75e6}          # G(0) = 0: the plain load


def test_it_round_trips_through_toml_and_dataset_attrs_and_is_absent_otherwise():
    grid = Grid(n1=16, n3=16, L1=16000.0, L3=16000.0)
    base = Scene(material=Material(mu=3.2e10, cs=3464.0, nu=0.25), grid=grid,
                 law=ConstantFriction(mu_f=10.0, sigma_n=120e6), loading=Loading(tau0_1=75e6), t_end=0.1,
                 record=Record(fields=()))
    sc = base.replace(loading=Loading(tau0_1=75e6, **NUC))
    assert scenes_equal(Scene.from_toml(sc.to_toml()), sc)
    ds = sc.to_dataset()
    assert ds.attrs["loading.nucleation_radius"] == 3000.0 and ds.attrs["loading.nucleation_dtau_1"] == 25e6
    assert scenes_equal(Scene.from_dataset(ds), sc)
    assert scene_to_data(sc)[0]["loading"]["nucleation_time"] == 1.0
    # a scene without it writes exactly what it wrote before the option existed
    assert "nucleation" not in base.to_toml() and not any("nucleation" in k for k in base.to_dataset().attrs)


@pytest.mark.parametrize("bad, field, message", [
    ({"nucleation_radius": 0.0}, "nucleation_radius", "must be > 0"),
    ({"nucleation_time": -1.0}, "nucleation_time", "must be >= 0"),
    ({"nucleation_x3": float("nan")}, "nucleation_x3", "must be a finite number"),
    ({"nucleation_dtau_1": True}, "nucleation_dtau_1", "must be a number"),
    ({"nucleation_radius": np.zeros(3)}, "nucleation_radius", "must be a number"),
    ({"nucleation_time": None}, "nucleation_time", "is required with"),
    ({"nucleation_dtau_1": None}, "nucleation_dtau_1", "is required with"),
])
def test_bad_nucleation_is_named(bad, field, message):
    with pytest.raises(InputError, match=rf"^loading\.{field}: {message}"):
        Loading(tau0_1=1.0, **{**NUC, **bad})


def test_a_normal_law_refuses_a_shear_nucleation():
    from cracklab import LinearCohesive

    with pytest.raises(InputError, match=r"^loading\.tau0_1: law 'linear_cohesive' does not act on component 1"):
        Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=Grid(n1=8, n3=8, L1=8.0, L3=8.0),
              law=LinearCohesive(tau_c=1.0, delta_c=0.1), loading=Loading(tau0_2=0.5, **NUC), t_end=0.1)


def test_taper_is_the_tpv_tanh_transition():
    from cracklab.scenes import taper

    W, w = 15000.0, 3000.0
    x = np.array([0.0, -15000.0, 15000.0, 15750.0, 16500.0, -16500.0, 17250.0, 17999.0, 18000.0, 25000.0])
    B = taper(x, W, w)
    want = [1.0, 1.0, 1.0] + [0.5 * (1 + math.tanh(w / (abs(v) - W - w) + w / (abs(v) - W))) for v in x[3:8]] + \
        [0.0, 0.0]
    np.testing.assert_allclose(B, want, rtol=1e-13, atol=0)
    assert B[4] == 0.5 and taper(16500.0, W, w) == 0.5
    assert taper(15000.0 + 1e-6, W, w) == 1.0 and taper(18000.0 - 1e-6, W, w) == 0.0   # smooth ends
    with pytest.raises(InputError, match=r"^w: must be > 0"):
        taper(x, W, 0.0)
