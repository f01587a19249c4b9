"""Linear slip-weakening friction."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .base import SHEAR, bonded_mask, check_parameter, parameter
from .friction import NORMAL_STATE, Friction, normal_slip_scale, normal_time


@dataclass(frozen=True)
class SlipWeakening(Friction):
    """Linear slip-weakening friction: mu_s sigma_n -> mu_d sigma_n over D_c of slip.

    ``sigma_n`` is the (compressive positive) normal stress; None: the current normal
    traction, max(0, -tau_2), or its regularised form with ``normal_slip_scale`` and/or
    ``normal_time`` (laws/friction.py). The slip is the accumulated slip path.
    In 3D the slip rate is collinear with the shear traction.
    """

    mu_s: float | np.ndarray = parameter(accepted=">= 0", doc="static friction coefficient")
    mu_d: float | np.ndarray = parameter(accepted=">= 0; <= mu_s at every node",
                                          doc="dynamic friction coefficient")
    D_c: float | np.ndarray = parameter(unit="length", accepted="> 0", doc="slip over which mu_s falls to mu_d")
    sigma_n: float | np.ndarray | None = parameter(
        unit="stress", default=None, accepted=">= 0",
        doc="normal stress, compressive positive; absent: the current normal traction max(0, -tau_2)")
    normal_slip_scale: float | np.ndarray | None = normal_slip_scale()
    normal_time: float | np.ndarray | None = normal_time()
    bonded: np.ndarray | None = bonded_mask()
    kind = "slip_weakening"
    #: a small scene of the law (docs/reference/toml.md shows it, tests/docs/test_toml_page.py runs it)
    example = """\
# A TPV3-like fault on a coarse grid (about 470 m): slip weakening under 120 MPa,
# nucleated from t = 0 by a shear stress raised up to 30 MPa within 3 km
name = "slip_weakening_example"
t_end = 1.0

[units]
length = "m"
time = "s"
stress = "Pa"

[material]
mu = 3.2038e10
cs = 3464.0
nu = 0.25

[grid]
n1 = 64
n3 = 32
L1 = 30000.0
L3 = 15000.0

[law]
kind = "slip_weakening"
mu_s = 0.677
mu_d = 0.525
D_c = 0.4
sigma_n = 120e6

[loading]
tau0_1 = 70e6
nucleation_dtau_1 = 30e6
nucleation_radius = 3000.0
nucleation_time = 0.0
nucleation_x1 = 15000.0
nucleation_x3 = 7500.0

[record]
fields = ["v_1", "slip"]
every = 5
"""
    state_variables = {"slip": ("slip path", "length"), **NORMAL_STATE}

    def __post_init__(self):
        check_parameter(self, "mu_s", allow_equal=True)
        check_parameter(self, "mu_d", allow_equal=True)
        check_parameter(self, "D_c")
        if self.sigma_n is not None:
            check_parameter(self, "sigma_n", allow_equal=True)
        self.check_normal()
        try:
            above = np.asarray(self.mu_d) > np.asarray(self.mu_s)
        except ValueError:          # fields of different shapes: the scene names the wrong one
            above = False
        if np.any(above):
            raise InputError("law.mu_d", f"must be <= law.mu_s (static friction {self.mu_s!r}), got {self.mu_d!r}"
                             if np.ndim(self.mu_d) == 0 and np.ndim(self.mu_s) == 0 else
                             "must be <= law.mu_s at every point of the field")

    def state_fields(self) -> float:
        """The slip, and sigma* when regularised."""
        return 1 + self.normal_fields()

    def init_state(self, grid):
        return {"slip": np.zeros(grid.shape), **self.normal_state(grid)}

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        self.normal_update(state, dt, v_prev)
        if v_prev is not None:
            speed = np.sqrt(sum(v_prev[c] ** 2 for c in v_prev if c in SHEAR))
            state["slip"] += dt * speed

    def coefficient(self, state, t, grid):
        weakening = np.clip(state["slip"] / self.D_c, 0.0, 1.0)
        return self.mu_s - (self.mu_s - self.mu_d) * weakening

    def failed(self, state):
        return state["slip"] >= self.D_c

    def energy_state(self, grid):
        """The budget rebuilds the slip path: the initial state (none) to begin with. None
        when the strength follows the normal traction: its G needs that traction's history,
        and the budget then gives no fracture energy."""
        return None if self.follows_normal else self.init_state(grid)

    def energy_update(self, state, delta, delta_prev):
        """The slip path grows by the length of the shear slip's change since the last snapshot."""
        if delta_prev is not None:
            state["slip"] = state["slip"] + np.sqrt(sum((delta[c] - delta_prev[c]) ** 2 for c in delta if c in SHEAR))

    def fracture_energy(self, state):
        """G reached so far: (mu_s - mu_d) sigma_n (m - m^2 / (2 D_c)) with m = min(slip, D_c)."""
        Dc = np.asarray(self.D_c, dtype=float)
        m = np.minimum(state["slip"], Dc)
        drop = (np.asarray(self.mu_s) - np.asarray(self.mu_d)) * np.asarray(self.sigma_n)
        return drop * (m - m * m / (2.0 * Dc))
