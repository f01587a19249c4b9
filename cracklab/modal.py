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

Note: read the coordinate as ``r["T"]``; ``r.T`` is the xarray transpose.
"""
from __future__ import annotations

import math
from itertools import product

import numpy as np
import xarray as xr

from .errors import InputError

__all__ = [
    "MODES",
    "FORMULATIONS",
    "CONVOLUTIONS",
    "INTEGRATIONS",
    "SCHEMES",
    "MAX_STEPS",
    "modal_response",
    "implicit_coefficient",
    "eta_hat",
    "long_time_amplitude",
    "long_time_period",
    "precision_factor",
]

MODES = ("I", "II", "III")
FORMULATIONS = ("displacement", "velocity")
#: the paper's three convolution rules; "exact" (exactly pre-integrated kernel) is
#: accepted as well when cracklab.weights provides it
CONVOLUTIONS = ("discretized", "trapezoid", "simpson")
INTEGRATIONS = ("explicit", "semi-implicit")
#: the 12 (formulation, convolution, integration) implementations of section 3.1
SCHEMES = list(product(FORMULATIONS, CONVOLUTIONS, INTEGRATIONS))
#: refuse runs with more time steps than this (the work is O(N^2))
MAX_STEPS = 200_000

_ALL_CONVOLUTIONS = CONVOLUTIONS + ("exact",)


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
    from .kernels import eta_hat as _eta

    return float(_eta(mode, nu))


def _weights(mode, gamma, N, nu, formulation, convolution, simpson_n):
    from .weights import convolution_weights

    j = np.arange(N + 1)
    kwargs = dict(nu=nu, rule=convolution, formulation=formulation)
    if convolution == "simpson":
        kwargs["simpson_n"] = simpson_n
    w = np.asarray(convolution_weights(mode, gamma, j, **kwargs), dtype=float)
    if w.shape != (N + 1,):
        raise RuntimeError(f"convolution_weights returned shape {w.shape}, expected {(N + 1,)}")
    return w


def _halves_last(convolution: str) -> bool:
    from .weights import halves_last

    return bool(halves_last(convolution))


def _static(mode, nu) -> float:
    from .kernels import static_integral

    return float(static_integral(mode, nu))


def _coefficients(mode, gamma, nu, formulation, integration, xk0):
    """(prefactor g, Z(0) or None, B) for the recurrence; B is the r_n coefficient."""
    eta = eta_hat(mode, nu)
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


def implicit_coefficient(mode, *, gamma, nu=0.25, formulation="displacement",
                         convolution="trapezoid", integration="explicit", simpson_n=4) -> float:
    """Coefficient B of the unknown r_n on the right-hand side of the discrete modal equation.

    Each step solves ``r_n = A_n + B r_n``.  B = 0 means the step is explicit; it is
    zero for displacement + explicit and (up to rounding) for velocity + discretized
    + semi-implicit, where the two r_n contributions cancel.
    """
    mode = _choice("mode", mode, MODES)
    gamma = _positive("gamma", gamma)
    nu = _poisson(nu)
    formulation = _choice("formulation", formulation, FORMULATIONS)
    convolution = _choice("convolution", convolution, _ALL_CONVOLUTIONS)
    integration = _choice("integration", integration, INTEGRATIONS)
    simpson_n = _simpson_n(simpson_n)
    xk0 = _weights(mode, gamma, 0, nu, formulation, convolution, simpson_n)[0]
    return float(_coefficients(mode, gamma, nu, formulation, integration, xk0)[2])


def modal_response(mode, *, gamma, T_end, nu=0.25, formulation="displacement",
                   convolution="trapezoid", integration="explicit", simpson_n=4) -> xr.DataArray:
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
    convolution : {"discretized", "trapezoid", "simpson", "exact"}
        Weights of eqs. (45), (46), (47) (or exactly pre-integrated kernel).
    integration : {"explicit", "semi-implicit"}
        Eq. (49) or (50).
    simpson_n : even int >= 2
        Sub-intervals of the Simpson pre-integration (47).

    Returns
    -------
    xarray.DataArray named "r" on coordinate "T" = n gamma, n = 0..N.  If the
    recurrence overflows, the remaining values are NaN and the attribute
    ``nonfinite_from_T`` records where.  See the module docstring for the recurrences.
    """
    mode = _choice("mode", mode, MODES)
    gamma = _positive("gamma", gamma)
    T_end = _positive("T_end", T_end)
    nu = _poisson(nu)
    formulation = _choice("formulation", formulation, FORMULATIONS)
    convolution = _choice("convolution", convolution, _ALL_CONVOLUTIONS)
    integration = _choice("integration", integration, INTEGRATIONS)
    simpson_n = _simpson_n(simpson_n)
    N = _n_steps(gamma, T_end)
    if N > MAX_STEPS:
        raise InputError(
            "T_end",
            f"T_end/gamma = {N} steps exceeds the limit of {MAX_STEPS} (the work grows as N^2); "
            "use a larger gamma or a smaller T_end",
        )

    w = _weights(mode, gamma, N, nu, formulation, convolution, simpson_n)
    halve = _halves_last(convolution)
    g, z0, B = _coefficients(mode, gamma, nu, formulation, integration, w[0])
    if 1.0 - B == 0.0:
        raise InputError("gamma", f"the step equation is singular for gamma = {gamma!r} with this scheme")
    inv = 1.0 / (1.0 - B)
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
            rn = A * inv
            r[n] = rn
            d[n] = dn_known if explicit else dn_known + 0.5 * rn
            if not math.isfinite(rn):
                r[n:] = np.nan
                bad_from = n * gamma
                break

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
    from .exact import rayleigh_speed_ratio

    return float(rayleigh_speed_ratio(nu))


def long_time_amplitude(mode, nu=0.25) -> float:
    """Amplitude A of the long-time form r ~ A sin(s_R T) for modes I and II (Appendix B).

    In T and s = p/(q c_s), L[r](s) = eta / M(s) with the impedance
    ``M(s) = eta s + L[C](s)`` (:func:`cracklab.kernels.impedance`).  The poles
    ``s = +- i s_R`` give ``r ~ 2 Re[eta e^{i s_R T} / M'(i s_R)]``; M is real on the
    imaginary axis below the branch points and ``M'(iy) = -i dM(iy)/dy``, so
    ``A = -2 eta / (dM(iy)/dy)`` at ``y = s_R``.  The value is taken from
    :func:`cracklab.exact.modal_long_time_amplitude`: 0.5844 (mode I, eq. B.5) and
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
