"""The exponential engine's compiled step: the recursive states advanced eight steps at a time.

:class:`cracklab.history.exponential.ExponentialEngine` keeps, per mode, the last Jd >= 8
inputs (the direct taps) and, per term p, the states s_p of Re x and Im x
(``s_p(n) = rho_p s_p(n-1) + x_{n-Jd}``, tail sum ``Re sum_p e_p s_p``).  Because the
input that enters the states at step n is Jd >= 8 steps old, the states of a mode can be
advanced through the next :data:`BLOCK` steps at once, from inputs already kept:
:func:`advance` does so for one eighth of the modes at every step (eighth n mod 8 of
the natural mode order, with the recursion factors and coefficients of every mode in rows
of their own, so that every array is streamed in order), keeping the states in registers
for the eight steps and storing the eight tail sums in ``F``, and adds to them the taps
j >= 8 of the modes that have more than 8 (small gamma: those inputs are older than x_n);
:func:`taps` then returns ``S_n = sum_j w_j x_{n-j}`` (j < 8) plus the stored sum of step
n for every mode.  Or,
where the caller's thread has more to do than the states' advance (the engine's
``taps_ahead``), :func:`pretaps` adds the taps 1 <= j < 8 of the next step to its row
with the advance (on the worker thread when there is one), and :func:`taps` returns
``w_0 x_n`` plus the stored sum.

Layout.  The last 8 inputs of every mode are kept slot by slot over the modes ("tap
major"): ``R[k % 8, m] = x_k``, with the weights ``W[j, m] = w_j`` and the tail sums
``F[(n + r) % 8, m]``, so that :func:`taps` reads and writes only whole rows in the modes'
natural order (16 B per mode and row; a ring per mode spans two cache lines that are
both read and written back).  Modes with Jd > 8 also keep their inputs in a circular
ring of their own (``L``, x_k in slot k mod Jd), which :func:`advance` fills from the rows
(the 8 inputs since its last visit) and then reads for the states' inputs and the taps
j >= 8.
The sums are those of the per-step recursion, reordered (fast-math).

The eight steps of :func:`advance` are written out: the term loop then vectorises with
the sixteen partial sums in registers (a loop over the steps inside it does not).
"""
from __future__ import annotations

import numba

from ..jit import njit
# BLOCK: steps per call of advance (every ring holds at least this many inputs; the eight
# steps are written out below)
from .base import BLOCK

if BLOCK != 8:  # pragma: no cover - the steps of advance are written out for 8
    raise ImportError(f"cracklab.history.blocked is written for blocks of 8 steps, not {BLOCK}")


@njit(parallel=True, fastmath=True)
def advance(n, lo, hi, lstart, jd, R, L, wl, RR, RI, ER, EI, Ar, Ai, Br, Bi, F):
    """Advance the states of modes lo..hi-1 through steps n..n+7; F[(n+j) % 8, m] = tail sum
    of step n+j for each mode m (plus, for Jd > 8, the taps sum_{8 <= k < Jd} w_k x_{n+j-k},
    ``wl[lstart // 2 + k]`` = w_k).

    Inputs x_{n+j-Jd}, j < 8, as kept after step n - 1: for Jd = 8, R[(n + j) % 8, m]; for
    Jd > 8, slot (n + j) mod Jd of the mode's circular ring in L (real parts, then imaginary
    parts at +Jd; ``lstart`` per mode), which first takes x_{n-8} .. x_{n-1} from the rows.
    RR/RI: rho_p, ER/EI: e_p, and the states Ar..Bi, a row per mode: every array is read
    (and the states written) in the modes' order.
    """
    P = RR.shape[1]
    nc = 16
    for c in numba.prange(nc):
        for m in range(lo + c * (hi - lo) // nc, lo + (c + 1) * (hi - lo) // nc):
            J = jd[m]
            if J == 8:
                k = n & 7
                v = R[k, m]; x0r = v.real; x0i = v.imag
                v = R[(k + 1) & 7, m]; x1r = v.real; x1i = v.imag
                v = R[(k + 2) & 7, m]; x2r = v.real; x2i = v.imag
                v = R[(k + 3) & 7, m]; x3r = v.real; x3i = v.imag
                v = R[(k + 4) & 7, m]; x4r = v.real; x4i = v.imag
                v = R[(k + 5) & 7, m]; x5r = v.real; x5i = v.imag
                v = R[(k + 6) & 7, m]; x6r = v.real; x6i = v.imag
                v = R[(k + 7) & 7, m]; x7r = v.real; x7i = v.imag
            else:
                b0 = lstart[m]
                # first the 8 inputs that came in since this mode's last advance, from the rows
                for r in range(8):
                    v = R[(n + r) & 7, m]  # x_{n-8+r}
                    k = (n - 8 + r + J) % J
                    L[b0 + k] = v.real
                    L[b0 + J + k] = v.imag
                k = n % J
                x0r = L[b0 + k]; x0i = L[b0 + J + k]
                k = k + 1 if k + 1 < J else 0
                x1r = L[b0 + k]; x1i = L[b0 + J + k]
                k = k + 1 if k + 1 < J else 0
                x2r = L[b0 + k]; x2i = L[b0 + J + k]
                k = k + 1 if k + 1 < J else 0
                x3r = L[b0 + k]; x3i = L[b0 + J + k]
                k = k + 1 if k + 1 < J else 0
                x4r = L[b0 + k]; x4i = L[b0 + J + k]
                k = k + 1 if k + 1 < J else 0
                x5r = L[b0 + k]; x5i = L[b0 + J + k]
                k = k + 1 if k + 1 < J else 0
                x6r = L[b0 + k]; x6i = L[b0 + J + k]
                k = k + 1 if k + 1 < J else 0
                x7r = L[b0 + k]; x7i = L[b0 + J + k]
            f0r = 0.0; f1r = 0.0; f2r = 0.0; f3r = 0.0; f4r = 0.0; f5r = 0.0; f6r = 0.0; f7r = 0.0
            f0i = 0.0; f1i = 0.0; f2i = 0.0; f3i = 0.0; f4i = 0.0; f5i = 0.0; f6i = 0.0; f7i = 0.0
            for q in range(P):
                rr = RR[m, q]
                ri = RI[m, q]
                er = ER[m, q]
                ei = EI[m, q]
                ar = Ar[m, q]
                ai = Ai[m, q]
                br = Br[m, q]
                bi = Bi[m, q]
                # step n + 0
                t0 = ar * rr - ai * ri + x0r
                t1 = ar * ri + ai * rr
                t2 = br * rr - bi * ri + x0i
                bi = br * ri + bi * rr
                ar = t0
                ai = t1
                br = t2
                f0r += er * ar - ei * ai
                f0i += er * br - ei * bi
                # step n + 1
                t0 = ar * rr - ai * ri + x1r
                t1 = ar * ri + ai * rr
                t2 = br * rr - bi * ri + x1i
                bi = br * ri + bi * rr
                ar = t0
                ai = t1
                br = t2
                f1r += er * ar - ei * ai
                f1i += er * br - ei * bi
                # step n + 2
                t0 = ar * rr - ai * ri + x2r
                t1 = ar * ri + ai * rr
                t2 = br * rr - bi * ri + x2i
                bi = br * ri + bi * rr
                ar = t0
                ai = t1
                br = t2
                f2r += er * ar - ei * ai
                f2i += er * br - ei * bi
                # step n + 3
                t0 = ar * rr - ai * ri + x3r
                t1 = ar * ri + ai * rr
                t2 = br * rr - bi * ri + x3i
                bi = br * ri + bi * rr
                ar = t0
                ai = t1
                br = t2
                f3r += er * ar - ei * ai
                f3i += er * br - ei * bi
                # step n + 4
                t0 = ar * rr - ai * ri + x4r
                t1 = ar * ri + ai * rr
                t2 = br * rr - bi * ri + x4i
                bi = br * ri + bi * rr
                ar = t0
                ai = t1
                br = t2
                f4r += er * ar - ei * ai
                f4i += er * br - ei * bi
                # step n + 5
                t0 = ar * rr - ai * ri + x5r
                t1 = ar * ri + ai * rr
                t2 = br * rr - bi * ri + x5i
                bi = br * ri + bi * rr
                ar = t0
                ai = t1
                br = t2
                f5r += er * ar - ei * ai
                f5i += er * br - ei * bi
                # step n + 6
                t0 = ar * rr - ai * ri + x6r
                t1 = ar * ri + ai * rr
                t2 = br * rr - bi * ri + x6i
                bi = br * ri + bi * rr
                ar = t0
                ai = t1
                br = t2
                f6r += er * ar - ei * ai
                f6i += er * br - ei * bi
                # step n + 7
                t0 = ar * rr - ai * ri + x7r
                t1 = ar * ri + ai * rr
                t2 = br * rr - bi * ri + x7i
                bi = br * ri + bi * rr
                ar = t0
                ai = t1
                br = t2
                f7r += er * ar - ei * ai
                f7i += er * br - ei * bi
                Ar[m, q] = ar
                Ai[m, q] = ai
                Br[m, q] = br
                Bi[m, q] = bi
            F[(n + 0) & 7, m] = complex(f0r, f0i)
            F[(n + 1) & 7, m] = complex(f1r, f1i)
            F[(n + 2) & 7, m] = complex(f2r, f2i)
            F[(n + 3) & 7, m] = complex(f3r, f3i)
            F[(n + 4) & 7, m] = complex(f4r, f4i)
            F[(n + 5) & 7, m] = complex(f5r, f5i)
            F[(n + 6) & 7, m] = complex(f6r, f6i)
            F[(n + 7) & 7, m] = complex(f7r, f7i)
            if J > 8:
                # the taps j >= 8 of steps n + r (r < 8) are on inputs older than x_n, all in
                # the ring: added to the tail sums here, so that taps needs only j < 8
                b0 = lstart[m]
                w0 = b0 // 2
                for r in range(8):
                    kr = 0.0
                    ki = 0.0
                    k = (n + r - 8 + J) % J  # x_{n+r-j} in slot (n + r - j) mod Jd, from j = 8 on
                    for j in range(8, J):
                        kr += wl[w0 + j] * L[b0 + k]
                        ki += wl[w0 + j] * L[b0 + J + k]
                        k = k - 1 if k > 0 else J - 1
                    f = F[(n + r) & 7, m]
                    F[(n + r) & 7, m] = complex(f.real + kr, f.imag + ki)


@njit(parallel=True, fastmath=True)
def pretaps(n, W, R, F):
    """F[n % 8, m] += sum_{1 <= j < 8} W[j, m] x_{n-j}, x_{n-j} = R[(n - j) % 8, m]: the taps of
    step n on inputs already kept, added ahead of the step (after advance has written the
    row), so that :func:`taps` has only w_0 x_n left.  Whole rows, natural mode order."""
    M = R.shape[1]
    k = n & 7
    for c in numba.prange(64):
        for m in range(c * M // 64, (c + 1) * M // 64):
            x1 = R[(k + 7) & 7, m]; x2 = R[(k + 6) & 7, m]; x3 = R[(k + 5) & 7, m]; x4 = R[(k + 4) & 7, m]
            x5 = R[(k + 3) & 7, m]; x6 = R[(k + 2) & 7, m]; x7 = R[(k + 1) & 7, m]
            sr = (W[1, m] * x1.real + W[2, m] * x2.real + W[3, m] * x3.real + W[4, m] * x4.real
                  + W[5, m] * x5.real + W[6, m] * x6.real + W[7, m] * x7.real)
            si = (W[1, m] * x1.imag + W[2, m] * x2.imag + W[3, m] * x3.imag + W[4, m] * x4.imag
                  + W[5, m] * x5.imag + W[6, m] * x6.imag + W[7, m] * x7.imag)
            f = F[k, m]
            F[k, m] = complex(f.real + sr, f.imag + si)


@njit(parallel=True, fastmath=True)
def taps(x, n, W, R, F, out, scale, scaled, ahead):
    """out[m] = F[n % 8, m] + sum_{j < 8} W[j, m] x_{n-j} (times scale[m] if ``scaled``), and
    R[n % 8, m] = x_n; x_{n-j} = R[(n - j) % 8, m].  With ``ahead``, F already holds the taps
    j >= 1 (:func:`pretaps`) and only w_0 x_n is added."""
    M = x.size
    k0 = n & 7
    k1 = (n - 1) & 7
    k2 = (n - 2) & 7
    k3 = (n - 3) & 7
    k4 = (n - 4) & 7
    k5 = (n - 5) & 7
    k6 = (n - 6) & 7
    k7 = (n - 7) & 7
    for c in numba.prange(64):
        for m in range(c * M // 64, (c + 1) * M // 64):
            v = x[m]
            f = F[k0, m]
            if ahead:
                ar = f.real + W[0, m] * v.real
                ai = f.imag + W[0, m] * v.imag
            else:
                x1 = R[k1, m]; x2 = R[k2, m]; x3 = R[k3, m]; x4 = R[k4, m]
                x5 = R[k5, m]; x6 = R[k6, m]; x7 = R[k7, m]
                ar = (f.real + W[0, m] * v.real + W[1, m] * x1.real + W[2, m] * x2.real + W[3, m] * x3.real
                      + W[4, m] * x4.real + W[5, m] * x5.real + W[6, m] * x6.real + W[7, m] * x7.real)
                ai = (f.imag + W[0, m] * v.imag + W[1, m] * x1.imag + W[2, m] * x2.imag + W[3, m] * x3.imag
                      + W[4, m] * x4.imag + W[5, m] * x5.imag + W[6, m] * x6.imag + W[7, m] * x7.imag)
            R[k0, m] = v
            if scaled:
                sc = scale[m]
                ar *= sc
                ai *= sc
            out[m] = complex(ar, ai)
