"""Direct history engine: full (or windowed) ring buffer per mode."""
from __future__ import annotations

import math

import numpy as np

from ..elastic.modes import gammas_sample, mode_gamma, modes
from ..elastic.weights import convolution_weights
from ..limits import MAX_STEPS
from .base import register

#: doubles of temporaries per weight while exact weights are computed (measured: the
#: product rule's integrals take about 205, the other rules about 20; solver/budget.py)
_WEIGHT_TEMPS = {"product": 210, "other": 22}


def deliver(flat, shape, out=None, scale=None):
    """An engine's S_n (flat, complex) times ``scale`` if given, as ``shape``: written into
    ``out`` when given (push(x, out=, scale=) of every engine)."""
    if scale is not None:
        flat *= np.broadcast_to(scale, shape).reshape(-1)
    if out is None:
        return flat.reshape(shape)
    out[...] = flat.reshape(shape)
    return out


@register
class DirectEngine:
    """Direct evaluation of S_n = sum_j w_j x_{n-j}, O(n) work per mode and step.

    ``gamma`` holds q c_s dt for each mode (any shape); the weights are those of
    Eqs. (45)-(47) for the given kernel, rule and formulation (or, with rule "product",
    the product-integration weights of cracklab.elastic.weights.product_weights), shifted by ``lag``
    (lag = 1 gives sum_{j>=1} w_j x_{n-j} when x_{n-1} is pushed at step n).
    ``window`` truncates the history at T = q c_s t <= window (None: untruncated).

    Storage: a doubled ring buffer written at decreasing positions, so that the last
    L values, newest first, are one contiguous slice; complex values are read as
    interleaved (re, im) floats against weights stored twice per mode, so the sum is a
    single contiguous reduction.
    """

    name = "direct"
    windowed = True         # it keeps a truncated history (window)
    flat_cost = False       # its step grows with the history
    extra_at_build = False  # memory's extra: while its buffer and weights grow, every engine built
    CHUNK = 256             # the growth step of its buffer and weight table (``chunk``)

    @classmethod
    def memory(cls, scene, kernel, scheme, material, shared=False) -> tuple[int, int]:
        """(bytes held, extra bytes while it grows) of one direct engine of a half space of
        ``material`` over a run of ``scene`` (its window's length, if shorter); ``shared``
        (ExponentialEngine.memory) changes nothing here: the direct engine keeps its own
        history and weights."""
        from .tables import max_bytes

        grid = scene.grid
        M = modes(grid)
        length = scene.nsteps + 1
        if scene.numerics.window is not None:
            gmin = mode_gamma(2 * np.pi / max(grid.L1, grid.L3 if not grid.plane else 0.0), material.cs, scene.dt)
            length = min(length, int(math.ceil(scene.numerics.window / gmin)) + 1)
        chunk = cls.CHUNK
        rows = int(math.ceil(length / chunk)) * chunk
        buf = 2 * length * M * 16          # the doubled ring; its rows past the history stay untouched
        weights = rows * 2 * M * 8
        g, weight = gammas_sample(grid, scene.dt, material.cs)
        distinct = min(M, int(np.unique(np.round(g, 12)).size * weight))
        table = min(max_bytes(), distinct * rows * 8)
        temps = _WEIGHT_TEMPS["product" if scheme.rule == "product" else "other"]
        # growing: the old buffer beside the new one, the weights concatenated, the next
        # chunk of weights computed
        return int(buf + weights + table), int(max(buf // 4 + weights, chunk * distinct * 8 * temps))

    def __init__(self, *, kernel, gamma, nu, rule="trapezoid", formulation="displacement",
                 lag=0, window=None, chunk=CHUNK, threads=1, nsteps=None):
        self.kernel, self.nu, self.rule, self.formulation = kernel, nu, rule, formulation
        self.shape = np.shape(gamma)
        self.gamma = np.asarray(gamma, dtype=float).ravel()
        # many modes share |q|: evaluate the kernel once per distinct gamma
        self._ug, self._inv = np.unique(self.gamma, return_inverse=True)
        self.lag = int(lag)
        self.chunk = int(chunk)
        self.window = window
        self.cap = None
        positive = self.gamma[self.gamma > 0]
        if window is not None and positive.size:
            # steps until the mode of smallest gamma reaches T = window; a window longer
            # than the run (or than any run) truncates no buffer: the whole history is kept
            # (grown as the run goes, as without a window), and the weights of every mode
            # still end at T = window (_weights)
            span = float(window) / float(positive.min())
            limit = (MAX_STEPS if nsteps is None else int(nsteps)) + 2
            self.cap = int(np.ceil(span)) + 1 if span + 1 <= limit else None
        m = self.gamma.size
        self._w2 = np.empty((0, 2 * m))
        self._bufcap = self.cap or self.chunk
        self._buf = np.zeros((2 * self._bufcap, m), dtype=complex)
        self.n = 0  # number of values pushed

    def _weights(self, j0: int, j1: int) -> np.ndarray:
        # the table of the distinct gammas comes from the process-wide kernel-table cache
        # (cracklab.history.tables): runs on the same grid and time step share it
        from .tables import weight_table

        w = weight_table(self.kernel, self._ug, j0 + self.lag, j1 + self.lag, nu=self.nu, rule=self.rule,
                         formulation=self.formulation)
        if self.window is not None:
            # truncate each mode at its own window T <= window
            j = np.arange(j0, j1)[:, None] + self.lag
            w = np.where(j * self._ug[None, :] <= self.window, w, 0.0)
        return np.ascontiguousarray(w[:, self._inv], dtype=float)

    def _slot(self, i: int, cap: int) -> int:
        """Position of x_i in a buffer of capacity cap (positions decrease with i)."""
        return (-i) % cap

    def _grow(self):
        old, n = self._bufcap, self.n
        new = 2 * old
        buf = np.zeros((2 * new, self._buf.shape[1]), dtype=complex)
        for i in range(max(0, n - old), n):
            v = self._buf[self._slot(i, old)]
            p = self._slot(i, new)
            buf[p] = v
            buf[p + new] = v
        self._buf, self._bufcap = buf, new

    def wait(self) -> None:
        """Nothing runs between pushes (the interface of ExponentialEngine.wait)."""

    def push(self, x: np.ndarray, out: np.ndarray | None = None, scale: np.ndarray | None = None) -> np.ndarray:
        """Push x_n (shape of gamma) and return S_n of the same shape (written into ``out`` if
        given; multiplied by ``scale``, real, shape of gamma, if given)."""
        x = np.asarray(x).ravel()
        n = self.n
        length = n + 1 if self.cap is None else min(n + 1, self.cap)
        if self.cap is None and length > self._bufcap:
            self._grow()
        cap = self._bufcap
        if self._w2.shape[0] < length:
            j0 = self._w2.shape[0]
            j1 = max(length, j0 + self.chunk) if self.cap is None else self.cap
            w = self._weights(j0, j1)
            self._w2 = np.concatenate([self._w2, np.repeat(w, 2, axis=1)])
        p = self._slot(n, cap)
        self._buf[p] = x
        self._buf[p + cap] = x
        hist = self._buf[p:p + length].view(float)       # newest first, (re, im) interleaved
        s = np.einsum("jm,jm->m", self._w2[:length], hist).view(complex)
        self.n = n + 1
        return deliver(s, self.shape, out, scale)

    overlap = False  # no work left for a worker thread (see ExponentialEngine.overlap)

    @property
    def buffer_nbytes(self) -> int:
        """Bytes of the ring buffer of past values (doubles as the history outgrows it,
        unless a window bounds it)."""
        return int(self._buf.nbytes)

    def launch(self) -> None:
        """Nothing to start: the direct engine does all its work in push (see ExponentialEngine.launch)."""

    def get_state(self) -> dict:
        """The dynamic state: the step count and the stored history, newest first."""
        length = self.n if self.cap is None else min(self.n, self.cap)
        if length == 0:
            return {"n": 0, "hist": np.zeros((0, self.gamma.size), dtype=complex)}
        p = self._slot(self.n - 1, self._bufcap)
        return {"n": self.n, "hist": self._buf[p:p + length].copy()}

    def set_state(self, state: dict) -> None:
        """Restore a state from :meth:`get_state` (same constructor arguments)."""
        hist = np.asarray(state["hist"], dtype=complex)
        n = int(state["n"])
        self.n = 0
        cap = self.cap or self.chunk
        while self.cap is None and cap < hist.shape[0]:
            cap *= 2
        self._bufcap = cap
        self._buf = np.zeros((2 * cap, self.gamma.size), dtype=complex)
        for j in range(hist.shape[0]):  # hist[j] is x_{n-1-j}
            q = self._slot(n - 1 - j, cap)
            self._buf[q] = hist[j]
            self._buf[q + cap] = hist[j]
        self.n = n

    def weight(self, j: int) -> np.ndarray:
        """w_j (lag included) for every mode (from the table push() built, when it holds j)."""
        if j < self._w2.shape[0]:
            return self._w2[j, 0::2].reshape(self.shape)
        return self._weights(j, j + 1)[0].reshape(self.shape)

    def start_weight(self, n: int) -> np.ndarray:
        """E_0(n) of the product rule (the start-up term on x_0), for every mode.

        Tabulated ``chunk`` values of n at a time per distinct gamma, so that consecutive
        steps evaluate no kernel."""
        from ..elastic.weights import product_weights

        tab = getattr(self, "_e0tab", None)
        if tab is None or not tab[0] <= n < tab[0] + tab[1].shape[0]:
            nn = np.arange(n, n + self.chunk)[:, None]
            e = product_weights(self.kernel, self._ug[None, :], nn, nu=self.nu, order=1, part="start0")
            self._e0tab = tab = (n, np.asarray(e, dtype=float).reshape(self.chunk, -1))
        return tab[1][n - tab[0]][self._inv].reshape(self.shape)
