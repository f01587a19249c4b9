"""Measured stability limits of the time-stepping schemes against Poisson's ratio
(section 3.1, Eq. 52; docs/reference/stability.md, "Limits for every Poisson ratio").

``LIMITS[scheme][mode][k]`` is the largest gamma = q c_s dt up to which the envelope of
the single-mode response of that scheme grows by at most GROWTH_TOLERANCE = 5e-4 per
unit T (less than a factor e over T = 2000) at Poisson's ratio ``NU_NODES[k]``,
measured with ``cracklab.modal_response`` over T = 1000 to 2000 (studies/stability_nu.py,
docs/figures/stability_nu.json). The largest gamma on a grid is gamma_M = q_max c_s dt,
Eq. (52), and a traction-free plane is stable when gamma_M is within the limit of every
kernel the scene drives (the Fourier modes do not interact).

Between two nodes the limit is the smaller of the two node values; above the last node
(nu > 0.499) the mode I limit follows the P-wave scaling gamma_max ~ c_s / c_d that the
table shows (q c_d dt ~ 4 for the displacement scheme at every nu). The limit a scene is
held to is SAFETY times that.

Mode II grows at every gamma with the displacement and velocity schemes (about 9e-3
gamma^2 per unit T), so their mode II limits are small; the product scheme does not grow
and is the default whenever a shear component is active.
"""
from __future__ import annotations

from ..elastic.kernels import wave_speed_ratio
from ..elastic.modes import mode_gamma  # noqa: F401  (stability.mode_gamma, as before)
from .schemes import SCHEMES as _SCHEMES

GROWTH_TOLERANCE = 5e-4
#: the fraction of the measured limit that a scene may use (covers the bisection's
#: resolution and the margin between the single-mode and the grid runs)
SAFETY = 0.97

#: formulation -> the modal scheme (formulation, convolution, integration) it steps with
SCHEMES = {name: scheme.modal for name, scheme in _SCHEMES.items()}


NU_NODES = (-0.9, -0.825, -0.75, -0.625, -0.5, -0.375, -0.25, -0.125, 0.0, 0.025, 0.05,
            0.075, 0.1, 0.125, 0.15, 0.175, 0.2, 0.225, 0.25, 0.275, 0.3, 0.325, 0.35,
            0.375, 0.4, 0.425, 0.45, 0.46, 0.47, 0.475, 0.48, 0.485, 0.49, 0.4925, 0.495,
            0.497, 0.499)

#: {scheme: {mode: limits at NU_NODES}}, each scheme's own table (``Scheme.limits``, in its
#: file under solver/schemes/; the product2 scheme has the product scheme's linear recurrence,
#: hence its limits)
LIMITS = {name: scheme.limits for name, scheme in _SCHEMES.items()}
for _name, _table in LIMITS.items():
    if set(_table) != {"I", "II", "III"} or any(len(row) != len(NU_NODES) for row in _table.values()):
        raise ImportError(f"the scheme {_name!r} gives no limit for every mode I, II, III at each of NU_NODES")


def gamma_max(formulation: str, mode: str, nu: float, *, measured: bool = False) -> float:
    """Largest stable gamma = q c_s dt of a scheme's ``mode`` kernel at Poisson ratio ``nu``
    (SAFETY times the measured limit; the measured one itself with ``measured=True``)."""
    table = LIMITS[formulation][mode]
    nu = float(nu)
    if nu >= NU_NODES[-1]:
        g = table[-1] * (wave_speed_ratio(NU_NODES[-1]) / wave_speed_ratio(nu) if mode == "I" else 1.0)
    elif nu <= NU_NODES[0]:
        g = table[0]
    else:
        k = next(i for i, x in enumerate(NU_NODES) if x > nu)
        g = table[k - 1] if nu == NU_NODES[k - 1] else min(table[k - 1], table[k])
    return g if measured else SAFETY * g


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


def gamma_limit(formulation, components, plane: bool, nu: float, *, measured: bool = False) -> tuple[float, str]:
    """(largest stable gamma, the mode that sets it) for the kernels ``components`` drive."""
    return min((gamma_max(formulation, m, nu, measured=measured), m) for m in modes_of(components, plane))


def beta_max(grid, formulation, convolution, components, *, nu, measured: bool = False) -> float:
    """Largest stable beta for the grid, scheme and Poisson ratio: gamma_max / (q_max dx_min)
    (Eq. 52). ``convolution`` is the scheme's rule (one per formulation, kept for callers)."""
    del convolution
    g, _ = gamma_limit(formulation, components, grid.plane, nu, measured=measured)
    return g / (grid.q_max() * grid.dx_min)
