"""The event catalogue of a sequence run (cracklab.output.sequence): xarray in, xarray out."""
from __future__ import annotations

import xarray as xr


def events(ds) -> xr.Dataset:
    """The catalogue of a sequence run's Dataset ``ds`` (``cracklab.simulate`` of a scene with
    ``sequence``): on the ``event`` dimension, each event's start and end (the largest slip
    rate crossing ``event_threshold`` up and down), duration, hypocentre (x1, x3 of the
    largest slip rate at the start), peak slip rate and its time, mean slip and rupture
    area (the points whose slip rate exceeded the threshold) and moment (per unit length in
    2D). On an ensemble (``cracklab.open_ensemble``) the catalogue is on (member, event),
    each member's padded with NaN after its last event:
    ``events(ens).to_dataframe().dropna(subset=["t_start"])`` is the tidy table of every
    member's events with the swept parameters."""
    if "event" not in ds.dims:
        raise ValueError("this Dataset has no event dimension: it is not the output of a sequence run "
                         "(a Scene with sequence set)")
    names = [v for v in ds.data_vars if "event" in ds[v].dims]
    out = ds[names]
    out.attrs = {k: ds.attrs[k] for k in ("event_threshold", "title") if k in ds.attrs}
    return out
