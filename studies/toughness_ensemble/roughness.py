"""Roughness statistics of crack fronts x1_f(x3): plain numpy helpers of the toughness
ensemble study (tested in tests/studies/test_front_studies.py)."""
from __future__ import annotations

import numpy as np


def front_rms(h, axis=-1):
    """Root-mean-square deviation of the front from its mean along x3 (``axis``):
    sqrt(<(h - <h>)^2>). NaN where any value along the axis is NaN."""
    h = np.asarray(h, dtype=float)
    d = h - h.mean(axis=axis, keepdims=True)
    return np.sqrt(np.mean(d * d, axis=axis))


def front_spectrum(h, L3, axis=-1):
    """One-sided power spectrum of the front along x3 (periodic, length ``L3``).

    Returns (k, P): wavenumbers k_m = 2 pi m / L3, m = 1 .. n//2, and P_m such that
    sum_m P_m = <(h - <h>)^2> (Parseval: the mean square deviation, i.e. front_rms^2).
    A front h = A cos(k_m x3) puts A^2 / 2 at k_m."""
    h = np.asarray(h, dtype=float)
    h = np.moveaxis(h, axis, -1)
    n = h.shape[-1]
    c = np.fft.rfft(h - h.mean(axis=-1, keepdims=True), axis=-1) / n
    P = 2.0 * np.abs(c[..., 1:]) ** 2
    if n % 2 == 0:
        P[..., -1] /= 2.0            # the Nyquist mode has no conjugate partner
    m = np.arange(1, P.shape[-1] + 1)
    return 2.0 * np.pi * m / L3, P


def on_grid(x, y, grid):
    """y(x) sampled at ``grid`` for a non-decreasing x (the mean advance of a front):
    linear interpolation; NaN outside [x[0], x[-1]] (no extrapolation). Repeated x
    (a stalled front) keep the last y."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if x.size < 2:
        return np.full(np.shape(grid), np.nan)
    xs = np.maximum.accumulate(x)
    # keep the last sample of each run of equal x
    keep = np.r_[xs[1:] > xs[:-1], True]
    xs, ys = xs[keep], y[keep]
    out = np.interp(grid, xs, ys) if xs.size > 1 else np.full(np.shape(grid), np.nan)
    return np.where((np.asarray(grid) >= xs[0]) & (np.asarray(grid) <= xs[-1]), out, np.nan)


def band(values, q=(10.0, 90.0), axis=0):
    """(mean, low percentile, high percentile) across ``axis`` (the members), NaN-aware."""
    v = np.asarray(values, dtype=float)
    return (np.nanmean(v, axis=axis), np.nanpercentile(v, q[0], axis=axis),
            np.nanpercentile(v, q[1], axis=axis))


def power_law_fit(x, y):
    """Exponent and prefactor of y = c x^p by least squares in log-log over the finite,
    positive samples; (nan, nan) with fewer than 2."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    if ok.sum() < 2:
        return float("nan"), float("nan")
    p, c = np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)
    return float(p), float(np.exp(c))
