"""Discrete convolution weights xk_j of section 3.1, eqs. (44)-(48).

The discrete convolution is ``S_n = sum_{j=0}^n xk_j x_{n-j}`` (eq. 44 with
``x = d`` for the displacement formulation, eq. 48 with ``x = r`` for the
velocity formulation).  The kernel function ``K`` is ``C(T)`` (eq. 26) for the
displacement formulation and ``Z(T) = int_T^inf C`` for the velocity
formulation; ``gamma = q c_s dt``.
"""

from __future__ import annotations

import numpy as np

from . import kernels as _k

__all__ = ["RULES", "FORMULATIONS", "halves_last", "convolution_weights"]

RULES = ("discretized", "trapezoid", "simpson", "exact")
FORMULATIONS = ("displacement", "velocity")

# below this gamma the "exact" cell mean is taken from a 4-point Gauss rule on
# the cell (error ~ gamma^8) instead of the difference of antiderivatives,
# whose round-off grows like 1e-16 / gamma
_GAMMA_SMALL = 1e-3
_GL_X, _GL_W = np.polynomial.legendre.leggauss(4)


def _choice(name, value, allowed):
    if value not in allowed:
        raise ValueError(f"{name} must be one of {allowed}, got {value!r}")
    return value


def halves_last(rule):
    """True if the last weight xk_n must be halved by the caller (rule "discretized", eq. 45).

    Eq. (45) applies the trapezoidal end correction to both ends of the
    history: xk_0 = K(0)/2 is built into the weights, but xk_n = K(gamma n)/2
    depends on the current step n and is left to the caller.  Eqs. (46)-(47)
    and the exact rule have no such correction.
    """
    _choice("rule", rule, RULES)
    return rule == "discretized"


def convolution_weights(kernel, gamma, j, *, nu=0.25, rule="trapezoid",
                        formulation="displacement", simpson_n=4):
    """Weights xk_j of eqs. (45)-(47), broadcast over ``gamma`` (>= 0) and integer ``j`` (>= 0).

    rule "discretized" (45): xk_0 = K(0)/2, xk_j = K(gamma j) (last-term halving
    not applied, see `halves_last`); "trapezoid" (46): (K(gamma j) + K(gamma (j+1)))/2;
    "simpson" (47): composite Simpson mean of K over [gamma j, gamma (j+1)] with
    ``simpson_n`` (even) sub-intervals; "exact": the exact cell mean
    (I(gamma (j+1)) - I(gamma j))/gamma, I = int_0^T K (closed form for C and Z).
    K = C for formulation "displacement" (44), K = Z for "velocity" (48).
    At gamma = 0 every rule gives K(0) (K(0)/2 for j = 0 in "discretized").
    """
    _choice("kernel", kernel, _k.KERNELS)
    _choice("rule", rule, RULES)
    _choice("formulation", formulation, FORMULATIONS)
    if rule == "simpson":
        if (isinstance(simpson_n, bool) or not isinstance(simpson_n, (int, np.integer))
                or simpson_n < 2 or simpson_n % 2):
            raise ValueError(f"simpson_n must be an even integer >= 2, got {simpson_n!r}")
    _k.wave_speed_ratio(nu)  # validates nu

    gamma = np.asarray(gamma, dtype=float)
    if not np.all(np.isfinite(gamma)) or np.any(gamma < 0):
        raise ValueError("gamma must be finite and >= 0")
    j_arr = np.asarray(j)
    if j_arr.dtype.kind not in "iu":
        if j_arr.dtype.kind != "f" or not np.all(j_arr == np.round(j_arr)):
            raise ValueError("j must hold non-negative integers")
    if np.any(j_arr < 0):
        raise ValueError("j must hold non-negative integers")
    g, jj = np.broadcast_arrays(gamma, j_arr.astype(float))

    if formulation == "displacement":
        def K(T):
            return np.asarray(_k.C(kernel, T, nu), dtype=float)

        def I(T):
            return np.asarray(_k.integral(kernel, T, nu), dtype=float)
    else:
        def K(T):
            return np.asarray(_k.Z(kernel, T, nu), dtype=float)

        def I(T):
            return np.asarray(_k.Z_integral(kernel, T, nu), dtype=float)

    if rule == "discretized":
        out = K(g * jj)
        out = np.where(jj == 0, 0.5 * out, out)
    elif rule == "trapezoid":
        out = 0.5 * (K(g * jj) + K(g * (jj + 1.0)))
    elif rule == "simpson":
        n = int(simpson_n)
        out = K(g * jj) + K(g * (jj + 1.0))
        for m in range(1, n):
            out = out + (4.0 if m % 2 else 2.0) * K(g * (jj + m / n))
        out = out / (3.0 * n)
    else:  # exact
        big = g >= _GAMMA_SMALL
        out = np.empty(g.shape)
        if np.any(big):
            gb, jb = g[big], jj[big]
            out[big] = (I(gb * (jb + 1.0)) - I(gb * jb)) / gb
        if np.any(~big):
            gs, js = g[~big], jj[~big]
            acc = np.zeros(gs.shape)
            for xg, wg in zip(_GL_X, _GL_W):
                acc += 0.5 * wg * K(gs * (js + 0.5 * (1.0 + xg)))
            out[~big] = acc
    return out[()] if out.ndim == 0 else out
