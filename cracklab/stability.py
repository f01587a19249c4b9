"""Measured stability limits of the time-stepping schemes (section 3.1, Eq. 52).

``GAMMA_MAX[scheme][mode]`` is the largest gamma = q c_s dt for which the envelope of
the single-mode response of that scheme grows by less than 5e-4 per unit T (less than
a factor e over T = 2000), measured with ``cracklab.modal_response`` over T = 1000 to
2000 (docs/stability.md, studies/stability_map.py). The largest gamma on a grid
is gamma_M = q_max c_s dt, Eq. (52).

Mode II grows at every gamma with both schemes (about 9e-3 gamma^2 per unit T with the
explicit one, as reported in ERRATA section 4), so its limits are small; a scheme that
does not grow is the subject of the stability work on the fast engine.
"""
from __future__ import annotations

GROWTH_TOLERANCE = 5e-4

GAMMA_MAX = {
    ("displacement", "trapezoid"): {"I": 2.3, "II": 0.23, "III": 2.3},
    ("velocity", "discretized"): {"I": 0.34, "II": 0.27, "III": 2.3},
    # measured at growth < 1e-5 per unit T (docs/stability.md)
    ("product", "product"): {"I": 2.5, "II": 2.5, "III": 2.5},
}


def modes_of(components, plane: bool) -> tuple[str, ...]:
    """Fourier-mode kernels that a set of active components exercises."""
    modes = []
    if 2 in components:
        modes.append("I")
    if plane:
        modes += [m for c, m in ((1, "II"), (3, "III")) if c in components]
    elif 1 in components or 3 in components:
        modes += ["II", "III"]
    return tuple(modes)


def beta_max(grid, formulation, convolution, components) -> float:
    """Largest stable beta for the grid and scheme: gamma_max / (q_max dx_min)."""
    limits = GAMMA_MAX[(formulation, convolution)]
    gmax = min(limits[m] for m in modes_of(components, grid.plane))
    return gmax / (grid.q_max() * grid.dx_min)
