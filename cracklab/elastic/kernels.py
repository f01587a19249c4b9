"""Convolution kernels of the spectral boundary-integral formulation.

Geubelle & Rice (1995), eq. (26) and Appendix A, with the correction of the
mode II kernel (docs/reference/equations.md, "Convolution kernels: Eq. (26), C_II (corrected)").  Time is dimensionless,
``T = q c_s t``; ``a = c_d / c_s`` with ``a**2 = 2 (1 - nu) / (1 - 2 nu)``.

Everything is closed form in Bessel functions (``scipy.special`` only).  The
building blocks, all functions of ``x >= 0``, are

* ``W(x) = 1 - int_0^x J1(u)/u du``                      (eq. 26),
* ``g(x) = J0(x) - x W(x)``                                (g(0) = 1),
* ``k(x) = J1(x) + x g(x)``                                (k(0) = 0),

with ``int_x^inf J0 = W(x) - J1(x)``, ``int_0^x W = 1 - g(x)``,
``int_0^x u g(u) du = x k(x) / 3``.  ``W`` is evaluated from its power series
for ``x < 2`` and from the Neumann series ``int_0^x J0 = 2 sum_k J_{2k+1}(x)``
(Miller's backward recurrence) for ``2 <= x < 38``: ``scipy.special.itj0y0``
has absolute errors up to ~1e-10 near x = 20, and ``scipy.special.jv`` is
too slow for the hot path.  For ``x >= 38`` all three come from the
asymptotic form ``W = A(x) J0(x) + B(x) J1(x)`` with series ``A, B`` in
``1/x**2``, written so that the cancellations in ``g`` and ``k`` are exact.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import special as sp

__all__ = [
    "KERNELS",
    "wave_speed_ratio",
    "eta_hat",
    "W",
    "C_I",
    "C_II",
    "C_III",
    "C",
    "C0",
    "static_integral",
    "Z",
    "integral",
    "Z_integral",
    "laplace",
    "impedance",
    "branch_transform",
    "FACE_KERNELS",
    "ALL_KERNELS",
]

from . import face_kernels as _face  # noqa: E402
from .waves import wave_speed_ratio  # noqa: E402,F401  (kernels.wave_speed_ratio, as before)

#: the kernels of the pair of one material (Eq. 26)
KERNELS = ("I", "II", "III")
#: the kernels of one half space's face (elastic/face_kernels.py)
FACE_KERNELS = _face.FACE_KERNELS
ALL_KERNELS = KERNELS + FACE_KERNELS

# --------------------------------------------------------------------------
# Bessel building blocks
# --------------------------------------------------------------------------

_X_ASY = 38.0  # switch from the Neumann series to the asymptotic series
_N_ASY = 16  # number of terms of the asymptotic series in y = 1/x**2


def _asymptotic_coefficients(n):
    """Coefficients of W = (Pa J0 + Pb J1 / x) / x, Pa = sum al y^m, Pb = sum be y^m.

    From W' = -J1/x: al_0 = 1, be_m = (2m+1) al_m, al_{m+1} = -(2m+3) be_m.
    """
    al = np.empty(n + 1)
    be = np.empty(n + 1)
    al[0] = 1.0
    for m in range(n):
        be[m] = (2 * m + 1) * al[m]
        al[m + 1] = -(2 * m + 3) * be[m]
    be[n] = (2 * n + 1) * al[n]
    return al, be


_AL, _BE = _asymptotic_coefficients(_N_ASY)


def _horner(coef, y):
    out = np.full_like(y, coef[-1])
    for c in coef[-2::-1]:
        out = out * y + c
    return out


# W(x) = 1 - sum_k (-1)^k (x/2)^(2k+1) / (k! (k+1)! (2k+1)) for x < _X_SERIES
_X_SERIES = 2.0
_SERIES = np.array([(-1.0) ** k / (math.factorial(k) * math.factorial(k + 1) * (2 * k + 1))
                    for k in range(14)])
# Miller's backward recurrence for J_n(x), _X_SERIES <= x < _X_ASY, started at
# order _N_MILLER (J_84(38) ~ 1e-20) and normalised by J0 + 2 sum J_2k = 1
_N_MILLER = 84


def _w_series(x):
    h = 0.5 * x
    return 1.0 - h * _horner(_SERIES, h * h)


def _w_miller(x):
    """1 - J1 - 2 sum_{k>=1} J_{2k+1} = 1 - int_0^x J0 + J1 (Neumann series, eq. 26)."""
    f_next = np.zeros_like(x)
    f_cur = np.full_like(x, 1e-280)
    norm = np.zeros_like(x)  # f_0 + 2 sum f_2k
    odd = np.zeros_like(x)  # f_1 + 2 sum_{k>=1} f_2k+1
    two_over_x = 2.0 / x
    for n in range(_N_MILLER, 0, -1):  # f_cur = f_n -> f_{n-1}
        if n % 2:
            odd += (1.0 if n == 1 else 2.0) * f_cur
        else:
            norm += 2.0 * f_cur
        f_cur, f_next = n * two_over_x * f_cur - f_next, f_cur
    norm += f_cur  # f_0
    return 1.0 - odd / norm


def _blocks(x):
    """Return J0, J1, W, g, k at ``x >= 0`` (arrays of equal shape)."""
    x = np.asarray(x, dtype=float)
    j0 = sp.j0(x)
    j1 = sp.j1(x)
    w = np.empty_like(x)
    g = np.empty_like(x)
    kk = np.empty_like(x)

    small = x < _X_ASY
    if np.any(small):
        xs = x[small]
        ser = xs < _X_SERIES
        ws = np.empty_like(xs)
        ws[ser] = _w_series(xs[ser])
        ws[~ser] = _w_miller(xs[~ser])
        gs = j0[small] - xs * ws
        w[small] = ws
        g[small] = gs
        kk[small] = j1[small] + xs * gs

    large = ~small
    if np.any(large):
        xl = x[large]
        y = 1.0 / (xl * xl)
        pa = _horner(_AL[:_N_ASY], y)
        pb = _horner(_BE[:_N_ASY], y)
        ta = y * _horner(_AL[1 : _N_ASY + 1], y)  # pa - 1 without cancellation
        tb = y * _horner(_BE[1 : _N_ASY + 1], y)  # pb - 1
        j0l = j0[large]
        j1l = j1[large]
        w[large] = (pa * j0l + pb * j1l / xl) / xl
        g[large] = -ta * j0l - (pb / xl) * j1l
        kk[large] = -tb * j1l - xl * ta * j0l
    return j0, j1, w, g, kk


def _j1x(x):
    """J1(x)/x, exact at x = 0 (value 1/2)."""
    x = np.asarray(x, dtype=float)
    tiny = np.abs(x) < 1e-4
    xs = np.where(tiny, 1.0, x)
    return np.where(tiny, 0.5 - x * x / 16.0, sp.j1(xs) / xs)


# --------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------


def _check_kernel(kernel):
    if kernel not in ALL_KERNELS:
        raise ValueError(f"kernel must be one of {ALL_KERNELS}, got {kernel!r}")
    return kernel


def _time(T):
    T = np.asarray(T, dtype=float)
    if np.any(T < 0) or np.any(np.isnan(T)):
        raise ValueError("T must be >= 0")
    return T


def _out(arr):
    arr = np.asarray(arr)
    return arr[()] if arr.ndim == 0 else arr


def eta_hat(kernel, nu=0.25):
    """Dimensionless radiation-damping factor of eq. (4)/(24): a for mode I (and a face's
    normal kernel H22), 1 for II, III (and H11), 0 for the coupling H12."""
    _check_kernel(kernel)
    if kernel == "H12":
        return 0.0
    return wave_speed_ratio(nu) if kernel in ("I", "H22") else 1.0


# --------------------------------------------------------------------------
# time-domain kernels, eq. (26)
# --------------------------------------------------------------------------


def W(T):
    """W(T) = 1 - int_0^T J1(x)/x dx = int_T^inf J1(x)/x dx, eq. (26)."""
    T = _time(T)
    return _out(_blocks(T)[2])


def C_I(T, nu=0.25):
    """Mode I (tensile) kernel C_I(T), eq. (26).

    Rewritten with g(x) = J0(x) - x W(x):
    C_I = a^3 J1(aT)/(aT) - 4 g(T) + (4/a) g(aT) + (4a - a^3 - 4/a) J0(aT).
    """
    T = _time(T)
    a = wave_speed_ratio(nu)
    _, _, _, g1, _ = _blocks(T)
    j0a, _, _, ga, _ = _blocks(a * T)
    out = a**3 * _j1x(a * T) - 4.0 * g1 + (4.0 / a) * ga + (4.0 * a - a**3 - 4.0 / a) * j0a
    return _out(out)


def C_II(T, nu=0.25):
    """Mode II (in-plane shear) kernel C_II(T), eq. (26) with the correction -(4/a) J0(aT) (docs/reference/equations.md).

    Rewritten with g(x) = J0(x) - x W(x):
    C_II = J1(T)/T + 4 g(T) - J0(T) - (4/a) g(aT).
    """
    T = _time(T)
    a = wave_speed_ratio(nu)
    j01, _, _, g1, _ = _blocks(T)
    _, _, _, ga, _ = _blocks(a * T)
    out = _j1x(T) + 4.0 * g1 - j01 - (4.0 / a) * ga
    return _out(out)


def C_III(T):
    """Mode III (anti-plane) kernel C_III(T) = J1(T)/T, eq. (26); 1/2 at T = 0."""
    T = _time(T)
    return _out(_j1x(T))


def C(kernel, T, nu=0.25):
    """Kernel C_kernel(T) of eq. (26) for kernel in {"I", "II", "III"}."""
    if kernel in FACE_KERNELS:
        return _face.C(kernel, T, nu)
    _check_kernel(kernel)
    if kernel == "I":
        return C_I(T, nu)
    if kernel == "II":
        return C_II(T, nu)
    return C_III(T)


def C0(kernel, nu=0.25):
    """Exact C(0) from eq. (26): 4a - 4 - a^3/2 (I), 7/2 - 4/a (II), 1/2 (III)."""
    if kernel in FACE_KERNELS:
        return _face.C0(kernel, nu)
    _check_kernel(kernel)
    if kernel == "III":
        return 0.5
    a = wave_speed_ratio(nu)
    if kernel == "I":
        return 4.0 * a - 4.0 - 0.5 * a**3
    return 3.5 - 4.0 / a


def static_integral(kernel, nu=0.25):
    """int_0^inf C dT: 2(1 - 1/a^2) = 1/(1-nu) for I and II (text after eq. 33), 1 for III."""
    if kernel in FACE_KERNELS:
        return _face.static_integral(kernel, nu)
    _check_kernel(kernel)
    if kernel == "III":
        return 1.0
    a = wave_speed_ratio(nu)
    return 2.0 * (1.0 - 1.0 / a**2)


# --------------------------------------------------------------------------
# velocity-formulation kernel Z(T) = int_T^inf C, eqs. (33), (48)
# --------------------------------------------------------------------------


def Z(kernel, T, nu=0.25):
    """Z(T) = int_T^inf C(T') dT', the velocity-formulation kernel of eqs. (33) and (48).

    Closed forms (Q(x) = int_x^inf J0 = W(x) - J1(x), g(x) = J0(x) - x W(x)):
    Z_I   = a^2 W(aT) - 2Q(T) + (4 - a^2 - 2/a^2) Q(aT) + 2T g(T) - (2/a) T g(aT),
    Z_II  = W(T) + Q(T) - (2/a^2) Q(aT) - 2T g(T) + (2/a) T g(aT),
    Z_III = W(T).
    """
    if kernel in FACE_KERNELS:
        return _face.Z(kernel, T, nu)
    _check_kernel(kernel)
    T = _time(T)
    _, j11, w1, g1, _ = _blocks(T)
    if kernel == "III":
        return _out(w1)
    a = wave_speed_ratio(nu)
    _, j1a, wa, ga, _ = _blocks(a * T)
    q1 = w1 - j11
    qa = wa - j1a
    if kernel == "I":
        out = (
            a**2 * wa
            - 2.0 * q1
            + (4.0 - a**2 - 2.0 / a**2) * qa
            + 2.0 * T * g1
            - (2.0 / a) * T * ga
        )
    else:
        out = w1 + q1 - (2.0 / a**2) * qa - 2.0 * T * g1 + (2.0 / a) * T * ga
    return _out(out)


def integral(kernel, T, nu=0.25):
    """int_0^T C(T') dT' = static_integral - Z(T) (eqs. 26, 33)."""
    if kernel in FACE_KERNELS:
        return _face.integral(kernel, T, nu)
    return _out(static_integral(kernel, nu) - np.asarray(Z(kernel, T, nu)))


def Z_integral(kernel, T, nu=0.25):
    """int_0^T Z(T') dT', antiderivative of the velocity kernel of eq. (48), in closed form.

    With k(x) = J1(x) + x g(x), int_0^T W(bt) dt = (1 - g(bT))/b,
    int_0^T Q(bt) dt = (J0(bT) - g(bT))/b, int_0^T t g(bt) dt = T k(bT)/(3b).
    Tends to int_0^inf T C(T) dT = a (I), 1 (II, III).
    """
    if kernel in FACE_KERNELS:
        return _face.Z_integral(kernel, T, nu)
    _check_kernel(kernel)
    T = _time(T)
    j01, _, _, g1, k1 = _blocks(T)
    if kernel == "III":
        return _out(1.0 - g1)
    a = wave_speed_ratio(nu)
    j0a, _, _, ga, ka = _blocks(a * T)
    if kernel == "I":
        ca = (4.0 - a**2 - 2.0 / a**2) / a
        out = (
            a * (1.0 - ga)
            - 2.0 * (j01 - g1)
            + ca * (j0a - ga)
            + (2.0 / 3.0) * T * k1
            - (2.0 / (3.0 * a**2)) * T * ka
        )
    else:
        out = (
            (1.0 - g1)
            + (j01 - g1)
            - (2.0 / a**3) * (j0a - ga)
            - (2.0 / 3.0) * T * k1
            + (2.0 / (3.0 * a**2)) * T * ka
        )
    return _out(out)


# --------------------------------------------------------------------------
# Laplace domain, eqs. (23)-(24) and Appendix A
# --------------------------------------------------------------------------


def laplace(kernel, s, nu=0.25):
    """Laplace transform in T of C_kernel at (complex) s, Appendix A as corrected in docs/reference/equations.md ("Laplace transforms").

    With R = 4 sqrt(1+s^2/a^2) sqrt(1+s^2) - (2+s^2)^2 (principal roots):
    L[C_I] = -R/(s^2 sqrt(1+s^2/a^2)) - a s, L[C_II] = -R/(s^2 sqrt(1+s^2)) - s,
    L[C_III] = sqrt(1+s^2) - s.  Evaluated without cancellation for small and
    large |s| (meant for Re s >= 0).
    """
    if kernel in FACE_KERNELS:
        return _face.laplace(kernel, s, nu)
    _check_kernel(kernel)
    s = np.asarray(s)
    cplx = np.iscomplexobj(s)
    s = s.astype(complex)
    als = np.sqrt(1.0 + s * s)
    u = 1.0 / (als + s)  # sqrt(1+s^2) - s
    if kernel == "III":
        out = u
    else:
        a = wave_speed_ratio(nu)
        ald = np.sqrt(1.0 + s * s / a**2)
        v = 1.0 / (ald + s / a)  # sqrt(1+s^2/a^2) - s/a
        alpha = ald if kernel == "I" else als
        s2 = s * s
        with np.errstate(divide="ignore", invalid="ignore"):
            # small |s|: R/s^2 = P/D after rationalising, no s^2 cancellation
            p = 16.0 / a**2 - 16.0 + s2 * (16.0 / a**2 - 24.0) - 8.0 * s2**2 - s2**3
            d = 4.0 * ald * als + (2.0 + s2) ** 2
            eta = a if kernel == "I" else 1.0
            small = -p / (d * alpha) - eta * s
            # large |s|: sqrt(1+s^2) = s + u, sqrt(1+s^2/a^2) = s/a + v, and
            # s^3 u = s^2 (1 - u^2)/2, a s^3 v = a^2 s^2 (1 - v^2)/2, so that the
            # s^2 terms combine into the exact coefficient C(0)/eta.
            rest = 4.0 - 4.0 * s * u / a - 4.0 * s * v - 4.0 * u * v
            if kernel == "I":
                num = s2 * (4.0 - 4.0 / a - 0.5 * a**2) + 0.5 * a**2 * s2 * v * v + rest
            else:
                num = s2 * (3.5 - 4.0 / a) + 0.5 * s2 * u * u + rest
            large = num / (s2 * alpha)
        out = np.where(np.abs(s) <= 1.0, small, large)
    if not cplx:
        out = out.real
    return _out(out)


def impedance(kernel, s, nu=0.25):
    """M(s) = eta_hat s + L[C](s), eq. (23)-(24): traction transform = -(mu q/2) M(s) D_hat.

    M_I = -R/(s^2 sqrt(1+s^2/a^2)), M_II = -R/(s^2 sqrt(1+s^2)), M_III = sqrt(1+s^2).
    """
    _check_kernel(kernel)
    s_arr = np.asarray(s)
    return _out(eta_hat(kernel, nu) * s_arr + np.asarray(laplace(kernel, s_arr, nu)))


def branch_transform(kernel, s, A, B, a):
    """L[C_kernel](s) with explicit branch values A = sqrt(1+s^2), B = sqrt(1+s^2/a^2)
    (the form the branch cuts of history/fit.py and elastic/cuts.py evaluate)."""
    if kernel in FACE_KERNELS:
        return _face.branch_transform(kernel, s, A, B, a)
    _check_kernel(kernel)
    if kernel == "III":
        return A - s
    R = 4.0 * A * B - (2.0 + s * s) ** 2
    alpha = B if kernel == "I" else A
    eta = a if kernel == "I" else 1.0
    return -R / (s * s * alpha) - eta * s
