"""The time-scheme protocol: a scheme is a class holding its coefficients (its rule, the
kernel its history convolves, its modal recurrence) and the two parts of a step that
differ between schemes (docs/developer/developer.md, "Add a time scheme"):

* ``channel(kernel, engine, q, gamma, mu, cs, nu)``: its part of the response, the
  prefactors of one channel's functional for a half space of modulus ``mu`` (already
  scaled: mu/2 for the discontinuity of an identical pair), shear wave speed ``cs``
  and Poisson ratio ``nu``;
* ``estimate(run, n, t)``: steps (i)-(iv), the slip update (where the scheme updates it
  first) and the elastic estimate f_n; returns (f, trial slip, law step or None);
* ``finish(run, n, v_new)``: the slip update after step (v) (semi-implicit schemes).

The Stepper (solver/stepper.py) runs a scheme; a HalfSpace (solver/halfspace.py) asks it
for its channels and, through ``functional`` or ``predict`` and ``correct``, for f_n.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


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
    rule = ""            # convolution rule of its weights
    convolves = ""       # "displacement" (kernel C against D) or "velocity" (Z against V)
    lag = 0              # the history starts this many steps back
    modal = ()           # (formulation, convolution, integration) of cracklab.modal_response
    mean_velocity = False  # it updates the law at the step's mean velocity: the Stepper gives it
                           # arrays of the grid for it (run.vmean) and for trial slips (run.work)

    @property
    def front_order(self) -> int:
        """The order in dt of a slip-weakening front's rupture time: 2 where the law is
        updated at the step's mean velocity (its slip path by the trapezoid rule), 1 where it
        is updated with v_{n-1} (the rectangle rule; docs/reference/stability.md, "The order of a
        rupture front")."""
        return 2 if self.mean_velocity else 1

    def finish(self, run, n, v_new):
        """After step (v): nothing to update by default."""
