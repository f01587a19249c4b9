"""Figures of the crack length of a run or an ensemble and of a whole ensemble: curves
coloured by a swept parameter, the final length against another, one panel per member."""
from __future__ import annotations

import json
import math

import numpy as np

from ..analysis import crack_length
from .common import new_axes, finish_figure, field_label, member_of, get_pyplot, parameter_label
from .runs import FAILED_EDGE, rupture_contours


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
    plt = get_pyplot()
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

    fig, ax = new_axes(ax)
    L = crack_length(ds)
    if "member" not in L.dims:
        ax.plot(L.t, L, "k-")
    else:
        plt = get_pyplot()
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
    return finish_figure(fig, path)


def ensemble_summary(ens, *, by=None, x=None, path=None, title=None):
    """Two panels: crack length against time per member coloured by ``by``; the final
    crack length against ``x`` with one line per value of ``by`` (members lacking ``x``
    or ``by`` are drawn as grey dashed levels). Defaults: the product axes of the sweep."""
    plt = get_pyplot()
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
    return finish_figure(fig, path)


def ensemble_panels(ens, *, path=None, ncols=None, levels=8, title=None):
    """Rupture-time contours of every member, one panel each, over its tau_c field, with
    the edge of the ruptured region in black (said in a legend)."""
    from matplotlib.lines import Line2D

    plt = get_pyplot()
    n = ens.sizes["member"]
    if ncols is None:
        ncols = 2 if n <= 4 else 3 if n <= 9 else 4
    nrows = math.ceil(n / ncols)
    d0 = member_of(ens, 0)
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
    fig.colorbar(sm, ax=axes, label=field_label(ens, "rupture_time") + " (contours)", shrink=0.6, aspect=30)
    if d0.sizes["x3"] > 1:
        fig.legend(handles=[Line2D([], [], color="k", lw=1.4, label=f"black: {FAILED_EDGE}")],
                   loc="outside lower center", fontsize=8, frameon=False)
    if title:
        fig.suptitle(title)
    return finish_figure(fig, path)
