"""The traction-free plane (Lamb's problem)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .base import ALL, Law, bonded_mask, parameter


@dataclass(frozen=True)
class TractionFree(Law):
    """Traction-free plane, Lamb's problem; ``contact`` forbids interpenetration."""

    contact: bool = parameter(kind="option", default=False, accepted="true or false",
                              doc="forbid interpenetration (the opening stays >= 0)")
    bonded: np.ndarray | None = bonded_mask()
    reads_slip = False  # its update does not read delta (the product scheme then skips its trial slips)
    kind = "traction_free"
    #: a small scene of the law (docs/reference/toml.md shows it, tests/docs/test_toml_page.py runs it)
    example = """\
# A traction-free plane under a uniform step of tension: it opens everywhere,
# at the rate 2 cs tau0_2 / (mu a) (the radiation damping of mode I)
name = "traction_free_example"
t_end = 0.2

[material]
mu = 1.0
cs = 1.0
nu = 0.25

[grid]
n1 = 16
n3 = 16
L1 = 1.0
L3 = 1.0

[law]
kind = "traction_free"
contact = false

[loading]
tau0_2 = 1.0

[record]
fields = ["delta_2", "v_2"]
"""
    components = ALL

    def __post_init__(self):
        if not isinstance(self.contact, (bool, np.bool_)):
            raise InputError("law.contact", f"must be true or false, got {self.contact!r}")

    def init_state(self, grid):
        return {}

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        pass

    def strength(self, state, t, grid):
        return 0.0
