"""History (time-convolution) engines.

An engine serves one channel of modes (one kernel) and answers, at every step,
S_n = sum_{j=0}^{n} w_j(gamma) x_{n-j}, the discrete convolution of Eq. (44)/(48)
for each Fourier mode, where x_n is the value pushed at step n. The response layer
owns the physical prefactors; laws and the stepper never see an engine.
"""
from __future__ import annotations

from .direct import DirectEngine
from .exponential import ExponentialEngine

ENGINES = {"direct": DirectEngine, "exponential": ExponentialEngine}


def resolve_engine(name: str, window=None) -> str:
    """"auto": the exponential engine (flat cost per step), or the direct one for a windowed history."""
    if name == "auto":
        return "direct" if window is not None else "exponential"
    return name


def make_engine(name: str, **kwargs):
    """Build the history engine called ``name`` (see ``ENGINES``; "auto": :func:`resolve_engine`)."""
    name = resolve_engine(name, kwargs.get("window"))
    try:
        cls = ENGINES[name]
    except KeyError:
        from ..errors import InputError

        raise InputError("numerics.engine", f"must be one of {sorted(ENGINES)}, got {name!r}") from None
    return cls(**kwargs)


__all__ = ["DirectEngine", "ENGINES", "ExponentialEngine", "make_engine", "resolve_engine"]
