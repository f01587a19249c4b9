"""The Bromwich integral of a kernel folded onto its branch cuts (history/fit.py, item 1).

A kernel's transform F(s) is analytic except on the cuts from s = +-i b (b = 1, and
b = a = c_d/c_s for the kernels with a P wave), all running to the left. Then

    K(T) = 2 Re sum_b exp(i b T) g_b(T),   g_b(T) = int_0^inf rho_b(x) exp(-x T) dx,
    rho_b(x) = [F(ib - x - i0) - F(ib - x + i0)] / (2 pi i),

and across the cut from i b only the root sqrt(s - i b) changes sign, so the jump is
evaluated exactly. The quadrature is the trapezoid rule in u = log x (step 0.2 over
[-46, 4.5]), which reproduces the kernels to ~1e-11 for T >= 0.5.
"""
from __future__ import annotations

import numpy as np

from .waves import wave_speed_ratio

H, UMIN, UMAX = 0.2, -46.0, 4.5


def density(transform, b, x, a):
    """rho_b(x), x > 0, of ``transform(s, A, B, a)`` (A = sqrt(1+s^2), B = sqrt(1+s^2/a^2)
    given explicitly); ``b`` is 1 or a."""
    x = np.asarray(x, dtype=float)
    s = 1j * b - x
    A = np.sqrt(s + 1j) * np.sqrt(s - 1j)
    B = np.sqrt(s + 1j * a) * np.sqrt(s - 1j * a) / a
    root = 1j * np.sqrt(x)  # sqrt(s - i b) on the upper side of the cut
    if b == 1.0:
        up = np.sqrt(s + 1j) * root
        fa, fb = transform(s, up, B, a), transform(s, -up, B, a)
    elif b == a:
        up = np.sqrt(s + 1j * a) * root / a
        fa, fb = transform(s, A, up, a), transform(s, A, -up, a)
    else:
        raise ValueError(f"b must be 1 or a = {a}, got {b!r}")
    return (fb - fa) / (2j * np.pi)


def quadrature(transform, nu, branch_points, h=H, umin=UMIN, umax=UMAX):
    """[(b, x_k, w_k)] per cut: g_b(T) ~ sum_k w_k exp(-x_k T)."""
    a = wave_speed_ratio(nu)
    u = np.arange(umin, umax + 0.5 * h, h)
    x = np.exp(u)
    return [(b, x, density(transform, b, x, a) * x * h) for b in branch_points]


def evaluate(quad, T, order=0, chunk=2048):
    """K(T) (order 0) or its antiderivatives of order 1, 2 (up to their constants: the terms
    exp((ib - x) T)/(ib - x)^order) from a :func:`quadrature`."""
    T = np.asarray(T, dtype=float)
    flat = T.ravel()
    out = np.zeros(flat.shape)
    order_ = np.argsort(flat, kind="stable")
    ts = flat[order_]
    acc = np.zeros(ts.shape)
    for b, x, w in quad:
        z = 1j * b - x
        ww = w / z**order if order else w
        for i in range(0, ts.size, chunk):
            t = ts[i:i + chunk]
            live = x * t[0] < 745.0  # the other terms are below the smallest double at every t here
            acc[i:i + chunk] += 2.0 * (np.exp(np.outer(t, z[live])) @ ww[live]).real
    out[order_] = acc
    return out.reshape(T.shape)
