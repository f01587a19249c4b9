"""An animated GIF of a field over its snapshots."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .common import (GIF_FRAMES, GIF_NODES, cmap_for, is_plane, field_label, colour_limits, member_of, plane_image, get_pyplot,
                     robust_range, thin_out)


def animate(ds, path, field="delta_2", *, member=None, fps=6, dpi=80, cmap=None, robust=True):
    """An animated GIF of ``field`` over its snapshots, looping.

    The figure (axes, colour bar, labels) is drawn once; each frame redraws only the
    field and the time in the title (blitting) and goes to Pillow, as matplotlib's
    PillowWriter does, so that a GIF of a few dozen frames takes about a second. Frames
    are read one at a time, at most ``GIF_FRAMES`` of them on at most ``GIF_NODES`` nodes
    per axis (bounded memory on any store)."""
    plt = get_pyplot()
    from PIL import Image

    d = thin_out(member_of(ds, member), GIF_NODES)
    if field not in d or "t" not in d[field].dims or d.sizes["t"] == 0:
        raise ValueError(f"no snapshots of {field!r} to animate")
    if d.sizes["t"] > GIF_FRAMES:       # every k-th snapshot, the last one kept
        keep = np.unique(np.linspace(0, d.sizes["t"] - 1, GIF_FRAMES).round().astype(int))
        d = d.isel(t=keep)
    da = d[field].transpose("t", "x1", "x3")
    # the colour (or y) range from a few frames, then one frame read at a time
    sample = np.asarray(da.isel(t=np.unique(np.linspace(0, da.sizes["t"] - 1, 12).round().astype(int))).values)
    if robust:
        vmin, vmax = colour_limits(sample, field, True, 1.0, 99.5)
    else:
        vmin, vmax = robust_range(sample, 0.0, 100.0)
    del sample
    plane = is_plane(d)
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=dpi, layout="constrained")
    first = np.asarray(da.isel(t=0).values)
    if plane:               # the plane problem: the field is a line along x1
        (artist,) = ax.plot(d["x1"].values, first[:, 0], color="C0", lw=1.5)
        pad = 0.05 * (vmax - vmin)
        ax.set_ylim(vmin - pad, vmax + pad)
        ax.set_xlabel(field_label(d, "x1"))
        ax.set_ylabel(field_label(d, field))
        ax.grid(alpha=0.3)
    else:
        artist = plane_image(ax, d, first, cmap=cmap or cmap_for(field), vmin=vmin, vmax=vmax)
        fig.colorbar(artist, ax=ax, label=field_label(d, field), shrink=0.9)
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
