"""Kernels of one half space's face: its traction from its own face displacement (the
independent formulation of docs/equations.md, "One half space: Eqs. (20)-(22)").

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
branch cuts (solver/cuts.py) beyond, each where it is accurate to ~1e-12.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from . import cuts

FACE_KERNELS = ("H11", "H22", "H12")

#: terms of the series in t = 1/s
_N = 64


def _ratio(nu):
    from .kernels import wave_speed_ratio

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


def _taylor_sum(c, T, order):
    T = np.asarray(T, dtype=float)
    out = np.zeros_like(T)
    fact = math.factorial
    for m in range(1, c.size):
        k = m - 1 + order
        out += c[m] * T**k / fact(k)
    return out


def _parts(kernel, T, nu, order):
    """The regular part of H (order 0), int_0^T of it (1), int_0^T int_0^t of it (2)."""
    T = np.asarray(T, dtype=float)
    if np.any(T < 0) or np.any(np.isnan(T)):
        raise ValueError("T must be >= 0")
    c = _series_cached(kernel, float(nu))
    Ts = series_limit(nu)
    near = T <= Ts
    out = np.empty(T.shape)
    if np.any(near):
        out[near] = _taylor_sum(c, T[near], order)
    if np.any(~near):
        q = _quadrature(kernel, float(nu))
        Tf = T[~near]
        if order == 0:
            out[~near] = cuts.evaluate(q, Tf)
        else:
            # continue the antiderivatives from T_s with the cut representation
            base = _taylor_sum(c, np.array([Ts]), order)[0]
            I1 = cuts.evaluate(q, Tf, order=1) - cuts.evaluate(q, np.array([Ts]), order=1)[0]
            if order == 1:
                out[~near] = base + I1
            else:
                i1s = _taylor_sum(c, np.array([Ts]), 1)[0]
                J = (cuts.evaluate(q, Tf, order=2) - cuts.evaluate(q, np.array([Ts]), order=2)[0]
                     - (Tf - Ts) * cuts.evaluate(q, np.array([Ts]), order=1)[0])
                out[~near] = base + i1s * (Tf - Ts) + J
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
