"""Isotropic linear elastic material of a half space."""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..errors import InputError, check_fields_nesting, check_positive
from ..elastic.kernels import wave_speed_ratio


@dataclass(frozen=True)
class Material:
    """Shear modulus ``mu``, shear wave speed ``cs`` and Poisson ratio ``nu``."""

    mu: float
    cs: float
    nu: float

    def __post_init__(self):
        check_fields_nesting(self, "material")
        for name in ("mu", "cs", "nu"):
            if isinstance(getattr(self, name), (bool, np.bool_)):
                raise InputError(f"material.{name}", f"must be a number, got {getattr(self, name)!r}")
        object.__setattr__(self, "mu", check_positive("material.mu", self.mu))
        object.__setattr__(self, "cs", check_positive("material.cs", self.cs))
        try:
            nu = float(self.nu)
        except (TypeError, ValueError, OverflowError):
            raise InputError("material.nu", f"must be a number in (-1, 0.5), got {self.nu!r}") from None
        if not -1.0 < nu < 0.5:
            raise InputError("material.nu", f"must be in (-1, 0.5), got {self.nu!r}")
        object.__setattr__(self, "nu", nu)
        rho = self.mu / self.cs**2 if self.cs**2 > 0 else float("inf")
        if not (np.isfinite(rho) and rho > 0 and np.isfinite(self.mu / self.cs)):
            raise InputError("material.cs", f"mu / cs^2 (the density) must be a finite number > 0, got "
                                            f"mu = {self.mu!r}, cs = {self.cs!r}")

    @property
    def a(self) -> float:
        """c_d / c_s, with (c_d/c_s)^2 = 2(1-nu)/(1-2nu) (cracklab.kernels.wave_speed_ratio)."""
        return wave_speed_ratio(self.nu)

    @property
    def cd(self) -> float:
        """Dilatational wave speed c_d = a c_s."""
        return self.a * self.cs

    @property
    def rho(self) -> float:
        """Density mu / c_s^2."""
        return self.mu / self.cs**2

    @cached_property
    def cR(self) -> float:
        """Rayleigh wave speed."""
        from ..elastic.waves import rayleigh_speed_ratio

        return float(rayleigh_speed_ratio(self.nu)) * self.cs

    def eta(self, component: int) -> float:
        """Radiation damping V_jj of Eq. (4) of an interface between two half spaces of
        this material: mu/(2 cs) for shear, mu a/(2 cs) for opening."""
        return self.mu * (self.a if component == 2 else 1.0) / (2.0 * self.cs)
