"""Slip and state of a rate-and-state plane, fully dynamic, at a variable step (docs/reference/
equations.md, "Sequences: the dynamic response at a variable step"): the quasi-dynamic
system (quasi_dynamic.py) with the static response replaced by the whole of Eq. (33),

    F_j = -(mu q / 2) Z(0) D_j + (mu q / 2) int_0^t Z(q c_s (t - s)) V_j(s) ds   (per channel)

the convolution kept exactly by the history at a variable step (history/variable.py) for
a slip rate linear over each step. The radiation damping -eta V of step (v) is Eq. (3)'s
own; the convolution gives it back as the plane slows down (int_0^inf Z = 1 for II and III),
so between events the traction is the static one. Before t = 0 the plane did not move.

The convolution at the end of a step depends on the slip rate there: the step is a
predictor-corrector (:func:`steps`, Lapusta et al. 2000's, with the history exact), whose
two slip-rate estimates give the error of the step."""
from __future__ import annotations

import numpy as np

from ...history.variable import VariableHistory
from .quasi_dynamic import QuasiDynamic
from .static import StaticResponse


class DynamicResponse:
    """The traction of Eq. (33) between two identical half spaces of ``material`` on ``grid``,
    at steps no shorter than ``h_floor``: the ``static`` response (its components, channels,
    transforms and spring, static.py) plus the convolution of each moving mode.

    Per step: :meth:`prepare` (h), then :meth:`traction` (slip, slip rate at the step's end)
    as often as the step needs, then :meth:`commit` (the end's slip rate)."""

    def __init__(self, static: StaticResponse, material, grid, h_floor):
        self.static = static
        q = np.broadcast_to(static.q, grid.spectral_shape)
        self.moving = np.flatnonzero(q.ravel() > 0)         # the q = 0 mode has no history
        qm = q.ravel()[self.moving]
        self.dynamic = 0.5 * material.mu * qm
        self.engines = {ch: VariableHistory(ch, material.nu, qm * material.cs, h_floor) for ch in self.static.factor}
        self._AB = None
        self._h = None          # the step prepared (a stage's prepare of the same step is kept)

    def start(self, v: dict) -> None:
        """The slip rate at t = 0."""
        V, _ = self.static.spectra(v)
        for ch, eng in self.engines.items():
            eng.start(V[ch].ravel()[self.moving])

    def prepare(self, h: float) -> None:
        if self._AB is not None and h == self._h:
            return
        self._AB = {ch: eng.prepare(h) for ch, eng in self.engines.items()}
        self._h = h

    def traction(self, delta: dict, v_end: dict) -> dict:
        """{component: F} at the end of the step prepared, for the slip ``delta`` there and a
        slip rate growing linearly to ``v_end`` over the step."""
        X, zeros = self.static.spectra(delta)
        V, _ = self.static.spectra(v_end)
        F = {}
        for ch, x in X.items():
            f = self.static.factor[ch] * x
            A, B = self._AB[ch]
            flat = f.reshape(-1)
            flat[self.moving] += self.dynamic * (A + B * V[ch].reshape(-1)[self.moving])
            F[ch] = f
        return self.static.fields(F, zeros)

    def commit(self, v_end: dict) -> None:
        V, _ = self.static.spectra(v_end)
        for ch, eng in self.engines.items():
            eng.commit(V[ch].reshape(-1)[self.moving])
        self._AB = self._h = None

    def get_state(self) -> dict:
        return {ch: eng.get_state() for ch, eng in self.engines.items()}

    def set_state(self, state: dict) -> None:
        for ch, eng in self.engines.items():
            eng.set_state(state[ch])
        self._AB = self._h = None


#: the default slow steps' bound (``FullyDynamic.slow_rate``): the end rate's error moves the
#: solved slip rate by at most this fraction of it (docs/studies/cycles.md, its effect on BP1-FD)
SLOW_FRACTION = 0.1


class FullyDynamic(QuasiDynamic):
    """The fully dynamic system of the same values as :class:`QuasiDynamic`, at steps no
    shorter than ``h_floor`` (a Scene's dt = beta dx / c_s by default)."""

    def __init__(self, material, grid, law, tau0, sigma, plate, creep=None, stiffness=0.0, transforms=None,
                 h_floor=None, mirror=False):
        super().__init__(material, grid, law, tau0, sigma, plate, creep=creep, stiffness=stiffness,
                         transforms=transforms, mirror=mirror)
        self.response = DynamicResponse(self.static, material, grid, h_floor)
        self.v_end = None       # {component: the slip rate field the step's end is taken at}
        self.started = False    # whether the history holds t = 0 (before: no convolution)

    def start(self, f):
        """Start the history with the slip rates of the rates ``f`` at t = 0."""
        self.response.start(self.rate_fields(f))
        self.started = True

    def elastic(self, delta, t=0.0):
        """The static response until the history starts, then Eq. (33) at the step's end."""
        if not self.started:
            return super().elastic(delta, t)
        shape = self.grid.shape
        F = self.response.traction({c: delta[c].reshape(shape) for c in self.comps}, self.v_end)
        return {c: x.ravel() for c, x in F.items()}

    def stage(self, dt, rates, c) -> None:
        """Before the stage i ``dt`` = c_i h into a step of a pair, with the rates of the stages
        before it (``rates``, a row each) and ``c`` = (c_0 .. c_i): the history prepared for a
        step of dt, the end's slip rate in its newest piece extrapolated to c_i along the line
        through the last two stages' rates (the last one's alone after one stage, or when
        the two are at one time)."""
        self.response.prepare(dt)
        f = rates[-1]
        i = len(c) - 1
        if i >= 2 and c[i - 1] > c[i - 2] and c[i] != c[i - 1]:
            f = f + ((c[i] - c[i - 1]) / (c[i - 1] - c[i - 2])) * (rates[-1] - rates[-2])
        self.v_end = self.rate_fields(f)

    def advance(self, y, f_a, f_b, h):
        """y after a step of ``h`` from ``y`` with the rates ``f_a`` at its start and ``f_b``
        at its end: slip by the trapezoid, the state exactly at the constant slip rate
        (|V_a| + |V_b|) / 2 (the law's state update, as in step (v) of the fixed-step runs:
        stable at any h V / L, where a rule on dpsi/dt is not)."""
        y_new = y + 0.5 * h * (f_a + f_b)
        _, psi = self.split(y)
        _, psi_new = self.split(y_new)
        s = self.slides
        speed = 0.5 * (self._speed(f_a) + self._speed(f_b))
        psi_new[s] = self.law.evolve_state(psi[s], speed, h, at=self.at_slides)
        return y_new

    def _speed(self, dy):
        """|V| at the sliding points of the rates ``dy``."""
        dd, _ = self.split(dy)
        s = self.slides
        if len(self.comps) == 1:
            return np.abs(dd[self.comps[0]][s])
        return np.sqrt(sum(dd[c][s] ** 2 for c in self.comps))

    def slow_rate(self, fraction=SLOW_FRACTION) -> float:
        """The slip rate below which the radiation damping eta V moves the solved slip rate
        by at most ``fraction`` of a change of the traction's end rate: fraction times the
        least sigma a / eta over the sliding points (the slow steps' bound, predictor_corrector.py)."""
        s = self.slides
        if not np.any(s):
            return 0.0
        return float(fraction * np.min(self.sigma_s * self._a[s]) / self.eta)

    def rate_fields(self, dy):
        """{component: slip rate field} of the rates ``dy``."""
        dd, _ = self.split(dy)
        shape = self.grid.shape
        return {c: dd[c].reshape(shape) for c in self.comps}

    def get_state(self) -> dict:
        return {"history": self.response.get_state()}

    def set_state(self, state: dict) -> None:
        self.response.set_state(state["history"])
        self.started = True
