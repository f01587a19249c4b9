"""The time stepper: steps (i)-(v) of section 3 for any active set of components."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .errors import SimulationError
from .laws import solve_velocity
from .response import Response
from .spectral import Transforms


@dataclass
class State:
    """Solver state after step n (time t)."""

    n: int
    t: float
    delta: dict
    v: dict
    tau: dict
    strength: np.ndarray
    law_state: dict


def steps(scene, response=None):
    """Generate the State after each step n = 0 .. nsteps.

    Displacement formulation: explicit update (37), delta_n = delta_{n-1} + dt v_{n-1}.
    Velocity formulation: semi-implicit update (50); the functional is evaluated at
    delta*_n = delta_{n-1} + dt v_{n-1}/2 and the law at the predictor delta_{n-1} + dt v_{n-1}.
    Product scheme: trapezoid update (50) with one predictor-corrector pass: the law is
    solved with the velocity held at v_{n-1} (on a copy of the law state), then again
    with the functional of that predicted velocity; 2 FFT pairs per step.
    """
    grid, mat, law, load = scene.grid, scene.material, scene.law, scene.loading
    comps = scene.components
    dt = scene.dt
    if response is None:
        response = Response(mat, grid, dt, comps, formulation=scene.formulation,
                            engine=scene.numerics.engine, window=scene.numerics.window,
                            transforms=Transforms(grid, scene.numerics.fft_threads))
    eta = {c: mat.eta(c) for c in comps}
    zero = {c: np.zeros(grid.shape) for c in comps}
    delta = {c: zero[c].copy() for c in comps}
    v = {c: zero[c].copy() for c in comps}
    lstate = law.init_state(grid)
    velocity = scene.formulation == "velocity"
    product = scene.formulation == "product"
    area = grid.dx1 * (grid.dx3 if not grid.plane else 1.0)
    width = grid.L3 if not grid.plane else 1.0
    l0 = None
    tau = None
    for n in range(scene.nsteps + 1):
        t = n * dt
        if product:
            known = {c: delta[c] + 0.5 * dt * v[c] for c in comps} if n > 0 else delta
            f = response.predict(v)
            trial = {c: known[c] + 0.5 * dt * v[c] for c in comps} if n > 0 else delta
            if n > 0:  # predictor: the law on a copy of its state
                pstate = {k: (a.copy() if isinstance(a, np.ndarray) else a) for k, a in lstate.items()}
                law.update(pstate, trial, dt, v, t, tau)
                tau0 = load.at(t, comps, _crack_length(law, pstate, load, area, width, l0))
                vp, _ = solve_velocity(law, pstate, {c: tau0[c] + f[c] for c in comps}, trial, eta, dt,
                                       law.strength(pstate, t, grid))
                f = response.correct(vp)
                trial = {c: known[c] + 0.5 * dt * vp[c] for c in comps}
        elif velocity:
            dstar = {c: delta[c] + 0.5 * dt * v[c] for c in comps}
            f = response.functional(dstar, v)
            trial = {c: delta[c] + dt * v[c] for c in comps}
        else:
            if n > 0:
                for c in comps:
                    delta[c] += dt * v[c]
            f = response.functional(delta)
            trial = delta
        law.update(lstate, trial, dt, v if n > 0 else None, t, tau if n > 0 else None)
        if load.constant_K and l0 is None:
            l0 = load.l0 or _crack_length(law, lstate, load, area, width, None)
            if load.l0 is None:
                # Loading.factor scales by sqrt(l0 / l): give it the initial length
                load = dataclasses.replace(load, l0=l0)
        length = _crack_length(law, lstate, load, area, width, l0)
        tau0 = load.at(t, comps, length)
        strength = law.strength(lstate, t, grid)
        tau_star = {c: tau0[c] + f[c] for c in comps}
        v_new, tau = solve_velocity(law, lstate, tau_star, trial, eta, dt, strength)
        if (velocity or product) and n > 0:
            # semi-implicit update (50) for n >= 1; delta_0 = 0 (the load starts at t = 0)
            for c in comps:
                delta[c] += 0.5 * dt * (v[c] + v_new[c])
        v = v_new
        check_finite(n, t, v, grid)
        yield State(n, t, delta, v, tau,
                    np.broadcast_to(strength, grid.shape), lstate)


def _crack_length(law, state, load, area, width, l0):
    """Mean crack length for constant-K loading (None when the load does not need it)."""
    if not load.constant_K:
        return None
    failed = law.failed(state)
    length = float(np.count_nonzero(failed)) * area / width if failed is not None else None
    return length or l0


def check_finite(n, t, v, grid):
    for c, vc in v.items():
        if not np.isfinite(vc).all():
            i, k = np.unravel_index(np.argmax(~np.isfinite(vc)), vc.shape)
            raise SimulationError(
                f"non-finite v_{c} at step {n} (t = {t:g}) at node ({i}, {k}), "
                f"x1 = {grid.x1[i]:g}, x3 = {grid.x3[k]:g}; the run was stopped")
