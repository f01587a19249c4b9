"""The main job of the quick start: Lamb's problem, verified against Pekeris, to Zarr + PNG."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np


def main(out="out", n=128, progress=True):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .exact import lamb_arrivals, lamb_opening
    from .record import Record
    from .scenes import lamb
    from .simulate import simulate, stations

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    r_cells = n // 4
    grid_dx = 1.0 / n
    r = r_cells * grid_dx
    t_end = 1.7 * r  # before the periodic image's P wave reaches the station
    station = {"r": (0.5 + r, 0.5)}
    scene = lamb(n=n, t_end=t_end, record=Record(fields=("delta_2",), every=10, stations=station))
    store = out / "lamb.zarr"
    ds = simulate(scene, progress=progress and os.isatty(2), store=str(store))
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
    late = tau > 1.35
    err = float(np.max(np.abs(st.delta_2.values[late] - static)) / static) if late.any() else float("nan")
    print(f"cracklab demo: wrote {store} and {out / 'lamb.png'}; "
          f"late-time opening within {100 * err:.1f}% of the static value")
    return ds
