"""cracklab.loops: the compiled rotation and shear solve against the numpy expressions
they replace (bitwise: the same operations in the same order), and a whole 3D shear run
with and without them."""
from __future__ import annotations

import numpy as np
import pytest

from cracklab.solver import loops
pytest.importorskip("numba")


def test_rotation_matches_eq28_and_inverts():
    rng = np.random.default_rng(0)
    shape = (16, 9)
    ang = rng.uniform(0, 2 * np.pi, shape)
    c, s = np.cos(ang), np.sin(ang)
    a = rng.standard_normal(shape) + 1j * rng.standard_normal(shape)
    b = rng.standard_normal(shape) + 1j * rng.standard_normal(shape)
    two, three = loops.rotate(c, s, a, b)
    assert np.array_equal(two, c * a + s * b) and np.array_equal(three, c * b - s * a)
    back1, back3 = loops.rotate(c, s, two, three, inverse=True)
    assert np.allclose(back1, a, atol=1e-14) and np.allclose(back3, b, atol=1e-14)
    # a stack of spectra (time first) broadcasts against the per-mode c, s
    at, bt = np.stack([a, 2 * a]), np.stack([b, -b])
    two_t, three_t = loops.rotate(c, s, at, bt)
    assert np.array_equal(two_t[1], c * (2 * a) + s * (-b)) and np.array_equal(three_t[0], three)


@pytest.mark.parametrize("strength_kind", ["scalar", "field"])
@pytest.mark.parametrize("with_bonded", [False, True])
def test_shear_velocity_matches_the_numpy_step(strength_kind, with_bonded):
    from cracklab import TractionFree
    from cracklab.laws import solve_velocity

    rng = np.random.default_rng(1)
    shape = (12, 7)
    t1, t3 = rng.standard_normal(shape), rng.standard_normal(shape)
    t1[0, 0] = t3[0, 0] = 0.0                      # |tau*| = 0: v = 0
    S = 0.8 if strength_kind == "scalar" else rng.uniform(0, 1.5, shape)
    bonded = rng.random(shape) < 0.3 if with_bonded else None
    law = TractionFree() if bonded is None else TractionFree(bonded=bonded)
    eta = {1: 0.5, 3: 0.5}
    v, tau = solve_velocity(law, {}, {1: t1, 3: t3}, None, eta, 0.1, S)
    v_only, none = solve_velocity(law, {}, {1: t1, 3: t3}, None, eta, 0.1, S, traction=False)
    assert none is None and all(np.array_equal(v_only[c], v[c]) for c in (1, 3))
    mag = np.sqrt(t1**2 + t3**2)
    scale = np.where(mag > 0, np.maximum(mag - S, 0.0) / (0.5 * np.where(mag > 0, mag, 1.0)), 0.0)
    if bonded is not None:
        scale = np.where(bonded, 0.0, scale)
    for c, t in ((1, t1), (3, t3)):
        assert np.array_equal(v[c], scale * t)
        assert np.array_equal(tau[c], t - 0.5 * (scale * t))
    # where it slides, the traction sits on the strength and points along tau*
    slide = (scale > 0)
    assert np.allclose(np.hypot(tau[1], tau[3])[slide], np.broadcast_to(S, shape)[slide])


@pytest.mark.parametrize("formulation", ["product", "velocity", "displacement"])
def test_3d_shear_run_is_the_same_with_the_numpy_glue(monkeypatch, formulation):
    """A 3D shear run (slip weakening, bonded border; each time scheme) with the compiled
    loops, which write into the response's work arrays, and with them switched off (fresh
    arrays everywhere) gives the same slip to the last bit."""
    from cracklab import (Grid, Loading, Material, Numerics, Record, Scene, SlipWeakening, simulate)

    g = Grid(n1=32, n3=16, L1=2.0, L3=1.0)
    x1, x3 = np.meshgrid(g.x1, g.x3, indexing="ij")
    patch = (np.abs(x1 - 1.0) < 0.2) & (np.abs(x3 - 0.5) < 0.2)
    bonded = (np.abs(x1 - 1.0) > 0.8) | (np.abs(x3 - 0.5) > 0.4)
    law = SlipWeakening(mu_s=0.6, mu_d=0.5, D_c=0.01, sigma_n=1.0, bonded=bonded)
    sc = Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=g, law=law,
               loading=Loading(tau0_1=np.where(patch, 0.62, 0.55)), t_end=0.6,
               beta=0.2 if formulation == "product" else 0.05,  # inside each scheme's stable range
               record=Record(fields=("delta_1", "delta_3"), every=10),
               numerics=Numerics(engine="exponential", formulation=formulation))
    fast = simulate(sc)
    with loops.python_only():
        slow = simulate(sc)
    assert float(np.abs(fast.delta_1).max()) > 0
    for f in ("delta_1", "delta_3"):
        assert np.array_equal(fast[f].values, slow[f].values)


@pytest.mark.parametrize("broken_kind", ["all", "mask"])
@pytest.mark.parametrize("contact", [False, True])
@pytest.mark.parametrize("with_bonded", [False, True])
@pytest.mark.parametrize("strength_kind", ["scalar", "field"])
def test_normal_velocity_matches_the_numpy_step(broken_kind, contact, with_bonded, strength_kind):
    """Step (v) for the opening: the compiled pass against the numpy expressions it
    replaces, bit for bit (a NaN stays a NaN, so the finiteness check still sees it)."""
    rng = np.random.default_rng(2)
    shape = (12, 7)
    t2 = rng.standard_normal(shape)
    t2[3, 3] = np.nan
    S = 0.3 if strength_kind == "scalar" else rng.uniform(0, 1.0, shape)
    broken = True if broken_kind == "all" else rng.random(shape) < 0.5
    delta = rng.uniform(-0.1, 0.1, shape)
    bonded = rng.random(shape) < 0.3 if with_bonded else None
    eta, dt = 0.7, 0.05
    v, tau = loops.normal_velocity(t2, S, eta, broken, delta if contact else None, dt, bonded)
    ref = (t2 - S) / eta
    ref = np.where(broken, ref, np.maximum(ref, 0.0)) if broken is not True else ref
    if contact:
        ref = np.maximum(ref, -delta / dt)
    if bonded is not None:
        ref = np.where(bonded, 0.0, ref)
    assert np.array_equal(v, ref, equal_nan=True)
    assert np.array_equal(tau, t2 - eta * ref, equal_nan=True)
    assert np.isnan(v[3, 3]) == (bonded is None or not bonded[3, 3])


def test_add_scaled_matches_numpy():
    rng = np.random.default_rng(3)
    y, x = rng.standard_normal((9, 5)), rng.standard_normal((9, 5))
    ref = y + 0.37 * x
    out = loops.add_scaled(y, 0.37, x)
    assert out is y and np.array_equal(y, ref)
    loops.add_scaled(y, 2.0, 1.5)  # a scalar broadcasts (the numpy path)
    assert np.array_equal(y, ref + 2.0 * 1.5)


def test_mode_i_run_is_the_same_with_the_numpy_glue(monkeypatch):
    """A mode I run with a cohesive law and contact, compiled loops on and off: the same
    opening to the last bit."""
    from cracklab import Grid, LinearCohesive, Loading, Material, Numerics, Record, Scene, simulate

    g = Grid(n1=32, n3=16, L1=2.0, L3=1.0)
    x1, x3 = np.meshgrid(g.x1, g.x3, indexing="ij")
    crack = (np.abs(x1 - 1.0) < 0.25) & (np.abs(x3 - 0.5) < 0.2)
    law = LinearCohesive(tau_c=1.0, delta_c=0.02, initial_crack=crack)
    sc = Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=g, law=law,
               loading=Loading(tau0_2=np.where(crack, 0.9, 0.6) * np.cos(3 * x3)), t_end=0.8, beta=0.2,
               record=Record(fields=("delta_2",), every=8), numerics=Numerics(engine="exponential"))
    fast = simulate(sc)
    with loops.python_only():
        slow = simulate(sc)
    assert float(np.abs(fast.delta_2).max()) > 0
    assert np.array_equal(fast["delta_2"].values, slow["delta_2"].values)


def test_product_scheme_helpers_match_numpy():
    rng = np.random.default_rng(4)
    shape = (10, 6)
    x, y, z = (rng.standard_normal(shape) for _ in range(3))
    assert np.array_equal(loops.plus_scaled(x, 0.3, y), x + 0.3 * y)
    w = np.empty(shape)
    assert loops.plus_scaled(x, 0.3, y, out=w) is w and np.array_equal(w, x + 0.3 * y)
    assert loops.plus_mean(x, 0.7, y, z, out=w) is w and np.array_equal(w, x + 0.7 * (y + z))
    assert np.array_equal(loops.plus_mean(x, 0.7, y, z), x + 0.7 * (y + z))
    ref = x + 0.25 * (y + z)
    assert loops.add_mean_step(x, 0.25, y, z) is x and np.array_equal(x, ref)
    H = rng.standard_normal(shape) + 1j * rng.standard_normal(shape)
    V = rng.standard_normal(shape) + 1j * rng.standard_normal(shape)
    K = rng.standard_normal(shape)
    out = np.empty_like(H)
    assert loops.plus_product(H, K, V, out=out) is out and np.array_equal(out, H + K * V)
    assert np.array_equal(loops.plus_product(H, 2.0, V), H + 2.0 * V)  # a scalar K broadcasts
