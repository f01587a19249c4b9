"""Interface laws and step (v) of the algorithm (``solve_velocity``), then small runs.

Step (v): with tau* the traction the plane would carry if it did not move further
(load plus elastodynamic functional), Eq. (3) reads tau = tau* - eta v, and the law
says tau <= strength, with v = 0 (stick) below strength. So v = (tau* - S)/eta for
the opening of a point that opens, and |v| = (|tau*| - S)/eta along tau* in shear.
"""
from __future__ import annotations

import numpy as np
import pytest

from cracklab import (Grid, LinearCohesive, Loading, Material, Numerics, PrescribedRupture, Record,
                      Scene, SlipWeakening, TractionFree, simulate)
from cracklab.laws import solve_velocity
from cracklab.solver.interfaces import for_scene as interface_for_scene

MAT = Material(mu=1.0, cs=1.0, nu=0.25)
ETA = {c: MAT.eta(c) for c in (1, 2, 3)}
DT = 0.01
G = Grid(n1=4, n3=2, L1=1.0, L3=0.5)   # 8 points for hand-made states


def col(*values):
    """A (4, 2) field from 8 values, row-major."""
    return np.asarray(values, dtype=float).reshape(4, 2)


# ============================================================================ step (v): opening
def test_opening_sticks_at_or_below_strength_and_opens_above():
    law = LinearCohesive(tau_c=1.0, delta_c=0.1)
    state = law.init_state(G)
    strength = law.strength(state, 0.0, G)
    np.testing.assert_array_equal(strength, 1.0)
    tau_star = {2: col(-3.0, 0.0, 0.5, 1.0, 1.0 + 1e-12, 1.5, 2.0, 4.0)}
    delta = {2: np.zeros(G.shape)}
    v, tau = solve_velocity(law, state, tau_star, delta, ETA, DT, strength)
    expected = np.maximum(tau_star[2] - 1.0, 0.0) / ETA[2]
    np.testing.assert_allclose(v[2], expected, rtol=1e-14, atol=0)
    assert v[2].ravel()[3] == 0.0 and v[2].ravel()[4] > 0.0
    # the traction after the step: tau* where stuck, the strength where opening
    np.testing.assert_allclose(tau[2], np.minimum(tau_star[2], 1.0), rtol=1e-14, atol=1e-15)
    assert set(v) == set(tau) == {2}


def test_cohesive_points_never_close():
    """Inside the cohesive zone (0 < delta_max < delta_c) the opening rate is >= 0."""
    law = LinearCohesive(tau_c=1.0, delta_c=0.1)
    state = law.init_state(G)
    opening = col(0.0, 0.01, 0.05, 0.09, 0.02, 0.03, 0.0999, 0.04)
    law.update(state, {2: opening}, DT, None, 0.0)
    strength = law.strength(state, 0.0, G)
    # strengths 1, .9, .5, .1, .8, .7, .001, .6
    tau_star = {2: col(-5.0, -1.0, 0.0, 0.3, 0.5, 0.9, 0.0, -0.2)}
    v, tau = solve_velocity(law, state, tau_star, {2: opening}, ETA, DT, strength)
    assert np.all(v[2] >= 0.0)
    expected = np.maximum(tau_star[2] - strength, 0.0) / ETA[2]
    np.testing.assert_allclose(v[2], expected, rtol=1e-13, atol=1e-15)
    assert np.flatnonzero(v[2]).tolist() == [3, 5]
    np.testing.assert_allclose(v[2].ravel()[[3, 5]], [0.2 / ETA[2], 0.2 / ETA[2]], rtol=1e-12)


def test_broken_points_close_but_not_through_contact():
    law = LinearCohesive(tau_c=1.0, delta_c=0.1)
    state = law.init_state(G)
    opening = col(0.2, 0.2, 0.15, 0.15, 0.3, 0.3, 0.12, 0.5)
    law.update(state, {2: opening}, DT, None, 0.0)
    assert np.all(law.broken(state))
    strength = law.strength(state, 0.0, G)
    np.testing.assert_array_equal(strength, 0.0)
    # mild compression: closes at (tau* - 0)/eta, not reaching contact within the step
    mild = -0.5 * opening.min() * ETA[2] / DT
    tau_star = {2: np.full(G.shape, mild)}
    v, _ = solve_velocity(law, state, tau_star, {2: opening}, ETA, DT, strength)
    np.testing.assert_allclose(v[2], mild / ETA[2], rtol=1e-14)
    assert np.all(v[2] < 0)
    # strong compression: closes exactly to delta = 0 after the step, never below
    tau_star = {2: col(-1e3, -1e4, -50.0, -1e3, -1e5, -1e3, -1e3, -1e3)}
    v, tau = solve_velocity(law, state, tau_star, {2: opening}, ETA, DT, strength)
    after = opening + DT * v[2]
    assert np.all(after >= -1e-15)
    np.testing.assert_allclose(v[2], np.maximum(tau_star[2] / ETA[2], -opening / DT), rtol=1e-14)
    # contact pressure: the traction after the step is compressive where contact acts
    assert np.all(tau[2] < 0)


def test_traction_free_without_contact_interpenetrates():
    law = TractionFree(contact=False)
    state = law.init_state(G)
    opening = np.full(G.shape, 0.01)
    tau_star = {2: np.full(G.shape, -10.0)}
    v, tau = solve_velocity(law, state, tau_star, {2: opening}, ETA, DT, 0.0)
    np.testing.assert_allclose(v[2], -10.0 / ETA[2])
    np.testing.assert_allclose(tau[2], 0.0, atol=1e-14)
    v, _ = solve_velocity(TractionFree(contact=True), state, tau_star, {2: opening}, ETA, DT, 0.0)
    np.testing.assert_allclose(v[2], -opening / DT)


@pytest.mark.parametrize("component", [2, 1])
def test_bonded_points_never_move(component):
    bonded = col(1, 0, 0, 1, 1, 1, 0, 0).astype(bool)
    if component == 2:
        law = TractionFree(bonded=bonded)
        comps = (2,)
    else:
        law = SlipWeakening(mu_s=0.6, mu_d=0.4, D_c=0.1, sigma_n=1.0, bonded=bonded)
        comps = (1, 3)
    state = law.init_state(G)
    strength = law.strength(state, 0.0, G)
    tau_star = {c: np.full(G.shape, 5.0 + c) for c in comps}
    delta = {c: np.zeros(G.shape) for c in comps}
    v, tau = solve_velocity(law, state, tau_star, delta, ETA, DT, strength)
    for c in comps:
        assert np.all(v[c][bonded] == 0.0)
        assert np.all(v[c][~bonded] != 0.0)
        np.testing.assert_array_equal(tau[c][bonded], tau_star[c][bonded])


# ============================================================================ step (v): shear
def test_shear_slip_is_collinear_with_traction_and_sticks_below_strength():
    law = SlipWeakening(mu_s=0.6, mu_d=0.4, D_c=0.1, sigma_n=2.0)   # strength 1.2
    state = law.init_state(G)
    strength = law.strength(state, 0.0, G)
    np.testing.assert_allclose(strength, 1.2)
    rng = np.random.default_rng(0)
    angle = rng.uniform(0, 2 * np.pi, G.shape)
    mag = col(0.0, 0.5, 1.1, 1.2, 1.3, 2.0, 5.0, 1.2 + 1e-9)
    tau_star = {1: mag * np.cos(angle), 3: mag * np.sin(angle)}
    delta = {1: np.zeros(G.shape), 3: np.zeros(G.shape)}
    v, tau = solve_velocity(law, state, tau_star, delta, ETA, DT, strength)
    speed = np.hypot(v[1], v[3])
    np.testing.assert_allclose(speed, np.maximum(mag - 1.2, 0.0) / ETA[1], rtol=1e-9, atol=1e-15)
    slipping = speed > 0
    assert slipping.sum() == 4
    # along tau*: the cross product vanishes and the dot product is positive
    cross = v[1] * tau_star[3] - v[3] * tau_star[1]
    np.testing.assert_allclose(cross, 0.0, atol=1e-14)
    assert np.all((v[1] * tau_star[1] + v[3] * tau_star[3])[slipping] > 0)
    # the traction on slipping points is the strength, in the direction of tau*
    np.testing.assert_allclose(np.hypot(tau[1], tau[3])[slipping], 1.2, rtol=1e-13)
    for c in (1, 3):
        np.testing.assert_array_equal(tau[c][~slipping], tau_star[c][~slipping])


def test_plane_mode_III_slip_alone():
    law = SlipWeakening(mu_s=0.6, mu_d=0.4, D_c=0.1, sigma_n=1.0)
    state = law.init_state(G)
    tau_star = {3: col(-1.0, -0.6, -0.3, 0.0, 0.3, 0.6, 0.61, 1.0)}
    v, tau = solve_velocity(law, state, tau_star, {3: np.zeros(G.shape)}, ETA, DT,
                            law.strength(state, 0.0, G))
    expected = np.sign(tau_star[3]) * np.maximum(np.abs(tau_star[3]) - 0.6, 0.0) / ETA[3]
    np.testing.assert_allclose(v[3], expected, rtol=1e-12, atol=1e-15)
    assert set(v) == {3}


# ============================================================================ strength evolution
def test_linear_cohesive_strength_follows_the_maximum_opening():
    law = LinearCohesive(tau_c=2.0, delta_c=0.1)
    state = law.init_state(G)
    history = [col(0, 0.01, 0.02, 0.05, 0.08, 0.1, 0.2, -0.05),
               col(0, 0.02, 0.01, 0.06, 0.0, 0.05, 0.1, 0.03)]   # second step partly closes
    dmax = np.zeros(G.shape)
    for opening in history:
        law.update(state, {2: opening}, DT, None, 0.0)
        dmax = np.maximum(dmax, opening)
        expected = 2.0 * np.clip(1.0 - dmax / 0.1, 0.0, 1.0)
        np.testing.assert_allclose(law.strength(state, 0.0, G), expected, rtol=1e-14, atol=1e-15)
    s = law.strength(state, 0.0, G).ravel()
    # hand values after both steps: max openings 0, .02, .02, .06, .08, .1, .2, .03
    np.testing.assert_allclose(s, [2.0, 1.6, 1.6, 0.8, 0.4, 0.0, 0.0, 1.4], rtol=1e-13, atol=1e-15)
    assert law.broken(state).ravel().tolist() == [False] * 5 + [True, True, False]
    # no rehealing: closing completely does not restore strength
    law.update(state, {2: np.zeros(G.shape)}, DT, None, 0.0)
    np.testing.assert_allclose(law.strength(state, 0.0, G).ravel(), s, rtol=0, atol=0)


def test_linear_cohesive_initial_crack_has_no_strength():
    crack = col(0, 1, 1, 0, 0, 0, 0, 0).astype(bool)
    law = LinearCohesive(tau_c=1.0, delta_c=0.1, initial_crack=crack)
    state = law.init_state(G)
    s = law.strength(state, 0.0, G)
    np.testing.assert_array_equal(s[crack], 0.0)
    np.testing.assert_array_equal(s[~crack], 1.0)
    np.testing.assert_array_equal(law.broken(state), crack)


def test_slip_weakening_strength_follows_the_slip_path():
    law = SlipWeakening(mu_s=0.7, mu_d=0.5, D_c=0.2, sigma_n=3.0)
    state = law.init_state(G)
    assert law.update(state, {1: 0, 3: 0}, DT, None, 0.0) is None   # no rate at n = 0: no slip
    np.testing.assert_array_equal(state["slip"], 0.0)
    # back-and-forth slip along x1 plus a 3D component: the path, not the net slip, counts
    rates = [({1: col(1, -2, 0, 5, 10, 0, 3, 30), 3: col(0, 0, 4, 0, 0, 0, 4, 0)}),
             ({1: col(-1, 2, 0, -5, 10, 0, -3, 30), 3: col(0, 0, -4, 0, 0, 0, 4, 0)})]
    path = np.zeros(G.shape)
    for v in rates:
        law.update(state, {1: 0, 3: 0}, DT, v, 0.0)
        path += DT * np.hypot(v[1], v[3])
        np.testing.assert_allclose(state["slip"], path, rtol=1e-14)
    # path: .02, .04, .08, .1, .2, 0, .1, .6
    np.testing.assert_allclose(path.ravel(), [0.02, 0.04, 0.08, 0.1, 0.2, 0.0, 0.1, 0.6], rtol=1e-12)
    expected = 3.0 * (0.7 - 0.2 * np.clip(path / 0.2, 0.0, 1.0))
    np.testing.assert_allclose(law.strength(state, 0.0, G), expected, rtol=1e-14)
    np.testing.assert_allclose(law.strength(state, 0.0, G).ravel()[[4, 5, 7]], [1.5, 2.1, 1.5], rtol=1e-13)
    np.testing.assert_array_equal(law.failed(state).ravel(), path.ravel() >= 0.2)


def test_prescribed_rupture_plane_distance_to_a_line():
    g = Grid(n1=8, n3=1, L1=1.0, L3=1.0)
    law = PrescribedRupture(speed=2.0, origin=(0.5, 0.3), residual=0.1, strength_before=5.0)
    state = law.init_state(g)
    r = np.abs(g.x1 - 0.5)[:, None]   # x3 of the origin plays no role in the plane problem
    for t in (0.0, 0.06, 0.125, 0.2, 0.25, 0.3):
        law.update(state, {}, 0.01, None, t)
        s = law.strength(state, t, g)
        expected = np.where(t >= r / 2.0, 0.1, 5.0)
        np.testing.assert_array_equal(s, expected)
        np.testing.assert_array_equal(law.broken(state), t >= r / 2.0)


def test_prescribed_rupture_3d_distance_to_a_point():
    g = Grid(n1=8, n3=8, L1=1.0, L3=1.0)
    law = PrescribedRupture(speed=1.0, origin=(0.5, 0.25))
    state = law.init_state(g)
    x1, x3 = np.meshgrid(g.x1, g.x3, indexing="ij")
    r = np.hypot(x1 - 0.5, x3 - 0.25)
    for t in (0.0, 0.125, 0.2, 0.3, 0.5):
        law.update(state, {}, 0.01, None, t)
        s = law.strength(state, t, g)
        np.testing.assert_array_equal(s, np.where(t >= r, 0.0, np.inf))
    # node (5, 1) at (0.625, 0.125) is at r = 0.125 sqrt(2) = 0.177 from the origin
    st = law.init_state(g)
    for t, expected in ((0.17, np.inf), (0.18, 0.0)):
        law.update(st, {}, 0.01, None, t)
        assert law.strength(st, t, g)[5, 1] == expected
        assert law.strength(st, t, g)[4, 2] == 0.0        # the origin node itself


def test_prescribed_rupture_weakening_time():
    """Linear drop over [r/v - tw/2, r/v + tw/2] from the traction carried when it began."""
    g = Grid(n1=8, n3=1, L1=1.0, L3=1.0)
    tw = 0.1
    law = PrescribedRupture(speed=1.0, origin=(0.0, 0.0), residual=0.2, strength_before=9.0,
                            weakening_time=tw)
    state = law.init_state(g)
    i = 3                         # r = 0.375: the drop runs over t in [0.325, 0.425]
    carried = {1: np.full(g.shape, 0.6), 3: np.full(g.shape, 0.8)}   # |tau| = 1
    for t, expected in ((0.3, 9.0), (0.33, 0.2 + 0.95 * 0.8), (0.35, 0.2 + 0.75 * 0.8), (0.375, 0.6),
                        (0.4, 0.2 + 0.25 * 0.8), (0.43, 0.2), (0.6, 0.2)):
        law.update(state, {}, 0.025, None, t, carried)
        assert law.strength(state, t, g)[i, 0] == pytest.approx(expected, abs=1e-12), t
    # a point that carried less than the residual drops from the residual (no jump upward)
    law2 = PrescribedRupture(speed=1.0, residual=0.5, weakening_time=tw)
    st2 = law2.init_state(g)
    low = {3: np.full(g.shape, 0.1)}
    law2.update(st2, {}, 0.025, None, 0.33, low)
    assert law2.strength(st2, 0.33, g)[i, 0] == pytest.approx(0.5)
    assert law2.strength(st2, 0.4, g)[i, 0] == pytest.approx(0.5)


# ============================================================================ small runs
def _rupture_from_snapshots(res, name, level):
    """First recorded time at which ``name`` reached ``level`` at each node (NaN if never)."""
    vals = res[name].values
    reached = vals >= level
    first = np.argmax(reached, axis=0)
    t = res["t"].values[first]
    return np.where(reached.any(axis=0), t, np.nan)


N_CRACK = 512
C0 = 0.05


def cohesive_scene(constant_K=False, t_end=0.12, fields=("delta_2", "strength", "v_2", "tau_2"),
                   tau0=0.5):
    g = Grid(n1=N_CRACK, n3=1, L1=1.0, L3=1.0)
    centre = g.x1[N_CRACK // 2]
    crack = (np.abs(g.x1 - centre) <= C0 + 1e-12)[:, None]
    law = LinearCohesive(tau_c=1.0, delta_c=0.01, initial_crack=crack)
    return Scene(material=MAT, grid=g, law=law,
                 loading=Loading(tau0_2=tau0, constant_K=constant_K),
                 t_end=t_end, beta=0.5, record=Record(fields=fields, every=1),
                 numerics=Numerics()), crack[:, 0]


@pytest.fixture(scope="module")
def cohesive_run():
    sc, crack = cohesive_scene()
    return sc, crack, simulate(sc)


def test_mode_I_cohesive_crack_grows_symmetrically(cohesive_run):
    sc, crack, res = cohesive_run
    n = N_CRACK
    c = n // 2
    # G0 = (1 - nu) sigma^2 pi c0 / (2 mu) = 0.0147 against Gc = tau_c delta_c / 2 = 0.005
    G0 = (1 - MAT.nu) * 0.5**2 * np.pi * C0 / (2 * MAT.mu)
    assert G0 > 2.5 * 0.5 * 1.0 * 0.01
    broken_t = _rupture_from_snapshots(res, "delta_2", 0.01)[:, 0]
    tr = res["rupture_time"].values[:, 0]
    right = np.arange(c, n)
    grown = [i for i in right if not crack[i] and np.isfinite(broken_t[i])]
    assert len(grown) >= 10, "the crack did not grow"
    # symmetric about the centre node c: node c + j mirrors node c - j
    for arr in (broken_t, tr):
        mirror = arr[(2 * c - np.arange(n)) % n]
        np.testing.assert_array_equal(np.isnan(arr), np.isnan(mirror))
        ok = np.isfinite(arr)
        np.testing.assert_allclose(arr[ok], mirror[ok], rtol=0, atol=1e-12)
    for field in ("delta_2", "strength"):
        v = res[field].values[:, :, 0]
        np.testing.assert_allclose(v, v[:, (2 * c - np.arange(n)) % n], rtol=1e-9, atol=1e-12)
    # fails later the further from the initial crack (monotone along the growth)
    ahead = right[~crack[right]]
    bt = broken_t[ahead]
    bt = bt[np.isfinite(bt)]
    assert np.all(np.diff(bt) >= 0) and bt[-1] > bt[0]
    rt = tr[ahead]
    rt = rt[np.isfinite(rt)]
    assert np.all(np.diff(rt) >= 0) and rt.size > bt.size   # the cohesive zone leads
    # points start to open (rupture_time) before they break, and break ahead of nothing
    both = np.isfinite(broken_t) & ~crack
    assert np.all(tr[both] <= broken_t[both])
    # behind the cohesive zone: zero strength and opening >= delta_c, at every recorded time
    for s, d in zip(res["strength"].values[:, :, 0], res["delta_2"].values[:, :, 0]):
        behind = (d >= 0.01) & ~crack
        np.testing.assert_array_equal(s[behind], 0.0)
        newly = ~crack & (s == 0.0)
        assert np.all(d[newly] >= 0.01 - 1e-15)
        # never negative opening with contact
        assert np.all(d >= -1e-15)
    # cohesive zone at the end: strength tau_c (1 - delta/delta_c) and the traction equals it
    d, s = res["delta_2"].values[-1, :, 0], res["strength"].values[-1, :, 0]
    tau, v = res["tau_2"].values[-1, :, 0], res["v_2"].values[-1, :, 0]
    zone = (d > 0) & (d < 0.01) & ~crack
    assert zone.sum() >= 4
    np.testing.assert_allclose(s[zone], 1.0 * (1.0 - d[zone] / 0.01), rtol=1e-9, atol=1e-12)
    opening = v > 0
    np.testing.assert_allclose(tau[opening], s[opening], rtol=1e-9, atol=1e-12)
    assert np.all(tau[~opening] <= s[~opening] + 1e-12)


def test_constant_K_scales_the_load_with_crack_length():
    """The applied traction (tau + eta v - f, with f recomputed from the recorded openings)
    equals tau0 sqrt(l0 / l(t)) with l the length of broken plane (delta_max >= delta_c)."""
    sc, crack = cohesive_scene(constant_K=True, t_end=0.1, fields=("delta_2", "v_2", "tau_2"), tau0=0.6)
    res = simulate(sc)
    g = sc.grid
    resp = interface_for_scene(sc)   # the same scheme and history engine as the run
    dmax = np.where(crack, np.inf, 0.0)
    l0 = crack.sum() * g.dx1
    factors, expected = [], []
    for d, v, tau in zip(res["delta_2"].values, res["v_2"].values, res["tau_2"].values):
        f = resp.functional({2: d})[2]
        applied = tau + MAT.eta(2) * v - f
        np.testing.assert_allclose(applied, applied.mean(), rtol=0, atol=1e-9)   # uniform in space
        factors.append(applied.mean() / 0.6)
        dmax = np.maximum(dmax, d[:, 0])
        expected.append(np.sqrt(l0 / (np.count_nonzero(dmax >= 0.01) * g.dx1)))
    factors, expected = np.array(factors), np.array(expected)
    assert expected[-1] < 0.8   # the crack grew and the load dropped noticeably
    np.testing.assert_allclose(factors, expected, rtol=1e-9)


def test_slip_weakening_mode_III_nucleates_and_grows():
    g = Grid(n1=512, n3=1, L1=1.0, L3=1.0)
    x = g.x1 - g.x1[256]
    patch = (np.abs(x) <= 0.03 + 1e-12)[:, None]
    tau0 = np.where(patch, 0.85, 0.7)
    law = SlipWeakening(mu_s=0.8, mu_d=0.5, D_c=0.002, sigma_n=1.0)
    sc = Scene(material=MAT, grid=g, law=law, loading=Loading(tau0_3=tau0), t_end=0.15, beta=0.5,
               record=Record(fields=("v_3", "tau_3", "strength", "delta_3"), every=1))
    assert sc.components == (3,)
    res = simulate(sc)
    v, tau, s = res["v_3"].values[..., 0], res["tau_3"].values[..., 0], res["strength"].values[..., 0]
    # step 0: slip exactly where the load exceeds mu_s sigma_n
    np.testing.assert_array_equal(v[0] != 0, patch[:, 0])
    np.testing.assert_allclose(v[0][patch[:, 0]], (0.85 - 0.8) / MAT.eta(3), rtol=1e-12)
    # the slipping region grows outward, symmetrically
    tr = res["rupture_time"].values[:, 0]
    assert np.isfinite(tr).sum() > 3 * patch.sum()
    right = tr[256:]
    right = right[np.isfinite(right)]
    assert np.all(np.diff(right) >= 0)
    np.testing.assert_allclose(tr, tr[(512 - np.arange(512)) % 512], rtol=0, atol=1e-12)
    # traction on slipping points equals the friction strength; elsewhere it is below it
    slipping = v != 0
    assert slipping.sum() > 1000
    np.testing.assert_allclose(np.abs(tau[slipping]), s[slipping], rtol=0, atol=1e-9)
    assert np.all(np.abs(tau[~slipping]) <= s[~slipping] + 1e-9)
    # slip rate never reverses under this monotone loading, and strength drops to mu_d sigma_n
    assert np.all(v >= 0)
    assert s[-1].min() == pytest.approx(0.5)
