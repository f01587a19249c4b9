"""Measured stability limits of the time-stepping schemes (section 3.1, Eq. 52).

``GAMMA_MAX[scheme][mode]`` is the largest gamma = q c_s dt for which the single-mode
response of that scheme stays bounded (see docs/verification.md for how it was
measured). The largest gamma on a grid is gamma_M = q_max c_s dt, Eq. (52).
"""
from __future__ import annotations

GAMMA_MAX = {
    ("displacement", "trapezoid"): {"I": 2.3, "II": 2.3, "III": 2.3},
    ("velocity", "discretized"): {"I": 2.3, "II": 2.3, "III": 2.3},
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
