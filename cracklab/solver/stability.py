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

from .kernels import wave_speed_ratio
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

# studies/stability_nu.py (docs/figures/stability_nu.json), gamma = q c_s dt at NU_NODES
LIMITS = {
    "displacement": {
        "I": (3.3031, 3.2719, 3.2375, 3.1844, 3.1219, 3.0516, 2.9750, 2.8984, 3.2375, 3.2313,
               3.2313, 2.7078, 2.6391, 2.5922, 2.5453, 2.4969, 2.4406, 2.3781, 2.3062, 2.2266,
               2.1391, 2.0422, 1.9344, 1.8125, 1.6719, 1.4992, 1.2742, 1.1609, 1.0250, 0.9453,
               0.8547, 0.7488, 0.6188, 0.5391, 0.4430, 0.3451, 0.2004),
        "II": (3.1469, 3.1469, 3.1469, 3.1469, 3.1344, 3.1344, 0.4859, 0.3357, 0.2793, 0.2721,
               0.2656, 0.2598, 0.2547, 0.2500, 0.2455, 0.2416, 0.2381, 0.2352, 0.2324, 0.2303,
               0.2281, 0.2260, 0.2238, 0.2217, 0.2193, 0.2162, 0.2121, 0.2098, 0.2070, 0.2055,
               0.2035, 0.2014, 0.1984, 0.1967, 0.1945, 0.1924, 0.1896),
        "III": (2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250,
               2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250,
               2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250,
               2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250, 2.8250),
    },
    "velocity": {
        "I": (3.0750, 3.0734, 3.0703, 3.0656, 3.0578, 0.8758, 0.4996, 0.3902, 0.3367, 0.3299,
               0.3238, 0.3189, 0.3152, 0.3129, 0.3119, 0.3131, 0.3172, 0.3258, 0.3418, 0.3734,
               0.4492, 1.6437, 1.5227, 1.4156, 1.2914, 1.1422, 0.9531, 0.8602, 0.7516, 0.6895,
               0.6191, 0.5387, 0.4418, 0.3834, 0.3137, 0.2434, 0.1406),
        "II": (0.5301, 0.4574, 0.4082, 0.3521, 0.3150, 0.2893, 0.2723, 0.2629, 0.2598, 0.2598,
               0.2600, 0.2602, 0.2605, 0.2609, 0.2611, 0.2615, 0.2621, 0.2631, 0.2641, 0.2654,
               0.2668, 0.2680, 0.2691, 0.2701, 0.2705, 0.2701, 0.2684, 0.2670, 0.2650, 0.2639,
               0.2619, 0.2600, 0.2570, 0.2551, 0.2529, 0.2500, 0.2449),
        "III": (2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594,
               2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594,
               2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594,
               2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594, 2.5594),
    },
    "product": {
        "I": (3.1344, 3.1344, 2.6484, 3.1344, 3.1344, 6.0000, 6.0000, 5.7406, 5.3812, 5.3156,
               5.2500, 5.1906, 5.1344, 5.0812, 5.0344, 4.9938, 4.9625, 4.9406, 4.9344, 4.9437,
               4.9812, 5.0563, 5.1813, 5.3719, 5.6344, 6.0000, 6.0000, 6.0000, 6.0000, 6.0000,
               6.0000, 5.5781, 4.7875, 4.1219, 3.1812, 2.4500, 1.4078),
        "II": (6.0000, 6.0000, 6.0000, 6.0000, 5.7188, 5.2031, 4.6594, 4.1000, 3.1469, 3.1469,
               3.1469, 3.2437, 3.1406, 3.0437, 2.9453, 2.8484, 2.7531, 2.6594, 2.5672, 2.4766,
               2.3859, 2.2953, 2.2063, 2.1172, 2.0281, 1.9391, 1.8484, 1.8125, 1.7766, 1.7594,
               1.7406, 1.7234, 1.7047, 1.6953, 1.6859, 1.6781, 1.6719),
        "III": (3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563,
               3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563,
               3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563,
               3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563, 3.7563),
    },
}
#: the product scheme with the law at the step's mean velocity (schemes/product2.py) has the
#: product scheme's linear recurrence (the same modal scheme, the traction-free plane steps the
#: same to the last bit): the same limits
LIMITS["product2"] = LIMITS["product"]


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
