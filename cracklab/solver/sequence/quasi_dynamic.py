"""Slip and state of a rate-and-state plane as one ODE system, quasi-dynamic (docs/reference/
equations.md, "Sequences: the quasi-dynamic response"): at time t, with slip delta and state
psi,

    tau*_j = tau0_j + F_j[delta] + k (V_p,j t - <delta_j>)        (the static response, static.py)
    |tau*| - eta V = sigma f(V, psi),   v_j = V tau*_j / |tau*|     (step (v), no state update)
    d delta_j / dt = v_j,   d psi / dt = G(V, psi)                  (the law's evolution)

where the plane slides; on the creeping region v_j = V_p,j (kinematic), on bonded points
v_j = 0. eta = mu / (2 c_s), the radiation damping of Eq. (4). The unknowns are one flat
array y = (delta_j for each slipping component, psi)."""
from __future__ import annotations

import numpy as np

from ...errors import InputError
from .mirror import mirror_index
from .static import StaticResponse


class QuasiDynamic:
    """The system of ``material``, ``grid``, the ``law`` (one that heals), ``tau0``
    ({component: field or number}, the shear load), ``sigma`` (compressive normal stress,
    field or number), ``plate`` ({component: V_p >= 0} of every slipping shear component),
    ``creep`` (mask of the creeping region, or None), ``stiffness`` (the spring on the mean
    slip, stress per length): the values of a Scene, which checked them (model/sequence.py,
    ``Sequence.check_scene``; ``system_of`` in run.py builds the system of a scene)."""

    def __init__(self, material, grid, law, tau0, sigma, plate, creep=None, stiffness=0.0, transforms=None,
                 mirror=False):
        comps = tuple(sorted(plate))
        shape = grid.shape
        self.grid, self.law, self.comps = grid, law, comps
        self.n = int(np.prod(shape))
        self.plate = {c: float(v) for c, v in plate.items()}
        bonded = np.zeros(shape, bool) if law.bonded is None else np.broadcast_to(np.asarray(law.bonded, bool), shape)
        creep = np.zeros(shape, bool) if creep is None else np.broadcast_to(np.asarray(creep, bool), shape)
        self.creep = creep.ravel()
        self.slides = (~bonded & ~creep).ravel()
        self.stiffness = float(stiffness)
        self.static = StaticResponse(material, grid, comps, stiffness=self.stiffness, transforms=transforms)
        self.eta = material.eta(comps[0])
        self.tau0 = {c: np.broadcast_to(np.asarray(tau0.get(c, 0.0), dtype=float), shape).ravel() for c in comps}
        self.sigma = np.broadcast_to(np.asarray(sigma, dtype=float), shape).ravel()
        if np.any(self.sigma[self.slides] <= 0) or not np.all(np.isfinite(self.sigma)):
            raise InputError("law.sigma_n", "must be finite and > 0 (compressive) where the plane slides")
        self.sigma_s = np.ascontiguousarray(self.sigma[self.slides])
        self.plate_speed = float(np.sqrt(sum(v * v for v in self.plate.values())))
        # the error scales (``scales``): L and a at every point, and the points integrated
        self._L, self._a = (np.broadcast_to(np.asarray(getattr(law, name), dtype=float), shape).ravel()
                            for name in ("L", "a"))
        self._keep = np.concatenate([self.slides] * (len(comps) + 1))
        # Sequence.mirror: each node's image about x1 = 0, whose traction is made the same
        self.image = mirror_index(shape) if mirror else None
        self.lnV = None     # the last solve's ln V: Newton's guesses for the next
        self.last = None    # (V, tau, v) of the last evaluation of ``rates``

    # -- the unknowns
    def split(self, y):
        """({component: slip}, psi) views of the flat array ``y``."""
        n = self.n
        return {c: y[i * n:(i + 1) * n] for i, c in enumerate(self.comps)}, y[len(self.comps) * n:]

    def initial(self):
        """y at t = 0: no slip, and the law's initial state under the load at t = 0."""
        T = np.sqrt(sum(self.tau0[c] ** 2 for c in self.comps))
        shape = self.grid.shape
        psi = self.law.initial_state(T.reshape(shape), self.sigma.reshape(shape), self.eta).ravel().astype(float)
        psi[~self.slides] = 0.0     # a Scene's load slides at V_ini where it slides (RateState.check_scene)
        return np.concatenate([np.zeros(self.n * len(self.comps)), psi])

    def traction(self, t, y):
        """{component: tau*} at (t, y): load, elastic response and the spring's load."""
        delta, _ = self.split(y)
        shape = self.grid.shape
        F = self.elastic({c: delta[c].reshape(shape) for c in self.comps})
        tau = {c: self.tau0[c] + F[c].ravel() + self.stiffness * self.plate[c] * t for c in self.comps}
        if self.image is not None:      # exactly even: the same solve at a node and its image
            tau = {c: 0.5 * (x + x[self.image]) for c, x in tau.items()}
        return tau

    def elastic(self, delta: dict) -> dict:
        """{component: F} of the slip fields ``delta``: the static response."""
        return self.static.traction(delta)

    def stage(self, dt, rates) -> None:
        """Before a stage ``dt`` into a step, the previous stage's rates ``rates``: nothing for
        the static response (dynamic.py prepares its history here)."""

    def rates(self, t, y):
        """dy/dt at (t, y); keeps (V, tau, v) of the evaluation in ``last``."""
        delta, psi = self.split(y)
        tau = self.traction(t, y)
        s = self.slides
        if len(self.comps) == 1:
            ts = {self.comps[0]: tau[self.comps[0]][s]}
            T = np.abs(ts[self.comps[0]])
        else:
            ts = {c: tau[c][s] for c in self.comps}
            T = np.sqrt(sum(x * x for x in ts.values()))
        Vs, self.lnV, dps = self.law.slide_rates(T, psi[s], self.sigma_s, self.eta, guess=self.lnV, at=s)
        dy = np.zeros_like(y)
        dd, dpsi = self.split(dy)
        V = np.zeros(self.n)
        V[s] = Vs
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.where(T > 0, Vs / T, 0.0)
        for c in self.comps:
            dd[c][s] = ratio * ts[c]
            dd[c][self.creep] = self.plate[c]
            tau[c] -= self.eta * dd[c]
        V[self.creep] = self.plate_speed
        dpsi[s] = dps
        self.last = (V, tau, {c: dd[c].copy() for c in self.comps})
        return dy

    def scales(self, y):
        """The error scale of each unknown relative to the tolerance: slip against L + |slip|,
        state against a (an error of a in psi is a factor e in V)."""
        delta, _ = self.split(y)
        return np.concatenate([self._L + np.abs(delta[c]) for c in self.comps] + [self._a]), self._keep
