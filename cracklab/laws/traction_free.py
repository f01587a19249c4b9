"""The traction-free plane (Lamb's problem)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, check_fields_nesting
from .base import ALL, Law, bonded_mask, parameter


@dataclass(frozen=True)
class TractionFree(Law):
    """Traction-free plane, Lamb's problem; ``contact`` forbids interpenetration."""

    contact: bool = parameter(kind="option", default=False, accepted="true or false",
                              doc="forbid interpenetration (the opening stays >= 0)")
    bonded: np.ndarray | None = bonded_mask()
    reads_slip = False  # its update does not read delta (the product scheme then skips its trial slips)
    kind = "traction_free"
    components = ALL

    def __post_init__(self):
        check_fields_nesting(self, "law")
        if not isinstance(self.contact, (bool, np.bool_)):
            raise InputError("law.contact", f"must be true or false, got {self.contact!r}")

    def init_state(self, grid):
        return {}

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        pass

    def strength(self, state, t, grid):
        return 0.0
