"""The exact history at a variable time step (docs/reference/equations.md, "Sequences: the
dynamic response at a variable step").

For each mode of rate r = q c_s (> 0) the engine gives the convolution of Eq. (33),

    I(t) = int_0^t Z(r (t - s)) V(s) ds,

for a slip-rate history V that is linear between the ends of the steps taken (continuous,
V = 0 before t = 0), whatever their lengths. In u = r (t - s):

* near, u < T0: the exact kernel, through P0 = int_0^u Z and P00 = int_0^u P0, Chebyshev
  series per panel of [0, T0] built from the closed form of Z (``elastic.kernels.Z``), so a
  piece of V contributes (P0, P00 at its clipped ends, divided by its length);
* tail, u >= T0: the exponential fit Z ~ 2 Re sum_p c_p exp(lambda_p u) (history/fit.py).
  One complex state per term and per real input (Re V, Im V),
  S_p(t) = int_{s < t - T0/r} exp(lambda_p r (t - s)) V(s) ds, advances over a step h of
  any length exactly: S_p(t + h) = exp(lambda_p r h) S_p(t) + the integral over the slab
  of V that crossed u = T0 during the step, in closed form per piece.

Nothing is sampled or re-interpolated: the only approximation is the fit of the tail.
A mode keeps the pieces of V still inside its near window, at most ceil(T0 / (r h_floor))
+ 3 of them for steps no shorter than ``h_floor`` (a step or two shorter fit in; more stop
the run); step lengths (not times) are stored, so
the ages of the pieces are sums of step lengths and keep their precision late in a long
run.

The exponentials of a step are shared: e^{lam_p r h} of the step serves the slab's parts
of length r h or r h - T0 and, kept to the next step, that step's older piece; each slab
piece starts at the end of the one before (e^{lam_p x} by products), and 1 / lam_p is
computed once, so the walk computes e^{lam_p L} only for the pieces no step has.

A mode whose every term decays below e^-NEGLIGIBLE over a step (r h times the slowest
term's rate >= NEGLIGIBLE: the slow phases of a sequence, kernel III) takes it in closed
form: its window is the step's own piece and its old states and older pieces contribute
nothing, so I(t + h) = (the near kernel's weight + sum_p 2 Re c_p e^{lam_p T0} (...) / r) V(t)
+ the same for V(t + h); its states are left as that closed form (``lazy``) and written
out only when a shorter step, or a checkpoint, needs them.

A step is taken in two calls: :meth:`VariableHistory.prepare` (h, with the step's start
value already pushed) gives I(t + h) = A + B V(t + h) for every mode, linear in the
unknown end value (the interface law then finds V(t + h)); :meth:`commit` (V(t + h)) pushes
it and advances the states.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import SimulationError
from ..jit import njit
from .fit import get_fit

__all__ = ["NearTable", "VariableHistory", "T0_VARIABLE", "memory"]

#: the start of the fitted tail in u = q c_s (t - s): a mode keeps the pieces of its last
#: T0 / r seconds, T0 / (r h) of them, against fits of 11, 30 and 34 terms for Z_III, Z_I
#: and Z_II (7, 24 and 28 from T0 = 4, with eight times the pieces)
T0_VARIABLE = 0.5
#: -Re z beyond which e^z (below 2e-22) is left out of a sum of terms of order one
NEGLIGIBLE = 50.0
#: panels of [0, T0] and the degree of their Chebyshev series of Z (P0 and P00 to round-off,
#: 1e-15, for every kernel: tests/history/test_variable_history.py)
_PANELS = 64
_DEGREE = 10


def _capacity(r, T0, h_floor):
    """The pieces a mode of rate r keeps at most, for steps no shorter than ``h_floor``."""
    return np.ceil(T0 / (np.asarray(r, dtype=float) * h_floor)).astype(np.int64) + 3


def memory(kernel, nu, r, h_floor, *, T0=T0_VARIABLE, tol=None) -> int:
    """Bytes a :class:`VariableHistory` of these arguments holds: its rings, step lengths,
    states, the step's prepared states and the weights of a run of steps of ``h_floor``."""
    cap = _capacity(r, T0, h_floor)
    P = get_fit(kernel, nu, "velocity", T0=T0, tol=tol).lam.size
    return int(cap.sum() * 24 + (cap.max() + 1) * 8 + np.size(r) * (12 * P * 16 + 8 + 24 + 32 + 2))


class NearTable:
    """P0(u) = int_0^u Z and P00(u) = int_0^u P0 on [0, T0]: Chebyshev coefficients per panel
    (``p0``, ``p00``: (panels, degree + 2)), in the panel's variable x = (u - centre) / half."""

    def __init__(self, kernel, nu, T0=T0_VARIABLE, panels=_PANELS, degree=_DEGREE):
        from numpy.polynomial import chebyshev as C

        from ..elastic.kernels import Z

        self.T0, self.panels = float(T0), int(panels)
        width = self.T0 / self.panels
        self.half = 0.5 * width
        nodes = np.cos(np.pi * (np.arange(degree + 1) + 0.5) / (degree + 1))
        p0 = np.zeros((self.panels, degree + 3))
        p00 = np.zeros((self.panels, degree + 3))
        v0 = v00 = 0.0
        for i in range(self.panels):
            centre = (i + 0.5) * width
            z = C.chebfit(nodes, np.asarray(Z(kernel, centre + self.half * nodes, nu), dtype=float), degree)
            c0 = C.chebint(z, lbnd=-1.0, k=0.0, scl=self.half)     # int from the panel's left end
            c0[0] += v0
            c00 = C.chebint(c0, lbnd=-1.0, k=0.0, scl=self.half)
            c00[0] += v00
            p0[i, :c0.size], p00[i, :c00.size] = c0, c00
            v0, v00 = float(C.chebval(1.0, c0)), float(C.chebval(1.0, c00))
        self.p0, self.p00 = p0, p00

    def __call__(self, u):
        """(P0(u), P00(u)) for u in [0, T0] (numpy; the engine's loop evaluates them compiled)."""
        u = np.atleast_1d(np.asarray(u, dtype=float))
        out = np.array([_p(self.p0, self.p00, self.half, x) for x in u])
        return out[:, 0], out[:, 1]


class VariableHistory:
    """The convolutions I(t) of one kernel (``kernel`` "I", "II" or "III" at Poisson's ratio
    ``nu``) for modes of rates ``r`` (q c_s, > 0), at steps no shorter than ``h_floor``.
    ``tol``: the fit's tolerance (history/fit.py's default when None)."""

    def __init__(self, kernel, nu, r, h_floor, *, T0=T0_VARIABLE, tol=None):
        r = np.ascontiguousarray(r, dtype=float)
        if r.ndim != 1 or np.any(~(r > 0)) or not np.all(np.isfinite(r)):
            raise ValueError("r must be a 1D array of finite rates > 0")
        if not h_floor > 0:
            raise ValueError("h_floor must be > 0")
        self.kernel, self.nu, self.T0, self.h_floor = kernel, float(nu), float(T0), float(h_floor)
        self.r = r
        fit = get_fit(kernel, nu, "velocity", T0=self.T0, tol=tol)
        self.lam = np.ascontiguousarray(fit.lam, dtype=complex)
        self.coef = np.ascontiguousarray(fit.coef, dtype=complex)
        self.near = NearTable(kernel, nu, self.T0)
        cap = _capacity(r, self.T0, self.h_floor)
        self.cap = cap
        self.off = np.concatenate([[0], np.cumsum(cap)]).astype(np.int64)
        self.ring = np.zeros(int(self.off[-1]), dtype=complex)     # V at the ends of the pieces kept
        self.hcap = int(cap.max()) + 1
        self.hring = np.zeros(self.hcap)                              # the step lengths
        M, P = r.size, self.lam.size
        self.first = np.zeros(M, dtype=np.int64)   # per mode: the oldest step end it keeps
        self.n = 0                                  # step ends pushed: 0 .. n
        self.started = False
        self.SR = np.zeros((M, P), dtype=complex)
        self.SI = np.zeros((M, P), dtype=complex)
        self._prep = None
        # the prepared states, reused from step to step (prepare writes them, commit reads them)
        self._kR = np.empty((M, P), dtype=complex)
        self._kI = np.empty((M, P), dtype=complex)
        self._sB = np.empty((M, P), dtype=complex)
        # e^{lam_p r h} of the step prepared (``_g``) and of the step committed last (``_glast``,
        # valid when ``_glast_n`` is the step ends pushed): the walk's pieces of those lengths
        # take them instead of computing them again
        self._g = np.zeros((M, P), dtype=complex)
        self._glast = np.zeros((M, P), dtype=complex)
        self._glast_n = -1
        # modes whose every term decayed below e^-NEGLIGIBLE over their last step (``lazy``):
        # their states are the closed form of that step's piece, written out only when a
        # shorter step needs them (``_collapse``: the modes that collapse in the step prepared)
        self.decay = float(np.min(-self.lam.real))
        self.lazy = np.zeros(M, dtype=np.uint8)
        self._collapse = np.zeros(M, dtype=np.uint8)
        self.last_h, self.run = None, 0     # the last step committed, and how many in a row were it
        self._cache = None                  # the weights of a run of equal steps (h, arrays)

    def start(self, V0):
        """Push the value at t = 0 (before the first step)."""
        if self.started:
            raise RuntimeError("the history has started already")
        _push(self.ring, self.off, self.cap, 0, np.ascontiguousarray(V0, dtype=complex))
        self.started = True

    def prepare(self, h):
        """(A, B): I(t + h) = A + B V(t + h) for every mode (A complex, B real)."""
        if not self.started:
            raise RuntimeError("start(V0) first")
        h = float(h)
        if not h > 0:
            raise ValueError(f"a step must be > 0, got {h!r}")
        M, P = self.SR.shape
        cache = self._uniform(h)
        A = np.zeros(M, dtype=complex)
        B = np.zeros(M)
        kR, kI, sB = self._kR, self._kI, self._sB
        _prepare(self.r, self.lam, self.coef, self.near.p0, self.near.p00, self.near.half, self.T0,
                 self.ring, self.off, self.cap, self.hring, self.hcap, self.first, self.n, h,
                 self.SR, self.SI, A, B, kR, kI, sB, self._g, self._glast, self._glast_n == self.n,
                 self.lazy, self._collapse, self.decay if self.COLLAPSE else 0.0,
                 cache is not None, self.run, *(cache or self._NONE))
        self._prep = (h, kR, kI, sB)
        return A, B

    _NONE = (np.zeros(1, np.int64), np.zeros(1), np.zeros(1, np.int64), np.zeros(1, np.int64),
             np.zeros((1, 4, 1), complex), np.zeros((1, 1), complex))
    #: equal steps in a row before their weights are computed once and reused
    UNIFORM_AFTER = 8
    #: whether a mode whose terms all decay over a step takes it in closed form
    COLLAPSE = True

    def _uniform(self, h):
        """The weights of a window of steps all ``h`` long (cL, cw, cwo, ce0, cs, cg), when the
        last UNIFORM_AFTER steps were h long (a rupture at the dynamic step); else None."""
        if h != self.last_h or self.run < self.UNIFORM_AFTER:
            return None
        if self._cache is None or self._cache[0] != h:
            M, P = self.SR.shape
            cL = np.zeros(M, dtype=np.int64)
            _uniform_pieces(self.r, self.T0, h, cL)
            cwo = np.concatenate([[0], np.cumsum(cL + 1)]).astype(np.int64)
            arrays = (cL, np.zeros(int(cwo[-1])), cwo, np.zeros(M, dtype=np.int64),
                      np.zeros((M, 4, P), dtype=complex), np.zeros((M, P), dtype=complex))
            _uniform_weights(self.r, self.lam, self.near.p0, self.near.p00, self.near.half, self.T0, h, *arrays)
            self._cache = (h, arrays)
        return self._cache[1]

    def commit(self, V):
        """Push the end value V(t + h) of the step prepared last and advance the states."""
        if self._prep is None:
            raise RuntimeError("prepare(h) first")
        h, kR, kI, sB = self._prep
        V = np.ascontiguousarray(V, dtype=complex)
        _advance(kR, kI, sB, V, self.SR, self.SI, self._collapse, self.lazy)
        self._g, self._glast = self._glast, self._g       # the step's e^{lam r h}: the newest piece's from here
        self._glast_n = self.n + 1
        self.hring[self.n % self.hcap] = h
        self.run = self.run + 1 if h == self.last_h else 1
        self.last_h = h
        self.n += 1
        _push(self.ring, self.off, self.cap, self.n, V)
        over = _drop(self.r, self.T0, self.hring, self.hcap, self.first, self.n, self.cap)
        self._prep = None
        if over >= 0:
            raise SimulationError(f"the history of mode {over} (q c_s = {self.r[over]:.6g}) holds more pieces than "
                                  f"its ring: too many steps shorter than the floor {self.h_floor:g}")

    def get_state(self) -> dict:
        _write_out(self.r, self.lam, self.T0, self.ring, self.off, self.cap, self.hring, self.hcap, self.n,
                   self.SR, self.SI, self.lazy)          # the states as the run's before this one held them
        return {"ring": self.ring.copy(), "hring": self.hring.copy(), "first": self.first.copy(), "n": self.n,
                "started": self.started, "SR": self.SR.copy(), "SI": self.SI.copy(),
                "last_h": self.last_h, "run": self.run,
                "g_last": self._glast.copy() if self._glast_n == self.n else None}

    def set_state(self, state: dict) -> None:
        self.ring = np.array(state["ring"], dtype=complex)
        self.hring = np.array(state["hring"], dtype=float)
        self.first = np.array(state["first"], dtype=np.int64)
        self.n, self.started = int(state["n"]), bool(state["started"])
        self.SR = np.array(state["SR"], dtype=complex)
        self.SI = np.array(state["SI"], dtype=complex)
        self.last_h = None if state["last_h"] is None else float(state["last_h"])
        self.run = int(state["run"])
        g = state.get("g_last")         # None (or absent: a state written before it was kept): computed again
        self._glast = np.zeros_like(self.SR) if g is None else np.array(g, dtype=complex)
        self._glast_n = -1 if g is None else self.n
        self.lazy[:] = 0
        self._prep = None


# ------------------------------------------------------------------------ compiled loops
@njit()
def _cheb(c, x):
    """Clenshaw: sum_k c_k T_k(x)."""
    b1 = 0.0
    b2 = 0.0
    for k in range(c.size - 1, 0, -1):
        b1, b2 = 2.0 * x * b1 - b2 + c[k], b1
    return x * b1 - b2 + c[0]


@njit()
def _p(p0, p00, half, u):
    """(P0(u), P00(u)) from the panels' series."""
    i = int(u / (2.0 * half))
    if i >= p0.shape[0]:
        i = p0.shape[0] - 1
    if i < 0:
        i = 0
    x = (u - (2 * i + 1) * half) / half
    return _cheb(p0[i], x), _cheb(p00[i], x)


@njit()
def _phi(z):
    """((e^z - 1)/z, (e^z (z - 1) + 1)/z^2): int_0^1 e^{z v} dv and int_0^1 v e^{z v} dv."""
    if z.real < -NEGLIGIBLE:                # e^z below 2e-22: its terms are below the last bit
        return -1.0 / z, 1.0 / (z * z)
    if abs(z) < 1e-3:
        z2 = z * z
        return (1.0 + z / 2.0 + z2 / 6.0 + z2 * z / 24.0 + z2 * z2 / 120.0,
                0.5 + z / 3.0 + z2 / 8.0 + z2 * z / 30.0 + z2 * z2 / 144.0)
    e = np.exp(z)
    return (e - 1.0) / z, (e * (z - 1.0) + 1.0) / (z * z)


@njit()
def _advance(kR, kI, sB, V, SR, SI, collapse, lazy):
    """The states at the step's end, in place: S = k + sB V (Re V into SR, Im V into SI);
    a mode that collapsed in the step is left lazy (its state the closed form of the step)."""
    M, P = SR.shape
    for k in range(M):
        if collapse[k]:
            lazy[k] = 1
            continue
        vr = V[k].real
        vi = V[k].imag
        for p in range(P):
            SR[k, p] = kR[k, p] + sB[k, p] * vr
            SI[k, p] = kI[k, p] + sB[k, p] * vi


@njit()
def _push(ring, off, cap, j, V):
    for k in range(cap.size):
        ring[off[k] + j % cap[k]] = V[k]


@njit()
def _near(p0, p00, half, T0, ua, ub):
    """(w_a, w_b) of a piece from u_b to u_a on the exact kernel over u < T0 (times r)."""
    P0x, P00x = _p(p0, p00, half, ub)
    y = ua if ua < T0 else T0
    P0y, P00y = _p(p0, p00, half, y)
    return _near_w(P0x, P00x, P0y, P00y, ua, ub, y)


@njit()
def _near_w(P0x, P00x, P0y, P00y, ua, ub, y):
    """``_near`` from P0, P00 at u_b (x) and at y = min(u_a, T0)."""
    d = ua - ub
    d00 = P00y - P00x
    return ((y - ub) * P0y - d00) / d, ((ua - y) * P0y - d * P0x + d00) / d


@njit()
def _slab(lam, elo, ua, ub, lo, hi, rk, ea, eb):
    """ea_p, eb_p: int e^{lam_p u} (u - u_b)/d du / r and int e^{lam_p u} (u_a - u)/d du / r
    over the part of the piece in [lo, hi] (elo_p = e^{lam_p lo})."""
    d = ua - ub
    x = ub if ub > lo else lo
    y = ua if ua < hi else hi
    L = y - x
    ca = (x - ub) / d                        # the weight of Va at x
    cb = (ua - x) / d
    for p in range(lam.size):
        z = lam[p] * x
        if x == lo:
            ex = elo[p] * L / rk
        elif z.real < -NEGLIGIBLE:
            ea[p] = 0.0
            eb[p] = 0.0
            continue
        else:
            ex = np.exp(z) * L / rk
        f1, f2 = _phi(lam[p] * L)
        ea[p] = ex * (ca * f1 + (L / d) * f2)
        eb[p] = ex * (cb * f1 - (L / d) * f2)


@njit()
def _slab_chain(lam, il, il2, ex, known, x, L, d, ca, cb, rk, ea, eb):
    """``_slab``'s weights of a piece whose part in the slab starts at x and is L long, from
    ex_p = e^{lam_p x} (then set to e^{lam_p (x + L)}, the next older piece's start):
    e^{lam_p L} is ``known[p]`` when given (an array), else computed; 1 / lam_p and
    1 / lam_p^2 come as ``il``, ``il2``, so no complex division is left per term."""
    Ld = L / d
    for p in range(lam.size):
        if lam[p].real * x < -NEGLIGIBLE:      # e^{lam x} below 2e-22, and beyond x too
            ea[p] = 0.0
            eb[p] = 0.0
            ex[p] = 0.0
            continue
        z = lam[p] * L
        if z.real < -NEGLIGIBLE:
            e = known[p] if known.size else 0.0
            f1 = -il[p] / L
            f2 = il2[p] / (L * L)
        elif abs(z) < 1e-3:
            z2 = z * z
            e = known[p] if known.size else 1.0 + z * (1.0 + z / 2.0 * (1.0 + z / 3.0 * (1.0 + z / 4.0 * (1.0 + z / 5.0))))
            f1 = 1.0 + z / 2.0 + z2 / 6.0 + z2 * z / 24.0 + z2 * z2 / 120.0
            f2 = 0.5 + z / 3.0 + z2 / 8.0 + z2 * z / 30.0 + z2 * z2 / 144.0
        else:
            e = known[p] if known.size else np.exp(z)
            f1 = (e - 1.0) * il[p] / L
            f2 = (e * (z - 1.0) + 1.0) * il2[p] / (L * L)
        w = ex[p] * (L / rk)
        ea[p] = w * (ca * f1 + Ld * f2)
        eb[p] = w * (cb * f1 - Ld * f2)
        ex[p] = ex[p] * e


@njit()
def _decayed_weights(il, il2, elo, T0, rk, d, ea, eb):
    """ea_p, eb_p of a piece d = r h long whose every term decayed below e^-NEGLIGIBLE over
    it (``_slab_chain``'s negligible branch on its part (T0, d) alone); 1 / lam_p and
    1 / lam_p^2 come as ``il``, ``il2``."""
    ca = T0 / d
    cb = (d - T0) / d
    for p in range(il.size):
        ea[p] = elo[p] / rk * (-ca * il[p] + il2[p] / d)
        eb[p] = elo[p] / rk * (-cb * il[p] - il2[p] / d)


@njit()
def _write_out_one(k, r, il, il2, elo, T0, ring, off, cap, hring, hcap, n, SR, SI, ea, eb):
    """Write out the state of lazy mode k: the closed form of its last step's piece."""
    rk = r[k]
    ck = cap[k]
    _decayed_weights(il, il2, elo, T0, rk, rk * hring[(n - 1) % hcap], ea, eb)
    Va = ring[off[k] + (n - 1) % ck]
    Vb = ring[off[k] + n % ck]
    for p in range(il.size):
        SR[k, p] = ea[p] * Va.real + eb[p] * Vb.real
        SI[k, p] = ea[p] * Va.imag + eb[p] * Vb.imag


@njit()
def _write_out(r, lam, T0, ring, off, cap, hring, hcap, n, SR, SI, lazy):
    """Write out the states of every lazy mode."""
    elo = np.exp(lam * T0)
    il = 1.0 / lam
    il2 = il * il
    ea = np.empty(lam.size, dtype=np.complex128)
    eb = np.empty(lam.size, dtype=np.complex128)
    for k in range(r.size):
        if lazy[k]:
            _write_out_one(k, r, il, il2, elo, T0, ring, off, cap, hring, hcap, n, SR, SI, ea, eb)
            lazy[k] = 0


@njit()
def _prepare(r, lam, coef, p0, p00, half, T0, ring, off, cap, hring, hcap, first, n, h, SR, SI, A, B, kR, kI, sB,
             gh, glast, last_ok, lazy, collapse, decay, cached, run, cL, cw, cwo, ce0, cs, cg):
    """I(t + h) = A + B V(t + h) per mode (module docstring); ``gh`` gets e^{lam_p r h} of
    this step, ``glast`` holds that of the step before when ``last_ok``. A mode whose every
    term decays below e^-NEGLIGIBLE over the step (r h ``decay`` >= NEGLIGIBLE, ``decay``
    the slowest term's rate; 0: never) takes it in closed form, marked in ``collapse``: its
    window is the step's own piece, its old states and older pieces contribute nothing.
    A ``lazy`` mode's state (module docstring) is written out before a step that needs it."""
    M = r.size
    P = lam.size
    elo = np.exp(lam * T0)
    emlo = np.exp(-lam * T0)
    il = 1.0 / lam
    il2 = il * il
    ea = np.empty(P, dtype=np.complex128)
    eb = np.empty(P, dtype=np.complex128)
    ex = np.empty(P, dtype=np.complex128)      # e^{lam_p x} at the start x of a slab piece
    eL = np.empty(P, dtype=np.complex128)      # e^{lam_p L} of the newest piece's part in the slab
    none = np.empty(0, dtype=np.complex128)
    P0_0, P00_0 = _p(p0, p00, half, 0.0)       # at the window's ends, the same for every mode
    P0_T, P00_T = _p(p0, p00, half, T0)
    # the closed form of a collapsed mode: the tail's sums over the terms of its weights
    S1 = 0.0
    S2 = 0.0
    for p in range(P):
        S1 += 2.0 * (coef[p] * elo[p] * il[p]).real
        S2 += 2.0 * (coef[p] * elo[p] * il2[p]).real
    for k in range(M):
        rk = r[k]
        acc = 0.0 + 0.0j
        bk = 0.0
        ck = cap[k]
        base = off[k]
        if decay > 0.0 and rk * h * decay >= NEGLIGIBLE:
            collapse[k] = 1
            d = rk * h
            wa, wb = _near_w(P0_0, P00_0, P0_T, P00_T, d, 0.0, T0)
            Va = ring[base + n % ck]
            A[k] = wa * Va / rk + Va * ((-(T0 / d) * S1 + S2 / d) / rk)
            B[k] = wb / rk + (-((d - T0) / d) * S1 - S2 / d) / rk
            continue
        collapse[k] = 0
        last_ok_k = last_ok
        if lazy[k]:
            _write_out_one(k, r, il, il2, elo, T0, ring, off, cap, hring, hcap, n, SR, SI, ea, eb)
            lazy[k] = 0
            last_ok_k = False           # its last step's e^{lam r h} were not kept
        if cached and run >= cL[k] - 1 and n - first[k] >= cL[k] - 1:
            # every piece of the window is a step of h: the weights of the last uniform run
            o = cwo[k]
            i = n % ck                              # the ring's slot of step end n + 1 - e
            for e in range(1, cL[k] + 1):
                acc += cw[o + e] * ring[base + i]
                i = i - 1 if i > 0 else ck - 1
            bk = cw[o]
            for p in range(P):
                gh[k, p] = cg[k, p]
                kR[k, p] = cg[k, p] * SR[k, p]
                kI[k, p] = cg[k, p] * SI[k, p]
                sB[k, p] = 0.0
            for i in range(4):
                e = ce0[k] + i
                if e > cL[k]:
                    break
                if e == 0:
                    for p in range(P):
                        sB[k, p] += cs[k, i, p]
                else:
                    V = ring[base + (n + 1 - e) % ck]
                    for p in range(P):
                        kR[k, p] += cs[k, i, p] * V.real
                        kI[k, p] += cs[k, i, p] * V.imag
        else:
            lo = T0
            hi = T0 + rk * h
            for p in range(P):
                z = lam[p] * (rk * h)
                # e^z, and the newest piece's part in the slab, (T0, r h) when it crosses T0:
                # e^{lam (r h - T0)}, each where it is not negligible
                g = np.exp(z) if z.real > -NEGLIGIBLE + lam[p].real * T0 else 0.0
                eL[p] = g * emlo[p]
                if z.real < -NEGLIGIBLE:
                    g = 0.0
                gh[k, p] = g
                kR[k, p] = g * SR[k, p]
                kI[k, p] = g * SI[k, p]
                sB[k, p] = 0.0
                ex[p] = elo[p]                  # the slab starts at u = T0
            # the pieces, newest first: piece j runs from step end j to j + 1 (j = n: the step);
            # P0, P00 at a piece's older end are those at the next older piece's newer end;
            # the slab's pieces follow one another, so each starts where the last one ended
            ub = 0.0
            P0x, P00x = P0_0, P00_0
            i = n % ck                  # the ring's slot of step end j
            ih = n % hcap               # the slot of step j's length
            Vb = 0.0 + 0.0j
            for j in range(n, first[k] - 1, -1):
                hj = h if j == n else hring[ih]
                ua = ub + rk * hj
                Va = ring[base + i]
                if ub < T0:                                   # near: the exact kernel
                    if ua < T0:
                        y = ua
                        P0y, P00y = _p(p0, p00, half, y)
                    else:
                        y = T0
                        P0y, P00y = P0_T, P00_T
                    wa, wb = _near_w(P0x, P00x, P0y, P00y, ua, ub, y)
                    P0x, P00x = P0y, P00y
                    acc += (wa * Va + wb * Vb) / rk
                    if j == n:
                        bk += wb / rk
                if ua > lo and ub < hi:                        # the slab that crossed u = T0
                    from_lo = not ub > lo
                    to_hi = not ua < hi
                    x = lo if from_lo else ub
                    y = hi if to_hi else ua
                    d = ua - ub
                    # e^{lam L} of the part known already: all of the slab (r h), the newest
                    # piece's part (r h - T0), the step before's whole (its own e^{lam r h}) or
                    # its part up to hi (T0)
                    if from_lo and to_hi:
                        known = gh[k]
                    elif from_lo and j == n:
                        known = eL
                    elif j == n - 1 and not from_lo and (to_hi or last_ok_k):
                        known = elo if to_hi else glast[k]
                    else:
                        known = none
                    _slab_chain(lam, il, il2, ex, known, x, y - x, d, (x - ub) / d, (ua - x) / d, rk, ea, eb)
                    for p in range(P):
                        kR[k, p] += ea[p] * Va.real + eb[p] * Vb.real
                        kI[k, p] += ea[p] * Va.imag + eb[p] * Vb.imag
                        if j == n:
                            sB[k, p] += eb[p]
                if ua >= hi:
                    break
                ub = ua
                Vb = Va
                i = i - 1 if i > 0 else ck - 1
                ih = ih - 1 if ih > 0 else hcap - 1
        tail = 0.0 + 0.0j
        tb = 0.0
        for p in range(P):
            c = coef[p]
            tail += 2.0 * (c * kR[k, p]).real + 2.0j * (c * kI[k, p]).real
            tb += 2.0 * (c * sB[k, p]).real
        A[k] = acc + tail
        B[k] = bk + tb


@njit()
def _uniform_pieces(r, T0, h, cL):
    """The pieces of steps all h long that a mode's window and slab reach (as _prepare walks them)."""
    for k in range(r.size):
        rk = r[k]
        hi = T0 + rk * h
        ub = 0.0
        m = 0
        while True:
            ua = ub + rk * h
            m += 1
            if ua >= hi:
                break
            ub = ua
        cL[k] = m


@njit()
def _uniform_weights(r, lam, p0, p00, half, T0, h, cL, cw, cwo, ce0, cs, cg):
    """The weights of a window of steps all h long, per end (e = 0: the step's own end)."""
    P = lam.size
    ea = np.empty(P, dtype=np.complex128)
    eb = np.empty(P, dtype=np.complex128)
    elo = np.exp(lam * T0)
    for k in range(r.size):
        rk = r[k]
        lo = T0
        hi = T0 + rk * h
        o = cwo[k]
        for e in range(cL[k] + 1):
            cw[o + e] = 0.0
        for p in range(P):
            cg[k, p] = np.exp(lam[p] * rk * h)
            for i in range(4):
                cs[k, i, p] = 0.0
        ce0[k] = -1
        ub = 0.0
        for lag in range(cL[k]):
            ua = ub + rk * h
            if ub < T0:
                wa, wb = _near(p0, p00, half, T0, ua, ub)
                cw[o + lag + 1] += wa / rk
                cw[o + lag] += wb / rk
            if ua > lo and ub < hi:
                if ce0[k] < 0:
                    ce0[k] = lag
                _slab(lam, elo, ua, ub, lo, hi, rk, ea, eb)
                for p in range(P):
                    cs[k, lag + 1 - ce0[k], p] += ea[p]
                    cs[k, lag - ce0[k], p] += eb[p]
            ub = ua


@njit()
def _drop(r, T0, hring, hcap, first, n, cap):
    """Forget the pieces wholly past u = T0; the first mode whose ring would overflow, or -1."""
    over = -1
    for k in range(r.size):
        u = 0.0
        j = n - 1
        lim = T0 / r[k]
        while j >= first[k]:
            u += hring[j % hcap]
            if u >= lim:
                break
            j -= 1
        if j > first[k]:
            first[k] = j
        if n - first[k] + 1 > cap[k] and over < 0:
            over = k
    return over
