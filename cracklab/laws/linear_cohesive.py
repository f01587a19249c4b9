"""The mode I linear cohesive law (Eq. 38, Fig. 4)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .base import NORMAL, Law, bonded_mask, check_parameter, parameter


@dataclass(frozen=True)
class LinearCohesive(Law):
    """Mode I linear cohesive law (Fig. 4): strength tau_c (1 - max opening/delta_c)^+.

    No rehealing; inside the cohesive zone the opening rate cannot be negative;
    broken faces may close but never interpenetrate. ``initial_crack`` marks points
    broken at t = 0.
    """

    tau_c: float | np.ndarray = parameter(unit="stress", accepted="> 0", doc="cohesive (tensile) strength")
    delta_c: float | np.ndarray = parameter(unit="length", accepted="> 0",
                                            doc="critical opening, where the strength reaches 0")
    initial_crack: np.ndarray | None = parameter(kind="mask", default=None, doc="points broken at t = 0")
    bonded: np.ndarray | None = bonded_mask()
    reads_slip = True  # its update reads delta
    kind = "linear_cohesive"
    #: a small scene of the law (docs/reference/toml.md shows it, tests/docs/test_toml_page.py runs it)
    example = """\
# A mode I crack in the plane problem: nodes 0-2 and 13-15 (the crack across the
# periodic boundary) broken at t = 0, the plane under a suddenly applied tension
name = "linear_cohesive_example"
t_end = 0.5

[material]
mu = 1.0
cs = 1.0
nu = 0.25

[grid]
n1 = 16
n3 = 1
L1 = 1.0
L3 = 1.0

[law]
kind = "linear_cohesive"
tau_c = 1.0
delta_c = 0.01
initial_crack = [[true], [true], [true], [false], [false], [false], [false], [false],
                 [false], [false], [false], [false], [false], [true], [true], [true]]

[loading]
tau0_2 = 0.4

[record]
fields = ["delta_2", "delta_max"]
every = 4
"""
    components = NORMAL
    contact = True
    state_variables = {"delta_max": ("largest opening reached", "length")}

    def __post_init__(self):
        check_parameter(self, "tau_c")
        check_parameter(self, "delta_c")

    def state_fields(self) -> float:
        return 1

    def init_state(self, grid):
        dmax = np.zeros(grid.shape)
        if self.initial_crack is not None:
            dmax = np.where(self.initial_crack, np.inf, 0.0)
        return {"delta_max": dmax}

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        np.maximum(state["delta_max"], delta[2], out=state["delta_max"])

    def strength(self, state, t, grid):
        return self.tau_c * np.clip(1.0 - state["delta_max"] / self.delta_c, 0.0, 1.0)

    def broken(self, state):
        return state["delta_max"] >= self.delta_c

    def failed(self, state):
        return self.broken(state)

    def energy_state(self, grid):
        """The budget rebuilds the largest opening reached: the initial state to begin with."""
        return self.init_state(grid)

    def energy_update(self, state, delta, delta_prev):
        if 2 in delta:
            state["delta_max"] = np.maximum(state["delta_max"], delta[2])

    def energy_failed(self, state):
        return self.failed(state)

    def fracture_energy(self, state):
        """G reached so far: the work of the cohesive traction, tau_c (m - m^2 / (2 delta_c)) with
        m = min(delta_max, delta_c); none on the initial crack."""
        dc = np.asarray(self.delta_c, dtype=float)
        m = np.minimum(state["delta_max"], dc)
        g = np.asarray(self.tau_c, dtype=float) * (m - m * m / (2.0 * dc))
        initial = False if self.initial_crack is None else np.asarray(self.initial_crack, dtype=bool)
        return np.where(initial, 0.0, g)
