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

Modules: ``runs`` (snapshot, rupture contours), ``ensembles`` (crack length curves,
ensemble summary and panels), ``animation`` (GIF), ``standard`` (``summary_figures``),
``common`` (what they share: labels, thinning, colour limits).
"""
from ..analysis import crack_length
from .animation import animate
from .common import GIF_FRAMES, GIF_NODES, GREEK, MAX_NODES, parameter_label, plural
from .ensembles import crack_length_plot, ensemble_panels, ensemble_summary
from .runs import FAILED_EDGE, rupture_contours, snapshot
from .standard import summary_figures

__all__ = ["snapshot", "rupture_contours", "crack_length", "crack_length_plot", "ensemble_summary",
           "ensemble_panels", "animate", "summary_figures", "parameter_label", "plural"]
