"""Time schemes, one class per file (protocol: base.py). Every module of this package is
imported and each class it registers (``base.register``) is in ``SCHEMES``, which maps each
``Numerics.formulation`` to its scheme, so that adding a scheme is one file."""
from __future__ import annotations

import importlib
import pkgutil

from .base import REGISTRY, Channel, Run, Scheme, register  # noqa: F401


def _discover() -> dict:
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name != "base":
            module = importlib.import_module(f"{__name__}.{info.name}")
            for obj in vars(module).values():
                if isinstance(obj, type) and issubclass(obj, Scheme) and obj.__module__ == module.__name__:
                    globals()[obj.__name__] = obj
    return dict(sorted(REGISTRY.items(), key=lambda item: (item[1].order, item[0])))


#: {formulation: scheme}
SCHEMES = _discover()


def scheme_of(formulation) -> Scheme:
    """The scheme of ``formulation``: a name of ``SCHEMES``, or a scheme, returned as it is."""
    return formulation if isinstance(formulation, Scheme) else SCHEMES[formulation]
