"""Kernels of eq. (26), their Laplace transforms (Appendix A, ERRATA 1) and Z = int_T^inf C."""
import math

import mpmath as mp
import numpy as np
import pytest
from scipy import integrate
from scipy import special as sp
from verification import check

from cracklab import kernels as K

NUS = (0.2, 0.25, 0.35)
KERNELS = ("I", "II", "III")


def a_of(nu):
    return math.sqrt(2 * (1 - nu) / (1 - 2 * nu))


def smooth_integral(f, X, p=8):
    """int_0^inf f(T) exp(-(T/X)^p) dT by panel Gauss-Legendre on [0, 2X].

    The cutoff has vanishing derivatives of order 1..p-1 at 0, so for the
    oscillatory, slowly decaying kernels it reproduces the Abel (= improper)
    integral up to O(X^-p) plus the exponentially small Fourier tail.
    """
    edges = np.linspace(0.0, 2.0 * X, int(8 * X) + 1)
    xg, wg = np.polynomial.legendre.leggauss(20)
    lo, hi = edges[:-1, None], edges[1:, None]
    T = 0.5 * (lo + hi) + 0.5 * (hi - lo) * xg
    return float(np.sum(0.5 * (hi - lo) * wg * f(T) * np.exp(-((T / X) ** p))))


def deriv(f, T, h=1e-2):
    """Fourth-order central difference."""
    return (8 * (f(T + h) - f(T - h)) - (f(T + 2 * h) - f(T - 2 * h))) / (12 * h)


def numerical_laplace(f, s):
    """int_0^inf exp(-sT) f(T) dT: 24-point Gauss-Legendre on panels of width 1/2 up to
    exp(-Re(s) T) < 1e-18 (the integrand is smooth; complex s allowed)."""
    Tmax = 42.0 / s.real + 10.0
    edges = np.arange(0.0, Tmax + 0.5, 0.5)
    xg, wg = np.polynomial.legendre.leggauss(24)
    lo, hi = edges[:-1, None], edges[1:, None]
    T = 0.5 * (lo + hi) + 0.5 * (hi - lo) * xg
    return complex(np.sum(0.5 * (hi - lo) * wg * np.exp(-s * T) * f(T)))


def laplace_mp(kernel, s, nu):
    """ERRATA section 1 formulas, evaluated directly in 50-digit arithmetic."""
    with mp.workdps(50):
        a = mp.sqrt(2 * (1 - mp.mpf(nu)) / (1 - 2 * mp.mpf(nu)))
        s = mp.mpc(s)
        als, ald = mp.sqrt(1 + s**2), mp.sqrt(1 + s**2 / a**2)
        R = 4 * ald * als - (2 + s**2) ** 2
        if kernel == "I":
            v = -R / (s**2 * ald) - a * s
        elif kernel == "II":
            v = -R / (s**2 * als) - s
        else:
            v = als - s
        return complex(v)


# ----------------------------------------------------------------------------- basics
def test_wave_speed_ratio():
    assert K.wave_speed_ratio(0.25) == pytest.approx(math.sqrt(3.0), rel=1e-15)
    assert K.wave_speed_ratio(0.0) == pytest.approx(math.sqrt(2.0), rel=1e-15)
    for bad in (0.5, 0.7, -1.0):
        with pytest.raises(ValueError):
            K.wave_speed_ratio(bad)


@pytest.mark.parametrize("nu", NUS)
def test_C_at_zero_is_exact(nu):
    a = a_of(nu)
    expect = {"I": 4 * a - 4 - a**3 / 2, "II": 3.5 - 4 / a, "III": 0.5}
    for k in KERNELS:
        assert K.C0(k, nu) == pytest.approx(expect[k], rel=1e-14, abs=1e-15)
        # pytest.approx(rel=1e-13, abs=1e-14): abs(C(0) - expect) <= 1e-13 max(abs(expect), 0.1)
        err = abs(float(K.C(k, 0.0, nu)) - expect[k]) / max(abs(expect[k]), 0.1)
        check("kernel-C0", err, f"kernel {k}, nu = {nu}")
        # continuity at T -> 0+ (J1(x)/x must be evaluated safely)
        assert float(K.C(k, 1e-7, nu)) == pytest.approx(expect[k], abs=1e-6)
    assert float(K.C_III(0.0)) == 0.5 and np.isfinite(K.C_III(np.array([0.0, 1e-300]))).all()


def test_kernels_vectorised_and_dispatch():
    T = np.linspace(0.0, 50.0, 11)
    for k in KERNELS:
        v = K.C(k, T, 0.25)
        assert v.shape == T.shape and v.dtype == np.float64
        assert np.isscalar(K.C(k, 1.0, 0.25)) or np.ndim(K.C(k, 1.0, 0.25)) == 0
        assert K.Z(k, T.reshape(1, -1), 0.25).shape == (1, 11)
    np.testing.assert_array_equal(K.C("I", T, 0.3), K.C_I(T, 0.3))
    np.testing.assert_array_equal(K.C("II", T, 0.3), K.C_II(T, 0.3))
    np.testing.assert_array_equal(K.C("III", T, 0.3), K.C_III(T))
    with pytest.raises(ValueError, match="kernel"):
        K.C("IV", T, 0.25)
    with pytest.raises(ValueError):
        K.C("I", -1.0, 0.25)


def test_kernels_match_printed_form():
    """The rewritten closed forms equal eq. (26) (C_II as corrected) built from W, J0, J1."""
    T = np.array([0.1, 0.7, 2.0, 5.5, 13.0, 30.0])
    for nu in NUS:
        a = a_of(nu)
        W1, Wa = K.W(T), K.W(a * T)
        c1 = (a**3 * sp.j1(a * T) / (a * T) + 4 * T * (W1 - Wa) + (4 * a - a**3) * sp.j0(a * T)
              - 4 * sp.j0(T))
        c2 = sp.j1(T) / T + 4 * T * (Wa - W1) - (4 / a) * sp.j0(a * T) + 3 * sp.j0(T)
        np.testing.assert_allclose(K.C_I(T, nu), c1, rtol=1e-11, atol=1e-12)
        np.testing.assert_allclose(K.C_II(T, nu), c2, rtol=1e-11, atol=1e-12)
        np.testing.assert_allclose(K.C_III(T), sp.j1(T) / T, rtol=1e-14)


# ----------------------------------------------------------------------------- W
def W_mp(T):
    """W = 1 - int_0^T J0 + J1(T), with int_0^T J0 = T 1F2(1/2; 1, 3/2; -T^2/4) (40 digits)."""
    with mp.workdps(40):
        x = mp.mpf(T)
        return float(1 - x * mp.hyp1f2(0.5, 1, 1.5, -x * x / 4) + mp.besselj(1, x))


def test_W_against_mpmath():
    assert float(K.W(0.0)) == 1.0
    T = np.array([1e-3, 0.5, 3.0, 9.0, 17.0, 20.0, 25.0, 31.0, 37.99, 38.01, 45.0, 100.0,
                  1e3, 1e4, 1e5])
    got = K.W(T)
    ref = np.array([W_mp(t) for t in T])
    envelope = np.minimum(1.0, np.sqrt(2 / (np.pi * T)) / T)
    err = np.abs(got - ref)
    # absolute accuracy, and relative to the T^-3/2 envelope of the oscillating tail
    assert np.all(err <= 1e-12 * envelope + 1e-16), (T, err / envelope)
    assert np.max(err) < 1e-14


# ----------------------------------------------------------------------------- Laplace
@pytest.mark.parametrize("nu", NUS)
@pytest.mark.parametrize("kernel", KERNELS)
def test_laplace_matches_numerical_transform(kernel, nu):
    """Numerical transform of the time-domain kernel vs the exact transform (1e-9)."""
    f = lambda T: K.C(kernel, T, nu)  # noqa: E731
    for s in (0.5, 1.0, 2.0, 5.0, 1.0 + 2.0j):
        num = numerical_laplace(f, complex(s))
        exact = complex(K.laplace(kernel, np.asarray(s), nu))
        check("kernel-laplace", abs(num - exact) / max(1.0, abs(exact)), f"{(s, num, exact)}")


def test_printed_C_II_fails_the_transform():
    """The seed's -4 (c_d/c_s) J0(aT) in C_II is inconsistent with eq. (23); -(4/a) J0(aT) is right."""
    nu = 0.25
    a = a_of(nu)

    def printed(T):
        return (sp.j1(T) / T + 4 * T * (K.W(a * T) - K.W(T)) - 4 * a * sp.j0(a * T) + 3 * sp.j0(T))

    s = 1.0
    num = numerical_laplace(printed, complex(s)).real
    assert abs(num - K.laplace("II", s, nu)) > 0.1


@pytest.mark.parametrize("nu", (0.2, 0.25, 0.35, 0.45))
def test_laplace_no_cancellation(nu):
    """Small, large and complex s against the direct formula in 50 digits."""
    svals = [1e-6, 1e-3, 0.1, 0.999, 1.0, 1.001, 3.0, 1e2, 1e4, 1e6,
             0.3 + 0.4j, 1 + 1j, 0.01 + 3j, 5 - 20j, 0.5 + 0.99j, 1e-3 + 1e3j]
    for k in KERNELS:
        for s in svals:
            got = complex(K.laplace(k, np.asarray(s, dtype=complex), nu))
            ref = laplace_mp(k, s, nu)
            assert abs(got - ref) <= 1e-11 * abs(ref), (k, s, got, ref)
    # real input gives real output, arrays broadcast
    out = K.laplace("I", np.array([0.5, 2.0]), nu)
    assert out.dtype == np.float64 and out.shape == (2,)


@pytest.mark.parametrize("nu", NUS)
def test_laplace_at_zero_is_static_integral(nu):
    for k in KERNELS:
        expect = 1.0 if k == "III" else 1.0 / (1.0 - nu)
        assert float(K.laplace(k, 0.0, nu)) == pytest.approx(expect, rel=1e-14)


@pytest.mark.parametrize("nu", NUS)
def test_impedance(nu):
    a = a_of(nu)
    s = np.array([0.1, 1.0, 4.0, 0.5 + 2j])
    als, ald = np.sqrt(1 + s**2), np.sqrt(1 + s**2 / a**2)
    R = 4 * ald * als - (2 + s**2) ** 2
    np.testing.assert_allclose(K.impedance("I", s, nu), -R / (s**2 * ald), rtol=1e-12)
    np.testing.assert_allclose(K.impedance("II", s, nu), -R / (s**2 * als), rtol=1e-12)
    np.testing.assert_allclose(K.impedance("III", s, nu), als, rtol=1e-13)
    assert K.eta_hat("I", nu) == pytest.approx(a) and K.eta_hat("II", nu) == K.eta_hat("III", nu) == 1.0
    # instantaneous response: M(s) ~ eta_hat s + C(0)/s
    big = 1e4
    for k in KERNELS:
        M = float(K.impedance(k, big, nu))
        assert (M - K.eta_hat(k, nu) * big) * big == pytest.approx(K.C0(k, nu), rel=1e-5, abs=1e-9)
    # the Rayleigh pole of the modal response: M_I(i s_R) = M_II(i s_R) = 0
    x = 0.9194017**2 if nu == 0.25 else None
    if x is not None:
        for k in ("I", "II"):
            M = complex(K.impedance(k, np.asarray(1j * math.sqrt(x)), nu))
            assert abs(M) < 1e-5


# ----------------------------------------------------------------------------- static integral, Z
@pytest.mark.parametrize("nu", NUS)
def test_static_integrals(nu):
    for k in KERNELS:
        expect = 1.0 if k == "III" else 1.0 / (1.0 - nu)
        assert K.static_integral(k, nu) == pytest.approx(expect, rel=1e-14)
        assert float(K.Z(k, 0.0, nu)) == pytest.approx(expect, rel=1e-13)
        num = smooth_integral(lambda T: K.C(k, T, nu), 100.0)
        check("kernel-static-integral", abs(num - expect), f"{(k, num)}")


@pytest.mark.parametrize("nu", NUS)
def test_Z_is_the_tail_integral(nu):
    T = np.array([0.05, 0.4, 1.0, 3.3, 9.0, 20.0, 37.9, 38.1, 60.0, 250.0, 3000.0])
    for k in KERNELS:
        # d/dT Z = -C
        dZ = deriv(lambda x: K.Z(k, x, nu), T)
        np.testing.assert_allclose(dZ, -K.C(k, T, nu), atol=2e-8)
        # Z(T) = int_0^inf C - int_0^T C, the latter by adaptive quadrature
        S = 1.0 if k == "III" else 1.0 / (1.0 - nu)
        for t in (0.5, 4.0, 27.0):
            part = integrate.quad(lambda x: float(K.C(k, x, nu)), 0.0, t, limit=400,
                                  epsabs=1e-13, epsrel=1e-13)[0]
            assert float(K.Z(k, t, nu)) == pytest.approx(S - part, abs=1e-11)
            assert float(K.integral(k, t, nu)) == pytest.approx(part, abs=1e-11)
        # Z -> 0 like T^-1/2
        Tl = np.linspace(1e4, 1e4 + 50, 400)
        assert np.max(np.abs(K.Z(k, Tl, nu))) < 5.0 / math.sqrt(1e4)
        Tl = np.linspace(1e5, 1e5 + 50, 400)
        assert np.max(np.abs(K.Z(k, Tl, nu))) < 5.0 / math.sqrt(1e5)


@pytest.mark.parametrize("nu", NUS)
def test_Z_integral(nu):
    """int_0^T Z: derivative, value at 0, and limit int_0^inf T C(T) dT = -L'(0) (a, 1, 1)."""
    a = a_of(nu)
    T = np.array([0.05, 1.0, 7.0, 37.9, 38.1, 200.0])
    for k in KERNELS:
        assert float(K.Z_integral(k, 0.0, nu)) == 0.0
        d = deriv(lambda x: K.Z_integral(k, x, nu), T)
        np.testing.assert_allclose(d, K.Z(k, T, nu), atol=2e-8)
        expect = a if k == "I" else 1.0
        dL = (K.laplace(k, 1e-4, nu) - K.laplace(k, -1e-4, nu)) / 2e-4
        assert -dL == pytest.approx(expect, rel=1e-7)
        num = smooth_integral(lambda x: K.Z(k, x, nu), 100.0)
        assert num == pytest.approx(expect, abs=1e-8)
