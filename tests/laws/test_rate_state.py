"""Rate-and-state friction (cracklab/laws/rate_state.py): the law, its step (v) and state
update, its inputs. The verification against an exact solution is in
test_rate_state_verification.py."""
import itertools
import math

import numpy as np
import pytest

import cracklab
from cracklab import Grid, InputError, Loading, Material, Numerics, Record, Scene, SimulationError
from cracklab.laws import LAWS, RateState
from cracklab.laws import rate_state as rs
from cracklab.model.scene_io import scenes_equal
from cracklab.solver.stepper import Stepper

MAT = Material(mu=1.0, cs=1.0, nu=0.25)
ETA = MAT.eta(1)
LAW = dict(a=0.01, b=0.015, L=1e-3, V0=1e-6, f0=0.6, sigma_n=1.0)
# SCEC TPV101-104: whole space c_s 3464 m/s, rho 2670 kg/m^3, sigma_n 120 MPa
TPV_ETA = 2670.0 * 3464.0**2 / (2 * 3464.0)


def plane(law, tau0=0.62, t_end=0.2, fields=("v_1", "psi", "tau_1", "strength"), n3=1, **kw):
    grid = Grid(n1=8, n3=n3, L1=0.08, L3=0.08)
    load = tau0 if isinstance(tau0, Loading) else Loading(tau0_1=tau0)
    return Scene(material=MAT, grid=grid, law=law, loading=load, t_end=t_end,
                 record=Record(fields=fields, every=1), **kw)


def coefficient(V, psi, a, V0):
    """f(V, psi) = a asinh[V / (2 V0) exp(psi / a)], in mpmath-free closed form."""
    lnu = math.log(V / (2 * V0)) + psi / a
    return a * (lnu + math.log(2) + math.exp(-2 * lnu) / 4 if lnu > 18 else math.asinh(math.exp(lnu)))


# ---------------------------------------------------------------------------- the law as data
def test_it_registers_by_its_toml_name_and_round_trips():
    assert LAWS["rate_state"] is RateState
    grid = Grid(n1=8, n3=8, L1=1.0, L3=1.0)
    a = 0.01 + 0.001 * np.arange(64.0).reshape(8, 8)
    law = RateState(a=a, b=0.014, L=0.4, V0=1e-6, f0=0.6, sigma_n=120e6, V_ini=1e-16, evolution="slip",
                    f_w=0.2, V_w=np.full((8, 8), 0.5))
    sc = Scene(material=Material(mu=3.2e10, cs=3464.0, nu=0.25), grid=grid, law=law,
               loading=Loading(tau0_1=40e6), t_end=1e-3, record=Record(fields=("psi",)),
               units={"length": "m", "time": "s", "stress": "Pa"})
    back = Scene.from_toml(sc.to_toml())
    assert scenes_equal(back, sc)
    ds = sc.to_dataset()
    assert ds.attrs["law.kind"] == "rate_state" and ds.attrs["law.evolution"] == "slip"
    assert ds["law_V_w"].attrs["units"] == "m s-1"
    assert scenes_equal(Scene.from_dataset(ds), sc)


@pytest.mark.parametrize("bad, message", [
    ({"a": 0.0}, r"^law\.a: must be > 0, got 0"),
    ({"b": -0.01}, r"^law\.b: must be > 0"),
    ({"L": 0.0}, r"^law\.L: must be > 0"),
    ({"V0": -1e-6}, r"^law\.V0: must be > 0"),
    ({"V_ini": 0.0}, r"^law\.V_ini: must be > 0"),
    ({"V_ini": None}, r"^law\.V_ini: is required"),
    ({"f0": float("nan")}, r"^law\.f0: must be a finite number"),
    ({"psi_ini": float("inf"), "V_ini": None}, r"^law\.psi_ini: must be a finite number"),
    ({"sigma_n": -1.0}, r"^law\.sigma_n: must be >= 0"),
    ({"evolution": "aging"}, r"^law\.evolution: must be one of ageing, slip"),
    ({"f_w": 0.2}, r"^law\.V_w: must be given with law\.f_w"),
    ({"f_w": 0.2, "V_w": 0.1}, r"^law\.f_w: strong velocity weakening .* goes with evolution = 'slip'"),
    ({"f_w": 0.0, "V_w": 0.1, "evolution": "slip"}, r"^law\.f_w: must be > 0"),
    ({"f_w": 0.2, "V_w": 0.0, "evolution": "slip"}, r"^law\.V_w: must be > 0"),
    ({"a": np.array([[0.01, -0.01]])}, r"^law\.a: must be > 0, got a field holding -0\.01"),
])
def test_bad_parameters_name_the_field_and_its_range(bad, message):
    with pytest.raises(InputError, match=message):
        RateState(**{**LAW, "V_ini": 1e-9, **bad})


def test_an_initial_state_from_v_ini_needs_a_load_above_the_damping_under_compression():
    law = RateState(**LAW, V_ini=1e-3)
    with pytest.raises(InputError, match=r"^law\.V_ini: the initial state from V_ini needs.*at node \(0, 0\), x1 = 0, "
                                         r"x3 = 0: \|tau0\| = 0, eta V_ini = 0\.0005"):
        plane(law, Loading(tau0_1=0.62, time="ramp", ramp_time=0.1))       # no load at t = 0
    with pytest.raises(InputError, match=r"^law\.V_ini: .*\|tau0\| = 0\.0004, eta V_ini = 0\.0005"):
        plane(law, 0.0004)
    follow = RateState(**{**LAW, "sigma_n": None}, V_ini=1e-3)
    with pytest.raises(InputError, match=r"^law\.V_ini: .*compression \(-tau0_2 > 0\).*-tau0_2 = 0"):
        plane(follow, Loading(tau0_1=0.62, tau0_2=0.5))                    # open faces


def test_an_initial_state_inconsistent_with_the_initial_stress_is_named():
    psi = 0.6
    carried = coefficient(1e-6, psi, 0.01, 1e-6) + ETA * 1e-6      # the load that slides at 1e-6 with psi
    plane(RateState(**LAW, V_ini=1e-6, psi_ini=psi), carried)      # consistent: accepted
    with pytest.raises(InputError, match=r"^law\.psi_ini: is inconsistent with the initial stress: at node \(0, 0\)"
                                         r".*sigma f\(V_ini, psi_ini\) = 0\.6 but \|tau0\| - eta V_ini = 0\.6099995 "):
        plane(RateState(**LAW, V_ini=1e-6, psi_ini=psi), 0.61)


def test_psi_is_recorded_by_name_with_its_unit():
    ds = cracklab.simulate(plane(RateState(**LAW, V_ini=1e-6), t_end=0.05))
    assert ds.psi.attrs["units"] == "1" and "psi" in ds.psi.attrs["long_name"]
    assert np.all(np.isfinite(ds.psi.values))


# ---------------------------------------------------------------------------- step (v)
@pytest.mark.parametrize("tol, accuracy", [(rs.STEP_TOL, 1e-10), (1e-7, 1e-12)])
def test_newton_converges_from_1e_20_to_1e2_over_the_tpv_ranges_from_any_guess(tol, accuracy):
    """|tau*| - eta V = sigma a asinh[V / (2 V0) exp(psi / a)] for V from 1e-20 to 1e2 m/s, a over
    TPV101-104's 0.008-0.02, psi from 0.1 to 1.2, sigma 120 MPa (and 1 kPa, 0), guesses from
    none and 1e-25 to 1e5 m/s: V to 1e-10 relative at the run's tolerance (1e-12 at tol 1e-7),
    never negative or NaN, at most 12 evaluations."""
    rs._kernel()
    worst, most = 0.0, 0
    for a, psi, sigma, V in itertools.product([0.008, 0.01, 0.016, 0.02], [0.1, 0.3, 0.5, 0.7, 0.9, 1.2],
                                              [120e6, 1e3, 0.0], np.logspace(-20, 2, 45)):
        lnc = psi / a - math.log(2e-6)
        T = TPV_ETA * V + sigma * coefficient(V, psi, a, 1e-6)
        for guess in [math.nan, 1e-25, 1e-20, V * 1e-6, V, V * 1e6, 1e2, 1e5, 0.0]:
            x0 = math.log(guess) if guess > 0 else (-math.inf if guess == 0 else math.nan)
            W, x, it = rs._newton(T, sigma * a, TPV_ETA, lnc, x0, guess, tol)
            assert 0 <= it <= 12 and W > 0 and math.isfinite(W), (a, psi, sigma, V, guess, W, it)
            assert abs(math.exp(x) / W - 1) < 1e-14
            worst, most = max(worst, abs(W / V - 1)), max(most, it)
    assert worst < accuracy and most <= 12


def test_newton_takes_one_evaluation_from_a_guess_that_is_already_the_root():
    rs._kernel()
    lnc = 0.7 / 0.01 - math.log(2e-6)
    for V in (1e-16, 1e-3, 3.0):
        T = TPV_ETA * V + 120e6 * coefficient(V, 0.7, 0.01, 1e-6)
        assert rs._newton(T, 120e6 * 0.01, TPV_ETA, lnc, math.log(V * (1 + 1e-9)), V * (1 + 1e-9), rs.STEP_TOL)[2] == 1


def tpv_points(shape=(12, 10)):
    """A plane of points spanning TPV101-104's parameters and slip rates from 1e-20 to 1e2 m/s."""
    rng = np.random.default_rng(3)
    a = rng.uniform(0.008, 0.02, shape)
    psi = rng.uniform(0.2, 1.0, shape)
    V = 10.0 ** rng.uniform(-20, 2, shape)
    T = TPV_ETA * V + 120e6 * np.vectorize(coefficient)(V, psi, a, 1e-6)
    return a, psi, V, T


def test_step_v_solves_the_balance_at_every_point_along_the_traction():
    """The compiled pass over a plane of points (the initial step, psi given): V and v along
    tau*, tau = tau* - eta v, |tau| = sigma f(V, psi) = the recorded strength."""
    a, psi, V, T = tpv_points()
    angle = np.linspace(0, 2 * np.pi, T.size).reshape(T.shape)
    law = RateState(a=a, b=0.012, L=0.02, V0=1e-6, f0=0.6, sigma_n=120e6, psi_ini=psi)
    grid = Grid(n1=12, n3=10, L1=1.0, L3=1.0)
    state = law.init_state(grid)
    law.update(state, None, 1e-3, None, 0.0)
    tau_star = {1: T * np.cos(angle), 3: T * np.sin(angle)}
    v, tau = law.solve(state, {c: x.copy() for c, x in tau_star.items()}, None, {1: TPV_ETA, 3: TPV_ETA}, 1e-3,
                       law.strength(state, 0.0, grid))
    speed = np.hypot(v[1], v[3])
    np.testing.assert_allclose(speed, V, rtol=1e-10)
    np.testing.assert_allclose(v[1] * tau_star[3] - v[3] * tau_star[1], 0.0, atol=1e-12 * speed.max() * T.max())
    for c in (1, 3):
        np.testing.assert_array_equal(tau[c], tau_star[c] - TPV_ETA * v[c])
    np.testing.assert_allclose(np.hypot(tau[1], tau[3]), state["strength"], rtol=1e-12)
    # the traction balance to 1e-10 (eta V + sigma a) at every point
    residual = np.abs(state["strength"] - 120e6 * rs.friction_coefficient(speed, psi, a, 1e-6))
    assert np.all(residual <= 1e-10 * (TPV_ETA * speed + 120e6 * a))


def test_zero_traction_gives_zero_slip_rate_and_bonded_points_stay():
    law = RateState(**LAW, psi_ini=0.6, bonded=np.eye(4, dtype=bool))
    grid = Grid(n1=4, n3=4, L1=1.0, L3=1.0)
    state = law.init_state(grid)
    law.update(state, None, 1e-3, None, 0.0)
    t1 = np.full((4, 4), 0.7)
    t1[0, 1] = 0.0
    v, tau = law.solve(state, {1: t1, 3: np.zeros((4, 4))}, None, {1: ETA, 3: ETA}, 1e-3, None)
    assert v[1][0, 1] == 0.0 and np.all(v[1][np.eye(4, dtype=bool)] == 0.0) and np.all(v[1] >= 0)
    np.testing.assert_array_equal(tau[1][np.eye(4, dtype=bool)], 0.7)


def test_a_step_that_cannot_converge_is_a_simulation_error_naming_the_point_and_values():
    law = RateState(**LAW, psi_ini=0.6)
    grid = Grid(n1=4, n3=4, L1=1.0, L3=1.0)
    state = law.init_state(grid)
    law.update(state, None, 1e-3, None, 0.0)
    t1 = np.full((4, 4), 0.7)
    t1[2, 3] = np.nan
    with pytest.raises(SimulationError, match=r"did not converge at node \(2, 3\), x1 = 0\.5, x3 = 0\.75: \|tau\*\| = "
                                              r"nan, sigma = 1, eta = 0\.5, a = 0\.01, V0 = 1e-06, psi = 0\.6"):
        law.solve(state, {1: t1, 3: np.zeros((4, 4))}, None, {1: ETA, 3: ETA}, 1e-3, None)


def test_the_python_fallback_runs_the_same_arithmetic():
    """Without numba the same functions run as Python: the same V and psi (to the last bits:
    the compiled math library may differ by an ulp)."""
    a, psi, V, T = tpv_points((6, 4))
    law = RateState(a=a, b=0.012, L=0.02, V0=1e-6, f0=0.6, sigma_n=120e6, psi_ini=psi)
    grid = Grid(n1=6, n3=4, L1=1.0, L3=1.0)
    results = []
    for python in (False, True):
        rs._kernel()
        saved = {}
        if python:
            for name in rs._HELPERS + rs._PASSES:
                saved[name] = getattr(rs, name)
                setattr(rs, name, saved[name].py_func)
            rs._KERNEL[0], kernel = rs._chunked, rs._KERNEL[0]
        try:
            state = law.init_state(grid)
            law.update(state, None, 1e-3, None, 0.0)
            law.solve(state, {1: T.copy(), 3: np.zeros(T.shape)}, None, {1: TPV_ETA, 3: TPV_ETA}, 1e-3, None)
            law.update(state, None, 1e-3, {1: 0, 3: 0}, 0.0)
            law.solve(state, {1: 1.01 * T, 3: np.zeros(T.shape)}, None, {1: TPV_ETA, 3: TPV_ETA}, 1e-3, None)
            results.append((state["V"].copy(), state["psi"].copy()))
        finally:
            for name, f in saved.items():
                setattr(rs, name, f)
            if python:
                rs._KERNEL[0] = kernel
    for x, y in zip(*results):
        np.testing.assert_allclose(y, x, rtol=1e-13)


# ---------------------------------------------------------------------------- the state update
@pytest.mark.parametrize("evolution", ["ageing", "slip", "strong"])
def test_the_state_update_is_exact_at_constant_slip_rate(evolution):
    """Over a step at constant V, psi follows the closed form: the ageing law's
    theta' = theta e^-s + (L / V)(1 - e^-s) (theta + dt at V = 0), the slip laws'
    psi' = psi_ss + (psi - psi_ss) e^-s (s = V dt / L), for V from 0 and 1e-20 to 1e2."""
    rs._kernel()
    a, b, L, V0, f0, fw, Vw = 0.012, 0.014, 0.4, 1e-6, 0.6, 0.2, 0.3
    law = {"ageing": rs.AGEING, "slip": rs.SLIP, "strong": rs.STRONG}[evolution]
    for psi, V, dt in itertools.product([0.3, 0.6, 0.9], [0.0] + list(np.logspace(-20, 2, 23)), [1e-4, 1e-2, 1.0]):
        s = V * dt / L
        if evolution == "ageing":
            theta = L / V0 * math.exp((psi - f0) / b)
            theta = theta + dt if V == 0 else theta * math.exp(-s) + L / V * -math.expm1(-s)
            want = f0 + b * math.log(V0 * theta / L)
            z = math.exp((psi - f0) / b)
        else:
            if V == 0:
                want = psi
            else:
                fss = f0 - (b - a) * math.log(V / V0)
                if evolution == "strong":
                    fss = fw + (fss - fw) / (1 + (V / Vw) ** 8) ** 0.125
                psiss = a * math.log(2 * V0 / V * math.sinh(fss / a))
                want = psiss + (psi - psiss) * math.exp(-s)
            z = psi
        zn, got = rs._evolve(law, z, psi, V, math.nan, a, 1 / a, b, dt / L, V0 * dt / L, math.log(2 * V0), f0, fw, Vw)
        assert abs(got - want) <= 1e-13 * max(1.0, abs(want)), (psi, V, dt, got, want)
        assert math.isfinite(got)


@pytest.mark.parametrize("evolution", ["ageing", "slip"])
def test_the_sequence_state_step_is_the_closed_form_at_each_point_of_field_parameters(evolution):
    """RateState.evolve_state (the fully dynamic sequences' state step) with a and L fields
    on a grid and a mask of points: at each point the closed form of the test above."""
    n = 12
    a = np.linspace(0.008, 0.02, n)
    L = np.linspace(0.004, 0.04, n)
    law = RateState(a=a, b=0.015, L=L, V0=1e-6, f0=0.6, sigma_n=1.0, V_ini=1e-9, evolution=evolution)
    at = np.arange(n) % 3 != 0
    psi = np.linspace(0.4, 0.9, at.sum())
    V = np.logspace(-12, 1, at.sum())
    got = law.evolve_state(psi, V, 0.37, at=at)
    for k, (ai, Li, p, v) in enumerate(zip(a[at], L[at], psi, V)):
        s = v * 0.37 / Li
        if evolution == "ageing":
            theta = Li / 1e-6 * math.exp((p - 0.6) / 0.015)
            theta = theta * math.exp(-s) + Li / v * -math.expm1(-s)
            want = 0.6 + 0.015 * math.log(1e-6 * theta / Li)
        else:
            fss = 0.6 - (0.015 - ai) * math.log(v / 1e-6)
            psiss = ai * math.log(2e-6 / v * math.sinh(fss / ai))
            want = psiss + (p - psiss) * math.exp(-s)
        assert abs(got[k] - want) <= 1e-13 * max(1.0, abs(want)), (k, got[k], want)


def test_the_initial_state_from_v_ini_slides_at_v_ini():
    """psi(0) = a ln[(2 V0 / V_ini) sinh((|tau0| - eta V_ini) / (a sigma))], and the first
    step then slides at V_ini (the traction at V_ini is tau0 - eta V_ini)."""
    tau0 = 0.63
    ds = cracklab.simulate(plane(RateState(**LAW, V_ini=1e-5), tau0, t_end=0.05))
    psi = 0.01 * math.log(2e-6 / 1e-5 * math.sinh((tau0 - ETA * 1e-5) / 0.01))
    np.testing.assert_allclose(ds.psi.values[0], psi, rtol=1e-14)
    np.testing.assert_allclose(ds.v_1.values[0], 1e-5, rtol=1e-12)
    np.testing.assert_allclose(ds.tau_1.values[0], tau0 - ETA * 1e-5, rtol=1e-14)
    np.testing.assert_allclose(ds.strength.values, ds.tau_1.values, rtol=1e-14)


def test_in_3d_the_slip_rate_is_collinear_with_a_uniform_load_and_the_same_as_the_plane_run():
    """Uniform load at an angle on an 8 x 8 plane: v along the load, |v| the plane run's."""
    law = RateState(**LAW, V_ini=1e-6, evolution="slip")
    c, s = math.cos(0.5), math.sin(0.5)
    flat = cracklab.simulate(plane(law, 0.64, fields=("v_1",)))
    ds = cracklab.simulate(plane(law, Loading(tau0_1=0.64 * c, tau0_3=0.64 * s), fields=("v_1", "v_3"), n3=8))
    np.testing.assert_allclose(np.hypot(ds.v_1.values, ds.v_3.values), flat.v_1.values[:, :, :1] * np.ones(8),
                               rtol=1e-13)
    np.testing.assert_allclose(ds.v_3.values, ds.v_1.values * s / c, rtol=1e-13)


def test_following_the_normal_traction_is_the_constant_sigma_n_run():
    """A uniform load with tau0_2 = -1 followed: the run with sigma_n = 1 (the normal traction
    of the q = 0 mode stays tau0_2; the product scheme's predictor runs on a copy of the state)."""
    law = RateState(**LAW, V_ini=1e-6)
    follow = RateState(**{**LAW, "sigma_n": None}, V_ini=1e-6)
    a = cracklab.simulate(plane(law, 0.64))
    b = cracklab.simulate(plane(follow, Loading(tau0_1=0.64, tau0_2=-1.0)))
    for name in ("v_1", "psi", "tau_1", "strength"):
        np.testing.assert_allclose(b[name].values, a[name].values, rtol=1e-14, err_msg=name)


@pytest.mark.parametrize("formulation", ["product", "velocity", "displacement"])
def test_a_resumed_run_is_the_uninterrupted_run(formulation):
    """Stepper state after step m (the law's state included) continues bit for bit, on a
    3D patch that slides (the elastodynamic response is not nil)."""
    grid = Grid(n1=16, n3=16, L1=1.0, L3=1.0)
    x1, x3 = np.meshgrid(grid.x1, grid.x3, indexing="ij")
    tau0 = 0.62 + 0.05 * (np.hypot(x1 - 0.5, x3 - 0.5) < 0.2)
    sc = Scene(material=MAT, grid=grid, law=RateState(**{**LAW, "L": 1e-2}, psi_ini=0.6), loading=Loading(tau0_1=tau0),
               t_end=0.6, beta=0.05, record=Record(fields=()), numerics=Numerics(formulation=formulation))
    whole = [s.v[1].copy() for s in Stepper(sc)]
    first = Stepper(sc)
    for n, _ in zip(range(20), first):
        pass
    saved = first.get_state()
    rest = [s.v[1].copy() for s in Stepper(sc, start=saved)]
    assert len(rest) == len(whole) - 20
    for x, y in zip(whole[20:], rest):
        np.testing.assert_array_equal(y, x)
    assert np.all(np.isfinite(whole[-1])) and whole[-1].max() > 1e-3


def test_the_vector_passes_give_the_scalar_pass_to_round_off(monkeypatch):
    """The ageing law's vector passes (laws/rate_state._fast_loop: the common branches
    without calls or early exits, bit for bit; _wide_loop: the rupture's points, with
    laws/elementary.py's exp, expm1, log and log1p, within a few ulp of the library's) leave
    to the scalar pass only the points they cannot do, and the run agrees with the scalar
    pass alone to round-off through nucleation and rupture: the slip rates within 1e-12 of
    their largest at every step, states, slip rates and strengths at the end within 1e-11
    relative (3e-15 and 1.3e-13 measured; Newton stops at 1e-10 relative in V, where a
    stopping test decided the other way would show), the same Newton evaluations."""
    import cracklab.laws.rate_state as rs
    from cracklab.cli.bench import bench_scene
    from cracklab.solver.stepper import Stepper

    def run():
        stepper = Stepper(bench_scene(48, 48, "shear", 150, engine="exponential", law="rate_state"))
        steps, left = [], []
        for s in stepper:
            steps.append(np.stack([s.v[c] for c in sorted(s.v)]))
            if "slow" in stepper.lstate:
                left.append(stepper.lstate["slow"].mean())
        ls = stepper.lstate
        end = {k: ls[k].copy() for k in ("psi", "V", "z", "strength")}
        return np.array(steps), end, (ls["newton_evaluations"], ls["newton_solves"], ls["newton_most"]), left

    fast = run()
    monkeypatch.setattr(rs, "_fast_kernel", lambda: None)
    scalar = run()
    # the vector passes did all but 1 % of the points over the run, all but 5 % at every step
    assert scalar[3] == [] and np.mean(fast[3]) < 0.01 and max(fast[3]) < 0.05
    assert fast[2] == scalar[2]
    v, w = fast[0], scalar[0]
    assert np.max(np.abs(v - w)) <= 1e-12 * np.max(np.abs(w)) and w.max() > 0.1     # a rupture, m/s
    for k in ("psi", "V", "z", "strength"):
        np.testing.assert_allclose(fast[1][k], scalar[1][k], rtol=1e-11, atol=0, err_msg=k)
    assert not all(np.array_equal(fast[1][k], scalar[1][k]) for k in ("psi", "V", "z"))   # the wide pass ran


def test_the_newton_step_grows_V_by_its_series_to_the_last_bits():
    """Newton's last step V e^h (laws/rate_state._grow: series to h^4 below |h| = 1e-3, to h^8
    up to 1e-2, where the scalar and the vector passes both take it) against exp: within
    2 ulp over the range it is used on."""
    import math

    import cracklab.laws.rate_state as rs

    grow = getattr(rs._grow, "py_func", rs._grow)
    h = np.concatenate([np.linspace(-1e-2, 1e-2, 4001), np.geomspace(1e-12, 1e-2, 500), -np.geomspace(1e-12, 1e-2, 500)])
    got = np.array([grow(1.0, x) for x in h])
    want = np.array([math.exp(x) for x in h])
    assert np.max(np.abs(got - want) / want) <= 2 * np.finfo(float).eps


def test_the_fast_pass_compiles_to_vector_code(tmp_path):
    """The fast and wide passes are compiled into vector instructions (laws/rate_state.LLVM_OPTIONS: without
    them LLVM leaves the loop scalar, too many arrays to check for overlap). Compiled afresh
    in a child process, with its own numba cache (cached code cannot be inspected)."""
    import os
    import subprocess
    import sys

    code = """
import re
import cracklab.laws.rate_state as rs
from cracklab.cli.bench import bench_scene
from cracklab.solver.stepper import Stepper
for _ in Stepper(bench_scene(32, 32, "shear", 6, engine="exponential", law="rate_state")):
    pass
irs = [f.inspect_llvm(sig) for f in (rs._fast_loop, rs._wide_loop) for sig in f.signatures]
print(len(irs), min(len(re.findall(r"<[0-9]+ x double>", ir)) for ir in irs))
"""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    compiled, vector_ops = map(int, out.stdout.split()[-2:])
    assert compiled >= 2 and vector_ops > 20
