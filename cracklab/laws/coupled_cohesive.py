"""A mixed-mode linear cohesive law: modes I, II and III soften together (docs/reference/equations.md,
"Coupled cohesive law")."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .base import ALL, SHEAR, Law, bonded_mask, check_parameter, parameter
from .solve import solve_normal_first, solve_velocity


@dataclass(frozen=True)
class CoupledCohesive(Law):
    """Mixed-mode linear cohesive law: one effective opening
    lambda = sqrt(max(delta_2, 0)^2 + (beta |delta_s|)^2) (delta_s the shear slip vector)
    softens the normal strength tau_c and the shear strength tau_s together, each times
    (1 - lambda_max / delta_c)^+ with lambda_max the largest lambda reached (no rehealing).
    Pressed faces add friction mu_f max(0, -tau_2) to the shear strength; broken faces
    may close but never interpenetrate; inside the cohesive zone the opening rate cannot
    be negative. Fracture energy of a proportional path at mixity phi (tan phi =
    beta |delta_s| / delta_2): G = delta_c (tau_c cos phi + tau_s sin phi / beta) / 2.
    """

    tau_c: float | np.ndarray = parameter(unit="stress", accepted=">= 0", doc="normal (tensile) cohesive strength")
    tau_s: float | np.ndarray = parameter(unit="stress", accepted=">= 0", doc="shear cohesive strength")
    delta_c: float | np.ndarray = parameter(unit="length", accepted="> 0",
                                            doc="critical effective opening, where both strengths reach 0")
    beta: float = parameter(kind="scalar", default=1.0, accepted="> 0",
                           doc="weight of the shear slip in the effective opening")
    mu_f: float | np.ndarray = parameter(default=0.0, accepted=">= 0", doc="friction coefficient of pressed faces")
    initial_crack: np.ndarray | None = parameter(kind="mask", default=None, doc="points broken at t = 0")
    bonded: np.ndarray | None = bonded_mask()
    reads_slip = True
    contact = True
    kind = "coupled_cohesive"
    #: a small scene of the law (docs/reference/toml.md shows it, tests/docs/test_toml_page.py runs it)
    example = """\
# Modes I and II softening together in the plane problem: a crack of nodes 0-2
# and 13-15 (across the periodic boundary) under a mixed, ramped load
name = "coupled_cohesive_example"
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
kind = "coupled_cohesive"
tau_c = 1.0
tau_s = 1.0
delta_c = 0.02
beta = 1.0
mu_f = 0.3
initial_crack = [[true], [true], [true], [false], [false], [false], [false], [false],
                 [false], [false], [false], [false], [false], [true], [true], [true]]

[loading]
tau0_1 = 0.3
tau0_2 = 0.3
time = "ramp"
ramp_time = 0.1

[record]
fields = ["delta_1", "delta_2", "lambda_max"]
"""
    components = ALL
    state_variables = {"lambda_max": ("largest effective opening reached", "length")}

    def __post_init__(self):
        check_parameter(self, "tau_c", allow_equal=True)
        check_parameter(self, "tau_s", allow_equal=True)
        check_parameter(self, "delta_c")
        check_parameter(self, "mu_f", allow_equal=True)
        if isinstance(self.beta, (bool, np.bool_)) or not isinstance(self.beta, (int, float, np.floating, np.integer)):
            raise InputError("law.beta", f"must be a number > 0, got {self.beta!r}")
        check_parameter(self, "beta")

    def effective_opening(self, delta):
        """lambda = sqrt(max(delta_2, 0)^2 + beta^2 |delta_s|^2) of the components in ``delta``."""
        shear = [c for c in SHEAR if c in delta]
        lam2 = np.maximum(delta[2], 0.0) ** 2 if 2 in delta else 0.0
        if shear:
            lam2 = lam2 + self.beta**2 * sum(delta[c] ** 2 for c in shear)
        return np.sqrt(lam2)

    def state_fields(self) -> float:
        return 1

    def init_state(self, grid):
        lam = np.zeros(grid.shape)
        if self.initial_crack is not None:
            lam = np.where(self.initial_crack, np.inf, 0.0)
        return {"lambda_max": lam}

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        np.maximum(state["lambda_max"], self.effective_opening(delta), out=state["lambda_max"])

    def strength(self, state, t, grid):
        """The factor (1 - lambda_max / delta_c)^+ both cohesive strengths carry."""
        return np.clip(1.0 - state["lambda_max"] / self.delta_c, 0.0, 1.0)

    def broken(self, state):
        return state["lambda_max"] >= self.delta_c

    def failed(self, state):
        return self.broken(state)

    def shear_strength(self, factor, tau):
        """tau_s (1 - lambda_max / delta_c)^+ + mu_f max(0, -tau_2)."""
        s = self.tau_s * factor
        return s + self.mu_f * np.maximum(0.0, -tau[2]) if 2 in tau else s

    def applied_strength(self, strength, tau, state=None):
        """The shear strength where a shear component is active, else the normal one."""
        if any(c in tau for c in SHEAR):
            return self.shear_strength(strength, tau)
        return self.tau_c * strength

    def solve(self, state, tau_star, delta, eta, dt, strength, load=None, traction=True):
        """Step (v): the normal component against tau_c x factor, then the shear ones against
        the shear strength with the normal traction just found."""
        if 2 not in tau_star:
            return solve_velocity(self, state, tau_star, delta, eta, dt, self.tau_s * strength, load, traction)
        return solve_normal_first(self, state, tau_star, delta, eta, dt, self.tau_c * strength,
                                  lambda tau: self.shear_strength(strength, tau), load, traction)

    # -- the energy budget: the work of the cohesive tractions along the recorded path
    def energy_state(self, grid):
        """lambda_max and the cohesive work G, rebuilt from the recorded slip."""
        return {**self.init_state(grid), "G": np.zeros(grid.shape)}

    def energy_update(self, state, delta, delta_prev):
        """G grows by (1 - lambda/delta_c)^+ (tau_c d delta_2 + tau_s |d delta_s|), the
        factor the mean of its values at the two snapshots (exact on proportional paths)."""
        lam = np.maximum(state["lambda_max"], self.effective_opening(delta))
        if delta_prev is not None:
            dc = np.asarray(self.delta_c, dtype=float)
            f0 = np.clip(1.0 - state["lambda_max"] / dc, 0.0, 1.0)
            f1 = np.clip(1.0 - lam / dc, 0.0, 1.0)
            work = 0.0
            if 2 in delta:
                work = work + self.tau_c * np.maximum(delta[2] - delta_prev[2], 0.0)
            shear = [c for c in SHEAR if c in delta]
            if shear:
                work = work + self.tau_s * np.sqrt(sum((delta[c] - delta_prev[c]) ** 2 for c in shear))
            state["G"] = state["G"] + 0.5 * (f0 + f1) * work
        state["lambda_max"] = lam

    def energy_failed(self, state):
        return self.failed(state)

    def fracture_energy(self, state):
        """The cohesive work reached so far (none on the initial crack)."""
        initial = False if self.initial_crack is None else np.asarray(self.initial_crack, dtype=bool)
        return np.where(initial, 0.0, state["G"])
