"""The product scheme with the law at the step's mean velocity (docs/reference/stability.md, "The
order of a rupture front"): the same response as ``product`` (Z integrated exactly against
the piecewise-linear velocity, the trapezoid update (50), one predictor-corrector pass),
but the law's update of step n, which the product scheme makes with v_{n-1} (a slip path
S_n = S_{n-1} + dt |v_{n-1}|, the rectangle rule, half a step behind the trapezoid slip of
(50)), is made with the mean velocity (v_{n-1} + v*_n)/2 of the step, v*_n the predicted
velocity: S_n = S_{n-1} + dt |v_{n-1} + v*_n|/2, the trapezoid rule. The predictor's law
solve runs on a copy of the law's state updated with v_{n-1}, as the product scheme's
does where the law reads the slip; a law that reads the slip gets the product scheme's
trial slips. On a slip-weakening front the rupture time converges at second order in dt,
where the product scheme's converges at first. Two FFT pairs, two law updates and two
pointwise law solves per step."""
from __future__ import annotations

import numpy as np

from ..loops import plus_mean, plus_scaled
from .base import register
from .product import Product


@register
class Product2(Product):
    name = "product2"
    order = 3
    mean_velocity = True

    def estimate(self, run, n, t):
        """The predictor (velocity held at v_{n-1}; the law on a copy of its state, updated
        with v_{n-1}), then the corrector's f_n and the law's update with the step's mean
        velocity (v_{n-1} + v*_n)/2 (and, where the law reads the slip, the trial slip
        delta_{n-1} + dt (v_{n-1} + v*_n)/2)."""
        response, law, delta, v, tau = run.response, run.law, run.delta, run.v, run.tau
        dt, comps, eta, grid = run.dt, run.comps, run.eta, run.grid
        f = response.predict(v)
        if n == 0:
            return f, delta, None
        work, mean = run.work, run.vmean
        trial = {c: plus_scaled(delta[c], dt, v[c], out=work[c]) for c in comps} if run.trial_slips else delta
        pstate = {k: (a.copy() if isinstance(a, np.ndarray) else a) for k, a in run.lstate.items()}
        law.update(pstate, trial, dt, v, t, tau)
        # tau* = tau0 + f (the law's solve adds the load; f: the response's work arrays)
        terms = run.load.terms(t, comps, run.crack_length(pstate), grid)
        vp, _ = law.solve(pstate, f, trial, eta, dt, law.strength(pstate, t, grid), terms, traction=False)
        f = response.correct(vp)
        for c in comps:
            np.add(v[c], vp[c], out=mean[c])
            mean[c] *= 0.5
        if run.trial_slips:
            trial = {c: plus_mean(delta[c], 0.5 * dt, v[c], vp[c], out=work[c]) for c in comps}
        return f, trial, run.update_law(n, t, trial, mean, tau)
