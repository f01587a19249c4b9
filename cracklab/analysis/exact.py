"""Exact and reference solutions used by the tests and studies.

Modal response (section 3.1, eqs. 39-41, Appendix B), Lamb's problem
(section 3.2, as corrected in docs/reference/equations.md, "Reference solutions"), and static and
self-similar crack openings (the same section).
"""

from __future__ import annotations

import math

import mpmath as mp
import numpy as np
from scipy import optimize, special

from ..elastic import kernels as _k
from ..elastic.waves import rayleigh_roots, rayleigh_speed_ratio  # noqa: F401  (part of this module's API)

__all__ = [
    "rayleigh_speed_ratio",
    "rayleigh_roots",
    "modal_long_time_amplitude",
    "modal_long_time_amplitude_G",
    "modal_exact",
    "pekeris_G",
    "lamb_opening",
    "lamb_arrivals",
    "penny_opening",
    "griffith_opening",
    "periodic_row_opening",
    "elliptical_opening",
    "kostrov_slip",
]

_MODES = ("I", "II", "III")


def _mode(mode):
    if mode not in _MODES:
        raise ValueError(f"mode must be one of {_MODES}, got {mode!r}")
    return mode


def _out(arr):
    arr = np.asarray(arr)
    return arr[()] if arr.ndim == 0 else arr


# ----------------------------------------------------------------------------- Rayleigh
# rayleigh_speed_ratio and rayleigh_roots live with the wave speeds (cracklab.elastic.waves)


def modal_long_time_amplitude(nu=0.25, mode="I"):
    """f(nu) of eq. (B.5): r(T) ~ f sin(s_R T) for a step load on one mode (I or II).

    From the residue of r_hat(s) = eta_hat / M(s) = -eta_hat s^2 alpha / R(s) at
    s = i s_R (alpha = sqrt(1+s^2/a^2) for I, sqrt(1+s^2) for II, see
    `kernels.impedance`): the residue is rho = -i f/2, so r ~ 2 Re(rho e^{i s_R T})
    = f sin(s_R T) with f = 2 eta_hat s_R alpha / K, where
    R'(i s_R) = i s_R K, K = 4 (alpha_s/(a^2 alpha_d) + alpha_d/alpha_s) - 4 (2 - s_R^2).
    0.5844 for mode I at nu = 1/4.
    """
    if mode not in ("I", "II"):
        raise ValueError(f"mode must be one of ('I', 'II'), got {mode!r}")
    a = _k.wave_speed_ratio(nu)
    y = rayleigh_speed_ratio(nu)
    als = math.sqrt(1.0 - y * y)
    ald = math.sqrt(1.0 - y * y / a**2)
    K = 4.0 * (als / (a * a * ald) + ald / als) - 4.0 * (2.0 - y * y)
    if mode == "I":
        return 2.0 * a * y * ald / K
    return 2.0 * y * als / K


def modal_long_time_amplitude_G(nu=0.25):
    """Mode I f(nu) by the construction of Appendix B: f = (c_d/c_R) G(i s_R), eqs. (B.3)-(B.4).

    G(s) = sqrt(1+s^2/a^2) {4 sqrt(1+s^2) sqrt(1+s^2/a^2) + (2+s^2)^2} / ((s^2+s_1^2)(s^2+s_2^2)).
    """
    a = _k.wave_speed_ratio(nu)
    xr, x1, x2 = rayleigh_roots(nu)
    als = math.sqrt(1.0 - xr)
    ald = math.sqrt(1.0 - xr / a**2)
    G = ald * (4.0 * als * ald + (2.0 - xr) ** 2) / ((x1 - xr) * (x2 - xr))
    return float((a / math.sqrt(xr)) * G.real)


# ----------------------------------------------------------------------------- modal r(T)
_MODAL_CACHE: dict = {}


def _modal_transform(mode, nu):
    """r_hat(s) = eta_hat / M(s) in mpmath, eq. (41), with the branch cuts of
    sqrt(1 + s^2/b^2) = sqrt(s/b - i) sqrt(s/b + i) laid horizontally to the left of
    +-ib (the principal branch for Re s > 0), so that a Talbot contour can enclose them."""
    j = mp.mpc(0, 1)
    nu_m = mp.mpf(nu)

    def f(s):
        a = mp.sqrt(2 * (1 - nu_m) / (1 - 2 * nu_m))
        als = mp.sqrt(s - j) * mp.sqrt(s + j)
        if mode == "III":
            return 1 / als
        ald = mp.sqrt(s / a - j) * mp.sqrt(s / a + j)
        R = 4 * ald * als - (2 + s * s) ** 2
        if mode == "I":
            return -a * s * s * ald / R
        return -s * s * als / R

    return f


def _talbot(F, t, M):
    """Fixed Talbot inversion (Abate & Valko 2004) of F at time t > 0 with M nodes.

    Contour s(theta) = r theta (cot theta + i), r = 2M/(5t); the terms reach
    e^{rt} = e^{2M/5}, hence the working precision of 0.18 M + 24 digits.
    """
    with mp.workdps(int(0.18 * M) + 24):
        t = mp.mpf(t)
        r = mp.mpf(2 * M) / (5 * t)
        total = (F(r) * mp.exp(r * t)).real / 2
        for k in range(1, M):
            th = k * mp.pi / M
            cot = mp.cot(th)
            s = r * th * mp.mpc(cot, 1)
            sigma = th + (th * cot - 1) * cot
            total += (mp.exp(t * s) * F(s) * mp.mpc(1, sigma)).real
        return float(r / M * total)


def _modal_point(mode, T, nu):
    key = (mode, float(nu), float(T))
    hit = _MODAL_CACHE.get(key)
    if hit is not None:
        return hit
    if T == 0.0:
        val = 1.0
    else:
        # the Talbot contour crosses the imaginary axis at i pi M / (5T); it must
        # pass to the right of the branch points +-i b (b = a for modes I, II;
        # 1 for III) and of the Rayleigh poles +-i s_R
        b = _k.wave_speed_ratio(nu) if mode != "III" else 1.0
        M = int(math.ceil(1.3 * 5.0 * b * T / math.pi)) + 24
        val = _talbot(_modal_transform(mode, nu), T, M)
    _MODAL_CACHE[key] = val
    return val


def modal_exact(mode, T, nu=0.25, *, numerical=False):
    """Exact r(T) = V(T)/V(0+) of one traction-free Fourier mode under a step load, eqs. (39)-(41).

    r_hat(s) = eta_hat / M(s) (Laplace in T; eta_hat = a for mode I, 1 for II, III).
    Mode III returns J0(T) (unless ``numerical``, used to validate the inversion);
    modes I and II use a fixed Talbot inversion in mpmath arithmetic (slow, about
    0.1 s at T = 50; values are cached).
    T >= 0; r(0) = 1.
    """
    _mode(mode)
    T = np.asarray(T, dtype=float)
    if np.any(T < 0) or np.any(~np.isfinite(T)):
        raise ValueError("T must be finite and >= 0")
    if mode == "III" and not numerical:
        return _out(special.j0(T))
    _k.wave_speed_ratio(nu)
    flat = [_modal_point(mode, float(t), nu) for t in T.ravel()]
    return _out(np.array(flat, dtype=float).reshape(T.shape))


# ----------------------------------------------------------------------------- Lamb / Pekeris
_SQ3 = math.sqrt(3.0)
_TAU_P = 1.0 / _SQ3
_TAU_S = 1.0
_TAU_R = math.sqrt(3.0 + _SQ3) / 2.0


def lamb_arrivals():
    """(tau_P, tau_S, tau_R) = (1/sqrt3, 1, sqrt(3+sqrt3)/2), tau = c_s t / r, nu = 1/4 (section 3.2)."""
    return (_TAU_P, _TAU_S, _TAU_R)


def pekeris_G(tau):
    """Pekeris (1955) G(tau) for nu = 1/4 (docs/reference/equations.md, "Reference solutions": corrects the formula of section 3.2).

    Surface displacement under a step point load P: w = P/(pi mu r) G(tau), tau = c_s t/r.
    G = 0 before tau_P, -> -inf as tau -> tau_R-, 3/8 from tau_R on.
    """
    tau = np.asarray(tau, dtype=float)
    t2 = tau * tau
    c1 = math.sqrt(3.0 * _SQ3 + 5.0)
    c2 = math.sqrt(3.0 * _SQ3 - 5.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ga = (6.0 - _SQ3 / np.sqrt(t2 - 0.25) - c1 / np.sqrt(_TAU_R**2 - t2)
              + c2 / np.sqrt(t2 - (3.0 - _SQ3) / 4.0)) / 32.0
        gb = (6.0 - c1 / np.sqrt(_TAU_R**2 - t2)) / 16.0
    out = np.where(tau < _TAU_P, 0.0,
                   np.where(tau < _TAU_S, ga, np.where(tau < _TAU_R, gb, 0.375)))
    return _out(out)


def lamb_opening(r, t, P=1.0, mu=1.0, cs=1.0):
    """Opening 2w = 2P/(pi mu r) G(cs t/r) of the plane under opposite step point loads P (nu = 1/4).

    docs/reference/equations.md, "Reference solutions" (the printed section 3.2 formula is garbled); static value 3P/(4 pi mu r).
    """
    r = np.asarray(r, dtype=float)
    t = np.asarray(t, dtype=float)
    return _out(2.0 * P / (math.pi * mu * r) * pekeris_G(cs * t / r))


# ----------------------------------------------------------------------------- static cracks
def penny_opening(r, c, p, mu, nu):
    """Penny crack of radius c under pressure p: 4(1-nu)p/(pi mu) sqrt(c^2-r^2), 0 outside (docs/reference/equations.md, "Reference solutions")."""
    r = np.asarray(r, dtype=float)
    return _out(4.0 * (1.0 - nu) * p / (math.pi * mu) * np.sqrt(np.clip(c * c - r * r, 0.0, None)))


def _plane_factor(mode, nu):
    """2(1-nu) for modes I, II (stiffness mu|q|/(2(1-nu))); 2 for mode III (mu|q|/2)."""
    _mode(mode)
    return 2.0 if mode == "III" else 2.0 * (1.0 - nu)


def griffith_opening(x, c, p, mu, nu, mode="I"):
    """2D crack of half length c under load p: (2(1-nu)p/mu) sqrt(c^2-x^2) for I, II; (2p/mu) sqrt for III."""
    x = np.asarray(x, dtype=float)
    f = _plane_factor(mode, nu)
    return _out(f * p / mu * np.sqrt(np.clip(c * c - x * x, 0.0, None)))


def periodic_row_opening(x, c, L, p, mu, nu, mode="I"):
    """Periodic row (period L) of cracks |x - nL| < c under load p (docs/reference/equations.md, "Reference solutions").

    (f p/mu)(L/pi) arccosh(cos(pi x/L)/cos(pi c/L)) with x reduced to [-L/2, L/2),
    f = 2(1-nu) for modes I, II and 2 for mode III; 0 outside the cracks.
    """
    x = np.asarray(x, dtype=float)
    if not 0.0 < c < 0.5 * L:
        raise ValueError("need 0 < c < L/2")
    f = _plane_factor(mode, nu)
    xr = x - L * np.round(x / L)
    ratio = np.cos(math.pi * xr / L) / math.cos(math.pi * c / L)
    val = f * p / mu * (L / math.pi) * np.arccosh(np.maximum(ratio, 1.0))
    return _out(np.where(np.abs(xr) < c, val, 0.0))


def elliptical_opening(x1, x3, a, b, p, mu, nu):
    """Elliptical crack (semi-axes a along x1, b along x3) under pressure p, Green & Sneddon (1950).

    delta = 2(1-nu) p b_min / (mu E(k)) sqrt(1 - x1^2/a^2 - x3^2/b^2), k^2 = 1 - b_min^2/b_max^2,
    E the complete elliptic integral of the second kind; a = b gives `penny_opening`,
    a -> inf the Griffith opening in x3.
    """
    x1 = np.asarray(x1, dtype=float)
    x3 = np.asarray(x3, dtype=float)
    lo, hi = min(a, b), max(a, b)
    E = special.ellipe(1.0 - (lo / hi) ** 2)
    inside = 1.0 - (x1 / a) ** 2 - (x3 / b) ** 2
    return _out(2.0 * (1.0 - nu) * p * lo / (mu * E) * np.sqrt(np.clip(inside, 0.0, None)))


def kostrov_slip(x, t, v, dtau, mu, cs=1.0):
    """Kostrov (1964) self-similar mode III crack grown from a line at speed v < cs.

    slip = (2/E(k)) (dtau/mu) sqrt(v^2 t^2 - x^2), k^2 = 1 - v^2/cs^2, 0 outside; v -> 0 gives
    the static (2 dtau/mu) sqrt(c^2 - x^2) with c = v t.
    """
    if not 0.0 < v <= cs:
        raise ValueError("need 0 < v <= cs")
    x = np.asarray(x, dtype=float)
    t = np.asarray(t, dtype=float)
    E = special.ellipe(1.0 - (v / cs) ** 2)
    return _out(2.0 / E * dtau / mu * np.sqrt(np.clip((v * t) ** 2 - x * x, 0.0, None)))
