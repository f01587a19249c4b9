"""What a run records: grid fields at a cadence, station series, rupture time."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, check_fields_nesting

FIELDS = ("delta_1", "delta_2", "delta_3", "v_1", "v_2", "v_3", "tau_1", "tau_2", "tau_3", "strength")
#: each face's own displacement u and velocity v on a bimaterial interface, ``<u|v>_<j>_<side>``
#: (side "top": x2 = 0+, "bottom": x2 = 0-; u_j_top - u_j_bottom = delta_j); computed only when
#: recorded, and then also recorded at the stations
FACE_FIELDS = tuple(f"{k}_{c}_{side}" for k in ("u", "v") for side in ("top", "bottom") for c in (1, 2, 3))


def face_field(name: str):
    """(kind "u" or "v", side, component) of a face field's name, None for another name."""
    if name not in FACE_FIELDS:
        return None
    kind, c, side = name.split("_")
    return kind, side, int(c)


def state_fields() -> tuple:
    """The state variables of the laws, which a Record may name too (the Scene checks that
    its law has the one named)."""
    from ..laws import LAWS

    return tuple(sorted({name for law in LAWS.values() for name in law.state_variables}))


@dataclass(frozen=True)
class Record:
    """Grid ``fields`` every ``every`` steps or at ``times`` (optionally on ``region``,
    {"x1": (lo, hi), "x3": (lo, hi)} in coordinates), and every step at ``stations``
    {name: (x1, x3)} (the slip, slip rate and traction components and the strength, and the
    faces' fields among ``fields``: ``FACE_FIELDS``). With neither ``every`` nor ``times``,
    about 20 snapshots are kept. ``fields`` None (the default): the slip of every component
    the scene activates (delta_2 in mode I), resolved by the Scene."""

    fields: tuple | None = None
    every: int | None = None
    times: tuple | None = None
    region: dict | None = None
    stations: dict | None = None

    def __post_init__(self):
        check_fields_nesting(self, "record")
        if self.fields is None:
            self._check_rest()
            return
        if isinstance(self.fields, str):
            object.__setattr__(self, "fields", (self.fields,))
        if not isinstance(self.fields, (list, tuple, np.ndarray)):
            raise InputError("record.fields", f"must be a list of field names ({', '.join(FIELDS)}), "
                                              f"got {self.fields!r}")
        object.__setattr__(self, "fields", tuple(self.fields))
        state = state_fields()
        for f in self.fields:
            if not isinstance(f, str) or (f not in FIELDS and f not in FACE_FIELDS and f not in state):
                raise InputError("record.fields", f"unknown field {f!r}; accepted: {', '.join(FIELDS)}, "
                                                  f"a face's motion on a bimaterial interface (u_1_top, v_1_top, "
                                                  f"... u_3_bottom, v_3_bottom) or a state variable of the law "
                                                  f"({', '.join(state)})")
        self._check_rest()

    def _check_rest(self):
        if self.every is not None:
            if isinstance(self.every, bool) or not isinstance(self.every, (int, np.integer)) or self.every < 1:
                raise InputError("record.every", f"must be an integer >= 1, got {self.every!r}")
        if self.times is not None:
            try:
                if isinstance(self.times, (str, bytes, dict)) or any(
                        isinstance(t, (bool, np.bool_, str, bytes)) for t in np.atleast_1d(self.times)):
                    raise TypeError
                times = tuple(float(t) for t in np.atleast_1d(self.times))
            except (TypeError, ValueError, OverflowError):
                raise InputError("record.times", f"must be a list of times in [0, t_end], got {self.times!r}") from None
            object.__setattr__(self, "times", times)
        if self.every is not None and self.times is not None:
            raise InputError("record.times", "give either record.every or record.times, not both")
        if self.region is not None:
            if not isinstance(self.region, dict):
                raise InputError("record.region", f"must be a table {{x1 = [lo, hi], x3 = [lo, hi]}}, "
                                                  f"got {self.region!r}")
            for key, bounds in dict(self.region).items():
                if key not in ("x1", "x3"):
                    raise InputError(f"record.region.{key}", "unknown key; accepted: x1, x3")
                try:
                    ok = np.ndim(bounds) == 1 and len(bounds) == 2 and not any(
                        isinstance(b, (bool, np.bool_, str, bytes)) for b in bounds) and \
                        float(bounds[0]) <= float(bounds[1])
                except (TypeError, ValueError, OverflowError):
                    ok = False
                if not ok:
                    raise InputError(f"record.region.{key}", f"must be (lo, hi) with lo <= hi, got {bounds!r}")
        if self.stations is not None:
            if not isinstance(self.stations, dict):
                raise InputError("record.stations", f"must be a table {{name = [x1, x3]}}, got {self.stations!r}")
            stations = {}
            for k, v in dict(self.stations).items():
                try:
                    if isinstance(v, (str, bytes)) or any(isinstance(x, (bool, np.bool_)) for x in v):
                        raise TypeError
                    stations[str(k)] = tuple(float(x) for x in v)
                except (TypeError, ValueError, OverflowError):
                    stations[str(k)] = ()
                if len(stations[str(k)]) not in (1, 2):
                    raise InputError(f"record.stations.{k}", f"must be (x1, x3) (or (x1,) in 2D), got {v!r}")
            object.__setattr__(self, "stations", stations)

    def snapshot_steps(self, nsteps: int, dt: float) -> np.ndarray:
        if self.times is not None:
            for t in self.times:
                if not 0 <= t <= nsteps * dt * (1 + 1e-12):
                    raise InputError("record.times", f"must lie in [0, t_end = {nsteps * dt:.6g}] (the end of the "
                                                     f"last of {nsteps} steps of dt = {dt:.6g}), got {t:.6g}")
            return np.unique(np.rint(np.asarray(self.times) / dt).astype(int))
        every = self.every or max(1, nsteps // 20)
        steps = np.arange(0, nsteps + 1, every)
        return steps

    def snapshot_count(self, nsteps: int, dt: float) -> int:
        """``len(snapshot_steps(nsteps, dt))`` without making the steps (for ``every``)."""
        if self.times is not None:
            return len(self.snapshot_steps(nsteps, dt))
        every = self.every or max(1, nsteps // 20)
        return nsteps // every + 1

    def region_slices(self, grid) -> tuple[slice, slice]:
        def sl(coord, bounds, field):
            if bounds is None:
                return slice(None)
            lo, hi = bounds
            idx = np.nonzero((coord >= lo) & (coord <= hi))[0]
            if idx.size == 0:
                raise InputError(f"record.region.{field}", f"({lo}, {hi}) holds no grid node")
            return slice(int(idx[0]), int(idx[-1]) + 1)

        region = self.region or {}
        s1 = sl(grid.x1, region.get("x1"), "x1")
        if getattr(grid, "free_surface", False) and region.get("x3") is not None and region["x3"][1] < 0:
            raise InputError("record.region.x3", f"{tuple(region['x3'])} lies above the free surface: with "
                                                 f"grid.free_surface, x3 is the depth below it, in [0, L3 = {grid.L3:g}]")
        s3 = slice(None) if grid.plane else sl(grid.x3, region.get("x3"), "x3")
        return s1, s3

    def station_nodes(self, grid) -> dict:
        out = {}
        surface = getattr(grid, "free_surface", False)
        for name, xy in (self.stations or {}).items():
            if len(xy) == 1 and not grid.plane:
                raise InputError(f"record.stations.{name}", f"{xy!r} gives x1 only: on a 3D grid (n3 = {grid.n3}) "
                                                            f"a station needs both coordinates, (x1, x3)")
            x1, x3 = (xy + (0.0,))[:2]
            if surface and x3 < 0:
                raise InputError(f"record.stations.{name}", f"({x1}, {x3}) lies above the free surface: with "
                                                            f"grid.free_surface, x3 is the depth below it, in "
                                                            f"[0, L3 = {grid.L3:g}]")
            if surface and not (0 <= x1 < grid.L1 and x3 <= grid.L3):
                raise InputError(f"record.stations.{name}", f"({x1}, {x3}) is outside the half plane [0, L1) x "
                                                            f"[0, L3] below the free surface")
            if not surface and not (0 <= x1 < grid.L1 and (grid.plane or 0 <= x3 < grid.L3)):
                raise InputError(f"record.stations.{name}", f"({x1}, {x3}) is outside the grid [0, L1) x [0, L3)")
            out[name] = grid.nearest_node(x1, x3)
        return out
