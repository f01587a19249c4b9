"""Discrete convolution weights xk_j of section 3.1, eqs. (44)-(48).

The discrete convolution is ``S_n = sum_{j=0}^n xk_j x_{n-j}`` (eq. 44 with
``x = d`` for the displacement formulation, eq. 48 with ``x = r`` for the
velocity formulation).  The kernel function ``K`` is ``C(T)`` (eq. 26) for the
displacement formulation and ``Z(T) = int_T^inf C`` for the velocity
formulation; ``gamma = q c_s dt``.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from . import kernels as _k
from .kernels import ALL_KERNELS, Z

__all__ = ["RULES", "FORMULATIONS", "halves_last", "convolution_weights", "product_weights", "product_taps"]

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
    _choice("kernel", kernel, _k.ALL_KERNELS)
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


# ---------------------------------------------------------------------------- product integration
def _poisson(value) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InputError("nu", f"must be a number in (-1, 0.5), got {value!r}") from None
    if isinstance(value, bool) or not -1.0 < x < 0.5:
        raise InputError("nu", f"must be in (-1, 0.5), got {value!r}")
    return x


# Gauss-Legendre nodes on [0, 1] for the cell moments of Z (Z is entire; 10 nodes give
# ~1e-15 relative accuracy up to gamma = 3, where a cell spans 5 rad of the P wave)
GAUSS_U, GAUSS_W = np.polynomial.legendre.leggauss(10)
GAUSS_U = 0.5 * (GAUSS_U + 1.0)
GAUSS_W = 0.5 * GAUSS_W


def product_weights(kernel, gamma, j, *, nu=0.25, order=1, part="lag"):
    """Weights of the product-integration convolutions (velocity formulation), for an engine.

    The velocity history is interpolated between the samples r_k (order 1: linearly;
    order 3: cubic Lagrange through r_{k-1}..r_{k+2} on [t_k, t_{k+1}], quadratic through
    r_{n-2}, r_{n-1}, r_n on the newest cell and through r_0, r_1, r_2 on the oldest), and
    Z is integrated exactly (10-point Gauss-Legendre per cell of the closed-form Z)
    against the interpolant.  With these weights, at step n,

        S^v_n = sum_{m=0}^{n} W_m r_{n-m} + sum_{i=0}^{2} E_i(n) r_i          (i <= n)

    is ``(1/dt) int_0^{t_n} Z(q c_s (t_n - t')) r(t') dt'`` and the matching
    displacement (the exact integral of the same interpolant) is
    ``d_n = sum_{k=0}^{n} r_k - (r_n + r_0)/2`` (order 1, the trapezoid rule (50)) or
    ``d_n = sum_k r_k - (15 (r_n + r_0) - 4 (r_{n-1} + r_1) + (r_{n-2} + r_2)) / 24``
    (order 3, n >= 2; n = 1 is the trapezoid rule).  W_0 multiplies the current
    velocity; the E_i(n) vanish when the run starts at rest (r_0 = r_1 = r_2 = 0).

    part "lag": ``W_j``; part "start0", "start1", "start2": ``E_i(n)`` at ``n = j``.
    Broadcast over ``gamma >= 0`` and integer ``j >= 0``.
    """
    if kernel not in ALL_KERNELS:
        raise InputError("kernel", f"must be one of {', '.join(map(repr, ALL_KERNELS))}; got {kernel!r}")
    nu = _poisson(nu)
    if order not in (1, 3) or isinstance(order, bool):
        raise InputError("order", f"must be 1 or 3, got {order!r}")
    if part not in ("lag", "start0", "start1", "start2"):
        raise InputError("part", f"must be one of 'lag', 'start0', 'start1', 'start2'; got {part!r}")
    g = np.asarray(gamma, dtype=float)
    if not np.all(np.isfinite(g)) or np.any(g < 0):
        raise InputError("gamma", "must be finite and >= 0")
    jj = np.asarray(j)
    if jj.dtype.kind not in "iu" or np.any(jj < 0):
        raise InputError("j", "must hold non-negative integers")
    g, jj = np.broadcast_arrays(g, jj.astype(np.int64))

    def cell(c, basis, s):
        """weight of node s of `basis` on kernel cell c (0 where c < 0)."""
        cc = np.maximum(c, 0)
        M = _moments_at(kernel, g, cc, nu)
        return np.where(c >= 0, np.tensordot(basis[s], M, axes=1), 0.0)

    if order == 1:
        if part == "lag":
            out = np.where(jj >= 1, cell(jj - 1, LINEAR, 0), 0.0) + cell(jj, LINEAR, 1)
        elif part == "start0":
            out = np.where(jj >= 1, -cell(jj, LINEAR, 1), 0.0)
        else:
            out = np.zeros(g.shape)
        return out[()] if out.ndim == 0 else out
    n = jj
    if part == "lag":
        out = np.zeros(g.shape)
        for s in (-1, 0, 1, 2):
            c = n - 1 + s
            out = out + np.where(c >= 1, cell(c, CUBIC, s), 0.0)
        for m in (0, 1, 2):
            out = out + np.where(n == m, cell(np.zeros_like(n), NEWEST, 1 - m), 0.0)
    else:
        i = int(part[-1])
        out = cell(n - 1, OLDEST, i)
        for k, c in ((0, n - 1), (-1, n), (-2, n + 1)):  # cells with r_i at node i - k
            if -1 <= i - k <= 2:
                out = out - cell(c, CUBIC, i - k)
        out = np.where(n >= 2, out, 0.0)
        if i <= 1:  # n = 1: one linear cell; E_i(1) = exact weight minus the lag weight
            lag = product_weights(kernel, g, 1 - i, nu=nu, order=3, part="lag")
            out = np.where(n == 1, cell(np.zeros_like(n), LINEAR, i) - lag, out)
    return out[()] if out.ndim == 0 else out


def product_taps(kernel, gamma, taps, lag, *, nu=0.25):
    """The order-1 product weights of runs of consecutive lags, with every cell's moments
    computed once: for each ``gamma[u]`` the lags j = lag .. lag + taps[u] - 1, as two
    flat arrays (the runs one after the other) of ``product_weights(..., part="lag")`` and
    ``part="start0"`` at those (gamma, j) (the same numbers: W_j and E_0(j) share the cells
    j - 1 and j, which product_weights evaluates anew for each)."""
    if kernel not in ALL_KERNELS:
        raise InputError("kernel", f"must be one of {', '.join(map(repr, ALL_KERNELS))}; got {kernel!r}")
    nu = _poisson(nu)
    g = np.asarray(gamma, dtype=float).ravel()
    taps = np.asarray(taps, dtype=np.int64).ravel()
    lag = int(lag)
    if g.shape != taps.shape or np.any(taps < 0) or lag < 0:
        raise InputError("taps", "must be one non-negative count per gamma (and lag >= 0)")
    if not np.all(np.isfinite(g)) or np.any(g < 0):
        raise InputError("gamma", "must be finite and >= 0")
    first = max(lag - 1, 0)
    ncell = np.where(taps > 0, lag + taps - first, 0)          # cells first .. lag + taps - 1 per gamma
    cstart = np.concatenate([[0], np.cumsum(ncell)[:-1]]).astype(np.int64)
    uc = np.repeat(np.arange(g.size), ncell)
    cc = first + np.arange(uc.size) - cstart[uc]
    M = _moments_at(kernel, g[uc], cc, nu)
    # the same contraction as product_weights' cell(), on all cells at once
    a = np.tensordot(LINEAR[0], M, axes=1)   # node 0 of cell c: W_{c+1}'s part
    b = np.tensordot(LINEAR[1], M, axes=1)   # node 1 of cell c: W_c's part, -E_0(c)
    tstart = np.concatenate([[0], np.cumsum(taps)[:-1]]).astype(np.int64)
    ut = np.repeat(np.arange(g.size), taps)
    j = lag + np.arange(ut.size) - tstart[ut]
    here = cstart[ut] + (j - first)                          # cell j
    prev = here - 1                                          # cell j - 1 (j >= 1)
    has = j >= 1
    w = np.where(has, a[np.where(has, prev, here)], 0.0) + b[here]
    e0 = np.where(has, -b[here], 0.0)
    return w, e0


def _moments_at(kernel, g, c, nu):
    """M[p] = int_0^1 Z((c + 1 - u') g) u'^p du', p = 0..3, broadcast over g and c."""
    T = (np.asarray(c, dtype=float)[..., None] + 1.0 - GAUSS_U) * np.asarray(g, dtype=float)[..., None]
    z = np.asarray(Z(kernel, T, nu), dtype=float) * GAUSS_W
    return np.stack([z @ GAUSS_U**p for p in range(4)])


# Lagrange bases in u' = (t' - t_k)/dt on a velocity cell [t_k, t_{k+1}], as power
# coefficients (constant first), for the node offsets (in steps, relative to t_k)
def lagrange_basis(nodes):
    out = {}
    for xi in nodes:
        c = np.array([1.0])
        for xj in nodes:
            if xj != xi:
                c = np.polynomial.polynomial.polymul(c, np.array([-xj, 1.0])) / (xi - xj)
        out[xi] = np.pad(c, (0, 4 - c.size))
    return out


CUBIC = lagrange_basis((-1, 0, 1, 2))  # interior cells
NEWEST = lagrange_basis((-1, 0, 1))  # cell [t_{n-1}, t_n]: quadratic through n-2, n-1, n
OLDEST = lagrange_basis((0, 1, 2))  # cell [t_0, t_1]: quadratic through 0, 1, 2
LINEAR = lagrange_basis((0, 1))
