"""Figures of one run (or one member of an ensemble): a field at one time, the
rupture-time contours."""
from __future__ import annotations

import numpy as np

from .common import new_axes, cmap_for, plane_extent, finish_figure, is_plane, field_label, colour_limits, member_of, plane_image, get_pyplot, thin_out


def snapshot(ds, field="delta_2", *, t=None, member=None, ax=None, path=None, cmap=None, robust=True):
    """``field`` over the plane at the snapshot nearest ``t`` (default: the last); in the
    plane problem (n3 = 1) a line along x1."""
    d = thin_out(member_of(ds, member))
    if field not in d:
        raise ValueError(f"no field {field!r} in this result; recorded: "
                         f"{', '.join(v for v in d.data_vars if 't' in d[v].dims) or 'none'}")
    da = d[field]
    if "t" in da.dims:
        if da.sizes["t"] == 0:
            raise ValueError(f"{field!r} has no snapshots")
        da = da.isel(t=-1) if t is None else da.sel(t=t, method="nearest")
    values = da.transpose("x1", "x3").values
    fig, ax = new_axes(ax)
    if is_plane(d):
        ax.plot(d["x1"].values, values[:, 0], color="C0", lw=1.5)
        ax.set_xlabel(field_label(d, "x1"))
        ax.set_ylabel(field_label(d, field))
        ax.grid(alpha=0.3)
    else:
        vmin, vmax = colour_limits(values, field, robust)
        mesh = plane_image(ax, d, values, cmap=cmap or cmap_for(field), vmin=vmin, vmax=vmax)
        fig.colorbar(mesh, ax=ax, label=field_label(d, field), shrink=0.9)
    when = f" at t = {float(da['t']):.3g}" if "t" in da.coords else ""
    ax.set_title(f"{d[field].attrs.get('long_name', field)}{when}")
    return finish_figure(fig, path)


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

    plt = get_pyplot()
    d = thin_out(member_of(ds, member))
    rt = d["rupture_time"].transpose("x1", "x3")
    values = rt.values
    fig, ax = new_axes(ax)
    bg, bgv = _background(d, rt.shape) if background else (None, None)
    x1, x3 = plane_extent(d)
    finite = np.isfinite(values)
    bg_label = None
    if bg is not None:
        bg_label = field_label(d, bg.name).replace("scene input law.", "")
    if is_plane(d):
        if finite.any():
            ax.plot(x1, values[:, 0], "k-", lw=1.5, label="rupture time")
        else:
            ax.text(0.5, 0.5, "nothing ruptured", transform=ax.transAxes, ha="center")
        ax.set_xlabel(field_label(d, "x1"))
        ax.set_ylabel(field_label(d, "rupture_time"))
        ax.grid(alpha=0.3)
        if bg is not None:
            twin = ax.twinx()
            twin.plot(x1, bgv[:, 0], color="0.55", lw=1.2)
            twin.set_ylabel(bg_label, color="0.4")
        ax.set_title(title or "rupture time")
        return finish_figure(fig, path)
    if bg is not None:
        lo, hi = float(np.nanmin(bgv)), float(np.nanmax(bgv))
        greys = ListedColormap(plt.get_cmap("Greys")(np.linspace(0.05, 0.45, 256)))   # light: contours stay visible
        mesh = plane_image(ax, d, bgv, cmap=greys, vmin=lo, vmax=hi)
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
                fig.colorbar(cs, ax=ax, label=field_label(d, "rupture_time"), shrink=0.8)
        if not finite.all():
            ax.contour(x1, x3, finite.T.astype(float), levels=[0.5], colors="k", linewidths=1.4)
    ax.set_aspect("equal")
    ax.set_xlabel(field_label(d, "x1"))
    ax.set_ylabel(field_label(d, "x3"))
    ax.set_title(title or f"rupture time contours (black: {FAILED_EDGE})")
    return finish_figure(fig, path)
