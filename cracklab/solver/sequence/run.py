"""A sequence scene's run: the system of the scene (quasi_dynamic.py, or dynamic.py for the
fully dynamic response), its step control, stepped by :func:`integrate.integrate` with the
scene's pair or by :func:`predictor_corrector.integrate_dynamic`, resumable from its state."""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
import numpy as np

from .control import StepControl
from .dynamic import FullyDynamic
from .integrate import integrate
from .pairs import PAIRS
from .predictor_corrector import integrate_dynamic
from .quasi_dynamic import QuasiDynamic


@dataclass(frozen=True)
class SequenceState:
    """After accepted step ``n`` (time ``t``, reached by a step ``dt``): the fields over the
    grid, {component: array} for ``delta``, ``v``, ``tau``; ``psi`` and the slip rate
    magnitude ``V``, each computed when first asked from ``fields`` (the system's
    ``Fields`` at this point, quasi_dynamic.py); :meth:`at` reads a field at a few nodes
    without it, :meth:`peak` the largest slip rate and its node, :meth:`largest` and
    :meth:`spread` keep a running maximum of the slip rate at the system's points."""

    n: int
    t: float
    dt: float
    fields: object = field(repr=False)

    @cached_property
    def delta(self) -> dict:
        return self.fields.grid_of("delta")

    @cached_property
    def v(self) -> dict:
        return self.fields.grid_of("v")

    @cached_property
    def tau(self) -> dict:
        return self.fields.grid_of("tau")

    @cached_property
    def psi(self) -> np.ndarray:
        return self.fields.grid_of("psi")

    @cached_property
    def V(self) -> np.ndarray:
        return self.fields.grid_of("V")

    def at(self, name: str, nodes) -> np.ndarray:
        """The field ``name`` ("delta_3", "v_1", "tau_3", "psi" or "V") at the flat indices
        ``nodes`` (an int64 array) of the grid."""
        kind, _, c = name.partition("_")
        if kind in self.__dict__:           # the field over the grid is there already
            x = self.__dict__[kind]
            return (x[int(c)] if c else x).ravel()[nodes]
        return self.fields.at_of(name, nodes)

    def peak(self, s1, s3) -> tuple:
        """(the largest slip rate over the grid's nodes [s1, s3], its node (i, k)), the first
        node in the grid's order that has it; without the field over the grid."""
        return self.fields.peak_of(s1, s3)

    def largest(self, most=None) -> np.ndarray:
        """``most`` (the largest slip rate so far at each of the system's points; None: a new
        array) raised to this state's slip rate, in place; :meth:`spread` puts it on the grid."""
        V = self.fields.own("V")
        return V.copy() if most is None else np.maximum(most, V, out=most)

    def spread(self, name: str, x) -> np.ndarray:
        """``x``, the field ``name`` at the system's points (or over the grid already), over the
        grid: the plate's values where the plane creeps outside them."""
        return self.fields.spread(name, np.asarray(x, dtype=float))


def system_of(scene, transforms=None) -> QuasiDynamic:
    """The system of a sequence scene: :class:`QuasiDynamic`, or :class:`FullyDynamic` at
    steps no shorter than the scene's dt_min."""
    seq, law, grid = scene.sequence, scene.law, scene.grid
    comps = components_of(scene)
    tau0 = {c: scene.loading.field(c) for c in comps}
    if law.sigma_n is not None:
        sigma = law.sigma_n
    else:
        sigma = np.maximum(0.0, -np.asarray(scene.loading.field(2), dtype=float))
    plate = {c: {1: seq.plate_rate_1, 3: seq.plate_rate_3}[c] for c in comps}
    args = (scene.material, grid, law, tau0, sigma, plate)
    if seq.response == "dynamic":
        dt_min = steps_of(scene)[0]
        return FullyDynamic(*args, creep=seq.creep, stiffness=seq.stiffness, transforms=transforms, h_floor=dt_min,
                            mirror=seq.mirror)
    return QuasiDynamic(*args, creep=seq.creep, stiffness=seq.stiffness, transforms=transforms, mirror=seq.mirror,
                        window=True)


def components_of(scene) -> list:
    """The shear components a sequence scene slips along: the loaded ones and the plate's."""
    return sorted({c for c in scene.components if c in (1, 3)} | set(scene.sequence.plate))


def steps_of(scene) -> tuple:
    """(dt_min, dt_max, dt_first) of a sequence scene, its defaults filled in."""
    return scene.sequence.steps(scene.grid.dx_min, scene.material.cs, scene.t_end, scene.beta)


class SequenceRun:
    """Iterate for the :class:`SequenceState` after each accepted step of ``scene`` (its
    ``sequence`` set), from t = 0 or from ``start`` (a dict of :meth:`get_state`)."""

    def __init__(self, scene, start=None):
        self.scene = scene
        seq = scene.sequence
        self.system = system_of(scene)
        dt_min, dt_max, dt_first = steps_of(scene)
        self.control = StepControl(tolerance=seq.tolerance, dt_min=dt_min, dt_max=dt_max, dt_first=dt_first)
        self.pair = PAIRS[seq.pair]
        self.dynamic = seq.response == "dynamic"
        self.n, self.t, self.dt_next = 0, 0.0, dt_first
        self.y = self.system.initial()
        self.rates = None       # dy/dt at (t, y), from the last accepted step
        if start is not None:
            self.set_state(start)

    def get_state(self) -> dict:
        lnV = self.system.lnV
        return {"n": self.n, "t": self.t, "dt_next": self.dt_next, "y": self.y.copy(),
                "lnV": None if lnV is None else lnV.copy(),
                "rates": None if self.rates is None else self.rates.copy(),
                "last": None if self.system.last is None else list(self.system.last),
                **({"system": self.system.get_state()} if self.dynamic else {})}

    def set_state(self, state: dict) -> None:
        self.n, self.t, self.dt_next = int(state["n"]), float(state["t"]), float(state["dt_next"])
        own = self.system.on_points
        self.y = own(np.array(state["y"], dtype=float))
        lnV = None if state["lnV"] is None else np.array(state["lnV"], dtype=float)
        self.system.lnV = lnV if lnV is None or lnV.size == self.system.solved else None   # another layout's: no guess
        self.rates = None if state["rates"] is None else own(np.array(state["rates"], dtype=float))
        if self.dynamic:
            self.system.set_state(state["system"])
        last = state.get("last")
        self.system.last = None if last is None else (own(last[0]), {int(c): own(a) for c, a in last[1].items()},
                                                      {int(c): own(a) for c, a in last[2].items()})

    def state(self, dt=0.0) -> SequenceState:
        """The fields at the current point (the system's last evaluation is at it)."""
        sysm = self.system
        if sysm.last is None:
            sysm.rates(self.t, self.y)
        return SequenceState(self.n, self.t, dt, sysm.fields(self.t, self.y, sysm.last))

    def __iter__(self):
        if self.n == 0:
            yield self.state()
        if self.dynamic:
            seq = self.scene.sequence
            slow = self.system.slow_rate() if seq.slow_rate is None else seq.slow_rate
            steps = integrate_dynamic(self.system, self.y, self.t, self.scene.t_end, self.control, dt=self.dt_next,
                                      n0=self.n, rates=self.rates, pair=self.pair if slow > 0 else None,
                                      slow_rate=slow)
        else:
            steps = integrate(self.system, self.y, self.t, self.scene.t_end, self.pair, self.control,
                              dt=self.dt_next, n0=self.n, rates=self.rates)
        for acc in steps:
            self.n, self.t, self.y, self.dt_next, self.rates = acc.n, acc.t, acc.y, acc.dt_next, acc.rates
            yield self.state(acc.dt)
