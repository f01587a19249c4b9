"""Kernels of one half space's face: its traction from its own face displacement (the
independent formulation of docs/reference/equations.md, "One half space: Eqs. (20)-(22)").

For the upper half space x2 > 0 and one Fourier mode, in the frame of the wave vector
(L along q, N = 2 normal, T transverse; T = q c_s t and s = p/(q c_s) dimensionless,
a = c_d/c_s, A = sqrt(1 + s^2), B = sqrt(1 + s^2/a^2)),

    T_L = -mu q [s + L[H11]] U_L + i mu q (2 - R) U_N,
    T_N = -i mu q (2 - R) U_L - mu q [a s + L[H22]] U_N,       T_T = -mu q A U_T,
    R = (1 - A^2)/(1 - A B) = a^2 (1 + A B)/(s^2 + 1 + a^2),

so that L[H11] = B R - s, L[H22] = A R - a s and, for the coupling, L[H12] = R - 2
(T_L = ... - i mu q L[H12] U_N). The transverse kernel is C_III of the pair. H11, H22
tend to constants as s -> inf (bounded kernels); H12 tends to a - 2: the coupling has an
instantaneous part (a - 2) delta(T), which the velocity formulation keeps in its static
term Z(0) = L[H12](0) while Z(T > 0) is that of the regular rest.

R has no pole: s^2 + 1 + a^2 = 0 where 1 + A B = 0 on the principal sheet; the kernels are
analytic off the branch cuts from s = +-i and +-i a, like those of the pair.

Time domain, without a closed form: the Taylor series at T = 0 (the coefficients are those
of the expansion of L[H] in 1/s) for T <= T_s, and the Bromwich integral folded onto the
branch cuts (elastic/cuts.py) beyond, each where it is accurate to ~1e-12. On T_s < T <=
T_TABLE, where the exact taps of the history engines lie, the cut representation (of H and
of its first two antiderivatives) is read from piecewise Chebyshev interpolants of it
(degree 20 on pieces 0.5 long, built once per kernel and nu from the cut sums: they
reproduce them to their own round-off, ~1e-15 of the function's size), a few dozen
operations per time instead of a sum over ~500 exponentials.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from . import cuts
from .waves import wave_speed_ratio

FACE_KERNELS = ("H11", "H22", "H12")

#: terms of the series in t = 1/s
_N = 64


def _ratio(nu):
    return wave_speed_ratio(nu)


# ------------------------------------------------------------------ transforms
def branch_transform(kernel, s, A, B, a):
    """L[H](s) with explicit branch values A = sqrt(1 + s^2), B = sqrt(1 + s^2/a^2)."""
    R = a * a * (1.0 + A * B) / (s * s + 1.0 + a * a)
    if kernel == "H11":
        return B * R - s
    if kernel == "H22":
        return A * R - a * s
    if kernel == "H12":
        return R - 2.0
    raise ValueError(f"kernel must be one of {FACE_KERNELS}, got {kernel!r}")


def _mul(x, y):
    return np.convolve(x, y)[:_N]


def _sqrt_series(c):
    """sqrt(1 + c t^2) as a power series in t."""
    out = np.zeros(_N)
    coef = 1.0
    for k in range(0, (_N + 1) // 2):
        out[2 * k] = coef * c**k
        coef *= (0.5 - k) / (k + 1)
    return out


def _inverse(x):
    """1/x as a power series (x[0] != 0)."""
    out = np.zeros(_N)
    out[0] = 1.0 / x[0]
    for n in range(1, _N):
        out[n] = -np.dot(x[1:n + 1], out[n - 1::-1][:n]) / x[0]
    return out


def _shift_down(x):
    """x/t for a series with x[0] = 0 (checked to round-off)."""
    return np.append(x[1:], 0.0)


@lru_cache(maxsize=64)
def _series_cached(kernel, nu):
    a = _ratio(nu)
    SA, SB = _sqrt_series(1.0), _sqrt_series(a * a)
    one = np.zeros(_N)
    one[0] = 1.0
    t2 = np.zeros(_N)
    t2[2] = 1.0
    if kernel in FACE_KERNELS:
        R = a * _mul(a * t2 + _mul(SA, SB), _inverse(one + (1.0 + a * a) * t2))
        if kernel == "H11":
            return _shift_down(_mul(SB, R) / a - one)
        if kernel == "H22":
            return _shift_down(_mul(SA, R) - a * one)
        return R - 2.0 * one
    # the pair's kernels (Appendix A), for checks of the series against their closed forms
    P = _mul(one + 2.0 * t2, one + 2.0 * t2) - 4.0 * _mul(t2, _mul(SA, SB)) / a
    if kernel == "III":
        return _shift_down(SA - one)
    if kernel == "II":
        return _shift_down(_mul(P - SA, _inverse(SA)))
    if kernel == "I":
        return a * _shift_down(_mul(P - SB, _inverse(SB)))
    raise ValueError(f"kernel {kernel!r} has no series here")


def series(kernel, nu=0.25):
    """Coefficients c_m of t^m (t = 1/s) of L[kernel]: C(T) = sum_{m>=1} c_m T^(m-1)/(m-1)!,
    plus c_0 delta(T)."""
    return _series_cached(kernel, float(nu)).copy()


def _radius(nu):
    """Radius in s beyond which the series in 1/s converges (the farthest singularity of
    its pieces, s = i sqrt(1 + a^2))."""
    a = _ratio(nu)
    return math.sqrt(1.0 + a * a)


def series_limit(nu):
    """T_s: the Taylor series is used for T <= T_s (terms (rho T)^n/n!, rho T_s <= 4)."""
    return min(2.0, 4.0 / _radius(nu))


def laplace(kernel, s, nu=0.25):
    """L[H](s) (complex s, Re s >= 0): the closed form with principal roots for |s| <= 2 rho,
    the series in 1/s beyond (no cancellation at large |s|)."""
    a = _ratio(nu)
    s = np.asarray(s)
    cplx = np.iscomplexobj(s)
    s = s.astype(complex)
    rho = _radius(nu)
    near = np.abs(s) <= 2.0 * rho
    sn = np.where(near, s, 1.0)
    out = branch_transform(kernel, sn, np.sqrt(1.0 + sn * sn), np.sqrt(1.0 + sn * sn / a**2), a)
    if not np.all(near):
        t = np.where(near, 0.0, 1.0 / np.where(near, 1.0, s))
        c = _series_cached(kernel, float(nu))
        far = np.zeros_like(t)
        for cm in c[::-1]:
            far = far * t + cm
        out = np.where(near, out, far)
    if not cplx:
        out = out.real
    return out[()] if out.ndim == 0 else out


def static_integral(kernel, nu=0.25):
    """L[H](0) = int_0^inf H dT (the delta of H12 included): 2a^2/(1+a^2) R-factor forms."""
    a = _ratio(nu)
    r0 = 2.0 * a * a / (1.0 + a * a)
    return {"H11": r0, "H22": r0, "H12": r0 - 2.0}[kernel]


def instantaneous(kernel, nu=0.25):
    """c_0: the weight of delta(T) in the kernel (a - 2 for H12, 0 for H11, H22)."""
    return float(_series_cached(kernel, float(nu))[0])


# ------------------------------------------------------------------ time domain
@lru_cache(maxsize=64)
def _quadrature(kernel, nu):
    return cuts.quadrature(lambda s, A, B, a: branch_transform(kernel, s, A, B, a), nu, (1.0, _ratio(nu)))


@lru_cache(maxsize=256)
def _taylor_coefficients(kernel, nu, order):
    """d_k of sum_k d_k T^k, the series of the regular part's antiderivative of ``order``
    (c_m T^(m - 1 + order) / (m - 1 + order)!), highest power first, for Horner's rule."""
    c = _series_cached(kernel, nu)
    d = np.zeros(c.size - 1 + order)
    for m in range(1, c.size):
        k = m - 1 + order
        d[k] = c[m] / math.factorial(k)
    # on T <= T_s the terms beyond ~30 are below 1e-20 of the largest: left out
    size = np.abs(d) * series_limit(nu) ** np.arange(d.size)
    keep = int(np.flatnonzero(size > 1e-20 * size.max()).max()) + 1
    return d[:keep][::-1].copy()


def _taylor_sum(c, T, order):
    """sum_{m>=1} c_m T^(m - 1 + order) / (m - 1 + order)! (Horner's rule)."""
    T = np.asarray(T, dtype=float)
    d = np.zeros(c.size - 1 + order)
    for m in range(1, c.size):
        d[m - 1 + order] = c[m] / math.factorial(m - 1 + order)
    return _horner(d[::-1], T)


def _horner(d, T):
    out = np.full(T.shape, d[0])
    for dk in d[1:]:
        out *= T
        out += dk
    return out


#: the Chebyshev interpolants of the cut representation cover T_s < T <= T_TABLE (the exact
#: taps of the history engines lie below ~10: T0 = 4 and a few gamma, the levels' margin)
T_TABLE = 12.0
_PIECE, _DEGREE = 0.5, 20


@lru_cache(maxsize=64)
def _anchors(kernel, nu):
    """What the continuation from T_s needs, per kernel: the series' antiderivatives at T_s
    (orders 1, 2) and the cut representation's there (orders 1, 2)."""
    c = _series_cached(kernel, nu)
    Ts = np.array([series_limit(nu)])
    q = _quadrature(kernel, nu)
    return (_taylor_sum(c, Ts, 1)[0], _taylor_sum(c, Ts, 2)[0],
            cuts.evaluate(q, Ts, order=1)[0], cuts.evaluate(q, Ts, order=2)[0])


def _far(kernel, T, nu, order):
    """The regular part's function of ``order`` for T > T_s from the cut sums, continued from
    the series at T_s (orders 1 and 2)."""
    q = _quadrature(kernel, nu)
    if order == 0:
        return cuts.evaluate(q, T)
    Ts = series_limit(nu)
    s1, s2, k1, k2 = _anchors(kernel, nu)
    I1 = cuts.evaluate(q, T, order=1) - k1
    if order == 1:
        return s1 + I1
    J = cuts.evaluate(q, T, order=2) - k2 - (T - Ts) * k1
    return s2 + s1 * (T - Ts) + J


@lru_cache(maxsize=192)
def _table(kernel, nu, order):
    """Chebyshev coefficients (pieces, degree + 1) of :func:`_far` on [T_s, T_TABLE] in
    pieces of length _PIECE (the last one reaching T_TABLE or a little beyond)."""
    Ts = series_limit(nu)
    n = int(math.ceil((T_TABLE - Ts) / _PIECE))
    x = np.cos(np.pi * (np.arange(_DEGREE + 1) + 0.5) / (_DEGREE + 1))   # first-kind nodes
    lo = Ts + _PIECE * np.arange(n)
    vals = _far(kernel, (lo[:, None] + 0.5 * _PIECE * (x[None, :] + 1.0)).ravel(), nu, order)
    vals = vals.reshape(n, _DEGREE + 1)
    # c_k = (2 - [k = 0]) / (N + 1) sum_j f(x_j) T_k(x_j)
    Tk = np.cos(np.outer(np.arange(_DEGREE + 1), np.pi * (np.arange(_DEGREE + 1) + 0.5) / (_DEGREE + 1)))
    coef = vals @ Tk.T * (2.0 / (_DEGREE + 1))
    coef[:, 0] *= 0.5
    coef = np.ascontiguousarray(coef.T)         # (degree + 1, pieces): one row per order k
    coef.setflags(write=False)
    return coef


def _from_table(kernel, T, nu, order):
    """:func:`_far` on T_s < T <= T_TABLE from its Chebyshev pieces (Clenshaw's recurrence)."""
    coef = _table(kernel, nu, order)
    Ts = series_limit(nu)
    u = (T - Ts) / _PIECE
    i = np.minimum(u.astype(np.int64), coef.shape[1] - 1)
    x = 2.0 * (u - i) - 1.0
    # the times grouped by piece (a counting sort), each group with its own coefficients
    order = np.argsort(i.astype(np.int16), kind="stable")
    bounds = np.concatenate([[0], np.cumsum(np.bincount(i, minlength=coef.shape[1]))])
    xs = x[order]
    out = np.empty(T.shape)
    res = np.empty(xs.shape)
    for p in np.flatnonzero(np.diff(bounds)):
        sl = slice(bounds[p], bounds[p + 1])
        res[sl] = _clenshaw(coef[:, p], xs[sl])
    out[order] = res
    return out


def _clenshaw(c, x):
    """sum_k c_k T_k(x)."""
    x2 = 2.0 * x
    b1 = np.full(x.shape, c[-1])
    b2 = np.zeros(x.shape)
    for ck in c[-2:0:-1]:
        b0 = x2 * b1
        b0 -= b2
        b0 += ck
        b1, b2 = b0, b1
    out = x * b1
    out -= b2
    out += c[0]
    return out


def _parts(kernel, T, nu, order):
    """The regular part of H (order 0), int_0^T of it (1), int_0^T int_0^t of it (2)."""
    T = np.asarray(T, dtype=float)
    if np.any(T < 0) or np.any(np.isnan(T)):
        raise ValueError("T must be >= 0")
    nu = float(nu)
    Ts = series_limit(nu)
    out = np.empty(T.shape)
    near = T <= Ts
    mid = ~near & (T <= T_TABLE)
    far = T > T_TABLE
    if np.any(near):
        out[near] = _horner(_taylor_coefficients(kernel, nu, order), T[near])
    if np.any(mid):
        out[mid] = _from_table(kernel, T[mid], nu, order)
    if np.any(far):
        out[far] = _far(kernel, T[far], nu, order)
    return out


def C(kernel, T, nu=0.25):
    """H(T) for T > 0 (the regular part; H12's delta(T) weight is :func:`instantaneous`)."""
    return _out(_parts(kernel, T, nu, 0))


def integral(kernel, T, nu=0.25):
    """int_0+^T H (the regular part)."""
    return _out(_parts(kernel, T, nu, 1))


def Z(kernel, T, nu=0.25):
    """Z(T) = int_T^inf H: L[H](0) at T = 0 (the whole kernel), the regular part's tail for T > 0."""
    T = np.asarray(T, dtype=float)
    reg0 = static_integral(kernel, nu) - instantaneous(kernel, nu)
    out = reg0 - _parts(kernel, T, nu, 1)
    out = np.where(T == 0, static_integral(kernel, nu), out)
    return _out(out)


def Z_integral(kernel, T, nu=0.25):
    """int_0^T Z(T') dT' (the value at the single point T' = 0 does not count)."""
    T = np.asarray(T, dtype=float)
    reg0 = static_integral(kernel, nu) - instantaneous(kernel, nu)
    return _out(reg0 * T - _parts(kernel, T, nu, 2))


def C0(kernel, nu=0.25):
    """H(0+) = c_1."""
    return float(_series_cached(kernel, float(nu))[1])


def _out(arr):
    arr = np.asarray(arr)
    return arr[()] if arr.ndim == 0 else arr
