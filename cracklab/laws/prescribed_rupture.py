"""A strength drop at a prescribed rupture speed (Kostrov's crack)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .base import ALL, Law, bonded_mask, check_parameter, parameter


@dataclass(frozen=True)
class PrescribedRupture(Law):
    """Strength drops from ``strength_before`` to ``residual`` once t > r / speed (Kostrov tests).

    r is the distance to the nucleation point ``origin`` = (x1, x3) in 3D, or to the
    line x1 = origin[0] in the plane problem. With ``weakening_time`` t_w > 0 the drop
    is linear in time over [r/speed - t_w/2, r/speed + t_w/2], starting from the
    traction the point carried when the drop began (a time-weakening release that
    avoids the pulses of cell-by-cell jumps; t_w = dx/speed is one cell).
    """

    speed: float = parameter(unit="velocity", kind="scalar", accepted="> 0", doc="rupture speed")
    origin: tuple = parameter(unit="length", kind="option", default=(0.0, 0.0),
                              accepted="[x1, x3] (or [x1] in 2D), finite",
                              doc="nucleation point (in 2D the line x1 = origin[0])")
    residual: float | np.ndarray = parameter(unit="stress", default=0.0, accepted=">= 0", doc="strength after the drop")
    strength_before: float | np.ndarray = parameter(unit="stress", default=np.inf, accepted=">= 0 or inf",
                                                    doc="strength before the rupture arrives")
    weakening_time: float = parameter(unit="time", kind="scalar", default=0.0, accepted=">= 0",
                                      doc="duration of the linear drop (0: a jump)")
    bonded: np.ndarray | None = bonded_mask()
    reads_slip = False  # its update does not read delta (the product scheme then skips its trial slips)
    kind = "prescribed_rupture"
    #: a small scene of the law (docs/reference/toml.md shows it, tests/docs/test_toml_page.py runs it)
    example = """\
# Kostrov's crack: the strength drops from infinity to 0 as a circle growing at
# 0.7 cs from the centre passes, over 0.05 time units
name = "prescribed_rupture_example"
t_end = 0.5

[material]
mu = 1.0
cs = 1.0
nu = 0.25

[grid]
n1 = 32
n3 = 32
L1 = 1.0
L3 = 1.0

[law]
kind = "prescribed_rupture"
speed = 0.7
origin = [0.5, 0.5]
residual = 0.0
strength_before = inf
weakening_time = 0.05

[loading]
tau0_1 = 1.0

[record]
fields = ["delta_1"]

[record.stations]
centre = [0.5, 0.5]
"""
    components = ALL
    contact = False

    def __post_init__(self):
        check_parameter(self, "speed")
        check_parameter(self, "residual", allow_equal=True)
        check_parameter(self, "strength_before", allow_equal=True, allow_inf=True)
        check_parameter(self, "weakening_time", allow_equal=True)
        if np.ndim(self.speed) or np.ndim(self.weakening_time):
            raise InputError("law.speed" if np.ndim(self.speed) else "law.weakening_time", "must be a number")
        origin = self.origin
        try:
            ok = not isinstance(origin, (str, bytes, dict)) and 1 <= len(origin) <= 2 and all(
                not isinstance(x, (bool, np.bool_)) and np.isfinite(float(x)) for x in origin)
        except (TypeError, ValueError, OverflowError):
            ok = False
        if not ok:
            raise InputError("law.origin", f"must be [x1, x3] (or [x1] in 2D) of finite numbers, got {origin!r}")
        object.__setattr__(self, "origin", tuple(float(x) for x in origin))

    def state_fields(self) -> float:
        return 2

    def init_state(self, grid):
        x1, x3 = np.meshgrid(grid.x1, grid.x3, indexing="ij")
        r = np.abs(x1 - self.origin[0])
        if not grid.plane:
            r = np.hypot(r, x3 - self.origin[1])
        start = r / self.speed - 0.5 * self.weakening_time
        return {"t_start": start, "s_start": np.full(grid.shape, np.nan), "_t": -np.inf}

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        state["_t"] = t
        new = (t >= state["t_start"]) & np.isnan(state["s_start"])
        if new.any():
            if tau_prev:
                level = np.sqrt(sum(tau_prev[c] ** 2 for c in tau_prev))
            else:
                level = np.zeros(state["s_start"].shape)
            state["s_start"][new] = np.maximum(level[new], self.residual if np.ndim(self.residual) == 0
                                               else np.asarray(self.residual)[new])

    def strength(self, state, t, grid):
        started = t >= state["t_start"]
        if self.weakening_time > 0:
            frac = np.clip(1.0 - (t - state["t_start"]) / self.weakening_time, 0.0, 1.0)
            s0 = np.where(started, state["s_start"], 0.0)
            dropping = self.residual + (s0 - self.residual) * frac
        else:
            dropping = self.residual
        return np.where(started, dropping, self.strength_before)

    def broken(self, state):
        return state["_t"] >= state["t_start"]

    def failed(self, state):
        return self.broken(state)
