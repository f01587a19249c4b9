"""Long-time stability of the single-mode schemes (docs/reference/stability.md, studies/stability_map.py).

The default scheme (displacement, trapezoid pre-integration (46), explicit (37)) lets the
mode II Rayleigh oscillation grow; the product-integration predictor-corrector schemes
(velocity formulation, Z integrated exactly against the interpolated velocity, one
corrector pass of (50)) do not, for modes I, II, III up to gamma = 2.5, and converge to
the exact response at second (piecewise-linear velocity) or fourth (piecewise-cubic)
order.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.special as sp
from scipy import integrate

from cracklab import kernels

from cracklab.analysis import exact
from cracklab.errors import InputError
from cracklab.analysis.modal import (
    STABLE_SCHEME,
    envelope_growth,
    implicit_coefficient,
    long_time_period,
    modal_response,
    product_weights,
)
from cracklab.analysis.modal import product_tables

NU = 0.25
DEFAULT = dict(formulation="displacement", convolution="trapezoid", integration="explicit")
CUBIC_PC = dict(zip(("formulation", "convolution", "integration"), STABLE_SCHEME))
LINEAR_PC = dict(formulation="velocity", convolution="product", integration="predictor-corrector")
#: growth per unit T below which a run counts as not growing: a factor e^0.015 = 1.015
#: over T = 1500.  The measured rates of the stable schemes are negative (< -1e-6).
GROWTH_TOL = 1e-5


def growth(mode, gamma, T_end, scheme, **kw):
    """Slope of ln(max |r| per period) over [T_end/2, T_end]; mode III uses |r| sqrt(T)
    (the rate relative to the T^-1/2 decay of J0).  inf if the run overflowed."""
    return envelope_growth(modal_response(mode, gamma=gamma, T_end=T_end, nu=NU, **scheme, **kw))


# ----------------------------------------------------------------------------- the problem
def test_default_scheme_mode_II_grows():
    """ERRATA section 4: about 9.3e-3 gamma^2 per unit T (2.3e-3 at gamma = 0.5), while the
    mode I oscillation of the same scheme decays."""
    g2 = growth("II", 0.5, 1500.0, DEFAULT)
    assert 1.5e-3 < g2 < 3.5e-3, g2
    assert growth("I", 0.5, 1500.0, DEFAULT) < -1e-3


# ----------------------------------------------------------------------------- the fix
@pytest.mark.parametrize("scheme", [CUBIC_PC, LINEAR_PC], ids=["cubic", "linear"])
@pytest.mark.parametrize("gamma", [0.3, 1.0, 2.0])
@pytest.mark.parametrize("mode", ["I", "II", "III"])
def test_product_predictor_corrector_does_not_grow(mode, gamma, scheme):
    g = growth(mode, gamma, 1500.0, scheme)
    assert g < GROWTH_TOL, g


def test_stable_up_to_gamma_2_5():
    """gamma_M = pi beta sqrt(2) = 2.22 for beta = 0.5 on a square grid; margin to 2.5."""
    for mode in ("I", "II", "III"):
        for scheme in (CUBIC_PC, LINEAR_PC):
            assert growth(mode, 2.5, 1000.0, scheme) < GROWTH_TOL, (mode, scheme)


def test_what_the_corrector_is_for():
    """Without the corrector (predictor only) and with two corrector passes mode II blows up
    at large gamma; Heun on the default scheme does not cure the mode II growth."""
    assert growth("II", 2.0, 500.0, LINEAR_PC | dict(integration="explicit")) > 1e-2
    assert growth("II", 2.0, 500.0, CUBIC_PC | dict(integration="explicit")) > 1e-2
    assert growth("II", 2.2, 500.0, CUBIC_PC, corrector_passes=2) > 1e-2
    heun = dict(DEFAULT, integration="predictor-corrector")
    assert growth("II", 0.5, 1500.0, heun) > 1e-3


# ----------------------------------------------------------------------------- accuracy
GAMMAS = (0.2, 0.1, 0.05)
T_GRID = 0.2 * np.arange(1, 51)


@pytest.fixture(scope="module")
def reference():
    return {m: (sp.j0(T_GRID) if m == "III" else np.asarray(exact.modal_exact(m, T_GRID, NU), dtype=float))
            for m in ("I", "II", "III")}


def errors(mode, scheme, ref):
    out = []
    for g in GAMMAS:
        r = modal_response(mode, gamma=g, T_end=10.0, nu=NU, **scheme)
        s = round(0.2 / g)
        np.testing.assert_allclose(r["T"].values[s::s][:T_GRID.size], T_GRID, atol=1e-9)
        out.append(float(np.max(np.abs(r.values[s::s][:T_GRID.size] - ref))))
    return np.array(out)


@pytest.mark.parametrize("mode", ["I", "II", "III"])
def test_convergence_to_the_exact_response(mode, reference):
    """Max error for T <= 10.  Measured (gamma 0.2, 0.1, 0.05): default 5.7e-2, 2.8e-2, 1.4e-2
    (mode I); linear 2.1e-3, 5.3e-4, 1.3e-4; cubic 8.3e-6, 5.5e-7, 3.5e-8."""
    e_def = errors(mode, DEFAULT, reference[mode])
    e_lin = errors(mode, LINEAR_PC, reference[mode])
    e_cub = errors(mode, CUBIC_PC, reference[mode])
    assert np.all((e_lin[:-1] / e_lin[1:] > 3.6) & (e_lin[:-1] / e_lin[1:] < 4.4)), e_lin  # second order
    assert np.all(e_cub[:-1] / e_cub[1:] > 13.0), e_cub  # fourth order
    assert np.all(e_lin < 0.1 * e_def) and np.all(e_cub < 2e-3 * e_def), (e_def, e_lin, e_cub)


def test_long_time_form():
    """Mode I: amplitude 0.5844 and period 2 pi / s_R (Eq. B.5); mode III: J0."""
    s_R = exact.rayleigh_speed_ratio(NU)
    r = modal_response("I", gamma=0.05, T_end=200.0, nu=NU, **CUBIC_PC)
    T, y = r["T"].values, r.values
    m = (T >= 150.0) & (T <= 200.0)
    M = np.column_stack([np.cos(s_R * T[m]), np.sin(s_R * T[m])])
    (c, s), *_ = np.linalg.lstsq(M, y[m], rcond=None)
    assert math.hypot(c, s) == pytest.approx(0.5844, rel=0.003)  # measured 0.5838
    assert s > 0 and abs(c) < 0.01 * s
    Tw, yw = T[m], y[m]
    k = np.nonzero(np.sign(yw[:-1]) * np.sign(yw[1:]) < 0)[0]
    tz = Tw[k] - yw[k] * (Tw[k + 1] - Tw[k]) / (yw[k + 1] - yw[k])
    period = 2.0 * np.polyfit(np.arange(tz.size), tz, 1)[0]
    assert period == pytest.approx(2 * math.pi / s_R, rel=5e-4)
    r3 = modal_response("III", gamma=0.05, T_end=30.0, nu=NU, **CUBIC_PC)
    assert np.max(np.abs(r3.values - sp.j0(r3["T"].values))) < 1e-6  # measured 7e-8 (default 1.5e-2)
    # and at a coarse step the 50th Rayleigh period keeps most of its amplitude
    r = modal_response("I", gamma=0.3, T_end=50 * long_time_period("I", NU) + 1.0, nu=NU, **CUBIC_PC)
    T, y = r["T"].values, r.values
    w = T >= 49 * long_time_period("I", NU)
    M = np.column_stack([np.cos(s_R * T[w]), np.sin(s_R * T[w])])
    amp = math.hypot(*np.linalg.lstsq(M, y[w], rcond=None)[0])
    assert amp / 0.5844 > 0.98  # measured 0.992 (default 0.735)


# ----------------------------------------------------------------------------- weights
@pytest.mark.parametrize("order", [1, 3])
def test_product_weights_integrate_polynomials_exactly(order):
    """S^v_n is the exact integral of Z against the interpolated velocity, so it is exact for
    velocities of degree <= 1 (order 1) or <= 2 (order 3: cubic cells, quadratic end cells;
    n = 1 is a single linear cell)."""
    gamma, N = 0.7, 12
    W, E, _, _ = product_tables("II", gamma, N, NU, order)
    j = np.arange(N + 1)
    np.testing.assert_allclose(W, product_weights("II", gamma, j, nu=NU, order=order, part="lag"), atol=1e-14)
    for i in range(3):
        np.testing.assert_allclose(E[i], product_weights("II", gamma, j, nu=NU, order=order, part=f"start{i}"),
                                   atol=1e-14)
    for n in (1, 2, 3, 4, 9, 12):
        degree = 1 if (order == 1 or n == 1) else 2
        for p in range(degree + 1):
            v = (np.arange(n + 1) / n) ** p  # r(t) = (t / t_n)^p
            S = np.dot(W[:n + 1], v[::-1]) + sum(E[i, n] * v[i] for i in range(min(2, n) + 1))
            ref, _ = integrate.quad(lambda T: kernels.Z("II", T, NU) * (1 - T / (n * gamma)) ** p,
                                    0.0, n * gamma, epsabs=1e-13, epsrel=1e-12, limit=200)
            assert S == pytest.approx(ref / gamma, abs=1e-11), (n, p)


def test_implicit_coefficients():
    # the predictor alone is explicit; the corrector's coefficient is -(gamma/eta) w^I_0
    # with w^I_0 ~ gamma C(0)/6 (linear): small, applied to the predicted velocity
    assert implicit_coefficient("II", gamma=1.0, nu=NU, **(LINEAR_PC | dict(integration="explicit"))) == 0.0
    B = implicit_coefficient("II", gamma=0.1, nu=NU, **LINEAR_PC)
    assert B == pytest.approx(-0.1 * 0.1 * kernels.C0("II", NU) / 6.0, rel=0.05)
    assert abs(implicit_coefficient("II", gamma=0.1, nu=NU, **CUBIC_PC)) < abs(B)


def test_validation():
    with pytest.raises(InputError) as e:
        modal_response("I", gamma=0.1, T_end=1.0, formulation="displacement", convolution="product")
    assert e.value.field == "convolution"
    for bad in (0, 1.5, True, "1"):
        with pytest.raises(InputError) as e:
            modal_response("I", gamma=0.1, T_end=1.0, corrector_passes=bad, **CUBIC_PC)
        assert e.value.field == "corrector_passes"
    r = modal_response("II", gamma=0.5, T_end=5.0, **CUBIC_PC)
    assert r.attrs["convolution"] == "product-cubic" and r.attrs["corrector_passes"] == 1
    assert r.values[0] == 1.0 and np.all(np.isfinite(r.values))
