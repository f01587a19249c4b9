"""What the scene builders share: the unit material and the check of a builder's argument."""
from __future__ import annotations

from ..errors import InputError
from ..model.material import Material

UNIT = Material(mu=1.0, cs=1.0, nu=0.25)


def _require(name, ok, message):
    if not ok:
        raise InputError(name, message)
