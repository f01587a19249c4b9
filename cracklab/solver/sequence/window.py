"""The static response on a window of the plane (docs/reference/equations.md, "Sequences:
the quasi-dynamic response on a window"): where a sequence's plane creeps at the plate
rate, its slip is V_p t exactly, and a uniform slip loads the plane only through the
spring on the mean slip, so

    F[delta] = F[delta - V_p t] - k V_p t,

and delta - V_p t vanishes outside the smallest periodic box holding every point that does
not creep (the window). On the window F[delta - V_p t] is the periodic grid's static
response (static.py) convolved with a field that is zero outside the window: the
response to a unit slip at one node, sampled at the window's offsets and convolved by
FFTs of at least 2 m - 1 nodes along each axis the window is shorter than half of (m its
nodes there), the whole axis otherwise. The same numbers as the whole grid's transforms,
to round-off, at the cost of the window's."""
from __future__ import annotations

import numpy as np
import scipy.fft as sfft

from ...jit import njit
from ..spectral import backend_name, host_wisdom, pyfftw


def periodic_box(mask_1d) -> tuple[int, int]:
    """(start, length) of the shortest run of consecutive indices, with wrap-around, holding
    every True of ``mask_1d`` (the whole axis, (0, n), when all are True or none)."""
    n = mask_1d.size
    on = np.flatnonzero(mask_1d)
    if on.size == 0 or on.size == n:
        return 0, n
    gaps = np.diff(np.concatenate([on, [on[0] + n]]))     # gap after each True, the last wrapping
    k = int(np.argmax(gaps))
    start = int(on[(k + 1) % on.size])
    return start, n - int(gaps[k]) + 1


class WindowedStatic:
    """The static response of ``static`` (a StaticResponse on ``grid``, periodic) on the window
    of the nodes of ``mask`` (a boolean field: the nodes whose slip may differ from the plate's).

    ``points``: the window's nodes as flat indices of the grid, increasing; ``traction``
    takes {component: slip less V_p t at ``points``} and gives {component: its static
    traction at ``points``}. ``worth``: whether the window's transforms are smaller than
    the grid's."""

    def __init__(self, static, grid, mask):
        mask = np.broadcast_to(np.asarray(mask, bool), grid.shape)
        shape = grid.shape
        self.comps = static.components
        axes = []
        for ax, n in enumerate(shape):
            start, m = periodic_box(np.any(mask, axis=1 - ax))
            M = sfft.next_fast_len(2 * m - 1, real=True)
            if M >= n:
                start, m, M = 0, n, n
            axes.append((start, m, M, n))
        self.axes = axes
        self.size = tuple(M for _, _, M, _ in axes)
        self.box = tuple(m for _, m, _, _ in axes)
        self.worth = int(np.prod(self.size)) < int(np.prod(shape))
        idx = [(start + np.arange(m)) % n for start, m, _, n in axes]
        box_flat = (idx[0][:, None] * shape[1] + idx[1][None, :]).ravel()
        self.points = np.sort(box_flat)
        # box cell -> position in points, and back
        self.to_box = np.searchsorted(self.points, box_flat)
        self.from_box = np.argsort(self.to_box)
        # the kernels: the response to a unit slip of each component at node (0, 0), sampled at
        # the window's offsets (each axis: -(m - 1) .. m - 1, or the whole periodic axis)
        src, dst = [], []
        for start, m, M, n in axes:
            d = np.arange(n) if m == n else np.arange(-(m - 1), m)
            src.append(d % n)
            dst.append(d % M)
        # transform only the axes longer than a node (the plane problem's x3 is one); through
        # FFTW plans of the padded box (made at the first call) when the backend is pyfftw,
        # with 1/N in the kernels
        self.fft_axes = tuple(ax for ax in range(2) if self.size[ax] > 1) or (0,)
        self.fftw = backend_name() == "pyfftw"
        self._plans = None
        scale = 1.0 / np.prod([self.size[ax] for ax in self.fft_axes]) if self.fftw else 1.0
        self.kernels = {}
        for b in self.comps:
            unit = {c: np.zeros(shape) for c in self.comps}
            unit[b][0, 0] = 1.0
            F = static.traction(unit)
            for a in self.comps:
                K = np.zeros(self.size)
                K[np.ix_(dst[0], dst[1])] = F[a][np.ix_(src[0], src[1])]
                self.kernels[a, b] = scale * self._scipy_forward(K)

    def traction(self, slip: dict, shift=None) -> dict:
        """{component: static traction at ``points``} of {component: slip at ``points``, less
        ``shift`` ({component: a number}; None: nothing)} that is zero outside the window. One
        component with FFTW goes into and out of FFTW's arrays in compiled passes: the same
        numbers as the general path (``_traction``), without its copies."""
        shift = shift or {}
        if self.fftw and len(self.comps) == 1:
            c = self.comps[0]
            return {c: self._traction_one(slip[c], float(shift.get(c, 0.0)))}
        return self._traction(slip, shift)

    def _traction(self, slip, shift):
        spectra = {b: self._forward((np.asarray(slip[b], dtype=float)[self.to_box] - shift.get(b, 0.0))
                                    .reshape(self.box)) for b in self.comps}
        out = {}
        for a in self.comps:
            acc = sum(self.kernels[a, b] * spectra[b] for b in self.comps)
            field = self._inverse(acc)[:self.box[0], :self.box[1]]
            out[a] = np.ascontiguousarray(field).ravel()[self.from_box]
        return out

    def _traction_one(self, slip, shift):
        into_box(slip, self.to_box, shift, self.box_in())
        out = np.empty(self.points.size)
        out_of_box(self.convolve_one(), self.from_box, out)
        return out

    def box_in(self):
        """The window's box in the FFTW plan's input (one component with FFTW): the slip of
        its cells (row-major; ``to_box``: the place among ``points`` of each cell), the
        padding zero."""
        fwd, _ = self._plans or self._plan()
        return fwd.input_array[:self.box[0], :self.box[1]]

    def convolve_one(self):
        """The static traction of the slip in :meth:`box_in` on the box's cells (row-major;
        ``from_box``: the cell of each of ``points``), a view of the plan's output."""
        fwd, inv = self._plans or self._plan()
        fwd.execute()
        c = self.comps[0]
        np.multiply(self.kernels[c, c], fwd.output_array, out=inv.input_array)
        inv.execute()
        return inv.output_array[:self.box[0], :self.box[1]]

    def _forward(self, box):
        """The spectrum of ``box`` padded with zeros to ``size``."""
        if not self.fftw:
            return self._scipy_forward(box)
        fwd, _ = self._plans or self._plan()
        fwd.input_array[:self.box[0], :self.box[1]] = box       # the padding stays zero
        fwd.execute()
        return fwd.output_array.copy()

    def _inverse(self, spectrum):
        """The field of ``spectrum`` over ``size`` (1/N in the kernels with FFTW)."""
        if not self.fftw:
            if len(self.fft_axes) == 1:
                ax = self.fft_axes[0]
                return sfft.irfft(spectrum, n=self.size[ax], axis=ax)
            return sfft.irfftn(spectrum, s=self.size, axes=self.fft_axes)
        _, inv = self._plans or self._plan()
        inv.input_array[...] = spectrum
        inv.execute()
        return inv.output_array

    def _scipy_forward(self, box):
        if len(self.fft_axes) == 1:       # the 1D transform costs less to call
            ax = self.fft_axes[0]
            return sfft.rfft(box, n=self.size[ax], axis=ax)
        return sfft.rfftn(box, s=self.size, axes=self.fft_axes)

    def _plan(self):
        """FFTW's plans of the padded box (a real-to-complex plan leaves its input alone), from
        and into the host's wisdom: a resumed run transforms as the run it resumes."""
        flags, axes = ("FFTW_MEASURE",), self.fft_axes
        spec_shape = self.kernels[self.comps[0], self.comps[0]].shape
        with host_wisdom():
            fwd = pyfftw.FFTW(pyfftw.empty_aligned(self.size, dtype="float64"),
                              pyfftw.empty_aligned(spec_shape, dtype="complex128"), axes=axes, flags=flags)
            inv = pyfftw.FFTW(pyfftw.empty_aligned(spec_shape, dtype="complex128"),
                              pyfftw.empty_aligned(self.size, dtype="float64"), axes=axes,
                              direction="FFTW_BACKWARD", flags=flags)
        fwd.input_array[...] = 0.0          # planning wrote into it; the padding stays zero from here
        self._plans = (fwd, inv)
        return self._plans


@njit()
def into_box(values, to_box, shift, box):
    """box (row-major cells) = values[to_box] - shift."""
    m = box.shape[1]
    if m == 1:                  # a line (the plane problem): no division per cell
        for p in range(to_box.size):
            box[p, 0] = values[to_box[p]] - shift
        return
    for p in range(to_box.size):
        box[p // m, p % m] = values[to_box[p]] - shift


@njit()
def out_of_box(box, from_box, out):
    """out[q] = the cell from_box[q] of box (row-major)."""
    m = box.shape[1]
    if m == 1:
        for q in range(from_box.size):
            out[q] = box[from_box[q], 0]
        return
    for q in range(from_box.size):
        f = from_box[q]
        out[q] = box[f // m, f % m]
