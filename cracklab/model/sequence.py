"""What makes a scene a sequence of earthquakes: the plate's loading and the adaptive time
step (docs/reference/equations.md, "Sequences"). A Scene with ``sequence`` set runs through
cracklab.solver.sequence instead of the fixed-step stepper."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, check_fields_nesting, check_positive

RESPONSES = ("quasi_dynamic", "dynamic")
PAIRS = ("dormand_prince", "bogacki_shampine")
#: accepted steps a sequence is expected to take, for its disk and memory estimates (SEAS
#: BP1-QD over 1500 years takes some 10^4 to 10^5)
STEPS_ESTIMATE = 100_000


@dataclass(frozen=True)
class Sequence:
    """A sequence scene's loading, time step and recording.

    * ``response``: "quasi_dynamic" (the static response plus radiation damping) or
      "dynamic" (the full elastodynamic response, its history exact at a variable step).
    * ``plate_rate_1``, ``plate_rate_3``: the plate rate V_p along each shear component
      (velocity, >= 0, not both 0). The ``creep`` region (a mask; None: none) slides at it
      kinematically, and a spring of ``stiffness`` (stress per length, >= 0) on the mean
      slip pulls the plane at it: tau += k (V_p t - mean slip).
    * ``tolerance``: the relative error of a step (slip against L + |slip|, state against
      a); ``dt_min``, ``dt_max``, ``dt_first``: the step's bounds and the first step tried
      (time; None: 1e-3 dx / c_s, or the dynamic step beta dx / c_s with the dynamic
      response, t_end / 50, dx / c_s); ``pair``: the embedded Runge-Kutta pair of the
      quasi-dynamic response ("dormand_prince", order 5; "bogacki_shampine", order 3). The
      dynamic response steps by a predictor-corrector (order 2) and takes a step of dt_min
      whatever its error: that is the fixed-step ruptures' step; while its largest slip
      rate is below ``slow_rate`` (velocity, >= 0; None: 0.1 of the least sigma a / eta
      over the fault, where the radiation damping moves the solved slip rate by a tenth
      or less of an error in the history's end rate; 0: never) it steps by ``pair`` too.
    * ``mirror``: the plane is even about x1 = 0 (node (i, k) is node (n1 - i, k)): a free
      surface of the plane problem, the grid holding the fault and its image (scenes.bp1).
      The traction is made exactly even before each solve, so that the transforms'
      round-off cannot grow into ruptures of the fault and its image at different times;
      the scene's fields must be even.
    * Recording: the stations and the largest slip rate every ``station_every`` accepted
      steps; the fields of ``record.fields`` every ``slow_interval`` between events and
      every ``fast_interval`` during them (time; None: t_end / 100 and 100 dx / c_s), and
      at each event's start and end. An event lasts while the largest slip rate exceeds
      ``event_threshold`` (velocity).
    """

    response: str = "quasi_dynamic"
    plate_rate_1: float = 0.0
    plate_rate_3: float = 0.0
    creep: np.ndarray | None = None
    stiffness: float = 0.0
    tolerance: float = 1e-7
    dt_min: float | None = None
    dt_max: float | None = None
    dt_first: float | None = None
    pair: str = "dormand_prince"
    slow_rate: float | None = None
    event_threshold: float = 1e-3
    slow_interval: float | None = None
    fast_interval: float | None = None
    station_every: int = 1
    mirror: bool = False

    def __post_init__(self):
        check_fields_nesting(self, "sequence")
        if not isinstance(self.response, str) or self.response not in RESPONSES:
            raise InputError("sequence.response", f"must be one of {', '.join(RESPONSES)}, got {self.response!r}")
        for name in ("plate_rate_1", "plate_rate_3", "stiffness"):
            object.__setattr__(self, name, _number(f"sequence.{name}", getattr(self, name), allow_zero=True))
        for name in ("tolerance", "event_threshold"):
            object.__setattr__(self, name, _number(f"sequence.{name}", getattr(self, name)))
        if self.tolerance >= 1:
            raise InputError("sequence.tolerance",
                             f"must be in (0, 1): a relative error per step, got {self.tolerance!r}")
        for name in ("dt_min", "dt_max", "dt_first", "slow_interval", "fast_interval"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, _number(f"sequence.{name}", getattr(self, name)))
        if self.slow_rate is not None:
            object.__setattr__(self, "slow_rate", _number("sequence.slow_rate", self.slow_rate, allow_zero=True))
        if not isinstance(self.pair, str) or self.pair not in PAIRS:
            raise InputError("sequence.pair", f"must be one of {', '.join(PAIRS)}, got {self.pair!r}")
        if isinstance(self.station_every, bool) or not isinstance(self.station_every, (int, np.integer)) \
                or self.station_every < 1:
            raise InputError("sequence.station_every", f"must be an integer >= 1, got {self.station_every!r}")
        if not isinstance(self.mirror, (bool, np.bool_)):
            raise InputError("sequence.mirror", f"must be true or false, got {self.mirror!r}")
        object.__setattr__(self, "mirror", bool(self.mirror))
        if self.creep is not None:
            arr = np.asarray(self.creep)
            if arr.dtype != bool:
                raise InputError("sequence.creep", f"must be a boolean mask, got dtype {arr.dtype}")
        if self.plate_rate_1 == 0 and self.plate_rate_3 == 0:
            raise InputError("sequence.plate_rate_1", "the plate rate must be > 0 along at least one shear component "
                                                      "(plate_rate_1 or plate_rate_3): without it nothing loads "
                                                      "the fault between events")
        self.steps()     # the bounds given must agree with each other

    @property
    def plate(self) -> dict:
        """{component: V_p} of the components the plate moves along (V_p > 0)."""
        return {c: v for c, v in ((1, self.plate_rate_1), (3, self.plate_rate_3)) if v > 0}

    def steps(self, dx=None, cs=None, t_end=None, beta=None) -> tuple[float, float, float]:
        """(dt_min, dt_max, dt_first), the defaults filled in from the grid spacing ``dx``, the
        shear wave speed ``cs``, ``t_end`` and the scene's ``beta`` (None: only the given
        bounds checked)."""
        floor = beta if self.response == "dynamic" and beta is not None else 1e-3
        dt_min = self.dt_min if self.dt_min is not None or dx is None else floor * dx / cs
        dt_max = self.dt_max if self.dt_max is not None or t_end is None else t_end / 50.0
        dt_first = self.dt_first if self.dt_first is not None or dx is None else dx / cs
        if dt_min is not None and dt_max is not None and dt_min > dt_max:
            raise InputError("sequence.dt_min", f"must be <= sequence.dt_max, got dt_min = {dt_min!r} > dt_max = "
                                                f"{dt_max!r}")
        if dt_first is not None:
            lo = dt_min if dt_min is not None else 0.0
            hi = dt_max if dt_max is not None else math.inf
            if not lo <= dt_first <= hi:
                if self.dt_first is None:
                    dt_first = min(max(dt_first, lo), hi)
                else:
                    raise InputError("sequence.dt_first", f"must lie in [dt_min, dt_max] = [{lo!r}, {hi!r}], "
                                                          f"got {dt_first!r}")
        return dt_min, dt_max, dt_first

    def intervals(self, dx, cs, t_end) -> tuple[float, float]:
        """(slow_interval, fast_interval) with the defaults filled in."""
        return (self.slow_interval if self.slow_interval is not None else t_end / 100.0,
                self.fast_interval if self.fast_interval is not None else 100.0 * dx / cs)

    def expected_rows(self, scene) -> tuple[int, int]:
        """(snapshots, station rows) a run of ``scene`` is expected to record: an estimate,
        not a bound (the number of events and of accepted steps are the run's own):
        twice the slow cadence's count (as many fast snapshots as slow), and ``STEPS_ESTIMATE``
        accepted steps."""
        slow, _ = self.intervals(scene.grid.dx_min, scene.material.cs, scene.t_end)
        nsnap = 2 * (int(scene.t_end / slow) + 1) if scene.record.fields else 0
        return nsnap, STEPS_ESTIMATE // self.station_every + 1

    def check_scene(self, scene) -> None:
        """Checks against the rest of the scene: a law that heals, a creep mask of the grid's
        shape that leaves points to slide, plate rates along components the law acts on,
        and no fixed-step recording."""
        law, grid = scene.law, scene.grid
        if not getattr(law, "heals", False):
            raise InputError("law.kind", f"a sequence needs a law whose strength heals (rate_state): "
                                         f"{law.kind!r} cannot heal, so no cycles are possible")
        for c in self.plate:
            if c not in law.components:
                raise InputError(f"sequence.plate_rate_{c}", f"law {law.kind!r} does not act on component {c}")
            if grid.free_surface and c == 3:
                raise InputError("sequence.plate_rate_3", "must be 0 with grid.free_surface: slip along x3 is "
                                                          "odd about the free surface")
        if scene.materials[0] != scene.materials[1]:
            raise InputError("materials", "a sequence runs between two identical half spaces for now (the "
                                          "quasi-dynamic response of a bimaterial pair is not available)")
        shape = grid.shape
        bonded = np.zeros(shape, bool) if law.bonded is None else np.broadcast_to(np.asarray(law.bonded, bool), shape)
        creep = np.zeros(shape, bool)
        if self.creep is not None:
            creep = np.asarray(self.creep)
            if creep.shape != shape:
                raise InputError("sequence.creep", f"field shape must be {shape}, got {creep.shape}")
        if np.all(creep | bonded):
            raise InputError("sequence.creep", "covers the whole plane (with the bonded points): no point is left "
                                               "to slide under the friction law")
        if self.mirror:
            _check_even(scene, creep)
        rec = scene.record
        if rec.every is not None or rec.times is not None:
            raise InputError("record.every" if rec.every is not None else "record.times",
                             "a sequence records its fields at sequence.slow_interval between events and "
                             "sequence.fast_interval during them; leave record.every and record.times out")


def _check_even(scene, creep) -> None:
    """With ``sequence.mirror``: every field of the scene even about x1 = 0, or one error naming the first that is not."""
    from ..solver.sequence.mirror import mirror_index

    from ..laws import law_parameters

    shape = scene.grid.shape
    image = mirror_index(shape)
    fields = [("sequence.creep", creep)]
    fields += [(f"law.{name}", value) for name, value in law_parameters(scene.law).items() if np.ndim(value) > 0]
    fields += [(f"loading.tau0_{c}", scene.loading.field(c)) for c in (1, 2, 3)]
    for name, value in fields:       # a number is even: only the fields over the grid are looked at
        arr = np.broadcast_to(np.asarray(value), shape).ravel()
        if not np.array_equal(arr, arr[image]):
            bad = int(np.flatnonzero(arr != arr[image])[0])
            i, k = np.unravel_index(bad, shape)
            raise InputError(name, f"must be even about x1 = 0 with sequence.mirror (node ({i}, {k}) differs from its "
                                   f"image ({(-i) % shape[0]}, {k})); make the field even or leave sequence.mirror out")


def _number(field, value, allow_zero=False) -> float:
    if isinstance(value, (bool, np.bool_)):
        raise InputError(field, f"must be a number {'>= 0' if allow_zero else '> 0'}, got {value!r}")
    return check_positive(field, value, allow_zero=allow_zero)
