"""Runs of the TPV101/TPV103 study (studies/tpv101/run.py): the scenes, their Zarr stores
and the wall-time records next to them. A store that holds a finished run of the same
scene is reused; a killed run resumes from its last checkpoint."""
from __future__ import annotations

import json
import platform
import shutil
import time
from pathlib import Path

DEFAULT_DOMAIN = (72000.0, 36000.0)


def build_scene(problem, dx, t_end=None, domain=None):
    """``scenes.<problem>`` (tpv101 or tpv103) at ``dx`` with its stations, the rupture
    time of the whole plane and the slip field at the end."""
    from cracklab import scenes
    from cracklab.model.record import Record

    builder = getattr(scenes, problem)
    kw = {} if t_end is None else {"t_end": float(t_end)}
    if domain is not None:
        kw["domain"] = tuple(float(x) for x in domain)
    base = builder(dx=float(dx), **kw)
    rec = Record(fields=("delta_1",), times=(base.nsteps * base.dt,), stations=dict(base.record.stations))
    return base.replace(record=rec)


def tag(problem, dx, domain=None):
    d = "" if domain is None or tuple(domain) == DEFAULT_DOMAIN else \
        f"_{domain[0] / 1e3:g}x{domain[1] / 1e3:g}km"
    return f"{problem}_dx{dx:g}{d}"


def store_path(out, problem, dx, domain=None):
    return Path(out) / f"{tag(problem, dx, domain)}.zarr"


def complete(store, scene):
    """The store holds a finished run of this very scene (and its wall-time record)."""
    import xarray as xr

    from cracklab.output.simulate import scene_of

    if not Path(store).exists() or not Path(store).with_suffix(".json").exists():
        return False
    try:
        ds = xr.open_zarr(store, consolidated=False)
        return ds.attrs.get("cracklab_status") == "complete" and "rupture_time" in ds and \
            scene_of(ds).to_toml() == scene.to_toml()
    except Exception:
        return False


def run_one(problem, dx, out, *, t_end=None, domain=None, force=False, log=print, progress=True):
    """Run (or reuse, or resume) one grid spacing; return its metadata dict."""
    import cracklab
    from cracklab.output.simulate import simulate

    scene = build_scene(problem, dx, t_end, domain)
    store = store_path(out, problem, dx, domain)
    meta_path = store.with_suffix(".json")
    if not force and complete(store, scene):
        meta = json.loads(meta_path.read_text())
        log(f"{problem} {dx:g} m: reusing {store} (ran in {meta['wall_s']:.0f} s)")
        return meta
    resume = store.exists() and not force
    if force and store.exists():
        shutil.rmtree(store)
    meta_path.unlink(missing_ok=True)
    g = scene.grid
    log(f"{problem} {dx:g} m: grid {g.n1} x {g.n3} ({g.L1 / 1e3:g} km x {g.L3 / 1e3:g} km), beta = "
        f"{scene.beta:.4f}, dt = {scene.dt:.3e} s, {scene.nsteps} steps to t = {scene.nsteps * scene.dt:g} s "
        f"-> {store}{' (resuming)' if resume else ''}")
    t0 = time.time()
    try:
        simulate(scene, store=str(store), progress=progress, resume=resume)
    except Exception:
        if not resume:
            raise
        shutil.rmtree(store)                     # a store this run cannot resume: start over
        simulate(scene, store=str(store), progress=progress)
    wall = time.time() - t0
    meta = {"problem": problem, "dx": float(dx), "t_end": scene.nsteps * scene.dt, "n1": g.n1, "n3": g.n3,
            "domain": [g.L1, g.L3], "beta": scene.beta, "dt": scene.dt, "nsteps": scene.nsteps, "wall_s": wall,
            "s_per_step": wall / scene.nsteps, "resumed": resume, "formulation": scene.formulation,
            "engine": scene.numerics.engine, "cracklab_version": cracklab.__version__, "host": platform.node()}
    meta_path.write_text(json.dumps(meta, indent=1))
    log(f"{problem} {dx:g} m: done in {wall:.0f} s ({1e3 * wall / scene.nsteps:.1f} ms/step)")
    return meta


def load_run(out, problem, dx, domain=None):
    """(Dataset, scene, station Dataset, metadata) of a finished run."""
    import xarray as xr

    from cracklab.output.simulate import scene_of, stations

    store = store_path(out, problem, dx, domain)
    ds = xr.open_zarr(store, consolidated=False)
    meta = json.loads(store.with_suffix(".json").read_text())
    return ds, scene_of(ds), stations(ds).load(), meta
