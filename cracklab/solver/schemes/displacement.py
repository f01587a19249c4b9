"""The displacement formulation: Eq. (32) with the trapezoid pre-integrated kernel (46)
and the explicit update (37), F_n = -(mu q / 2) gamma sum_{j=0}^n xk_j D_{n-j}."""
from __future__ import annotations

from ..loops import add_scaled
from .base import Channel, Scheme, register


@register
class Displacement(Scheme):
    name = "displacement"
    order = 0
    rule = "trapezoid"
    convolves = "displacement"
    lag = 0
    any_rule = True      # the trapezoid (46), or the discretized (45) or simpson (47) weights
    modal = ("displacement", "trapezoid", "explicit")
    #: studies/stability_nu.py (docs/figures/stability_nu.json): gamma = q c_s dt at
    #: solver.stability.NU_NODES
    limits = {
        "I": (3.3031, 3.2719, 3.2375, 3.1844, 3.1219, 3.0516, 2.9750, 2.8984, 3.2375, 3.2313,
                3.2313, 2.7078, 2.6391, 2.5922, 2.5453, 2.4969, 2.4406, 2.3781, 2.3062, 2.2266,
                2.1391, 2.0422, 1.9344, 1.8125, 1.6719, 1.4992, 1.2742, 1.1609, 1.0250, 0.9453,
                0.8547, 0.7488, 0.6188, 0.5391, 0.4430, 0.3451, 0.2004),
        "II": (3.1469, 3.1469, 3.1469, 3.1469, 3.1344, 3.1344, 0.4859, 0.3357, 0.2793, 0.2721,
                0.2656, 0.2598, 0.2547, 0.2500, 0.2455, 0.2416, 0.2381, 0.2352, 0.2324, 0.2303,
                0.2281, 0.2260, 0.2238, 0.2217, 0.2193, 0.2162, 0.2121, 0.2098, 0.2070, 0.2055,
                0.2035, 0.2014, 0.1984, 0.1967, 0.1945, 0.1924, 0.1896),
        "III": (2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250,
                2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250,
                2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250,
                2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250),
    }

    def channel(self, kernel, engine, q, gamma, mu, cs, nu):
        return Channel(kernel, engine, -mu * q * gamma)

    def estimate(self, run, n, t):
        """delta_n = delta_{n-1} + dt v_{n-1} (37), then f_n of delta_n."""
        delta, v, dt = run.delta, run.v, run.dt
        if n > 0:
            for c in run.comps:
                 add_scaled(delta[c], dt, v[c])
        return run.response.functional(delta), delta, None
