"""What every friction law shares: its strength is a friction coefficient times the
compressive normal stress, either the constant parameter ``sigma_n`` or, when a law is
given no ``sigma_n``, the normal traction of the current step (docs/equations.md,
"Friction that follows the normal traction").

A friction law derives from :class:`Friction` and writes ``coefficient(state, t, grid)``
(its friction coefficient) instead of ``strength``. Without ``sigma_n`` it acts on all
three components: step (v) first solves the normal component (no tensile strength, no
interpenetration), tau_2 = tau*_2 - eta_2 v_2 with v_2 = max(tau*_2 / eta_2, -delta_2 / dt),
then slides with the strength coefficient x max(0, -tau_2). The scene must then load the
normal component (tau0_2 < 0 where the faces are pressed together).
"""
from __future__ import annotations

import numpy as np

from .base import ALL, SHEAR, Law
from .solve import solve_normal_first, solve_velocity


class Friction(Law):
    """Defaults of a friction law (see the module docstring); its dataclass has the
    parameter ``sigma_n`` (None: follow the normal traction)."""

    reads_slip = False

    @property
    def follows_normal(self) -> bool:
        """True when the strength follows the current normal traction (no ``sigma_n``)."""
        return self.sigma_n is None

    @property
    def components(self):
        return ALL if self.follows_normal else SHEAR

    @property
    def contact(self):
        """The faces do not interpenetrate where the law solves the normal component."""
        return self.follows_normal

    @property
    def needs(self) -> tuple:
        """Components the scene must load: the normal one when the law follows it."""
        return (2,) if self.follows_normal else ()

    def coefficient(self, state, t, grid):
        """The friction coefficient (a number or an (n1, n3) field)."""
        raise NotImplementedError

    def strength(self, state, t, grid):
        """Eq. (38): coefficient x sigma_n; the coefficient alone when the law follows the
        normal traction (step (v) multiplies it by that traction, see ``applied_strength``)."""
        mu = self.coefficient(state, t, grid)
        return mu if self.follows_normal else mu * self.sigma_n

    def applied_strength(self, strength, tau):
        """The strength step (v) applied, from ``strength`` and the traction of the step."""
        if not self.follows_normal:
            return strength
        return strength * np.maximum(0.0, -tau[2])

    def solve(self, state, tau_star, delta, eta, dt, strength, load=None, traction=True):
        """Step (v); with the normal traction followed: the normal component first (zero
        strength, contact), then the shear components against coefficient x max(0, -tau_2)."""
        if not self.follows_normal or 2 not in tau_star:
            return solve_velocity(self, state, tau_star, delta, eta, dt, strength, load, traction)
        return solve_normal_first(self, state, tau_star, delta, eta, dt, 0.0,
                                  lambda tau: self.applied_strength(strength, tau), load, traction)
