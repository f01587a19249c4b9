"""Constant (Coulomb) friction: the strength mu_f sigma_n does not change."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import check_fields_nesting
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
    state_variables = dict(NORMAL_STATE)

    def __post_init__(self):
        check_fields_nesting(self, "law")
        check_parameter(self, "mu_f", allow_equal=True)
        if self.sigma_n is not None:
            check_parameter(self, "sigma_n", allow_equal=True)
        self.check_normal()

    def init_state(self, grid):
        return self.normal_state(grid)

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        self.normal_update(state, dt, v_prev)

    def coefficient(self, state, t, grid):
        return self.mu_f
