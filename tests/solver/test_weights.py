"""Discrete convolution weights of section 3.1, eqs. (44)-(48)."""
import math
import warnings

import numpy as np
import pytest
from scipy import integrate

from cracklab import kernels as K
from cracklab.elastic.weights import FORMULATIONS, RULES, convolution_weights, halves_last

NU = 0.25
KERNELS = ("I", "II", "III")


def kfun(kernel, formulation, nu=NU):
    if formulation == "displacement":
        return lambda T: np.asarray(K.C(kernel, T, nu), dtype=float)
    return lambda T: np.asarray(K.Z(kernel, T, nu), dtype=float)


def test_constants_and_halving():
    assert set(RULES) == {"discretized", "trapezoid", "simpson", "exact"}
    assert set(FORMULATIONS) == {"displacement", "velocity"}
    assert halves_last("discretized") is True
    for r in ("trapezoid", "simpson", "exact"):
        assert halves_last(r) is False
    with pytest.raises(ValueError, match="rule"):
        halves_last("midpoint")


def test_broadcast_shapes():
    g = np.array([0.1, 0.5, 1.0])[:, None]
    j = np.arange(7)
    for rule in RULES:
        w = convolution_weights("I", g, j, rule=rule)
        assert w.shape == (3, 7) and w.dtype == np.float64
    w = convolution_weights("II", 0.3, 4, rule="trapezoid")
    assert np.ndim(w) == 0
    assert convolution_weights("III", 0.3, np.arange(5)).shape == (5,)


@pytest.mark.parametrize("formulation", FORMULATIONS)
@pytest.mark.parametrize("kernel", KERNELS)
def test_discretized_and_trapezoid(kernel, formulation):
    f = kfun(kernel, formulation)
    g, j = 0.37, np.arange(60)
    disc = convolution_weights(kernel, g, j, rule="discretized", formulation=formulation)
    trap = convolution_weights(kernel, g, j, rule="trapezoid", formulation=formulation)
    K0 = K.C0(kernel, NU) if formulation == "displacement" else K.static_integral(kernel, NU)
    # eq. (45): xk_0 = K(0)/2, xk_j = K(gamma j)
    assert disc[0] == pytest.approx(K0 / 2, rel=1e-13)
    np.testing.assert_allclose(disc[1:], f(g * j[1:]), rtol=1e-14, atol=1e-15)
    # eq. (46): mean of the neighbouring samples
    np.testing.assert_allclose(trap, 0.5 * (f(g * j) + f(g * (j + 1))), rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(trap[1:-1], 0.5 * (disc[1:-1] + disc[2:]), rtol=1e-13, atol=1e-15)
    assert trap[0] == pytest.approx(disc[0] + 0.5 * disc[1], rel=1e-13)


@pytest.mark.parametrize("formulation", FORMULATIONS)
@pytest.mark.parametrize("kernel", KERNELS)
def test_exact_is_the_cell_mean(kernel, formulation):
    """Exact weights against adaptive quadrature of K over each cell, and telescoping sums."""
    f = kfun(kernel, formulation)
    g = 0.8
    j = np.array([0, 1, 2, 5, 17, 40, 100])
    w = convolution_weights(kernel, g, j, rule="exact", formulation=formulation)
    for jj, wj in zip(j, w):
        ref = integrate.quad(lambda T: float(f(T)), g * jj, g * (jj + 1), epsabs=1e-14, epsrel=1e-13)[0] / g
        assert wj == pytest.approx(ref, abs=1e-11)
    n = 500
    wall = convolution_weights(kernel, g, np.arange(n), rule="exact", formulation=formulation)
    anti = K.integral if formulation == "displacement" else K.Z_integral
    assert g * wall.sum() == pytest.approx(float(anti(kernel, g * n, NU)), abs=1e-10)


@pytest.mark.parametrize("formulation", FORMULATIONS)
@pytest.mark.parametrize("kernel", KERNELS)
def test_simpson(kernel, formulation):
    f = kfun(kernel, formulation)
    g, j = 0.9, np.arange(0, 80, 7)
    s2 = convolution_weights(kernel, g, j, rule="simpson", formulation=formulation, simpson_n=2)
    classic = (f(g * j) + 4 * f(g * (j + 0.5)) + f(g * (j + 1))) / 6
    np.testing.assert_allclose(s2, classic, rtol=1e-13, atol=1e-15)
    ex = convolution_weights(kernel, g, j, rule="exact", formulation=formulation)
    errs = [np.max(np.abs(convolution_weights(kernel, g, j, rule="simpson", formulation=formulation,
                                              simpson_n=n) - ex)) for n in (4, 8, 16, 64)]
    assert errs[-1] < 1e-9
    # fourth-order convergence in 1/N
    assert 10 < errs[0] / errs[1] < 22 and 10 < errs[1] / errs[2] < 22, errs


@pytest.mark.parametrize("kernel", KERNELS)
def test_displacement_sums_reach_static_integral(kernel):
    """gamma sum_j xk_j -> int_0^inf C = 1/(1-nu) (I, II) or 1 (III).

    The partial sums oscillate like T^-1/2; a smooth cutoff exp(-(gamma j/X)^8)
    removes the tail.  The kernels are even in T and band-limited (frequencies
    1 and a), so for gamma < pi/a even the trapezoid-type sums are exact.
    """
    S = 1.0 if kernel == "III" else 1.0 / (1.0 - NU)
    X = 150.0
    for g, rule in ((0.5, "exact"), (1.0, "simpson"), (0.1, "trapezoid"), (1.0, "trapezoid"),
                    (0.7, "discretized")):
        j = np.arange(int(2 * X / g) + 1)
        w = convolution_weights(kernel, g, j, rule=rule)
        Tm = g * (j + 0.5)
        total = g * np.sum(w * np.exp(-((Tm / X) ** 8)))
        assert total == pytest.approx(S, abs=1e-9), (rule, g, total - S)
    # the unsmoothed partial sums approach it too, within the T^-1/2 tail
    g = 0.5
    j = np.arange(40000)
    part = g * np.cumsum(convolution_weights(kernel, g, j, rule="exact"))
    tail = part[-2000:] - S
    assert np.max(np.abs(tail)) < 3.0 / math.sqrt(g * 38000)
    assert abs(np.mean(tail)) < 1e-3


@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_gamma_zero_and_tiny(formulation):
    j = np.arange(6)
    for kernel in KERNELS:
        K0 = K.C0(kernel, NU) if formulation == "displacement" else K.static_integral(kernel, NU)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            for rule in RULES:
                w = convolution_weights(kernel, np.array([0.0, 0.0]), j[:, None], rule=rule,
                                        formulation=formulation)
                expect = np.full((6, 2), K0)
                if rule == "discretized":
                    expect[0] = K0 / 2
                np.testing.assert_allclose(w, expect, rtol=1e-13)
        # tiny gamma: exact weights stay accurate (no 1/gamma round-off)
        g = 1e-6
        w = convolution_weights(kernel, g, j, rule="exact", formulation=formulation)
        s = convolution_weights(kernel, g, j, rule="simpson", simpson_n=8, formulation=formulation)
        np.testing.assert_allclose(w, s, rtol=1e-12)
        g = 2e-3  # just above the switch to the difference of antiderivatives
        w = convolution_weights(kernel, g, j, rule="exact", formulation=formulation)
        s = convolution_weights(kernel, g, j, rule="simpson", simpson_n=8, formulation=formulation)
        np.testing.assert_allclose(w, s, rtol=1e-10, atol=1e-10)


def test_nu_is_used():
    a = convolution_weights("I", 0.5, np.arange(5), nu=0.2)
    b = convolution_weights("I", 0.5, np.arange(5), nu=0.35)
    assert np.max(np.abs(a - b)) > 1e-2
    np.testing.assert_array_equal(convolution_weights("III", 0.5, np.arange(5), nu=0.2),
                                  convolution_weights("III", 0.5, np.arange(5), nu=0.35))


def test_validation():
    with pytest.raises(ValueError, match=r"kernel.*\('I', 'II', 'III', 'H11', 'H22', 'H12'\)"):
        convolution_weights("IV", 0.1, 1)
    with pytest.raises(ValueError, match=r"rule.*discretized.*trapezoid.*simpson.*exact"):
        convolution_weights("I", 0.1, 1, rule="midpoint")
    with pytest.raises(ValueError, match=r"formulation.*displacement.*velocity"):
        convolution_weights("I", 0.1, 1, formulation="stress")
    for n in (3, 0, 2.0, True):
        with pytest.raises(ValueError, match="simpson_n"):
            convolution_weights("I", 0.1, 1, rule="simpson", simpson_n=n)
    with pytest.raises(ValueError, match="gamma"):
        convolution_weights("I", -0.1, 1)
    with pytest.raises(ValueError, match="gamma"):
        convolution_weights("I", np.nan, 1)
    with pytest.raises(ValueError, match="j"):
        convolution_weights("I", 0.1, -1)
    with pytest.raises(ValueError, match="j"):
        convolution_weights("I", 0.1, 1.5)
    with pytest.raises(ValueError):
        convolution_weights("I", 0.1, 1, nu=0.5)
    # float j with integral values is accepted
    assert convolution_weights("I", 0.1, 2.0) == convolution_weights("I", 0.1, 2)
