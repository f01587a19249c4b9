"""The time-scheme protocol: a scheme is a class holding its coefficients (its rule, the
kernel its history convolves, its modal recurrence, its stability limits, what it needs of
the run) and the two parts of a step that differ between schemes (docs/developer/developer.md, "Add
a time scheme"). A scheme class registers with the :func:`register` decorator; every module
of this package is imported (``schemes.SCHEMES``), so that a new scheme is one file:

* ``channel(kernel, engine, q, gamma, mu, cs, nu)``: its part of the response, the
  prefactors of one channel's functional for a half space of modulus ``mu`` (already
  scaled: mu/2 for the discontinuity of an identical pair), shear wave speed ``cs``
  and Poisson ratio ``nu``;
* ``estimate(run, n, t)``: steps (i)-(iv), the slip update (where the scheme updates it
  first) and the elastic estimate f_n; returns (f, trial slip, law step or None);
* ``finish(run, n, v_new)``: the slip update after step (v) (semi-implicit schemes).

``run`` is a :class:`Run`, the part of the Stepper's state a scheme reads and writes. The
Stepper (solver/stepper.py) runs a scheme; a HalfSpace (solver/halfspace.py) asks it for its
channels and, through ``functional`` or ``predict`` and ``correct``, for f_n.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

#: {name: scheme}, every registered scheme (ordered by ``Scheme.order``: schemes.SCHEMES)
REGISTRY: dict = {}


def register(cls):
    """Class decorator: register one instance of the scheme ``cls`` under its ``name`` (a
    value of ``Numerics.formulation``)."""
    if not cls.name:
        raise ValueError(f"{cls.__name__} has no name")
    if cls.name in REGISTRY and type(REGISTRY[cls.name]) is not cls:
        raise ValueError(f"two schemes are named {cls.name!r}: {type(REGISTRY[cls.name]).__name__}, {cls.__name__}")
    REGISTRY[cls.name] = cls()
    return cls


@dataclass(slots=True)
class Run:
    """What a scheme's ``estimate`` and ``finish`` read and write of a run: the Stepper's
    state after step n - 1 (``delta``, ``v``, ``tau``, the law's state ``lstate``, the load,
    which constant-K loading replaces once) and what the step is made with. The Stepper
    owns one and keeps it current."""

    response: object            # the interface (solver/interfaces): functional, predict, correct
    law: object
    grid: object
    dt: float
    comps: tuple                # the active components
    eta: dict                   # {component: radiation damping of the pair}
    load: object                # the scene's Loading (with l0 once constant-K loading has measured it)
    delta: dict
    v: dict
    tau: dict | None
    lstate: dict
    trial_slips: bool           # the law is stepped on trial slips (Scheme.needs_trial_slips, law reads the slip)
    work: dict | None           # arrays of the grid for trial slips (trial_slips)
    vmean: dict | None          # arrays of the grid for the step's mean velocity (Scheme.mean_velocity)
    update_law: Callable        # (n, t, trial, v, tau) -> (crack length, strength, load terms): step (i)
    crack_length: Callable      # (law state) -> mean crack length of constant-K loading, or None


@dataclass
class Channel:
    """The prefactors and running terms of one channel's functional."""

    kernel: str
    engine: object
    pre: np.ndarray          # prefactor per mode
    static: np.ndarray | None = None   # velocity formulation: -(mu q/2) Z(0) (pair)
    v0: np.ndarray | None = None
    K: np.ndarray | None = None        # product scheme: coefficient of V_n
    dknown: np.ndarray | None = None   # product scheme: D_{n-1} + dt V_{n-1}/2
    H: np.ndarray | None = None        # product scheme: F_n without its V_n term


class Scheme:
    """Defaults of the protocol (see the module docstring)."""

    name = ""            # Numerics.formulation
    order = 0            # its place in lists of schemes (Numerics.formulation's accepted values)
    rule = ""            # convolution rule of its weights
    any_rule = False     # it takes any convolution rule (HalfSpace's ``rule``), not only its own
    convolves = ""       # "displacement" (kernel C against D) or "velocity" (Z against V)
    lag = 0              # the history starts this many steps back
    modal = ()           # (formulation, convolution, integration) of cracklab.modal_response
    mean_velocity = False  # it updates the law at the step's mean velocity: the Stepper gives it
                           # arrays of the grid for it (run.vmean)
    needs_trial_slips = False  # it steps the law on trial slips where the law reads the slip: the
                               # Stepper gives it arrays of the grid for them (run.work)
    #: measured stability limits, {mode: largest gamma = q c_s dt per Poisson ratio of
    #: solver.stability.NU_NODES} (studies/stability_nu.py; solver/stability.py reads them)
    limits: dict = {}

    @property
    def front_order(self) -> int:
        """The order in dt of a slip-weakening front's rupture time: 2 where the law is
        updated at the step's mean velocity (its slip path by the trapezoid rule), 1 where it
        is updated with v_{n-1} (the rectangle rule; docs/reference/stability.md, "The order of a
        rupture front")."""
        return 2 if self.mean_velocity else 1

    def finish(self, run, n, v_new):
        """After step (v): nothing to update by default."""
