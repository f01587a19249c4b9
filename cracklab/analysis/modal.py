"""Single Fourier mode under a step load: the modal analysis of section 3.1.

One mode of wave number q of a traction-free plane is loaded by a unit step
``tau0 H(t)``.  With ``T = q c_s t``, ``gamma = q c_s dt`` and the radiation
damping coefficient ``eta mu / (2 c_s)`` (``eta = a = c_d/c_s`` for mode I,
``eta = 1`` for modes II and III), the traction-free condition reads

    0 = tau0 - (eta mu / 2 c_s) V(t) + F(t),
    F(t) = -(mu q / 2) int_0^t C(q c_s (t - t')) D(t') q c_s dt'          (32)

so that ``V(0+) = 2 tau0 c_s / (eta mu)`` and ``r = V / V(0+) = 1 + F / tau0``.

Displacement formulation.  With ``D(t_n) = V(0+) dt d_n`` and
``int C(T - T') D dT' ~ gamma V(0+) dt S^d_n``, ``S^d_n = sum_{j=0}^n xk_j d_{n-j}``:

    F / tau0 = -(mu q / 2 tau0) gamma V(0+) dt S^d_n = -(gamma^2 / eta) S^d_n,
    r_n = 1 - (gamma^2 / eta) S^d_n.                                     (42)

For mode I (eta = a) this is eq. (42) with c_s/c_d = 1/a.

Velocity formulation.  Integrating (32) by parts with
``Z(T) = int_T^inf C`` (so ``d/dt' Z(q c_s (t - t')) = q c_s C``) and D(0) = 0:

    int_0^t C(q c_s (t-t')) D(t') q c_s dt' = Z(0) D(t) - int_0^t Z(q c_s (t-t')) V(t') dt'.

Then ``-(mu q / 2 tau0) Z(0) V(0+) dt d_n = -(gamma / eta) Z(0) d_n`` and
``(mu q / 2 tau0) (gamma / q c_s) V(0+) S^v_n = (gamma / eta) S^v_n`` with
``S^v_n = sum_{j=0}^n xk_j r_{n-j}`` built on the Z kernel, so

    r_n = 1 - (gamma / eta) Z(0) d_n + (gamma / eta) S^v_n.              (43)

``Z(0) = int_0^inf C`` is ``1/(1-nu) = 2(1 - 1/a^2)`` for modes I and II and 1 for
mode III; for mode I, ``(gamma/a) 2 (1 - 1/a^2) d_n`` is the
``2 gamma (c_s/c_d)(1 - c_s^2/c_d^2) d_n`` term of eq. (43).

Time integration: explicit ``d_{n+1} = d_n + r_n`` (49) or semi-implicit
``d_{n+1} = d_n + (r_n + r_{n+1})/2`` (50), with ``d_0 = 0``, ``r_0 = 1``.  Wherever
``r_n`` appears on the right-hand side (through ``xk_0`` in the velocity
formulation, through ``d_n`` in the semi-implicit scheme) the relation is linear in
``r_n`` and is solved exactly: ``r_n = A_n / (1 - B)`` with the constant coefficient
``B`` given by :func:`implicit_coefficient`.  For the velocity formulation with the
discretized kernel (``xk_0 = Z(0)/2``) and semi-implicit integration,
``B = (gamma/eta) (xk_0 - Z(0)/2) = 0``: the scheme is explicit, as the paper notes.

The convolution sums run over ``j = 0..n`` as printed in (44) and (48).  For the
discretized kernel (45) the last weight ``xk_n`` is halved at each step.  With the
pre-integrated kernels in the velocity formulation the ``j = n`` term multiplies
``r_0 = 1`` over the interval ``[-dt, 0]``, as in the printed sum; this is an
``O(gamma)`` error of the same order as the schemes themselves.

Measured behaviour (mode I, nu = 1/4).  Substituting (50) into (43) with the
discretized kernel gives ``r_n = 1 - (gamma/eta) sum_{j=1}^n w_j I(j gamma) r_{n-j}``
(``I = int_0^T C = Z(0) - Z``, trapezoid weights ``w_j``), and summing (42) by parts
with (49) gives the same recurrence with ``I`` replaced by the pre-integrated sums
``gamma sum_{j<m} xk_j``.  With the exact Z used here, the velocity/discretized/
semi-implicit scheme therefore has the same long-time growth as
displacement/simpson (or exact)/explicit: slow growth, about 1e-3 per unit T at
gamma = 0.5, for 0 < gamma <~ 2.2, and decay at 2.3.  Only the trapezoid
pre-integration (46) adds enough damping for displacement/trapezoid/explicit to
decay for all gamma <= 2.3; it blows up from about 2.35.

Product integration and predictor-corrector (docs/reference/stability.md).  The schemes above
let the mode II Rayleigh oscillation grow (about 9.3e-3 gamma^2 per unit T for the
default displacement/trapezoid/explicit scheme): sampling ``I = int_0^T C``, whose slope
jumps to C(0) at T = 0, and the trapezoid pre-integration each shift the discrete
Rayleigh root by ``-C(0) gamma^2/12``, which beats the damping of the scheme in mode II.
``convolution="product"`` / ``"product-cubic"`` (velocity formulation only) integrate Z
exactly against the piecewise-linear / piecewise-cubic interpolant of the velocity
history, with d_n the exact integral of the same interpolant (:func:`product_weights`).
The current velocity then enters only through a small instantaneous weight, which
``integration="predictor-corrector"`` applies to a predicted velocity (predictor:
velocity held over the step; one corrector pass).  ``STABLE_SCHEME`` (cubic, one pass)
is fourth order and does not grow for modes I, II, III up to gamma = 2.6 (3.0 tested);
the linear one is second order and stable to 2.5.  "explicit" with a product
convolution is the predictor alone and "semi-implicit" solves for r_n (not usable on a
grid, where the instantaneous weight is non-local).

Note: read the coordinate as ``r["T"]``; ``r.T`` is the xarray transpose.
"""
from __future__ import annotations

import math
from itertools import product

import numpy as np
import xarray as xr

from ..errors import InputError
from ..solver.schemes import scheme_of

__all__ = [
    "MODES",
    "FORMULATIONS",
    "CONVOLUTIONS",
    "INTEGRATIONS",
    "SCHEMES",
    "STABLE_SCHEME",
    "PRODUCT_CONVOLUTIONS",
    "MAX_STEPS",
    "modal_response",
    "scheme_response",
    "implicit_coefficient",
    "product_weights",
    "eta_hat",
    "long_time_amplitude",
    "long_time_period",
    "precision_factor",
]

MODES = ("I", "II", "III")
FORMULATIONS = ("displacement", "velocity")
#: the paper's three convolution rules; "exact" (exactly pre-integrated kernel) is
#: accepted as well when cracklab.elastic.weights provides it
CONVOLUTIONS = ("discretized", "trapezoid", "simpson")
INTEGRATIONS = ("explicit", "semi-implicit")
#: the 12 (formulation, convolution, integration) implementations of section 3.1
SCHEMES = list(product(FORMULATIONS, CONVOLUTIONS, INTEGRATIONS))
#: refuse runs with more time steps than this (the work is O(N^2))
MAX_STEPS = 200_000

#: product integration of Z against the interpolated velocity: piecewise linear
#: ("product", second order) or piecewise cubic ("product-cubic", fourth order)
PRODUCT_CONVOLUTIONS = ("product", "product-cubic")
_ALL_CONVOLUTIONS = CONVOLUTIONS + ("exact",) + PRODUCT_CONVOLUTIONS
_ALL_INTEGRATIONS = INTEGRATIONS + ("predictor-corrector",)
#: the most accurate scheme of the single-mode study that does not grow (docs/reference/stability.md):
#: velocity formulation, product integration of Z against the piecewise-cubic velocity, and
#: one predictor-corrector pass of the semi-implicit update (50); the grid's "product"
#: formulation is its piecewise-linear variant ("velocity", "product", "predictor-corrector")
STABLE_SCHEME = ("velocity", "product-cubic", "predictor-corrector")


# ----------------------------------------------------------------------------- checks
def _choice(field: str, value, accepted) -> str:
    if isinstance(value, str):
        v = value.strip()
        if field == "integration":
            v = v.replace("_", "-")
        if v in accepted:
            return v
    raise InputError(field, f"must be one of {', '.join(map(repr, accepted))}; got {value!r}")


def _finite(field: str, value) -> float:
    if isinstance(value, bool):
        raise InputError(field, f"must be a number, got {value!r}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(field, f"must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise InputError(field, f"must be finite, got {value!r}")
    return x


def _positive(field: str, value) -> float:
    x = _finite(field, value)
    if x <= 0.0:
        raise InputError(field, f"must be > 0, got {value!r}")
    return x


def _poisson(value) -> float:
    x = _finite("nu", value)
    if not -1.0 < x < 0.5:
        raise InputError("nu", f"must be in (-1, 0.5), got {value!r}")
    return x


def _simpson_n(value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise InputError("simpson_n", f"must be an even integer >= 2, got {value!r}")
    if value < 2 or value % 2:
        raise InputError("simpson_n", f"must be an even integer >= 2, got {value!r}")
    return int(value)


def _passes(value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise InputError("corrector_passes", f"must be an integer >= 1, got {value!r}")
    return int(value)


def _scheme(formulation, convolution, integration):
    formulation = _choice("formulation", formulation, FORMULATIONS)
    convolution = _choice("convolution", convolution, _ALL_CONVOLUTIONS)
    integration = _choice("integration", integration, _ALL_INTEGRATIONS)
    if convolution in PRODUCT_CONVOLUTIONS and formulation != "velocity":
        raise InputError("convolution", f"{convolution!r} is implemented for the velocity formulation "
                         "only (formulation='velocity')")
    return formulation, convolution, integration


def _n_steps(gamma: float, T_end: float) -> int:
    # ceil, tolerant of rounding in T_end / gamma (e.g. 0.3 / 0.1)
    ratio = T_end / gamma
    n = int(math.ceil(ratio - 1e-9 * max(1.0, ratio)))
    return max(n, 1)


# ----------------------------------------------------------------------------- model
def eta_hat(mode: str, nu: float) -> float:
    """Radiation damping factor relative to mu/(2 c_s): a = c_d/c_s for mode I, else 1."""
    mode = _choice("mode", mode, MODES)
    nu = _poisson(nu)
    from ..elastic.kernels import eta_hat as _eta

    return float(_eta(mode, nu))


def _weights(mode, gamma, N, nu, formulation, convolution, simpson_n):
    from ..elastic.weights import convolution_weights

    j = np.arange(N + 1)
    kwargs = dict(nu=nu, rule=convolution, formulation=formulation)
    if convolution == "simpson":
        kwargs["simpson_n"] = simpson_n
    w = np.asarray(convolution_weights(mode, gamma, j, **kwargs), dtype=float)
    if w.shape != (N + 1,):
        raise RuntimeError(f"convolution_weights returned shape {w.shape}, expected {(N + 1,)}")
    return w


from ..elastic.weights import (  # noqa: E402  (the product weights live with the solver)
    CUBIC as _CUBIC,
    GAUSS_U as _GLU,
    GAUSS_W as _GLW,
    LINEAR as _LINEAR,
    NEWEST as _NEWEST,
    OLDEST as _OLDEST,
    lagrange_basis as _lagrange,
    product_weights,
)

_POWERS = 1.0 / np.arange(1, 5)  # int_0^1 u'^p du'


def _z_moments(mode, gamma, ncell, nu):
    """M[p, c] = int_0^1 Z((c + 1 - u') gamma) u'^p du', p = 0..3, cells c = 0..ncell-1.

    Cell c of the kernel (T in [c gamma, (c+1) gamma]) is the velocity cell
    [t_k, t_{k+1}], k = n - 1 - c, at step n; u' runs forward in time on it.
    """
    from ..elastic.kernels import Z

    T = (np.arange(ncell)[:, None] + 1.0 - _GLU[None, :]) * gamma
    z = np.asarray(Z(mode, T, nu), dtype=float) * _GLW
    return np.stack([z @ _GLU**p for p in range(4)])


def product_tables(mode, gamma, N, nu, order):
    """Lag weights W_m, start-up corrections E[i, n] (samples r_0, r_1, r_2 at step n) and
    the end corrections of the displacement sum, for product integration of order 1 or 3.

    At step n: S^v_n = sum_{m=0}^n W_m r_{n-m} + sum_{i<=2, i<=n} E[i, n] r_i and
    d_n = sum_{k=0}^n r_k + sum_j D_new[j] r_{n-j} + sum_i D_old[i] r_i (n >= 2 for order 3).
    """
    M = _z_moments(mode, gamma, N + 3, nu)
    E = np.zeros((3, N + 1))
    if order == 1:
        right = _LINEAR[0] @ M  # weight of the left node r_k on cell c
        left = _LINEAR[1] @ M  # weight of the right node r_{k+1}
        W = np.zeros(N + 1)
        W[0] = left[0]
        W[1:] = right[:N] + left[1:N + 1]
        # r_0: only the cell [t_0, t_1] (cell n-1), not the one before t = 0 (cell n)
        E[0, 1:] = -left[np.arange(2, N + 2) - 1]
        return W, E, (-0.5,), (-0.5,)
    A = {s: _CUBIC[s] @ M for s in (-1, 0, 1, 2)}
    B_new = {s: float(_NEWEST[s] @ M[:, 0]) for s in (-1, 0, 1)}
    B_old = {s: _OLDEST[s] @ M for s in (0, 1, 2)}
    W = np.zeros(N + 1)
    m = np.arange(N + 1)
    for s in (-1, 0, 1, 2):
        c = m - 1 + s
        ok = c >= 1
        W[ok] += A[s][c[ok]]
    for j in (0, 1, 2):
        W[j] += B_new[1 - j]
    # replace cell n-1 (k = 0) by the quadratic through r_0, r_1, r_2 and drop the cells
    # n and n+1 (before t = 0) that the lag weights include
    n = np.arange(2, N + 1)
    E[0, 2:] = B_old[0][n - 1] - A[0][n - 1] - A[1][n] - A[2][n + 1]
    E[1, 2:] = B_old[1][n - 1] - A[1][n - 1] - A[2][n]
    E[2, 2:] = B_old[2][n - 1] - A[2][n - 1]
    if N >= 1:
        # n = 1: a single cell, linear
        E[1, 1] = float(_LINEAR[1] @ M[:, 0]) - W[0]
        E[0, 1] = float(_LINEAR[0] @ M[:, 0]) - W[1]
    d_new = (-15.0 / 24.0, 4.0 / 24.0, -1.0 / 24.0)
    return W, E, d_new, d_new


def _run_product(mode, gamma, N, nu, order, integration, passes):
    """Velocity formulation (43) with product integration; returns (r_0..r_N, overflow T or None).

    Step n: S^v_n = S_known + cS r_n and d_n = D_known + cD r_n (see
    :func:`product_weights`), r_n = A + B r_n with
    A = 1 - (gamma/eta) Z(0) D_known + (gamma/eta) S_known, B = (gamma/eta) (cS - Z(0) cD).
    """
    eta = eta_hat(mode, nu)
    g = gamma / eta
    z0 = _static(mode, nu)
    W, E, d_new, d_old = product_tables(mode, gamma, N, nu, order)
    wr = np.ascontiguousarray(W[::-1])  # wr[N - m] = W_m
    r = np.full(N + 1, np.nan)
    r[0] = 1.0
    total = 1.0  # sum_{k<n} r_k
    solve = integration == "semi-implicit"
    npass = passes + 1 if integration == "predictor-corrector" else 1
    W0 = float(W[0])
    dn = [float(c) for c in d_new] + [0.0] * (3 - len(d_new))
    do = [float(c) for c in d_old] + [0.0] * (3 - len(d_old))
    start_S = None  # sum_i E[i, n] r_i for n >= 3, once r_0..r_2 are known
    start_D = 0.0
    r1 = r2 = 0.0  # r_{n-1}, r_{n-2} as floats
    bad_from = None
    with np.errstate(over="ignore", invalid="ignore"):
        for n in range(1, N + 1):
            S_known = float(np.dot(wr[N - n:N], r[:n]))
            if n >= 3:
                if start_S is None:
                    start_S = (E[0] * r[0] + E[1] * r[1] + E[2] * r[2]).tolist()
                    start_D = float(do[0] * r[0] + do[1] * r[1] + do[2] * r[2])
                    B_coef = g * (W0 - z0 * (1.0 + dn[0]))
                S_known += start_S[n]
                D_known = total + dn[1] * r1 + dn[2] * r2 + start_D
                A = 1.0 - g * z0 * D_known + g * S_known
                if solve:
                    rn = A / (1.0 - B_coef)
                else:
                    rn = r1
                    for _ in range(npass):
                        rn = A + B_coef * rn
                r[n] = rn
                total += rn
                r1, r2 = rn, r1
                if not math.isfinite(rn):
                    r[n:] = np.nan
                    bad_from = n * gamma
                    break
                continue
            else:
                cS = W0
                for i in range(n + 1):
                    if i == n:
                        cS += E[i, n]
                    else:
                        S_known += E[i, n] * r[i]
                if order == 3 and n == 1:
                    D_known, cD = 0.5 * r[0], 0.5
                else:
                    D_known, cD = total, 1.0 + dn[0]
                    for j in (1, 2):
                        if n - j >= 0:
                            D_known += dn[j] * r[n - j]
                    for i in range(3):
                        if i == n:
                            cD += do[i]
                        elif i < n:
                            D_known += do[i] * r[i]
            A = 1.0 - g * z0 * D_known + g * S_known
            B = g * (cS - z0 * cD)
            if solve:
                rn = A / (1.0 - B)
            else:
                # predictor: velocity held over the step (r_n -> r_{n-1}); then the
                # corrector passes, each an explicit evaluation at the latest value
                rn = r[n - 1]
                for _ in range(npass):
                    rn = A + B * rn
            r[n] = rn
            total += float(rn)
            r1, r2 = float(rn), float(r[n - 1])
            if not math.isfinite(rn):
                r[n:] = np.nan
                bad_from = n * gamma
                break
    return r, bad_from


def _halves_last(convolution: str) -> bool:
    from ..elastic.weights import halves_last

    return bool(halves_last(convolution))


def _static(mode, nu) -> float:
    from ..elastic.kernels import static_integral

    return float(static_integral(mode, nu))


def _coefficients(mode, gamma, nu, formulation, integration, xk0):
    """(prefactor g, Z(0) or None, B) for the recurrence; B is the r_n coefficient."""
    eta = eta_hat(mode, nu)
    if integration == "predictor-corrector":
        integration = "semi-implicit"  # the corrector is (50), applied to a predicted r_n
    if formulation == "displacement":
        g = gamma * gamma / eta
        # r_n = 1 - g (xk_0 d_n + hist); d_n holds r_n/2 in the semi-implicit scheme
        B = 0.0 if integration == "explicit" else -0.5 * g * xk0
        return g, None, B
    g = gamma / eta
    z0 = _static(mode, nu)
    # r_n = 1 - g Z0 d_n + g (xk_0 r_n + hist)
    B = g * xk0 if integration == "explicit" else g * (xk0 - 0.5 * z0)
    return g, z0, B


def scheme_response(scheme, mode, *, gamma, T_end, nu=0.25) -> xr.DataArray:
    """:func:`modal_response` of a grid time scheme (``scheme``: a name of
    ``cracklab.solver.schemes.SCHEMES`` or the scheme), with the single-mode recurrence the
    scheme declares (``Scheme.modal``: formulation, convolution, integration)."""
    formulation, convolution, integration = scheme_of(scheme).modal
    return modal_response(mode, gamma=gamma, T_end=T_end, nu=nu, formulation=formulation,
                          convolution=convolution, integration=integration)


def implicit_coefficient(mode, *, gamma, nu=0.25, formulation="displacement",
                         convolution="trapezoid", integration="explicit", simpson_n=4) -> float:
    """Coefficient B of the unknown r_n on the right-hand side of the discrete modal equation.

    Each step solves ``r_n = A_n + B r_n``.  B = 0 means the step is explicit; it is
    zero for displacement + explicit and (up to rounding) for velocity + discretized
    + semi-implicit, where the two r_n contributions cancel.  For
    ``integration="predictor-corrector"`` B is the coefficient of the semi-implicit
    corrector (50), which is applied to the predicted r_n instead of being solved for.
    """
    mode = _choice("mode", mode, MODES)
    gamma = _positive("gamma", gamma)
    nu = _poisson(nu)
    formulation, convolution, integration = _scheme(formulation, convolution, integration)
    simpson_n = _simpson_n(simpson_n)
    if convolution in PRODUCT_CONVOLUTIONS:
        if integration == "explicit":
            return 0.0  # the predictor alone: velocity held over the step
        order = 1 if convolution == "product" else 3
        W0 = float(product_weights(mode, gamma, 0, nu=nu, order=order, part="lag"))
        cD = 0.5 if order == 1 else 9.0 / 24.0  # weight of r_n in d_n (steady, n >= 3)
        return float(gamma / eta_hat(mode, nu) * (W0 - _static(mode, nu) * cD))
    xk0 = _weights(mode, gamma, 0, nu, formulation, convolution, simpson_n)[0]
    return float(_coefficients(mode, gamma, nu, formulation, integration, xk0)[2])


def modal_response(mode, *, gamma, T_end, nu=0.25, formulation="displacement",
                   convolution="trapezoid", integration="explicit", simpson_n=4,
                   corrector_passes=1) -> xr.DataArray:
    """Velocity ratio r = V(t)/V(0+) of one Fourier mode under a unit step load.

    Parameters
    ----------
    mode : {"I", "II", "III"}
        Kernel C_I, C_II or C_III (eta = a, 1, 1).
    gamma : float > 0
        ``q c_s dt``.
    T_end : float > 0
        Final ``T = q c_s t``; ``N = ceil(T_end / gamma)`` steps are taken.
    nu : float in (-1, 0.5)
    formulation : {"displacement", "velocity"}
        Eq. (42) with C, or eq. (43) with Z = int_T^inf C.
    convolution : {"discretized", "trapezoid", "simpson", "exact", "product"}
        Weights of eqs. (45), (46), (47) (or exactly pre-integrated kernel), or
        "product" (velocity formulation only): Z integrated exactly against the
        piecewise-linear interpolation of the velocity (:func:`product_weights`).
    integration : {"explicit", "semi-implicit", "predictor-corrector"}
        Eq. (49) or (50), or "predictor-corrector": the predictor is the step with the
        unknown r_n replaced by r_{n-1} (for the velocity formulation: velocity held over
        the step, ``d*_n = d_{n-1} + r_{n-1}``), followed by ``corrector_passes``
        evaluations of the semi-implicit step (50) at the latest prediction.  Every
        pass is explicit (on the grid: one FFT pair and a pointwise law solve).
    simpson_n : even int >= 2
        Sub-intervals of the Simpson pre-integration (47).
    corrector_passes : int >= 1
        Corrector passes of the predictor-corrector integration (1: PECE).  Ignored
        by the other integrations.  Two passes are less stable than one (mode II
        grows from gamma ~ 2; docs/reference/stability.md).

    Returns
    -------
    xarray.DataArray named "r" on coordinate "T" = n gamma, n = 0..N.  If the
    recurrence overflows, the remaining values are NaN and the attribute
    ``nonfinite_from_T`` records where.  See the module docstring for the recurrences.

    Notes
    -----
    The grid's product scheme is (velocity, product, predictor-corrector, one pass):
    second order, and its single-mode response does not grow for modes I, II, III up
    to gamma = 2.5. :data:`STABLE_SCHEME` is its piecewise-cubic variant (fourth order,
    up to gamma = 2.6), which runs here only (docs/reference/stability.md).
    """
    mode = _choice("mode", mode, MODES)
    gamma = _positive("gamma", gamma)
    T_end = _positive("T_end", T_end)
    nu = _poisson(nu)
    formulation, convolution, integration = _scheme(formulation, convolution, integration)
    simpson_n = _simpson_n(simpson_n)
    passes = _passes(corrector_passes)
    N = _n_steps(gamma, T_end)
    if N > MAX_STEPS:
        raise InputError(
            "T_end",
            f"T_end/gamma = {N} steps exceeds the limit of {MAX_STEPS} (the work grows as N^2); "
            "use a larger gamma or a smaller T_end",
        )

    if convolution in PRODUCT_CONVOLUTIONS:
        r, bad_from = _run_product(mode, gamma, N, nu, 1 if convolution == "product" else 3,
                                   integration, passes)
        return _as_dataarray(r, bad_from, mode, gamma, nu, formulation, convolution, integration,
                             simpson_n, passes)
    w = _weights(mode, gamma, N, nu, formulation, convolution, simpson_n)
    halve = _halves_last(convolution)
    g, z0, B = _coefficients(mode, gamma, nu, formulation, integration, w[0])
    corrector = integration == "predictor-corrector"
    if 1.0 - B == 0.0 and not corrector:
        raise InputError("gamma", f"the step equation is singular for gamma = {gamma!r} with this scheme")
    inv = 1.0 / (1.0 - B) if not corrector else None
    explicit = integration == "explicit"
    displacement = formulation == "displacement"

    r = np.full(N + 1, np.nan)
    d = np.zeros(N + 1)
    r[0] = 1.0
    # wr[N - n + i] = xk_{n-i}: the history sum is a dot product of contiguous slices
    wr = np.ascontiguousarray(w[1:][::-1])
    bad_from = None
    with np.errstate(over="ignore", invalid="ignore"):
        for n in range(1, N + 1):
            # known history x_{n-1}, ..., x_0 against xk_1 .. xk_n
            x = d if displacement else r
            hist = float(np.dot(wr[N - n:], x[:n]))
            if halve:
                hist -= 0.5 * w[n] * x[0]
            if explicit:
                dn_known = d[n - 1] + r[n - 1]  # = d_n
            else:
                dn_known = d[n - 1] + 0.5 * r[n - 1]  # d_n = this + r_n / 2
            if displacement:
                A = 1.0 - g * (w[0] * dn_known + hist)
            else:
                A = 1.0 - g * z0 * dn_known + g * hist
            if corrector:
                # predictor: r_n -> r_{n-1}; then `passes` corrector evaluations of (50)
                rn = r[n - 1]
                for _ in range(passes + 1):
                    rn = A + B * rn
            else:
                rn = A * inv
            r[n] = rn
            d[n] = dn_known if explicit else dn_known + 0.5 * rn
            if not math.isfinite(rn):
                r[n:] = np.nan
                bad_from = n * gamma
                break

    return _as_dataarray(r, bad_from, mode, gamma, nu, formulation, convolution, integration,
                         simpson_n, passes)


def _as_dataarray(r, bad_from, mode, gamma, nu, formulation, convolution, integration, simpson_n,
                  passes) -> xr.DataArray:
    corrector = integration == "predictor-corrector"
    N = r.size - 1
    attrs = {
        "mode": mode,
        "gamma": gamma,
        "nu": nu,
        "formulation": formulation,
        "convolution": convolution,
        "integration": integration,
        "long_name": "velocity ratio V(t)/V(0+) of a single Fourier mode under a step load",
        "units": "1",
    }
    if convolution == "simpson":
        attrs["simpson_n"] = simpson_n
    if corrector:
        attrs["corrector_passes"] = passes
    if bad_from is not None:
        attrs["nonfinite_from_T"] = bad_from
    T = np.arange(N + 1) * gamma
    return xr.DataArray(
        r,
        dims=("T",),
        coords={"T": ("T", T, {"long_name": "q c_s t", "units": "1"})},
        name="r",
        attrs=attrs,
    )


# ----------------------------------------------------------------------------- long time
def _rayleigh_ratio(nu: float) -> float:
    from ..elastic.waves import rayleigh_speed_ratio

    return float(rayleigh_speed_ratio(nu))


def long_time_amplitude(mode, nu=0.25) -> float:
    """Amplitude A of the long-time form r ~ A sin(s_R T) for modes I and II (Appendix B).

    In T and s = p/(q c_s), L[r](s) = eta / M(s) with the impedance
    ``M(s) = eta s + L[C](s)`` (:func:`cracklab.elastic.kernels.impedance`).  The poles
    ``s = +- i s_R`` give ``r ~ 2 Re[eta e^{i s_R T} / M'(i s_R)]``; M is real on the
    imaginary axis below the branch points and ``M'(iy) = -i dM(iy)/dy``, so
    ``A = -2 eta / (dM(iy)/dy)`` at ``y = s_R``.  The value is taken from
    :func:`cracklab.analysis.exact.modal_long_time_amplitude`: 0.5844 (mode I, eq. B.5) and
    0.1566 (mode II) at nu = 1/4.  Mode III has no Rayleigh pole (r = J0(T)).
    """
    mode = _choice("mode", mode, ("I", "II"))
    nu = _poisson(nu)
    from .exact import modal_long_time_amplitude

    return float(modal_long_time_amplitude(nu, mode=mode))


def long_time_period(mode, nu=0.25) -> float:
    """Period in T of the long-time oscillation: 2 pi / (c_R/c_s) for I and II, 2 pi for III."""
    mode = _choice("mode", mode, MODES)
    nu = _poisson(nu)
    if mode == "III":
        return 2.0 * math.pi
    return 2.0 * math.pi / _rayleigh_ratio(nu)


def envelope_growth(r, *, t0=None) -> float:
    """Growth per unit T of the envelope of a response of :func:`modal_response`: the slope
    of ln(max |r| per period) against T over [t0, T_end] (default t0 = T_end / 2), the
    period being that of the long-time oscillation (2 pi / s_R for modes I and II, 2 pi for
    mode III); for mode III, |r| sqrt(T), the rate relative to the T^-1/2 decay of J0.
    inf when the response overflowed. The measure of docs/reference/stability.md."""
    mode, nu = r.attrs["mode"], r.attrs["nu"]
    T, y = r["T"].values, np.abs(r.values)
    if not np.all(np.isfinite(y)):
        return math.inf
    if mode == "III":
        y = y * np.sqrt(T)
    P = long_time_period(mode, nu)
    start = 0.5 * T[-1] if t0 is None else float(t0)
    tm, ym = [], []
    for a in np.arange(start, T[-1] - P + 1e-9, P):
        sel = (T >= a) & (T < a + P)
        k = int(np.argmax(y[sel]))
        tm.append(T[sel][k])
        ym.append(y[sel][k])
    return float(np.polyfit(tm, np.log(ym), 1)[0])


def precision_factor(r, nu=None, period=10, *, mode=None, method="max") -> float:
    """Precision factor of Fig. 6: numerical over exact long-time amplitude in one period.

    ``r`` is a DataArray from :func:`modal_response` (its attrs give ``mode`` and
    ``nu`` unless passed).  The window is ``[(period-1) P, period P]`` with P from
    :func:`long_time_period`.  For modes I and II the reference is
    :func:`long_time_amplitude`; for mode III the J0 envelope ``sqrt(2/(pi T))``, i.e.
    the factor is computed on ``r sqrt(pi T / 2)``.

    method "max" (the paper's definition): the largest |r| sampled in the window.
    At large gamma the window holds few samples, so this under-reads the amplitude
    by up to 1 - cos(gamma s_R / 2).  method "fit": least-squares amplitude of
    ``c cos(w T) + s sin(w T)`` at the exact long-time frequency over the window.
    A run that overflowed gives ``inf``.
    """
    if not isinstance(r, xr.DataArray) or "T" not in r.coords:
        raise InputError("r", "must be a DataArray with coordinate 'T' (from modal_response)")
    mode = _choice("mode", mode if mode is not None else r.attrs.get("mode"), MODES)
    nu = _poisson(nu if nu is not None else r.attrs.get("nu", 0.25))
    if isinstance(period, bool) or not isinstance(period, (int, np.integer)) or period < 1:
        raise InputError("period", f"must be an integer >= 1, got {period!r}")
    method = _choice("method", method, ("max", "fit"))
    P = long_time_period(mode, nu)
    T = np.asarray(r["T"].values, dtype=float)
    y = np.asarray(r.values, dtype=float)
    t0, t1 = (period - 1) * P, period * P
    if T[-1] < t1 * (1 - 1e-12):
        raise InputError("period", f"period {period} ends at T = {t1:.6g} but r stops at T = {T[-1]:.6g}")
    sel = (T >= t0) & (T <= t1)
    if not np.all(np.isfinite(y[T <= t1])):
        return math.inf
    Tw, yw = T[sel], y[sel]
    if mode == "III":
        yw = yw * np.sqrt(np.pi * Tw / 2.0)
        ref = 1.0
    else:
        ref = long_time_amplitude(mode, nu)
    if method == "max":
        if Tw.size == 0:
            raise InputError("r", f"no sample in the window T in [{t0:.6g}, {t1:.6g}]")
        return float(np.max(np.abs(yw)) / ref)
    if Tw.size < 3:
        raise InputError("r", f"fewer than 3 samples in the window T in [{t0:.6g}, {t1:.6g}] for a fit")
    om = 2.0 * np.pi / P
    M = np.column_stack([np.cos(om * Tw), np.sin(om * Tw)])
    coef, *_ = np.linalg.lstsq(M, yw, rcond=None)
    return float(np.hypot(*coef) / ref)
