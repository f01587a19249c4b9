"""Figures of runs and ensembles (matplotlib only).

Every function takes a run's Dataset (``cracklab.simulate`` or ``xarray.open_zarr``) or
an ensemble Dataset (``cracklab.open_ensemble``; pick one member with ``member=``, an id
or an integer position), draws on ``ax`` (a new figure when None) and, with ``path``,
saves the figure there and closes it. They return the matplotlib Figure (``animate``
returns the path).

* ``snapshot``: one field (delta_2, v_2, tau_2, strength, ...) at one time;
* ``rupture_contours``: contours of ``rupture_time`` over the plane (over the toughness
  field tau_c of the scene, when it is a field);
* ``crack_length`` (``cracklab.analysis.crack_length``) / ``crack_length_plot``: mean
  crack length l(t) = (area with rupture_time <= t) / L3, per member for an ensemble,
  coloured by a parameter;
* ``ensemble_summary``: crack length curves coloured by one parameter and the final
  length against another; ``ensemble_panels``: rupture-time contours of every member;
* ``animate``: an animated GIF of a field over its snapshots (PillowWriter).

Parameters are named in plain words (``parameter_label``), axes carry units, and in the
plane problem (n3 = 1) fields are drawn as lines along x1.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import xarray as xr

from ..analysis import crack_length, member_view
from ..analysis.members import trim_padding
from ..analysis.rupture import member_scenes, scene_dict

__all__ = ["snapshot", "rupture_contours", "crack_length", "crack_length_plot", "ensemble_summary",
           "ensemble_panels", "animate", "summary_figures", "parameter_label", "plural"]


# ---------------------------------------------------------------------------- helpers
def _plt():
    import matplotlib.pyplot as plt   # headless: matplotlib falls back to Agg by itself

    return plt


def plural(n: int, word: str) -> str:
    """"1 member", "2 members"."""
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def _member(ds, member=None):
    """One member of an ensemble Dataset as a run (the Dataset itself for a run)."""
    if "member" not in ds.dims:
        return ds
    if member is None:
        if ds.sizes["member"] != 1:
            raise ValueError(f"this is an ensemble of {plural(ds.sizes['member'], 'member')}: give member= "
                             f"(an id, e.g. {str(ds.member.values[0])!r}, or a position)")
        member = 0
    return member_view(ds, member)


def _trim(ds):
    """Drop the NaN padding an outer join (open_ensemble) left on this member."""
    return trim_padding(ds)


def _scene_data(ds) -> dict:
    return scene_dict(ds)


def _scene_list(ds) -> list[dict]:
    """Scene dicts per member (a list of one for a run)."""
    return member_scenes(ds)


GREEK = {"tau": r"\tau", "delta": r"\delta", "mu": r"\mu", "sigma": r"\sigma", "theta": r"\theta",
         "beta": r"\beta", "nu": r"\nu", "eta": r"\eta", "psi": r"\psi", "alpha": r"\alpha"}


def parameter_label(ds, name, *, units=True) -> str:
    """A swept parameter in plain words for legends and axes: a symbol for a Greek name
    (``law_delta_c`` -> delta_c in mathtext), else its key without the section of a law,
    loading or material path (other sections kept: "record every"), underscores as
    spaces; and its units when the coordinate has them."""
    import re

    var = ds[name] if name in ds.coords else None
    param = str(var.attrs.get("parameter", name) if var is not None else name)
    section, _, key = param.rpartition(".")
    head, _, sub = key.partition("_")
    m = re.fullmatch(r"([a-z]+?)(\d*)", head)
    if m and m.group(1) in GREEK:
        text = "$" + GREEK[m.group(1)] + (f"^{{{m.group(2)}}}" if m.group(2) else "") + \
            (f"_{{{sub.replace('_', ',')}}}" if sub else "") + "$"
    else:           # a law's or a loading's key says what it is; record.every, grid.n1 need their section
        text = (key if section in ("", "law", "loading", "material") else f"{section} {key}").replace("_", " ")
    u = var.attrs.get("units") if var is not None else None
    return f"{text} [{u}]" if units and u and u != "1" else text


def _label(ds, name):
    """"long name [units]" of a variable or coordinate (its name without a long name)."""
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


def _is_plane(ds) -> bool:
    """The plane problem (n3 = 1): fields are lines along x1."""
    return ds.sizes.get("x3", 0) == 1


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
    """pcolormesh of an (x1, x3) array with x1 across, x3 up, equal aspect (3D grids)."""
    x1, x3 = _extent(ds)
    mesh = ax.pcolormesh(x1, x3, np.asarray(values).T, cmap=cmap, vmin=vmin, vmax=vmax, norm=norm,
                         shading="nearest", rasterized=True)
    ax.set_aspect("equal")
    ax.set_xlabel(_label(ds, "x1"))
    ax.set_ylabel(_label(ds, "x3"))
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


def _limits(values, field, robust, lo=2.0, hi=98.0):
    """Colour (or y) limits of a field: percentiles with ``robust``, symmetric about 0 for
    tractions and rates; None, None otherwise (the data's own range)."""
    if not robust:
        return None, None
    vmin, vmax = _robust(values, lo, hi)
    if field.startswith(("tau", "v_")):
        m = max(abs(vmin), abs(vmax))
        vmin, vmax = -m, m
    return vmin, vmax


# ---------------------------------------------------------------------------- one run
def snapshot(ds, field="delta_2", *, t=None, member=None, ax=None, path=None, cmap=None, robust=True):
    """``field`` over the plane at the snapshot nearest ``t`` (default: the last); in the
    plane problem (n3 = 1) a line along x1."""
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
    if _is_plane(d):
        ax.plot(d["x1"].values, values[:, 0], color="C0", lw=1.5)
        ax.set_xlabel(_label(d, "x1"))
        ax.set_ylabel(_label(d, field))
        ax.grid(alpha=0.3)
    else:
        vmin, vmax = _limits(values, field, robust)
        mesh = _plane_image(ax, d, values, cmap=cmap or _cmap_for(field), vmin=vmin, vmax=vmax)
        fig.colorbar(mesh, ax=ax, label=_label(d, field), shrink=0.9)
    when = f" at t = {float(da['t']):.3g}" if "t" in da.coords else ""
    ax.set_title(f"{d[field].attrs.get('long_name', field)}{when}")
    return _finish(fig, path)


FAILED_EDGE = "edge of the ruptured region"


def _background(d, shape):
    """The scene's varying toughness (tau_c, else delta_c) on the recorded plane, or None."""
    for name in ("input_law_tau_c", "input_law_delta_c"):
        if name in d:
            bg = d[name]
            values = np.asarray(bg.values, dtype=float)
            if values.shape == shape and np.isfinite(values).any() and np.nanmax(values) > np.nanmin(values):
                return bg, values
    return None, None


def rupture_contours(ds, *, member=None, levels=10, ax=None, path=None, background=True, title=None,
                     colorbar=True):
    """Contours of ``rupture_time`` (the crack front every so often) and, in black, the edge
    of the region that ruptured; with ``background`` over the scene's tau_c field when it
    varies (asperities, random toughness), in greys over that field's own range. In the
    plane problem (n3 = 1): rupture time against x1, tau_c on a second axis."""
    from matplotlib.colors import ListedColormap

    plt = _plt()
    d = _thin(_member(ds, member))
    rt = d["rupture_time"].transpose("x1", "x3")
    values = rt.values
    fig, ax = _axes(ax)
    bg, bgv = _background(d, rt.shape) if background else (None, None)
    x1, x3 = _extent(d)
    finite = np.isfinite(values)
    bg_label = None
    if bg is not None:
        bg_label = _label(d, bg.name).replace("scene input law.", "")
    if _is_plane(d):
        if finite.any():
            ax.plot(x1, values[:, 0], "k-", lw=1.5, label="rupture time")
        else:
            ax.text(0.5, 0.5, "nothing ruptured", transform=ax.transAxes, ha="center")
        ax.set_xlabel(_label(d, "x1"))
        ax.set_ylabel(_label(d, "rupture_time"))
        ax.grid(alpha=0.3)
        if bg is not None:
            twin = ax.twinx()
            twin.plot(x1, bgv[:, 0], color="0.55", lw=1.2)
            twin.set_ylabel(bg_label, color="0.4")
        ax.set_title(title or "rupture time")
        return _finish(fig, path)
    if bg is not None:
        lo, hi = float(np.nanmin(bgv)), float(np.nanmax(bgv))
        greys = ListedColormap(plt.get_cmap("Greys")(np.linspace(0.05, 0.45, 256)))   # light: contours stay visible
        mesh = _plane_image(ax, d, bgv, cmap=greys, vmin=lo, vmax=hi)
        if colorbar:
            fig.colorbar(mesh, ax=ax, label=bg_label, shrink=0.8, pad=0.01)
    if not finite.any():
        ax.text(0.5, 0.5, "nothing ruptured", transform=ax.transAxes, ha="center")
    else:
        tmax = float(np.max(values[finite]))
        if np.isscalar(levels) or isinstance(levels, int):
            lv = np.linspace(0.0, tmax, int(levels) + 1)[1:] if tmax > 0 else [tmax]
        else:
            lv = np.asarray(levels)
        filled = np.where(finite, values, tmax * 10 + 1.0)
        lv = np.unique(np.asarray(lv, dtype=float))
        lv = lv[(lv > float(np.min(values[finite]))) & (lv <= tmax)]
        if lv.size:
            cmap = ListedColormap(plt.get_cmap("plasma")(np.linspace(0.0, 0.85, 256)))
            cs = ax.contour(x1, x3, filled.T, levels=lv, cmap=cmap, vmin=0.0, vmax=float(np.max(lv)),
                            linewidths=1.0)
            if colorbar:
                fig.colorbar(cs, ax=ax, label=_label(d, "rupture_time"), shrink=0.8)
        if not finite.all():
            ax.contour(x1, x3, finite.T.astype(float), levels=[0.5], colors="k", linewidths=1.4)
    ax.set_aspect("equal")
    ax.set_xlabel(_label(d, "x1"))
    ax.set_ylabel(_label(d, "x3"))
    ax.set_title(title or f"rupture time contours (black: {FAILED_EDGE})")
    return _finish(fig, path)


def _numeric_coord(ds, name):
    """A numeric coordinate as floats (NaN where a member lacks it), None if not numeric."""
    from ..ensemble.read import NO_INTEGER

    if name is None or name not in ds.coords:
        return None
    v = ds[name].values
    if v.dtype.kind not in "iuf":
        return None
    out = v.astype(float)
    if v.dtype.kind in "iu" and str(ds[name].attrs.get("comment", "")).startswith(f"{NO_INTEGER}:"):
        out[v == NO_INTEGER] = np.nan
    return out


def _value_label(ds, name, value) -> str:
    """"symbol = value units" of a parameter's value, for legends and titles."""
    u = ds[name].attrs.get("units") if name in ds.coords else None
    v = f"{value:.3g}" if isinstance(value, (float, np.floating)) else str(value)
    return f"{parameter_label(ds, name, units=False)} = {v}" + (f" {u}" if u and u != "1" else "")


def _da_label(da) -> str:
    units = da.attrs.get("units")
    name = da.attrs.get("long_name", da.name)
    return f"{name} [{units}]" if units and units != "1" else str(name)


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
        parts.append(_value_label(ens, name, v))
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
            handles = [Line2D([], [], color=c, lw=2.5, label=_value_label(ds, by, u)) for u, c in table.items()] + \
                [Line2D([], [], color="k", ls=styles[k % len(styles)], label=_value_label(ds, style, u))
                 for k, u in enumerate(suniq)] + handles
        elif norm is not None:
            fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cm), ax=ax, label=parameter_label(ds, by))
        if handles:
            ax.legend(handles=handles, fontsize=7.5, loc="lower right", framealpha=0.9)
    ax.set_xlabel(_da_label(L["t"]))
    ax.set_ylabel(_da_label(L))
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
            a1.plot(xv[sel][order], final[sel][order], "o-", color=colour, label=_value_label(ens, by, b))
        rest = ~(np.isfinite(xv) & np.isfinite(bv))
        for i in np.nonzero(rest)[0]:
            a1.axhline(final[i], color="0.4", ls=(0, (3, 2)), lw=1.2, label=_member_label(ens, i))
        a1.set_xlabel(parameter_label(ens, x))
        a1.legend(fontsize=8, loc="best")
    else:
        a1.bar(np.arange(len(final)), final, color="C0")
        a1.set_xticks(np.arange(len(final)), [_member_label(ens, i) for i in range(len(final))],
                      rotation=30, ha="right", fontsize=7)
    units = L.attrs.get("units", "1")
    a1.set_ylabel(f"mean crack length at t = {float(L.t[-1]):.3g}" + (f" [{units}]" if units != "1" else ""))
    a1.set_title("final mean crack length")
    a1.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    return _finish(fig, path)


def ensemble_panels(ens, *, path=None, ncols=None, levels=8, title=None):
    """Rupture-time contours of every member, one panel each, over its tau_c field, with
    the edge of the ruptured region in black (said in a legend)."""
    from matplotlib.lines import Line2D

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
        rt = np.asarray(ens["rupture_time"].values)
        tmax = float(np.max(rt[np.isfinite(rt)])) if np.isfinite(rt).any() else 0.0
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
    if d0.sizes["x3"] > 1:
        fig.legend(handles=[Line2D([], [], color="k", lw=1.4, label=f"black: {FAILED_EDGE}")],
                   loc="outside lower center", fontsize=8, frameon=False)
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
    # the colour (or y) range from a few frames, then one frame read at a time
    sample = np.asarray(da.isel(t=np.unique(np.linspace(0, da.sizes["t"] - 1, 12).round().astype(int))).values)
    if robust:
        vmin, vmax = _limits(sample, field, True, 1.0, 99.5)
    else:
        vmin, vmax = _robust(sample, 0.0, 100.0)
    del sample
    plane = _is_plane(d)
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=dpi, layout="constrained")
    first = np.asarray(da.isel(t=0).values)
    if plane:               # the plane problem: the field is a line along x1
        (artist,) = ax.plot(d["x1"].values, first[:, 0], color="C0", lw=1.5)
        pad = 0.05 * (vmax - vmin)
        ax.set_ylim(vmin - pad, vmax + pad)
        ax.set_xlabel(_label(d, "x1"))
        ax.set_ylabel(_label(d, field))
        ax.grid(alpha=0.3)
    else:
        artist = _plane_image(ax, d, first, cmap=cmap or _cmap_for(field), vmin=vmin, vmax=vmax)
        fig.colorbar(artist, ax=ax, label=_label(d, field), shrink=0.9)
    t = da["t"].values
    name = da.attrs.get("long_name", field)
    title = ax.set_title(f"{name}, t = {t[-1]:.3g}")
    fig.canvas.draw()                    # final layout, with the widest title
    fig.set_layout_engine("none")
    title.set_text("")                   # hidden titles get moved off the figure: empty it instead
    artist.set_visible(False)
    fig.canvas.draw()
    background = fig.canvas.copy_from_bbox(fig.bbox)
    artist.set_visible(True)
    images = []
    for k in range(len(t)):
        frame = np.asarray(da.isel(t=k).values)
        if plane:
            artist.set_ydata(frame[:, 0])
        else:
            artist.set_array(frame.T.ravel())
        title.set_text(f"{name}, t = {t[k]:.3g}")
        fig.canvas.restore_region(background)
        ax.draw_artist(artist)
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
