"""Embedded explicit Runge-Kutta pairs: a pair is its Butcher tableau (docs/reference/
equations.md, "Sequences: the time step"), a frozen dataclass with no behaviour beyond
what the tableau says. ``b`` advances the solution at ``order``; ``e = b - b_hat`` gives the
error estimate of the embedded solution of order ``order - 1``; ``fsal``: the last stage is
evaluated at the new solution (its rates start the next step)."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class EmbeddedPair:
    name: str
    order: int
    c: tuple
    a: tuple          # rows of the strictly lower triangle, a[i] for stage i (a[0] = ())
    b: tuple
    e: tuple
    fsal: bool

    @property
    def stages(self) -> int:
        return len(self.c)

    @property
    def evaluations(self) -> int:
        """Rate evaluations per accepted step: the stages less the first when it is the last
        stage of the step before (fsal)."""
        return self.stages - 1 if self.fsal else self.stages


#: Dormand & Prince (1980), RK5(4)7FM: order 5, error of order 4, first same as last
DORMAND_PRINCE = EmbeddedPair(
    name="dormand_prince", order=5,
    c=(0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0),
    a=((),
       (1 / 5,),
       (3 / 40, 9 / 40),
       (44 / 45, -56 / 15, 32 / 9),
       (19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729),
       (9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656),
       (35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84)),
    b=(35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0.0),
    e=(35 / 384 - 5179 / 57600, 0.0, 500 / 1113 - 7571 / 16695, 125 / 192 - 393 / 640,
       -2187 / 6784 + 92097 / 339200, 11 / 84 - 187 / 2100, -1 / 40),
    fsal=True)

#: Bogacki & Shampine (1989): order 3, error of order 2, first same as last
BOGACKI_SHAMPINE = EmbeddedPair(
    name="bogacki_shampine", order=3,
    c=(0.0, 1 / 2, 3 / 4, 1.0),
    a=((), (1 / 2,), (0.0, 3 / 4), (2 / 9, 1 / 3, 4 / 9)),
    b=(2 / 9, 1 / 3, 4 / 9, 0.0),
    e=(2 / 9 - 7 / 24, 1 / 3 - 1 / 4, 4 / 9 - 1 / 3, -1 / 8),
    fsal=True)

PAIRS = {p.name: p for p in (DORMAND_PRINCE, BOGACKI_SHAMPINE)}
