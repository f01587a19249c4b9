"""The Fourier modes of a grid: how many an engine holds a history for, and the step
gamma = q c_s dt of each, in units of the mode's own time T = q c_s t (the variable of the
kernels, the fits and the stability limits)."""
from __future__ import annotations

import math

import numpy as np


def mode_gamma(q, cs, dt):
    """gamma = q c_s dt, the step of a Fourier mode of wavenumber ``q`` in units of its own
    time T = q c_s t (of a material of shear wave speed ``cs``): the variable of the limits."""
    return q * cs * dt


def modes(grid) -> int:
    """Fourier modes of the grid's spectra (what an engine holds a history for)."""
    s = grid.spectral_shape
    return int(s[0]) * int(s[1])


def gammas_sample(grid, dt, cs, limit=1 << 20):
    """(sample of gamma = q c_s dt over the modes, weight of each sampled mode): every mode
    for grids of up to ``limit`` modes, else a regular subsample of the two axes."""
    k, m = grid._axes()
    total = k.size * m.size
    step = max(1, int(math.ceil(math.sqrt(total / limit))))
    ks, ms = k[::step], m[::step]
    q = np.sqrt(ks[:, None] ** 2 + ms[None, :] ** 2).ravel()
    return mode_gamma(q, cs, dt), total / q.size


def directions(grid) -> tuple:
    """(q, c, s) of every mode of the grid's spectral layout: the wave-vector magnitude
    q = sqrt(k^2 + m^2) and the cosines c = k/q, s = m/q of Eq. (28) (0 for q = 0)."""
    k, m = grid.wavenumbers()
    q = np.sqrt(k**2 + m**2)
    with np.errstate(invalid="ignore", divide="ignore"):
        return q, np.where(q > 0, k / q, 0.0), np.where(q > 0, m / q, 0.0)
