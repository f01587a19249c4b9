"""Run a scene and return (or stream to Zarr) a labelled xarray Dataset."""
from __future__ import annotations

import json

import numpy as np
import xarray as xr

from . import __version__
from .errors import SimulationError
from .io import scene_from_data, scene_to_json
from .stepper import steps

LONG_NAMES = {
    "delta_1": ("slip along x1", "length"), "delta_2": ("opening", "length"),
    "delta_3": ("slip along x3", "length"), "v_1": ("slip rate along x1", "velocity"),
    "v_2": ("opening rate", "velocity"), "v_3": ("slip rate along x3", "velocity"),
    "tau_1": ("shear traction along x1", "stress"), "tau_2": ("normal traction (tension positive)", "stress"),
    "tau_3": ("shear traction along x3", "stress"), "strength": ("strength of the interface", "stress"),
}


def _units(scene, kind):
    u = scene.units
    if kind == "velocity":
        return "1" if u["length"] == "1" and u["time"] == "1" else f"{u['length']} {u['time']}-1"
    return u[kind]


def _attrs(scene, name):
    long_name, kind = LONG_NAMES[name]
    return {"long_name": long_name, "units": _units(scene, kind)}


INPUT_KINDS = {"tau0_1": "stress", "tau0_2": "stress", "tau0_3": "stress", "tau_c": "stress",
               "sigma_n": "stress", "residual": "stress", "strength_before": "stress",
               "delta_c": "length", "D_c": "length"}


def _input_attrs(scene, name):
    """Attrs of a scene input field stored as ``input_<section>_<key>``."""
    section, key = name[len("input_"):].split("_", 1)
    kind = INPUT_KINDS.get(key)
    return {"long_name": f"scene input {section}.{key}", "units": scene.units[kind] if kind else "1"}


def _field(state, name):
    if name == "strength":
        return state.strength
    kind, c = name.split("_")
    return {"delta": state.delta, "v": state.v, "tau": state.tau}[kind][int(c)]


class _Recorder:
    """Collects snapshots, station series and rupture times; streams to Zarr if asked."""

    def __init__(self, scene, store, flush_every=8):
        self.scene, self.store, self.flush_every = scene, store, flush_every
        grid = scene.grid
        self.steps = set(int(s) for s in scene.record.snapshot_steps(scene.nsteps, scene.dt)) \
            if scene.record.fields else set()
        self.s1, self.s3 = scene.record.region_slices(grid)
        self.nodes = scene.record.station_nodes(grid)
        comps = scene.components
        self.station_fields = [f"{k}_{c}" for k in ("delta", "v", "tau") for c in comps] + ["strength"]
        self.series = {f: np.full((scene.nsteps + 1, len(self.nodes)), np.nan) for f in self.station_fields}
        self.rupture = np.full(grid.shape, np.nan)
        self.pending = []
        self.written = False
        self.times = []
        # the scene as attrs and input arrays, serialised once per run
        self.scene_json, self.inputs = scene_to_json(scene)
        self.x1 = grid.x1[self.s1]
        self.x3 = grid.x3[self.s3]

    def __call__(self, state):
        thr = self.scene.numerics.rupture_threshold
        speed = np.sqrt(sum(v**2 for v in state.v.values()))
        new = np.isnan(self.rupture) & (speed > thr)
        self.rupture[new] = state.t
        for j, (i, k) in enumerate(self.nodes.values()):
            for f in self.station_fields:
                self.series[f][state.n, j] = _field(state, f)[i, k]
        if state.n in self.steps:
            self.pending.append((state.t, {f: np.array(_field(state, f)[self.s1, self.s3])
                                           for f in self.scene.record.fields}))
            if self.store is not None and len(self.pending) >= self.flush_every:
                self.flush()

    def _snapshot_ds(self, items):
        t = np.array([it[0] for it in items])
        ds = xr.Dataset(coords=self._coords(t))
        for f in self.scene.record.fields:
            ds[f] = (("t", "x1", "x3"), np.stack([it[1][f] for it in items]), _attrs(self.scene, f))
        return ds

    def _coords(self, t):
        u = self.scene.units
        return {
            "t": ("t", t if t is not None else np.zeros(0), {"units": u["time"], "long_name": "time", "axis": "T", "standard_name": "time"}),
            "x1": ("x1", self.x1, {"units": u["length"], "long_name": "distance along x1", "axis": "X"}),
            "x3": ("x3", self.x3, {"units": u["length"], "long_name": "distance along x3", "axis": "Y"}),
        }

    def flush(self):
        if not self.pending:
            return
        ds = self._snapshot_ds(self.pending)
        if self.store is not None:
            if not self.written:
                ds.attrs.update(self.global_attrs())
                ds.to_zarr(self.store, mode="w", consolidated=False)
                self.written = True
            else:
                ds.to_zarr(self.store, append_dim="t", consolidated=False)
        else:
            self.times.append(ds)
        self.pending = []

    def global_attrs(self):
        return {"Conventions": "CF-1.10", "title": f"cracklab run: {self.scene.name}",
                "source": f"cracklab {__version__}", "cracklab_version": __version__,
                "scene": self.scene_json}

    def finish(self, last_n):
        self.flush()
        scene = self.scene
        t_all = np.arange(last_n + 1) * scene.dt
        extra = xr.Dataset(coords={k: v for k, v in self._coords(None).items() if k != "t"})
        extra["rupture_time"] = (("x1", "x3"), self.rupture[self.s1, self.s3],
                                 {"long_name": "first time the point failed", "units": scene.units["time"]})
        if self.nodes:
            extra = extra.assign_coords(
                station=("station", np.array(list(self.nodes), dtype=object)),
                station_x1=("station", [scene.grid.x1[i] for i, _ in self.nodes.values()],
                            {"units": scene.units["length"], "long_name": "station x1"}),
                station_x3=("station", [scene.grid.x3[k] for _, k in self.nodes.values()],
                            {"units": scene.units["length"], "long_name": "station x3"}),
                t_station=("t_station", t_all, {"units": scene.units["time"], "long_name": "time"}))
            for f in self.station_fields:
                extra[f"station_{f}"] = (("station", "t_station"), self.series[f][:last_n + 1].T, _attrs(scene, f))
        for name, arr in self.inputs.items():
            extra[name] = (("input_x1", "input_x3"), np.asarray(arr), _input_attrs(scene, name))
        extra.attrs = self.global_attrs()
        if self.store is not None:
            if not self.written:
                xr.Dataset(coords={"t": self._coords(None)["t"]}, attrs=self.global_attrs()).to_zarr(
                    self.store, mode="w", consolidated=False)
            extra.to_zarr(self.store, mode="a", consolidated=False)
            return xr.open_zarr(self.store, consolidated=False)
        parts = self.times or [xr.Dataset(coords={"t": self._coords(None)["t"]})]
        ds = xr.concat(parts, dim="t") if len(parts) > 1 else parts[0]
        ds = xr.merge([ds, extra], combine_attrs="override")
        ds.attrs = self.global_attrs()
        return ds


def simulate(scene, *, progress=False, store=None):
    """Run ``scene``; return a Dataset indexed by (t, x1, x3) with the recorded fields,
    ``rupture_time`` and, with stations, series over ``t_station``. With ``store`` the
    snapshots stream to that Zarr store during the run and the result is read back lazily.
    On a blow-up, what was recorded is kept (flushed to the store) and SimulationError raised.
    """
    rec = _Recorder(scene, store)
    iterator = steps(scene)
    if progress:
        from tqdm.auto import tqdm

        iterator = tqdm(iterator, total=scene.nsteps + 1, desc=scene.name, unit="step")
    last = -1
    try:
        for state in iterator:
            rec(state)
            last = state.n
    except SimulationError as exc:
        exc.partial = rec.finish(max(last, 0))
        raise
    return rec.finish(last)


def stations(result) -> xr.Dataset:
    """Station series of a run: dims (station, t), variables named as the grid fields."""
    names = [v for v in result.data_vars if v.startswith("station_")]
    if not names:
        raise ValueError("this result has no stations; give record=Record(stations={...})")
    ds = result[names].rename({n: n[len("station_"):] for n in names})
    ds = ds.rename({"t_station": "t"})
    return ds.set_coords([c for c in ("station_x1", "station_x3") if c in ds]).rename(
        {"station_x1": "x1", "station_x3": "x3"})


def scene_of(result):
    """The scene that produced ``result`` (from its attrs and input variables)."""
    data = json.loads(result.attrs["scene"])
    arrays = {n: np.asarray(result[n].values) for n in result.data_vars if n.startswith("input_")}
    return scene_from_data(data, arrays)
