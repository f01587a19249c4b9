"""The output of a sequence run (cracklab.solver.sequence): station series and the largest
slip rate at every accepted step (or every ``sequence.station_every``), the recorded fields
at the slow and fast cadences and at each event's start and end, and the event catalogue
on an ``event`` dimension (docs/guide/sequences.md)."""
from __future__ import annotations

import math
import time
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from ..errors import InputError
from ..laws.base import cell_area_and_width
from ..model.scene_io import scene_to_json
from ..model.units import unit
from ..solver.budget import SEQUENCE_ROWS, SEQUENCE_SNAPSHOT_BYTES
from ..solver.sequence.run import SequenceRun
from ..version import __version__
from . import checkpoint, verify
from .attrs import field_attrs, input_attrs
from .policy import checkpoint_policy

#: why a snapshot was taken (``snapshot_kind``: the index): the slow and fast cadences,
#: an event's start and end
KINDS = ("slow", "fast", "start", "end")
#: samples of the largest slip rate around a peak that refine it (a quartic in ln V)
PEAK_SAMPLES = 5


def refine_peak(t, lnV) -> tuple[float, float]:
    """(time, value) of the largest slip rate from samples around a local maximum of ln V
    (``PEAK_SAMPLES`` of them, the largest in the middle): the maximum of the quartic through
    them (the sampled maximum where the quartic has none inside)."""
    t, lnV = np.asarray(t, dtype=float), np.asarray(lnV, dtype=float)
    j = int(np.argmax(lnV))
    if t.size < PEAK_SAMPLES or not np.all(np.isfinite(lnV)):
        return float(t[j]), float(math.exp(lnV[j]))
    x = t - t[j]
    span = float(np.ptp(x)) or 1.0
    coef = np.polyfit(x / span, lnV, PEAK_SAMPLES - 1)
    roots = np.roots(np.polyder(coef))
    roots = roots[np.isreal(roots)].real
    roots = roots[(roots >= x.min() / span) & (roots <= x.max() / span)]
    if roots.size == 0:
        return float(t[j]), float(math.exp(lnV[j]))
    values = np.polyval(coef, roots)
    k = int(np.argmax(values))
    if values[k] < lnV[j]:
        return float(t[j]), float(math.exp(lnV[j]))
    return float(t[j] + roots[k] * span), float(math.exp(values[k]))


class _Events:
    """The catalogue, built step by step: an event starts when the largest slip rate rises
    above the threshold and ends when it falls below it again."""

    def __init__(self, scene, s1, s3):
        self.threshold = scene.sequence.event_threshold
        self.scene, self.s1, self.s3 = scene, s1, s3
        self.rows = []
        self.current = None
        self.window = []        # the last PEAK_SAMPLES (t, ln max V)
        self.prev = None        # (t, max V) of the last step

    def step(self, state, vmax, where) -> str | None:
        """Feed one accepted step; returns "start" or "end" when an event starts or ends at it."""
        t = state.t
        self.window = (self.window + [(t, math.log(max(vmax, 1e-300)))])[-PEAK_SAMPLES:]
        out = None
        ev = self.current
        if ev is None and vmax >= self.threshold and self.prev is not None:
            t0, v0 = self.prev
            ev = self.current = {"t_start": _crossing(t0, v0, t, vmax, self.threshold),
                                 "hypocentre": where, "peak": (t, vmax), "slip0": _slip(state),
                                 "vmax": state.largest()}       # at the system's points: no grid a step
            out = "start"
        elif ev is not None:
            state.largest(ev["vmax"])
            if vmax > ev["peak"][1]:
                ev["peak"] = (t, vmax)
            if len(self.window) == PEAK_SAMPLES and self.window[PEAK_SAMPLES // 2][1] >= max(
                    w[1] for w in self.window) and self.window[PEAK_SAMPLES // 2][0] >= ev["t_start"]:
                tp, vp = refine_peak(*zip(*self.window))
                if vp >= ev.get("refined", (0.0, 0.0))[1]:
                    ev["refined"] = (tp, vp)
            if vmax < self.threshold:
                t0, v0 = self.prev
                self._close(ev, _crossing(t0, v0, t, vmax, self.threshold), state)
                out = "end"
        self.prev = (t, vmax)
        return out

    def _close(self, ev, t_end, state):
        scene = self.scene
        grid = scene.grid
        slip = _slip(state) - ev["slip0"]
        area = state.spread("V", ev["vmax"]) >= self.threshold
        cell, _ = cell_area_and_width(grid)
        region = np.zeros(grid.shape, bool)
        region[self.s1, self.s3] = True
        ruptured = area & region
        moment = scene.material.mu * float(np.sum(slip[region])) * cell
        A = float(np.count_nonzero(ruptured)) * cell
        peak = ev.get("refined") if ev.get("refined", (0, 0))[1] >= ev["peak"][1] else ev["peak"]
        self.rows.append({"t_start": ev["t_start"], "t_end": t_end, "duration": t_end - ev["t_start"],
                          "hypocentre_x1": float(grid.x1[ev["hypocentre"][0]]),
                          "hypocentre_x3": float(grid.x3[ev["hypocentre"][1]]),
                          "peak_slip_rate": peak[1], "t_peak": peak[0],
                          "mean_slip": float(np.sum(slip[ruptured]) * cell / A) if A > 0 else 0.0,
                          "moment": moment, "rupture_area": A})
        self.current = None

    def dataset(self, units) -> xr.Dataset:
        rows = self.rows
        u = units
        meta = {"t_start": ("start: the largest slip rate rises above the threshold", u["time"]),
                "t_end": ("end: it falls below the threshold again", u["time"]),
                "duration": ("duration of the event", u["time"]),
                "hypocentre_x1": ("x1 of the largest slip rate at the start", u["length"]),
                "hypocentre_x3": ("x3 of the largest slip rate at the start", u["length"]),
                "peak_slip_rate": ("largest slip rate of the event", unit(u, "velocity")),
                "t_peak": ("time of the largest slip rate", u["time"]),
                "mean_slip": ("mean slip over the points whose slip rate exceeded the threshold", u["length"]),
                "moment": ("seismic moment, mu times the slip integrated over the recorded region"
                           + (" (per unit length along x3)" if self.scene.grid.plane else ""),
                           unit(u, "stress") + " " + u["length"] + ("2" if self.scene.grid.plane else "3")
                           if u["length"] != "1" else "1"),
                "rupture_area": ("area whose slip rate exceeded the threshold"
                                 + (" (a length in 2D)" if self.scene.grid.plane else ""),
                                 u["length"] + ("" if self.scene.grid.plane else "2") if u["length"] != "1" else "1")}
        data = {k: ("event", np.array([r[k] for r in rows], dtype=float), {"long_name": v[0], "units": v[1]})
                for k, v in meta.items()}
        return xr.Dataset(data, coords={"event": ("event", np.arange(len(rows)), {"long_name": "event number"})},
                          attrs={"event_threshold": self.threshold})


def _slip(state) -> np.ndarray:
    """Slip magnitude over the grid."""
    return np.sqrt(sum(d ** 2 for d in state.delta.values()))


def _crossing(t0, v0, t1, v1, threshold) -> float:
    """The time the largest slip rate crossed ``threshold`` between two steps (linear in ln V)."""
    if not (v0 > 0 and v1 > 0) or v0 == v1:
        return float(t1)
    r = (math.log(threshold) - math.log(v0)) / (math.log(v1) - math.log(v0))
    return float(t0 + min(1.0, max(0.0, r)) * (t1 - t0))


def _field(state, name):
    if name == "psi":
        return state.psi
    kind, c = name.split("_")
    return getattr(state, kind)[int(c)]       # tau only when asked: on a window it costs the grid's transforms


class SequenceRecorder:
    """What a sequence run records (module docstring), kept in memory or streamed to a Zarr
    store (``path``: a local directory, or the ``Store`` of a URL): the rows since the last
    flush are appended to the store's ``t`` and ``t_station`` variables, the run's and the
    recorder's state then written as a checkpoint (output/checkpoint.py), so that a killed
    run resumes from it; the catalogue, the inputs and the attrs are written at the end,
    the status last."""

    def __init__(self, scene, path=None):
        seq, grid, rec = scene.sequence, scene.grid, scene.record
        self.scene, self.path = scene, path
        self.s1, self.s3 = rec.region_slices(grid)
        self.nodes = rec.station_nodes(grid)
        self.flat_nodes = np.array([i * grid.shape[1] + j for i, j in self.nodes.values()], dtype=np.int64)
        self.x1, self.x3 = grid.x1, grid.x3     # the grid computes them when asked: once per run here
        comps = sorted({c for c in scene.components if c in (1, 3)} | set(seq.plate))
        self.fields = [f for f in rec.fields if f == "psi" or f.split("_")[0] in ("delta", "v", "tau")
                       and int(f.split("_")[1]) in comps]
        self.station_fields = [f"{k}_{c}" for k in ("delta", "v", "tau") for c in comps] + ["psi"]
        self.slow, self.fast = seq.intervals(grid.dx_min, scene.material.cs, scene.t_end)
        self.events = _Events(scene, self.s1, self.s3)
        self.snaps, self.snap_t, self.snap_kind = [], [], []
        self.snap_bytes = 0     # of the snapshots kept
        self.rows = {name: [] for name in ("t_station", "max_slip_rate", "x1", "x3", "time_step")}
        self.series = {f: [] for f in self.station_fields}
        self.next_snapshot = 0.0
        self.smallest, self.largest = math.inf, 0.0
        # wall-clock seconds spent stepping in events and between them (a resume adds to them)
        self.wall = {"fast": 0.0, "slow": 0.0}
        self._clock = None
        self.written = {"t": 0, "t_station": 0}     # rows in the store
        # the scene as attrs and input arrays, and its digest, serialised once per run
        self.scene_json, self.inputs = scene_to_json(scene)
        self.digest = checkpoint.scene_digest(self.scene_json, self.inputs)

    def __call__(self, state) -> None:
        scene, grid, seq = self.scene, self.scene.grid, self.scene.sequence
        if state.n > 0:
            self.smallest, self.largest = min(self.smallest, state.dt), max(self.largest, state.dt)
        vmax, where = state.peak(self.s1, self.s3)     # the recorded region (a builder's mirror image left out)
        change = self.events.step(state, vmax, where) if state.n > 0 else None
        end = state.t >= scene.t_end
        if state.n % seq.station_every == 0 or change is not None or end:
            for name, value in (("t_station", state.t), ("max_slip_rate", vmax), ("x1", self.x1[where[0]]),
                                ("x3", self.x3[where[1]]), ("time_step", state.dt)):
                self.rows[name].append(float(value))
            for f in self.station_fields:       # read at the stations only (on a window: no field spread)
                self.series[f].append(state.at(f, self.flat_nodes))
        in_event = self.events.current is not None
        now = time.perf_counter()
        if self._clock is not None:
            self.wall["fast" if in_event or change is not None else "slow"] += now - self._clock
        self._clock = now
        if self.fields and (state.t >= self.next_snapshot or change is not None or end):
            self.snaps.append({f: _field(state, f)[self.s1, self.s3].copy() for f in self.fields})
            self.snap_bytes += sum(x.nbytes for x in self.snaps[-1].values())
            self.snap_t.append(state.t)
            self.snap_kind.append(change or ("fast" if in_event else "slow"))
            self.next_snapshot = state.t + (self.fast if in_event else self.slow)

    # -- the parts of the Dataset
    def _coords(self):
        grid, u = self.scene.grid, self.scene.units
        return {"x1": ("x1", grid.x1[self.s1], {"units": u["length"], "long_name": "distance along x1", "axis": "X"}),
                "x3": ("x3", grid.x3[self.s3], {"units": u["length"], "long_name": "distance along x3", "axis": "Y"})}

    def _time_attrs(self):
        u = self.scene.units["time"]
        return {"units": u, "long_name": "time", "axis": "T", **({"standard_name": "time"} if u != "1" else {})}

    def snapshot_part(self) -> xr.Dataset:
        """The snapshots not yet written, on t."""
        scene, grid = self.scene, self.scene.grid
        ds = xr.Dataset(coords={"t": ("t", np.array(self.snap_t, dtype=float), self._time_attrs()), **self._coords()})
        shape = (0, len(grid.x1[self.s1]), len(grid.x3[self.s3]))
        for f in self.fields:
            ds[f] = (("t", "x1", "x3"), np.stack([s[f] for s in self.snaps]) if self.snaps else np.zeros(shape),
                     field_attrs(scene, f))
        ds["snapshot_kind"] = ("t", np.array([KINDS.index(k) for k in self.snap_kind], dtype=np.int8),
                               {"long_name": "why the snapshot was taken",
                                "flag_values": np.arange(len(KINDS), dtype=np.int8), "flag_meanings": " ".join(KINDS)})
        return ds

    def station_part(self) -> xr.Dataset:
        """The rows of the station series and the largest slip rate not yet written, on t_station."""
        scene, grid, u = self.scene, self.scene.grid, self.scene.units
        r = self.rows
        ds = xr.Dataset(coords={"t_station": ("t_station", np.array(r["t_station"]),
                                              {**self._time_attrs(), "long_name": "time of the station series"})})
        vel = unit(u, "velocity")
        ds["max_slip_rate"] = ("t_station", np.array(r["max_slip_rate"]),
                               {"long_name": "largest slip rate on the plane", "units": vel})
        ds["max_slip_rate_x1"] = ("t_station", np.array(r["x1"]),
                                  {"long_name": "x1 of the largest slip rate", "units": u["length"]})
        ds["max_slip_rate_x3"] = ("t_station", np.array(r["x3"]),
                                  {"long_name": "x3 of the largest slip rate", "units": u["length"]})
        ds["time_step"] = ("t_station", np.array(r["time_step"]),
                           {"long_name": "the accepted step that ended at t_station", "units": u["time"]})
        if self.nodes:
            n = len(self.nodes)
            for f in self.station_fields:
                ds[f"station_{f}"] = (("station", "t_station"), np.array(self.series[f]).reshape(-1, n).T,
                                      field_attrs(scene, f))
        return ds

    def station_coords(self) -> dict:
        grid, u = self.scene.grid, self.scene.units
        if not self.nodes:
            return {}
        return {"station": ("station", np.array(list(self.nodes), dtype=object), {"long_name": "station name"}),
                "station_x1": ("station", np.array([grid.x1[i] for i, _ in self.nodes.values()]),
                               {"units": u["length"]}),
                "station_x3": ("station", np.array([grid.x3[j] for _, j in self.nodes.values()]),
                               {"units": u["length"]})}

    def final_part(self, steps) -> xr.Dataset:
        """The catalogue, the scene's inputs and the attrs."""
        scene = self.scene
        ds = self.events.dataset(scene.units)
        for name, arr in self.inputs.items():
            ds[name] = (("input_x1", "input_x3"), np.asarray(arr), input_attrs(scene, name))
        ds.attrs = {"Conventions": "CF-1.10", "title": f"cracklab sequence: {scene.name}",
                    "source": f"cracklab {__version__}", "cracklab_version": __version__, "scene": self.scene_json,
                    "event_threshold": scene.sequence.event_threshold, "accepted_steps": int(steps),
                    "smallest_step": self.smallest, "largest_step": self.largest,
                    "wall_time_in_events": self.wall["fast"], "wall_time_between_events": self.wall["slow"]}
        return ds

    def full(self) -> bool:
        """Whether what is kept should be written: SEQUENCE_SNAPSHOT_BYTES of snapshots or
        SEQUENCE_ROWS rows of the station series (solver/budget.py counts as much)."""
        return self.snap_bytes >= SEQUENCE_SNAPSHOT_BYTES or len(self.rows["t_station"]) >= SEQUENCE_ROWS

    def _clear(self):
        self.snaps, self.snap_t, self.snap_kind = [], [], []
        self.snap_bytes = 0
        self.rows = {name: [] for name in self.rows}
        self.series = {f: [] for f in self.station_fields}

    # -- the store
    def flush(self) -> None:
        """Append the rows since the last flush to the store (creating it at the first)."""
        for dim, part in (("t", self.snapshot_part), ("t_station", self.station_part)):
            ds = part()
            if ds.sizes[dim] == 0:
                continue
            first_ever = not any(self.written.values())
            if not first_ever:
                ds = ds.drop_vars([v for v in ("x1", "x3") if v in ds.variables])
            ds.attrs = self.identity("running")     # every write puts the group's attrs: these
            if self.written[dim] == 0:          # this dim's variables are new: their encoding
                if dim == "t_station":
                    ds = ds.assign_coords(**self.station_coords())
                enc = checkpoint.encoding(ds)
                for name, var in ds.variables.items():
                    if dim in var.dims:     # snapshots about SNAPSHOT_CHUNK_BYTES a chunk of a field;
                        # series in long chunks (a chunk per row would make reading t back cost memory
                        # in proportion to the run)
                        along = snapshots_per_chunk(var) if dim == "t" and var.ndim > 1 else CHUNK
                        enc[name]["chunks"] = tuple(along if d == dim else ds.sizes[d] for d in var.dims)
                _write(ds, self.path, mode="w" if first_ever else "a", encoding=enc)
            else:
                _write(ds, self.path, mode="a", append_dim=dim)
            self.written[dim] += ds.sizes[dim]
        self._clear()

    def identity(self, status) -> dict:
        """The store's group attrs while it runs: what identifies the run (its scene and
        digest, so that ``cracklab run`` knows the store as this scene's run) and its status."""
        return {"scene": self.scene_json, "cracklab_run_format": checkpoint.RUN_FORMAT,
                "cracklab_scene_digest": self.digest, "cracklab_status": status}

    def _mark(self, status, extra=None) -> None:
        import zarr

        zarr.open_group(_zarr(self.path), mode="a").attrs.update({**self.identity(status), **(extra or {})})

    def get_state(self) -> dict:
        ev = self.events
        return {"written": dict(self.written), "next_snapshot": self.next_snapshot, "smallest": self.smallest,
                "largest": self.largest, "wall": dict(self.wall), "rows": ev.rows, "current": ev.current, "window": ev.window,
                "prev": ev.prev}

    def set_state(self, state) -> None:
        self.written = {k: int(v) for k, v in state["written"].items()}
        self.next_snapshot, self.smallest, self.largest = (float(state[k]) for k in ("next_snapshot", "smallest",
                                                                                      "largest"))
        self.wall = {k: float(v) for k, v in state.get("wall", self.wall).items()}
        ev = self.events
        ev.rows, ev.window, ev.prev = state["rows"], [tuple(w) for w in state["window"]], \
            None if state["prev"] is None else tuple(state["prev"])
        cur = state["current"]
        if cur is not None:
            cur = dict(cur)
            for key in ("hypocentre", "peak", "refined"):
                if key in cur:
                    cur[key] = tuple(cur[key])
        ev.current = cur

    def finish(self, steps, resumed_from=None) -> xr.Dataset:
        """The run's Dataset: in memory, or the store completed (then read back lazily;
        ``resumed_from``: the accepted step a resume started after, in its attrs)."""
        if self.path is None:
            ds = xr.merge([self.snapshot_part(), self.station_part().assign_coords(**self.station_coords())],
                          combine_attrs="override")
            final = self.final_part(steps)
            ds = xr.merge([ds, final], combine_attrs="override")
            ds.attrs = final.attrs
            return ds
        self.flush()
        final = self.final_part(steps)
        attrs, final.attrs = final.attrs, self.identity("running")
        _write(final, self.path, mode="a", encoding=checkpoint.encoding(final))
        final.attrs = attrs
        # what cracklab.output.verify expects of the complete store beyond t, x1, x3, the
        # fields and the inputs
        stations = ["station", "station_x1", "station_x3", *(f"station_{f}" for f in self.station_fields)] \
            if self.nodes else []
        final.attrs["cracklab_final_arrays"] = ["t_station", "max_slip_rate", "max_slip_rate_x1",
                                                "max_slip_rate_x3", "time_step", "snapshot_kind", "event",
                                                *final.data_vars, *stations]
        import zarr

        self._mark("complete", {**final.attrs,
                                **({} if resumed_from is None else {"cracklab_resumed_from": int(resumed_from)})})
        checkpoint.remove(self.path)       # before the consolidated metadata: of what is there
        with warnings.catch_warnings():     # zarr: consolidated metadata is not in the v3 spec yet
            warnings.simplefilter("ignore")
            zarr.consolidate_metadata(_zarr(self.path))
        return xr.open_zarr(_zarr(self.path))


#: rows per chunk of the t_station variables of a store
CHUNK = 4096
#: bytes of a chunk of a recorded field's snapshots (at least one snapshot a chunk): a chunk
#: costs about a millisecond to write whatever its size up to about this, and a flush that
#: ends inside a chunk rewrites it whole with the next (zarr writes a chunk atomically)
SNAPSHOT_CHUNK_BYTES = 1 << 20


def snapshots_per_chunk(var) -> int:
    """Snapshots along t in a chunk of the recorded field ``var`` (t, x1, x3)."""
    one = var.dtype.itemsize * int(np.prod(var.shape[1:]))
    return max(1, SNAPSHOT_CHUNK_BYTES // max(one, 1))


def _zarr(path):
    """What zarr is given for the store at ``path`` (a local directory, or a ``Store``)."""
    return str(path) if isinstance(path, Path) else path.zarr_store()


def _exists(path) -> bool:
    """Whether anything is at ``path`` (a local directory, or a ``Store``)."""
    return path.exists() if isinstance(path, Path) else path.children() is not None


def _write(ds, path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")     # zarr v3: no spec yet for consolidated metadata or UTF-32 strings
        ds.to_zarr(_zarr(path), consolidated=False, write_empty_chunks=True, **kw)


def run_sequence(scene, *, progress=False, store=None, resume=False, checkpoint_every=None) -> xr.Dataset:
    """Run a sequence scene (``scene.sequence`` set); return its Dataset: the scene's inputs,
    the fields of ``record.fields`` on (t, x1, x3) at the slow and fast cadences and at each
    event's start and end, the station series and ``max_slip_rate`` (with its place) on
    ``t_station``, the catalogue on ``event`` (``cracklab.analysis.events``). ``store``: a
    Zarr store the run streams to (a local path or a URL: ``cracklab.output.stores``),
    checkpointing as ``simulate``'s ``checkpoint_every`` says (N accepted steps, or "60s"
    of wall time: the default; 0 never); ``resume``:
    continue a killed run from its checkpoint (the same numbers, bit for bit)."""
    path = None
    if store is not None:
        import os

        from .stores import store_for

        if not isinstance(store, (str, os.PathLike)):
            raise InputError("store", "a sequence streams to a Zarr store given by its path or URL, got "
                             + repr(store))
        target = store_for(store)
        if not target.checkpoints:
            raise InputError("store", f"a sequence streams to a store that keeps checkpoints; {target} "
                                      f"({target.kind}) does not")
        path = target.path if target.local else target
    rec = SequenceRecorder(scene, path)
    start = None
    if resume and path is not None and _complete(path, rec.digest):
        return xr.open_zarr(_zarr(path))
    if resume and path is not None and _exists(path):
        ck = checkpoint.read(path)
        if ck is not None and ck.get("digest") == rec.digest:
            start = ck
            _cut(path, ck["recorder"]["written"])
            rec.set_state(ck["recorder"])
    if start is None and path is not None and _exists(path):
        checkpoint.check_writable_target(path)      # a run store (or empty): never another directory
        checkpoint.as_store(path).clear()
    run = SequenceRun(scene, start=None if start is None else start["run"])
    every_n, every_s = checkpoint_policy(checkpoint_every)
    last_ck = time.monotonic()
    bar = _progress(progress, scene)
    for state in run:
        rec(state)
        if bar is not None:
            bar.update(state.t - bar.n)
        due = (every_n is not None and run.n % every_n == 0 and run.n > 0) or \
            (every_s is not None and time.monotonic() - last_ck >= every_s)
        if path is not None and not due and rec.full():
            rec.flush()             # memory bounded: a resume cuts what came after its checkpoint
        if path is not None and due:
            rec.flush()
            checkpoint.write(path, {"digest": rec.digest, "run": run.get_state(), "recorder": rec.get_state()})
            last_ck = time.monotonic()
    if bar is not None:
        bar.close()
    return rec.finish(run.n, None if start is None else int(start["run"]["n"]))


def _complete(path, digest) -> bool:
    """The store at ``path`` holds the sequence of the scene of ``digest``, complete and
    sound (``cracklab.output.verify``: every array and chunk there, read against its checksum)."""
    import zarr

    try:
        attrs = dict(zarr.open_group(_zarr(path), mode="r").attrs)
    except Exception:  # noqa: BLE001 - absent or not a Zarr group
        return False
    if attrs.get("cracklab_status") != "complete" or attrs.get("cracklab_scene_digest") != digest:
        return False
    report = verify.check_run(path if isinstance(path, Path) else path.tree())
    if not report.ok:
        verify.warn_damaged(path, report, "the sequence is run again from the start")
    return report.ok


def _cut(path, written) -> None:
    """Shorten the store's t and t_station variables to the rows a checkpoint counted."""
    import zarr

    g = zarr.open_group(_zarr(path), mode="a")
    for name in list(g.array_keys()):
        arr = g[name]
        dims = getattr(arr.metadata, "dimension_names", None) or ()
        if dims and dims[-1] == "t_station" and arr.shape[-1] != written["t_station"]:
            arr.resize(tuple(arr.shape[:-1]) + (written["t_station"],))
        elif dims and dims[0] == "t" and arr.shape[0] != written["t"]:
            arr.resize((written["t"],) + tuple(arr.shape[1:]))


def _progress(progress, scene):
    if not progress:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=scene.t_end, desc=scene.name, unit=scene.units["time"] if scene.units["time"] != "1" else "t",
                bar_format="{l_bar}{bar}| {n:.3g}/{total:.3g} {unit} [{elapsed}<{remaining}]")


