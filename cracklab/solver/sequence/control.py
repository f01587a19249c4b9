"""The step control of the sequence solvers: a tolerance on the error estimate of an
embedded pair, bounds on the step, and the next step from the last error (the standard
controller, Hairer, Norsett & Wanner 1993, II.4)."""
from __future__ import annotations

from dataclasses import dataclass

SAFETY = 0.9
GROW = 5.0          # at most this factor up after an accepted step
SHRINK = 0.2        # at most this factor down after a rejected one


@dataclass(frozen=True)
class StepControl:
    """``tolerance``: the relative error allowed per step (slip against L + |slip|, state
    against a); ``dt_min``, ``dt_max``: bounds on the step (s; a step that cannot meet the
    tolerance at ``dt_min`` stops the run); ``dt_first``: the first step tried. Their values
    come from a Scene's ``Sequence``, which checked them (``Sequence.steps``)."""

    tolerance: float = 1e-7
    dt_min: float = 1e-8
    dt_max: float = 3.15e7
    dt_first: float = 1e-3

    def next_step(self, dt: float, error: float, order: int, accepted: bool) -> float:
        """The step after one of length ``dt`` whose scaled error is ``error`` (1: at the
        tolerance) for a pair of ``order`` (its estimate is of order - 1)."""
        if not error > 0:                       # zero: grow the most; NaN: shrink the most
            factor = GROW if error == 0 else SHRINK
        else:
            factor = SAFETY * error ** (-1.0 / order)
            factor = min(GROW if accepted else 1.0, max(SHRINK, factor))
        return min(self.dt_max, max(self.dt_min, dt * factor))
