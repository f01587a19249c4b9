"""The main job of the quick start (``cracklab demo``, ``python3 bootstrap.py demo``).

1. The asperity ensemble of studies/asperity_ensemble/study.toml (asperity diameter x
   toughness contrast on a 128 x 64 grid, plus one random-toughness member), run on an
   embedded dask LocalCluster (or ``scheduler``) into OUT/ensemble.zarr, then the summary
   figures OUT/ensemble_crack_length.png, OUT/ensemble_rupture.png and the animation
   OUT/ensemble_random.gif.
2. Lamb's problem verified against Pekeris (1955): OUT/lamb.zarr and OUT/lamb.png.
"""
from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

STUDY = Path(__file__).resolve().parents[2] / "studies" / "asperity_ensemble" / "study.toml"


def _say(msg):
    print(f"cracklab demo: {msg}", flush=True)


def lamb_demo(out="out", n=128, progress=None):
    """Lamb's problem against Pekeris: OUT/lamb.zarr and OUT/lamb.png."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..analysis.exact import lamb_arrivals, lamb_opening
    from ..model.record import Record
    from ..scenes import lamb
    from ..output.simulate import simulate, stations

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if progress is None:
        progress = os.isatty(2)
    r_cells = n // 4
    grid_dx = 1.0 / n
    r = r_cells * grid_dx
    t_end = 1.7 * r  # before the periodic image's P wave reaches the station
    station = {"r": (0.5 + r, 0.5)}
    scene = lamb(n=n, t_end=t_end, record=Record(fields=("delta_2",), every=10, stations=station))
    store = out / "lamb.zarr"
    ds = simulate(scene, progress=progress, store=str(store))
    st = stations(ds).sel(station="r")
    tau = st.t.values / r
    exact = lamb_opening(r, st.t.values)
    static = lamb_opening(r, np.array([10.0 * r]))[0]
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.5))
    snap = ds.delta_2.isel(t=-1)
    snap.plot(ax=ax0, x="x1", y="x3", robust=True, cmap="RdBu_r")
    ax0.set_aspect("equal")
    ax0.set_title(f"opening at t = {float(snap.t):.3f}")
    ax1.plot(tau, st.delta_2 / static, label="cracklab")
    ax1.plot(tau, exact / static, "k--", label="Pekeris (1955)")
    for name, ta in zip("PSR", lamb_arrivals()):
        ax1.axvline(ta, color="0.7", lw=0.8)
        ax1.text(ta, 1.3, name)
    ax1.set_xlabel(r"$\tau = c_s t / r$")
    ax1.set_ylabel("opening / static value")
    ax1.set_ylim(-1.5, 1.5)
    ax1.legend()
    ax1.set_title(f"opening {r_cells} cells from the load")
    fig.tight_layout()
    fig.savefig(out / "lamb.png", dpi=120)
    plt.close(fig)
    late = tau > 1.35
    err = float(np.max(np.abs(st.delta_2.values[late] - static)) / static) if late.any() else float("nan")
    _say(f"wrote {store} and {out / 'lamb.png'}; late-time opening within {100 * err:.1f}% "
         f"of the static value (Pekeris)")
    return ds


def ensemble_demo(out="out", *, study=STUDY, scheduler=None, workers=None, progress=None) -> bool:
    """Run ``study`` into OUT/ensemble.zarr and draw its figures; False if a member failed."""
    from .. import plots as P
    from ..ensemble import load_study, open_ensemble, run_study

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if not Path(study).is_file():
        raise FileNotFoundError(f"study file {study} not found (the demo runs from a source checkout)")
    spec = load_study(study)
    store = out / "ensemble.zarr"
    t0 = time.perf_counter()
    where = scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS") or \
        f"a local cluster of {workers or 'one worker per core'}"
    _say(f"study {spec.name!r} ({Path(study).name}) on {where} -> {store}")
    result = run_study(spec, store, scheduler=scheduler, workers=workers, progress=progress)
    _say(result.summary())
    if result.skipped:
        _say(f"({len(result.skipped)} members were already complete in {store}: delete it to recompute)")
    ens = open_ensemble(store, members=result.members).load()
    if ens.sizes["member"] == 0:
        return False
    paths = [out / "ensemble_crack_length.png", out / "ensemble_rupture.png"]
    P.ensemble_summary(ens, by="contrast", x="diameter", path=paths[0],
                       title=f"{spec.name}: {P.plural(ens.sizes['member'], 'member')}")
    P.ensemble_panels(ens, path=paths[1], title="rupture-time contours over tau_c (black: failed region)")
    random = [i for i, name in enumerate(ens.scene_name.values) if name == "random_toughness"]
    if random:
        paths.append(out / "ensemble_random.gif")
        P.animate(ens, paths[-1], "delta_2", member=random[0])
    _say(f"figures ({time.perf_counter() - t0:.0f} s for the ensemble): " + ", ".join(map(str, paths)))
    return result.ok


def main(out="out", n=128, progress=None, scheduler=None, workers=None, lamb=True):
    """Both parts; returns False when an ensemble member failed."""
    t0 = time.perf_counter()
    ok = ensemble_demo(out, scheduler=scheduler, workers=workers, progress=progress)
    if lamb:
        lamb_demo(out, n=n, progress=progress)
    _say(f"done in {time.perf_counter() - t0:.0f} s; outputs in {Path(out).resolve()}")
    if not ok:
        print("cracklab demo: some ensemble members failed (see above)", file=sys.stderr)
    return ok
