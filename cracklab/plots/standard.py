"""The standard figures of a run or an ensemble, written into one directory."""
from __future__ import annotations

from pathlib import Path

from .animation import animate
from .common import member_of
from .ensembles import crack_length_plot, ensemble_panels, ensemble_summary
from .runs import rupture_contours, snapshot


def summary_figures(ds, out, *, field="delta_2", by=None, x=None, gif_member=None, prefix=""):
    """Write the standard figures of a run or an ensemble into directory ``out``; returns
    the list of paths. Fault run (a shear component active): rupture-time contours, final
    slip, station slip rate. Other run: snapshot, rupture contours, crack length, GIF. Ensemble:
    summary (crack length curves + final lengths), rupture-time panels and a GIF of
    ``gif_member`` (default: the first member)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    if "member" in ds.dims:
        paths.append(out / f"{prefix}crack_length.png")
        ensemble_summary(ds, by=by, x=x, path=paths[-1])
        paths.append(out / f"{prefix}rupture_panels.png")
        ensemble_panels(ds, path=paths[-1])
        member = 0 if gif_member is None else gif_member
        d = member_of(ds, member)
        if field in d and d.sizes.get("t", 0) > 1:
            paths.append(out / f"{prefix}{field}_{str(d.member.values) if 'member' in d.coords else 'run'}.gif")
            animate(d, paths[-1], field)
        return paths
    from ..analysis.faults import is_fault

    if is_fault(ds):
        from .faults import fault_figures

        return fault_figures(ds, out, prefix)
    if field in ds and ds.sizes.get("t", 0) > 0:
        paths.append(out / f"{prefix}{field}.png")
        snapshot(ds, field, path=paths[-1])
    if "rupture_time" in ds:
        paths.append(out / f"{prefix}rupture_time.png")
        rupture_contours(ds, path=paths[-1])
        paths.append(out / f"{prefix}crack_length.png")
        crack_length_plot(ds, path=paths[-1])
    if field in ds and ds.sizes.get("t", 0) > 1:
        paths.append(out / f"{prefix}{field}.gif")
        animate(ds, paths[-1], field)
    return paths
