"""Single-mode (modal) analysis of section 3.1: accuracy, convergence, scheme behaviour."""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.special as sp
from verification import check

from cracklab import kernels

from cracklab.analysis import exact
from cracklab.errors import InputError
from cracklab.analysis.modal import (
    SCHEMES,
    implicit_coefficient,
    long_time_amplitude,
    long_time_period,
    modal_response,
    precision_factor,
)

NU = 0.25
S_R = 0.9194017  # c_R / c_s at nu = 1/4 (ERRATA section 3)
BEST = [("displacement", "trapezoid", "explicit"), ("velocity", "discretized", "semi-implicit")]


def run(mode, gamma, T_end, scheme=("displacement", "trapezoid", "explicit"), **kw):
    f, c, i = scheme
    return modal_response(mode, gamma=gamma, T_end=T_end, nu=NU, formulation=f, convolution=c,
                          integration=i, **kw)


# ----------------------------------------------------------------------------- output form
def test_output_form():
    r = run("I", 0.3, 1.0)
    assert r.name == "r" and r.dims == ("T",)
    # N = ceil(T_end / gamma) = 4 steps, T = n gamma
    np.testing.assert_allclose(r["T"].values, 0.3 * np.arange(5))
    assert r.values[0] == 1.0
    assert r.attrs["mode"] == "I" and r.attrs["gamma"] == 0.3 and r.attrs["nu"] == NU
    assert (r.attrs["formulation"], r.attrs["convolution"], r.attrs["integration"]) == (
        "displacement", "trapezoid", "explicit")
    assert r.attrs["units"] == "1" and r.attrs["long_name"]
    assert r["T"].attrs["long_name"] == "q c_s t"
    # exact multiples do not gain a spurious step from rounding
    assert run("III", 0.1, 0.3).sizes["T"] == 4


# ----------------------------------------------------------------------------- 1. mode III
def test_mode_III_matches_J0():
    r = run("III", 0.05, 30.0)
    T = r["T"].values
    err = np.max(np.abs(r.values - sp.j0(T)))
    # measured 0.0145 (first order: about 0.3 gamma)
    check("modal-III-J0", err)


# ----------------------------------------------------------------------------- 2. mode I long time
def test_mode_I_long_time_form():
    A_exact = exact.modal_long_time_amplitude(NU)
    assert A_exact == pytest.approx(0.5844, abs=1e-4)
    assert long_time_amplitude("I", NU) == pytest.approx(A_exact, rel=1e-6)
    assert long_time_period("I", NU) == pytest.approx(2 * math.pi / S_R, rel=1e-6)

    r = run("I", 0.05, 200.0)
    T, y = r["T"].values, r.values
    m = (T >= 150.0) & (T <= 200.0)
    M = np.column_stack([np.cos(S_R * T[m]), np.sin(S_R * T[m])])
    (c, s), *_ = np.linalg.lstsq(M, y[m], rcond=None)
    amp = math.hypot(c, s)
    check("modal-I-amplitude", abs(amp / 0.5844 - 1), f"amplitude {amp}")
    # mostly sin(s_R T), as in (B.5)
    assert s > 0 and abs(c) < 0.1 * s

    # period from zero crossings (linear interpolation between samples)
    Tw, yw = T[m], y[m]
    k = np.nonzero(np.sign(yw[:-1]) * np.sign(yw[1:]) < 0)[0]
    tz = Tw[k] - yw[k] * (Tw[k + 1] - Tw[k]) / (yw[k + 1] - yw[k])
    assert tz.size >= 10
    half = np.polyfit(np.arange(tz.size), tz, 1)[0]
    check("modal-I-period", abs(2 * half / (2 * math.pi / S_R) - 1), f"period {2 * half}")


def test_long_time_amplitude_from_impedance():
    """A = -2 eta / (dM(iy)/dy) at y = s_R, with M = kernels.impedance (Appendix B residue)."""
    h = 1e-6
    for mode in ("I", "II"):
        eta = kernels.eta_hat(mode, NU)
        dM = (kernels.impedance(mode, 1j * (S_R + h), NU) - kernels.impedance(mode, 1j * (S_R - h), NU)) / (2 * h)
        assert abs(dM.imag) < 1e-6 * abs(dM.real)
        assert long_time_amplitude(mode, NU) == pytest.approx(-2 * eta / dM.real, rel=1e-5)
    assert long_time_amplitude("II", NU) == pytest.approx(0.1566, abs=2e-4)


def test_mode_II_long_time_amplitude():
    """The mode II Rayleigh residue against a fine numerical run."""
    A = long_time_amplitude("II", NU)
    r = run("II", 0.025, 120.0)
    T, y = r["T"].values, r.values
    m = (T >= 80.0) & (T <= 120.0)
    M = np.column_stack([np.cos(S_R * T[m]), np.sin(S_R * T[m])])
    (c, s), *_ = np.linalg.lstsq(M, y[m], rcond=None)
    assert math.hypot(c, s) == pytest.approx(A, rel=0.03)
    assert s > 0 and abs(c) < 0.1 * s


# ----------------------------------------------------------------------------- 3. convergence
GAMMAS = (0.2, 0.1, 0.05, 0.025)
T_GRID = 0.2 * np.arange(1, 51)  # (0, 10], multiples of the largest gamma


@pytest.fixture(scope="module")
def exact_on_grid():
    return {
        "I": np.asarray(exact.modal_exact("I", T_GRID, NU), dtype=float),
        "II": np.asarray(exact.modal_exact("II", T_GRID, NU), dtype=float),
        "III": sp.j0(T_GRID),
    }


def test_exact_reference_sane(exact_on_grid):
    np.testing.assert_allclose(exact_on_grid["III"][:5], np.asarray(exact.modal_exact("III", T_GRID[:5], NU)),
                               atol=1e-8)


@pytest.mark.parametrize("mode", ["I", "II", "III"])
def test_first_order_convergence(mode, exact_on_grid):
    ref = exact_on_grid[mode]
    errors = []
    for g in GAMMAS:
        r = run(mode, g, 10.0)
        stride = round(0.2 / g)
        vals = r.values[stride::stride][: T_GRID.size]
        np.testing.assert_allclose(r["T"].values[stride::stride][: T_GRID.size], T_GRID, atol=1e-9)
        errors.append(np.max(np.abs(vals - ref)))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    # ratios in [1.7, 2.3]: first order
    check(f"modal-convergence-{mode}", np.max(np.abs(ratios - 2.0)), f"errors {errors}, ratios {ratios}")


# ----------------------------------------------------------------------------- 4. the 12 schemes
def test_twelve_schemes_run():
    assert len(SCHEMES) == 12 and len(set(SCHEMES)) == 12
    for scheme in SCHEMES:
        for mode in ("I", "II", "III"):
            r = run(mode, 0.5, 20.0, scheme)
            assert r.sizes["T"] == 41
            assert np.all(np.isfinite(r.values)), (mode, scheme)
            assert r.values[0] == 1.0
            assert (r.attrs["formulation"], r.attrs["convolution"], r.attrs["integration"]) == scheme


@pytest.mark.parametrize("mode", ["I", "II", "III"])
def test_velocity_discretized_semi_implicit_is_explicit(mode):
    for scheme in SCHEMES:
        f, c, i = scheme
        B = implicit_coefficient(mode, gamma=0.5, nu=NU, formulation=f, convolution=c, integration=i)
        if scheme == ("velocity", "discretized", "semi-implicit"):
            assert abs(B) < 1e-12, B  # the r_n terms cancel
        elif f == "displacement" and i == "explicit":
            assert B == 0.0
        else:
            assert abs(B) > 1e-3, (scheme, B)


def test_velocity_discretized_semi_implicit_cancelled_form():
    """With the r_n terms cancelled, (43) + (45) + (50) is
    r_n = 1 - (gamma/eta) sum_j w_j (Z(0) - Z(j gamma)) r_{n-j}, trapezoid weights w_j, j = 1..n."""
    gamma, N = 0.4, 60
    a = kernels.wave_speed_ratio(NU)
    for mode, eta in (("I", a), ("II", 1.0), ("III", 1.0)):
        z = np.asarray(kernels.Z(mode, gamma * np.arange(N + 1), NU), dtype=float)
        I = kernels.static_integral(mode, NU) - z
        r = np.empty(N + 1)
        r[0] = 1.0
        for n in range(1, N + 1):
            w = I[1:n + 1].copy()
            w[-1] *= 0.5
            r[n] = 1.0 - gamma / eta * np.dot(w, r[n - 1::-1])
        got = run(mode, gamma, gamma * N, ("velocity", "discretized", "semi-implicit")).values
        np.testing.assert_allclose(got, r, atol=1e-10, rtol=0)


def test_best_schemes_agree_at_small_gamma():
    a = run("I", 0.05, 30.0, BEST[0]).values
    b = run("I", 0.05, 30.0, BEST[1]).values
    # measured: max difference 0.014 (both first order, different O(gamma) errors)
    assert np.max(np.abs(a - b)) < 0.02


def test_stability_at_gamma_2_3():
    for scheme in BEST:
        r = run("I", 2.3, 500.0, scheme)
        y = np.abs(r.values)
        assert np.all(np.isfinite(y)) and y.max() <= 1.0 + 1e-12, scheme
        T = r["T"].values
        assert y[T > 400].max() < 0.5 * y[(T > 50) & (T < 150)].max(), scheme  # decays
    # displacement + discretized kernel + explicit, unstable in the paper, blows up
    r = run("I", 2.3, 500.0, ("displacement", "discretized", "explicit"))
    y = np.abs(r.values)
    assert not np.all(np.isfinite(y)) or y[r["T"].values > 400].max() > 1e3


# ----------------------------------------------------------------------------- precision factor
def test_precision_factor():
    r = run("I", 0.05, 70.0)
    pf = precision_factor(r, NU)
    assert pf == pytest.approx(1.0, abs=0.03)
    assert precision_factor(r, NU, method="fit") == pytest.approx(pf, abs=0.02)
    r3 = run("III", 0.05, 65.0)
    assert precision_factor(r3) == pytest.approx(1.0, abs=0.03)
    # artificial damping of the explicit scheme at larger gamma (Fig. 5, 6)
    assert precision_factor(run("I", 1.0, 70.0)) < 0.8
    with pytest.raises(InputError) as e:
        precision_factor(run("I", 0.5, 20.0))
    assert e.value.field == "period"


# ----------------------------------------------------------------------------- 5. validation
@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(mode="IV"), "mode"),
        (dict(mode=1), "mode"),
        (dict(gamma=0.0), "gamma"),
        (dict(gamma=-0.1), "gamma"),
        (dict(gamma=float("nan")), "gamma"),
        (dict(gamma="x"), "gamma"),
        (dict(T_end=0.0), "T_end"),
        (dict(T_end=float("inf")), "T_end"),
        (dict(T_end=1e9), "T_end"),
        (dict(nu=0.5), "nu"),
        (dict(nu=-1.0), "nu"),
        (dict(formulation="traction"), "formulation"),
        (dict(convolution="midpoint"), "convolution"),
        (dict(integration="implicit"), "integration"),
        (dict(simpson_n=3), "simpson_n"),
        (dict(simpson_n=0), "simpson_n"),
    ],
)
def test_validation(kwargs, field):
    args = dict(mode="I", gamma=0.1, T_end=1.0)
    args.update(kwargs)
    mode = args.pop("mode")
    with pytest.raises(ValueError) as e:
        modal_response(mode, **args)
    assert isinstance(e.value, InputError)
    assert e.value.field == field
    assert field in str(e.value)
    if field in ("mode", "formulation", "convolution", "integration"):
        assert "must be one of" in str(e.value)
    if field == "nu":
        assert "(-1, 0.5)" in str(e.value)


def test_a_grid_scheme_names_its_single_mode_recurrence():
    """scheme_response runs the recurrence a grid scheme declares: the displacement scheme the
    paper's trapezoid/explicit one, the product schemes the product rule's predictor-corrector
    (product2 the same: it changes the law's update, not the linear response)."""
    from cracklab.analysis.modal import scheme_response
    from cracklab.solver.schemes import SCHEMES

    expected = {"displacement": ("displacement", "trapezoid", "explicit"),
                "velocity": ("velocity", "discretized", "semi-implicit"),
                "product": ("velocity", "product", "predictor-corrector"),
                "product2": ("velocity", "product", "predictor-corrector")}
    assert set(expected) == set(SCHEMES)
    for name, (formulation, convolution, integration) in expected.items():
        for scheme in (name, SCHEMES[name]):
            got = scheme_response(scheme, "II", gamma=0.3, T_end=6.0, nu=0.25)
            ref = modal_response("II", gamma=0.3, T_end=6.0, nu=0.25, formulation=formulation,
                                 convolution=convolution, integration=integration)
            np.testing.assert_array_equal(got.values, ref.values)
