"""Constant (Coulomb) friction: the strength mu_f sigma_n does not change."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import bonded_mask, check_parameter, parameter
from .friction import NORMAL_STATE, Friction, normal_slip_scale, normal_time


@dataclass(frozen=True)
class ConstantFriction(Friction):
    """Shear strength ``mu_f sigma_n`` (``sigma_n`` compressive positive; None: the current
    normal traction or its regularised form, laws/friction.py): the plane slides where the shear traction would
    exceed it, with the slip rate collinear with the traction."""

    mu_f: float | np.ndarray = parameter(accepted=">= 0", doc="friction coefficient")
    sigma_n: float | np.ndarray | None = parameter(
        unit="stress", default=None, accepted=">= 0",
        doc="normal stress, compressive positive; absent: the current normal traction max(0, -tau_2)")
    normal_slip_scale: float | np.ndarray | None = normal_slip_scale()
    normal_time: float | np.ndarray | None = normal_time()
    bonded: np.ndarray | None = bonded_mask()
    kind = "constant_friction"
    #: a small scene of the law (docs/reference/toml.md shows it, tests/docs/test_toml_page.py runs it)
    example = """\
# Coulomb friction that follows the normal traction (no sigma_n), in the plane
# problem: pressed by tau0_2 = -1, the plane slides where tau0_1 > mu_f = 0.6
name = "constant_friction_example"
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
kind = "constant_friction"
mu_f = 0.6

[loading]
tau0_1 = [[0.5], [0.5], [0.5], [0.5], [0.5], [0.5], [0.7], [0.7],
          [0.7], [0.7], [0.5], [0.5], [0.5], [0.5], [0.5], [0.5]]
tau0_2 = -1.0

[record]
fields = ["delta_1", "tau_2"]
every = 4
"""
    state_variables = dict(NORMAL_STATE)

    def __post_init__(self):
        check_parameter(self, "mu_f", allow_equal=True)
        if self.sigma_n is not None:
            check_parameter(self, "sigma_n", allow_equal=True)
        self.check_normal()

    def state_fields(self) -> float:
        return self.normal_fields()

    def init_state(self, grid):
        return self.normal_state(grid)

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        self.normal_update(state, dt, v_prev)

    def coefficient(self, state, t, grid):
        return self.mu_f
