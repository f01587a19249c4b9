"""Exponential-sum history engine: cost and memory per mode independent of the run length.

The kernel K (C or Z, see :mod:`cracklab.weights`) is represented, for
T = q c_s t >= T0, by ``K(T) ~ 2 Re sum_p c_p exp(lambda_p T)`` (conjugate pairs,
Re lambda_p < 0, absolute error <= 1e-5 |K(0)| (5e-6 for mode II) on the whole half line
T >= T0; :mod:`cracklab.history.fit`).  For a mode with gamma = q c_s dt the weights split at
J0 = ceil(T0 / gamma) (rounded up to a small set of levels, and >= lag + 1):

* k = j + lag < J0: the exact weights ``convolution_weights(kernel, gamma, k)`` against
  a ring buffer of the last Jd = J0 - lag values of the mode ("direct taps");
* k >= J0: the weight of the rule applied to the fitted kernel,
  ``w_k = 2 Re sum_p c_p f_p rho_p^k`` with ``rho_p = exp(lambda_p gamma)`` and the
  rule factor f_p (discretized 1, trapezoid (1 + rho)/2, Simpson, exact
  (rho - 1)/(lambda gamma)), i.e. the pre-integration of eqs. (45)-(47) applied to
  each exponential exactly.  The tail sum is carried by one complex state per term
  and per real input (real and imaginary parts of x):
  ``s_p(n) = rho_p s_p(n-1) + x_{n-Jd}``, ``S_tail = 2 Re sum_p c_p f_p rho_p^J0 s_p``
  (taken separately for the real and imaginary parts of x).

Per mode and step this costs Jd real multiply-adds of the direct taps plus P complex
multiply-adds (P exponentials with conjugates, P/2 states for each of Re x and Im x: 22
for C_III, 68 for C_II, 70 for C_I at nu = 1/4), and the memory is fixed at construction.
Modes with gamma = 0 (q = 0) get exact weights K(0) for all k (a running sum).
See docs/fast_engine.md.

``window`` (a truncated history) is not supported: the engine keeps the whole
history by construction; use the direct engine for windowed runs.
"""
from __future__ import annotations

import os

import numpy as np

from ..errors import InputError
from ..weights import FORMULATIONS, RULES, convolution_weights
from .fit import DEFAULT_T0, get_fit

__all__ = ["ExponentialEngine", "direct_taps"]

# levels for the number of direct taps: grouping modes by level keeps the
# number of per-step numpy calls small (a mode gets at most ~25 % extra taps)
_LEVELS = np.array(sorted({1, 2, 3, 4, 5, 6, 7, 8} | {int(round(2 ** (k / 4))) for k in range(12, 80)}))
_RESYNC = 512
_SUPPORTED_RULES = ("discretized", "trapezoid", "simpson", "exact")  # recompute the powers of weight() exactly every so many calls


def direct_taps(gamma, lag=0, T0=DEFAULT_T0):
    """Number of direct taps Jd (>= 1) for each gamma: the exact weights w_lag .. w_{lag+Jd-1}.

    J0 = Jd + lag is ceil(T0 / gamma) (at least lag + 1), with Jd rounded up to one of
    a few levels (``_LEVELS``); gamma = 0 gives Jd = 1.
    """
    g = np.asarray(gamma, dtype=float)
    pos = g > 0
    with np.errstate(divide="ignore"):
        j0 = np.where(pos, np.ceil(T0 / np.where(pos, g, 1.0) * (1 - 1e-12)), 1.0)
    jd = np.maximum(j0, lag + 1) - lag
    i = np.searchsorted(_LEVELS, jd)
    big = i >= _LEVELS.size
    out = np.where(big, jd, _LEVELS[np.minimum(i, _LEVELS.size - 1)])
    return np.where(pos, out, 1).astype(np.int64)


def _rule_factor(rule, z, simpson_n=4):
    """Cell factor f(z), z = lambda gamma: weight of exp(lambda T) on cell k is f rho^k."""
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
        small = np.abs(z) < 1e-8
        zs = np.where(small, 1.0, z)
        return np.where(small, 1.0 + 0.5 * z, np.expm1(zs) / zs)
    raise ValueError(f"the exponential engine does not support rule {rule!r} "
                     f"(supported: {', '.join(_SUPPORTED_RULES)})")


# ----------------------------------------------------------------------------- numba kernel
def _numba_push():
    """The fused per-step loop, compiled with numba (None if numba is unavailable)."""
    try:
        import numba
    except Exception:  # pragma: no cover - numba is a dependency, but keep numpy working
        return None

    @numba.njit(cache=True, nogil=True)
    def push(x, n, order, us, start, jd_u, wstart_u, w, buf, rho_u, coef_u, sig, out):
        """One step for every mode; modes visited in the order of their gamma (index us)."""
        ph = rho_u.shape[1]
        for i in range(order.size):
            m = order[i]
            u = us[i]
            J = jd_u[u]
            b0 = start[i]
            w0 = wstart_u[u]
            p = n % J
            old = buf[b0 + p]
            buf[b0 + p] = x[m]
            accr = 0.0
            acci = 0.0
            k = p
            for j in range(J):  # direct taps: w_{lag+j} x_{n-j}
                v = buf[b0 + k]
                wj = w[w0 + j]
                accr += wj * v.real
                acci += wj * v.imag
                k -= 1
                if k < 0:
                    k += J
            xr = old.real  # x_{n-J} enters the recursive states
            xi = old.imag
            for q in range(ph):
                r = rho_u[u, q]
                c = coef_u[u, q]
                s0 = r * sig[i, 0, q] + xr
                s1 = r * sig[i, 1, q] + xi
                sig[i, 0, q] = s0
                sig[i, 1, q] = s1
                accr += c.real * s0.real - c.imag * s0.imag
                acci += c.real * s1.real - c.imag * s1.imag
            out[m] = complex(accr, acci)

    return push


_NUMBA = None


def _get_numba():
    global _NUMBA
    if _NUMBA is None:
        _NUMBA = _numba_push() or False
    return _NUMBA or None


def _backend_choice():
    env = os.environ.get("CRACKLAB_EXP_BACKEND", "").strip().lower()
    if env in ("numpy", "numba"):
        return env
    return "numba" if _get_numba() is not None else "numpy"


# ----------------------------------------------------------------------------- engine
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

    def __init__(self, *, kernel, gamma, nu, rule="trapezoid", formulation="displacement",
                 lag=0, window=None, chunk=256):
        if window is not None:
            raise InputError("numerics.window",
                             "the exponential history engine keeps the whole (untruncated) history and "
                             "does not support a window; use engine='direct' for a windowed history")
        if rule not in RULES or rule not in _SUPPORTED_RULES:
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
        self.fit = get_fit(kernel, nu, formulation)
        self.T0 = self.fit.T0
        self.pairs = self.fit.pairs
        self.backend = _backend_choice()
        self.n = 0

        ug, inv = np.unique(self.gamma, return_inverse=True)
        self._ug, self._inv = ug, inv
        jd_u = direct_taps(ug, self.lag, self.T0)
        self._jd_u = jd_u
        self._j0_u = jd_u + self.lag  # first fitted weight index
        lam, c = self.fit.lam, self.fit.coef
        z = ug[:, None] * lam[None, :]
        rho_u = np.exp(z)
        cf_u = c[None, :] * _rule_factor(rule, z)  # weight of cell k: 2 Re sum cf rho^k
        e_u = 2.0 * cf_u * np.exp(z * self._j0_u[:, None])  # S_tail = Re sum_p e_p s_p
        zero = ug == 0
        # q = 0: every weight beyond the first is K(0)
        self._k0_zero = k0 = float(convolution_weights(kernel, 0.0, self.lag + 1, nu=nu, rule=rule,
                                                       formulation=formulation))
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
        self._wflat = np.asarray(convolution_weights(kernel, ug[uu], jj + self.lag, nu=nu, rule=rule,
                                                     formulation=formulation), dtype=float).ravel()
        # weight() cache: powers rho^k for the last k asked
        self._wk = None
        self._wpow = None
        self._wrho = None
        self._wcalls = 0

        m = self.gamma.size
        if self.backend == "numba":
            self._push_nb = _get_numba()
            order = np.argsort(inv, kind="stable")
            us = inv[order].astype(np.int64)
            self._order, self._us = order.astype(np.int64), us
            self._jd_u_i = np.ascontiguousarray(jd_u, dtype=np.int64)
            jd_sorted = jd_u[us]
            self._start = np.zeros(m, dtype=np.int64)
            if m:
                self._start[1:] = np.cumsum(jd_sorted)[:-1]
            self._buf = np.zeros(int(jd_sorted.sum()), dtype=complex)
            self._rho = np.ascontiguousarray(rho_u)
            self._coef = np.ascontiguousarray(e_u)
            self._sig = np.zeros((m, 2, self.pairs), dtype=complex)
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

    # ------------------------------------------------------------------ public
    @property
    def nbytes(self) -> int:
        """Bytes held by the per-mode state (buffers, weights, recursion factors, states)."""
        if self.backend == "numba":
            arrs = [self._buf, self._wflat, self._rho, self._coef, self._sig, self._order, self._us,
                    self._start]
        else:
            arrs = [self._wflat, self._rho, self._ef, self._sig, self._xin, self._xp, self._S]
            for g in self._groups:
                arrs += [g[3], g[4]]
        return int(sum(a.nbytes for a in arrs))

    def state_shapes(self) -> list:
        """Shapes of every state array (for checking that nothing grows with n)."""
        if self.backend == "numba":
            arrs = [self._buf, self._rho, self._coef, self._sig]
        else:
            arrs = [self._rho, self._ef, self._sig] + [g[3] for g in self._groups]
        return [a.shape for a in arrs]

    def _state_arrays(self) -> dict:
        if self.backend == "numba":
            return {"buf": self._buf, "sig": self._sig}
        out = {"sig": self._sig}
        for i, g in enumerate(self._groups):
            out[f"buf{i}"] = g[3]
        return out

    def get_state(self) -> dict:
        """The dynamic state (step count, direct-tap buffers, recursive states), copied."""
        out = {k: a.copy() for k, a in self._state_arrays().items()}
        out["n"] = self.n
        out["layout"] = self.backend
        return out

    def set_state(self, state: dict) -> None:
        """Restore a state from :meth:`get_state` (same constructor arguments and backend)."""
        if state.get("layout") != self.backend:
            raise ValueError(f"engine state was saved with backend {state.get('layout')!r}, "
                             f"this engine uses {self.backend!r}")
        for k, a in self._state_arrays().items():
            a[...] = state[k]
        self.n = int(state["n"])

    def push(self, x: np.ndarray) -> np.ndarray:
        """Push x_n (shape of gamma) and return S_n = sum_j w_{j+lag} x_{n-j} (same shape)."""
        x = np.asarray(x, dtype=complex).ravel()
        if x.size != self.gamma.size:
            raise ValueError(f"x has {x.size} values, expected {self.gamma.size}")
        n = self.n
        if self.backend == "numba":
            out = np.empty(x.size, dtype=complex)
            self._push_nb(x, n, self._order, self._us, self._start, self._jd_u_i, self._wstart_u,
                          self._wflat, self._buf, self._rho, self._coef, self._sig, out)
            self.n = n + 1
            return out.reshape(self.shape)
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
        out = np.empty(m, dtype=complex)
        out[self._perm] = S
        self.n = n + 1
        return out.reshape(self.shape)

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
        out = np.empty(ug.shape)
        direct = j < self._jd_u
        out[direct] = self._wflat[self._wstart_u[direct] + j]
        zero = (ug == 0) & ~direct
        out[zero] = self._k0_zero
        fitted = ~direct & ~zero
        if np.any(fitted):
            self._wcalls += 1
            if self._wk is not None and k == self._wk + 1 and self._wcalls % _RESYNC:
                self._wpow *= self._wrho
            else:
                z = ug[:, None] * self.fit.lam[None, :]
                self._wrho = np.exp(z)
                self._wpow = np.exp(z * k)
            self._wk = k
            out[fitted] = 2.0 * np.einsum("up,up->u", self._cf_u[fitted], self._wpow[fitted]).real
        return out[self._inv].reshape(self.shape)
