"""The grid engine against the single-mode (modal) recurrences, exactly.

A traction-free plane loaded by one Fourier mode tau0 cos(k x1 + m x3) H(t) responds
in that mode only, and the modal analysis of section 3.1 (``cracklab.modal_response``,
an independent implementation of the same discrete schemes) gives its rate:

    v(x, t_n) = V(0+) r_n cos(k x1 + m x3),   V(0+) = tau0 / eta,   r_n = r(T = n gamma),

with gamma = q c_s dt, q = |(k, m)|, eta = mu a / (2 c_s) for the opening and
mu / (2 c_s) for slip. Step n of the engine is time t = n dt (the load acts from n = 0).
3D shear splits into the part of the slip along the wave vector (kernel C_II) and
the part across it (kernel C_III), Eqs. (27)-(28): with c = k/q, s = m/q, a load
tau0_1 = cos(...) has longitudinal amplitude c and transverse amplitude -s, so

    v_1 = V0 [c^2 r_II + s^2 r_III] cos(...),   v_3 = V0 c s [r_II - r_III] cos(...),

and a load tau0_3 = cos(...) gives v_1 = V0 c s [r_II - r_III] cos(...),
v_3 = V0 [s^2 r_II + c^2 r_III] cos(...). These hold to round-off (~1e-13 V0): the
engine and the modal code evaluate the same recurrence in different ways (FFT of the
plane and a 2D ring buffer against a scalar loop).
"""
from __future__ import annotations

import numpy as np
import pytest

import cracklab
from cracklab import Grid, Loading, Material, Numerics, Record, Scene, TractionFree, simulate
from cracklab.analysis.modal import modal_response
from cracklab.solver.interfaces import interface
from cracklab.solver.stability import beta_max
from cracklab.elastic.weights import convolution_weights

MAT = Material(mu=1.0, cs=1.0, nu=0.25)
GRID3 = Grid(n1=16, n3=8, L1=1.0, L3=0.5)
PLANE = Grid(n1=16, n3=1, L1=1.0, L3=1.0)
SCHEMES = {
    "displacement": ("trapezoid", "explicit"),
    "velocity": ("discretized", "semi-implicit"),
}
TOL = 1e-10  # relative to V(0+)
NSTEPS = 100


def wave(grid, i1, i3):
    """cos(k x1 + m x3) on the grid for wave-vector indices (i1, i3), and (k, m)."""
    k = 2 * np.pi * i1 / grid.L1
    m = 2 * np.pi * i3 / grid.L3 if not grid.plane else 0.0
    x1, x3 = np.meshgrid(grid.x1, grid.x3, indexing="ij")
    return np.cos(k * x1 + m * x3), k, m


def scene(grid, loading, beta, *, fields, formulation="displacement", window=None, engine="direct",
          nsteps=NSTEPS, law=None):
    dt = beta * grid.dx_min / MAT.cs
    return Scene(material=MAT, grid=grid, law=law or TractionFree(), loading=loading,
                 t_end=nsteps * dt, beta=beta, record=Record(fields=fields, every=1),
                 numerics=Numerics(formulation=formulation, window=window, engine=engine))


def modal(mode, gamma, nsteps, formulation):
    conv, integ = SCHEMES[formulation]
    r = modal_response(mode, gamma=gamma, T_end=nsteps * gamma, nu=MAT.nu, formulation=formulation,
                       convolution=conv, integration=integ)
    assert r.sizes["T"] == nsteps + 1
    return r.values


def check_times(res, sc):
    assert res.sizes["t"] == sc.nsteps + 1 == NSTEPS + 1
    np.testing.assert_allclose(res["t"].values, np.arange(NSTEPS + 1) * sc.dt, rtol=1e-13, atol=0)


# ------------------------------------------------------------------------------ mode I
@pytest.mark.parametrize("formulation", ["displacement", "velocity"])
@pytest.mark.parametrize("grid, index", [(GRID3, (3, 2)), (GRID3, (5, -3)), (PLANE, (3, 0))],
                         ids=["3d-oblique", "3d-oblique-negative-m", "plane"])
def test_mode_I_single_wave_matches_modal(grid, index, formulation):
    shape, k, m = wave(grid, *index)
    q = np.hypot(k, m)
    beta = 0.5 * beta_max(grid, formulation, SCHEMES[formulation][0], (2,), nu=0.25)
    sc = scene(grid, Loading(tau0_2=shape), beta, fields=("v_2", "delta_2"), formulation=formulation)
    assert sc.components == (2,)
    res = simulate(sc)
    check_times(res, sc)
    V0 = 1.0 / MAT.eta(2)
    assert MAT.eta(2) == pytest.approx(MAT.mu * MAT.a / (2 * MAT.cs))
    r = modal("I", q * MAT.cs * sc.dt, NSTEPS, formulation)
    expected = V0 * r[:, None, None] * shape[None]
    err = np.max(np.abs(res["v_2"].values - expected)) / V0
    assert err < TOL, err
    # the response is not trivial: r has moved well away from 1 over the run
    assert np.ptp(r) > 0.5


# ------------------------------------------------------------------------------ 3D shear
@pytest.mark.parametrize("formulation", ["displacement", "velocity"])
@pytest.mark.parametrize("loaded", [1, 3])
def test_3d_shear_single_wave_splits_into_modes_II_and_III(loaded, formulation):
    shape, k, m = wave(GRID3, 3, 2)
    q = np.hypot(k, m)
    c, s = k / q, m / q
    beta = min(0.05, 0.9 * beta_max(GRID3, formulation, SCHEMES[formulation][0], (1, 3), nu=0.25))
    sc = scene(GRID3, Loading(**{f"tau0_{loaded}": shape}), beta, fields=("v_1", "v_3"),
               formulation=formulation)
    assert sc.components == (1, 3)
    res = simulate(sc)
    check_times(res, sc)
    V0 = 1.0 / MAT.eta(1)
    assert MAT.eta(1) == MAT.eta(3) == pytest.approx(MAT.mu / (2 * MAT.cs))
    gamma = q * MAT.cs * sc.dt
    rII, rIII = modal("II", gamma, NSTEPS, formulation), modal("III", gamma, NSTEPS, formulation)
    # the two kernels differ enough over the run for the split to matter
    assert np.max(np.abs(rII - rIII)) > 0.05
    if loaded == 1:
        a1, a3 = c**2 * rII + s**2 * rIII, c * s * (rII - rIII)
    else:
        a1, a3 = c * s * (rII - rIII), s**2 * rII + c**2 * rIII
    for name, amp in (("v_1", a1), ("v_3", a3)):
        expected = V0 * amp[:, None, None] * shape[None]
        err = np.max(np.abs(res[name].values - expected)) / V0
        assert err < TOL, (name, err)


# ------------------------------------------------------------------------------ plane II / III
@pytest.mark.parametrize("formulation", ["displacement", "velocity"])
@pytest.mark.parametrize("component, mode", [(1, "II"), (3, "III")])
def test_plane_shear_single_wave_matches_modal(component, mode, formulation):
    shape, k, _ = wave(PLANE, 3, 0)
    beta = 0.5 * beta_max(PLANE, formulation, SCHEMES[formulation][0], (component,), nu=0.25)
    sc = scene(PLANE, Loading(**{f"tau0_{component}": shape}), beta, fields=(f"v_{component}",),
               formulation=formulation)
    assert sc.components == (component,)   # the plane problem does not couple II and III
    res = simulate(sc)
    check_times(res, sc)
    V0 = 1.0 / MAT.eta(component)
    r = modal(mode, k * MAT.cs * sc.dt, NSTEPS, formulation)
    expected = V0 * r[:, None, None] * shape[None]
    err = np.max(np.abs(res[f"v_{component}"].values - expected)) / V0
    assert err < TOL, err


# ------------------------------------------------------------------------------ superposition
def _random_field(rng, grid):
    return rng.standard_normal(grid.shape)


@pytest.mark.parametrize("grid", [GRID3, PLANE], ids=["3d", "plane"])
def test_mixed_loading_is_the_sum_of_single_component_runs(grid):
    rng = np.random.default_rng(7)
    loads = {c: _random_field(rng, grid) for c in (1, 2, 3)}
    beta = 0.8 * beta_max(grid, "displacement", "trapezoid", (1, 2, 3), nu=0.25)
    fields = ("v_1", "v_2", "v_3", "delta_1", "delta_2", "delta_3")
    nsteps = 40
    mixed = scene(grid, Loading(tau0_1=loads[1], tau0_2=loads[2], tau0_3=loads[3]), beta,
                  fields=fields, nsteps=nsteps)
    assert mixed.components == (1, 2, 3)
    res = simulate(mixed)
    singles = {}
    for c in (1, 2, 3):
        sc = scene(grid, Loading(**{f"tau0_{c}": loads[c]}), beta,
                   fields=tuple(f"{k}_{j}" for k in ("v", "delta") for j in (1, 2, 3)
                                if j in (c,) or (not grid.plane and c != 2 and j in (1, 3))),
                   nsteps=nsteps)
        singles[c] = simulate(sc)
    # every component is active and moves
    for f in fields:
        assert np.max(np.abs(res[f].values)) > 0.1
    scale = {c: 1.0 / MAT.eta(c) for c in (1, 2, 3)}
    for kind in ("v", "delta"):
        for j in (1, 2, 3):
            name = f"{kind}_{j}"
            expected = sum(singles[c][name].values for c in (1, 2, 3) if name in singles[c])
            err = np.max(np.abs(res[name].values - expected)) / (scale[j] * (mixed.t_end if kind == "delta" else 1))
            assert err < 1e-12, (name, err)
    if grid.plane:
        # no coupling in the plane problem: each component only sees its own load
        for j in (1, 3):
            assert scene(grid, Loading(**{f"tau0_{j}": loads[j]}), beta, fields=(),
                         nsteps=1).components == (j,)
    else:
        # in 3D a tau0_1 load does drive slip along x3
        assert np.max(np.abs(singles[1]["v_3"].values)) > 1e-3


def test_mode_I_scene_activates_component_2_only():
    shape, _, _ = wave(GRID3, 3, 2)
    sc = scene(GRID3, Loading(tau0_2=shape), 0.1, fields=("v_2",))
    assert sc.components == (2,)
    resp = interface(MAT, GRID3, sc.dt, sc.components)
    assert list(resp.channels) == ["I"]
    res = simulate(sc)
    assert {"v_2"} <= set(res.data_vars)
    assert not {"v_1", "v_3", "delta_1", "delta_3", "tau_1", "tau_3"} & set(res.data_vars)
    # asking for a component that is not computed is refused before the run
    with pytest.raises(cracklab.InputError, match="record.fields"):
        scene(GRID3, Loading(tau0_2=shape), 0.1, fields=("v_1",))
    # 3D shear needs both rotated channels, the plane problem only the one loaded
    assert sorted(interface(MAT, GRID3, sc.dt, (1, 3)).channels) == ["II", "III"]
    assert list(interface(MAT, PLANE, sc.dt, (3,)).channels) == ["III"]
    assert list(interface(MAT, PLANE, sc.dt, (1,)).channels) == ["II"]


# ------------------------------------------------------------------------------ history window
def truncated_modal_I(gamma, nsteps, window):
    """Displacement/trapezoid/explicit recurrence (42) with the weights xk_j dropped for
    j gamma > window (the kernel cut at T = window), written out here independently."""
    eta = MAT.a
    w = convolution_weights("I", gamma, np.arange(nsteps + 1), nu=MAT.nu, rule="trapezoid",
                            formulation="displacement")
    if window is not None:
        w = np.where(np.arange(nsteps + 1) * gamma <= window, w, 0.0)
    r = np.zeros(nsteps + 1)
    d = np.zeros(nsteps + 1)
    r[0] = 1.0
    for n in range(1, nsteps + 1):
        d[n] = d[n - 1] + r[n - 1]
        r[n] = 1.0 - gamma**2 / eta * np.dot(w[:n + 1], d[n::-1])
    return r


def test_history_window():
    shape, k, m = wave(GRID3, 3, 2)
    q = np.hypot(k, m)
    beta = 0.5 * beta_max(GRID3, "displacement", "trapezoid", (2,), nu=0.25)
    load = Loading(tau0_2=shape)
    base = scene(GRID3, load, beta, fields=("v_2",))
    gamma = q * base.dt
    assert gamma * NSTEPS > 20  # the run reaches well beyond T = 5
    # the hand-written reference reproduces modal_response without a window
    np.testing.assert_allclose(truncated_modal_I(gamma, NSTEPS, None), modal("I", gamma, NSTEPS, "displacement"),
                               rtol=0, atol=1e-12)
    full = simulate(base)["v_2"].values
    wide = GRID3.q_max() * MAT.cs * base.t_end * 1.01
    same = simulate(scene(GRID3, load, beta, fields=("v_2",), window=wide))["v_2"].values
    np.testing.assert_allclose(same, full, rtol=0, atol=1e-14)
    cut = simulate(scene(GRID3, load, beta, fields=("v_2",), window=5.0))["v_2"].values
    V0 = 1.0 / MAT.eta(2)
    assert np.max(np.abs(cut - full)) / V0 > 1e-3
    expected = V0 * truncated_modal_I(gamma, NSTEPS, 5.0)[:, None, None] * shape[None]
    err = np.max(np.abs(cut - expected)) / V0
    assert err < TOL, err


# ------------------------------------------------------------------------------ linearity
def test_linearity_doubling_the_load_doubles_delta():
    rng = np.random.default_rng(3)
    load = rng.standard_normal(GRID3.shape)
    beta = 0.5 * beta_max(GRID3, "displacement", "trapezoid", (2,), nu=0.25)
    one = simulate(scene(GRID3, Loading(tau0_2=load), beta, fields=("delta_2",), nsteps=50))["delta_2"].values
    two = simulate(scene(GRID3, Loading(tau0_2=2 * load), beta, fields=("delta_2",), nsteps=50))["delta_2"].values
    assert np.max(np.abs(one)) > 0
    np.testing.assert_allclose(two, 2 * one, rtol=0, atol=1e-13 * np.max(np.abs(one)))


@pytest.mark.parametrize("formulation", ["displacement", "velocity"])
@pytest.mark.parametrize("grid", [GRID3, PLANE], ids=["3d", "plane"])
@pytest.mark.parametrize("component", [1, 2, 3])
def test_uniform_load_opens_at_the_radiation_damping_rate(grid, component, formulation):
    """q = 0 has no history term: delta = tau0 t / eta exactly, from delta(0) = 0."""
    tau0 = 0.7
    beta = 0.5 * beta_max(grid, formulation, SCHEMES[formulation][0], (component,), nu=0.25)
    sc = scene(grid, Loading(**{f"tau0_{component}": tau0}), beta,
               fields=(f"delta_{component}", f"v_{component}", f"tau_{component}"),
               formulation=formulation, nsteps=30)
    res = simulate(sc)
    eta = MAT.eta(component)
    t = res["t"].values
    assert t[0] == 0.0
    expected = tau0 * t[:, None, None] / eta * np.ones((1,) + grid.shape)
    np.testing.assert_allclose(res[f"delta_{component}"].values, expected, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(res[f"v_{component}"].values, tau0 / eta, rtol=1e-12)
    np.testing.assert_allclose(res[f"tau_{component}"].values, 0.0, atol=1e-12)


@pytest.mark.parametrize("name,window", [("direct", None), ("direct", 20.0), ("exponential", None)])
def test_engine_state_round_trip(name, window):
    """An engine restored from get_state() continues exactly like the original."""
    from cracklab.history import make_engine

    rng = np.random.default_rng(3)
    g = rng.uniform(0, 2, (5, 4))
    g[0, 0] = 0.0
    kw = {} if window is None else {"window": window}
    a = make_engine(name, kernel="II", gamma=g, nu=0.25, **kw)
    b = make_engine(name, kernel="II", gamma=g, nu=0.25, **kw)
    xs = [rng.standard_normal(g.shape) + 1j * rng.standard_normal(g.shape) for _ in range(400)]
    for x in xs[:250]:
        a.push(x)
    b.set_state(a.get_state())
    for x in xs[250:]:
        ra, rb = a.push(x), b.push(x)
        assert np.array_equal(ra, rb)


@pytest.mark.parametrize("name", ["direct", "exponential"])
def test_push_scale_and_out(name):
    """push(x, out=, scale=) writes scale * S_n into out: the same numbers as scaling after,
    to rounding (the compiled taps run with fast-math: a part of a complex value that
    nearly cancels may differ in its last bits)."""
    from cracklab.history import make_engine

    rng = np.random.default_rng(8)
    g = rng.uniform(0, 2, (6, 5))
    g[0, 0] = 0.0
    a = make_engine(name, kernel="I", gamma=g, nu=0.25)
    b = make_engine(name, kernel="I", gamma=g, nu=0.25)
    scale = rng.standard_normal(g.shape)
    out = np.empty(g.shape, dtype=complex)
    for _ in range(40):
        x = rng.standard_normal(g.shape) + 1j * rng.standard_normal(g.shape)
        ra = a.push(x) * scale
        rb = b.push(x, out=out, scale=scale)
        assert rb is out
        np.testing.assert_allclose(rb, ra, rtol=1e-15, atol=1e-15 * np.abs(ra).max())
