"""The history at a variable step (history/variable.py) against the exact convolution of
Eq. (33) by quadrature: one mode driven by a slip-rate history, linear between the ends of
steps whose length varies over ten decades (1e-6 to 1e4 in u = q c_s t), up, down and up
again. The engine's only approximation is the fit of the kernel's tail (history/fit.py), so
its error is that of the fit: below 5 times the fit's tolerance times max |V| with the
default fits, and a hundred times smaller with a fit 1e-8 tight. Against the static
response, Z(0) q c_s |D|, the issue's yardstick, the error is below 1e-9 of it."""
from __future__ import annotations

import numpy as np
import pytest

from cracklab.elastic.kernels import Z
from cracklab.history.fit import DEFAULT_TOL
from cracklab.history.variable import NearTable, VariableHistory
from cracklab.elastic.kernels import Z_integral

NU = 0.25
R = 0.7       # q c_s of the mode (1/s): the steps in time are the u-steps over R


def steps():
    lg = np.concatenate([np.linspace(-6, 4, 41), np.linspace(4, -6, 41)[1:], np.linspace(-6, 1, 21)[1:]])
    return 10.0 ** lg / R


def rate(t):
    return np.cos(0.3 * np.log1p(t)) + 0.5 * np.sin(t / 7.0) + 0.2j * np.sin(np.sqrt(t))


def exact(kernel, t, V, m):
    """int_0^t_m Z(R (t_m - s)) V(s) ds, V linear between the t_j: Gauss-Legendre, 16 nodes
    on panels at most 2 long in u, each piece on its own."""
    x, w = np.polynomial.legendre.leggauss(16)
    total = 0.0
    for j in range(m):
        sa, sb = t[j], t[j + 1]
        edges = np.linspace(sa, sb, max(1, int(np.ceil(R * (sb - sa) / 2.0))) + 1)
        c, hw = 0.5 * (edges[1:] + edges[:-1]), 0.5 * (edges[1:] - edges[:-1])
        s = (c[:, None] + hw[:, None] * x).ravel()
        Vs = V[j] + (V[j + 1] - V[j]) * (s - sa) / (sb - sa)
        total += np.sum((hw[:, None] * w).ravel() * np.asarray(Z(kernel, R * (t[m] - s), NU)) * Vs)
    return total


def run(kernel, tol=None, h=None):
    h = steps() if h is None else h
    t = np.concatenate([[0.0], np.cumsum(h)])
    V = rate(t)
    eng = VariableHistory(kernel, NU, np.array([R]), h.min(), tol=tol)
    eng.start(V[:1])
    out = np.empty(h.size, dtype=complex)
    for j, hj in enumerate(h):
        A, B = eng.prepare(hj)
        out[j] = A[0] + B[0] * V[j + 1]
        eng.commit(V[j + 1:j + 2])
    return t, V, out


# after the rise, at the longest steps, on the way down, at the shortest, and at the end
CHECKS = (12, 30, 41, 50, 60, 70, 81, 90, 101)


@pytest.mark.parametrize("kernel", ["I", "II", "III"])
def test_a_step_varying_over_ten_decades_gives_the_exact_convolution(kernel):
    t, V, out = run(kernel)
    D = np.concatenate([[0.0], np.cumsum(0.5 * np.diff(t) * (V[1:] + V[:-1]))])
    static = abs(float(Z(kernel, 0.0, NU))) * R * np.max(np.abs(D))
    err = max(abs(out[m - 1] - exact(kernel, t, V, m)) for m in CHECKS)
    assert err <= 5 * DEFAULT_TOL[kernel] * np.max(np.abs(V)), err
    assert err <= 1e-9 * static, (err, static)


def test_the_error_is_the_fits():
    """With a fit 1e-8 tight the same history is a hundred times closer: the steps add nothing."""
    t, V, out = run("III", tol=1e-8)
    err = max(abs(out[m - 1] - exact("III", t, V, m)) for m in CHECKS)
    assert err <= 5e-8 * np.max(np.abs(V)), err


@pytest.mark.parametrize("kernel", ["I", "II", "III"])
def test_the_near_table_is_the_closed_form(kernel):
    from cracklab.history.variable import T0_VARIABLE

    u = np.linspace(0.0, T0_VARIABLE, 57)
    P0, P00 = NearTable(kernel, NU)(u)
    assert np.max(np.abs(P0 - Z_integral(kernel, u, NU))) < 1e-13
    # P00 = int_0^u P0 by Gauss-Legendre on the closed form of P0
    x, w = np.polynomial.legendre.leggauss(40)
    ref = np.array([0.5 * b * np.sum(w * Z_integral(kernel, 0.5 * b * (x + 1), NU)) for b in u])
    assert np.max(np.abs(P00 - ref)) < 1e-13


def test_many_steps_below_the_floor_stop_the_run():
    from cracklab.errors import SimulationError

    eng = VariableHistory("III", NU, np.array([1.0]), 0.1)      # 40 steps of 0.1 fill the window
    eng.start(np.zeros(1))
    with pytest.raises(SimulationError, match="floor"):
        for _ in range(100):
            eng.prepare(0.01)
            eng.commit(np.ones(1))


def test_the_memory_estimate_is_what_the_history_holds():
    from cracklab.history.variable import memory

    r = 2 * np.pi * np.arange(1, 200) / 1e4 * 3000.0
    eng = VariableHistory("II", NU, r, 0.01)
    eng.start(np.zeros(r.size))
    for _ in range(VariableHistory.UNIFORM_AFTER + 2):
        eng.prepare(0.01)
        eng.commit(np.ones(r.size))
    eng.prepare(0.01)
    prep = sum(a.nbytes for a in eng._prep[1:]) + sum(a.nbytes for a in eng._cache[1])
    held = (eng.ring.nbytes + eng.hring.nbytes + eng.SR.nbytes + eng.SI.nbytes + prep + eng.first.nbytes + r.nbytes
            + eng._g.nbytes + eng._glast.nbytes)
    assert abs(memory("II", NU, r, 0.01) - held) <= 0.05 * held, (memory("II", NU, r, 0.01), held)


def test_a_run_of_equal_steps_reuses_its_weights(monkeypatch):
    """Steps at a fixed length (a rupture at the dynamic step) take the weights computed once
    for that length: the same convolution as the general pass to round-off, and the exact
    one to the fit's accuracy."""
    h = np.concatenate([10.0 ** np.linspace(1, -2, 20), np.full(600, 0.01), 10.0 ** np.linspace(-2, 1, 10),
                        np.full(20, 10.0), [3.0]]) / R
    t, V, fast = run("II", h=h)
    monkeypatch.setattr(VariableHistory, "UNIFORM_AFTER", 10 ** 9)
    _, _, general = run("II", h=h)
    assert np.max(np.abs(fast - general)) <= 1e-12 * np.max(np.abs(general))
    err = max(abs(fast[m - 1] - exact("II", t, V, m)) for m in (100, 620, 630, 651))
    assert err <= 5 * DEFAULT_TOL["II"] * np.max(np.abs(V)), err


def test_the_exponentials_kept_from_the_last_step_are_the_ones_computed():
    """A step's e^{lam r h}, kept for the next step's walk, gives the convolution that
    computing them again gives (a state without them: a checkpoint of an older version),
    to round-off, over modes whose windows hold one piece to dozens and steps that
    grow, shrink and repeat (the run of equal steps' weights included)."""
    r = 2 * np.pi * np.arange(1, 300) / 2e4 * 3000.0
    h = np.concatenate([np.full(12, 0.004), 0.004 * 1.4 ** np.arange(1, 12), [0.3, 0.05, 0.2, 3.0, 1e4, 0.01]])
    V = np.exp(1j * np.outer(np.arange(h.size + 1), r) * 1e-3) * (1 + np.arange(h.size + 1))[:, None]
    for cut in (5, 14, 20, 26):
        eng = VariableHistory("II", NU, r, 0.004)
        eng.start(V[0])
        for j in range(cut):
            eng.prepare(h[j])
            eng.commit(V[j + 1])
        state = eng.get_state()
        assert state["g_last"] is not None
        again = VariableHistory("II", NU, r, 0.004)
        again.set_state({**state, "g_last": None})
        for j in range(cut, min(cut + 3, h.size)):
            A, B = eng.prepare(h[j])
            A2, B2 = again.prepare(h[j])
            assert np.max(np.abs(A - A2)) <= 1e-12 * np.max(np.abs(A)), (cut, j)
            assert np.max(np.abs(B - B2)) <= 1e-12 * np.max(np.abs(B)), (cut, j)
            eng.commit(V[j + 1])
            again.commit(V[j + 1])


def test_modes_whose_terms_all_decay_over_a_step_take_it_in_closed_form(monkeypatch):
    """A mode whose every term decays below e^-50 over a step takes it in closed form and
    keeps its state as that closed form until a shorter step writes it out: the same
    convolution and states as the walk's to round-off, through long steps, short ones after
    them and a state taken between (BP1-FD's slow phases, kernel III)."""
    r = 2 * np.pi * np.arange(1, 400) / 6.4e5 * 3464.0
    h = np.concatenate([np.full(10, 0.004), 10.0 ** np.linspace(-2, 7, 30), [3e6, 2e6, 5e6, 1e5, 10.0, 0.3, 0.01],
                        10.0 ** np.linspace(-2, 6.5, 12), [0.004, 3e6, 0.05]])
    V = np.exp(1j * np.outer(np.arange(h.size + 1), r) * 1e-3) * (1 + np.arange(h.size + 1))[:, None]

    def run(collapse):
        monkeypatch.setattr(VariableHistory, "COLLAPSE", collapse)
        eng = VariableHistory("III", NU, r, 0.004)
        eng.start(V[0])
        out, lazy = [], 0
        for j, hj in enumerate(h):
            A, B = eng.prepare(hj)
            out.append(np.concatenate([A, B]))
            eng.commit(V[j + 1])
            lazy = max(lazy, int(eng.lazy.sum()))
            if j == 45:
                state = eng.get_state()
        return np.array(out), lazy, state

    fast, lazy, s_fast = run(True)
    walk, none, s_walk = run(False)
    assert none == 0 and lazy > 300            # most modes collapse in the long steps
    assert np.max(np.abs(fast - walk), axis=1).max() <= 1e-13 * np.abs(walk).max()
    for key in ("SR", "SI"):
        assert np.max(np.abs(s_fast[key] - s_walk[key])) <= 1e-13 * np.abs(s_walk[key]).max(), key
