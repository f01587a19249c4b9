"""Exact and reference solutions: Rayleigh pole, modal r(T), Pekeris/Lamb, static cracks, Kostrov."""
import math

import mpmath as mp
import numpy as np
import pytest
from scipy import integrate, linalg
from scipy import special as sp

from cracklab.analysis import exact as E
from cracklab import kernels as K

NUS = (0.2, 0.25, 0.35)
SQ3 = math.sqrt(3.0)


# ----------------------------------------------------------------------------- Rayleigh
def test_rayleigh_speed():
    assert E.rayleigh_speed_ratio(0.25) == pytest.approx(0.9194017, abs=1e-7)
    # nu = 1/4: s_R^2 = 2 - 2/sqrt3 and the other roots 4, 2 + 2/sqrt3 (Appendix B)
    assert E.rayleigh_speed_ratio(0.25) ** 2 == pytest.approx(2 - 2 / SQ3, rel=1e-14)
    xr, x1, x2 = E.rayleigh_roots(0.25)
    assert sorted([x1.real, x2.real]) == pytest.approx([2 + 2 / SQ3, 4.0], rel=1e-12)
    for nu in (0.0, 0.2, 0.3, 0.35, 0.45):
        a = K.wave_speed_ratio(nu)
        x = E.rayleigh_speed_ratio(nu) ** 2
        assert 0.7 < x < 1.0
        assert (2 - x) ** 2 == pytest.approx(4 * math.sqrt(1 - x) * math.sqrt(1 - x / a**2), abs=1e-13)
    # c_R increases with nu
    assert E.rayleigh_speed_ratio(0.2) < E.rayleigh_speed_ratio(0.35)


@pytest.mark.parametrize("nu", NUS)
def test_long_time_amplitude_three_ways(nu):
    A = E.modal_long_time_amplitude(nu)
    # the construction of Appendix B, f = (c_d/c_R) G(i s_R)
    assert A == pytest.approx(E.modal_long_time_amplitude_G(nu), rel=1e-12)
    # residue of r_hat = a / M_I at i s_R, by a numerical limit on the numpy impedance
    sR = E.rayleigh_speed_ratio(nu)
    a = K.wave_speed_ratio(nu)
    eps = 1e-6
    rho = eps * a / complex(K.impedance("I", np.asarray(1j * sR + eps), nu))
    assert abs(rho.real) < 1e-5
    assert -2 * rho.imag == pytest.approx(A, rel=1e-5)
    rho2 = eps / complex(K.impedance("II", np.asarray(1j * sR + eps), nu))
    assert -2 * rho2.imag == pytest.approx(E.modal_long_time_amplitude(nu, "II"), rel=1e-5)


def test_long_time_amplitude_paper_value():
    assert E.modal_long_time_amplitude(0.25) == pytest.approx(0.5844, abs=5e-5)  # eq. (B.5)
    with pytest.raises(ValueError):
        E.modal_long_time_amplitude(0.25, "III")


# ----------------------------------------------------------------------------- modal r(T)
def test_modal_inversion_on_mode_III():
    """The Talbot inversion (with the cuts laid to the left) reproduces r = J0(T)."""
    T = np.array([0.3, 2.0, 7.0, 15.0, 30.0])
    got = E.modal_exact("III", T, numerical=True)
    np.testing.assert_allclose(got, sp.j0(T), atol=1e-12)
    np.testing.assert_array_equal(E.modal_exact("III", T), sp.j0(T))


@pytest.mark.parametrize("mode", ["I", "II"])
def test_modal_exact_against_de_hoog(mode):
    """An independent inversion (de Hoog, on a Bromwich line Re s > 0) of r_hat = eta / M(s)."""
    nu = 0.25
    a = K.wave_speed_ratio(nu)
    eta = a if mode == "I" else 1.0

    def rhat(s):  # principal branches suffice on Re s > 0
        als, ald = mp.sqrt(1 + s**2), mp.sqrt(1 + s**2 / a**2)
        R = 4 * als * ald - (2 + s**2) ** 2
        alpha = ald if mode == "I" else als
        return -eta * s**2 * alpha / R

    for T in (3.0, 12.0):
        with mp.workdps(30):
            ref = float(mp.invertlaplace(rhat, T, method="dehoog"))
        assert float(E.modal_exact(mode, T, nu)) == pytest.approx(ref, abs=1e-10)


@pytest.mark.parametrize("mode", ["I", "II", "III"])
def test_modal_exact_start(mode):
    """r(0) = 1 and r = 1 - C(0) T^2 / (2 eta_hat) + O(T^4): r_hat = 1/s - C(0)/(eta_hat s^3) + ...
    (C is even in T, so L[C] = C(0)/s + O(s^-3))."""
    nu = 0.25
    assert float(E.modal_exact(mode, 0.0, nu)) == 1.0
    T = 1e-2
    curv = (1.0 - float(E.modal_exact(mode, T, nu, numerical=True))) / T**2
    assert curv == pytest.approx(K.C0(mode, nu) / (2 * K.eta_hat(mode, nu)), rel=1e-3)
    r = E.modal_exact(mode, np.array([[0.5, 1.0], [1.5, 2.0]]), nu)
    assert r.shape == (2, 2)


@pytest.mark.parametrize("mode", ["I", "II"])
def test_modal_exact_long_time(mode):
    """r(T) -> A sin(s_R T) (eq. B.5) plus the branch-point waves e^{+-iT}, e^{+-iaT}, which decay
    like T^-3/2 (r_hat is analytic in sqrt(s -+ i), sqrt(s -+ ia)); fitted with their T^-5/2 terms."""
    nu = 0.25
    A = E.modal_long_time_amplitude(nu, mode)
    sR = E.rayleigh_speed_ratio(nu)
    a = K.wave_speed_ratio(nu)
    T = np.linspace(40.0, 100.0, 13)
    r = E.modal_exact(mode, T, nu)
    cols = [np.sin(sR * T), np.cos(sR * T)]
    for p in (1.5, 2.5):
        for w in (1.0, a):
            cols += [np.cos(w * T) / T**p, np.sin(w * T) / T**p]
    M = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(M, r, rcond=None)
    assert coef[0] == pytest.approx(A, rel=1e-3)
    assert abs(coef[1]) < 5e-3 * A
    assert np.max(np.abs(r - M @ coef)) < 2e-3 * A
    assert np.max(np.abs(r - A * np.sin(sR * T)) * T**1.5) < 20.0


# ----------------------------------------------------------------------------- Pekeris / Lamb
def test_lamb_arrivals():
    tp, ts, tr = E.lamb_arrivals()
    assert tp == pytest.approx(1 / SQ3) and ts == 1.0
    assert tr == pytest.approx(1 / 0.9194017, rel=1e-6)  # c_s / c_R


def test_pekeris_G():
    tp, ts, tr = E.lamb_arrivals()
    G = E.pekeris_G
    # quiet before the P wave, continuous at it
    assert np.all(G(np.linspace(0.0, tp - 1e-9, 50)) == 0.0)
    assert abs(float(G(tp + 1e-12))) < 1e-5
    # continuous across the S arrival, with a change of slope there
    left, right = float(G(1 - 1e-10)), float(G(1 + 1e-10))
    assert left == pytest.approx(right, abs=1e-8)
    assert left == pytest.approx((1 - SQ3) / 8, abs=1e-8)
    h = 1e-5
    sl = (float(G(1 - h)) - float(G(1 - 2 * h))) / h
    sr = (float(G(1 + 2 * h)) - float(G(1 + h))) / h
    assert abs(sl - sr) > 0.1
    # negative (opening against the load) before the Rayleigh wave, -inf at it
    mid = np.linspace(tp + 1e-6, tr - 1e-6, 200)
    assert np.all(G(mid) < 0)
    assert float(G(tr - 1e-9)) < -100
    # static value 3/8 after it: w = P (1-nu) / (2 pi mu r) at nu = 1/4 (Boussinesq)
    np.testing.assert_array_equal(G(np.array([tr, tr + 1e-9, 2.0, 50.0])), 0.375)
    assert G(np.array([0.5, 0.9])).shape == (2,)


def test_lamb_opening():
    r, P, mu = 2.0, 3.0, 1.5
    static = E.lamb_opening(r, 100.0, P=P, mu=mu)
    assert static == pytest.approx(3 * P / (4 * math.pi * mu * r))
    assert static == pytest.approx(P * (1 - 0.25) / (math.pi * mu * r))
    # scaling with c_s: the same tau gives the same value
    assert E.lamb_opening(r, 0.9, cs=2.0) == pytest.approx(E.lamb_opening(r, 1.8, cs=1.0))
    t = np.linspace(0, 5, 7)
    assert E.lamb_opening(np.full(7, 1.0), t).shape == (7,)


# ----------------------------------------------------------------------------- static cracks
def test_penny_and_ellipse():
    c, p, mu, nu = 0.3, 2.0, 1.5, 0.25
    r = np.array([0.0, 0.1, 0.29, 0.31, 1.0])
    penny = E.penny_opening(r, c, p, mu, nu)
    np.testing.assert_allclose(penny[:3], 4 * (1 - nu) * p / (math.pi * mu) * np.sqrt(c**2 - r[:3] ** 2))
    assert penny[3] == 0 and penny[4] == 0
    # a = b: Green & Sneddon reduces to Sneddon's penny crack
    x1, x3 = np.array([0.0, 0.1, 0.05, 0.3]), np.array([0.0, 0.0, 0.2, 0.2])
    np.testing.assert_allclose(E.elliptical_opening(x1, x3, c, c, p, mu, nu),
                               E.penny_opening(np.hypot(x1, x3), c, p, mu, nu), rtol=1e-14)
    # a >> b: the Griffith (plane strain) opening across the long axis
    b = 0.2
    x3 = np.linspace(-0.19, 0.19, 9)
    np.testing.assert_allclose(E.elliptical_opening(0.0, x3, 1e7 * b, b, p, mu, nu),
                               E.griffith_opening(x3, b, p, mu, nu, "I"), rtol=1e-9)
    # swapping the axes swaps the coordinates
    assert E.elliptical_opening(0.1, 0.05, 0.4, 0.2, p, mu, nu) == pytest.approx(
        float(E.elliptical_opening(0.05, 0.1, 0.2, 0.4, p, mu, nu)))
    # an elongated crack opens more at the centre than the inscribed penny
    assert E.elliptical_opening(0.0, 0.0, 0.4, 0.2, p, mu, nu) > E.penny_opening(0.0, 0.2, p, mu, nu)


def test_griffith():
    x = np.array([-0.2, 0.0, 0.05, 0.3])
    c, p, mu, nu = 0.25, 1.0, 2.0, 0.3
    for mode in ("I", "II"):
        np.testing.assert_allclose(E.griffith_opening(x, c, p, mu, nu, mode),
                                   2 * (1 - nu) * p / mu * np.sqrt(np.clip(c * c - x * x, 0, None)))
    np.testing.assert_allclose(E.griffith_opening(x, c, p, mu, nu, "III"),
                               2 * p / mu * np.sqrt(np.clip(c * c - x * x, 0, None)))
    with pytest.raises(ValueError, match="mode"):
        E.griffith_opening(x, c, p, mu, nu, "IV")


def spectral_static_row(N, L, c, stiffness, p=1.0):
    """Direct spectral static solution: opening D on the crack nodes |x| < c of an N-point periodic
    grid such that the traction (stiffness(|q|) D)^ equals p on the crack; D = 0 elsewhere."""
    x = (np.arange(N) - N // 2) * (L / N)
    q = 2 * np.pi * np.abs(np.fft.fftfreq(N, d=L / N))
    col = np.real(np.fft.ifft(stiffness(q)))  # first column of the circulant operator
    idx = np.nonzero(np.abs(x) < c)[0]
    A = col[(idx[:, None] - idx[None, :]) % N]
    d = np.zeros(N)
    d[idx] = linalg.solve(A, np.full(idx.size, p), assume_a="pos")
    return x, d, idx.size * (L / N) / 2  # effective half length (half a cell past the last node)


@pytest.mark.parametrize("mode", ["I", "II", "III"])
def test_periodic_row_against_spectral_static_solution(mode):
    mu, nu, L, c = 1.3, 0.25, 2.0, 0.5
    # plane static stiffness: traction = -(mu |q| / (2(1-nu))) D for I and II, -(mu |q| / 2) D for III
    if mode == "III":
        stiffness = lambda q: mu * q / 2  # noqa: E731
    else:
        stiffness = lambda q: mu * q / (2 * (1 - nu))  # noqa: E731
    errs = []
    for N in (512, 2048):
        x, d, c_eff = spectral_static_row(N, L, c, stiffness)
        ex = E.periodic_row_opening(x, c_eff, L, 1.0, mu, nu, mode)
        inner = np.abs(x) < 0.8 * c
        errs.append(np.max(np.abs(d[inner] - ex[inner])) / ex.max())
    assert errs[1] < 1.5e-3 and errs[1] < 0.5 * errs[0], errs


def test_periodic_row_shape():
    c, L, p, mu, nu = 0.2, 1.0, 1.0, 1.0, 0.25
    x = np.linspace(-0.5, 0.5, 101)
    d = E.periodic_row_opening(x, c, L, p, mu, nu, "I")
    # periodic, symmetric, zero outside the crack
    np.testing.assert_allclose(E.periodic_row_opening(x + 3 * L, c, L, p, mu, nu, "I"), d, atol=1e-12)
    np.testing.assert_allclose(d, d[::-1], atol=1e-12)
    assert np.all(d[np.abs(x) >= c] == 0) and np.all(d[np.abs(x) < c] > 0)
    # a sparse row (c << L) is a Griffith crack
    xs = np.linspace(-0.009, 0.009, 7)
    for mode in ("I", "III"):
        np.testing.assert_allclose(E.periodic_row_opening(xs, 0.01, 10.0, p, mu, nu, mode),
                                   E.griffith_opening(xs, 0.01, p, mu, nu, mode), rtol=2e-6)
    # neighbours open the crack further
    assert E.periodic_row_opening(0.0, c, L, p, mu, nu, "I") > E.griffith_opening(0.0, c, p, mu, nu, "I")


# ----------------------------------------------------------------------------- Kostrov
def test_kostrov():
    dtau, mu, cs = 2.0, 3.0, 1.5
    t = 2.0
    # slow growth: the static mode III crack of half length v t
    v = 1e-6 * cs
    x = np.linspace(-0.9, 0.9, 7) * v * t
    np.testing.assert_allclose(E.kostrov_slip(x, t, v, dtau, mu, cs),
                               E.griffith_opening(x, v * t, dtau, mu, 0.25, "III"), rtol=1e-9)
    # at v = cs, E(0) = pi/2
    assert E.kostrov_slip(0.0, t, cs, dtau, mu, cs) == pytest.approx(4 / math.pi * dtau / mu * cs * t)
    assert E.kostrov_slip(1.01 * 0.5 * t, t, 0.5, dtau, mu, cs) == 0.0
    # traction at the centre from the mode III impedance mu/2 sqrt(q^2 + p^2/cs^2): with
    # slip A sqrt(v^2 t^2 - x^2) the stress drop is (mu A / 4) int sqrt(u^2+b^2)/(1+u^2)^1.5 du, b = v/cs
    for v in (0.2, 0.7, 1.2):
        A = float(E.kostrov_slip(0.0, 1.0, v, dtau, mu, cs)) / v
        b = v / cs
        I = 2 * integrate.quad(lambda u: math.sqrt(u * u + b * b) / (1 + u * u) ** 1.5, 0, np.inf,
                               epsabs=1e-13, epsrel=1e-12)[0]
        assert mu * A / 4 * I == pytest.approx(dtau, rel=1e-9)
    with pytest.raises(ValueError):
        E.kostrov_slip(0.0, 1.0, 2.0, dtau, mu, cs)
