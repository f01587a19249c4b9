"""The velocity formulation: Eq. (33) with the discretised kernel (45) and the
semi-implicit update (50); F_n = -(mu q / 2) Z(0) D*_n + (mu / 2 c_s) gamma
[sum_{j=1}^n xk_j V_{n-j} - xk_n V_0 / 2] with D*_n = D_{n-1} + dt V_{n-1} / 2 (the V_n
terms of (50) cancel exactly, so the step stays explicit)."""
from __future__ import annotations

import numpy as np

from ..kernels import Z as Z_kernel
from ..loops import add_mean_step
from .base import Channel, Scheme


def z_at_zero(kernel, nu) -> float:
    """Z(0) = int_0^inf C of a kernel (the static term of the velocity formulation)."""
    return float(Z_kernel(kernel, np.zeros(1), nu)[0])


class Velocity(Scheme):
    name = "velocity"
    rule = "discretized"
    convolves = "velocity"
    lag = 1
    modal = ("velocity", "discretized", "semi-implicit")

    def channel(self, kernel, engine, q, gamma, mu, cs, nu):
        return Channel(kernel, engine, mu / cs * gamma, static=-mu * q * z_at_zero(kernel, nu))

    def estimate(self, run, n, t):
        """f_n at delta*_n = delta_{n-1} + dt v_{n-1}/2; the law sees delta_{n-1} + dt v_{n-1}."""
        delta, v, dt = run.delta, run.v, run.scene.dt
        dstar = {c: delta[c] + 0.5 * dt * v[c] for c in run.comps}
        f = run.response.functional(dstar, v)
        return f, {c: delta[c] + dt * v[c] for c in run.comps}, None

    def finish(self, run, n, v_new):
        """The semi-implicit update (50) for n >= 1; delta_0 = 0 (the load starts at t = 0).
        With contact the opening is then kept >= 0: step (v) bounds v_n with the trial
        opening, which the trapezoid of (50) can overshoot at the step the faces close."""
        if n > 0:
            for c in run.comps:
                add_mean_step(run.delta[c], 0.5 * run.scene.dt, run.v[c], v_new[c])
            if 2 in run.comps and run.scene.law.contact:
                np.maximum(run.delta[2], 0.0, out=run.delta[2])
