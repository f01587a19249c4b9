"""The kernels of one half space's face (elastic/face_kernels.py): checked against the pair's
closed forms of Eq. (26), their exact Laplace transforms, the static half space and the
high-frequency limits worked out by hand."""
import numpy as np
import pytest
from scipy import integrate

from cracklab.history import fit
from cracklab.elastic import cuts
from cracklab.elastic import face_kernels as fk
from cracklab.elastic import kernels as K

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


@pytest.mark.parametrize("nu", NUS)
@pytest.mark.parametrize("kernel", fk.FACE_KERNELS)
def test_tables_reproduce_the_cut_sums(kernel, nu):
    """On T_s < T <= T_TABLE the kernel and its two antiderivatives come from Chebyshev
    pieces of the cut representation: they reproduce it to its round-off (the pieces' ends
    and the table's end included), and the cut sums take over beyond."""
    Ts = fk.series_limit(nu)
    T = np.concatenate([np.random.default_rng(5).uniform(Ts, fk.T_TABLE, 2000),
                        Ts + fk._PIECE * np.arange(1, 8), [np.nextafter(Ts, 99.0), fk.T_TABLE]])
    for order in (0, 1, 2):
        want = fk._far(kernel, T, nu, order)
        got = fk._parts(kernel, T, nu, order)
        scale = max(1.0, np.abs(want).max())
        assert np.max(np.abs(got - want)) <= 2e-14 * scale, order
        beyond = np.array([fk.T_TABLE + 0.3, 40.0])
        np.testing.assert_array_equal(fk._parts(kernel, beyond, nu, order), fk._far(kernel, beyond, nu, order))


def test_taylor_part_keeps_the_series():
    """The Horner sum of the series (trailing terms below 1e-20 of the largest left out)
    equals the term-by-term sum on [0, T_s]."""
    import math

    for nu in NUS:
        Ts = fk.series_limit(nu)
        T = np.linspace(0.0, Ts, 301)
        for kernel in fk.FACE_KERNELS:
            c = fk.series(kernel, nu)
            for order in (0, 1, 2):
                want = sum(c[m] * T ** (m - 1 + order) / math.factorial(m - 1 + order) for m in range(1, c.size))
                np.testing.assert_allclose(fk._parts(kernel, T, nu, order), want, rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("kernel", ["H11", "H12", "H22", "III", "II"])
@pytest.mark.parametrize("lag", [0, 1, 2])
def test_product_taps_equal_product_weights(kernel, lag):
    from cracklab.history.exponential import direct_taps
    from cracklab.elastic.weights import product_taps, product_weights

    g = np.unique(np.concatenate([[0.0], np.random.default_rng(1).uniform(0.005, 0.9, 40)]))
    jd = direct_taps(g, lag, 4.0, extra=1, minimum=8)
    w, e0 = product_taps(kernel, g, jd, lag, nu=0.3)
    u = np.repeat(np.arange(g.size), jd)
    j = lag + np.arange(u.size) - np.concatenate([[0], np.cumsum(jd)[:-1]])[u]
    np.testing.assert_allclose(w, product_weights(kernel, g[u], j, nu=0.3, order=1, part="lag"), rtol=0, atol=1e-15)
    np.testing.assert_allclose(e0, product_weights(kernel, g[u], j, nu=0.3, order=1, part="start0"), rtol=0,
                               atol=1e-15)


def test_product_taps_refuse_bad_input():
    from cracklab.errors import InputError
    from cracklab.elastic.weights import product_taps

    with pytest.raises(InputError, match="taps"):
        product_taps("H11", [0.1, 0.2], [3], 1)
    with pytest.raises(InputError, match="gamma"):
        product_taps("H11", [-0.1], [3], 1)
    with pytest.raises(InputError, match="kernel"):
        product_taps("H13", [0.1], [3], 1)


def test_face_engine_taps_do_not_sum_the_cuts(monkeypatch):
    """The exact taps of a face kernel's exponential engine (here about 2 x 10^4 of them, ten
    Gauss points each) are read from the tables: the cut sums run only to build them."""
    from cracklab.history import ExponentialEngine, tables

    points = []
    real = cuts.evaluate

    def counting(quad, T, order=0, chunk=2048):
        points.append(np.count_nonzero(np.asarray(T) <= fk.T_TABLE))   # the fit's own checks go beyond
        return real(quad, T, order, chunk)

    monkeypatch.setattr(fk.cuts, "evaluate", counting)
    for f in (fk._table, fk._anchors, fk._quadrature):
        f.cache_clear()
    tables.clear()
    g = np.linspace(0.002, 0.5, 400)
    eng = ExponentialEngine(kernel="H22", gamma=g, nu=0.27, rule="product", formulation="velocity", lag=1,
                            nsteps=500)
    assert eng._wflat.size > 2e4
    assert sum(points) < 3 * 30 * 21 + 10      # three tables of < 30 pieces, 21 nodes each, and the anchors
