"""Loading: tau0_j(x1, x3) times a time function, Eq. (3).

``tau0`` is the traction the plane would carry if it were welded. Time functions:
"step" (H(t)), "ramp" (min(t / ramp_time, 1)) and "smooth" (the C1 ramp 3 s^2 - 2 s^3,
s = min(t / ramp_time, 1), which starts and ends without a jump in loading rate). With ``constant_K`` the load is
scaled by sqrt(l0 / l(t)), l the mean crack length (section 4), so that the nominal
stress intensity factor stays constant.

The forced nucleation of SCEC TPV101-104 adds the shear perturbation dtau_c F(r) G(t)
(components c = 1, 3), not scaled by the time function:
F(r) = exp(r^2 / (r^2 - R^2)) for r < R (else 0), r the distance from the centre
(nucleation_x1, nucleation_x3), and G(t) = exp((t - T)^2 / (t (t - 2T))) for 0 < t < T,
1 for t >= T, 0 for t <= 0 (R = nucleation_radius, T = nucleation_time).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, check_fields_nesting, check_positive

TIME_FUNCTIONS = ("step", "ramp", "smooth")
NUCLEATION = ("nucleation_dtau_1", "nucleation_dtau_3", "nucleation_radius", "nucleation_time", "nucleation_x1",
              "nucleation_x3")


@dataclass(frozen=True)
class Loading:
    """The traction ``tau0_j`` the plane would carry if it were welded (``tau0_2`` is tension),
    times the time function ``time``, plus the optional forced nucleation (see the module)."""

    tau0_1: float | np.ndarray = 0.0
    tau0_2: float | np.ndarray = 0.0
    tau0_3: float | np.ndarray = 0.0
    time: str = "step"
    ramp_time: float = 0.0
    constant_K: bool = False
    l0: float | None = None
    nucleation_dtau_1: float | None = None
    nucleation_dtau_3: float | None = None
    nucleation_radius: float | None = None
    nucleation_time: float | None = None
    nucleation_x1: float | None = None
    nucleation_x3: float | None = None

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
        self._check_nucleation()
        object.__setattr__(self, "_cache", {})

    def _check_nucleation(self):
        """All of radius, time and centre with at least one dtau, or none of them."""
        given = [k for k in NUCLEATION if getattr(self, k) is not None]
        if not given:
            return
        for key in NUCLEATION:
            value = getattr(self, key)
            field = f"loading.{key}"
            if value is None:
                if key.startswith("nucleation_dtau") and (self.nucleation_dtau_1 is not None
                                                          or self.nucleation_dtau_3 is not None):
                    continue
                raise InputError(field, f"is required with {', '.join(f'loading.{k}' for k in given)} (the "
                                        f"nucleation: nucleation_dtau_1 and/or nucleation_dtau_3, "
                                        f"nucleation_radius, nucleation_time, nucleation_x1, nucleation_x3)")
            if isinstance(value, (bool, np.bool_)) or np.ndim(value) != 0:
                raise InputError(field, f"must be a number, got {value!r}")
            if key == "nucleation_radius":
                check_positive(field, value)
            elif key == "nucleation_time":
                check_positive(field, value, allow_zero=True)
            else:
                try:
                    x = float(value)
                except (TypeError, ValueError, OverflowError):
                    raise InputError(field, f"must be a finite number, got {value!r}") from None
                if not np.isfinite(x):
                    raise InputError(field, f"must be a finite number, got {value!r}")

    def field(self, component: int):
        return getattr(self, f"tau0_{component}")

    def loaded(self) -> tuple[int, ...]:
        """Components with a non-zero load (the nucleation's included)."""
        return tuple(c for c in (1, 2, 3) if np.any(np.asarray(self.field(c)) != 0)
                     or (c != 2 and getattr(self, f"nucleation_dtau_{c}") not in (None, 0.0)))

    @property
    def nucleates(self) -> bool:
        """Whether the load has the forced nucleation."""
        return self.nucleation_radius is not None

    def nucleation_factor(self, t: float) -> float:
        """G(t) = exp((t - T)^2 / (t (t - 2T))) for 0 < t < T, 1 for t >= T, 0 for t <= 0."""
        T = self.nucleation_time
        if t <= 0.0:
            return 0.0
        if t >= T:
            return 1.0
        return float(np.exp((t - T) ** 2 / (t * (t - 2.0 * T))))

    def nucleation_field(self, grid) -> dict:
        """{c: dtau_c F(r)} on the nodes of ``grid``, F(r) = exp(r^2 / (r^2 - R^2)) for r < R
        (else 0), r the distance from (nucleation_x1, nucleation_x3)."""
        key = ("field", grid.shape, grid.dx1, grid.dx3)
        if key not in self._cache:
            x1, x3 = np.meshgrid(grid.x1 - self.nucleation_x1, grid.x3 - self.nucleation_x3, indexing="ij")
            r2, R2 = x1 * x1 + x3 * x3, self.nucleation_radius ** 2
            inside = r2 < R2
            F = np.zeros(grid.shape)
            F[inside] = np.exp(r2[inside] / (r2[inside] - R2))
            self._cache[key] = {c: getattr(self, f"nucleation_dtau_{c}") * F for c in (1, 3)
                                if getattr(self, f"nucleation_dtau_{c}") is not None}
        return self._cache[key]

    def _nucleation_terms(self, g, G, components, grid):
        """{c: g tau0_c + G dtau_c F} (the last one kept: after T it does not change)."""
        if grid is None:
            raise ValueError("a load with nucleation needs the grid (Loading.terms / at with grid=...)")
        key = ("terms", g, G, tuple(components), grid.shape, grid.dx1, grid.dx3)
        last = self._cache.get("terms")
        if last is None or last[0] != key:
            P = self.nucleation_field(grid)
            fields = {c: g * np.asarray(self.field(c), dtype=float) + G * P[c] if c in P else g * self.field(c)
                      for c in components}
            self._cache["terms"] = last = (key, fields)
        return last[1]

    def factor(self, t: float, crack_length: float | None = None) -> float:
        s = 1.0 if self.time == "step" else min(max(t, 0.0) / self.ramp_time, 1.0)
        g = s * s * (3.0 - 2.0 * s) if self.time == "smooth" else s
        if t < 0:
            g = 0.0
        if self.constant_K and crack_length:
            g *= np.sqrt(self.l0 / crack_length)
        return g

    def terms(self, t: float, components, crack_length: float | None = None, grid=None) -> tuple:
        """(g(t), {c: tau0_c}): tau0(t) = g tau0_c, for :func:`cracklab.laws.solve_velocity`;
        with the nucleation under way (G(t) > 0; ``grid`` needed) (1, {c: g tau0_c + G dtau_c F})."""
        g = self.factor(t, crack_length)
        if self.nucleates:
            G = self.nucleation_factor(t)
            if G > 0.0:
                return 1.0, self._nucleation_terms(g, G, components, grid)
        return g, {c: self.field(c) for c in components}

    def at(self, t: float, components, crack_length: float | None = None, grid=None) -> dict:
        """tau0(t) of ``components`` (the nucleation's perturbation included: ``grid`` needed)."""
        g = self.factor(t, crack_length)
        if self.nucleates:
            G = self.nucleation_factor(t)
            if G > 0.0:
                return dict(self._nucleation_terms(g, G, components, grid))
        return {c: g * self.field(c) for c in components}


def point_load(grid, P: float, x1: float, x3: float = 0.0) -> np.ndarray:
    """Field tau0 = P / (dx1 dx3) at the node nearest (x1, x3), zero elsewhere (section 3.2)."""
    f = np.zeros(grid.shape)
    i, k = grid.nearest_node(x1, x3)
    f[i, k] = P / (grid.dx1 * (grid.dx3 if not grid.plane else 1.0))
    return f
