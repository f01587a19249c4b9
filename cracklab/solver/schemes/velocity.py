"""The velocity formulation: Eq. (33) with the discretised kernel (45) and the
semi-implicit update (50); F_n = -(mu q / 2) Z(0) D*_n + (mu / 2 c_s) gamma
[sum_{j=1}^n xk_j V_{n-j} - xk_n V_0 / 2] with D*_n = D_{n-1} + dt V_{n-1} / 2 (the V_n
terms of (50) cancel exactly, so the step stays explicit)."""
from __future__ import annotations

import numpy as np

from ...elastic.kernels import Z as Z_kernel
from ..loops import add_mean_step
from .base import Channel, Scheme, register


def z_at_zero(kernel, nu) -> float:
    """Z(0) = int_0^inf C of a kernel (the static term of the velocity formulation)."""
    return float(Z_kernel(kernel, np.zeros(1), nu)[0])


@register
class Velocity(Scheme):
    name = "velocity"
    order = 1
    rule = "discretized"
    convolves = "velocity"
    lag = 1
    modal = ("velocity", "discretized", "semi-implicit")
    #: studies/stability_nu.py (docs/figures/stability_nu.json): gamma = q c_s dt at
    #: solver.stability.NU_NODES
    limits = {
        "I": (3.0750, 3.0734, 3.0703, 3.0656, 3.0578, 0.8758, 0.4996, 0.3902, 0.3367, 0.3299,
                0.3238, 0.3189, 0.3152, 0.3129, 0.3119, 0.3131, 0.3172, 0.3258, 0.3418, 0.3734,
                0.4492, 1.6437, 1.5227, 1.4156, 1.2914, 1.1422, 0.9531, 0.8602, 0.7516, 0.6895,
                0.6191, 0.5387, 0.4418, 0.3834, 0.3137, 0.2434, 0.1406),
        "II": (0.5301, 0.4574, 0.4082, 0.3521, 0.3150, 0.2893, 0.2723, 0.2629, 0.2598, 0.2598,
                0.2600, 0.2602, 0.2605, 0.2609, 0.2611, 0.2615, 0.2621, 0.2631, 0.2641, 0.2654,
                0.2668, 0.2680, 0.2691, 0.2701, 0.2705, 0.2701, 0.2684, 0.2670, 0.2650, 0.2639,
                0.2619, 0.2600, 0.2570, 0.2551, 0.2529, 0.2500, 0.2449),
        "III": (2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594,
                2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594,
                2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594,
                2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594),
    }

    def channel(self, kernel, engine, q, gamma, mu, cs, nu):
        return Channel(kernel, engine, mu / cs * gamma, static=-mu * q * z_at_zero(kernel, nu))

    def estimate(self, run, n, t):
        """f_n at delta*_n = delta_{n-1} + dt v_{n-1}/2; the law sees delta_{n-1} + dt v_{n-1}."""
        delta, v, dt = run.delta, run.v, run.dt
        dstar = {c: delta[c] + 0.5 * dt * v[c] for c in run.comps}
        f = run.response.functional(dstar, v)
        return f, {c: delta[c] + dt * v[c] for c in run.comps}, None

    def finish(self, run, n, v_new):
        """The semi-implicit update (50) for n >= 1; delta_0 = 0 (the load starts at t = 0).
        With contact the opening is then kept >= 0: step (v) bounds v_n with the trial
        opening, which the trapezoid of (50) can overshoot at the step the faces close."""
        if n > 0:
            for c in run.comps:
                 add_mean_step(run.delta[c], 0.5 * run.dt, run.v[c], v_new[c])
            if 2 in run.comps and run.law.contact:
                 np.maximum(run.delta[2], 0.0, out=run.delta[2])
