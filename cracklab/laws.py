"""Interface laws: the strength of the plane and how it evolves (Eq. 38, Fig. 4).

A law is a frozen dataclass of parameters (scalars or (n1, n3) fields) with three
plain methods: ``init_state``, ``update`` (after the displacement update, step (i))
and ``strength``; ``reads_slip`` says whether ``update`` reads the slip (a law without it
is taken to). ``solve_velocity`` is step (v) of the algorithm, shared by all laws.
Every law takes ``bonded``: a boolean (n1, n3) mask of points that never move.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from .errors import InputError, check_fields_nesting
from . import loops

NORMAL = (2,)
SHEAR = (1, 3)
ALL = (1, 2, 3)


def _check(law, name, lower=0.0, allow_equal=False, allow_inf=False):
    """Validate a scalar or field parameter of ``law`` (> lower, or >= with allow_equal;
    finite unless allow_inf)."""
    value = getattr(law, name)
    field_name = f"law.{name}"
    op = ">=" if allow_equal else ">"
    finite = "" if allow_inf else "finite "
    if isinstance(value, (bool, np.bool_, str, bytes)) or value is None:
        raise InputError(field_name, f"must be a {finite}number {op} {lower:g} or an (n1, n3) field of them, "
                                     f"got {value!r}")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise InputError(field_name, f"must be a {finite}number {op} {lower:g} or an (n1, n3) field of them, "
                                     f"got {value!r}") from None
    bad = (arr < lower) if allow_equal else (arr <= lower)
    infinite = np.isinf(arr) & ~bad if not allow_inf else np.zeros(arr.shape, bool)
    bad = bad | infinite | np.isnan(arr)
    if np.any(bad):
        if arr.ndim == 0:
            got = value
        else:
            got = f"a field holding {arr[bad].ravel()[0]:g}"
        if np.any(infinite) or np.any(np.isnan(arr)):
            raise InputError(field_name, f"must be a {finite}number {op} {lower:g}, got {got}")
        raise InputError(field_name, f"must be {op} {lower:g}, got {got}")
    if arr.ndim == 0:
        object.__setattr__(law, name, float(arr))


@dataclass(frozen=True)
class TractionFree:
    """Traction-free plane, Lamb's problem; ``contact`` forbids interpenetration."""

    contact: bool = False
    bonded: np.ndarray | None = None
    reads_slip = False  # its update does not read delta (the product scheme then skips its trial slips)
    kind = "traction_free"
    components = ALL

    def __post_init__(self):
        check_fields_nesting(self, "law")
        if not isinstance(self.contact, (bool, np.bool_)):
            raise InputError("law.contact", f"must be true or false, got {self.contact!r}")

    def init_state(self, grid):
        return {}

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        pass

    def strength(self, state, t, grid):
        return 0.0

    def broken(self, state):
        return True

    def failed(self, state):
        return None


@dataclass(frozen=True)
class LinearCohesive:
    """Mode I linear cohesive law (Fig. 4): strength tau_c (1 - max opening/delta_c)^+.

    No rehealing; inside the cohesive zone the opening rate cannot be negative;
    broken faces may close but never interpenetrate. ``initial_crack`` marks points
    broken at t = 0.
    """

    tau_c: float | np.ndarray
    delta_c: float | np.ndarray
    initial_crack: np.ndarray | None = None
    bonded: np.ndarray | None = None
    reads_slip = True  # its update reads delta
    kind = "linear_cohesive"
    components = NORMAL
    contact = True

    def __post_init__(self):
        check_fields_nesting(self, "law")
        _check(self, "tau_c")
        _check(self, "delta_c")

    def init_state(self, grid):
        dmax = np.zeros(grid.shape)
        if self.initial_crack is not None:
            dmax = np.where(self.initial_crack, np.inf, 0.0)
        return {"delta_max": dmax}

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        np.maximum(state["delta_max"], delta[2], out=state["delta_max"])

    def strength(self, state, t, grid):
        return self.tau_c * np.clip(1.0 - state["delta_max"] / self.delta_c, 0.0, 1.0)

    def broken(self, state):
        return state["delta_max"] >= self.delta_c

    def failed(self, state):
        return self.broken(state)


@dataclass(frozen=True)
class SlipWeakening:
    """Linear slip-weakening friction: mu_s sigma_n -> mu_d sigma_n over D_c of slip.

    ``sigma_n`` is the (compressive positive) normal stress; the slip is the
    accumulated slip path. In 3D the slip rate is collinear with the shear traction.
    """

    mu_s: float | np.ndarray
    mu_d: float | np.ndarray
    D_c: float | np.ndarray
    sigma_n: float | np.ndarray
    bonded: np.ndarray | None = None
    reads_slip = False  # its update does not read delta (the product scheme then skips its trial slips)
    kind = "slip_weakening"
    components = SHEAR

    def __post_init__(self):
        check_fields_nesting(self, "law")
        _check(self, "mu_s", allow_equal=True)
        _check(self, "mu_d", allow_equal=True)
        _check(self, "D_c")
        _check(self, "sigma_n", allow_equal=True)
        try:
            above = np.asarray(self.mu_d) > np.asarray(self.mu_s)
        except ValueError:          # fields of different shapes: the scene names the wrong one
            above = False
        if np.any(above):
            raise InputError("law.mu_d", f"must be <= law.mu_s (static friction {self.mu_s!r}), got {self.mu_d!r}"
                             if np.ndim(self.mu_d) == 0 and np.ndim(self.mu_s) == 0 else
                             "must be <= law.mu_s at every point of the field")

    def init_state(self, grid):
        return {"slip": np.zeros(grid.shape)}

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        if v_prev is not None:
            speed = np.sqrt(sum(v_prev[c] ** 2 for c in v_prev if c in SHEAR))
            state["slip"] += dt * speed

    def strength(self, state, t, grid):
        weakening = np.clip(state["slip"] / self.D_c, 0.0, 1.0)
        return (self.mu_s - (self.mu_s - self.mu_d) * weakening) * self.sigma_n

    def broken(self, state):
        return True

    def failed(self, state):
        return state["slip"] >= self.D_c


@dataclass(frozen=True)
class PrescribedRupture:
    """Strength drops from ``strength_before`` to ``residual`` once t > r / speed (Kostrov tests).

    r is the distance to the nucleation point ``origin`` = (x1, x3) in 3D, or to the
    line x1 = origin[0] in the plane problem. With ``weakening_time`` t_w > 0 the drop
    is linear in time over [r/speed - t_w/2, r/speed + t_w/2], starting from the
    traction the point carried when the drop began (a time-weakening release that
    avoids the pulses of cell-by-cell jumps; t_w = dx/speed is one cell).
    """

    speed: float
    origin: tuple = (0.0, 0.0)
    residual: float | np.ndarray = 0.0
    strength_before: float | np.ndarray = np.inf
    weakening_time: float = 0.0
    bonded: np.ndarray | None = None
    reads_slip = False  # its update does not read delta (the product scheme then skips its trial slips)
    kind = "prescribed_rupture"
    components = ALL
    contact = False

    def __post_init__(self):
        check_fields_nesting(self, "law")
        _check(self, "speed")
        _check(self, "residual", allow_equal=True)
        _check(self, "strength_before", allow_equal=True, allow_inf=True)
        _check(self, "weakening_time", allow_equal=True)
        if np.ndim(self.speed) or np.ndim(self.weakening_time):
            raise InputError("law.speed" if np.ndim(self.speed) else "law.weakening_time", "must be a number")
        origin = self.origin
        try:
            ok = not isinstance(origin, (str, bytes, dict)) and 1 <= len(origin) <= 2 and all(
                not isinstance(x, (bool, np.bool_)) and np.isfinite(float(x)) for x in origin)
        except (TypeError, ValueError, OverflowError):
            ok = False
        if not ok:
            raise InputError("law.origin", f"must be [x1, x3] (or [x1] in 2D) of finite numbers, got {origin!r}")
        object.__setattr__(self, "origin", tuple(float(x) for x in origin))

    def init_state(self, grid):
        x1, x3 = np.meshgrid(grid.x1, grid.x3, indexing="ij")
        r = np.abs(x1 - self.origin[0])
        if not grid.plane:
            r = np.hypot(r, x3 - self.origin[1])
        start = r / self.speed - 0.5 * self.weakening_time
        return {"t_start": start, "s_start": np.full(grid.shape, np.nan), "_t": -np.inf}

    def update(self, state, delta, dt, v_prev, t, tau_prev=None):
        state["_t"] = t
        new = (t >= state["t_start"]) & np.isnan(state["s_start"])
        if new.any():
            if tau_prev:
                level = np.sqrt(sum(tau_prev[c] ** 2 for c in tau_prev))
            else:
                level = np.zeros(state["s_start"].shape)
            state["s_start"][new] = np.maximum(level[new], self.residual if np.ndim(self.residual) == 0
                                               else np.asarray(self.residual)[new])

    def strength(self, state, t, grid):
        started = t >= state["t_start"]
        if self.weakening_time > 0:
            frac = np.clip(1.0 - (t - state["t_start"]) / self.weakening_time, 0.0, 1.0)
            s0 = np.where(started, state["s_start"], 0.0)
            dropping = self.residual + (s0 - self.residual) * frac
        else:
            dropping = self.residual
        return np.where(started, dropping, self.strength_before)

    def broken(self, state):
        return state["_t"] >= state["t_start"]

    def failed(self, state):
        return self.broken(state)


LAWS = {cls.kind: cls for cls in (TractionFree, LinearCohesive, SlipWeakening, PrescribedRupture)}


def law_parameters(law) -> dict:
    """Parameters of a law as a dict (fields of the dataclass)."""
    return {f.name: getattr(law, f.name) for f in fields(law)}


def solve_velocity(law, state, tau_star, delta, eta, dt, strength, load=None, traction=True):
    """Step (v): compare strength with the elastic estimate tau* and solve Eq. (3) for v.

    ``tau_star[j]`` is the traction if the plane did not move further (load plus f_j);
    with ``load`` = (g, {j: tau0_j}) it is f_j, and tau* = f_j + g tau0_j (added in the
    compiled pass, else in place first: the same numbers either way).
    Normal component: v = (tau* - S)/eta, non-negative where the point is not fully
    broken, limited by contact. Shear: |v| = (|tau*| - S)^+/eta along tau*.
    Returns (v, tau) as dicts over the active components (tau None unless ``traction``).
    """
    v = {}
    done = {}  # components whose v (bonded points included) and tau are final
    compiled = loops.compiled()
    shape = np.shape(next(iter(tau_star.values())))
    normal_fused = 2 in tau_star and compiled and len(shape) > 0
    shear_fused = compiled and all(c in tau_star for c in SHEAR)
    # the load each compiled pass adds itself; the rest is added here first
    nload = load if normal_fused and loops.fusable_load(load, shape, (2,)) else None
    sload = load if shear_fused and loops.fusable_load(load, shape, SHEAR) else None
    if load is not None:
        for c in tau_star:
            if (nload if c == 2 else sload) is None:
                loops.add_scaled(tau_star[c], load[0], load[1][c])
    if normal_fused:  # one compiled pass, same numbers
        contact = delta[2] if getattr(law, "contact", False) else None
        v[2], done[2] = loops.normal_velocity(tau_star[2], strength, eta[2], law.broken(state), contact, dt,
                                              law.bonded, load=nload)
    elif 2 in tau_star:
        v2 = (tau_star[2] - strength) / eta[2]
        broken = law.broken(state)
        v2 = np.where(broken, v2, np.maximum(v2, 0.0)) if broken is not True else v2
        if getattr(law, "contact", False):
            v2 = np.maximum(v2, -delta[2] / dt)
        v[2] = v2
    shear = [c for c in SHEAR if c in tau_star]
    if shear_fused:  # one compiled pass, the same numbers as below
        v[1], v[3], done[1], done[3] = loops.shear_velocity(tau_star[1], tau_star[3], strength, eta[1], law.bonded,
                                                            load=sload, traction=traction)
        shear = []
    if shear:
        mag = np.sqrt(sum(tau_star[c] ** 2 for c in shear))
        excess = np.maximum(mag - strength, 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            scale = np.where(mag > 0, excess / (eta[shear[0]] * mag), 0.0)
        for c in shear:
            v[c] = scale * tau_star[c]
    if law.bonded is not None:
        for c in v:
            if c not in done:
                v[c] = np.where(law.bonded, 0.0, v[c])
    if not traction:
        return v, None
    tau = {c: done[c] if c in done else tau_star[c] - eta[c] * v[c] for c in v}
    return v, tau
