"""Interface laws: the strength of the plane and how it evolves (Eq. 38, Fig. 4).

One law per module, each a frozen dataclass deriving from :class:`base.Law` (the
protocol: docs/developer/developer.md, "Add a law"). A law registers by its TOML name ``kind``:
every module of this package is imported, and each Law subclass with a ``kind`` found in
them is in :data:`LAWS`, so that adding a law is one file.
"""
from __future__ import annotations

import importlib
import inspect
import pkgutil

from .base import ALL, NORMAL, SHEAR, Law, law_parameters, parameter  # noqa: F401
from .solve import solve_velocity  # noqa: F401


def _discover() -> dict:
    found = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name in ("base", "solve", "friction"):
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        for obj in vars(module).values():
            if inspect.isclass(obj) and issubclass(obj, Law) and obj.kind and obj.__module__ == module.__name__:
                if obj.kind in found:
                    raise ImportError(f"two laws have the kind {obj.kind!r}: {found[obj.kind].__name__}, {obj.__name__}")
                found[obj.kind] = obj
                globals()[obj.__name__] = obj
    return found


#: {kind: law class}, every law of the package
LAWS = _discover()
