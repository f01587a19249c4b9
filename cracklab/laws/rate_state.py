"""Rate-and-state friction (docs/reference/equations.md, "Rate-and-state friction").

The regularised form of Lapusta et al. (2000) and SCEC TPV101-104: the friction
coefficient is f(V, psi) = a asinh[V / (2 V0) exp(psi / a)] and the strength f times the
compressive normal stress (``sigma_n``, or the current normal traction without it, as
every friction law: laws/friction.py). The state psi evolves by

* the ageing law, dpsi/dt = (b V0 / L) [exp((f0 - psi) / b) - V / V0]
  (psi = f0 + b ln(V0 theta / L), d theta / dt = 1 - V theta / L);
* the slip law, dpsi/dt = -(V / L) [psi - psi_ss(V)], with psi_ss the state at which
  f(V, psi_ss) = f_ss(V) = f0 - (b - a) ln(V / V0); with ``f_w`` and ``V_w`` (strong
  velocity weakening, TPV103/104) f_ss = f_w + (f_LV - f_w) / [1 + (V / V_w)^8]^(1/8).

Step (v): at each point, with tau* the traction if the plane stopped (load plus f_j),
the slip rate is collinear with tau* and its magnitude V >= 0 solves
|tau*| - eta V = sigma f(V, psi): a Newton iteration on ln V inside a bracket that every
evaluation narrows (bisection where a step leaves it), in one compiled pass over the
plane (:func:`_slide_loop`).

State update (second order, exact when V is constant over the step): over a step psi
is integrated exactly at a constant rate V*, the mean of V_{n-1} and the step's
estimate of V_n. A step's first solve predicts V_n with V* = V_{n-1}, then corrects
with the mean (two Newton solves); a later solve of the same step (the product
scheme's corrector) reuses the last estimate (one more). A solve with
``traction=False`` is the product scheme's predictor (solver/schemes/product.py): it
only predicts, and the step's solve that follows corrects, two solves in all.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, SimulationError
from ..jit import njit
from .base import SHEAR, bonded_mask, check_parameter, parameter
from . import elementary
from .friction import NORMAL_STATE, Friction, normal_slip_scale, normal_time
from .solve import solve_velocity

EVOLUTIONS = ("ageing", "slip")
AGEING, SLIP, STRONG = 0, 1, 2          # evolution laws of the compiled pass
INITIAL, PREDICT, CORRECT, FULL = 0, 1, 2, 3   # what a solve does with the state
LN2 = math.log(2.0)
THIRD, SIXTH, TWENTYFOURTH = 1.0 / 3.0, 1.0 / 6.0, 1.0 / 24.0
#: Newton: it stops when the error left after the step, below w step^2 with w = G''/G' <= 1
#: in x (for a step at most 1e-2 long), or below step^2 / 2, is under tol^2: STEP_TOL leaves
#: 1e-10 relative in V (a traction residual below 1e-10 (eta V + sigma a)); a prediction of V
#: (whose error reaches the step's result only times dt: through K V and the state's mean V)
#: stops at PREDICT_TOL (1e-8 relative); bisection stops at a bracket BRACKET_TOL narrow
STEP_TOL = 1e-5
PREDICT_TOL = 1e-4
BRACKET_TOL = 1e-13
MAX_ITERATIONS = 200


# ---------------------------------------------------------------------------- the compiled pass
# Plain functions, compiled by numba on first use (_kernel); without numba the same
# functions run as Python (slow, the same arithmetic).
def _lnsinh(y):
    """ln sinh(y) for y > 0, without overflow."""
    if y > 20.0:
        return y - LN2
    if y < 1e-4:
        return math.log(y) + y * y * SIXTH
    return math.log(math.sinh(y))


def _asinh_exp(lnu):
    """(asinh(u), u / sqrt(1 + u^2), 1 / (1 + u^2)) for u = exp(lnu), without overflow."""
    if lnu > 18.0:      # asinh(u) = ln(2u) + 1/(4u^2) - ...: the rest is below 1e-16 of it
        return lnu + LN2, 1.0, 0.0
    u = math.exp(lnu)
    if lnu < -18.0:
        return u, u, 1.0
    q = 1.0 / (1.0 + u * u)
    return math.asinh(u), u * math.sqrt(q), q


def _grow(V, h):
    """V e^h for |h| < 1e-2 without exp: the series to h^4 (the rest h^5 / 120 < 1e-17 for |h| <
    1e-3) or to h^8 (h^9 / 9! < 3e-24), chosen without a branch."""
    low = 1.0 + h * (1.0 + h * (0.5 + h * (SIXTH + h * TWENTYFOURTH)))
    high = 1.0 + h * (1.0 + h * (0.5 + h * (SIXTH + h * (TWENTYFOURTH + h * (1.0 / 120.0 + h * (
        1.0 / 720.0 + h * (1.0 / 5040.0 + h * (1.0 / 40320.0))))))))
    return V * (low if abs(h) < 1e-3 else high)


def _bounds(T, A, eta, lnc):
    """A bracket of the root of :func:`_newton`'s G: G(xhi) < 0 at V = T / eta, and G >= 0
    where eta V <= T/2 and A asinh(cV) <= T/2."""
    xhi = math.log(T / eta)
    return min(xhi - LN2, _lnsinh(0.5 * T / A) - lnc), xhi


def _newton(T, A, eta, lnc, x0, V0, tol):
    """V >= 0 with G = T - eta V - A asinh(c V) = 0, c = exp(lnc), from the guess x0 = ln V0
    (NaN or -inf: none), to a last step below ``tol`` in ln V; returns (V, ln V, evaluations),
    evaluations < 0 when it failed (bad input).

    Newton on x = ln V, safeguarded: each evaluation narrows the bracket [xlo, xhi] (G > 0
    left of the root), intersected with its analytic bounds (:func:`_bounds`) from the
    first step longer than 0.5 (or without a guess), and a step that leaves it is replaced
    by bisection."""
    if T == 0.0:
        return 0.0, -math.inf, 0
    if not (T > 0.0 and A >= 0.0 and eta > 0.0 and lnc == lnc):
        return math.nan, math.nan, -1
    if A == 0.0:
        V = T / eta
        return V, math.log(V), 0
    x = x0
    V = V0
    bounded = not (-740.0 < x < 700.0)    # no guess, or one exp cannot take
    if bounded:
        xlo, xhi = _bounds(T, A, eta, lnc)
        x = min(_lnsinh(T / A) - lnc, xhi)   # the root without damping, or T / eta
        V = math.exp(x)
    else:
        xlo, xhi = -math.inf, math.inf
    for it in range(1, MAX_ITERATIONS + 1):
        f, d, q = _asinh_exp(lnc + x)
        G = T - eta * V - A * f
        if G > 0.0:
            xlo = x
        elif G < 0.0:
            xhi = x
        else:
            return V, x, it
        damping = eta * V
        inverse = 1.0 / (damping + A * d)
        step = G * inverse                # the Newton step in x, -G / G'(x)
        # w = G''/G' in x, the part of G' that is linear in V (the damping, and friction where
        # u << 1, asinh(u) ~ u); the rest, friction where u >> 1 (asinh(u) ~ ln 2u), is linear
        # in x. Every derivative of G in x is within a few w |G'|, so the Newton step in x
        # leaves an error of about w step^2 / 2 (below w step^2 for |step| < 0.5)
        w = (damping + A * d * q) * inverse
        a_step = abs(step)
        if a_step < tol or (a_step < 1e-2 and w * step * step < tol * tol):   # converged
            return _grow(V, step), x + step, it
        # G is concave in x and convex in V: the Newton step in x ends beyond the root, the
        # one in V (x + ln(1 + step)) before it. Weigh them by w
        xn = x + step
        if step > -1.0:
            if abs(step) < 1e-2:
                xn += w * step * step * (step * THIRD - 0.5)     # w (ln(1 + step) - step)
            else:
                xn += w * (math.log1p(step) - step)
        if not bounded and not (abs(xn - x) < 0.5 and xlo < xn < xhi):   # a long step: bound it
            lo, hi = _bounds(T, A, eta, lnc)
            xlo, xhi, bounded = max(xlo, lo), min(xhi, hi), True
        if not (xlo < xn < xhi):          # outside the bracket: bisect
            xn = 0.5 * (xlo + xhi)
            if xhi - xlo < BRACKET_TOL:
                return math.exp(xn), xn, it
        dx = xn - x
        x = xn
        if abs(dx) < 1e-3:                # exp(x + dx) = V e^dx, _grow's series to dx^4
            V = _grow(V, dx)
        else:
            V = math.exp(x)
    return V, x, -MAX_ITERATIONS


def _fss(law, V, lnv, a, b, f0, fw, Vw):
    """f_ss(V) of the slip laws, lnv = ln(V / V0): f0 - (b - a) lnv, with strong velocity
    weakening (``law`` STRONG) f_w + (f_LV - f_w) / [1 + (V / V_w)^8]^(1/8)."""
    fss = f0 - (b - a) * lnv
    if law == STRONG:
        r = V / Vw
        r8 = r * r
        r8 = r8 * r8
        r8 = r8 * r8
        if r8 > 1e-16:
            fss = fw + (fss - fw) / (1.0 + r8) ** 0.125
        else:
            fss = fss - (fss - fw) * 0.125 * r8
    return fss


def _decay(s):
    """(e^-s, (1 - e^-s) / s) of the ageing law's step for s < 1e-4: their series to s^3 and s^4."""
    return 1.0 - s * (1.0 - s * (0.5 - s * SIXTH)), 1.0 - s * (0.5 - s * (SIXTH - s * TWENTYFOURTH))


def _evolve(law, z, psi, V, lnV, a, ia, b, dtL, q, ln2v0, f0, fw, Vw):
    """(z, psi) after dt at the constant slip rate V >= 0 (exact) from z (and psi of z, for the
    ageing law): for the ageing law z = exp((psi - f0) / b) = V0 theta / L, for the slip laws
    z = psi (and ``psi`` is not read); ia = 1 / a,
    dtL = dt / L, q = V0 dt / L, ln2v0 = ln(2 V0), lnV = ln V (NaN: not known)."""
    s = V * dtL
    if law == AGEING:
        # theta' = theta e^-s + (L / V)(1 - e^-s), i.e. z' = z e^-s + q (1 - e^-s) / s
        if s < 1e-4:    # the series, to s^4 / 24
            e, phi = _decay(s)
        else:
            e = math.exp(-s)
            phi = -math.expm1(-s) / s
        zn = z * e + q * phi
        r = (e - 1.0) + q * phi / z       # z' / z - 1
        if abs(r) < 1e-4:                 # psi' = psi + b ln(1 + r), the series to r^4 / 4
            return zn, psi + b * r * (1.0 - r * (0.5 - r * THIRD))
        return zn, f0 + b * math.log(zn)
    if s < 1e-17:       # psi - psi_ss is below 1e3: the change is below its last bit
        return z, z
    em = s * (1.0 - s * (0.5 - s * SIXTH)) if s < 1e-4 else -math.expm1(-s)   # 1 - e^-s
    lnv = (lnV if lnV == lnV else math.log(V)) - ln2v0 + LN2                  # ln(V / V0)
    y = _fss(law, V, lnv, a, b, f0, fw, Vw) * ia
    if not (y > 1e-300):
        y = 1e-300
    psiss = a * (LN2 - lnv + _lnsinh(y))             # f(V, psiss) = fss
    z = z - (z - psiss) * em
    return z, z


def _slide_loop(lo, hi, t1, t3, g, l1, sl1, l3, sl3, sig, ssig, a, sa, ia, sia, b, sb, dtL, sdtL, q, sq, ln2v0, sln2v0,
                f0, sf0,
                fw, sfw, Vw, sVw, Vi, sVi, law, mode, from_v, eta, bonded, has_bonded,
                z_old, V_old, z, psi, V, lnV, strength, v1, v3, o1, o3, slow, masked):
    """Step (v) with the state update of ``mode`` at the points lo <= i < hi (``masked``:
    only where ``slow`` is set, the rest done by :func:`_fast_loop`); returns (evaluations,
    Newton solves, most evaluations of one solve, the first point that failed or -1)."""
    total = 0
    solves = 0
    most = 0
    bad = -1
    for i in range(lo, hi):
        if masked and slow[i] == 0:
            continue
        x1 = t1[i] + g * l1[i * sl1]
        x3 = t3[i] + g * l3[i * sl3]
        T = math.sqrt(x1 * x1 + x3 * x3)
        ai = a[i * sa]
        iai = ia[i * sia]
        bi = b[i * sb]
        dLi = dtL[i * sdtL]
        qi = q[i * sq]
        l2 = ln2v0[i * sln2v0]
        fi = f0[i * sf0]
        fwi = fw[i * sfw]
        Vwi = Vw[i * sVw]
        A = sig[i * ssig] * ai
        zn = 0.0
        if mode == INITIAL:
            x0 = math.nan
            vi = math.nan
            if from_v:
                vi = Vi[i * sVi]
                x0 = math.log(vi)
                y = (T - eta * vi) / A
                # sigma f(V_ini, psi) = T - eta V_ini
                psi[i] = ai * (l2 - x0 + _lnsinh(y)) if y > 0.0 else math.nan
            p = psi[i]
            z[i] = math.exp((p - fi) / bi) if law == AGEING else p
        if has_bonded and bonded[i]:
            if mode == CORRECT or mode == FULL:
                zn, p = _evolve(law, z_old[i], psi[i], 0.0, -math.inf, ai, iai, bi, dLi, qi, l2, fi, fwi, Vwi)
                z[i] = zn
                psi[i] = p
            V[i] = 0.0
            lnV[i] = -math.inf
            strength[i] = T
            v1[i] = 0.0
            v3[i] = 0.0
            o1[i] = x1
            o3[i] = x3
            continue
        if mode == INITIAL:
            W, x, it = _newton(T, A, eta, p * iai - l2, x0, vi, STEP_TOL)
        elif mode == CORRECT:
            Vp = V[i]
            zn, p = _evolve(law, z_old[i], psi[i], 0.5 * (V_old[i] + Vp), math.nan, ai, iai, bi, dLi, qi, l2, fi,
                            fwi, Vwi)
            W, x, it = _newton(T, A, eta, p * iai - l2, lnV[i], Vp, STEP_TOL)
        else:
            Vo = V_old[i]
            xo = lnV[i]
            zn, p = _evolve(law, z_old[i], psi[i], Vo, xo, ai, iai, bi, dLi, qi, l2, fi, fwi, Vwi)
            W, x, it = _newton(T, A, eta, p * iai - l2, xo, Vo, PREDICT_TOL)
            if mode == FULL and it >= 0:
                total += it
                solves += 1
                most = max(most, it)
                zn, p = _evolve(law, z_old[i], psi[i], 0.5 * (Vo + W), math.nan, ai, iai, bi, dLi, qi, l2, fi, fwi, Vwi)
                W, x, it = _newton(T, A, eta, p * iai - l2, x, W, STEP_TOL)
        if it < 0 or not (W >= 0.0 and W < math.inf and abs(p) < math.inf):
            if bad < 0:
                bad = i
            W = math.nan
        else:
            total += it
            solves += 1
            most = max(most, it)
        V[i] = W
        lnV[i] = x
        scale = W / T if T > 0.0 else 0.0
        w1 = scale * x1
        w3 = scale * x3
        v1[i] = w1
        v3[i] = w3
        if mode != PREDICT:     # the prediction keeps only V (the corrector starts from it)
            if mode != INITIAL:
                z[i] = zn
            psi[i] = p
            strength[i] = T - eta * W
            o1[i] = x1 - eta * w1
            o3[i] = x3 - eta * w3
    return total, solves, most, bad


def _at(x, i):
    """x[i] of a field, x itself of a single value (compiled: one specialisation each)."""
    return x[i] if isinstance(x, np.ndarray) else x


def _part(x, lo, hi):
    """x[lo:hi] of a field, x itself of a single value."""
    return x[lo:hi] if isinstance(x, np.ndarray) else x


def _fast_loop(lo, hi, t1, t3, g, l1, l3, sig, a, b, dtL, q, ln2v0,
               correct, eta, bonded, has_bonded, z_old, V_old, z, psi, V, lnV, strength, v1, v3, o1, o3, slow):
    """The ageing law's PREDICT (``correct`` False) or CORRECT pass of :func:`_slide_loop` at
    the points lo <= i < hi that take its most common branches: the state changes by less than 1e-4 over
    the step (the series of :func:`_evolve`), u = V exp(psi / a) / (2 V0) > e^18 (asinh(u) =
    ln 2u) and the first Newton step from the guess converges (below 1e-2). The same
    arithmetic in the same order, in a loop without calls or early exits, which the
    compiler vectorises; ``slow[i]`` = 1 where another branch is needed (those points are
    left as they are, for :func:`_slide_loop`). ``l1`` ... ``ln2v0``: each a field (an
    array over the points) or a single value (a float, read once). Returns the number of
    points done."""
    # views of the chunk, indexed from 0: the compiler then sees no index wrap around
    t1, t3, z_old, V_old, z, psi, V, lnV = t1[lo:hi], t3[lo:hi], z_old[lo:hi], V_old[lo:hi], z[lo:hi], psi[lo:hi], \
        V[lo:hi], lnV[lo:hi]
    strength, v1, v3, o1, o3, slow = strength[lo:hi], v1[lo:hi], v3[lo:hi], o1[lo:hi], o3[lo:hi], slow[lo:hi]
    l1, l3, sig, a, b = _part(l1, lo, hi), _part(l3, lo, hi), _part(sig, lo, hi), _part(a, lo, hi), _part(b, lo, hi)
    dtL, q, ln2v0 = _part(dtL, lo, hi), _part(q, lo, hi), _part(ln2v0, lo, hi)
    if has_bonded:
        bonded = bonded[lo:hi]
    tol = STEP_TOL if correct else PREDICT_TOL
    tol2 = tol * tol
    done = 0
    for i in range(hi - lo):
        x1 = t1[i] + g * _at(l1, i)
        x3 = t3[i] + g * _at(l3, i)
        T = math.sqrt(x1 * x1 + x3 * x3)
        ai = _at(a, i)
        A = _at(sig, i) * ai
        Vo = V_old[i]
        Vg = V[i] if correct else Vo            # the Newton guess: the prediction, or V_{n-1}
        Vs = 0.5 * (Vo + Vg) if correct else Vo  # the state's constant rate over the step
        x = lnV[i]
        zo = z_old[i]
        qi = _at(q, i)
        s = Vs * _at(dtL, i)
        e, phi = _decay(s)
        zn = zo * e + qi * phi
        r = (e - 1.0) + qi * phi / zo
        p = psi[i] + _at(b, i) * r * (1.0 - r * (0.5 - r * THIRD))
        lnc = p * (1.0 / ai) - _at(ln2v0, i)   # 1 / a as the constants hold it, to the bit
        lnu = lnc + x
        G = T - eta * Vg - A * (lnu + LN2)
        damping = eta * Vg
        inverse = 1.0 / (damping + A)
        step = G * inverse
        w = damping * inverse
        a_step = abs(step)
        W = _grow(Vg, step)
        # & rather than `and`: no branches, so that the loop vectorises
        ok = (s < 1e-4) & (abs(r) < 1e-4) & (T > 0.0) & (A > 0.0) & (-740.0 < x) & (x < 700.0) \
            & (lnu > 18.0) & (G != 0.0) & (a_step < 1e-2) & ((a_step < tol) | (w * step * step < tol2)) \
            & (W >= 0.0) & (W < math.inf) & (abs(p) < math.inf) & (not (has_bonded & bonded[i * has_bonded]))
        scale = W / T
        w1 = scale * x1
        w3 = scale * x3
        slow[i] = 0 if ok else 1
        done += 1 if ok else 0
        V[i] = W if ok else V[i]
        lnV[i] = x + step if ok else x
        v1[i] = w1
        v3[i] = w3
        if correct:
            z[i] = zn if ok else z[i]
            psi[i] = p if ok else psi[i]
            strength[i] = T - eta * W
            o1[i] = x1 - eta * w1
            o3[i] = x3 - eta * w3
    return done


#: evaluations the wide pass (:func:`_wide_loop`) takes a point to before it leaves it to the scalar pass
WIDE_EVALUATIONS = 3


def _wide_work(n):
    """The work arrays of :func:`_wide_loop`, 21 of ``n`` floats, each its own allocation: the
    compiler vectorises loops over them behind run-time checks that they do not overlap (over
    the rows of one array it keeps the scalar loop, three times slower)."""
    e = np.empty
    return (e(n), e(n), e(n), e(n), e(n), e(n), e(n), e(n), e(n), e(n), e(n), e(n), e(n), e(n), e(n), e(n), e(n),
            e(n), e(n), e(n), e(n))


def _wide_loop(lo, hi, work, idx, t1, t3, g, l1, sl1, l3, sl3, sig, ssig, a, sa, ia, sia, b, sb, dtL, sdtL, q, sq,
               ln2v0, sln2v0, f0, sf0, fw, sfw, Vw, sVw, Vi, sVi, law, mode, from_v, eta, bonded, has_bonded,
               z_old, V_old, z, psi, V, lnV, strength, v1, v3, o1, o3, slow, masked):
    """The ageing law's PREDICT or CORRECT pass of :func:`_slide_loop` at the points lo <= i <
    hi that :func:`_fast_loop` left (``slow``), gathered, in loops the compiler vectorises:
    the state update of :func:`_evolve` and at most WIDE_EVALUATIONS evaluations of
    :func:`_newton` in the branch u = V exp(psi / a) / (2 V0) > e^18, without its bounds or
    bisection; the same arithmetic in the same order, with exp, expm1, log and log1p of
    laws/elementary.py (within a few ulp of the library's: the results agree with the scalar
    pass to round-off). The points it does get ``slow`` 0, the others are left to
    :func:`_slide_loop`; returns (evaluations, Newton solves, most evaluations of one solve)
    of the points it did. ``work``: :func:`_wide_work`, ``idx``: CHUNK integers."""
    correct = mode == CORRECT
    tol = STEP_TOL if correct else PREDICT_TOL
    tol2 = tol * tol
    X1, X3, TT, AA, LC, XX, VV, LO, HI, ZN, PP, IT, ZO, PS, VS, DL, QQ, BB, IA, L2, F0 = work
    m = 0
    for i in range(lo, hi):     # gather the points (scalar)
        if slow[i] == 0 or (has_bonded and bonded[i]):
            continue
        x1 = t1[i] + g * l1[i * sl1]
        x3 = t3[i] + g * l3[i * sl3]
        T = math.sqrt(x1 * x1 + x3 * x3)
        A = sig[i * ssig] * a[i * sa]
        x0 = lnV[i]
        # the scalar pass's other branches: no load, no friction, no guess
        if not (T > 0.0 and A > 0.0 and eta > 0.0 and -740.0 < x0 < 700.0):
            continue
        idx[m] = i
        Vg = V[i] if correct else V_old[i]           # the Newton guess: the prediction, or V_{n-1}
        X1[m], X3[m], TT[m], AA[m], XX[m], VV[m] = x1, x3, T, A, x0, Vg
        VS[m] = 0.5 * (V_old[i] + Vg) if correct else Vg    # the state's constant rate over the step
        ZO[m], PS[m], DL[m], QQ[m], BB[m], IA[m], L2[m], F0[m] = (z_old[i], psi[i], dtL[i * sdtL], q[i * sq],
                                                                  b[i * sb], ia[i * sia], ln2v0[i * sln2v0],
                                                                  f0[i * sf0])
        m += 1
    for j in range(m):          # the state update of _evolve, ageing law (vector code)
        s = VS[j] * DL[j]
        zo = ZO[j]
        qi = QQ[j]
        series = s < 1e-4
        e, phi = _decay(s)
        e = e if series else elementary.exp(-s)
        phi = phi if series else -elementary.expm1(-s) / s
        zn = zo * e + qi * phi
        r = (e - 1.0) + qi * phi / zo
        near = abs(r) < 1e-4
        p = PS[j] + BB[j] * r * (1.0 - r * (0.5 - r * THIRD)) if near else F0[j] + BB[j] * elementary.log(zn)
        lnc = p * IA[j] - L2[j]
        ZN[j] = zn
        PP[j] = p
        LC[j] = lnc
        LO[j] = -math.inf
        HI[j] = math.inf
        # IT: evaluations so far; 1000 + evaluations: converged (XX, VV the result); -1: to the scalar pass
        IT[j] = 0.0 if (s < 708.0) & (near | (zn >= 2.2250738585072014e-308)) & (zn < math.inf) & (lnc == lnc) \
            & (abs(p) < math.inf) else -1.0
    left = m
    for k in range(WIDE_EVALUATIONS):
        if left == 0:
            break
        left = 0
        for j in range(m):      # one evaluation of _newton (vector code)
            going = (IT[j] >= 0.0) & (IT[j] < 1000.0)
            x = XX[j]
            Vc = VV[j]
            lnu = LC[j] + x
            A = AA[j]
            G = TT[j] - eta * Vc - A * (lnu + LN2)
            damping = eta * Vc
            inverse = 1.0 / (damping + A)
            step = G * inverse
            w = damping * inverse
            a_step = abs(step)
            done = (G == 0.0) | (a_step < tol) | ((a_step < 1e-2) & (w * step * step < tol2))
            # the next x: Newton's in x weighed with Newton's in V by w (_newton)
            xn = x + step
            if step > -1.0:
                xn += w * step * step * (step * THIRD - 0.5) if a_step < 1e-2 else w * (elementary.log1p(step) - step)
            n = IT[j] + 1.0
            ok = going & (lnu > 18.0)
            LO[j] = x if going & (G > 0.0) else LO[j]
            HI[j] = x if going & (G < 0.0) else HI[j]
            inside = (abs(xn - x) < 0.5) & (LO[j] < xn) & (xn < HI[j]) & (xn < 700.0) & (xn > -700.0)
            dx = xn - x
            Vn = _grow(Vc, dx) if abs(dx) < 1e-3 else elementary.exp(xn)     # _newton's series: _grow's below 1e-3
            Vd = Vc if G == 0.0 else _grow(Vc, step)
            xd = x if G == 0.0 else x + step
            VV[j] = (Vd if done else Vn) if ok & (done | inside) else Vc
            XX[j] = (xd if done else xn) if ok & (done | inside) else x
            left_j = ((1000.0 + n if done else n) if ok & (done | inside) else -1.0) if going else IT[j]
            IT[j] = left_j
            left += 1 if (left_j >= 0.0) & (left_j < 1000.0) else 0
    total = 0
    solves = 0
    most = 0
    for j in range(m):          # scatter the points solved (scalar)
        W = VV[j]
        if not (IT[j] > 1000.0 and W >= 0.0 and W < math.inf):
            continue
        i = idx[j]
        it = int(IT[j] - 1000.0)
        total += it
        solves += 1
        most = max(most, it)
        T = TT[j]
        V[i] = W
        lnV[i] = XX[j]
        scale = W / T
        w1 = scale * X1[j]
        w3 = scale * X3[j]
        v1[i] = w1
        v3[i] = w3
        if correct:
            z[i] = ZN[j]
            psi[i] = PP[j]
            strength[i] = T - eta * W
            o1[i] = X1[j] - eta * w1
            o3[i] = X3[j] - eta * w3
        slow[i] = 0
    return total, solves, most

#: points per chunk of :func:`_chunked`: its arrays' share (about 25 doubles a point) stays
#: in the core's cache between the two passes
CHUNK = 2048


def _chunked(n, chunk, fast, fast_args, slide_args):
    """Step (v) over ``n`` points chunk by chunk: :func:`_fast_loop` and :func:`_wide_loop`
    (where ``fast``), then :func:`_slide_loop` on the points they left, while the chunk is in
    cache; returns :func:`_slide_loop`'s counts over all chunks with the vector passes'
    (the fast pass's points counted as one evaluation each)."""
    total = 0
    solves = 0
    most = 0
    bad = -1
    work = _wide_work(chunk if fast else 1)
    idx = np.empty(chunk if fast else 1, dtype=np.int64)
    for lo in range(0, n, chunk):
        hi = min(n, lo + chunk)
        if fast:
            done = _fast_loop(lo, hi, *fast_args)
            total += done
            solves += done
            if done > 0:
                most = max(most, 1)
            t, k, m = _wide_loop(lo, hi, work, idx, *slide_args)
            total += t
            solves += k
            most = max(most, m)
        t, k, m, b = _slide_loop(lo, hi, *slide_args)
        total += t
        solves += k
        most = max(most, m)
        if bad < 0 and b >= 0:
            bad = b
    return total, solves, most, bad


_HELPERS = ("_lnsinh", "_asinh_exp", "_grow", "_bounds", "_newton", "_fss", "_decay", "_evolve")
_PASSES = ("_slide_loop", "_fast_loop", "_wide_loop", "_wide_work", "_rate_loop", "_evolve_loop")
_KERNEL = []
#: LLVM vectorises a loop over several arrays only behind run-time checks that they do not
#: overlap, and by default gives up beyond 8 such checks; numba has no way to declare its
#: arrays distinct, and the fast pass reads and writes about twenty. These raise the limits
#: for the loops compiled after them in this process (vectorised or not, a loop without
#: fast-math computes the same IEEE results in the same order).
LLVM_OPTIONS = ("-runtime-memory-check-threshold=512", "-vectorize-memory-check-threshold=4096")


def _rate_loop(T, psi, sig, eta, a, sa, b, sb, V0, sV0, L, sL, f0, sf0, fw, sfw, Vw, sVw, law, guess, V, lnV,
               dpsi):
    """The sequence solvers' pass (:meth:`RateState.slide_rates`): at every point, V >= 0
    with T - eta V = sigma a asinh(V / (2 V0) e^(psi / a)) from the guess ln V ``guess``
    (NaN: none), into ``V``, ``lnV``, and the state's rate dpsi/dt of the evolution ``law``
    at it into ``dpsi``; a parameter x comes with its stride sx (0: one value). Returns the
    first point that failed, or -1."""
    ln2V0 = math.log(2.0 * V0[0]) if V0.size else 0.0     # ln(2 V0) of one V0 for every point, once
    for i in range(T.size):
        ai = a[i * sa]
        V0i = V0[i * sV0]
        x0 = guess[i]
        v, x, it = _newton(T[i], sig[i] * ai, eta, psi[i] / ai - (math.log(2.0 * V0i) if sV0 else ln2V0), x0,
                           math.exp(x0) if x0 == x0 else 0.0, STEP_TOL)
        if it < 0:
            return i
        V[i] = v
        lnV[i] = x
        bi = b[i * sb]
        Li = L[i * sL]
        if law == AGEING:
            dpsi[i] = (bi * V0i / Li) * (math.exp((f0[i * sf0] - psi[i]) / bi) - v / V0i)
        elif v > 0.0:
            lnv = x - math.log(V0i)                     # ln(V / V0)
            y = _fss(law, v, lnv, ai, bi, f0[i * sf0], fw[i * sfw], Vw[i * sVw]) / ai
            if not (y > 1e-300):
                y = 1e-300
            dpsi[i] = -(v / Li) * (psi[i] - ai * (LN2 - lnv + _lnsinh(y)))
        else:
            dpsi[i] = 0.0
    return -1


def _evolve_loop(psi, V, h, a, sa, b, sb, V0, sV0, L, sL, f0, sf0, fw, sfw, Vw, sVw, law, out):
    """The sequence solvers' state step (:meth:`RateState.evolve_state`): at every point, psi
    after ``h`` at the constant slip rate V[i] >= 0 (exact, :func:`_evolve`) into ``out``;
    a parameter x comes with its stride sx (0: one value)."""
    for i in range(psi.size):
        ai, bi, Li, V0i, f0i = a[i * sa], b[i * sb], L[i * sL], V0[i * sV0], f0[i * sf0]
        z = math.exp((psi[i] - f0i) / bi) if law == AGEING else psi[i]
        z, out[i] = _evolve(law, z, psi[i], V[i], math.nan, ai, 1.0 / ai, bi, h / Li, V0i * h / Li,
                            math.log(2.0 * V0i), f0i, fw[i * sfw], Vw[i * sVw])


def _compile_at(numba):
    """The compiled :func:`_at` and :func:`_part`: of a field or of the single value, by the argument's type."""
    from numba.core import types
    from numba.extending import overload

    @overload(_at, inline="always")
    def _at_typed(x, i):
        if isinstance(x, types.Array):
            return lambda x, i: x[i]
        return lambda x, i: x

    @overload(_part, inline="always")
    def _part_typed(x, lo, hi):
        if isinstance(x, types.Array):
            return lambda x, lo, hi: x[lo:hi]
        return lambda x, lo, hi: x


def _kernel():
    """The compiled pass (numba, cached on disk; the Python functions without numba)."""
    if not _KERNEL:
        try:
            import numba
        except Exception:  # pragma: no cover
            _KERNEL.append(_slide_loop)
        else:
            import llvmlite.binding as llvm

            for option in LLVM_OPTIONS:
                llvm.set_option("", option)
            _compile_at(numba)
            elementary.compile_functions()
            jit = njit(error_model="numpy")
            g = globals()
            for name in _HELPERS:           # the pass calls them by their global names, inlined
                g[name] = njit(error_model="numpy", inline="always")(g[name])
            for name in _PASSES:            # :func:`_chunked` calls them by their global names
                g[name] = jit(g[name])
            _KERNEL.append(jit(_chunked))
            _KERNEL.append(True)
            return _KERNEL[0]
        _KERNEL.append(_chunked)
    return _KERNEL[0]


def _fast_kernel():
    """Whether :func:`_chunked` runs :func:`_fast_loop` (compiled only: without numba the
    scalar pass does every point)."""
    _kernel()
    return len(_KERNEL) > 1


def _field(pair):
    """The (flat array, stride) ``pair`` of :func:`_flat` as :func:`_fast_loop` takes it: the
    array of a field, the float of a single value."""
    arr, stride = pair
    return arr if stride else float(arr[0])


def _flat(value, shape):
    """(flat float array, stride): one value (stride 0), or the field over ``shape``."""
    arr = np.asarray(value, dtype=float)
    if arr.size == 1:
        return arr.reshape(1), 0
    return np.ascontiguousarray(np.broadcast_to(arr, shape)).ravel(), 1


def friction_coefficient(V, psi, a, V0):
    """f(V, psi) = a asinh[V / (2 V0) exp(psi / a)] (numpy; overflow-free for large psi / a)."""
    V, psi, a, V0 = (np.asarray(x, dtype=float) for x in (V, psi, a, V0))
    lnu = np.log(np.maximum(V, np.finfo(float).tiny) / (2.0 * V0)) + psi / a
    with np.errstate(over="ignore"):
        f = np.where(lnu > 18.0, lnu + LN2, np.arcsinh(np.exp(np.minimum(lnu, 18.0))))
    return a * np.where(V > 0, f, 0.0)


@dataclass(frozen=True)
class RateState(Friction):
    """Regularised rate-and-state friction: f = a asinh[V / (2 V0)
    exp(psi / a)], the ageing law or the slip law (``evolution``), strong velocity
    weakening with ``f_w`` and ``V_w`` (slip law only). The initial state: ``psi_ini``,
    or from the initial slip rate ``V_ini`` and the load at t = 0, sigma f(V_ini, psi) =
    |tau0| - eta V_ini (both: they must agree). ``sigma_n`` compressive positive; None:
    the current normal traction, or its regularised form with ``normal_slip_scale`` and/or
    ``normal_time`` (laws/friction.py)."""

    a: float | np.ndarray = parameter(accepted="> 0", doc="direct-effect parameter")
    b: float | np.ndarray = parameter(accepted="> 0", doc="evolution-effect parameter")
    L: float | np.ndarray = parameter(unit="length", accepted="> 0", doc="characteristic slip of the state evolution")
    V0: float | np.ndarray = parameter(unit="velocity", accepted="> 0", doc="reference slip rate")
    f0: float | np.ndarray = parameter(accepted="finite", doc="steady-state friction coefficient at V0")
    sigma_n: float | np.ndarray | None = parameter(
        unit="stress", default=None, accepted=">= 0",
        doc="normal stress, compressive positive; absent: the current normal traction max(0, -tau_2)")
    V_ini: float | np.ndarray | None = parameter(
        unit="velocity", default=None, accepted="> 0; this or psi_ini",
        doc="initial slip rate: the initial state slides at it under the load at t = 0")
    psi_ini: float | np.ndarray | None = parameter(
        default=None, accepted="finite; this or V_ini (both: they must agree)", doc="initial state psi")
    evolution: str = parameter(kind="option", default="ageing", accepted=" or ".join(f'"{e}"' for e in EVOLUTIONS),
                               doc="state evolution law")
    f_w: float | np.ndarray | None = parameter(
        default=None, accepted='> 0; with V_w and evolution = "slip"',
        doc="weakened friction coefficient of strong velocity weakening")
    V_w: float | np.ndarray | None = parameter(
        unit="velocity", default=None, accepted="> 0; with f_w", doc="weakening slip rate of strong velocity weakening")
    normal_slip_scale: float | np.ndarray | None = normal_slip_scale()
    normal_time: float | np.ndarray | None = normal_time()
    bonded: np.ndarray | None = bonded_mask()
    kind = "rate_state"
    #: a small scene of the law (docs/reference/toml.md shows it, tests/docs/test_toml_page.py runs it)
    example = """\
# TPV101 on a coarse grid (600 m): ageing law, sliding at 1e-12 m/s under 75 MPa,
# nucleated by a 25 MPa patch of radius 3 km that grows over 1 s
name = "rate_state_example"
t_end = 2.0

[units]
length = "m"
time = "s"
stress = "Pa"

[material]
mu = 3.2038e10
cs = 3464.0
nu = 0.25

[grid]
n1 = 64
n3 = 32
L1 = 38400.0
L3 = 19200.0

[law]
kind = "rate_state"
a = 0.008
b = 0.012
L = 0.02
V0 = 1e-6
f0 = 0.6
sigma_n = 120e6
V_ini = 1e-12
evolution = "ageing"

[loading]
tau0_1 = 75e6
nucleation_dtau_1 = 25e6
nucleation_radius = 3000.0
nucleation_time = 1.0
nucleation_x1 = 19200.0
nucleation_x3 = 9600.0

[record]
fields = ["v_1", "psi"]
every = 10

[record.stations]
hypocentre = [19200.0, 9600.0]
"""
    state_variables = {"psi": ("state variable psi of f = a asinh[V exp(psi / a) / (2 V0)]", "1"), **NORMAL_STATE}
    heals = True

    def __post_init__(self):
        for name in ("a", "b", "L", "V0"):
            check_parameter(self, name)
        _check_finite(self, "f0")
        if self.sigma_n is not None:
            check_parameter(self, "sigma_n", allow_equal=True)
        self.check_normal()
        if self.V_ini is None and self.psi_ini is None:
            raise InputError("law.V_ini", "is required: the initial slip rate (> 0; the initial state then "
                                          "follows from the load at t = 0), or give law.psi_ini, the initial state")
        if self.V_ini is not None:
            check_parameter(self, "V_ini")
        if self.psi_ini is not None:
            _check_finite(self, "psi_ini")
        if not isinstance(self.evolution, str) or self.evolution not in EVOLUTIONS:
            raise InputError("law.evolution", f"must be one of {', '.join(EVOLUTIONS)}, got {self.evolution!r}")
        if (self.f_w is None) != (self.V_w is None):
            given, missing = ("f_w", "V_w") if self.V_w is None else ("V_w", "f_w")
            raise InputError(f"law.{missing}", f"must be given with law.{given} (strong velocity weakening needs both)")
        if self.f_w is not None:
            if self.evolution != "slip":
                raise InputError("law.f_w", f"strong velocity weakening (f_w, V_w) goes with evolution = 'slip', "
                                            f"got evolution = {self.evolution!r}")
            check_parameter(self, "f_w")
            check_parameter(self, "V_w")
        object.__setattr__(self, "_cache", {})

    # -- the protocol
    def state_fields(self) -> float:
        """psi, V and ln V, the strength, the last step's V, z and its last value (the ageing
        law; the slip laws: psi's last value), sigma* when regularised, the predictor's two
        work arrays (where the predictor solves without the traction: the shear product
        scheme) and, for the ageing law, the compiled pass's flags (a byte a point); the
        pass's parameters derived from fields (1 / a, dt / L, V0 dt / L, ln 2 V0)."""
        ageing = self.evolution == "ageing"
        fields = 4 + (3 if ageing else 2) + self.normal_fields() + 2 + (1 / 8 if ageing else 0)
        field = {name: np.ndim(getattr(self, name)) > 0 for name in ("a", "L", "V0")}
        return fields + field["a"] + field["L"] + (field["L"] or field["V0"]) + field["V0"]

    def init_state(self, grid):
        """psi (recorded), V and ln V, the strength; the evolution variable z with its value
        at the last step (z = exp((psi - f0) / b) = V0 theta / L for the ageing law, psi
        itself for the slip laws); the stage of the step and the Newton counts."""
        shape = grid.shape
        psi = np.full(shape, np.nan) if self.psi_ini is None else \
            np.array(np.broadcast_to(np.asarray(self.psi_ini, dtype=float), shape))
        state = {"psi": psi, "psi_old": psi.copy(), "V": np.zeros(shape), "V_old": np.zeros(shape),
                 "lnV": np.full(shape, -np.inf), "strength": np.zeros(shape), "stage": INITIAL,
                 "newton_evaluations": 0, "newton_solves": 0, "newton_most": 0, "spacing": [grid.dx1, grid.dx3],
                 **self.normal_state(grid)}
        if self.evolution == "ageing":
            del state["psi_old"]
            state["z"], state["z_old"] = np.zeros(shape), np.zeros(shape)
        return state

    def _z(self, state):
        """(z, z at the last step) of ``state``."""
        return (state["z"], state["z_old"]) if "z" in state else (state["psi"], state["psi_old"])

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        """A new step: the state and V of the last one start this one's state update (the
        arrays swap: the step's solves write every point of z and V anew)."""
        self.normal_update(state, dt, v_prev)
        if v_prev is None:
            state["stage"] = INITIAL
            return
        name = "z" if "z" in state else "psi"
        state[name], state[f"{name}_old"] = state[f"{name}_old"], state[name]
        state["V"], state["V_old"] = state["V_old"], state["V"]
        state["stage"] = PREDICT

    def strength(self, state, t, grid):
        """The strength sigma f(V, psi) the step's solve finds (filled in by :meth:`solve`)."""
        return state["strength"]

    def applied_strength(self, strength, tau, state=None):
        return strength

    def check_scene(self, scene):
        """The initial state from V_ini needs, at every point, a shear load at t = 0 above
        eta V_ini under compression; given psi_ini too, the two must agree with it."""
        super().check_scene(scene)
        if self.V_ini is None:
            return
        grid = scene.grid
        shape = grid.shape
        tau0 = {c: np.broadcast_to(np.asarray(v, dtype=float), shape)
                for c, v in scene.loading.at(0.0, (1, 2, 3), grid=grid).items()}
        T = np.sqrt(tau0[1] ** 2 + tau0[3] ** 2)
        sigma = np.broadcast_to(np.maximum(0.0, -tau0[2]) if self.follows_normal else
                                np.asarray(self.sigma_n, dtype=float), shape)
        eta = scene.material.eta(1)
        Vi = np.broadcast_to(np.asarray(self.V_ini, dtype=float), shape)
        a = np.broadcast_to(np.asarray(self.a, dtype=float), shape)
        free = np.ones(shape, bool) if self.bonded is None else ~np.asarray(self.bonded, dtype=bool)
        ok = (T - eta * Vi > 0) & (sigma > 0)
        if not np.all(ok | ~free):
            i, k = np.argwhere(~ok & free)[0]
            sig = "sigma_n" if not self.follows_normal else "-tau0_2"
            raise InputError("law.V_ini", f"the initial state from V_ini needs, at every point, a shear load at t = 0 "
                                          f"above eta V_ini and compression ({sig} > 0); at node ({i}, {k}), x1 = "
                                          f"{grid.x1[i]:g}, x3 = {grid.x3[k]:g}: |tau0| = {T[i, k]:g}, eta V_ini = "
                                          f"{eta * Vi[i, k]:g}, {sig} = {sigma[i, k]:g}")
        if self.psi_ini is None:
            return
        psi = np.broadcast_to(np.asarray(self.psi_ini, dtype=float), shape)
        carried = sigma * friction_coefficient(Vi, psi, a, np.broadcast_to(np.asarray(self.V0, float), shape))
        wanted = T - eta * Vi
        off = (np.abs(carried - wanted) > 1e-6 * np.abs(wanted)) & free
        if np.any(off):
            i, k = np.argwhere(off)[0]
            raise InputError("law.psi_ini", f"is inconsistent with the initial stress: at node ({i}, {k}), x1 = "
                                            f"{grid.x1[i]:g}, x3 = {grid.x3[k]:g}, sigma f(V_ini, psi_ini) = "
                                            f"{carried[i, k]:.9g} but |tau0| - eta V_ini = {wanted[i, k]:.9g} (a "
                                            f"relative difference above 1e-6); give law.V_ini or law.psi_ini alone")

    def solve(self, state, tau_star, delta, eta, dt, strength, load=None, traction=True):
        """Step (v): the normal component first when the law follows it (friction.py), then
        the shear components, V from |tau*| - eta V = sigma f(V, psi) with the state update
        of the step (module docstring)."""
        part = (lambda cs: None if load is None else (load[0], {c: load[1][c] for c in cs}))
        shear = tuple(c for c in SHEAR if c in tau_star)
        v, tau = {}, {}
        if self.follows_normal and 2 in tau_star:
            v, tau = solve_velocity(self, state, {2: tau_star[2]}, delta, eta, dt, 0.0, part((2,)), True)
            sigma = self.normal_stress(state, tau[2])
        else:
            sigma = self.sigma_n
        stage = state["stage"]
        mode = INITIAL if stage == INITIAL else CORRECT if stage == CORRECT else PREDICT if not traction else FULL
        vs, ts = self._slide(state, {c: tau_star[c] for c in shear}, eta[shear[0]], dt, sigma, part(shear), mode)
        if stage != INITIAL:
            state["stage"] = CORRECT
        v.update(vs)
        v = {c: v[c] for c in sorted(v)}
        if not traction:
            return v, None
        tau.update(ts)
        return v, {c: tau[c] for c in v}

    # -- the sequence solvers' protocol (cracklab.solver.sequence)
    def slide_rates(self, T, psi, sigma, eta, guess=None, at=None):
        """The slip rate V >= 0 with T - eta V = sigma f(V, psi) at every point (docs/reference/
        equations.md, "Rate-and-state friction") and the state's rate dpsi/dt at it, from the
        shear traction magnitude T if the plane stopped, the state psi, the compressive
        normal stress sigma and the radiation damping eta (a number): step (v) without a
        state update, for solvers that integrate psi themselves (cracklab.solver.sequence),
        in one compiled pass. ``guess``: ln V to start Newton from (None: the analytic
        bracket); ``at``: the points of the grid (a flat mask) T holds, for parameters that
        are fields. Returns (V, ln V, dpsi/dt), flat arrays."""
        T = np.ascontiguousarray(T, dtype=float).ravel()
        n = T.size

        def flat(x):
            x = np.asarray(x, dtype=float).ravel()
            return x if x.size == n and x.flags.c_contiguous else np.ascontiguousarray(np.broadcast_to(x, (n,)))

        params = self._points(at, n)
        x0 = np.full(n, np.nan) if guess is None else flat(guess)
        V, lnV, dpsi = np.empty(n), np.empty(n), np.empty(n)
        law = AGEING if self.evolution == "ageing" else STRONG if self.f_w is not None else SLIP
        _kernel()
        bad = globals()["_rate_loop"](T, flat(psi), flat(sigma), float(eta), *params, law, x0, V, lnV, dpsi)
        if bad >= 0:
            raise SimulationError(f"rate-and-state: no slip rate V >= 0 solves T - eta V = sigma f(V, psi) at point "
                                  f"{bad}: T = {T[bad]:.6g}, sigma = {flat(sigma)[bad]:.6g}, eta = {eta:.6g}, "
                                  f"psi = {flat(psi)[bad]:.6g}")
        return V, lnV, dpsi

    def evolve_state(self, psi, V, h, at=None):
        """psi after a step of ``h`` (s) at the constant slip rate ``V`` >= 0 at every point,
        exactly (the state update of step (v): module docstring), for solvers that integrate
        psi themselves (cracklab.solver.sequence); ``at`` as in :meth:`slide_rates`. Flat."""
        psi = np.ascontiguousarray(psi, dtype=float).ravel()
        V = np.ascontiguousarray(np.broadcast_to(np.asarray(V, dtype=float).ravel(), psi.shape))
        out = np.empty_like(psi)
        law = AGEING if self.evolution == "ageing" else STRONG if self.f_w is not None else SLIP
        _kernel()
        globals()["_evolve_loop"](psi, V, float(h), *self._points(at, psi.size), law, out)
        return out

    def _points(self, at, n):
        """(array, stride) pairs of a, b, V0, L, f0, f_w, V_w at the ``n`` points ``at`` (a
        flat mask of the grid; None: every point), as ``_flat`` gives them; kept for the
        mask of the last call (a sequence's system passes one mask every time)."""
        last = self._cache.get("points")
        if last is not None and last[0] is at and last[1] == n:
            return last[2]
        full = (n,) if at is None else (np.size(at),)
        out = []
        for name, missing in (("a", None), ("b", None), ("V0", None), ("L", None), ("f0", None), ("f_w", 0.0),
                              ("V_w", 1.0)):
            v = getattr(self, name)
            arr, stride = _flat(np.ravel(missing if v is None else v), full)
            out += [np.ascontiguousarray(arr[at]) if stride and at is not None else arr, stride]
        self._cache["points"] = (at, n, tuple(out))
        return self._cache["points"][2]

    def initial_state(self, T, sigma, eta):
        """psi at t = 0 over the grid: ``psi_ini``, or the state at which the plane slides at
        V_ini under the shear traction magnitude T (a field), sigma f(V_ini, psi) = T - eta V_ini."""
        T = np.asarray(T, dtype=float)
        if self.psi_ini is not None:
            return np.array(np.broadcast_to(np.asarray(self.psi_ini, dtype=float), T.shape))
        a, V0, Vi = (np.asarray(x, dtype=float) for x in (self.a, self.V0, self.V_ini))
        y = (T - eta * Vi) / (np.asarray(sigma, dtype=float) * a)
        with np.errstate(divide="ignore", invalid="ignore"):
            lnsinh = np.where(y > 20.0, y - LN2, np.log(np.sinh(np.minimum(y, 20.0))))
        return np.array(np.broadcast_to(a * (np.log(2.0 * V0 / Vi) + lnsinh), T.shape))

    def _constants(self, shape, dt):
        """The parameters as (flat array, stride) for the pass, with 1 / a, dt / L, V0 dt / L and ln(2 V0)."""
        key = (shape, dt)
        if key not in self._cache:
            self._cache.clear()
            V0, L = np.asarray(self.V0, dtype=float), np.asarray(self.L, dtype=float)
            a = np.asarray(self.a, dtype=float)
            self._cache[key] = (_flat(a, shape), _flat(1.0 / a, shape), _flat(self.b, shape), _flat(dt / L, shape),
                                _flat(V0 * dt / L, shape), _flat(np.log(2.0 * V0), shape),
                                _flat(self.f0, shape), _flat(0.0 if self.f_w is None else self.f_w, shape),
                                _flat(1.0 if self.V_w is None else self.V_w, shape),
                                _flat(1.0 if self.V_ini is None else self.V_ini, shape),
                                (np.zeros(1, bool), False) if self.bonded is None else
                                (np.ascontiguousarray(self.bonded, dtype=bool).ravel(), True))
        return self._cache[key]

    def _slide(self, state, tau_star, eta, dt, sigma, load, mode):
        """The compiled pass over the shear components in ``tau_star``; returns (v, tau)."""
        comps = tuple(tau_star)
        shape = np.shape(tau_star[comps[0]])
        zero = np.zeros(shape)
        t1 = np.ascontiguousarray(tau_star.get(1, zero), dtype=float).ravel()
        t3 = np.ascontiguousarray(tau_star.get(3, zero), dtype=float).ravel()
        g, (l1, sl1), (l3, sl3) = 0.0, (np.zeros(1), 0), (np.zeros(1), 0)
        if load is not None:
            g = float(load[0])
            l1, sl1 = _flat(load[1].get(1, 0.0), shape)
            l3, sl3 = _flat(load[1].get(3, 0.0), shape)
        a, ia, b, dtL, q, ln2v0, f0, fw, Vw, Vi, (bonded, has_bonded) = self._constants(shape, dt)
        sig = _flat(sigma, shape)
        law = AGEING if self.evolution == "ageing" else STRONG if self.f_w is not None else SLIP
        z, z_old = self._z(state)
        from_v = mode == INITIAL and self.psi_ini is None
        if mode == PREDICT:     # only v, which the corrector reads: into the state's work arrays
            if state.get("work") is None or state["work"][0].shape != shape:
                state["work"] = [np.empty(shape), np.empty(shape)]
            out = state["work"] * 2
        else:
            out = [np.empty(shape) for _ in range(4)]
        arrays = (z_old.ravel(), state["V_old"].ravel(), z.ravel(), state["psi"].ravel(), state["V"].ravel(),
                  state["lnV"].ravel(), state["strength"].ravel(), *(o.ravel() for o in out))
        n = t1.size
        fast = bool(law == AGEING and mode in (PREDICT, CORRECT) and _fast_kernel())
        if fast:
            slow = state.get("slow")
            if slow is None or slow.size != n:
                slow = state["slow"] = np.empty(n, dtype=np.int8)
        else:
            slow = np.zeros(1, dtype=np.int8)
        # (built without the fast pass too: the compiled driver types both calls)
        fast_args = (t1, t3, g, *(_field(x) for x in ((l1, sl1), (l3, sl3), sig, a, b, dtL, q, ln2v0)),
                     mode == CORRECT, float(eta), bonded, has_bonded, *arrays, slow)
        slide_args = (t1, t3, g, l1, sl1, l3, sl3, *sig, *a, *ia, *b, *dtL, *q, *ln2v0, *f0, *fw, *Vw, *Vi, law, mode,
                      from_v, float(eta), bonded, has_bonded, *arrays, slow, fast)
        total, solves, most, bad = _kernel()(n, CHUNK if fast else max(n, 1), fast, fast_args, slide_args)
        state["newton_evaluations"] += int(total)
        state["newton_solves"] += int(solves)
        state["newton_most"] = max(state["newton_most"], int(most))
        if bad >= 0:
            self._failed(state, bad, shape, t1, t3, g, l1, sl1, l3, sl3, sig, eta)
        v1, v3, o1, o3 = out
        v = {c: (v1 if c == 1 else v3) for c in comps}
        return v, {c: (o1 if c == 1 else o3) for c in comps}

    def _failed(self, state, i, shape, t1, t3, g, l1, sl1, l3, sl3, sig, eta):
        node = tuple(int(n) for n in np.unravel_index(i, shape))
        x1, x3 = node[0] * state["spacing"][0], node[1] * state["spacing"][1]
        T = math.hypot(t1[i] + g * l1[i * sl1], t3[i] + g * l3[i * sl3])

        def at(x):
            x = np.asarray(x, dtype=float).ravel()
            return float(x[i] if x.size > 1 else x[0])

        raise SimulationError(
            f"rate-and-state step (v) did not converge at node {node}, x1 = {x1:g}, x3 = {x3:g}: |tau*| = {T:.6g}, "
            f"sigma = {at(sig[0]):.6g}, eta = {eta:.6g}, a = {at(self.a):.6g}, "
            f"V0 = {at(self.V0):.6g}, psi = {at(state['psi']):.6g} (V = {at(state['V_old']):.6g} at the last "
            f"step): no slip rate V >= 0 solves |tau*| - eta V = "
            f"sigma f(V, psi); the run was stopped")


def _check_finite(law, name):
    value = getattr(law, name)
    try:
        arr = np.asarray(value, dtype=float)
        bad = isinstance(value, (bool, np.bool_, str, bytes)) or not np.all(np.isfinite(arr))
    except (TypeError, ValueError, OverflowError):
        bad = True
    if bad:
        raise InputError(f"law.{name}", f"must be a finite number or an (n1, n3) field of them, got {value!r}"
                         if np.ndim(value) == 0 else f"must be a finite number or an (n1, n3) field of them")
    if np.ndim(value) == 0:
        object.__setattr__(law, name, float(value))
