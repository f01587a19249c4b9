"""The interface-law protocol (docs/developer/developer.md, "Add a law").

A law is a frozen dataclass of its parameters that derives from :class:`Law`:

* class attributes: ``kind`` (its TOML name, by which it registers), ``example`` (a small
  TOML scene of the law, which docs/reference/toml.md shows), ``components``
  (the components it acts on: NORMAL, SHEAR or ALL), ``reads_slip`` (whether ``update``
  reads the slip), ``state_variables`` ({name: (long_name, unit)}: what of its state the
  recorder can record by name);
* parameters: dataclass fields made with :func:`parameter`, which says the unit each
  carries ("stress", "length", "velocity", "time", "1") and its kind ("field": a number
  or an (n1, n3) field; "mask": a boolean (n1, n3) field; "scalar": a number; "option":
  anything else); every law has the mask ``bonded`` (points that never move);
* methods: ``init_state(grid)``, ``update(state, delta, dt, v_prev, t, tau_prev)`` (step
  (i)) and ``strength(state, t, grid)`` (Eq. 38) to write, and ``state_fields()`` (how
  many arrays of the grid's size the state holds: the memory estimate's count; none by
  default) where the law keeps a state; ``broken``, ``failed``,
  ``solve`` (step (v): the shared :func:`cracklab.laws.solve.solve_velocity` unless the
  strength depends on v) and ``applied_strength`` (the strength it applied) have
  defaults, and so has ``check_scene(scene)`` (checks against the load and material when
  the Scene is built); a friction law derives from :class:`cracklab.laws.friction.Friction` and
  writes its ``coefficient`` instead of ``strength``;
* the energy budget's part (:mod:`cracklab.analysis.energy`), which rebuilds the state
  from the recorded slip: ``energy_state(grid)`` (the rebuilt state at t = 0; None: the
  law has none and gives no fracture energy), ``energy_update(state, delta, delta_prev)``
  (to the next snapshot), ``fracture_energy(state)`` and ``energy_failed(state)`` (for the
  crack length of constant-K loading); none by default.
"""
from __future__ import annotations

import dataclasses
import functools

import numpy as np

from ..errors import InputError, check_fields_nesting
from .solve import solve_velocity

NORMAL = (2,)
SHEAR = (1, 3)
ALL = (1, 2, 3)
UNITS = ("stress", "length", "velocity", "time", "1")
KINDS = ("field", "mask", "scalar", "option")


#: the accepted ranges a number or field parameter declares (``parameter(accepted=...)``,
#: optionally followed by "; " and a condition that involves other keys), every value of a
#: field in it: what docs/reference/toml.md shows, and what tests/docs/test_toml_page.py holds the
#: law's own checks to
RANGES = ("> 0", ">= 0", ">= 0 or inf", "finite")


def parameter(*, unit: str = "1", kind: str = "field", default=dataclasses.MISSING, accepted: str | None = None,
              doc: str = ""):
    """A law parameter: a dataclass field that carries its unit and kind (see module doc),
    its accepted range (one of :data:`RANGES` for a number or a field, then optionally "; "
    and a condition on other keys; free text for an option; None for a mask) and a
    one-line meaning ``doc`` (both for docs/reference/toml.md)."""
    if unit not in UNITS or kind not in KINDS:
        raise ValueError(f"unit must be one of {UNITS} and kind one of {KINDS}, got {unit!r}, {kind!r}")
    if kind in ("field", "scalar") and (accepted or "").split(";")[0] not in RANGES:
        raise ValueError(f"a {kind} parameter declares its range, one of {RANGES} (then, after a ';', what "
                         f"else it must satisfy), got {accepted!r}")
    return dataclasses.field(default=default, metadata={"unit": unit, "kind": kind, "accepted": accepted,
                                                        "doc": doc})


def bonded_mask():
    """The ``bonded`` parameter every law has: a boolean (n1, n3) mask, or None."""
    return parameter(kind="mask", default=None, doc="points that never move (true: bonded)")


def check_parameter(law, name, lower=0.0, allow_equal=False, allow_inf=False):
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


def cell_area_and_width(grid) -> tuple[float, float]:
    """Area of a cell of ``grid`` and the width of the plane across the crack: dx1 dx3 and
    L3, or dx1 and 1 in the plane problem (whose areas and lengths are per unit length along x3)."""
    return grid.dx1 * (grid.dx3 if not grid.plane else 1.0), (grid.L3 if not grid.plane else 1.0)


def failed_length(failed, cell_area: float, width: float):
    """Mean crack length of the failed cells: their area over the width of the plane across
    the crack (:func:`cell_area_and_width`), ``count * cell_area / width`` in that order (the
    constant-K load of a run scales with it, to the bit).  ``failed``: a boolean array
    (:meth:`Law.failed`; a float comes back) or numbers of failed cells (integers, e.g. one
    per time; an array comes back)."""
    failed = np.asarray(failed)
    if failed.dtype == bool:
        return float(np.count_nonzero(failed)) * cell_area / width
    return failed * cell_area / width


def _checked(post_init):
    """``post_init`` preceded by the check of the law's values' nesting (one InputError
    naming law.<field>), made once: by the outermost of the calls a law's ``__post_init__``
    makes up its classes (a law's own checks may call its base class's)."""
    @functools.wraps(post_init)
    def __post_init__(self):
        if type(self).__post_init__ is __post_init__:
            check_fields_nesting(self, "law")
        post_init(self)

    __post_init__.nesting_checked = True
    return __post_init__


class Law:
    """Defaults of the interface-law protocol (see the module docstring)."""

    def __init_subclass__(cls, **kwargs):
        """A law's own ``__post_init__`` (its checks) runs after the check of its values'
        nesting, which every law gets without calling it."""
        super().__init_subclass__(**kwargs)
        own = cls.__dict__.get("__post_init__")
        if own is not None and not getattr(own, "nesting_checked", False):
            cls.__post_init__ = _checked(own)

    @_checked
    def __post_init__(self):
        """Checks of the parameters made when the law is built (a law writes its own; the
        nesting of its values is checked before them)."""

    kind = ""
    #: a small, valid TOML scene of the law (docs/reference/toml.md shows it under the law,
    #: tests/docs/test_toml_page.py runs it; docs/tools/toml_page.py stops without one)
    example = ""
    components = ALL
    reads_slip = True
    contact = False
    state_variables: dict = {}
    #: whether the law heals (its strength recovers at rest): only such a law has cycles, and
    #: a sequence solver (cracklab.solver.sequence) takes only it; it then writes
    #: ``slide_rates`` and ``initial_state`` (laws/rate_state.py)
    heals = False

    @classmethod
    def parameters(cls) -> dict:
        """{name: (unit, kind)} of the law's parameters."""
        return {f.name: (f.metadata.get("unit", "1"), f.metadata.get("kind", "option"))
                for f in dataclasses.fields(cls)}

    def state_fields(self) -> float:
        """How many float arrays of the grid's size the law's state holds in a run: those of
        ``init_state`` and the work arrays its steps keep there (the memory estimate,
        solver/budget.py; checked against the state of real runs in tests/solver/test_budget.py).
        None by default."""
        return 0

    def broken(self, state):
        """Where the plane has no cohesion left (True: everywhere)."""
        return True

    def failed(self, state):
        """Where the plane has failed, for the crack length of constant-K loading (None: not defined)."""
        return None

    def solve(self, state, tau_star, delta, eta, dt, strength, load=None, traction=True):
        """Step (v): the velocity (and traction) from the elastic estimate ``tau_star``."""
        return solve_velocity(self, state, tau_star, delta, eta, dt, strength, load, traction)

    def applied_strength(self, strength, tau, state=None):
        """The strength step (v) applied (what the recorder records as ``strength``),
        from ``strength`` (of :meth:`strength`), the traction ``tau`` of the step and the
        law's ``state`` after it."""
        return strength

    def unrecordable(self, name):
        """Why the state variable ``name`` (one of ``state_variables``) is not recorded with
        these parameters, or None when it is (all of them by default)."""
        return None

    def check_scene(self, scene) -> None:
        """Checks of the law against the rest of its scene (its load, material, grid), made
        when the Scene is built: raise an InputError naming the field. None by default."""

    #: components the scene must load for the law to work (a friction law that follows
    #: the normal traction needs the normal component)
    needs = ()

    def energy_state(self, grid):
        """The state the energy budget rebuilds from the recorded slip, at t = 0 (``{name:
        array}``), or None when the law has none (the budget then gives no fracture energy)."""
        return None

    def energy_update(self, state, delta, delta_prev) -> None:
        """Bring the rebuilt ``state`` (:meth:`energy_state`) to the snapshot whose slip is
        ``delta`` ({component: array}); ``delta_prev`` is the previous snapshot's (None at the
        first)."""

    def energy_failed(self, state):
        """Where the plane has failed in the rebuilt ``state``, for the crack length of
        constant-K loading in the budget (None: the budget gives the load no crack length)."""
        return None

    def fracture_energy(self, state):
        """Fracture energy per unit area reached (an array over the plane) in the rebuilt
        ``state`` (:meth:`energy_state`); None when the law dissipates none."""
        return None


def parameter_docs(cls) -> dict:
    """{name: (unit, kind, accepted, doc)} of a law class's parameters (docs/reference/toml.md)."""
    return {f.name: (f.metadata.get("unit", "1"), f.metadata.get("kind", "option"), f.metadata.get("accepted"),
                     f.metadata.get("doc", "")) for f in dataclasses.fields(cls)}


def law_parameters(law) -> dict:
    """Parameters of a law as a dict (fields of the dataclass)."""
    return {f.name: getattr(law, f.name) for f in dataclasses.fields(law)}
