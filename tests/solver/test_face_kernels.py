"""The kernels of one half space's face (solver/face_kernels.py): checked against the pair's
closed forms of Eq. (26), their exact Laplace transforms, the static half space and the
high-frequency limits worked out by hand."""
import numpy as np
import pytest
from scipy import integrate

from cracklab.history import fit
from cracklab.solver import cuts
from cracklab.solver import face_kernels as fk
from cracklab.solver import kernels as K

NUS = (0.25, 0.1, 0.35, 0.45, -0.3)


@pytest.mark.parametrize("nu", NUS)
@pytest.mark.parametrize("kernel", ["I", "II", "III"])
def test_series_and_cuts_reproduce_the_pair_closed_forms(kernel, nu):
    """The two time-domain evaluations the face kernels use, applied to the pair's kernels."""
    Ts = fk.series_limit(nu)
    T = np.linspace(0.0, Ts, 101)
    np.testing.assert_allclose(fk._taylor_sum(fk.series(kernel, nu), T, 0), K.C(kernel, T, nu), rtol=0, atol=5e-14)
    q = cuts.quadrature(lambda s, A, B, a: K.branch_transform(kernel, s, A, B, a), nu,
                        (1.0,) if kernel == "III" else (1.0, K.wave_speed_ratio(nu)))
    T = np.linspace(Ts, 200.0, 2001)
    np.testing.assert_allclose(cuts.evaluate(q, T), K.C(kernel, T, nu), rtol=0, atol=2e-9)


@pytest.mark.parametrize("nu", NUS)
@pytest.mark.parametrize("kernel", fk.FACE_KERNELS)
def test_numerical_laplace_transform_matches_the_exact_one(kernel, nu):
    Ts = fk.series_limit(nu)
    for s in (0.2, 1.0, 3.0, 8.0):
        def f(T):
            return np.exp(-s * T) * fk.C(kernel, np.array([T]), nu)[0]

        num = sum(integrate.quad(f, lo, hi, limit=400, epsabs=1e-13, epsrel=1e-13)[0]
                  for lo, hi in ((0.0, Ts), (Ts, 20.0), (20.0, 300.0), (300.0, np.inf)))
        num += fk.instantaneous(kernel, nu)
        assert abs(num - fk.laplace(kernel, s, nu)) < 1e-7


@pytest.mark.parametrize("nu", NUS)
@pytest.mark.parametrize("kernel", fk.FACE_KERNELS)
def test_series_and_cuts_agree_where_both_hold(kernel, nu):
    T = np.linspace(0.5, fk.series_limit(nu), 40)
    np.testing.assert_allclose(fk._taylor_sum(fk.series(kernel, nu), T, 0), cuts.evaluate(fk._quadrature(kernel, nu), T),
                               rtol=0, atol=1e-12)


@pytest.mark.parametrize("nu", NUS)
def test_static_limits_are_the_static_half_space(nu):
    """Static plane strain half space under a face displacement (U_L, U_N) e^{iqx}:
    T_L = -mu q [4(1-nu)/(3-4nu)] U_L + i mu q [2(1-2nu)/(3-4nu)] U_N, and alike for T_N."""
    stiff = 4 * (1 - nu) / (3 - 4 * nu)
    couple = 2 * (1 - 2 * nu) / (3 - 4 * nu)
    for kernel, want in (("H11", stiff), ("H22", stiff), ("H12", -couple)):
        assert float(K.Z(kernel, np.zeros(1), nu)[0]) == pytest.approx(want, abs=1e-14)
        assert K.static_integral(kernel, nu) == pytest.approx(want, abs=1e-14)
        assert abs(fk.laplace(kernel, 1e-9, nu) - want) < 1e-8
        # the tail: Z(T) -> 0
        assert abs(float(K.Z(kernel, np.array([1e6]), nu)[0])) < 1e-6


@pytest.mark.parametrize("nu", NUS)
def test_high_frequency_limits(nu):
    """By hand from the 1/s expansion: H11(0+) = a - 1/2, H22(0+) = a^2 (1 - a/2),
    H12 = (a - 2) delta(T) + O(T)."""
    a = K.wave_speed_ratio(nu)
    assert fk.C0("H11", nu) == pytest.approx(a - 0.5, rel=1e-13)
    assert fk.C0("H22", nu) == pytest.approx(a * a * (1 - a / 2), rel=1e-12, abs=1e-14)
    assert fk.instantaneous("H12", nu) == pytest.approx(a - 2, rel=1e-13)
    assert fk.C0("H12", nu) == pytest.approx(0.0, abs=1e-14)
    assert float(K.C("H11", np.array([1e-8]), nu)[0]) == pytest.approx(a - 0.5, rel=1e-7)
    s = 1e4
    assert fk.laplace("H11", s, nu) * s == pytest.approx(a - 0.5, rel=1e-3)


@pytest.mark.parametrize("nu", NUS)
def test_identical_pair_from_two_faces_equals_the_combined_kernels(nu):
    """Eliminating the continuous component of two identical faces (the Schur complement of
    Eq. 23) gives the pair's impedances of Eqs. (23)-(24), which use the corrected C_II."""
    rng = np.random.default_rng(3)
    n = 300
    s = rng.uniform(0, 1, n) * 10 ** rng.uniform(-4, 3, n) + 1j * rng.normal(0, 1, n) * 10 ** rng.uniform(-4, 3, n)
    a = K.wave_speed_ratio(nu)
    m11 = s + fk.laplace("H11", s, nu)
    m22 = a * s + fk.laplace("H22", s, nu)
    c = fk.laplace("H12", s, nu)  # = R - 2: T_L = ... - i mu q c U_N
    for mode, got in (("II", m11 - c * c / m22), ("I", m22 - c * c / m11)):
        want = K.impedance(mode, s, nu)
        assert np.max(np.abs(got - want) / np.abs(want)) < 1e-12


def test_closed_form_and_series_of_the_transform_agree():
    nu = 0.3
    a = K.wave_speed_ratio(nu)
    s = np.array([9.0 + 1j, 5.0 - 4j, 20.0j + 0.1])
    for kernel in fk.FACE_KERNELS:
        closed = fk.branch_transform(kernel, s, np.sqrt(1 + s * s), np.sqrt(1 + s * s / a**2), a)
        np.testing.assert_allclose(fk.laplace(kernel, s, nu), closed, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("kernel", fk.FACE_KERNELS)
def test_exponential_fits_of_the_face_kernels(kernel):
    f = fit.fit_kernel(kernel, nu=0.25, formulation="velocity")
    assert f.err <= f.tol * f.scale
    T = np.linspace(1.0, 60.0, 600)
    assert np.max(np.abs(fit.evaluate(f, T) - K.Z(kernel, T, 0.25))) <= f.tol * f.scale


def test_unknown_kernel_is_refused():
    with pytest.raises(ValueError, match="H11"):
        K.C("H13", 1.0)
