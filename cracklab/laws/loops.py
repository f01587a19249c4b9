"""Compiled passes of step (v), the interface laws' velocity solve: one pass over the
grid, no temporaries (cracklab.laws.solve). The solver's own passes are in
cracklab.solver.loops; both are compiled through cracklab.jit.

* :func:`shear_velocity`: step (v) for the shear components, |v| = (|tau*| - S)^+ / eta
  along tau*, and the traction tau = tau* - eta v;
* :func:`normal_velocity`: step (v) for the normal component (opening rate and
  traction, with the law's broken mask, contact and bonded points);
* :func:`add_scaled`: y += a x in place (the slip update; the load where step (v) does
  not add it).

Each is a numba loop (compiled on first use, cached on disk); without numba the callers
use the numpy expressions, which give the same numbers to the last bit (the same
operations in the same order, no fast-math).
"""
from __future__ import annotations

import numpy as np

from ..jit import available as compiled, compiled_loop as _compiled, loop

__all__ = ["add_scaled", "compiled", "fusable_load", "normal_velocity", "shear_velocity"]


@loop("shear")
def _shear_loop(t1, t3, g, l1, l3, has_load, strength, scalar, eta, bonded, has_bonded, traction, v1, v3, o1, o3):
    for i in range(t1.size):
        a = t1[i]
        b = t3[i]
        if has_load:  # tau* = f + g tau0 (add_scaled)
            a += g * l1[i]
            b += g * l3[i]
        mag = np.sqrt(a * a + b * b)
        excess = mag - (strength[0] if scalar else strength[i])
        scale = excess / (eta * mag) if (excess > 0.0 and mag > 0.0) else 0.0
        if has_bonded and bonded[i]:
            scale = 0.0
        w1 = scale * a
        w3 = scale * b
        v1[i] = w1
        v3[i] = w3
        if traction:
            o1[i] = a - eta * w1
            o3[i] = b - eta * w3


@loop("normal")
def _normal_loop(t2, g, l2, has_load, strength, scalar, eta, broken, all_broken, contact, delta, dt, bonded,
                 has_bonded, v2, o2):
    for i in range(t2.size):
        t = t2[i]
        if has_load:  # tau* = f + g tau0 (add_scaled)
            t += g * l2[i]
        v = (t - (strength[0] if scalar else strength[i])) / eta
        if not all_broken and not broken[i] and v < 0.0:  # np.maximum(v, 0): NaN stays NaN
            v = 0.0
        if contact:
            lim = -delta[i] / dt
            if v < lim:
                v = lim
        if has_bonded and bonded[i]:
            v = 0.0
        v2[i] = v
        o2[i] = t - eta * v


@loop("axpy")
def _axpy_loop(y, a, x):
    for i in range(y.size):
        y[i] += a * x[i]


def _flat_strength(strength, shape):
    """(flat strength, is scalar): one value, or the field broadcast to ``shape``."""
    S = np.asarray(strength, dtype=float)
    if S.size == 1:
        return S.reshape(1), True
    return np.ascontiguousarray(np.broadcast_to(S, shape)).ravel(), False


def _flat_mask(mask, shape):
    """(flat bool array, present) for an optional mask broadcast to ``shape``."""
    if mask is None:
        return np.zeros(1, bool), False
    return np.ascontiguousarray(np.broadcast_to(mask, shape), dtype=bool).ravel(), True


def _flat_load(load, comps):
    """(g, flat tau0 of each of ``comps``, True) from load = (g, {c: tau0_c}), or (0, zeros, False)."""
    if load is None:
        return (0.0,) + (np.zeros(1),) * len(comps) + (False,)
    g, fields = load
    return (float(g),) + tuple(np.ascontiguousarray(fields[c], dtype=float).ravel() for c in comps) + (True,)


def fusable_load(load, shape, comps) -> bool:
    """Whether the compiled step (v) can add ``load`` = (g, {c: tau0_c}) itself: every
    field of ``comps`` an array of ``shape``."""
    return load is not None and all(np.shape(load[1][c]) == tuple(shape) for c in comps)


def shear_velocity(tau1, tau3, strength, eta, bonded=None, load=None, traction=True):
    """Step (v) in shear: v = (|tau*| - S)^+ / (eta |tau*|) tau* (zero where ``bonded``),
    tau = tau* - eta v; returns (v1, v3, tau1, tau3) (the tractions None unless
    ``traction``). ``strength`` is an array of the grid's shape or a scalar; ``load`` =
    (g, {1: tau0_1, 3: tau0_3}): tau* is tau + g tau0 (arrays of tau1's shape,
    :func:`fusable_load`), added in the pass. Needs numba
    (:func:`compiled`); without it :func:`cracklab.laws.solve_velocity` runs the same step in numpy."""
    S, scalar = _flat_strength(strength, tau1.shape)
    b, has_bonded = _flat_mask(bonded, tau1.shape)
    out = [np.empty(tau1.shape) for _ in range(4 if traction else 2)]
    o = [a.ravel() for a in out] + ([] if traction else [np.empty(1), np.empty(1)])
    _compiled("shear")(np.ascontiguousarray(tau1, dtype=float).ravel(), np.ascontiguousarray(tau3, dtype=float).ravel(),
                       *_flat_load(load, (1, 3)), S, scalar, float(eta), b, has_bonded, bool(traction), *o)
    return tuple(out) if traction else (out[0], out[1], None, None)


def normal_velocity(tau2, strength, eta, broken, contact_delta=None, dt=1.0, bonded=None, load=None):
    """Step (v), normal component: v = (tau* - S)/eta, at least 0 where not ``broken``
    (True: everywhere broken), at least -delta/dt with contact (``contact_delta`` = delta),
    0 where ``bonded``; tau = tau* - eta v; ``load`` = (g, {2: tau0_2}) as in
    :func:`shear_velocity`.  Returns (v, tau), the same numbers as the numpy expressions of
    :func:`cracklab.laws.solve_velocity`.  Needs numba (:func:`compiled`)."""
    S, scalar = _flat_strength(strength, tau2.shape)
    all_broken = broken is True
    b, _ = _flat_mask(None if all_broken else broken, tau2.shape)
    bd, has_bonded = _flat_mask(bonded, tau2.shape)
    contact = contact_delta is not None
    d = np.ascontiguousarray(np.broadcast_to(contact_delta, tau2.shape), dtype=float).ravel() if contact else np.zeros(1)
    v, tau = np.empty(tau2.shape), np.empty(tau2.shape)
    _compiled("normal")(np.ascontiguousarray(tau2, dtype=float).ravel(), *_flat_load(load, (2,)),
                        S, scalar, float(eta), b, all_broken,
                        contact, d, float(dt), bd, has_bonded, v.ravel(), tau.ravel())
    return v, tau


def add_scaled(y, a, x):
    """y += a x in place (y a C-contiguous float array; x of y's shape or broadcastable);
    the same numbers as ``y += a * x``."""
    f = _compiled("axpy")
    if f is None or not y.flags.c_contiguous or np.shape(x) != y.shape:
        y += a * x
        return y
    f(y.ravel(), float(a), np.ascontiguousarray(x, dtype=float).ravel())
    return y
