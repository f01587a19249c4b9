"""Figures of runs and ensembles (matplotlib only).

Every function takes a run's Dataset (``cracklab.simulate`` or ``xarray.open_zarr``) or
an ensemble Dataset (``cracklab.open_ensemble``; pick one member with ``member=``, an id
or an integer position), draws on ``ax`` (a new figure when None) and, with ``path``,
saves the figure there and closes it. They return the matplotlib Figure (``animate``
returns the path).

* ``snapshot``: one field (delta_2, v_2, tau_2, strength, ...) at one time;
* ``rupture_contours``: contours of ``rupture_time`` over the plane (over the toughness
  field tau_c of the scene, when it is a field);
* ``crack_length`` / ``crack_length_plot``: mean crack length l(t) = (area with
  rupture_time <= t) / L3, per member for an ensemble, coloured by a parameter;
* ``ensemble_summary``: crack length curves coloured by one parameter and the final
  length against another; ``ensemble_panels``: rupture-time contours of every member;
* ``animate``: an animated GIF of a field over its snapshots (PillowWriter).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import xarray as xr

from ..analysis import cell_area_and_width, failed_length

__all__ = ["snapshot", "rupture_contours", "crack_length", "crack_length_plot", "ensemble_summary",
           "ensemble_panels", "animate", "summary_figures"]


# ---------------------------------------------------------------------------- helpers
def _plt():
    import matplotlib.pyplot as plt   # headless: matplotlib falls back to Agg by itself

    return plt


def _member(ds, member=None):
    """One member of an ensemble Dataset (the Dataset itself for a run)."""
    if "member" not in ds.dims:
        return ds
    if member is None:
        if ds.sizes["member"] != 1:
            raise ValueError(f"this is an ensemble of {ds.sizes['member']} members: give member= "
                             f"(an id, e.g. {str(ds.member.values[0])!r}, or a position)")
        return _trim(ds.isel(member=0))
    if isinstance(member, (int, np.integer)) and not isinstance(member, bool):
        return _trim(ds.isel(member=int(member)))
    return _trim(ds.sel(member=member))


def _trim(ds):
    """Drop the NaN padding an outer join (open_ensemble) left on t, x1, x3 for this member:
    the positions where its first recorded field is NaN throughout."""
    fields = [v for v in ds.data_vars if {"t", "x1", "x3"} <= set(ds[v].dims) and ds[v].dtype.kind == "f"]
    if not fields or ds.sizes.get("t", 0) == 0:
        return ds
    ok = ds[fields[0]].notnull()
    keep = {}
    for dim in ("t", "x1", "x3"):
        k = ok.any([d for d in ok.dims if d != dim]).values
        if k.any() and not k.all():
            keep[dim] = np.nonzero(k)[0]
    return ds.isel(keep) if keep else ds


def _scene_data(ds) -> dict:
    text = None
    if "scene" in ds.coords and ds["scene"].ndim == 0:
        text = ds["scene"].item()
    elif "scene" in ds.attrs:
        text = ds.attrs["scene"]
    try:
        return json.loads(text) if text else {}
    except ValueError:
        return {}


def _scene_list(ds) -> list[dict]:
    """Scene dicts per member (a list of one for a run)."""
    if "member" in ds.dims:
        if "scene" in ds.coords and ds["scene"].ndim == 1:
            return [json.loads(s) if s else {} for s in ds["scene"].values]
        return [_scene_data(ds)] * ds.sizes["member"]
    return [_scene_data(ds)]


def _label(ds, name):
    var = ds[name]
    long_name = var.attrs.get("long_name", name)
    units = var.attrs.get("units")
    return f"{long_name} [{units}]" if units and units != "1" else long_name


def _finish(fig, path):
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=fig.dpi)
        _plt().close(fig)
    return fig


def _axes(ax, figsize=(7.0, 3.8)):
    plt = _plt()
    if ax is None:
        fig, ax = plt.subplots(figsize=figsize, dpi=110, layout="constrained")
        return fig, ax
    return ax.figure, ax


def _extent(ds):
    return ds["x1"].values, ds["x3"].values


#: nodes per axis drawn at most: a larger grid is drawn every k-th node, so that a figure
#: reads one thinned frame at a time whatever the store's size (bounded memory)
MAX_NODES = 1024
#: nodes per axis and frames of an animation at most
GIF_NODES, GIF_FRAMES = 400, 200


def _thin(ds, nodes=MAX_NODES):
    """``ds`` (lazily) every k-th node along x1 and x3, k such that at most ``nodes`` remain."""
    steps = {d: int(math.ceil(ds.sizes[d] / nodes)) for d in ("x1", "x3") if ds.sizes.get(d, 0) > nodes}
    return ds.isel({d: slice(None, None, k) for d, k in steps.items()}) if steps else ds


def _plane_image(ax, ds, values, *, cmap, vmin=None, vmax=None, norm=None):
    """pcolormesh of an (x1, x3) array with x1 across, x3 up, equal aspect."""
    x1, x3 = _extent(ds)
    if len(x3) == 1:   # plane problem: a strip
        x3 = np.array([0.0, 1.0])
        values = np.repeat(values, 2, axis=1)
    mesh = ax.pcolormesh(x1, x3, np.asarray(values).T, cmap=cmap, vmin=vmin, vmax=vmax, norm=norm,
                         shading="nearest", rasterized=True)
    ax.set_aspect("equal")
    ax.set_xlabel(_label(ds, "x1") if "long_name" in ds["x1"].attrs else "x1")
    ax.set_ylabel(_label(ds, "x3") if "long_name" in ds["x3"].attrs else "x3")
    return mesh


def _robust(values, lo=2.0, hi=98.0):
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return 0.0, 1.0
    a, b = np.percentile(v, [lo, hi])
    if a == b:
        a, b = a - 0.5 * (abs(a) or 1.0), b + 0.5 * (abs(b) or 1.0)
    return float(a), float(b)


def _cmap_for(field):
    return "RdBu_r" if field.startswith(("tau", "v_")) else "viridis"


# ---------------------------------------------------------------------------- one run
def snapshot(ds, field="delta_2", *, t=None, member=None, ax=None, path=None, cmap=None, robust=True):
    """``field`` over the plane at the snapshot nearest ``t`` (default: the last)."""
    d = _thin(_member(ds, member))
    if field not in d:
        raise ValueError(f"no field {field!r} in this result; recorded: "
                         f"{', '.join(v for v in d.data_vars if 't' in d[v].dims) or 'none'}")
    da = d[field]
    if "t" in da.dims:
        if da.sizes["t"] == 0:
            raise ValueError(f"{field!r} has no snapshots")
        da = da.isel(t=-1) if t is None else da.sel(t=t, method="nearest")
    values = da.transpose("x1", "x3").values
    fig, ax = _axes(ax)
    vmin, vmax = _robust(values) if robust else (None, None)
    if field.startswith(("tau", "v_")) and robust:
        m = max(abs(vmin), abs(vmax))
        vmin, vmax = -m, m
    mesh = _plane_image(ax, d, values, cmap=cmap or _cmap_for(field), vmin=vmin, vmax=vmax)
    fig.colorbar(mesh, ax=ax, label=_label(d, field), shrink=0.9)
    when = f" at t = {float(da['t']):.3g}" if "t" in da.coords else ""
    ax.set_title(f"{d[field].attrs.get('long_name', field)}{when}")
    return _finish(fig, path)


def rupture_contours(ds, *, member=None, levels=10, ax=None, path=None, background=True, title=None,
                     colorbar=True):
    """Contours of ``rupture_time`` (the crack front every so often); with ``background``
    over the scene's tau_c field when it varies (asperities, random toughness)."""
    d = _thin(_member(ds, member))
    rt = d["rupture_time"].transpose("x1", "x3")
    fig, ax = _axes(ax)
    bg = None
    if background:
        for name in ("input_law_tau_c", "input_law_delta_c"):
            if name in d:
                bg = d[name]
                break
    if bg is not None:
        bgv = bg.transpose(*[x for x in bg.dims]).values
        if bgv.shape == rt.shape:
            lo, hi = float(np.nanmin(bgv)), float(np.nanmax(bgv))
            mesh = _plane_image(ax, d, bgv, cmap="Greys", vmin=lo - 0.15 * (hi - lo + 1e-12),
                                vmax=hi + 1.2 * (hi - lo + 1e-12))
            if colorbar:
                key = bg.name[len("input_law_"):]
                fig.colorbar(mesh, ax=ax, label=f"{key} (background)", shrink=0.8, pad=0.01)
    values = rt.values
    x1, x3 = _extent(d)
    finite = np.isfinite(values)
    if not finite.any():
        ax.text(0.5, 0.5, "nothing ruptured", transform=ax.transAxes, ha="center")
    else:
        tmax = float(np.nanmax(values))
        if np.isscalar(levels) or isinstance(levels, int):
            lv = np.linspace(0.0, tmax, int(levels) + 1)[1:] if tmax > 0 else [tmax]
        else:
            lv = np.asarray(levels)
        if len(x3) == 1:
            ax.plot(x1, values[:, 0], "k-")
            ax.set_xlabel("x1")
            ax.set_ylabel("rupture time")
        else:
            filled = np.where(finite, values, np.nanmax(values) * 10 + 1.0)
            from matplotlib.colors import ListedColormap

            lv = np.unique(np.asarray(lv, dtype=float))
            lv = lv[(lv > np.nanmin(values)) & (lv <= np.nanmax(values))]
            if lv.size:
                cmap = ListedColormap(_plt().get_cmap("plasma")(np.linspace(0.0, 0.85, 256)))
                cs = ax.contour(x1, x3, filled.T, levels=lv, cmap=cmap, vmin=0.0, vmax=float(np.max(lv)),
                                linewidths=1.0)
                if colorbar:
                    fig.colorbar(cs, ax=ax, label=_label(d, "rupture_time"), shrink=0.8)
            ax.contour(x1, x3, finite.T.astype(float), levels=[0.5], colors="k", linewidths=1.4)
            ax.set_aspect("equal")
            ax.set_xlabel("x1")
            ax.set_ylabel("x3")
    ax.set_title(title or "rupture time contours (black: ruptured region)")
    return _finish(fig, path)


def crack_length(ds, t=None, *, n=256) -> xr.DataArray:
    """Mean crack length l(t) = (area where rupture_time <= t) / L3 (the plane's extent
    along x3; in the plane problem, the length that failed). ``t``: times (default ``n``
    points from 0 to the largest t_end). For an ensemble the result is (member, t)."""
    scenes = _scene_list(ds)
    rt = ds["rupture_time"]
    if t is None:
        t_end = max([float(s.get("t_end", np.nan)) for s in scenes if s] or [np.nan])
        if not math.isfinite(t_end):
            t_end = float(np.nanmax(rt.values)) if np.isfinite(rt.values).any() else 1.0
        t = np.linspace(0.0, t_end, n)
    t = np.atleast_1d(np.asarray(t, dtype=float))
    units = rt.attrs.get("units", "1")
    length_units = ds["x1"].attrs.get("units", "1") if "x1" in ds.coords else "1"

    def one(values, scene):
        area, width = _cell_area_and_width(ds, scene)
        v = np.sort(values[np.isfinite(values)].ravel())
        return failed_length(np.searchsorted(v, t, side="right"), area, width)  # failed cells at each t

    attrs = {"long_name": "mean crack length (ruptured area / L3)", "units": length_units}
    tc = ("t", t, {"long_name": "time", "units": units})
    if "member" in rt.dims:
        out = np.stack([one(rt.isel(member=i).values, scenes[i]) for i in range(rt.sizes["member"])])
        coords = {k: v for k, v in rt.coords.items() if v.dims == ("member",)}
        return xr.DataArray(out, dims=("member", "t"), coords={**coords, "t": tc}, name="crack_length",
                            attrs=attrs)
    return xr.DataArray(one(rt.values, scenes[0]), dims=("t",), coords={"t": tc}, name="crack_length",
                        attrs=attrs)


def _cell_area_and_width(ds, scene) -> tuple[float, float]:
    """The cell area and the width across the crack (:func:`cracklab.analysis.cell_area_and_width`)
    of the scene's grid; without one, of the recorded coordinates: dx1 and the number of
    nodes along x3 (the width in units of dx3)."""
    from ..errors import InputError
    from ..model.grid import Grid

    g = scene.get("grid", {})
    if {"n1", "n3", "L1", "L3"} <= set(g):
        try:
            return cell_area_and_width(Grid(n1=g["n1"], n3=g["n3"], L1=g["L1"], L3=g["L3"]))
        except (InputError, TypeError):
            pass
    x1, x3 = ds["x1"].values, ds["x3"].values
    dx1 = float(np.median(np.diff(x1))) if len(x1) > 1 else 1.0
    return dx1, float(len(x3) if len(x3) > 1 else 1)


def _numeric_coord(ds, name):
    if name is None or name not in ds.coords:
        return None
    v = ds[name].values
    return v.astype(float) if v.dtype.kind in "iuf" else None


def _member_label(ens, i, skip=()):
    swept = json.loads(ens.attrs.get("swept", "[]"))
    parts = []
    for p in swept:
        name = p.replace(".", "_")
        if name in skip or name not in ens.coords or name in ("seed", "builder"):
            continue
        v = ens[name].values[i]
        if isinstance(v, (float, np.floating)) and np.isnan(v):
            continue
        if isinstance(v, str) and not v:
            continue
        parts.append(f"{name}={v:.3g}" if isinstance(v, (float, np.floating)) else f"{name}={v}")
    if not parts and "scene_name" in ens.coords:
        parts.append(str(ens["scene_name"].values[i]))
    return ", ".join(parts)


def _default_by(ens):
    """Numeric swept parameters, the product axes first (in their order)."""
    axes = [p.replace(".", "_") for p in json.loads(ens.attrs.get("axes", "[]"))]
    swept = [p.replace(".", "_") for p in json.loads(ens.attrs.get("swept", "[]"))]
    names = list(dict.fromkeys(axes + swept))
    return [p for p in names if p != "seed" and _numeric_coord(ens, p) is not None
            and np.isfinite(_numeric_coord(ens, p)).any()]


def _pick_by(cands, by):
    """``by`` if given, else the second swept parameter (the first is the x axis)."""
    if by is not None:
        return by
    return cands[1] if len(cands) > 1 else cands[0] if cands else None


def _colours(values, cmap="viridis"):
    """(colour of each value (None where NaN), legend entries or None, norm or None):
    a few distinct values get discrete colours and a legend, many a colour bar."""
    plt = _plt()
    from matplotlib.colors import ListedColormap

    base = plt.get_cmap(cmap)
    cm = ListedColormap(base(np.linspace(0.0, 0.82, 256)))   # no pale end: curves stay visible
    if values is None or not np.isfinite(values).any():
        return [None] * (0 if values is None else len(values)), None, None, cm
    uniq = sorted(set(float(v) for v in values if np.isfinite(v)))
    if len(uniq) <= 8:
        pos = np.linspace(0.0, 1.0, len(uniq)) if len(uniq) > 1 else [0.5]
        table = {u: cm(p) for u, p in zip(uniq, pos)}
        return [table[float(v)] if np.isfinite(v) else None for v in values], table, None, cm
    norm = plt.Normalize(uniq[0], uniq[-1])
    return [cm(norm(v)) if np.isfinite(v) else None for v in values], None, norm, cm


def crack_length_plot(ds, *, by=None, style=None, ax=None, path=None, cmap="viridis", title=None):
    """Mean crack length against time: one curve for a run; for an ensemble one curve per
    member, coloured by the parameter ``by`` and dashed by ``style`` (coordinates; default
    the product axes of the sweep: the second colours, the first sets the line style);
    members without ``by`` in grey, dashed."""
    from matplotlib.lines import Line2D

    fig, ax = _axes(ax)
    L = crack_length(ds)
    if "member" not in L.dims:
        ax.plot(L.t, L, "k-")
    else:
        plt = _plt()
        cands = _default_by(ds)
        by = _pick_by(cands, by)
        if style is None:
            style = next((c for c in cands if c != by), None)
        colours, table, norm, cm = _colours(_numeric_coord(ds, by), cmap)
        svals = _numeric_coord(ds, style)
        suniq = sorted(set(float(v) for v in svals if np.isfinite(v))) if svals is not None else []
        styles = ["-", "--", ":", "-.", (0, (5, 1, 1, 1)), (0, (1, 3))]
        handles = []
        for i in range(L.sizes["member"]):
            y = L.isel(member=i)
            ls = styles[suniq.index(float(svals[i])) % len(styles)] if suniq and np.isfinite(svals[i]) else "-"
            if colours and colours[i] is not None:
                ax.plot(L.t, y, color=colours[i], ls=ls, lw=1.7)
            else:
                ax.plot(L.t, y, color="0.4", ls=(0, (3, 2)), lw=1.7)
                handles.append(Line2D([], [], color="0.4", ls=(0, (3, 2)), label=_member_label(ds, i)))
        if table:
            handles = [Line2D([], [], color=c, lw=2.5, label=f"{by} = {u:g}") for u, c in table.items()] + \
                [Line2D([], [], color="k", ls=styles[k % len(styles)], label=f"{style} = {u:g}")
                 for k, u in enumerate(suniq)] + handles
        elif norm is not None:
            fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cm), ax=ax, label=by)
        if handles:
            ax.legend(handles=handles, fontsize=7.5, loc="lower right", framealpha=0.9)
    ax.set_xlabel(f"time [{L.t.attrs.get('units', '1')}]" if L.t.attrs.get("units", "1") != "1" else "time")
    ax.set_ylabel(L.attrs["long_name"])
    ax.set_title(title or "mean crack length")
    ax.grid(alpha=0.3)
    return _finish(fig, path)


def ensemble_summary(ens, *, by=None, x=None, path=None, title=None):
    """Two panels: crack length against time per member coloured by ``by``; the final
    crack length against ``x`` with one line per value of ``by`` (members lacking ``x``
    or ``by`` are drawn as grey dashed levels). Defaults: the product axes of the sweep."""
    plt = _plt()
    cands = _default_by(ens)
    by = _pick_by(cands, by)
    if x is None:
        x = next((c for c in cands if c != by), None)
    fig, (a0, a1) = plt.subplots(1, 2, figsize=(12, 4.4), dpi=110, layout="constrained")
    crack_length_plot(ens, by=by, style=x, ax=a0)
    L = crack_length(ens)
    final = L.isel(t=-1).values
    xv, bv = _numeric_coord(ens, x), _numeric_coord(ens, by)
    if xv is not None and bv is not None:
        colours, table, norm, cm = _colours(bv)
        for b in sorted(set(float(v) for v in bv if np.isfinite(v))):
            sel = (bv == b) & np.isfinite(xv)
            order = np.argsort(xv[sel])
            colour = table[b] if table else cm(norm(b))
            a1.plot(xv[sel][order], final[sel][order], "o-", color=colour, label=f"{by} = {b:g}")
        rest = ~(np.isfinite(xv) & np.isfinite(bv))
        for i in np.nonzero(rest)[0]:
            a1.axhline(final[i], color="0.4", ls=(0, (3, 2)), lw=1.2, label=_member_label(ens, i))
        a1.set_xlabel(x)
        a1.legend(fontsize=8, loc="best")
    else:
        a1.bar(np.arange(len(final)), final, color="C0")
        a1.set_xticks(np.arange(len(final)), [_member_label(ens, i) for i in range(len(final))],
                      rotation=30, ha="right", fontsize=7)
    a1.set_ylabel(f"mean crack length at t = {float(L.t[-1]):.3g}")
    a1.set_title("final mean crack length")
    a1.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    return _finish(fig, path)


def ensemble_panels(ens, *, path=None, ncols=None, levels=8, title=None):
    """Rupture-time contours of every member, one panel each, over its tau_c field."""
    plt = _plt()
    n = ens.sizes["member"]
    if ncols is None:
        ncols = 2 if n <= 4 else 3 if n <= 9 else 4
    nrows = math.ceil(n / ncols)
    d0 = _member(ens, 0)
    aspect = (float(d0.x1[-1] - d0.x1[0]) / max(float(d0.x3[-1] - d0.x3[0]), 1e-12)) if d0.sizes["x3"] > 1 else 3
    w = 4.2
    fig, axes = plt.subplots(nrows, ncols, figsize=(w * ncols, w / aspect * nrows + 0.6 * nrows),
                             dpi=100, layout="constrained", squeeze=False)
    if np.isscalar(levels):
        rt = ens["rupture_time"].values
        tmax = float(np.nanmax(rt)) if np.isfinite(rt).any() else 0.0
        levels = np.linspace(0.0, tmax if tmax > 0 else 1.0, int(levels) + 1)[1:]
    for i in range(nrows * ncols):
        ax = axes.flat[i]
        if i >= n:
            ax.axis("off")
            continue
        rupture_contours(ens, member=i, ax=ax, levels=levels, colorbar=False,
                         title=_member_label(ens, i) or str(ens.member.values[i]))
        ax.title.set_fontsize(9)
        ax.tick_params(labelsize=7)
        ax.xaxis.label.set_size(8)
        ax.yaxis.label.set_size(8)
    from matplotlib.colors import ListedColormap

    cmap = ListedColormap(plt.get_cmap("plasma")(np.linspace(0.0, 0.85, 256)))
    sm = plt.cm.ScalarMappable(norm=plt.Normalize(0.0, float(np.max(levels))), cmap=cmap)
    fig.colorbar(sm, ax=axes, label=_label(ens, "rupture_time") + " (contours)", shrink=0.6, aspect=30)
    if title:
        fig.suptitle(title)
    return _finish(fig, path)


def animate(ds, path, field="delta_2", *, member=None, fps=6, dpi=80, cmap=None, robust=True):
    """An animated GIF of ``field`` over its snapshots, looping.

    The figure (axes, colour bar, labels) is drawn once; each frame redraws only the
    field and the time in the title (blitting) and goes to Pillow, as matplotlib's
    PillowWriter does, so that a GIF of a few dozen frames takes about a second. Frames
    are read one at a time, at most ``GIF_FRAMES`` of them on at most ``GIF_NODES`` nodes
    per axis (bounded memory on any store)."""
    plt = _plt()
    from PIL import Image

    d = _thin(_member(ds, member), GIF_NODES)
    if field not in d or "t" not in d[field].dims or d.sizes["t"] == 0:
        raise ValueError(f"no snapshots of {field!r} to animate")
    if d.sizes["t"] > GIF_FRAMES:       # every k-th snapshot, the last one kept
        keep = np.unique(np.linspace(0, d.sizes["t"] - 1, GIF_FRAMES).round().astype(int))
        d = d.isel(t=keep)
    da = d[field].transpose("t", "x1", "x3")
    # the colour range from a few frames, then one frame read at a time
    sample = np.asarray(da.isel(t=np.unique(np.linspace(0, da.sizes["t"] - 1, 12).round().astype(int))).values)
    vmin, vmax = _robust(sample, 1.0, 99.5) if robust else (np.nanmin(sample), np.nanmax(sample))
    del sample
    if field.startswith(("tau", "v_")):
        m = max(abs(vmin), abs(vmax))
        vmin, vmax = -m, m
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=dpi, layout="constrained")
    mesh = _plane_image(ax, d, np.asarray(da.isel(t=0).values), cmap=cmap or _cmap_for(field), vmin=vmin, vmax=vmax)
    fig.colorbar(mesh, ax=ax, label=_label(d, field), shrink=0.9)
    t = da["t"].values
    name = da.attrs.get("long_name", field)
    title = ax.set_title(f"{name}, t = {t[-1]:.3g}")
    fig.canvas.draw()                    # final layout, with the widest title
    fig.set_layout_engine("none")
    title.set_text("")                   # hidden titles get moved off the figure: empty it instead
    mesh.set_visible(False)
    fig.canvas.draw()
    background = fig.canvas.copy_from_bbox(fig.bbox)
    mesh.set_visible(True)
    images = []
    for k in range(len(t)):
        vals = np.asarray(da.isel(t=k).values)
        if d.sizes["x3"] == 1:
            vals = np.repeat(vals, 2, axis=1)
        mesh.set_array(np.asarray(vals).T.ravel())
        title.set_text(f"{name}, t = {t[k]:.3g}")
        fig.canvas.restore_region(background)
        ax.draw_artist(mesh)
        ax.draw_artist(title)
        rgba = np.asarray(fig.canvas.buffer_rgba())
        images.append(Image.fromarray(rgba[..., :3].copy()).convert("P", palette=Image.Palette.ADAPTIVE))
    plt.close(fig)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    images[0].save(path, save_all=True, append_images=images[1:], duration=int(1000 / fps), loop=0)
    return path


# ---------------------------------------------------------------------------- all at once
def summary_figures(ds, out, *, field="delta_2", by=None, x=None, gif_member=None, prefix=""):
    """Write the standard figures of a run or an ensemble into directory ``out``; returns
    the list of paths. Run: snapshot, rupture contours, crack length, GIF. Ensemble:
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
        d = _member(ds, member)
        if field in d and d.sizes.get("t", 0) > 1:
            paths.append(out / f"{prefix}{field}_{str(d.member.values) if 'member' in d.coords else 'run'}.gif")
            animate(d, paths[-1], field)
        return paths
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
