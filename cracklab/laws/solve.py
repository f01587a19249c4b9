"""Step (v) of the algorithm, shared by every law whose strength does not depend on v."""
from __future__ import annotations

import numpy as np

from . import loops

SHEAR = (1, 3)


def solve_normal_first(law, state, tau_star, delta, eta, dt, normal_strength, shear_strength, load=None,
                       traction=True):
    """Step (v) of a law whose shear strength depends on the normal traction of the same
    step: the normal component first against ``normal_strength`` (with the law's broken
    points and contact), then the shear components against ``shear_strength(tau)``, a
    function of the tractions just found. Returns (v, tau) as :func:`solve_velocity`."""
    part = (lambda cs: None if load is None else (load[0], {c: load[1][c] for c in cs}))
    shear = tuple(c for c in SHEAR if c in tau_star)
    v, tau = solve_velocity(law, state, {2: tau_star[2]}, delta, eta, dt, normal_strength, part((2,)), True)
    if not shear:       # the plane problem with only the normal component loaded
        return v, (tau if traction else None)
    vs, ts = solve_velocity(law, state, {c: tau_star[c] for c in shear}, delta, eta, dt, shear_strength(tau),
                            part(shear), traction)
    v.update(vs)
    v = {c: v[c] for c in sorted(v)}
    return v, ({c: (tau if c == 2 else ts)[c] for c in v} if traction else None)


def solve_velocity(law, state, tau_star, delta, eta, dt, strength, load=None, traction=True):
    """Step (v): compare strength with the elastic estimate tau* and solve Eq. (3) for v.

    ``tau_star[j]`` is the traction if the plane did not move further (load plus f_j);
    with ``load`` = (g, {j: tau0_j}) it is f_j, and tau* = f_j + g tau0_j (added in the
    compiled pass, else in place first: the same numbers either way).
    Normal component: v = (tau* - S)/eta, non-negative where the point is not fully
    broken, limited by contact. Shear: |v| = (|tau*| - S)^+/eta along tau*.
    Returns (v, tau) as dicts over the active components (tau None unless ``traction``).
    """
    v = {}
    done = {}  # components whose v (bonded points included) and tau are final
    compiled = loops.compiled()
    shape = np.shape(next(iter(tau_star.values())))
    normal_fused = 2 in tau_star and compiled and len(shape) > 0
    shear_fused = compiled and all(c in tau_star for c in SHEAR)
    # the load each compiled pass adds itself; the rest is added here first
    nload = load if normal_fused and loops.fusable_load(load, shape, (2,)) else None
    sload = load if shear_fused and loops.fusable_load(load, shape, SHEAR) else None
    if load is not None:
        for c in tau_star:
            if (nload if c == 2 else sload) is None:
                loops.add_scaled(tau_star[c], load[0], load[1][c])
    if normal_fused:  # one compiled pass, same numbers
        contact = delta[2] if getattr(law, "contact", False) else None
        v[2], done[2] = loops.normal_velocity(tau_star[2], strength, eta[2], law.broken(state), contact, dt,
                                              law.bonded, load=nload)
    elif 2 in tau_star:
        v2 = (tau_star[2] - strength) / eta[2]
        broken = law.broken(state)
        v2 = np.where(broken, v2, np.maximum(v2, 0.0)) if broken is not True else v2
        if getattr(law, "contact", False):
            v2 = np.maximum(v2, -delta[2] / dt)
        v[2] = v2
    shear = [c for c in SHEAR if c in tau_star]
    if shear_fused:  # one compiled pass, the same numbers as below
        v[1], v[3], done[1], done[3] = loops.shear_velocity(tau_star[1], tau_star[3], strength, eta[1], law.bonded,
                                                            load=sload, traction=traction)
        shear = []
    if shear:
        mag = np.sqrt(sum(tau_star[c] ** 2 for c in shear))
        excess = np.maximum(mag - strength, 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            scale = np.where(mag > 0, excess / (eta[shear[0]] * mag), 0.0)
        for c in shear:
            v[c] = scale * tau_star[c]
    if law.bonded is not None:
        for c in v:
            if c not in done:
                v[c] = np.where(law.bonded, 0.0, v[c])
    if not traction:
        return v, None
    tau = {c: done[c] if c in done else tau_star[c] - eta[c] * v[c] for c in v}
    return v, tau
