"""Exponential-sum history engine: cost and memory per mode independent of the run length.

The kernel K (C or Z, see :mod:`cracklab.elastic.weights`) is represented, for T = q c_s t in
[T0, T_end], by ``K(T) ~ 2 Re sum_p c_p exp(lambda_p T)`` (conjugate pairs, Re lambda_p < 0,
absolute error <= 1e-5 of the kernel's scale (5e-6 for mode II); :mod:`cracklab.history.fit`).
T0 = ``ENGINE_T0`` = 4; T_end covers the run (gamma_max times its number of steps, rounded up
to a half decade; the whole half line when the length is not given): the kernel is never
truncated inside the run.  For a mode with gamma = q c_s dt the weights split at
J0 = ceil(T0 / gamma) (+1 for the product rule, whose weight w_k reaches back to (k - 1) gamma;
rounded up to a small set of levels, and >= lag + 1):

* k = j + lag < J0: the exact weights (:func:`cracklab.elastic.weights.convolution_weights`, or
  :func:`cracklab.elastic.weights.product_weights`) against a ring buffer of the mode's recent values
  ("direct taps");
* k >= J0: the weight of the rule applied to the fitted kernel,
  ``w_k = 2 Re sum_p c_p f_p rho_p^(k - shift)`` with ``rho_p = exp(lambda_p gamma)`` and the
  rule factor f_p (discretized 1, trapezoid (1 + rho)/2, Simpson, exact (rho - 1)/(lambda gamma),
  product ((rho - 1)/(lambda gamma))^2 with shift 1), i.e. eqs. (45)-(47) (or the product
  integration of docs/reference/stability.md) applied to each exponential exactly.  The tail sum is
  carried by one complex state per term and per real input (Re x and Im x):
  ``s_p(n) = rho_p s_p(n-1) + x_{n-Jd}``, ``S_tail = Re sum_p e_p s_p``.

Backends (``CRACKLAB_EXP_BACKEND``): "numba" (default) runs the compiled loops of
:mod:`cracklab.history.blocked`: every mode keeps at least 8 direct taps, so the states
of a mode can be advanced 8 steps at a time from inputs already in its ring (one eighth
of the modes per step, staggered), their tail sums kept for the next 8 steps; "numpy"
runs the per-step recursion vectorised over the modes.  Both give the same sums to
round-off (docs/reference/fast_engine.md).  The numba backend with two or more threads overlaps:
push leaves the next step's advance due, :meth:`ExponentialEngine.launch` starts it on a
worker thread, and the caller's transforms and interface law run meanwhile (the next push
waits for it; the same numbers to the bit, ``CRACKLAB_OVERLAP=0`` switches it off).  The product
rule's start term E_0(n) (on the first velocity) is exact for n < J0 and fitted beyond.

Memory per mode is fixed at construction (2 P complex states, Jd >= 8 buffered values and
tap weights, 8 tail sums).  Modes with gamma = 0 (q = 0) get exact weights K(0) for all k (a running sum).
See docs/reference/fast_engine.md.

``window`` (a truncated history) is not supported: the engine keeps the whole history by
construction; use the direct engine for windowed runs.
"""
from __future__ import annotations

import math
import os
import time

import numpy as np

from ..errors import InputError
from ..jit import njit
from ..elastic.kernels import FACE_KERNELS
from ..elastic.modes import gammas_sample, mode_gamma, modes
from ..elastic.weights import FORMULATIONS, RULES, convolution_weights, product_taps
from . import tables
from .base import BLOCK as _BLOCK, register
from .direct import deliver
from .fit import DEFAULT_T0, get_fit

__all__ = ["ExponentialEngine", "backend_choice", "direct_taps", "exact_weights", "worker"]

# levels for the number of direct taps: grouping modes by level keeps the
# number of per-step numpy calls small (a mode gets at most ~25 % extra taps)
_LEVELS = np.array(sorted({1, 2, 3, 4, 5, 6, 7, 8} | {int(round(2 ** (k / 4))) for k in range(12, 80)}))
_RESYNC = 512
#: start of the fitted representation used by the engine (exact taps for T < ENGINE_T0)
ENGINE_T0 = 4.0
_SUPPORTED_RULES = ("discretized", "trapezoid", "simpson", "exact", "product")  # recompute the powers of weight() exactly every so many calls


def direct_taps(gamma, lag=0, T0=DEFAULT_T0, extra=0, minimum=1):
    """Number of direct taps Jd (>= ``minimum``) for each gamma: the exact weights w_lag .. w_{lag+Jd-1}.

    J0 = Jd + lag is ceil(T0 / gamma) + extra (at least lag + 1), with Jd rounded up to one
    of a few levels (``_LEVELS``); gamma = 0 gives Jd = ``minimum``.  ``extra`` = 1 for the
    product rule, whose weight w_k integrates the kernel from (k - 1) gamma.
    """
    g = np.asarray(gamma, dtype=float)
    pos = g > 0
    with np.errstate(divide="ignore"):
        j0 = np.where(pos, np.ceil(T0 / np.where(pos, g, 1.0) * (1 - 1e-12)) + extra, 1.0)
    jd = np.maximum(np.maximum(j0, lag + 1) - lag, minimum)
    i = np.searchsorted(_LEVELS, jd)
    big = i >= _LEVELS.size
    out = np.where(big, jd, _LEVELS[np.minimum(i, _LEVELS.size - 1)])
    return np.where(pos, out, minimum).astype(np.int64)


def _expm1_over(z):
    """(e^z - 1) / z, exact at z = 0."""
    small = np.abs(z) < 1e-8
    zs = np.where(small, 1.0, z)
    return np.where(small, 1.0 + 0.5 * z, np.expm1(zs) / zs)


def _rule_factor(rule, z, simpson_n=4):
    """Cell factor f(z), z = lambda gamma: weight of exp(lambda T) on cell k is f rho^(k - shift).

    ``shift`` is :data:`_SHIFT` of the rule: 1 for the product rule, whose hat function
    reaches back one cell (f = ((e^z - 1)/z)^2, i.e. (e^z - 2 + e^-z)/z^2 times e^z,
    written so that it never overflows), 0 otherwise.
    """
    if rule == "product":
        return _expm1_over(z) ** 2
    if rule == "discretized":
        return np.ones_like(z)
    if rule == "trapezoid":
        return 0.5 * (1.0 + np.exp(z))
    if rule == "simpson":
        n = simpson_n
        acc = 1.0 + np.exp(z)
        for m in range(1, n):
            acc = acc + (4.0 if m % 2 else 2.0) * np.exp(z * (m / n))
        return acc / (3.0 * n)
    if rule == "exact":  # mean of exp(lambda T) over the cell, (e^z - 1)/z
        return _expm1_over(z)
    raise ValueError(f"the exponential engine does not support rule {rule!r} "
                     f"(supported: {', '.join(_SUPPORTED_RULES)})")


_SHIFT = {"product": 1}


def _start_factor(z):
    """E_0 of the product rule for exp(lambda T): -(e^z - 1 - z)/z^2 (times rho^n)."""
    small = np.abs(z) < 1e-4
    zs = np.where(small, 1.0, z)
    return -np.where(small, 0.5 + z / 6.0 + z * z / 24.0, (np.expm1(zs) - zs) / (zs * zs))


def exact_weights(kernel, g, k, *, nu, rule, formulation, part="lag"):
    """The exact weights w_k (or, with part "start0", the product rule's E_0(k)) of the engine's
    direct taps: :func:`cracklab.elastic.weights.product_weights` (order 1) for the product rule,
    :func:`cracklab.elastic.weights.convolution_weights` otherwise."""
    if rule == "product":
        from ..elastic.weights import product_weights

        return product_weights(kernel, g, np.asarray(k, dtype=np.int64), nu=nu, order=1, part=part)
    return convolution_weights(kernel, g, k, nu=nu, rule=rule, formulation=formulation)


def _power_sum_numpy(pw, rho, coef, factor, out):
    pw *= rho
    out[:] = factor * np.einsum("up,up->u", coef, pw).real


def _make_power_sum():
    """pw *= rho; out = factor Re sum_p coef pw, per unique gamma (numba, numpy fallback)."""
    try:
        import numba
    except Exception:  # pragma: no cover
        return _power_sum_numpy

    @njit(parallel=True)
    def power_sum(pw, rho, coef, factor, out):
        for u in numba.prange(pw.shape[0]):
            acc = 0.0
            for p in range(pw.shape[1]):
                v = pw[u, p] * rho[u, p]
                pw[u, p] = v
                acc += coef[u, p].real * v.real - coef[u, p].imag * v.imag
            out[u] = factor * acc

    return power_sum


def _power_sum(pw, rho, coef, factor, out):
    global _POWER_SUM
    if _POWER_SUM is None:
        _POWER_SUM = _make_power_sum() if backend_choice() != "numpy" else _power_sum_numpy
    _POWER_SUM(pw, rho, coef, factor, out)


_POWER_SUM = None


def _set_threads(threads):
    import numba

    numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))


_BLOCKED = None
_ONE = np.ones(1)
_POOL = None


def _overlap_env():
    return os.environ.get("CRACKLAB_OVERLAP", "1") != "0"


def worker():
    """The process's history worker thread (one; recreated in a forked child)."""
    global _POOL
    if _POOL is None or _POOL[0] != os.getpid():
        from concurrent.futures import ThreadPoolExecutor

        _POOL = (os.getpid(), ThreadPoolExecutor(max_workers=1, thread_name_prefix="cracklab-history"))
    return _POOL[1]


def _blocked():
    """The compiled kernels (:mod:`cracklab.history.blocked`), or None if numba is unavailable."""
    global _BLOCKED
    if _BLOCKED is None:
        try:
            from . import blocked
        except Exception:  # pragma: no cover - no numba
            blocked = False
        _BLOCKED = blocked
    return _BLOCKED or None


def backend_choice():
    """The backend new engines use: "numba" (the default when numba imports) or "numpy"
    (``CRACKLAB_EXP_BACKEND`` forces one)."""
    env = os.environ.get("CRACKLAB_EXP_BACKEND", "").strip().lower()
    if env in ("numpy", "numba"):
        return env
    return "numba" if _blocked() is not None else "numpy"


# ----------------------------------------------------------------------------- engine
#: doubles of temporaries per exact tap weight while they are computed (half the direct
#: engine's: its states are not yet resident; solver/budget.py)
_TAP_TEMPS = {"product": 110, "other": 12}


@register
class ExponentialEngine:
    """History engine with O(P) work and memory per mode and step (see the module docstring).

    Same constructor and methods as :class:`cracklab.history.direct.DirectEngine`:
    ``push(x) -> S_n`` with ``S_n = sum_{j>=0} w_{j+lag} x_{n-j}`` and ``weight(j) = w_{j+lag}``
    (the weight the engine actually applies: exact for j + lag < J0, from the fit beyond).
    ``chunk`` is accepted for compatibility and ignored.  The backend is the fused numba
    loop when numba is importable, numpy otherwise; ``CRACKLAB_EXP_BACKEND=numpy|numba``
    forces one.
    """

    name = "exponential"
    windowed = False        # it keeps the whole history
    flat_cost = True
    extra_at_build = True   # memory's extra: the exact taps and fits while it is built

    @classmethod
    def memory(cls, scene, kernel, scheme, material, shared=False) -> tuple[int, int]:
        """(bytes held, extra bytes while it is built) of one exponential engine (numba
        backend) of a half space of ``material`` over a run of ``scene``; ``shared``: an
        engine of the same kernel and material is built before it in the run (its exact
        taps are then that one's, history/tables.py, and so is its start-up weight E_0:
        the bimaterial face's coupling channels)."""
        grid = scene.grid
        M = modes(grid)
        g, weight = gammas_sample(grid, scene.dt, material.cs)
        gmax = mode_gamma(grid.q_max(), material.cs, scene.dt)
        T_end = None if gmax == 0 else gmax * (scene.nsteps + 2)
        pairs = get_fit(kernel, material.nu, scheme.convolves, T0=ENGINE_T0, T_end=T_end).pairs
        jd = direct_taps(g, scheme.lag, ENGINE_T0, extra=_SHIFT.get(scheme.rule, 0), minimum=_BLOCK)
        long_taps = float(jd[jd > _BLOCK].sum()) * weight          # modes with their own ring
        distinct = min(M, int(np.unique(np.round(g, 12)).size * weight))
        taps = float(jd.sum()) / jd.size * distinct         # exact weights, per distinct gamma
        product = scheme.rule == "product"
        held = (M * pairs * 8 * 8                 # 4 state arrays, 4 recursion tables (re, im)
                + M * (2 * _BLOCK * 16 + _BLOCK * 8 + 2 * 8)    # last inputs, tail sums, taps, indices
                + M * 2 * 8                       # gamma and each mode's distinct gamma
                + long_taps * 24
                + distinct * pairs * 16 * (2 if product else 1))  # the fit's factors per distinct gamma (and E_0's)
        if not shared:      # the exact taps (and E_0's), memoised by kernel and gammas
            held += taps * 8 * (2 if product else 1)
        if product and not shared:
            # E_0 as the run goes: powers and ratios per distinct gamma, two buffers per mode
            held += 2 * distinct * pairs * 16 + 2 * M * 8
        temps = _TAP_TEMPS["product" if scheme.rule == "product" else "other"]
        building = max(distinct * pairs * 16 * 4 + M * 8 * 6 + M * pairs * 8, taps * 8 * temps)
        return int(held), int(building)

    def __init__(self, *, kernel, gamma, nu, rule="trapezoid", formulation="displacement",
                 lag=0, window=None, chunk=256, threads=1, nsteps=None):
        if window is not None:
            raise InputError("numerics.window",
                             "the exponential history engine keeps the whole (untruncated) history and "
                             "does not support a window; use engine='direct' for a windowed history")
        if rule not in _SUPPORTED_RULES:
            raise ValueError(f"rule must be one of {_SUPPORTED_RULES}, got {rule!r}")
        if formulation not in FORMULATIONS:
            raise ValueError(f"formulation must be one of {FORMULATIONS}, got {formulation!r}")
        if isinstance(lag, bool) or int(lag) != lag or lag < 0:
            raise ValueError(f"lag must be a non-negative integer, got {lag!r}")
        self.kernel, self.nu, self.rule, self.formulation = kernel, nu, rule, formulation
        self.window = None
        self.lag = int(lag)
        self.shape = np.shape(gamma)
        self.gamma = np.asarray(gamma, dtype=float).ravel()
        if not np.all(np.isfinite(self.gamma)) or np.any(self.gamma < 0):
            raise ValueError("gamma must be finite and >= 0")
        gmax = float(self.gamma.max()) if self.gamma.size else 0.0
        # the run needs the kernel on [T0, gamma_max (nsteps + 2)] only (None: the whole half line)
        T_end = None if nsteps is None or gmax == 0 else gmax * (int(nsteps) + 2)
        self.fit = get_fit(kernel, nu, formulation, T0=ENGINE_T0, T_end=T_end)
        self._n_max = math.inf if not math.isfinite(self.fit.T_end) or gmax == 0 else self.fit.T_end / gmax
        self.T0 = self.fit.T0
        self.pairs = self.fit.pairs
        self.backend = backend_choice()
        self.threads = int(threads or 1)
        self.n = 0
        # two or more threads: the states are advanced on a worker thread while the caller
        # goes on (transforms, interface law) between pushes
        self.overlap = self.backend == "numba" and self.threads >= 2 and _overlap_env()
        # the taps 1 <= j < 8 of the next step go with the advance (to the worker) in the
        # velocity-based schemes, whose caller does two transforms or more per pushed channel
        # besides the law: the caller's thread is the longer one there; the displacement
        # scheme's one transform pair per push is about as long as the advance, so its taps
        # stay with the caller (docs/studies/performance.md)
        self.taps_ahead = formulation != "displacement"
        self._pending = None  # the worker's advance (a Future)
        self._due = None      # the step whose advance push left for launch()
        #: the caller's share of each eighth's advance, in [0, 1/2] (see ``balance``; set by
        #: :meth:`rebalance` after every step)
        self.share = 0.0
        self._cut = None       # (step, first mode of the caller's share) of the pending advance
        #: the worker's (start, end) of its last advance (time.perf_counter seconds; None before one)
        self.worker_times = None
        self._scale_src = self._scale_flat = None

        ug, inv = np.unique(self.gamma, return_inverse=True)
        self._ug, self._inv = ug, inv
        self._shift = shift = _SHIFT.get(rule, 0)
        # at least BLOCK taps: the compiled loop advances the states BLOCK steps ahead (blocked.py)
        jd_u = direct_taps(ug, self.lag, self.T0, extra=shift, minimum=_BLOCK)
        self._jd_u = jd_u
        self._j0_u = jd_u + self.lag  # first fitted weight index
        lam, c = self.fit.lam, self.fit.coef
        z = ug[:, None] * lam[None, :]
        rho_u = np.exp(z)
        cf_u = c[None, :] * _rule_factor(rule, z)  # weight of cell k: 2 Re sum cf rho^(k - shift)
        e_u = 2.0 * cf_u * np.exp(z * (self._j0_u[:, None] - shift))  # S_tail = Re sum_p e_p s_p
        zero = ug == 0
        # q = 0: every weight beyond the first is K(0)
        exact = dict(nu=nu, rule=rule, formulation=formulation)
        self._exact = exact
        self._k0_zero = k0 = float(exact_weights(kernel, 0.0, self.lag + 1, **exact))
        if np.any(zero):
            # one running-sum state, the others switched off
            rho_u[zero] = 0.0
            rho_u[zero, 0] = 1.0
            e_u[zero] = 0.0
            e_u[zero, 0] = k0
        self._cf_u = cf_u
        # exact direct weights w_{lag+j}, j < Jd, per unique gamma, flattened
        self._wstart_u = np.zeros(ug.size, dtype=np.int64)
        if ug.size:
            self._wstart_u[1:] = np.cumsum(jd_u)[:-1]
        uu = np.repeat(np.arange(ug.size), jd_u)
        jj = np.arange(uu.size) - self._wstart_u[uu]
        # the exact taps, shared by every engine on the same gammas (history/tables.py)
        key = ("exponential-taps", kernel, tables.digest(ug), tables.digest(jd_u), self.lag, float(nu), rule,
               formulation)
        if rule == "product" and kernel in FACE_KERNELS:
            # a face kernel's lag weights and start-up term E_0(n) (exact for n < J0, fitted
            # beyond) from one pass over the cells (the pair's kernels keep the weights of
            # product_weights to the bit: one-material runs are unchanged)
            both = tables.memoised(key + ("lag+start0",), lambda: np.stack(
                product_taps(kernel, ug, jd_u, self.lag, nu=nu)))
            self._wflat, self._e0flat = both[0], both[1]
        else:
            self._wflat = tables.memoised(key + ("lag",), lambda: np.asarray(
                exact_weights(kernel, ug[uu], jj + self.lag, **exact), dtype=float).ravel())
            if rule == "product":  # start-up term E_0(n): exact for n < J0, fitted beyond
                self._e0flat = tables.memoised(key + ("start0",), lambda: np.asarray(
                    exact_weights(kernel, ug[uu], jj + self.lag, part="start0", **exact), dtype=float).ravel())
        if rule == "product":
            self._e0c = 2.0 * c[None, :] * _start_factor(z)
            self._e0c[zero] = 0.0
            self._e0pow = None
            self._e0_zero = None
        # start_weight's values: the last computed (step _e0next_n) and its two buffers
        self._e0next = self._e0next_n = self._e0bufs = None
        # weight() cache: powers rho^k for the last k asked
        self._wk = None
        self._wpow = None
        self._wrho = None
        self._wcalls = 0

        m = self.gamma.size
        if self.backend == "numba":
            self._setup_blocked(rho_u, e_u)
        else:
            # permute the modes so that each level of Jd is a contiguous block
            jd = jd_u[inv]
            perm = np.argsort(jd, kind="stable")
            self._perm = perm
            jdp = jd[perm]
            self._groups = []
            edges = np.flatnonzero(np.diff(jdp)) + 1
            bounds = np.concatenate([[0], edges, [m]]).astype(int)
            for o0, o1 in zip(bounds[:-1], bounds[1:]):
                if o1 <= o0:
                    continue
                J = int(jdp[o0])
                ui = inv[perm[o0:o1]]
                wd = self._wflat[self._wstart_u[ui][:, None] + np.arange(J)[None, :]]  # (Mg, J)
                # reversed, interleaved re/im: buf[p + 1 : p + 1 + J] holds x_{n-J+1} .. x_n
                wf = np.ascontiguousarray(np.repeat(wd[:, ::-1].T, 2, axis=1))
                buf = np.zeros((2 * J, o1 - o0), dtype=complex)
                self._groups.append((o0, o1, J, buf, wf))
            self._rho = np.ascontiguousarray(rho_u[inv[perm]])[:, None, :]  # (M, 1, Ph)
            e = e_u[inv[perm]]
            ef = np.empty((m, 2 * self.pairs))
            ef[:, 0::2] = e.real
            ef[:, 1::2] = -e.imag
            self._ef = ef
            self._sig = np.zeros((m, 2, self.pairs), dtype=complex)
            self._xin = np.zeros(m, dtype=complex)
            self._xp = np.zeros(m, dtype=complex)
            self._S = np.zeros(m, dtype=complex)

    def _setup_blocked(self, rho_u, e_u):
        """Tables and states of the compiled loops (blocked.py).

        taps sweeps the modes in their natural order over tap-major rows (the last 8 inputs
        R, weights W, tail sums F: row j or slot k, then the mode); advance works through
        one eighth of the modes per step, in the same order (the states, recursion factors
        and coefficients a row per mode); modes with more than 8 taps keep a ring of their
        own (L, circular), from which advance takes their states' inputs and taps j >= 8."""
        m, jd_u, inv = self.gamma.size, self._jd_u, self._inv
        # advance's eighths are eighths of the natural order
        self._bounds = [m * g // _BLOCK for g in range(_BLOCK + 1)]
        jd = jd_u[inv]
        self._jd = np.ascontiguousarray(jd, dtype=np.int64)
        # the exact weights w_0 .. w_7 of every mode, row by row
        self._W = np.ascontiguousarray(self._wflat[self._wstart_u[inv][None, :] + np.arange(_BLOCK)[:, None]])
        self._R = np.zeros((_BLOCK, m), dtype=complex)   # x_k in row k % 8
        self._F = np.zeros((_BLOCK, m), dtype=complex)   # tail sum of step n in row n % 8
        # modes with more taps: their own circular rings (x_k in slot k mod Jd; Jd real parts,
        # then Jd imaginary parts) and weights
        lm = np.flatnonzero(jd > _BLOCK).astype(np.int64)
        ljd = np.ascontiguousarray(jd[lm], dtype=np.int64)
        lstart = np.zeros(lm.size, dtype=np.int64)
        if lm.size:
            lstart[1:] = np.cumsum(2 * ljd)[:-1]
        wl = np.empty(int(ljd.sum()))
        for J in np.unique(ljd):
            sel = np.flatnonzero(ljd == J)
            wl[lstart[sel][:, None] // 2 + np.arange(J)[None, :]] = \
                self._wflat[self._wstart_u[inv[lm[sel]]][:, None] + np.arange(J)[None, :]]
        self._wl = wl
        self._L = np.zeros(int(2 * ljd.sum()))
        self._lstart = np.zeros(m, dtype=np.int64)
        self._lstart[lm] = lstart
        # the recursion factors and coefficients of every mode (not per distinct gamma): advance
        # then streams every array in order; a table per gamma, read in the modes' order, costs
        # a cache line per mode and array (docs/reference/fast_engine.md)
        self._rr, self._ri = (np.ascontiguousarray(a[inv]) for a in (rho_u.real, rho_u.imag))
        self._er, self._ei = (np.ascontiguousarray(a[inv]) for a in (e_u.real, e_u.imag))
        self._states = [np.zeros((m, self.pairs)) for _ in range(4)]  # Re and Im of s_p for Re x, then Im x

    # ------------------------------------------------------------------ public
    @property
    def nbytes(self) -> int:
        """Bytes held by the per-mode state (buffers, weights, recursion factors, states)."""
        if self.backend == "numba":
            arrs = [self._R, self._W, self._L, self._wl, self._wflat, self._rr, self._ri, self._er, self._ei,
                    self._F, self._jd, self._lstart, *self._states]
        else:
            arrs = [self._wflat, self._rho, self._ef, self._sig, self._xin, self._xp, self._S]
            for g in self._groups:
                arrs += [g[3], g[4]]
        return int(sum(a.nbytes for a in arrs))

    def state_shapes(self) -> list:
        """Shapes of every state array (for checking that nothing grows with n)."""
        if self.backend == "numba":
            arrs = [self._R, self._L, self._rr, self._er, self._F, *self._states]
        else:
            arrs = [self._rho, self._ef, self._sig] + [g[3] for g in self._groups]
        return [a.shape for a in arrs]

    def _state_arrays(self) -> dict:
        if self.backend == "numba":
            self._join()
            out = {"R": self._R, "L": self._L, "F": self._F}
            out.update({f"s{k}": a for k, a in enumerate(self._states)})
            return out
        out = {"sig": self._sig}
        for i, g in enumerate(self._groups):
            out[f"buf{i}"] = g[3]
        return out

    @property
    def balance(self) -> bool:
        """Whether the caller takes a share of each eighth's advance before it waits for the
        worker: with overlap where the taps stay with the caller (the displacement scheme,
        whose worker is the longer thread); the share follows the measured imbalance
        (:meth:`rebalance`).  With the taps ahead, the worker adds them to whole rows after
        the advance, so the eighth stays whole."""
        return self.overlap and not self.taps_ahead

    @property
    def pending(self) -> bool:
        """Whether an advance launched on the worker is not yet joined (by the next push,
        get_state or wait)."""
        return self._pending is not None

    @property
    def cut(self):
        """(n, cut) of the advance last launched: of the eighth of step n (:meth:`eighth`), the
        worker advances the modes below ``cut``, the caller the rest (None before a launch)."""
        return self._cut

    @property
    def j0(self) -> np.ndarray:
        """J0 of every mode (integers, shape of gamma): the weights w_k with k < J0 are exact
        (the direct taps), those from J0 on come from the fit."""
        return self._j0_u[self._inv].reshape(self.shape)

    @property
    def _layout(self) -> str:
        if self.backend != "numba":
            return self.backend
        # "-modes": the states are kept in the modes' order (a state kept sorted by gamma is refused)
        return "numba-pretaps-modes" if self.taps_ahead else "numba-tapmajor-modes"

    def eighth(self, n):
        """(lo, hi): the modes lo .. hi - 1 of the eighth that step n advances."""
        return self._bounds[n % _BLOCK], self._bounds[n % _BLOCK + 1]

    def _advance(self, n, threads, part=None):
        """Ready step n before x_n comes: advance the states of eighth n mod 8 through steps
        n .. n + 7 (blocked.advance), then (``taps_ahead``) add the taps 1 <= j < 8 of step n
        (blocked.pretaps).  ``part`` = (lo, hi): only the modes lo .. hi - 1 of
        the eighth (and no taps)."""
        lo, hi = part or self.eighth(n)
        _set_threads(threads)
        blocked = _blocked()
        if hi > lo:
            blocked.advance(n, lo, hi, self._lstart, self._jd, self._R, self._L, self._wl, self._rr, self._ri,
                            self._er, self._ei, *self._states, self._F)
        if self.taps_ahead and part is None:
            blocked.pretaps(n, self._W, self._R, self._F)

    def _scale_for(self, scale):
        """``scale`` flat, contiguous and writable (kept for the next push with the same array;
        writable like the unscaled call's, so that both run one compiled version of the taps)."""
        if scale is None:
            return None
        if scale is not self._scale_src:
            self._scale_src = scale
            flat = np.ascontiguousarray(np.broadcast_to(scale, self.shape), dtype=float).reshape(-1)
            self._scale_flat = flat if flat.flags.writeable else flat.copy()
        return self._scale_flat

    def launch(self) -> None:
        """Start the advance the last push left due on the worker thread (``overlap``).

        The caller pushes every channel of a step first, then launches, then does the work
        that does not touch the engine (transforms, interface law) while the states advance;
        the next push (or get_state) waits for them.  Without overlap, only the next step's
        start_weight is computed here (if it is in use).
        """
        if self._due is not None and self._pending is None:
            n = self._due
            lo, hi = self.eighth(n)
            cut = hi - int(self.share * (hi - lo)) if self.balance else hi
            self._cut = (n, cut)
            self._pending = worker().submit(self._ahead, n, cut)
            self._due = None
        elif self._pending is None:
            self._start_ahead()

    def _ahead(self, n, cut):
        """The worker's job after a push: the advance due (the eighth's modes
        below ``cut``), and the next start-up weight."""
        t0 = time.perf_counter()
        lo, hi = self.eighth(n)
        self._advance(n, 1, None if cut == hi else (lo, cut))
        self._start_ahead()
        self.worker_times = (t0, time.perf_counter())

    def wait(self) -> None:
        """Finish the advance the last push left (on the worker or here): the engine is idle
        until the next push."""
        self._join()

    def _join(self):
        """Finish the advance due after the last push: the caller's share of it here, then
        wait for the worker (re-raising its error); or run it all here if it was never launched."""
        pending, self._pending = self._pending, None
        if pending is not None:
            n, cut = self._cut
            lo, hi = self.eighth(n)
            if cut < hi:
                self._advance(n, 1, (cut, hi))
            arrived = time.perf_counter()
            pending.result()
            if self.balance:
                self.rebalance(arrived, cut - lo, hi - lo)
        if self._due is not None:
            due, self._due = self._due, None
            self._advance(due, self.threads)

    def rebalance(self, arrived, done_by_worker, size):
        """Move part of the next eighths between the threads (``share``): a quarter of the
        measured imbalance (the worker's end, ``worker_times``, against the caller's arrival
        ``arrived``, at the worker's cost per position: ``done_by_worker`` of the eighth's
        ``size`` modes), at most 2 % of an eighth per step, the caller's share within [0, 1/2]."""
        start, end = self.worker_times
        if done_by_worker <= 0 or size <= 0:
            return
        cost = (end - start) / done_by_worker
        step = 0.25 * (end - arrived) / (cost * size) if cost > 0 else 0.0
        self.share = min(0.5, max(0.0, self.share + min(0.02, max(-0.02, step))))

    _CACHES = ("_wpow", "_wrho", "_wk", "_wcalls", "_e0pow", "_e0rho", "_e0n", "_e0next", "_e0next_n")

    def get_state(self) -> dict:
        """The dynamic state (step count, direct-tap buffers, recursive states, and the powers
        weight() and start_weight() advance from call to call), copied."""
        out = {k: a.copy() for k, a in self._state_arrays().items()}
        out["n"] = self.n
        out["layout"] = self._layout
        for k in self._CACHES:
            v = getattr(self, k, None)
            out["cache" + k] = v.copy() if isinstance(v, np.ndarray) else v
        return out

    def set_state(self, state: dict) -> None:
        """Restore a state from :meth:`get_state` (same constructor arguments and backend)."""
        if state.get("layout") != self._layout:
            raise ValueError(f"engine state was saved with layout {state.get('layout')!r}, "
                             f"this engine uses {self._layout!r}")
        for k, a in self._state_arrays().items():
            a[...] = state[k]
        self.n = int(state["n"])
        for k in self._CACHES:
            if "cache" + k in state:
                v = state["cache" + k]
                setattr(self, k, np.array(v) if isinstance(v, np.ndarray) else v)

    def push(self, x: np.ndarray, out: np.ndarray | None = None, scale: np.ndarray | None = None) -> np.ndarray:
        """Push x_n (shape of gamma) and return S_n = sum_j w_{j+lag} x_{n-j} (same shape;
        written into ``out`` if given; multiplied by ``scale``, real, shape of gamma, if given)."""
        x = np.asarray(x, dtype=complex).ravel()
        if x.size != self.gamma.size:
            raise ValueError(f"x has {x.size} values, expected {self.gamma.size}")
        n = self.n
        if n > self._n_max:
            raise RuntimeError(f"the exponential engine was built for T <= {self.fit.T_end:g} "
                               f"({int(self._n_max)} steps); step {n} is beyond its fitted range")
        if self.backend == "numba":
            into = out is not None and out.dtype == complex and out.flags.c_contiguous  # taps write into out
            flat = out.reshape(-1) if into else np.empty(x.size, dtype=complex)
            self._join()  # the states of this step's eighth are advanced (after the last push)
            _set_threads(self.threads)
            sc = self._scale_for(scale)
            _blocked().taps(x, n, self._W, self._R, self._F, flat, _ONE if sc is None else sc, sc is not None,
                            self.taps_ahead)
            self.n = n + 1
            # the next step's eighth is advanced from the ring that now ends with x_n: here, or
            # (overlap) on the worker thread from launch() while the caller goes on
            if self.overlap:
                self._due = n + 1
            else:
                self._advance(n + 1, self.threads)
            return out if into else deliver(flat, self.shape, out)
        xp, xin, S = self._xp, self._xin, self._S
        np.take(x, self._perm, out=xp)
        Sf = S.view(float)
        for o0, o1, J, buf, wf in self._groups:
            p = n % J
            xin[o0:o1] = buf[p]
            buf[p] = xp[o0:o1]
            buf[p + J] = xp[o0:o1]
            hist = buf[p + 1:p + 1 + J].view(float)  # (J, 2 Mg), x_{n-J+1} .. x_n
            np.einsum("jk,jk->k", wf, hist, out=Sf[2 * o0:2 * o1])
        sig = self._sig
        sig *= self._rho
        sig += xin.view(float).reshape(-1, 2, 1)
        m = S.size
        Sf.reshape(m, 2)[...] += np.einsum("mkq,mq->mk", sig.view(float), self._ef)
        res = np.empty(m, dtype=complex)
        res[self._perm] = S
        self.n = n + 1
        return deliver(res, self.shape, out, scale)

    def start_weight(self, n: int) -> np.ndarray:
        """E_0(n) of the product rule (the start-up term on x_0), for every mode (n >= lag).

        Exact for n < J0, from the fit beyond: 2 Re sum_p c_p E(z_p) rho_p^n with
        E(z) = -(e^z - 1 - z)/z^2, the powers updated by one multiplication per call.
        Once asked for, E_0 of the next step is computed ahead with the states' advance
        (on the worker thread with ``overlap``); the array returned is valid for one step.
        """
        if self.rule != "product":
            raise ValueError("start_weight is defined for the product rule only")
        n = int(n)
        if n < self.lag:
            raise ValueError(f"n must be >= lag = {self.lag}, got {n}")
        if self._e0next is not None and self._e0next_n == n:
            return self._e0next
        if self._e0bufs is None:
            self._e0bufs = (np.empty(self.shape), np.empty(self.shape))
        return self._start_into(n, self._spare())

    def _spare(self):
        """The start-weight buffer that does not hold the value last given out."""
        a, b = self._e0bufs
        return b if self._e0next is a else a

    def _start_into(self, n, dest):
        """E_0(n) into ``dest`` (shape of gamma); kept as the value for step n."""
        ug = self._ug
        if n < self.lag + 1 or self._e0pow is None or n != self._e0n + 1 or n % _RESYNC == 0:
            z = ug[:, None] * self.fit.lam[None, :]
            self._e0rho = np.exp(z)
            self._e0pow = np.exp(z * n)
            out = np.einsum("up,up->u", self._e0c, self._e0pow).real
        else:
            out = np.empty(ug.shape)
            _power_sum(self._e0pow, self._e0rho, self._e0c, 1.0, out)
        self._e0n = n
        direct = n < self._j0_u
        out[direct] = self._e0flat[self._wstart_u[direct] + n - self.lag]
        zero = ~direct & (ug == 0)
        if np.any(zero):  # gamma = 0: a constant kernel, E_0(n) is the same for every n >= 1
            if self._e0_zero is None:
                self._e0_zero = float(exact_weights(self.kernel, 0.0, 1, part="start0", **self._exact))
            out[zero] = self._e0_zero
        np.take(out, self._inv, out=dest.reshape(-1))
        self._e0next, self._e0next_n = dest, n
        return dest

    def _start_ahead(self):
        """E_0 of the next push's step (if start_weight is in use), into the buffer that the
        current step does not use: the same operations as asking for it then."""
        if self._e0bufs is not None and self._e0next_n == self.n:
            self._start_into(self.n + 1, self._spare())

    def weight(self, j: int) -> np.ndarray:
        """w_{j+lag} for every mode, as applied by push() (no kernel evaluation: O(P) per mode).

        Consecutive calls (j, j + 1, ...) update the powers rho^k by one multiplication
        (recomputed exactly every ``_RESYNC`` calls).
        """
        j = int(j)
        if j < 0:
            raise ValueError(f"j must be >= 0, got {j}")
        k = j + self.lag
        ug = self._ug
        self._wcalls += 1
        if self._wk is not None and k == self._wk + 1 and self._wcalls % _RESYNC:
            out = np.empty(ug.shape)
            _power_sum(self._wpow, self._wrho, self._cf_u, 2.0, out)
        else:
            z = ug[:, None] * self.fit.lam[None, :]
            self._wrho = np.exp(z)
            self._wpow = np.exp(z * (k - self._shift))
            out = 2.0 * np.einsum("up,up->u", self._cf_u, self._wpow).real
        self._wk = k
        direct = j < self._jd_u
        out[direct] = self._wflat[self._wstart_u[direct] + j]
        out[~direct & (ug == 0)] = self._k0_zero
        return out[self._inv].reshape(self.shape)
