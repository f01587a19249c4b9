"""The runs of the asperity-front study: the paper's 3D problem (with and without the
asperities) and four cheap plane (n3 = 1) diagnostics of the crack speed."""
from __future__ import annotations

import dataclasses
import json
import shutil
import time
from pathlib import Path

import xarray as xr

from cracklab import Record, scenes, simulate
from cracklab.model.scene import Numerics

NUMERICS = Numerics(engine="exponential")


def scene_3d(asperities: bool, *, n1=512, n3=256, t_end=3.0, every=16):
    """Section 4 at the paper's size: 512 x 256, beta = 0.5, asperity_row defaults
    (the paper's geometry and loading); the opening every ``every`` steps."""
    return scenes.asperity_row(n1=n1, n3=n3, beta=0.5, t_end=t_end, asperities=asperities,
                               numerics=NUMERICS, record=Record(fields=("delta_2",), every=every))


def scene_plane(*, sudden=True, constant_K=True, n1=512, t_end=3.0, ramp_time=4.0, every=8, cohesive_zone=0.1,
                beta=0.5):
    """The uniform problem in the plane (exactly the x3-invariant 3D one): the paper's
    sudden constant-K load, or a slow smooth ramp (``sudden=False``), or a fixed load
    (``constant_K=False``, tau0 kept at its initial value); ``cohesive_zone`` (in Z) and
    ``beta`` as in ``scenes.asperity_row``."""
    sc = scenes.asperity_row(n1=n1, n3=1, beta=beta, t_end=t_end, asperities=False, numerics=NUMERICS,
                             cohesive_zone=cohesive_zone, record=Record(fields=("delta_2",), every=every))
    load = dataclasses.replace(sc.loading, constant_K=constant_K)
    if not sudden:
        load = dataclasses.replace(load, time="smooth", ramp_time=ramp_time)
    return sc.replace(loading=load)


PLANE_CASES = {
    "plane_sudden_constK": dict(sudden=True, constant_K=True, t_end=3.0),
    "plane_ramp_constK": dict(sudden=False, constant_K=True, t_end=7.0),
    "plane_sudden_fixed": dict(sudden=True, constant_K=False, t_end=3.0),
    "plane_ramp_fixed": dict(sudden=False, constant_K=False, t_end=6.0),
}
# the ramped constant-K case with a smaller cohesive zone (the same number of cells in
# it) and with a smaller time step: is the excess over Freund's speed physical or numerical?
ZONE_CASES = {
    "plane_ramp_constK_zone0.05": dict(sudden=False, constant_K=True, t_end=7.0, cohesive_zone=0.05, n1=1024,
                                       every=16),
    "plane_ramp_constK_zone0.025": dict(sudden=False, constant_K=True, t_end=7.0, cohesive_zone=0.025, n1=2048,
                                        every=32),
    "plane_ramp_constK_beta0.125": dict(sudden=False, constant_K=True, t_end=7.0, beta=0.125),
}


def run_one(scene, store: Path, force=False) -> dict:
    """Run ``scene`` into the Zarr ``store`` (skipped when a finished store is there);
    returns {"elapsed_s", "nsteps", "skipped"}. A sidecar ``<store>.json`` marks it done."""
    done = store.with_suffix(".json")
    if done.exists() and store.exists() and not force:
        info = json.loads(done.read_text())
        info["skipped"] = True
        return info
    if store.exists():
        shutil.rmtree(store)
    t0 = time.perf_counter()
    simulate(scene, store=str(store))
    info = {"elapsed_s": round(time.perf_counter() - t0, 2), "nsteps": scene.nsteps,
            "grid": [scene.grid.n1, scene.grid.n3], "dt": scene.dt, "skipped": False}
    done.write_text(json.dumps(info))
    return info


def open_run(store: Path) -> xr.Dataset:
    return xr.open_zarr(str(store), consolidated=False)
