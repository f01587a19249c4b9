"""Loading: tau0_j(x1, x3) times a time function, Eq. (3).

``tau0`` is the traction the plane would carry if it were welded. Time functions:
"step" (H(t)), "ramp" (min(t / ramp_time, 1)) and "smooth" (the C1 ramp 3 s^2 - 2 s^3,
s = min(t / ramp_time, 1), which starts and ends without a jump in loading rate). With ``constant_K`` the load is
scaled by sqrt(l0 / l(t)), l the mean crack length (section 4), so that the nominal
stress intensity factor stays constant.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, check_fields_nesting, check_positive

TIME_FUNCTIONS = ("step", "ramp", "smooth")


@dataclass(frozen=True)
class Loading:
    tau0_1: float | np.ndarray = 0.0
    tau0_2: float | np.ndarray = 0.0
    tau0_3: float | np.ndarray = 0.0
    time: str = "step"
    ramp_time: float = 0.0
    constant_K: bool = False
    l0: float | None = None

    def __post_init__(self):
        check_fields_nesting(self, "loading")
        if not isinstance(self.time, str) or self.time not in TIME_FUNCTIONS:
            raise InputError("loading.time", f"must be one of {TIME_FUNCTIONS}, got {self.time!r}")
        if isinstance(self.ramp_time, (bool, np.bool_)):
            raise InputError("loading.ramp_time", f"must be a number >= 0, got {self.ramp_time!r}")
        if self.time == "step":
            check_positive("loading.ramp_time", self.ramp_time, allow_zero=True)
        else:
            check_positive("loading.ramp_time", self.ramp_time)      # > 0 for a ramp
        if not isinstance(self.constant_K, (bool, np.bool_)):
            raise InputError("loading.constant_K", f"must be true or false, got {self.constant_K!r}")
        if self.l0 is not None:
            if isinstance(self.l0, (bool, np.bool_)):
                raise InputError("loading.l0", f"must be a number > 0, got {self.l0!r}")
            check_positive("loading.l0", self.l0)
        for c in (1, 2, 3):
            value = self.field(c)
            expect = "must be a finite number or an (n1, n3) field of finite numbers"
            if value is None or isinstance(value, (bool, np.bool_, str, bytes)):
                raise InputError(f"loading.tau0_{c}", f"{expect}, got {value!r}")
            try:
                arr = np.asarray(value, dtype=float)
            except (TypeError, ValueError, OverflowError):
                raise InputError(f"loading.tau0_{c}", f"{expect}, got {value!r}") from None
            if not np.all(np.isfinite(arr)):
                got = value if arr.ndim == 0 else "a field holding non-finite values"
                raise InputError(f"loading.tau0_{c}", f"{expect}, got {got}")

    def field(self, component: int):
        return getattr(self, f"tau0_{component}")

    def loaded(self) -> tuple[int, ...]:
        """Components with a non-zero load."""
        return tuple(c for c in (1, 2, 3) if np.any(np.asarray(self.field(c)) != 0))

    def factor(self, t: float, crack_length: float | None = None) -> float:
        s = 1.0 if self.time == "step" else min(max(t, 0.0) / self.ramp_time, 1.0)
        g = s * s * (3.0 - 2.0 * s) if self.time == "smooth" else s
        if t < 0:
            g = 0.0
        if self.constant_K and crack_length:
            g *= np.sqrt(self.l0 / crack_length)
        return g

    def terms(self, t: float, components, crack_length: float | None = None) -> tuple:
        """(g(t), {c: tau0_c}): tau0(t) = g tau0_c, for :func:`cracklab.laws.solve_velocity`."""
        return self.factor(t, crack_length), {c: self.field(c) for c in components}

    def at(self, t: float, components, crack_length: float | None = None) -> dict:
        g = self.factor(t, crack_length)
        return {c: g * self.field(c) for c in components}


def point_load(grid, P: float, x1: float, x3: float = 0.0) -> np.ndarray:
    """Field tau0 = P / (dx1 dx3) at the node nearest (x1, x3), zero elsewhere (section 3.2)."""
    f = np.zeros(grid.shape)
    i, k = grid.nearest_node(x1, x3)
    f[i, k] = P / (grid.dx1 * (grid.dx3 if not grid.plane else 1.0))
    return f
