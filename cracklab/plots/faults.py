"""Figures of a fault run: final slip map and station series (slip rate by default)."""
from __future__ import annotations

import numpy as np

from .common import new_axes, finish_figure, plane_image


def station_series(ds, field="v_1", *, stations=None, ax=None, path=None):
    """Series ``station_<field>`` over ``t_station`` of the named ``stations`` (default: all)."""
    name = f"station_{field}"
    if name not in ds:
        have = sorted(v.removeprefix("station_") for v in ds.data_vars if v.startswith("station_") and "t_station" in ds[v].dims)
        raise ValueError(f"--field {field}: no station series of it; recorded: {', '.join(have) or 'none'}")
    known = [str(s) for s in ds["station"].values]
    chosen = list(stations) if stations else known
    unknown = [s for s in chosen if s not in known]
    if unknown:
        raise ValueError(f"--station {unknown[0]}: no such station; choose among: {', '.join(known)}")
    fig, ax = new_axes(ax)
    t = ds["t_station"].values
    for s in chosen:
        ax.plot(t, np.asarray(ds[name].sel(station=s).values), label=s, lw=1.0)
    ax.set_xlabel(f"t ({ds['t_station'].attrs.get('units', '1')})")
    ax.set_ylabel(f"{field} ({ds[name].attrs.get('units', '1')})")
    if len(chosen) <= 16:
        ax.legend(fontsize=6, ncol=2)
    return finish_figure(fig, path)


def final_slip(ds, *, ax=None, path=None):
    """Map of the final slip |(delta_1, delta_3)| (the last snapshot)."""
    parts = [np.asarray(ds[n].isel(t=-1).values, dtype=float) for n in ("delta_1", "delta_3") if n in ds]
    if not parts or ds.sizes.get("t", 0) == 0:
        raise ValueError("no slip recorded (delta_1/delta_3 snapshots)")
    fig, ax = new_axes(ax)
    mesh = plane_image(ax, ds, np.sqrt(sum(p ** 2 for p in parts)), cmap="viridis")
    fig.colorbar(mesh, ax=ax, label="final slip")
    ax.set_title("final slip")
    return finish_figure(fig, path)


def fault_figures(ds, out, prefix=""):
    """The standard figures of a fault run: rupture-time contours, final slip, station slip rate."""
    from .runs import rupture_contours

    paths = []
    if "rupture_time" in ds:
        paths.append(out / f"{prefix}rupture_time_contours.png")
        rupture_contours(ds, path=paths[-1])
    if ds.sizes.get("t", 0) > 0 and ("delta_1" in ds or "delta_3" in ds):
        paths.append(out / f"{prefix}final_slip.png")
        final_slip(ds, path=paths[-1])
    if "station_v_1" in ds:
        paths.append(out / f"{prefix}station_slip_rate.png")
        station_series(ds, "v_1", path=paths[-1])
    return paths
