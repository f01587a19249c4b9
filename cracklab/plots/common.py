"""What the figures share: matplotlib on demand, one member of an ensemble as a run,
labels with units (``parameter_label``), thinning to the figure's size, colour limits."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..analysis import member_view
from ..analysis.members import trim_padding
from ..analysis.rupture import member_scenes, scene_dict


def get_pyplot():
    import matplotlib.pyplot as plt   # headless: matplotlib falls back to Agg by itself

    return plt


def plural(n: int, word: str) -> str:
    """"1 member", "2 members"."""
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def member_of(ds, member=None):
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


def field_label(ds, name):
    """"long name [units]" of a variable or coordinate (its name without a long name)."""
    var = ds[name]
    long_name = var.attrs.get("long_name", name)
    units = var.attrs.get("units")
    return f"{long_name} [{units}]" if units and units != "1" else long_name


def finish_figure(fig, path):
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=fig.dpi)
        get_pyplot().close(fig)
    return fig


def new_axes(ax, figsize=(7.0, 3.8)):
    plt = get_pyplot()
    if ax is None:
        fig, ax = plt.subplots(figsize=figsize, dpi=110, layout="constrained")
        return fig, ax
    return ax.figure, ax


def plane_extent(ds):
    return ds["x1"].values, ds["x3"].values


def is_plane(ds) -> bool:
    """The plane problem (n3 = 1): fields are lines along x1."""
    return ds.sizes.get("x3", 0) == 1


#: nodes per axis drawn at most: a larger grid is drawn every k-th node, so that a figure
#: reads one thinned frame at a time whatever the store's size (bounded memory)
MAX_NODES = 1024
#: nodes per axis and frames of an animation at most
GIF_NODES, GIF_FRAMES = 400, 200


def thin_out(ds, nodes=MAX_NODES):
    """``ds`` (lazily) every k-th node along x1 and x3, k such that at most ``nodes`` remain."""
    steps = {d: int(math.ceil(ds.sizes[d] / nodes)) for d in ("x1", "x3") if ds.sizes.get(d, 0) > nodes}
    return ds.isel({d: slice(None, None, k) for d, k in steps.items()}) if steps else ds


def plane_image(ax, ds, values, *, cmap, vmin=None, vmax=None, norm=None):
    """pcolormesh of an (x1, x3) array with x1 across, x3 up, equal aspect (3D grids)."""
    x1, x3 = plane_extent(ds)
    mesh = ax.pcolormesh(x1, x3, np.asarray(values).T, cmap=cmap, vmin=vmin, vmax=vmax, norm=norm,
                         shading="nearest", rasterized=True)
    ax.set_aspect("equal")
    ax.set_xlabel(field_label(ds, "x1"))
    ax.set_ylabel(field_label(ds, "x3"))
    return mesh


def robust_range(values, lo=2.0, hi=98.0):
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return 0.0, 1.0
    a, b = np.percentile(v, [lo, hi])
    if a == b:
        a, b = a - 0.5 * (abs(a) or 1.0), b + 0.5 * (abs(b) or 1.0)
    return float(a), float(b)


def cmap_for(field):
    return "RdBu_r" if field.startswith(("tau", "v_")) else "viridis"


def colour_limits(values, field, robust, lo=2.0, hi=98.0):
    """Colour (or y) limits of a field: percentiles with ``robust``, symmetric about 0 for
    tractions and rates; None, None otherwise (the data's own range)."""
    if not robust:
        return None, None
    vmin, vmax = robust_range(values, lo, hi)
    if field.startswith(("tau", "v_")):
        m = max(abs(vmin), abs(vmax))
        vmin, vmax = -m, m
    return vmin, vmax
