"""Periodic grid on the fracture plane and its wave numbers (Eq. 36)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, check_fields_nesting, check_positive


MAX_NODES_PER_AXIS = 2**16
MAX_NODES = 2**26


def is_fast_size(n: int) -> bool:
    """True when n factors into 2, 3, 5 and 7 only (sizes FFTW and pocketfft do fast)."""
    if n < 1:
        return False
    for p in (2, 3, 5, 7):
        while n % p == 0:
            n //= p
    return n == 1


def accepted_size(n: int) -> bool:
    """n nodes along an axis of a 3D grid as Grid accepts them: an even fast FFT size, 2 ..
    MAX_NODES_PER_AXIS (Grid refuses any other with the rule it breaks)."""
    return 2 <= n <= MAX_NODES_PER_AXIS and n % 2 == 0 and is_fast_size(n)


def next_fast_size(n: int) -> int:
    m = max(int(n), 2)
    while not (is_fast_size(m) and m % 2 == 0):
        m += 1
    return m


def _check_size(field: str, n) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise InputError(field, f"must be an integer (an even fast FFT size 2^a 3^b 5^c 7^d >= 2), got {n!r}")
    n = int(n)
    if n < 1:
        raise InputError(field, f"must be an integer >= 1 (an even fast FFT size, or 1 for n3), got {n}")
    return n


@dataclass(frozen=True)
class Grid:
    """Nodes x1_i = i L1/n1, x3_k = k L3/n3 on the periodic cell [0, L1) x [0, L3).

    ``n3 == 1`` is the plane (x3-invariant) problem and uses 1D transforms.

    ``free_surface=True`` (3D only) puts a free surface on the line x3 = 0 by mirror
    symmetry: the grid is then the half plane x3 = depth in [0, L3] below the surface,
    with n3 + 1 nodes x3_k = k L3/n3, k = 0 .. n3 (n3 is the number of intervals; the
    first node lies on the surface, the last on x3 = L3). It stands for the periodic
    cell [0, L1) x [0, 2 L3) of n1 x 2 n3 nodes whose fields are mirrored about x3 = 0
    (and so, by the period 2 L3, about x3 = L3 too): delta_1, delta_2, tau_1, tau_2 even,
    delta_3, tau_3 odd (zero on both lines). Every field has the shape (n1, n3 + 1);
    the transforms are cosine (even) and sine (odd) transforms along x3 and a real FFT
    along x1 (solver/spectral.py, docs/reference/equations.md "A free surface by mirror symmetry").
    """

    n1: int
    n3: int
    L1: float
    L3: float
    free_surface: bool = False

    def __post_init__(self):
        check_fields_nesting(self, "grid")
        n1 = _check_size("grid.n1", self.n1)
        n3 = _check_size("grid.n3", self.n3)
        for name, n in (("grid.n1", n1), ("grid.n3", n3)):
            if name == "grid.n3" and n == 1:
                continue
            if n < 2 or n % 2 or not is_fast_size(n):
                # the next fast size is searched only within the accepted sizes: near 2^63 the
                # fast sizes lie so far apart that the search would not end
                nearest = f"; nearest larger is {next_fast_size(n)}" if n <= MAX_NODES_PER_AXIS else \
                    f"; at most {MAX_NODES_PER_AXIS}"
                raise InputError(name, f"must be an even fast FFT size (2^a 3^b 5^c 7^d, >= 2), got {n}{nearest}")
        if n1 > MAX_NODES_PER_AXIS or n3 > MAX_NODES_PER_AXIS:
            name, n = ("grid.n1", n1) if n1 > MAX_NODES_PER_AXIS else ("grid.n3", n3)
            raise InputError(name, f"must be <= {MAX_NODES_PER_AXIS}, got {n}")
        if n1 * n3 > MAX_NODES:
            raise InputError("grid.n3", f"n1 * n3 must be <= {MAX_NODES} (2^26 nodes), got {n1} * {n3} = {n1 * n3}")
        object.__setattr__(self, "n1", n1)
        object.__setattr__(self, "n3", n3)
        for name in ("L1", "L3"):
            if isinstance(getattr(self, name), (bool, np.bool_)):
                raise InputError(f"grid.{name}", f"must be a number > 0, got {getattr(self, name)!r}")
        object.__setattr__(self, "L1", check_positive("grid.L1", self.L1))
        object.__setattr__(self, "L3", check_positive("grid.L3", self.L3))
        if not isinstance(self.free_surface, (bool, np.bool_)):
            raise InputError("grid.free_surface", f"must be true or false, got {self.free_surface!r}")
        object.__setattr__(self, "free_surface", bool(self.free_surface))
        if self.free_surface and n3 == 1:
            raise InputError("grid.free_surface", "needs a 3D grid (n3 >= 2): the free surface is the line "
                                                  "x3 = 0 of the plane, and the plane problem (n3 = 1) has no x3")

    @property
    def plane(self) -> bool:
        return self.n3 == 1

    @property
    def shape(self) -> tuple[int, int]:
        """The shape of every field: (n1, n3), or (n1, n3 + 1) on the half plane of a free surface."""
        return (self.n1, self.n3 + 1) if self.free_surface else (self.n1, self.n3)

    @property
    def dx1(self) -> float:
        """Node spacing L1/n1."""
        return self.L1 / self.n1

    @property
    def dx3(self) -> float:
        """Node spacing L3/n3."""
        return self.L3 / self.n3

    @property
    def dx_min(self) -> float:
        return self.dx1 if self.plane else min(self.dx1, self.dx3)

    @property
    def x1(self) -> np.ndarray:
        """Node coordinates x1_i = i L1/n1, i = 0 .. n1 - 1."""
        return np.arange(self.n1) * self.dx1

    @property
    def x3(self) -> np.ndarray:
        """Node coordinates x3_k = k L3/n3: k = 0 .. n3 - 1, or k = 0 .. n3 (the depth) below a free surface."""
        return np.arange(self.shape[1]) * self.dx3

    @property
    def spectral_shape(self) -> tuple[int, int]:
        """Plane problem: half spectrum along x1. 3D: full spectrum along x1, half along x3
        (the real transform runs along the contiguous axis x3, which FFTW does fastest).
        Free surface: half spectrum along x1 (k1 >= 0) and the n3 + 1 cosine / sine modes
        m = pi j / L3, j = 0 .. n3, along x3: as many modes as the periodic n1 x n3 grid."""
        if self.plane:
            return (self.n1 // 2 + 1, 1)
        if self.free_surface:
            return (self.n1 // 2 + 1, self.n3 + 1)
        return (self.n1, self.n3 // 2 + 1)

    def _axes(self) -> tuple[np.ndarray, np.ndarray]:
        """The wave numbers k (along x1) and m (along x3) of the spectral layout's axes."""
        if self.plane:
            return 2 * np.pi * np.fft.rfftfreq(self.n1, d=self.dx1), np.zeros(1)
        if self.free_surface:
            # m = pi j / L3, written as the doubled cell's (2 n3 nodes) so that both give the same numbers
            return (2 * np.pi * np.fft.rfftfreq(self.n1, d=self.dx1),
                    2 * np.pi * np.fft.rfftfreq(2 * self.n3, d=self.dx3))
        return (2 * np.pi * np.fft.fftfreq(self.n1, d=self.dx1),
                2 * np.pi * np.fft.rfftfreq(self.n3, d=self.dx3))

    def wavenumbers(self) -> tuple[np.ndarray, np.ndarray]:
        """k (along x1) and m (along x3) on the spectral layout, each of spectral_shape."""
        return np.meshgrid(*self._axes(), indexing="ij")

    def q_max(self) -> float:
        """Largest wave-vector magnitude on the grid: the same number as the maximum of
        sqrt(k^2 + m^2) over ``wavenumbers()``, from the two axes alone (rounding is
        monotone, so the maximum is at the largest k^2 and m^2): O(n1 + n3), not a
        field of n1 n3 values, when a scene is validated."""
        k, m = self._axes()
        return float(np.sqrt((k**2).max() + (m**2).max()))

    def nearest_node(self, x1: float, x3: float = 0.0) -> tuple[int, int]:
        """(i, k) of the node nearest (x1, x3), periodically; with a free surface the
        nearest node of the doubled cell folded onto the half plane (its mirror image)."""
        i = int(round(x1 / self.dx1)) % self.n1
        if self.plane:
            return i, 0
        if self.free_surface:
            k = int(round(x3 / self.dx3)) % (2 * self.n3)
            return i, (2 * self.n3 - k if k > self.n3 else k)
        return i, int(round(x3 / self.dx3)) % self.n3
