"""Closed-form estimates for the section 4 crack: Freund's equation of motion and a
Palmer-Rice type cohesive-zone size. Plain numpy, no cracklab state; the study and
tests/studies/test_front_studies.py use these.

Notation: mode I, plane strain, E' = 2 mu / (1 - nu), Gc = tau_c delta_c / 2 (linear
cohesive law), c_R Rayleigh speed, c_d dilatational speed.
"""
from __future__ import annotations

import numpy as np


def rayleigh_speed(nu, cs=1.0):
    """Rayleigh speed: root in (0, c_s) of (2 - x)^2 = 4 sqrt(1 - x) sqrt(1 - x k^2),
    x = (v/c_s)^2, k^2 = (c_s/c_d)^2 = (1 - 2 nu) / (2 (1 - nu)); solved by bisection."""
    k2 = (1.0 - 2.0 * nu) / (2.0 * (1.0 - nu))
    lo, hi = 1e-6, 1.0 - 1e-15

    def f(x):
        return (2.0 - x) ** 2 - 4.0 * np.sqrt(1.0 - x) * np.sqrt(1.0 - x * k2)

    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if f(lo) * f(mid) <= 0:
            hi = mid
        else:
            lo = mid
    return float(np.sqrt(0.5 * (lo + hi))) * cs


def freund_g(v, cR):
    """Freund's universal function of the crack speed for mode I, approximated as
    g(v) = 1 - v / c_R (G_dynamic = g(v) G_static)."""
    return 1.0 - np.asarray(v, dtype=float) / cR


def freund_speed(G_static_over_Gc, cR):
    """Crack speed from the energy balance g(v) G_static = Gc with g = 1 - v/c_R:
    v = c_R (1 - Gc / G_static); 0 where G_static <= Gc (the crack does not run)."""
    r = np.asarray(G_static_over_Gc, dtype=float)
    with np.errstate(divide="ignore"):
        v = cR * (1.0 - 1.0 / r)
    return np.where(r > 1.0, v, 0.0)


def periodic_factor(a, L):
    """G of a periodic row of collinear cracks (half length a, period L, uniform load)
    over G of the isolated crack: tan(pi a / L) / (pi a / L) (Koiter / Irwin)."""
    x = np.pi * np.asarray(a, dtype=float) / L
    return np.tan(x) / x


def static_G_ratio(length, *, g0_ratio=1.25, period=2.0, periodic=True):
    """G_static / Gc of the section 4 crack of full length ``length`` (the symmetric
    crack, half length a = length / 2) held at constant nominal K, G0 = g0_ratio Gc:
    g0_ratio for an isolated crack, times ``periodic_factor(a, period)`` on the periodic
    domain of period L1 = ``period``."""
    r = g0_ratio * np.ones_like(np.asarray(length, dtype=float))
    return r * periodic_factor(0.5 * np.asarray(length, dtype=float), period) if periodic else r


def A_I(v, nu, cs=1.0):
    """Rice's (1980) mode I speed function: G = (1 - nu) A_I(v) K^2 / (2 mu),
    A_I = v^2 alpha_d / ((1 - nu) c_s^2 D), D = 4 alpha_d alpha_s - (1 + alpha_s^2)^2,
    alpha_{d,s} = sqrt(1 - v^2 / c_{d,s}^2). A_I(0) = 1 (limit), A_I -> inf at c_R."""
    v = np.asarray(v, dtype=float)
    cd = cs * np.sqrt(2.0 * (1.0 - nu) / (1.0 - 2.0 * nu))
    small = np.abs(v) < 1e-6 * cs
    vv = np.where(small, 1e-6 * cs, v)
    ad = np.sqrt(1.0 - vv**2 / cd**2)
    as_ = np.sqrt(1.0 - vv**2 / cs**2)
    D = 4.0 * ad * as_ - (1.0 + as_**2) ** 2
    out = vv**2 * ad / ((1.0 - nu) * cs**2 * D)
    return np.where(small, 1.0, out)


def palmer_rice_zone(*, mu, nu, Gc, tau_c, v=0.0, cs=1.0):
    """Palmer-Rice type size of the cohesive zone of mode I, with the stress falling
    linearly across the zone (Palmer & Rice 1973; Rice 1980):
    R0 = (9 pi / 32) E' Gc / tau_c^2, E' = 2 mu / (1 - nu); a crack running at speed v
    has R(v) = R0 / A_I(v) (the zone length scales with K^2 / tau_c^2 and, at fixed
    G = Gc, K^2 = E' Gc / A_I(v))."""
    R0 = 9.0 * np.pi / 32.0 * (2.0 * mu / (1.0 - nu)) * Gc / tau_c**2
    return R0 / A_I(v, nu, cs)


def semi_infinite_step_K(p, t, nu, cs=1.0):
    """Mode I stress intensity factor of a stationary semi-infinite crack whose faces
    are loaded by a uniform pressure p from t = 0 (Freund 1990, section 2.5):
    K(t) = 2 p sqrt(c_d t (1 - 2 nu) / pi) / (1 - nu). It grows without bound: only the
    crack's far end (here, its back tip) brings it down to the static value."""
    cd = cs * np.sqrt(2.0 * (1.0 - nu) / (1.0 - 2.0 * nu))
    t = np.clip(np.asarray(t, dtype=float), 0.0, None)
    return 2.0 * p * np.sqrt(cd * t * (1.0 - 2.0 * nu) / np.pi) / (1.0 - nu)


def steady_speed(t, x, t0, t1):
    """Least-squares slope of x(t) over t0 <= t <= t1 (the mean speed in the window)
    and its residual rms; NaN when fewer than 3 samples fall in the window."""
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    m = (t >= t0) & (t <= t1) & np.isfinite(x)
    if m.sum() < 3:
        return float("nan"), float("nan")
    p = np.polyfit(t[m], x[m], 1)
    res = x[m] - np.polyval(p, t[m])
    return float(p[0]), float(np.sqrt(np.mean(res**2)))
