"""Run a scene and return (or stream to Zarr) a labelled xarray Dataset."""
from __future__ import annotations

import contextlib
import warnings

import numpy as np
import xarray as xr

from ..version import __version__
from . import checkpoint
from .disk import FLUSH, check_disk as holds, output_size, snapshots_per_chunk
from ..errors import InputError, Interrupted, SimulationError, StoreError
from ..model.record import face_field
from ..model.scene_io import scene_from_data, scene_to_json
from .policy import CHECKPOINT_SECONDS, checkpoint_policy  # noqa: F401
from .attrs import LONG_NAMES, field_attrs, input_attrs  # noqa: F401  (simulate.LONG_NAMES as before)
from ..solver.stepper import Stepper

def _field(state, name, faces=None):
    """The field ``name`` of ``state``; ``faces``: a dict that keeps the faces' fields of
    this state once computed (one inverse transform per kind and step)."""
    if name == "strength":
        return state.strength
    if name in state.law_state:
        return state.law_state[name]
    face = face_field(name)
    if face is not None:
        kind, side, c = face
        faces = {} if faces is None else faces
        if kind not in faces:
            faces[kind] = state.faces(kind)
        return faces[kind][side, c]
    kind, c = name.split("_")
    return {"delta": state.delta, "v": state.v, "tau": state.tau}[kind][int(c)]


class Recorder:
    """Collects snapshots, station series and rupture times; streams to Zarr if asked.

    A store run creates the store first at its final size (coordinates, snapshot variables
    NaN until written, the scene inputs and attrs), writes snapshots every ``flush_every``
    and at checkpoints, and adds the station series and rupture times at the end, then
    (last) ``cracklab_status``. Every array is written with a crc32c checksum per chunk,
    and every chunk of what is written is stored (NaN-only ones too), so that a missing
    chunk is a sign of damage (``cracklab.output.verify``). ``path`` is where checkpoints go:
    the store's local path, or its ``Store`` (a URL); None for store objects (no checkpoints)."""

    def __init__(self, scene, store, path=None, flush_every=FLUSH):
        self.scene, self.store, self.path, self.flush_every = scene, store, path, flush_every
        grid = scene.grid
        #: the snapshot steps, sorted (an array: a set of millions of ints took gigabytes)
        self.steps = np.asarray(scene.record.snapshot_steps(scene.nsteps, scene.dt), dtype=np.int64) \
            if scene.record.fields else np.zeros(0, np.int64)
        self.s1, self.s3 = scene.record.region_slices(grid)
        self.nodes = scene.record.station_nodes(grid)
        comps = scene.components
        self.station_fields = [f"{k}_{c}" for k in ("delta", "v", "tau") for c in comps] + ["strength"] + \
            [f for f in scene.record.fields if face_field(f)]
        self.series = {f: np.full((scene.nsteps + 1, len(self.nodes)), np.nan) for f in self.station_fields}
        # the arrays the end of the run writes (listed in the attrs: verification expects them)
        self.final_arrays = ["rupture_time"] + (
            ["station", "station_x1", "station_x3", "t_station"] + [f"station_{f}" for f in self.station_fields]
            if self.nodes else [])
        self.rupture = np.full(grid.shape, np.nan)
        self.pending = []
        self.written = False
        self.nsnap = 0              # snapshots in the store
        self.checkpoint_step = None
        self.kept_attrs = {}        # attrs of an empty group the run is written into (ensemble member)
        self.times = []
        # the scene as attrs and input arrays, serialised once per run
        self.scene_json, self.inputs = scene_to_json(scene)
        self.digest = checkpoint.scene_digest(self.scene_json, self.inputs)
        self.x1 = grid.x1[self.s1]
        self.x3 = grid.x3[self.s3]

    def __call__(self, state):
        thr = self.scene.numerics.rupture_threshold
        speed = np.sqrt(sum(v**2 for v in state.v.values()))
        new = np.isnan(self.rupture) & (speed > thr)
        self.rupture[new] = state.t
        faces = {}
        for j, (i, k) in enumerate(self.nodes.values()):
            for f in self.station_fields:
                self.series[f][state.n, j] = _field(state, f, faces)[i, k]
        i = int(np.searchsorted(self.steps, state.n))
        if i < self.steps.size and self.steps[i] == state.n:
            self.pending.append((state.t, {f: np.array(_field(state, f, faces)[self.s1, self.s3])
                                           for f in self.scene.record.fields}))
            if self.store is not None and len(self.pending) >= self.flush_every:
                self.flush()

    def _snapshot_ds(self, items):
        t = np.array([it[0] for it in items])
        ds = xr.Dataset(coords=self._coords(t))
        for f in self.scene.record.fields:
            ds[f] = (("t", "x1", "x3"), np.stack([it[1][f] for it in items]), field_attrs(self.scene, f))
        return ds

    def _coords(self, t):
        u = self.scene.units
        return {
            "t": ("t", t if t is not None else np.zeros(0), {"units": u["time"], "long_name": "time", "axis": "T",
                                                              **({"standard_name": "time"} if u["time"] != "1" else {})}),
            "x1": ("x1", self.x1, {"units": u["length"], "long_name": "distance along x1", "axis": "X"}),
            "x3": ("x3", self.x3, {"units": u["length"], "long_name": "distance along x3", "axis": "Y"}),
        }

    def _store_op(self, doing, fn, *args, **kwargs):
        """Run a write to the store; an OSError, or a store at a URL that cannot be reached
        (``objectstore.unreachable``), becomes one StoreError."""
        try:
            return fn(*args, **kwargs)
        except Exception as exc:
            from .objectstore import unreachable

            err = unreachable(self.path if self.path is not None else self.store, exc, doing)
            if err is None and not isinstance(exc, OSError):
                raise
            err = err or checkpoint.store_error(self.path or self.store, exc, doing)
            if self.checkpoint_step is not None:
                err.args = (f"{err.args[0]}; the store keeps the run up to its checkpoint after step "
                            f"{self.checkpoint_step}: fix the cause, then resume (cracklab run --resume)",)
            raise err from None

    def snapshot_times(self):
        """Times of all the snapshots of the run (as the stepper computes them)."""
        return self.steps * self.scene.dt

    def create(self):
        """Create the store at its final size: coordinates (all snapshot times), snapshot
        variables (NaN until written: shapes never change during the run, so a killed
        store always opens), scene inputs and attrs."""
        import dask.array as da

        t_all = self.snapshot_times()
        ds = xr.Dataset(coords=self._coords(t_all))
        n1, n3 = self.x1.size, self.x3.size
        ct = snapshots_per_chunk(n1, n3, self.flush_every)   # <= 8 MB chunks
        for f in self.scene.record.fields:
            ds[f] = (("t", "x1", "x3"), da.full((t_all.size, n1, n3), np.nan, chunks=(ct, n1, n3)),
                     field_attrs(self.scene, f))
        for name, arr in self.inputs.items():
            ds[name] = (("input_x1", "input_x3"), np.asarray(arr), input_attrs(self.scene, name))
        ds.attrs = self.global_attrs("running")
        if self.path is not None:
            # the group and its attrs first: a kill while creating leaves a store that
            # is recognisably a cracklab run (a resume starts it over)
            import zarr

            def fresh():
                zarr.open_group(self.store, mode="w").update_attributes(ds.attrs)
                ds.to_zarr(self.store, mode="a", consolidated=False, compute=False, write_empty_chunks=True,
                           encoding=checkpoint.encoding(ds))

            self._store_op("creating the store", fresh)
        else:
            self._store_op("creating the store", ds.to_zarr, self.store, mode="w", consolidated=False,
                           compute=False, write_empty_chunks=True, encoding=checkpoint.encoding(ds))
        self.written = True

    def flush(self):
        if not self.pending:
            return
        ds = self._snapshot_ds(self.pending)
        if self.store is not None:
            i0, i1 = self.nsnap, self.nsnap + len(self.pending)
            self._store_op(f"writing the snapshots up to t = {self.pending[-1][0]:g}", ds.drop_vars(["x1", "x3"]).to_zarr,
                           self.store, region={"t": slice(i0, i1)}, consolidated=False, write_empty_chunks=True)
            self.nsnap = i1
        else:
            self.times.append(ds)
        self.pending = []

    def global_attrs(self, status=None):
        out = {"Conventions": "CF-1.10", "title": f"cracklab run: {self.scene.name}",
               "source": f"cracklab {__version__}", "cracklab_version": __version__,
               "scene": self.scene_json}
        if self.store is not None:
            out = {**self.kept_attrs, **out}
            out.update({"cracklab_run_format": checkpoint.RUN_FORMAT, "cracklab_scene_digest": self.digest,
                        "cracklab_final_arrays": self.final_arrays, "cracklab_status": status or "running"})
            if self.checkpoint_step is not None and status == "running":
                out["cracklab_checkpoint_step"] = self.checkpoint_step
        return out

    # -- checkpoints ---------------------------------------------------------------
    def checkpoint(self, stepper, n):
        """Flush the snapshots, then write the checkpoint after step ``n``; seconds taken."""
        import time

        t0 = time.perf_counter()
        self.flush()
        state = {"cracklab_version": __version__, "digest": self.digest, "n": n, "nsnap": self.nsnap,
                 "stepper": stepper.get_state(), "rupture": self.rupture,
                 "series": {f: self.series[f][:n + 1] for f in self.station_fields}}
        self._store_op(f"writing the checkpoint after step {n}", checkpoint.write, self.path, state)
        self.checkpoint_step = n
        try:  # informational: the snapshots up to this step match the checkpoint; one
            # metadata write for both (zarr's attrs.update writes one key at a time, and a
            # kill between the two left the new step with the previous snapshot count)
            import zarr

            zarr.open_group(self.store, mode="a").update_attributes(
                {"cracklab_checkpoint_step": n, "cracklab_checkpoint_snapshots": self.nsnap})
        except OSError as exc:
            raise checkpoint.store_error(self.path, exc, f"recording the checkpoint after step {n}") from None
        return time.perf_counter() - t0

    def restore(self, ck):
        """Continue from checkpoint ``ck``: mark the store running (before anything of it
        is removed), cut it back to the checkpoint, restore the series."""
        import zarr

        self._store_op("preparing the store to resume",
                       lambda: zarr.open_group(self.store, mode="a").update_attributes({"cracklab_status": "running"}))
        self._store_op("preparing the store to resume", checkpoint.prepare_resume, self.path, self.snapshot_times())
        self.written = True
        self.nsnap = int(ck["nsnap"])
        self.checkpoint_step = int(ck["n"])
        for f in self.station_fields:
            rows = np.asarray(ck["series"][f])
            self.series[f][:rows.shape[0]] = rows
        self.rupture[...] = ck["rupture"]

    def finish(self, last_n, error=None):
        self.flush()
        scene = self.scene
        t_all = np.arange(last_n + 1) * scene.dt
        extra = xr.Dataset(coords={k: v for k, v in self._coords(None).items() if k != "t"})
        extra["rupture_time"] = (("x1", "x3"), self.rupture[self.s1, self.s3],
                                 {"long_name": "first time the point failed", "units": scene.units["time"]})
        if self.nodes:
            extra = extra.assign_coords(
                station=("station", np.array(list(self.nodes), dtype=object), {"long_name": "station name"}),
                station_x1=("station", [scene.grid.x1[i] for i, _ in self.nodes.values()],
                            {"units": scene.units["length"], "long_name": "station x1"}),
                station_x3=("station", [scene.grid.x3[k] for _, k in self.nodes.values()],
                            {"units": scene.units["length"], "long_name": "station x3"}),
                t_station=("t_station", t_all, {"units": scene.units["time"], "long_name": "time"}))
            for f in self.station_fields:
                extra[f"station_{f}"] = (("station", "t_station"), self.series[f][:last_n + 1].T,
                                         field_attrs(scene, f))
        if self.store is not None:
            if not self.written:
                self.create()
            if self.nsnap < len(self.steps):     # a failed run: keep what was recorded
                self._store_op("cutting the snapshots to those recorded", checkpoint.cut_snapshots,
                               self.store, self.nsnap)
            import zarr

            group = zarr.open_group(self.store, mode="a")
            extra.attrs = dict(group.attrs)       # as they are: the status comes last, below
            self._store_op("writing the station series and rupture times", extra.to_zarr, self.store,
                           mode="a", consolidated=False, write_empty_chunks=True,
                           encoding=checkpoint.encoding(extra, skip=group.array_keys()))
            final = self.global_attrs("failed" if error else "complete")
            if error:
                final["cracklab_error"] = str(error)
            # last: a kill or a full disk before this leaves a store that is not complete
            self._store_op("marking the store complete" if not error else "marking the store failed",
                           group.attrs.put, final)
            if self.path is not None:
                checkpoint.remove(self.path)
            # then its consolidated metadata, where xarray.open_zarr looks first (no warning):
            # of what is there, the checkpoint gone
            self._store_op("consolidating the store's metadata", _consolidate, self.store)
            return xr.open_zarr(self.store, consolidated=False)
        for name, arr in self.inputs.items():
            extra[name] = (("input_x1", "input_x3"), np.asarray(arr), input_attrs(scene, name))
        parts = self.times or [xr.Dataset(coords={"t": self._coords(None)["t"]})]
        ds = xr.concat(parts, dim="t") if len(parts) > 1 else parts[0]
        ds = xr.merge([ds, extra], combine_attrs="override")
        ds.attrs = self.global_attrs()
        return ds


def _consolidate(store):
    """The consolidated metadata of a finished run's group (zarr's warning that Zarr v3 does
    not standardise it yet silenced)."""
    import zarr

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        zarr.consolidate_metadata(store)


def _consolidated(path) -> bool:
    """Whether the run store at ``path`` (a directory, or ``Store.tree()``) has consolidated metadata."""
    from .verify import read_json

    doc, _ = read_json(path / "zarr.json")
    return isinstance((doc or {}).get("consolidated_metadata"), dict)


@contextlib.contextmanager
def _deferred_interrupt(enabled):
    """While a run into a store steps in the main thread, Ctrl-C (SIGINT) only sets a flag
    that the loop reads between two steps (a second Ctrl-C interrupts at once); yields the
    flag, a dict {"hit": bool}."""
    import signal
    import threading

    flag = {"hit": False}
    if not enabled or threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield flag
        return

    def handler(signum, frame):
        if flag["hit"]:
            raise KeyboardInterrupt
        flag["hit"] = True

    old = signal.signal(signal.SIGINT, handler)
    try:
        yield flag
    finally:
        signal.signal(signal.SIGINT, old)


def simulate(scene, *, progress=False, store=None, checkpoint_every=None, resume=False, check_memory=True,
             check_disk=True):
    """Run ``scene``; return a Dataset indexed by (t, x1, x3) with the recorded fields,
    ``rupture_time`` and, with stations, series over ``t_station``. A scene with ``sequence``
    set runs with an adaptive step (``cracklab.output.sequence.run_sequence``: its output
    has the event catalogue instead of ``rupture_time``; ``resume`` and
    ``checkpoint_every`` as here, no memory or disk refusal: its steps are its own). With ``store`` the
    snapshots stream to that Zarr store during the run and the result is read back lazily.
    On a blow-up, what was recorded is kept (flushed to the store) and SimulationError raised.

    A run into a store path or URL checkpoints its full state into the store (docs/guide/reliability.md):
    ``checkpoint_every`` N steps, or ``"60s"`` of wall time (default: every 60 s, at most 10 %
    of the run time), ``0`` never. ``resume=True`` continues a killed run from its last
    checkpoint (same results, bit for bit); with no checkpoint the run starts over, and a
    complete store is returned as is once every chunk of it has been read and checked
    (``cracklab.output.verify``). A damaged store is not served: a complete one, or one damaged
    before its checkpoint, is run again from the start (with a ``StoreWarning`` naming
    the damaged files). Store problems raise StoreError; a store given as a URL is checked
    before any step (``Store.check``: its scheme, credentials and bucket).

    ``check_memory``: estimate the run's memory first (``cracklab.solver.budget``) and raise
    ``MemoryBudgetError`` before any step when it exceeds the memory available.
    ``check_disk``: for a store on a local path, bound the bytes the run writes
    (``cracklab.output.disk``) and raise ``DiskBudgetError`` before any step when the
    store's file system cannot hold them. Ctrl-C
    during a run into a store path or URL stops it after the step in progress, writes a
    checkpoint there and raises ``Interrupted`` (its ``step``): a resume continues from it.
    """
    import os

    from .stores import store_for

    # the kind of storage, from the path or URL; a URL's scheme, credentials and bucket
    # are checked before any step
    target = store_for(store) if isinstance(store, (str, os.PathLike)) else None
    if target is not None:
        target.check()
    if scene.sequence is not None:      # a sequence of earthquakes: the adaptive step (output/sequence.py)
        from .sequence import run_sequence

        return run_sequence(scene, progress=progress, store=store, resume=resume,
                            checkpoint_every=checkpoint_every)
    every_n, every_s = checkpoint_policy(checkpoint_every)
    adaptive = checkpoint_every is None     # the default: keep checkpoints under 10 % of the time
    # where checkpoints go: a local store's directory, or the Store itself (a URL)
    path = None if target is None or not target.checkpoints else target.path if target.local else target
    if resume and path is None:
        raise InputError("resume", "needs a store to resume from (a local Zarr directory or a URL)")
    if check_memory:
        from ..solver.budget import check_memory as fits, run_memory

        fits(run_memory(scene, store=store is not None), what=f"the run of {scene.name!r}",
             hint="make the grid coarser or the run shorter, or run it anyway with check_memory=False "
                  "(cracklab run --no-memory-check)")
    if check_disk and target is not None and target.local:
        holds(output_size(scene), path, what=f"the run of {scene.name!r}",
              hint="record fewer fields, less often (record.every, record.times) or on a region "
                   "(record.region), or write to a larger disk; or run it anyway with check_disk=False "
                   "(cracklab run --no-disk-check)")
    rec = Recorder(scene, target.zarr_store() if target is not None else store, path)
    start, last = None, -1
    if path is not None:
        if resume:
            attrs, ck = checkpoint.check_resumable(path, __version__)
            if attrs.get("cracklab_scene_digest", rec.digest) != rec.digest or \
                    (ck is not None and ck["digest"] != rec.digest):
                raise StoreError(path, "holds a run of a different scene; run without resume to overwrite it "
                                       "or choose another path")
            from . import verify

            if attrs.get("cracklab_status") == "complete":
                report = verify.check_run(target.tree())
                if report.ok:
                    if ck is not None or not _consolidated(target.tree()):  # killed after the status, before
                        checkpoint.remove(path)                      # the clean-up and the consolidated metadata
                        _consolidate(str(path) if target.local else rec.store)
                    return xr.open_zarr(store if target.local else rec.store, consolidated=False)
                verify.warn_damaged(path, report, "the run is done again from the start")
                ck = None
            elif ck is not None:
                report = verify.check_run(target.tree(), snapshots=int(ck["nsnap"]), final=False)
                if not report.ok:
                    verify.warn_damaged(path, report, f"its checkpoint after step {int(ck['n'])} cannot be resumed "
                                                      f"from: the run is done again from the start")
                    ck = None
            if ck is not None:
                rec.restore(ck)
                start, last = ck["stepper"], int(ck["n"])
        else:
            checkpoint.check_writable_target(path)
        kind, attrs = checkpoint.inspect(path)
        if kind == "empty" and not rec.written:
            rec.kept_attrs = attrs
    with _deferred_interrupt(path is not None) as interrupt:
        return _run(scene, rec, store, path, start, last, progress, every_n, every_s, adaptive, interrupt)


def _run(scene, rec, store, path, start, last, progress, every_n, every_s, adaptive, interrupt):
    """The loop of ``simulate``: create the store, step, record, checkpoint."""
    import time

    if store is not None and not rec.written:
        rec.create()
    try:
        stepper = Stepper(scene, start=start)
    except (ValueError, KeyError, TypeError) as exc:
        if start is None:
            raise
        raise StoreError(path, f"its checkpoint does not fit this run ({exc}); run again without resume") from None
    iterator = iter(stepper)
    if progress:
        from tqdm.auto import tqdm

        iterator = tqdm(iterator, total=scene.nsteps + 1, initial=last + 1, desc=scene.name, unit="step")
    do_ckpt = path is not None and (every_n or every_s)
    t_ckpt, cost, n_ckpt = time.monotonic(), 0.0, last
    try:
        for state in iterator:
            rec(state)
            last = state.n
            if interrupt["hit"] and last < scene.nsteps:
                rec.checkpoint(stepper, last)
                raise Interrupted(last, path)
            if do_ckpt and last < scene.nsteps:
                if every_n:
                    due = last > max(n_ckpt, 0) and last % every_n == 0
                else:
                    due = time.monotonic() - t_ckpt >= (max(every_s, 10.0 * cost) if adaptive else every_s)
                if due:
                    cost = rec.checkpoint(stepper, last)
                    t_ckpt, n_ckpt = time.monotonic(), last
    except SimulationError as exc:
        exc.partial = rec.finish(max(last, 0), error=exc)
        raise
    return rec.finish(last)


def _station_order(name: str):
    """The order of a station Dataset's variables, as the recorder makes them: slip, rate,
    traction (by component), the strength, then the faces' fields (a store lists its
    arrays in no fixed order)."""
    kind, _, rest = name[len("station_"):].partition("_")
    rank = {"delta": 0, "v": 1, "tau": 2, "strength": 3}.get(kind, 4)
    return (rank, 0 if rest.isdigit() else 1, rest)


def stations(result) -> xr.Dataset:
    """Station series of a run: dims (station, t), variables named as the grid fields."""
    names = sorted((v for v in result.data_vars if v.startswith("station_")), key=_station_order)
    if not names:
        raise ValueError("this result has no stations; give record=Record(stations={...})")
    ds = result[names].rename({n: n[len("station_"):] for n in names})
    ds = ds.rename({"t_station": "t"})
    return ds.set_coords([c for c in ("station_x1", "station_x3") if c in ds]).rename(
        {"station_x1": "x1", "station_x3": "x3"})


def scene_of_store(path):
    """The scene of the run store at ``path`` (a local directory) from its attrs and input
    arrays alone, read past the rest of the store (an array whose metadata was changed
    by hand, which xarray refuses to open); refused when it is not the scene the run
    recorded (attr ``cracklab_scene_digest``)."""
    import os
    from pathlib import Path

    from ..model.scene_io import read_scene_json
    from .verify import read_json, stored_inputs

    p = Path(path)
    doc, why = read_json(p / "zarr.json")
    if doc is None:
        raise InputError(str(path), f"cannot open as a scene TOML or a cracklab Zarr store: its zarr.json is {why}")
    attrs = doc.get("attributes") or {}
    if "scene" not in attrs:
        raise InputError(str(path), "is a Zarr store but not a cracklab run (no 'scene' attribute)")
    fmt = attrs.get("cracklab_run_format", checkpoint.RUN_FORMAT)
    if not isinstance(fmt, int) or fmt > checkpoint.RUN_FORMAT:
        raise InputError(str(path), f"was written by cracklab {attrs.get('cracklab_version', '?')} in store format "
                                    f"{fmt!r}; this cracklab reads formats up to {checkpoint.RUN_FORMAT}")
    data = read_scene_json(attrs["scene"])
    names = sorted(e.name for e in os.scandir(p) if e.is_dir() and e.name.startswith("input_"))
    arrays = stored_inputs(p, names)
    if arrays is None:
        raise StoreError(p, "its scene's input arrays cannot be read (cracklab verify names the damaged files); "
                            "give the scene file (SCENE.toml) instead")
    digest = attrs.get("cracklab_scene_digest")
    if isinstance(digest, str) and checkpoint.scene_digest(attrs["scene"], arrays) != digest:
        raise StoreError(p, "its scene does not match the digest cracklab_scene_digest written with the run (changed "
                            "after the run); give the scene file: cracklab run SCENE.toml -o STORE --resume")
    return scene_from_data(data, arrays)


def scene_of(result):
    """The scene that produced ``result`` (from its attrs and input variables)."""
    from ..model.scene_io import read_scene_json

    if "scene" not in result.attrs:
        raise InputError("scene", "this Dataset holds no 'scene' attribute: it is not the output of a cracklab run")
    data = read_scene_json(result.attrs["scene"])
    arrays = {n: np.asarray(result[n].values) for n in result.data_vars if n.startswith("input_")}
    return scene_from_data(data, arrays)
