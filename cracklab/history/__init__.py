"""History (time-convolution) engines.

An engine serves one channel of modes (one kernel) and answers, at every step,
S_n = sum_{j=0}^{n} w_j(gamma) x_{n-j}, the discrete convolution of Eq. (44)/(48)
for each Fourier mode, where x_n is the value pushed at step n. The response layer
owns the physical prefactors; laws and the stepper never see an engine. An engine is
one file here, a class registered with ``base.register`` (protocol: base.py); every
module of the package is imported and each registered engine is in ``ENGINES``.
"""
from __future__ import annotations

import importlib
import pkgutil

from .base import REGISTRY, register  # noqa: F401


#: the modules of the package that hold no engine (the protocol, the exponential engine's
#: compiled loops, which load on first use, its fits and the weight tables; the history at a
#: variable step of the sequences, which is not a fixed-step engine)
_HELPERS = ("base", "blocked", "fit", "tables", "variable")


def _discover() -> dict:
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name not in _HELPERS:
            importlib.import_module(f"{__name__}.{info.name}")
    for cls in REGISTRY.values():
        globals()[cls.__name__] = cls
    return dict(sorted(REGISTRY.items()))


#: {name: engine class}
ENGINES = _discover()


def resolve_engine(name: str, window=None) -> str:
    """"auto": the first engine of flat cost per step that takes the window (the exponential
    one), else the first that keeps a truncated history (the direct one, for a windowed run)."""
    if name != "auto":
        return name
    takes = [n for n, cls in ENGINES.items() if window is None or cls.windowed]
    return next((n for n in takes if ENGINES[n].flat_cost), None) or takes[0]


def make_engine(name: str, **kwargs):
    """Build the history engine called ``name`` (see ``ENGINES``; "auto": :func:`resolve_engine`)."""
    name = resolve_engine(name, kwargs.get("window"))
    try:
        cls = ENGINES[name]
    except KeyError:
        from ..errors import InputError

        raise InputError("numerics.engine", f"must be one of {sorted(ENGINES)}, got {name!r}") from None
    return cls(**kwargs)


__all__ = ["DirectEngine", "ENGINES", "ExponentialEngine", "make_engine", "register", "resolve_engine"]
