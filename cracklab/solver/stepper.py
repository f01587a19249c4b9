"""The time stepper: steps (i)-(v) of section 3 for any active set of components."""
from __future__ import annotations

import dataclasses
import math
import weakref
from dataclasses import dataclass

import numpy as np

from ..errors import SimulationError
from ..laws.base import cell_area_and_width, failed_length
from .interfaces import for_scene as interface_for_scene
from .schemes import Run, scheme_of
from .spectral import Transforms
from .stability import mode_gamma

# Growth detectors (Stepper._check). Fast: the run stops when max |v| grew by more than
# GROWTH_FACTOR over the last GROWTH_WINDOW steps and exceeds GROWTH_BOUND times the
# velocity scale of the load, c_s max|tau0| / mu (the slip rate a stress of the size of
# the load radiates; peak slip rates at rupture fronts are a few times that scale).
# Slow: max |v| over blocks of SLOW_BLOCKS[i] steps; the run stops when the last SLOW_COUNT
# block maxima of one block size rise one after the other by SLOW_FACTOR in all and max |v|
# exceeds SLOW_BOUND times the velocity scale (growth of ln(10) / (16 x 25) = 0.6 % per step
# and more within 400 steps, down to 6e-5 per step within 40 000 steps), or at once when
# max |v| exceeds CEILING times it (a slip rate no stress of the load's size can drive).
GROWTH_WINDOW = 50
GROWTH_FACTOR = 1e3
GROWTH_BOUND = 1e3
SLOW_BLOCKS = (25, 250, 2500)
SLOW_COUNT = 16
SLOW_FACTOR = 10.0
SLOW_BOUND = 100.0
CEILING = 1e6


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
    #: each face's own motion, ``faces(kind)`` -> {(side, component): field} with kind "u"
    #: (displacement) or "v" (velocity) and side "top" or "bottom" (an inverse transform: for
    #: what is recorded); None when the interface does not hold its faces apart (one material)
    faces: object = None


def _weak(method):
    """``method`` of an object, called through a weak reference to it: what the Stepper hands
    its Run makes no reference cycle (the Stepper's arrays and engines are freed with it)."""
    ref, name = weakref.ref(method.__self__), method.__name__
    return lambda *args: getattr(ref(), name)(*args)


def _copy(x):
    if isinstance(x, dict):
        return {k: _copy(a) for k, a in x.items()}
    return x.copy() if isinstance(x, np.ndarray) else x


class Stepper:
    """A resumable run of ``scene``: iterate for the State after each step n = 0 .. nsteps.

    ``start``: a dict from :meth:`get_state` (taken after some step m); the iteration
    then continues with step m + 1 and gives the same States as an uninterrupted run.
    ``response``: the interface to use (solver/interfaces, built for this scene); its state
    is restored too.
    """

    def __init__(self, scene, response=None, start=None):
        self.scene = scene
        grid, comps, law = scene.grid, scene.components, scene.law
        self.comps = comps          # scene.components tests the load fields: once, not every step
        self._area_width = cell_area_and_width(grid)  # for the crack length of constant-K loading
        self.scheme = scheme = scheme_of(scene.formulation)
        if response is None:
            response = interface_for_scene(scene, Transforms(grid, scene.numerics.fft_threads), scheme=scheme)
        self.response = response
        # the product schemes' trial slips, where the law (or contact) reads the slip
        trial_slips = scheme.needs_trial_slips and reads_slip(law, comps)
        #: what the scheme reads and writes of the run (its state after the last step taken)
        self.run = Run(response=response, law=law, grid=grid, dt=scene.dt, comps=comps, eta=response.eta,
                       load=scene.loading, delta={c: np.zeros(grid.shape) for c in comps},
                       v={c: np.zeros(grid.shape) for c in comps}, tau=None, lstate=law.init_state(grid),
                       trial_slips=trial_slips,
                       work={c: np.empty(grid.shape) for c in comps} if trial_slips else None,
                       vmean={c: np.empty(grid.shape) for c in comps} if scheme.mean_velocity else None,
                       update_law=_weak(self.update_law), crack_length=_weak(self.crack_length))
        self.n = 0                  # the next step to take
        self.l0 = None
        # growth detector: max |v| of the last GROWTH_WINDOW steps, running load velocity scale
        self.vmax = np.zeros(GROWTH_WINDOW)
        self.vscale = 0.0
        # block maxima per block size, oldest first; the last one of each row is filling
        self.vblocks = np.zeros((len(SLOW_BLOCKS), SLOW_COUNT))
        base = max(float(np.max(np.abs(self.load.field(c)))) for c in comps)
        self._vunit = base * scene.material.cs / scene.material.mu
        if start is not None:
            self.set_state(start)

    # the run's state lives in ``run`` (what the scheme is handed)
    delta = property(lambda self: self.run.delta, lambda self, x: setattr(self.run, "delta", x))
    v = property(lambda self: self.run.v, lambda self, x: setattr(self.run, "v", x))
    tau = property(lambda self: self.run.tau, lambda self, x: setattr(self.run, "tau", x))
    lstate = property(lambda self: self.run.lstate, lambda self, x: setattr(self.run, "lstate", x))
    load = property(lambda self: self.run.load, lambda self, x: setattr(self.run, "load", x))
    eta = property(lambda self: self.run.eta)

    def get_state(self) -> dict:
        """Everything needed to continue after the last step taken (arrays copied)."""
        return {"n": self.n, "delta": _copy(self.delta), "v": _copy(self.v), "tau": _copy(self.tau),
                "law": _copy(self.lstate), "l0": self.l0, "load_l0": self.load.l0,
                "vmax": self.vmax.copy(), "vscale": self.vscale, "vblocks": self.vblocks.copy(),
                "response": self.response.get_state()}

    def set_state(self, state: dict) -> None:
        """Restore a state from :meth:`get_state` (a Stepper of the same scene)."""
        self.n = int(state["n"])
        self.delta = {int(c): np.array(a, dtype=float) for c, a in state["delta"].items()}
        self.v = {int(c): np.array(a, dtype=float) for c, a in state["v"].items()}
        self.tau = None if state["tau"] is None else {int(c): np.array(a) for c, a in state["tau"].items()}
        self.lstate = _copy(state["law"])
        self.l0 = state["l0"]
        if state["load_l0"] is not None and self.load.l0 is None:
            self.load = dataclasses.replace(self.load, l0=state["load_l0"])
        self.vmax = np.array(state["vmax"], dtype=float)
        self.vscale = float(state["vscale"])
        self.vblocks = np.array(state["vblocks"], dtype=float)
        self.response.set_state(state["response"])

    def __iter__(self):
        return self._run()

    def _run(self):
        """Steps (i)-(v) with the scene's scheme; see :func:`steps`."""
        scene, run = self.scene, self.run
        grid, law = scene.grid, scene.law
        dt = scene.dt
        scheme = self.scheme
        for n in range(self.n, scene.nsteps + 1):
            t = n * dt
            f, trial, law_step = scheme.estimate(run, n, t)
            # law_step: (crack length, strength, load terms) when the scheme did the law's update
            length, strength, terms = law_step or self.update_law(n, t, trial, run.v, run.tau)
            # tau* = tau0 + f (f: the response's work arrays)
            v_new, tau = law.solve(run.lstate, f, trial, run.eta, dt, strength, terms)
            scheme.finish(run, n, v_new)
            self.response.settle(v_new)
            run.v, run.tau, self.n = v_new, tau, n + 1
            self._check(n, t, v_new, run.load.factor(t, length))
            applied = law.applied_strength(strength, tau, run.lstate)
            yield State(n, t, run.delta, v_new, tau, np.broadcast_to(applied, grid.shape),
                        run.lstate, self._faces(v_new))

    def _faces(self, v_new):
        """``State.faces`` of this step: the interface's faces, their jump this step's delta or v."""
        fields = getattr(self.response, "face_fields", None)
        if fields is None:
            return None
        delta = self.delta
        return lambda kind: fields(kind, delta if kind == "u" else v_new)

    def crack_length(self, state):
        """Mean crack length of constant-K loading for the law state ``state`` (None when
        the load does not need it)."""
        area, width = self._area_width
        return _crack_length(self.scene.law, state, self.load, area, width, self.l0, self.scene.grid.free_surface)

    def update_law(self, n, t, trial, v, tau):
        """Step (i) for the law: its update with the slip ``trial`` (and v, tau of step
        n - 1), the initial crack length of constant-K loading at the first step; returns
        the crack length, the strength and the load terms that step (v) takes."""
        scene, law, lstate = self.scene, self.scene.law, self.lstate
        area, width = self._area_width
        law.update(lstate, trial, scene.dt, v if n > 0 else None, t, tau if n > 0 else None)
        load = self.load
        if load.constant_K and self.l0 is None:
            self.l0 = load.l0 or _crack_length(law, lstate, load, area, width, None, scene.grid.free_surface)
            if load.l0 is None:
                # Loading.factor scales by sqrt(l0 / l): give it the initial length
                self.load = dataclasses.replace(load, l0=self.l0)
        length = self.crack_length(lstate)
        return length, law.strength(lstate, t, scene.grid), self.load.terms(t, self.comps, length, scene.grid)

    def _check(self, n, t, v, g):
        """Stop on a non-finite velocity or on exponential growth, fast or slow (module constants)."""
        grid = self.scene.grid
        peaks = {}
        for c, vc in v.items():
            peaks[c] = max(float(vc.max()), -float(vc.min()))
            if not np.isfinite(peaks[c]):
                check_finite(n, t, v, grid)
        self.vscale = max(self.vscale, abs(g) * self._vunit)
        c = max(peaks, key=peaks.get)
        m = peaks[c]
        old = self.vmax[n % GROWTH_WINDOW] if n >= GROWTH_WINDOW else self.vmax[0]
        self.vmax[n % GROWTH_WINDOW] = m
        self.vblocks[:, -1] = np.maximum(self.vblocks[:, -1], m)
        fast = m > GROWTH_BOUND * self.vscale and m > GROWTH_FACTOR * old
        if fast or (self.vscale > 0 and m > CEILING * self.vscale):
            grew = f"{m / old:.3g}-fold" if old > 0 else "from zero"
            self._growth(n, t, v, c, m, f"grew {grew} over the last {min(n, GROWTH_WINDOW)} steps"
                                        + ("" if fast else f" to more than {CEILING:g} times the load's velocity "
                                                           f"scale (a slip rate no stress of its size drives)"))
        for blocks, size in zip(self.vblocks, SLOW_BLOCKS):
            if (n + 1) % size:
                continue
            if (n + 1) // size >= SLOW_COUNT and self.vscale > 0 and m > SLOW_BOUND * self.vscale \
                    and blocks[0] > 0 and np.all(np.diff(blocks) > 0) and blocks[-1] >= SLOW_FACTOR * blocks[0]:
                rate = float(np.polyfit(size * np.arange(SLOW_COUNT), np.log(blocks), 1)[0])
                gamma_m = mode_gamma(grid.q_max(), self.scene.material.cs, self.scene.dt)
                self._growth(n, t, v, c, m, f"grew {blocks[-1] / blocks[0]:.3g}-fold over the last "
                                            f"{size * SLOW_COUNT} steps, steadily: {100 * math.expm1(rate):.3g} % "
                                            f"per step (e-fold in {1 / rate:.3g} steps; {rate / gamma_m:.3g} per "
                                            f"unit T = q_max c_s t)")
            blocks[:-1] = blocks[1:]
            blocks[-1] = 0.0

    def _growth(self, n, t, v, c, m, how):
        """Raise the SimulationError of a growing max |v_c| = m at step n."""
        sc, grid = self.scene, self.scene.grid
        i, k = np.unravel_index(np.argmax(np.abs(v[c])), v[c].shape)
        bmax = sc.beta_max
        verdict = (f"the time step is unstable (beta = {sc.beta:g} exceeds the stable limit {bmax:.4g} of the "
                   f"{sc.formulation} scheme at nu = {sc.material.nu:g})" if sc.beta > bmax else
                   f"beta = {sc.beta:g} is within the stable limit {bmax:.4g} of the {sc.formulation} scheme at "
                   f"nu = {sc.material.nu:g}, so the growth comes from the interface law or the load (a smaller "
                   f"beta tells: a time-step instability moves with it)")
        raise SimulationError(
            f"exponential growth of v_{c} at step {n} (t = {t:g}) at node ({i}, {k}), "
            f"x1 = {grid.x1[i]:g}, x3 = {grid.x3[k]:g}: max |v_{c}| = {m:.3g} {how}, and is "
            f"{m / self.vscale:.3g} times the load's velocity scale c_s max|tau0| / mu = {self.vscale:.3g}; "
            f"{verdict}; the run was stopped")


def steps(scene, response=None, start=None):
    """Generate the State after each step n = 0 .. nsteps (from step m + 1 with ``start``,
    a :meth:`Stepper.get_state` taken after step m).

    Displacement formulation: explicit update (37), delta_n = delta_{n-1} + dt v_{n-1}.
    Velocity formulation: semi-implicit update (50); the functional is evaluated at
    delta*_n = delta_{n-1} + dt v_{n-1}/2 and the law at the predictor delta_{n-1} + dt v_{n-1}.
    Product scheme: trapezoid update (50) with one predictor-corrector pass: the law is
    solved with the velocity held at v_{n-1} (on a copy of the law state), then again
    with the functional of that predicted velocity; 2 FFT pairs per step.
    Raises SimulationError on a non-finite velocity or exponential growth.
    """
    yield from Stepper(scene, response, start)


def reads_slip(law, comps) -> bool:
    """Whether the law's update or step (v) reads the slip: a law says so with
    ``reads_slip`` (assumed true when it does not); contact on the normal component reads
    the opening."""
    return bool(getattr(law, "reads_slip", True)) or (2 in comps and bool(getattr(law, "contact", False)))


def _crack_length(law, state, load, area, width, l0, mirror=False):
    """Mean crack length for constant-K loading (None when the load does not need it).
    ``mirror``: the half plane of a free surface, whose nodes on x3 = 0 and x3 = L3 count
    half (in the doubled cell each stands for itself alone, the others for two)."""
    if not load.constant_K:
        return None
    failed = law.failed(state)
    if failed is None:
        return l0
    if mirror and np.ndim(failed) == 2:
        count = np.count_nonzero(failed) - 0.5 * (np.count_nonzero(failed[:, 0]) + np.count_nonzero(failed[:, -1]))
        return float(failed_length(count, area, width)) or l0
    return failed_length(failed, area, width) or l0


def check_finite(n, t, v, grid):
    """Raise SimulationError naming the step, time and first node where v is not finite."""
    for c, vc in v.items():
        if not np.isfinite(vc).all():
            i, k = np.unravel_index(np.argmax(~np.isfinite(vc)), vc.shape)
            raise SimulationError(
                f"non-finite v_{c} at step {n} (t = {t:g}) at node ({i}, {k}), "
                f"x1 = {grid.x1[i]:g}, x3 = {grid.x3[k]:g}; the run was stopped")
