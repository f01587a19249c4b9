"""Analysis of runs and ensembles: xarray in, xarray out.

The crack front (``fronts``: where the crack is, its speed, cohesive zone and roughness),
the crack length of the failed area and the rupture statistics (``rupture``;
:func:`failed_length` with :func:`cell_area_and_width` is the one definition the
constant-K load of a run, the energy budget and :func:`crack_length` use), the summary
table of an ensemble (``table``), the views of one member (``members``) and the event
catalogue of a sequence run (``events``). Every function takes a single run or an ensemble
(``cracklab.open_ensemble``) and, on an ensemble, returns its results along ``member``.
Also: the energy budget (``energy``), the single-mode problem (``modal``) and exact
solutions (``exact``).
"""
from ..laws.base import cell_area_and_width, failed_length
from .catalogue import events
from .fronts import (cohesive_zone, front_position, front_speed, initial_front, mean_crack_length, roughness,
                     structure_function)
from .members import member_view, over_members
from .rupture import crack_length, rupture_statistics
from .table import summary

__all__ = ["initial_front", "front_position", "mean_crack_length", "failed_length", "cell_area_and_width",
           "front_speed", "cohesive_zone", "roughness", "structure_function", "crack_length",
           "rupture_statistics", "member_view", "summary", "events"]
