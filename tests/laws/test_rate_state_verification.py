"""Rate-and-state friction against exact results (docs/reference/equations.md, "Rate-and-state friction").

A uniform fault under a uniform load moves only its q = 0 mode, whose elastodynamic
functional is nil: tau = tau0 - eta V exactly (eta = mu / (2 c_s)), and V(t), psi(t)
follow the differential-algebraic system

    |tau0| - eta V = sigma a asinh[V / (2 V0) exp(psi / a)],   dpsi/dt = G(V, psi),

solved here independently (scipy's Radau at rtol 1e-12 on psi, V from the algebraic
equation by brentq at each evaluation), against which cracklab's runs converge at the
scheme's order as dt halves; and a velocity-strengthening fault (a > b) under constant
load settles to the steady sliding rate of |tau0| - eta V = sigma f(V, psi_ss(V)).
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import cracklab
from cracklab import Grid, Loading, Material, Record, Scene
from cracklab.laws import RateState

LAW = dict(a=0.01, b=0.015, L=1e-3, V0=1e-6, f0=0.6, sigma_n=1.0)


def coefficient(V, psi, a, V0):
    lnu = math.log(V / (2 * V0)) + psi / a
    return a * (lnu + math.log(2) + math.exp(-2 * lnu) / 4 if lnu > 18 else math.asinh(math.exp(lnu)))


def slip_rate(psi, tau0, eta, p):
    """V of |tau0| - eta V = sigma f(V, psi) (brentq on ln V)."""
    def g(x):
        return tau0 - eta * math.exp(x) - p["sigma_n"] * coefficient(math.exp(x), psi, p["a"], p["V0"])
    return math.exp(brentq(g, -100.0, math.log(tau0 / eta), xtol=1e-15, rtol=1e-15))


def steady_psi(evolution, V, p):
    """psi_ss(V): f0 - b ln(V / V0) (ageing); a ln[(2 V0 / V) sinh(f_ss / a)] (slip)."""
    if evolution == "ageing":
        return p["f0"] - p["b"] * math.log(V / p["V0"])
    fss = p["f0"] - (p["b"] - p["a"]) * math.log(V / p["V0"])
    return p["a"] * math.log(2 * p["V0"] / V * math.sinh(fss / p["a"]))


def exact(evolution, p, tau0, eta, psi0, t):
    """psi(t) and V(t) of the q = 0 mode, the reduced ODE dpsi/dt = G(V(psi), psi) by Radau."""
    a, b, L, V0, f0 = (p[k] for k in ("a", "b", "L", "V0", "f0"))

    def rhs(_, y):
        V = slip_rate(y[0], tau0, eta, p)
        if evolution == "ageing":
            return [b * V0 / L * (math.exp((f0 - y[0]) / b) - V / V0)]
        return [-V / L * (y[0] - steady_psi("slip", V, p))]

    sol = solve_ivp(rhs, (0.0, t[-1]), [psi0], method="Radau", rtol=1e-12, atol=1e-14, t_eval=t)
    assert sol.success
    return sol.y[0], np.array([slip_rate(x, tau0, eta, p) for x in sol.y[0]])


@pytest.mark.parametrize("evolution, t_end", [("ageing", 1300.0), ("slip", 300.0)])
def test_the_q0_mode_converges_to_the_exact_solution_at_second_order(evolution, t_end):
    """Steady sliding at V_ini = 1e-9 (psi_ss), then a load step of sigma a ln(1e3): V jumps
    to 9e-7 at once and, the fault being velocity weakening (b > a), accelerates until the
    radiation damping (eta = 1250: mu = 2500, c_s = 1) holds it at 1.0e-4, five decades above
    V_ini. The largest errors in psi and ln V over the run fall 4-fold as dt halves (500 to
    4000 steps; measured orders 1.98-2.00)."""
    mat = Material(mu=2500.0, cs=1.0, nu=0.25)
    eta = mat.eta(1)
    psi0 = steady_psi(evolution, 1e-9, LAW)
    tau0 = LAW["sigma_n"] * coefficient(1e-9, psi0, LAW["a"], LAW["V0"]) + eta * 1e-9 + \
        LAW["sigma_n"] * LAW["a"] * math.log(1e3)
    steps = (500, 1000, 2000, 4000)
    t = np.linspace(0.0, t_end, steps[0] + 1)
    psi_e, V_e = exact(evolution, LAW, tau0, eta, psi0, t)
    assert V_e[0] < 1e-6 and V_e[-1] > 1e-4 and V_e[-1] / V_e[-2] < 1 + 1e-6   # through the jump, to steady sliding
    errors = []
    for n in steps:
        beta = 0.5
        dx = t_end / n * mat.cs / beta              # dt = t_end / n
        sc = Scene(material=mat, grid=Grid(n1=8, n3=1, L1=8 * dx, L3=1.0),
                   law=RateState(**LAW, psi_ini=psi0, evolution=evolution), loading=Loading(tau0_1=tau0),
                   t_end=t_end, beta=beta, record=Record(fields=("psi", "v_1"), every=n // steps[0]))
        assert sc.nsteps == n
        ds = cracklab.simulate(sc)
        psi, V = ds.psi.values[:, 0, 0], ds.v_1.values[:, 0, 0]
        assert np.ptp(ds.v_1.values, axis=(1, 2)).max() == 0.0          # uniform: the q = 0 mode only
        errors.append((np.abs(psi - psi_e).max(), np.abs(np.log(V / V_e)).max()))
    errors = np.array(errors)
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(orders > 1.97) and np.all(orders < 2.03), orders
    assert errors[-1, 1] < 1e-5


@pytest.mark.parametrize("evolution", ["ageing", "slip"])
def test_a_velocity_strengthening_fault_settles_to_the_steady_sliding_rate(evolution):
    """a > b, a uniform load at an angle on an 8 x 8 plane, starting to slide at half the
    steady rate: V settles to the root V_ss of |tau0| - eta V = sigma f(V, psi_ss(V)) (and psi to
    psi_ss(V_ss)), along the load, to 1e-10 (at constant V the state update is exact, so the
    discrete steady state is the exact one)."""
    p = dict(LAW, a=0.015, b=0.01, L=1e-4)
    mat = Material(mu=1.0, cs=1.0, nu=0.25)
    eta = mat.eta(1)
    V_ss = 1e-4
    tau0 = p["sigma_n"] * coefficient(V_ss, steady_psi(evolution, V_ss, p), p["a"], p["V0"]) + eta * V_ss
    angle = 0.4
    grid = Grid(n1=8, n3=8, L1=0.8, L3=0.8)
    sc = Scene(material=mat, grid=grid, law=RateState(**p, V_ini=0.5 * V_ss, evolution=evolution),
               loading=Loading(tau0_1=tau0 * math.cos(angle), tau0_3=tau0 * math.sin(angle)), t_end=120.0,
               record=Record(fields=("v_1", "v_3", "psi"), times=(0.0, 120.0)))
    ds = cracklab.simulate(sc)
    # the root, independently: brentq on the steady balance
    root = math.exp(brentq(lambda x: tau0 - eta * math.exp(x) - p["sigma_n"] * coefficient(
        math.exp(x), steady_psi(evolution, math.exp(x), p), p["a"], p["V0"]), math.log(1e-8), math.log(1e-2),
        xtol=1e-15, rtol=1e-15))
    assert abs(root / V_ss - 1) < 1e-12
    V = np.hypot(ds.v_1.values, ds.v_3.values)
    np.testing.assert_allclose(V[0], 0.5 * V_ss, rtol=1e-12)
    np.testing.assert_allclose(V[-1], root, rtol=1e-10)
    np.testing.assert_allclose(ds.psi.values[-1], steady_psi(evolution, root, p), rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.v_3.values[-1], ds.v_1.values[-1] * math.tan(angle), rtol=1e-12)
