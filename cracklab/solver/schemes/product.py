"""The product scheme: the velocity formulation with Z integrated exactly against the
piecewise-linear velocity history, the trapezoid update (50) and one predictor-corrector
pass (docs/reference/stability.md): F_n = -(mu q / 2) Z(0) D_n + (mu / 2 c_s) gamma [sum_{m=0}^n W_m
V_{n-m} + E_0(n) V_0]; the V_n terms form K V_n with K = (mu gamma / 2 c_s)(W_0 - Z(0)/2),
applied to a predicted, then a corrected velocity. Two FFT pairs per step."""
from __future__ import annotations

import numpy as np

from ..loops import plus_mean, plus_scaled
from ...elastic.weights import product_weights
from .base import register
from .velocity import Velocity, z_at_zero


@register
class Product(Velocity):
    name = "product"
    order = 2
    rule = "product"
    convolves = "velocity"
    lag = 1
    modal = ("velocity", "product", "predictor-corrector")
    needs_trial_slips = True
    #: studies/stability_nu.py (docs/figures/stability_nu.json): gamma = q c_s dt at
    #: solver.stability.NU_NODES
    limits = {
        "I": (3.1344, 3.1344, 2.6484, 3.1344, 3.1344, 6.0000, 6.0000, 5.7406, 5.3812, 5.3156,
                5.2500, 5.1906, 5.1344, 5.0812, 5.0344, 4.9938, 4.9625, 4.9406, 4.9344, 4.9437,
                4.9812, 5.0563, 5.1813, 5.3719, 5.6344, 6.0000, 6.0000, 6.0000, 6.0000, 6.0000,
                6.0000, 5.5781, 4.7875, 4.1219, 3.1812, 2.4500, 1.4078),
        "II": (6.0000, 6.0000, 6.0000, 6.0000, 5.7188, 5.2031, 4.6594, 4.1000, 3.1469, 3.1469,
                3.1469, 3.2437, 3.1406, 3.0437, 2.9453, 2.8484, 2.7531, 2.6594, 2.5672, 2.4766,
                2.3859, 2.2953, 2.2063, 2.1172, 2.0281, 1.9391, 1.8484, 1.8125, 1.7766, 1.7594,
                1.7406, 1.7234, 1.7047, 1.6953, 1.6859, 1.6781, 1.6719),
        "III": (3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563,
                3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563,
                3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563,
                3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563),
    }

    def channel(self, kernel, engine, q, gamma, mu, cs, nu):
        """The velocity formulation's channel, with K, the coefficient of V_n."""
        ch = super().channel(kernel, engine, q, gamma, mu, cs, nu)
        w0 = product_weights(kernel, gamma, np.zeros(gamma.shape, dtype=int), nu=nu, order=1, part="lag")
        ch.K = ch.pre * (w0 - 0.5 * z_at_zero(kernel, nu))
        return ch

    def estimate(self, run, n, t):
        """The predictor (velocity held at v_{n-1}; the law on a copy of its state where it
        reads the slip), then the corrector's f_n with the predicted velocity."""
        response, law, delta, v, tau = run.response, run.law, run.delta, run.v, run.tau
        dt, comps, eta = run.dt, run.comps, run.eta
        f = response.predict(v)
        if n == 0:
            return f, delta, None
        if run.trial_slips:
            work = run.work
            # trial slips: delta_{n-1} + dt (v_{n-1} + v_n)/2 with v_n = v_{n-1}
            trial = {c: plus_scaled(delta[c], dt, v[c], out=work[c]) for c in comps}
            pstate = {k: (a.copy() if isinstance(a, np.ndarray) else a) for k, a in run.lstate.items()}
            law.update(pstate, trial, dt, v, t, tau)
            # tau* = tau0 + f (the law's solve adds the load; f: the response's work arrays)
            terms = run.load.terms(t, comps, run.crack_length(pstate), run.grid)
            vp, _ = law.solve(pstate, f, trial, eta, dt, law.strength(pstate, t, run.grid), terms,
                               traction=False)
            f = response.correct(vp)
            # then with the predicted v_n
            return f, {c: plus_mean(delta[c], 0.5 * dt, v[c], vp[c], out=work[c]) for c in comps}, None
        # the law reads v_{n-1}, t and tau_{n-1}, not the slip: its update is the same for
        # the predictor and the step, done once, and so is its strength
        law_step = run.update_law(n, t, delta, v, tau)
        vp, _ = law.solve(run.lstate, f, delta, eta, dt, *law_step[1:], traction=False)
        return response.correct(vp), delta, law_step
