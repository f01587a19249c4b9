"""What every friction law shares: its strength is a friction coefficient times the
compressive normal stress, either the constant parameter ``sigma_n`` or, when a law is
given no ``sigma_n``, the normal traction of the current step (docs/reference/equations.md,
"Friction that follows the normal traction").

A friction law derives from :class:`Friction` and writes ``coefficient(state, t, grid)``
(its friction coefficient) instead of ``strength``. Without ``sigma_n`` it acts on all
three components: step (v) first solves the normal component (no tensile strength, no
interpenetration), tau_2 = tau*_2 - eta_2 v_2 with v_2 = max(tau*_2 / eta_2, -delta_2 / dt),
then slides with the strength coefficient x max(0, -tau_2). The scene must then load the
normal component (tau0_2 < 0 where the faces are pressed together).

A law that follows the normal traction may regularise it (Prakash & Clifton 1993; the form
of Rubin & Ampuero 2007): the strength then uses an effective normal stress sigma* that
relaxes towards the current compressive normal stress sigma = max(0, -tau_2),

    d sigma*/dt = -(|V| / L* + 1 / t*) (sigma* - sigma),

with the slip scale L* = ``normal_slip_scale`` and the time scale t* = ``normal_time``
(either or both; Rubin & Ampuero's (|V| + V*)/L* is both, with V* = L*/t*). Over a step the
ODE is integrated exactly for the slip rate V_{n-1} at the step's start and the step's
sigma_n: sigma*_n = sigma_n + (sigma*_{n-1} - sigma_n) exp(-(|V_{n-1}| / L* + 1 / t*) dt),
and sigma*_0 = sigma_0 (docs/reference/equations.md, "Regularised normal stress"). sigma* is the law
state ``sigma_eff`` (recordable).
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError
from .base import ALL, SHEAR, Law, check_parameter, parameter
from .solve import solve_normal_first, solve_velocity

#: what the law's state holds of the regularised normal stress (recordable: ``sigma_eff``)
NORMAL_STATE = {"sigma_eff": ("effective normal stress of the strength (compressive positive)", "stress")}


def normal_slip_scale():
    """The parameter L* of the regularised normal stress (a friction law's field)."""
    return parameter(unit="length", default=None, accepted="> 0; without sigma_n",
                     doc="slip scale L* over which the strength's normal stress follows the normal traction "
                         "(Prakash-Clifton); absent: no slip scale")


def normal_time():
    """The parameter t* of the regularised normal stress (a friction law's field)."""
    return parameter(unit="time", default=None, accepted="> 0; without sigma_n",
                     doc="time scale t* over which the strength's normal stress follows the normal traction "
                         "(Prakash-Clifton); absent: no time scale")


class Friction(Law):
    """Defaults of a friction law (see the module docstring); its dataclass has the
    parameter ``sigma_n`` (None: follow the normal traction)."""

    reads_slip = False
    normal_slip_scale = None
    normal_time = None

    @property
    def follows_normal(self) -> bool:
        """True when the strength follows the current normal traction (no ``sigma_n``)."""
        return self.sigma_n is None

    @property
    def regularised(self) -> bool:
        """True when the strength uses the regularised normal stress sigma* (module doc)."""
        return self.normal_slip_scale is not None or self.normal_time is not None

    def check_normal(self) -> None:
        """Validate ``normal_slip_scale`` and ``normal_time`` (call from __post_init__)."""
        for name in ("normal_slip_scale", "normal_time"):
            if getattr(self, name) is not None:
                check_parameter(self, name)

    def check_scene(self, scene) -> None:
        """A regularised normal stress goes without ``sigma_n`` (checked with the scene, after
        the fields' shapes)."""
        for name in ("normal_slip_scale", "normal_time"):
            if getattr(self, name) is not None and self.sigma_n is not None:
                raise InputError(f"law.{name}", "must be given without law.sigma_n: it regularises the normal "
                                                "traction the strength follows (a constant sigma_n has none), "
                                                "got both")

    def unrecordable(self, name):
        """Why the state variable ``name`` cannot be recorded with this law (None: it can)."""
        if name in NORMAL_STATE and not self.regularised:
            return (f"{name!r} is the regularised normal stress: give law.normal_slip_scale or law.normal_time "
                    f"(> 0, without law.sigma_n)")
        return None

    # -- the regularised normal stress: state, step update, value of a solve
    def normal_fields(self) -> int:
        """The arrays of the grid's size :meth:`normal_state` holds (Law.state_fields)."""
        return 3 if self.regularised else 0

    def normal_state(self, grid) -> dict:
        """The state of the regularised normal stress (none without it): sigma* of the step
        and of the last one, and the step's decay factor."""
        if not self.regularised:
            return {}
        return {"sigma_eff": np.zeros(grid.shape), "sigma_eff_old": np.zeros(grid.shape),
                "normal_decay": np.zeros(grid.shape)}

    def normal_update(self, state, dt, v_prev) -> None:
        """Start a step: sigma*_{n-1} becomes the old value and the decay
        exp(-(|V_{n-1}| / L* + 1 / t*) dt) is set (0 at the first step: sigma*_0 = sigma_0)."""
        if not self.regularised:
            return
        state["sigma_eff"], state["sigma_eff_old"] = state["sigma_eff_old"], state["sigma_eff"]
        decay = state["normal_decay"]
        if v_prev is None:
            decay[...] = 0.0
            return
        rate = np.zeros(decay.shape)
        if self.normal_slip_scale is not None:
            speed = np.sqrt(sum(v_prev[c] ** 2 for c in v_prev if c in SHEAR))
            rate += speed / np.asarray(self.normal_slip_scale, dtype=float)
        if self.normal_time is not None:
            rate += 1.0 / np.asarray(self.normal_time, dtype=float)
        np.exp(-dt * rate, out=decay)

    def normal_stress(self, state, tau2):
        """The normal stress of the strength in a solve of the step: max(0, -tau_2), or
        sigma*_n = sigma + (sigma*_{n-1} - sigma) decay (written into the state)."""
        sigma = np.maximum(0.0, -tau2)
        if not self.regularised:
            return sigma
        out = state["sigma_eff"]
        np.subtract(state["sigma_eff_old"], sigma, out=out)
        out *= state["normal_decay"]
        out += sigma
        return out

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

    def applied_strength(self, strength, tau, state=None):
        """The strength step (v) applied, from ``strength`` and the traction of the step
        (and, regularised, the law ``state`` of the step, which holds sigma*)."""
        if not self.follows_normal:
            return strength
        if self.regularised and state is not None:
            return strength * state["sigma_eff"]
        return strength * np.maximum(0.0, -tau[2])

    def solve(self, state, tau_star, delta, eta, dt, strength, load=None, traction=True):
        """Step (v); with the normal traction followed: the normal component first (zero
        strength, contact), then the shear components against coefficient x max(0, -tau_2)
        (x sigma* when regularised)."""
        if not self.follows_normal or 2 not in tau_star:
            return solve_velocity(self, state, tau_star, delta, eta, dt, strength, load, traction)
        return solve_normal_first(self, state, tau_star, delta, eta, dt, 0.0,
                                  lambda tau: strength * self.normal_stress(state, tau[2]), load, traction)
