"""The regularised normal stress of a friction law that follows the normal traction
(laws/friction.py, Prakash-Clifton in the form of Rubin & Ampuero 2007): sigma* relaxes
towards max(0, -tau_2) at the rate |V| / L* + 1 / t*, integrated exactly over a step."""
import math

import numpy as np
import pytest

import cracklab
from cracklab import Grid, InputError, Loading, Material, Numerics, Record, Scene, SlipWeakening
from cracklab.laws import ConstantFriction, RateState
from cracklab.solver.stepper import Stepper

TOP = Material(mu=1.0, cs=1.0, nu=0.25)
BOTTOM = Material(mu=0.6, cs=0.8, nu=0.3)
RS = dict(a=0.008, b=0.012, L=0.02, V0=1e-6, f0=0.6)


def _drive(law, sigmas, V, dt, check=None):
    """Step the law alone: the normal traction -sigmas[n] at step n, the slip rate V held
    (v_prev of every step but the first); returns sigma* and the shear traction per step
    (``check(state, tau)`` is called after every step)."""
    grid = Grid(n1=4, n3=1, L1=1.0, L3=1.0)
    state = law.init_state(grid)
    eta = {1: 0.5, 2: 0.9}
    delta = {1: np.zeros(grid.shape), 2: np.zeros(grid.shape)}
    out, tau1 = [], []
    for n, s in enumerate(sigmas):
        v_prev = None if n == 0 else {1: np.full(grid.shape, V), 2: np.zeros(grid.shape)}
        law.update(state, delta, dt, v_prev, n * dt)
        strength = law.strength(state, n * dt, grid)
        # a shear load well above the strength: the point slides; the normal one presses
        v, tau = law.solve(state, {1: np.full(grid.shape, 10.0), 2: np.full(grid.shape, -s)}, delta, eta, dt,
                           strength)
        np.testing.assert_array_equal(tau[2], -s)
        if check is not None:
            check(state, tau)
        out.append(state["sigma_eff"].copy())
        tau1.append(tau[1].copy())
    return np.array(out)[:, 0, 0], np.array(tau1)[:, 0, 0]


@pytest.mark.parametrize("scales", [{"normal_slip_scale": 0.05}, {"normal_time": 0.3},
                                    {"normal_slip_scale": 0.05, "normal_time": 0.3}])
@pytest.mark.parametrize("kind", ["slip_weakening", "constant_friction"])
def test_a_step_in_sigma_at_constant_slip_rate_relaxes_exponentially(kind, scales):
    """sigma = 2 at step 0, then 3: sigma*_n = 3 - exp(-(V / L* + 1 / t*) n dt), to round-off,
    and the shear traction is mu sigma*."""
    mu, V, dt, N = 0.6, 0.4, 0.01, 120
    law = (SlipWeakening(mu_s=mu, mu_d=mu, D_c=1.0, **scales) if kind == "slip_weakening" else
           ConstantFriction(mu_f=mu, **scales))
    sig, tau1 = _drive(law, [2.0] + [3.0] * N, V, dt)
    rate = V / scales.get("normal_slip_scale", math.inf) + 1.0 / scales.get("normal_time", math.inf)
    n = np.arange(N + 1)
    want = np.where(n == 0, 2.0, 3.0 - np.exp(-rate * n * dt))
    np.testing.assert_allclose(sig, want, rtol=1e-14)
    np.testing.assert_allclose(tau1, mu * want, rtol=1e-14)
    assert sig[N // 10] < 2.9     # it lags: the unregularised law would take 3 at once


def test_rate_state_strength_uses_sigma_eff():
    """The rate-and-state law slides against sigma* f(V, psi) with the same sigma*."""
    from cracklab.laws.rate_state import friction_coefficient

    law = RateState(**RS, psi_ini=0.6, normal_time=0.2)
    seen = []

    def check(state, tau):
        f = friction_coefficient(state["V"], state["psi"], RS["a"], RS["V0"])
        np.testing.assert_allclose(tau[1], state["sigma_eff"] * f, rtol=1e-9)
        seen.append(1)

    sig, tau1 = _drive(law, [2.0] + [3.0] * 30, 1e-3, 0.01, check)
    assert len(seen) == 31
    n = np.arange(31)
    np.testing.assert_allclose(sig, np.where(n == 0, 2.0, 3.0 - np.exp(-n * 0.01 / 0.2)), rtol=1e-14)


def bimaterial_scene(law, t_end=0.5, fields=("v_1", "tau_2", "strength"), every=1):
    """The plane in-plane problem between two materials: a slip-weakening rupture from an
    overstressed patch, whose slip changes the normal traction."""
    grid = Grid(n1=64, n3=1, L1=1.0, L3=1.0)
    x = grid.x1[:, None] * np.ones((1, 1))
    tau0 = 0.55 + 0.12 * (np.abs(x - 0.5) < 0.06)
    normal = -1.0 if law.sigma_n is None else 0.0     # a law with sigma_n does not act on tau_2
    return Scene(materials=(TOP, BOTTOM), grid=grid, law=law, loading=Loading(tau0_1=tau0, tau0_2=normal),
                 t_end=t_end, beta=0.3, record=Record(fields=fields, every=every), numerics=Numerics(formulation="auto"))


SW = dict(mu_s=0.6, mu_d=0.4, D_c=0.01)


@pytest.mark.parametrize("law", [SlipWeakening(**SW), RateState(**RS, V_ini=1e-6)])
def test_a_tiny_time_scale_is_the_unregularised_law(law):
    """t* far below dt: the decay is 0 and sigma* = max(0, -tau_2) at every step, so the run is
    the unregularised one to the bit."""
    import dataclasses

    a = cracklab.simulate(bimaterial_scene(law, t_end=0.3))
    b = cracklab.simulate(bimaterial_scene(dataclasses.replace(law, normal_time=1e-30), t_end=0.3,
                                           fields=("v_1", "tau_2", "strength", "sigma_eff")))
    if isinstance(law, SlipWeakening):   # a rupture: it slides and tau_2 moves
        assert float(np.abs(a.v_1).max()) > 0.1 and float(a.tau_2.std()) > 1e-3
    for name in ("v_1", "tau_2", "strength"):
        np.testing.assert_array_equal(b[name].values, a[name].values, err_msg=name)
    np.testing.assert_array_equal(b.sigma_eff.values, np.maximum(0.0, -a.tau_2.values))


def test_a_run_follows_the_discrete_relaxation():
    """In a bimaterial rupture (slip scale and time scale) the recorded sigma* obeys the
    step's exact relaxation against the recorded tau_2 and the slip rate of the step before,
    and lags the normal traction where it moves fast."""
    Ls, ts = 0.004, 0.05
    sc = bimaterial_scene(SlipWeakening(**SW, normal_slip_scale=Ls, normal_time=ts),
                          fields=("v_1", "tau_2", "strength", "sigma_eff"))
    ds = cracklab.simulate(sc)
    s = np.maximum(0.0, -ds.tau_2.values)
    se, v = ds.sigma_eff.values, ds.v_1.values
    np.testing.assert_array_equal(se[0], s[0])
    decay = np.exp(-sc.dt * (np.abs(v[:-1]) / Ls + 1.0 / ts))
    np.testing.assert_allclose(se[1:], s[1:] + (se[:-1] - s[1:]) * decay, rtol=1e-13, atol=1e-15)
    assert np.abs(se - s).max() > 0.02          # it does lag
    free = np.abs(v) > 0
    coef = ds.strength.values[free] / se[free]
    assert np.all((coef > 0.4 - 1e-12) & (coef < 0.6 + 1e-12))   # strength = mu(slip) sigma*


def test_a_resumed_regularised_run_is_the_uninterrupted_run():
    sc = bimaterial_scene(SlipWeakening(**SW, normal_slip_scale=0.004, normal_time=0.05), t_end=0.3)
    whole = [(st.v[1].copy(), st.law_state["sigma_eff"].copy()) for st in Stepper(sc)]
    first = Stepper(sc)
    for n, _ in zip(range(40), first):
        pass
    rest = [(st.v[1].copy(), st.law_state["sigma_eff"].copy()) for st in Stepper(sc, start=first.get_state())]
    assert len(rest) == len(whole) - 40
    for (v0, s0), (v1, s1) in zip(whole[40:], rest):
        np.testing.assert_array_equal(v1, v0)
        np.testing.assert_array_equal(s1, s0)


def test_toml_round_trip():
    law = SlipWeakening(**SW, normal_slip_scale=0.04, normal_time=0.002)
    sc = bimaterial_scene(law, fields=("sigma_eff",), every=None)
    text = sc.to_toml()
    assert "normal_slip_scale = 0.04" in text and "normal_time = 0.002" in text
    back = Scene.from_toml(text)
    assert back.law == law
    rs = RateState(**RS, V_ini=1e-6, normal_time=0.01)
    assert Scene.from_toml(sc.replace(law=rs).to_toml()).law == rs


@pytest.mark.parametrize("bad,field,words", [
    ({"normal_slip_scale": 0.0}, "normal_slip_scale", "must be > 0"),
    ({"normal_slip_scale": -1.0}, "normal_slip_scale", "must be > 0"),
    ({"normal_time": float("inf")}, "normal_time", "finite"),
    ({"normal_time": "x"}, "normal_time", "number"),
    ({"normal_time": 0.1, "sigma_n": 1.0}, "normal_time", "must be given without law.sigma_n"),
    ({"normal_slip_scale": 0.1, "sigma_n": 1.0}, "normal_slip_scale", "must be given without law.sigma_n"),
])
def test_bad_scales_name_the_field(bad, field, words):
    for cls, base in ((SlipWeakening, SW), (ConstantFriction, {"mu_f": 0.6}),
                      (RateState, {**RS, "V_ini": 1e-6})):
        with pytest.raises(InputError, match=rf"^law\.{field}: .*{words}"):
            bimaterial_scene(cls(**base, **bad))


def test_sigma_eff_is_recorded_only_when_regularised():
    with pytest.raises(InputError, match=r"^record.fields: 'sigma_eff' is the regularised normal stress: give "
                                         r"law.normal_slip_scale or law.normal_time"):
        bimaterial_scene(SlipWeakening(**SW), fields=("sigma_eff",))
