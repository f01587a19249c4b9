"""Time schemes, one class per file (protocol: base.py). ``SCHEMES`` maps each
``Numerics.formulation`` to its scheme."""
from __future__ import annotations

from .base import Channel, Scheme  # noqa: F401
from .displacement import Displacement
from .product import Product
from .product2 import Product2
from .velocity import Velocity

#: {formulation: scheme}
SCHEMES = {s.name: s for s in (Displacement(), Velocity(), Product(), Product2())}
