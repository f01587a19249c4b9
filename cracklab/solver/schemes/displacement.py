"""The displacement formulation: Eq. (32) with the trapezoid pre-integrated kernel (46)
and the explicit update (37), F_n = -(mu q / 2) gamma sum_{j=0}^n xk_j D_{n-j}."""
from __future__ import annotations

from ..loops import add_scaled
from .base import Channel, Scheme


class Displacement(Scheme):
    name = "displacement"
    rule = "trapezoid"
    convolves = "displacement"
    lag = 0
    modal = ("displacement", "trapezoid", "explicit")

    def channel(self, kernel, engine, q, gamma, mu, cs, nu):
        return Channel(kernel, engine, -mu * q * gamma)

    def estimate(self, run, n, t):
        """delta_n = delta_{n-1} + dt v_{n-1} (37), then f_n of delta_n."""
        delta, v, dt = run.delta, run.v, run.scene.dt
        if n > 0:
            for c in run.comps:
                add_scaled(delta[c], dt, v[c])
        return run.response.functional(delta), delta, None
