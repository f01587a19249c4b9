"""Wave speeds of an isotropic elastic solid: the ratio a = c_d / c_s of the dilatational
and shear speeds (footnote to Eq. 26) and the Rayleigh speed c_R / c_s (Appendix B).

The bottom layer of cracklab (with the kernels, the face kernels, their branch cuts and the
convolution weights of this package): it imports nothing of cracklab but its errors.
"""
from __future__ import annotations

import math

import numpy as np


def wave_speed_ratio(nu):
    """a = c_d/c_s from Poisson's ratio: a**2 = 2(1-nu)/(1-2nu) (footnote to eq. 26)."""
    nu = float(nu)
    if not -1.0 < nu < 0.5:
        raise ValueError(f"nu must satisfy -1 < nu < 0.5, got {nu}")
    return float(np.sqrt(2.0 * (1.0 - nu) / (1.0 - 2.0 * nu)))


def rayleigh_speed_ratio(nu=0.25):
    """c_R/c_s = s_R: root in (0, 1) of 4 sqrt(1-x) sqrt(1-x/a^2) = (2-x)^2, x = s_R^2 (Appendix B)."""
    a = wave_speed_ratio(nu)

    def f(x):  # R(i s_R) / x; negative near 0, +1 at x = 1
        return ((2.0 - x) ** 2 - 4.0 * math.sqrt(1.0 - x) * math.sqrt(1.0 - x / a**2)) / x

    from scipy import optimize  # here: scipy.optimize takes 20 MB and 0.2 s to import

    x = optimize.brentq(f, 1e-12, 1.0, xtol=1e-16, rtol=1e-15, maxiter=200)
    return math.sqrt(x)


def rayleigh_roots(nu=0.25):
    """(s_R^2, s_1^2, s_2^2): roots of the rationalised Rayleigh polynomial of (B.2)-(B.3).

    16(1+s^2)(1+s^2/a^2) - (2+s^2)^4 = -s^2 (s^2+s_R^2)(s^2+s_1^2)(s^2+s_2^2); with
    x = -s^2 the cubic is x^3 - 8x^2 + (24 - 16/a^2)x - 16(1 - 1/a^2) = 0.  s_1^2, s_2^2
    may be complex (nu > ~0.26).
    """
    a = wave_speed_ratio(nu)
    roots = np.roots([1.0, -8.0, 24.0 - 16.0 / a**2, -16.0 * (1.0 - 1.0 / a**2)]).astype(complex)
    xr = rayleigh_speed_ratio(nu) ** 2
    i = int(np.argmin(np.abs(roots - xr)))
    others = sorted(np.delete(roots, i), key=lambda z: (z.real, z.imag))
    return (xr, complex(others[0]), complex(others[1]))
