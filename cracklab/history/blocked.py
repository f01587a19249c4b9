"""The exponential engine's compiled step: the recursive states advanced eight steps at a time.

:class:`cracklab.history.exponential.ExponentialEngine` keeps, per mode, the last Jd >= 8
inputs in a ring (the direct taps) and, per term p, the states s_p of Re x and Im x
(``s_p(n) = rho_p s_p(n-1) + x_{n-Jd}``, tail sum ``Re sum_p e_p s_p``).  Because the
input that enters the states at step n is Jd >= 8 steps old, the states of a mode can be
advanced through the next :data:`BLOCK` steps at once, from inputs already in its ring:
:func:`advance` does so for one eighth of the modes at every step (eighth n mod 8 of
the natural mode order at step n, each eighth sorted by gamma so that the coefficient
rows are read in order), keeping the states in registers for the eight steps and storing
the eight tail sums in ``F``; :func:`taps` then, for every mode in its natural
order, shifts x_n into the ring and returns ``S_n = sum_j w_j x_{n-j}`` (j < Jd) plus
the tail sum of step n.
The sums are those of the per-step recursion, reordered (fast-math); the states and the
coefficient tables are read once per eight steps instead of every step, and no loop
makes array views (each view costs reference counting per mode).  The taps sweep reads
only sequential streams (rings, per-mode weights, F): a table lookup per mode cost more
than the arithmetic.

The eight steps of :func:`advance` are written out: the term loop then vectorises with
the sixteen partial sums in registers (a loop over the steps inside it does not).
"""
from __future__ import annotations

import numba

# BLOCK: steps per call of advance (every ring holds at least this many inputs; the eight
# steps are written out below)
from .exponential import _BLOCK as BLOCK

if BLOCK != 8:  # pragma: no cover - the steps of advance are written out for 8
    raise ImportError(f"cracklab.history.blocked is written for blocks of 8 steps, not {BLOCK}")


@numba.njit(cache=True, nogil=True, parallel=True, fastmath=True)
def advance(n, lo, hi, order, us, start, jd_u, ring, RR, RI, ER, EI, Ar, Ai, Br, Bi, F):
    """Advance the states of sorted positions lo..hi-1 through steps n..n+7; F[m, (n+j) % 8] =
    tail sum of step n+j for their modes m = order[i].

    Inputs: x_{n+j-Jd} = ring[start + j] (the ring holds x_{n-Jd} .. x_{n-1} oldest first,
    real parts then imaginary parts at +Jd; ``start`` per sorted position), read before step
    n shifts x_n in.  RR/RI: rho_p, ER/EI: e_p per unique gamma (rows ``us``); the states
    Ar..Bi per sorted position.
    """
    P = RR.shape[1]
    nc = 16
    for c in numba.prange(nc):
        for i in range(lo + c * (hi - lo) // nc, lo + (c + 1) * (hi - lo) // nc):
            u = us[i]
            m = order[i]
            J = jd_u[u]
            b0 = start[i]
            x0r = ring[b0 + 0]
            x0i = ring[b0 + J + 0]
            x1r = ring[b0 + 1]
            x1i = ring[b0 + J + 1]
            x2r = ring[b0 + 2]
            x2i = ring[b0 + J + 2]
            x3r = ring[b0 + 3]
            x3i = ring[b0 + J + 3]
            x4r = ring[b0 + 4]
            x4i = ring[b0 + J + 4]
            x5r = ring[b0 + 5]
            x5i = ring[b0 + J + 5]
            x6r = ring[b0 + 6]
            x6i = ring[b0 + J + 6]
            x7r = ring[b0 + 7]
            x7i = ring[b0 + J + 7]
            f0r = 0.0; f1r = 0.0; f2r = 0.0; f3r = 0.0; f4r = 0.0; f5r = 0.0; f6r = 0.0; f7r = 0.0
            f0i = 0.0; f1i = 0.0; f2i = 0.0; f3i = 0.0; f4i = 0.0; f5i = 0.0; f6i = 0.0; f7i = 0.0
            for q in range(P):
                rr = RR[u, q]
                ri = RI[u, q]
                er = ER[u, q]
                ei = EI[u, q]
                ar = Ar[i, q]
                ai = Ai[i, q]
                br = Br[i, q]
                bi = Bi[i, q]
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
                Ar[i, q] = ar
                Ai[i, q] = ai
                Br[i, q] = br
                Bi[i, q] = bi
            F[m, (n + 0) % 8] = complex(f0r, f0i)
            F[m, (n + 1) % 8] = complex(f1r, f1i)
            F[m, (n + 2) % 8] = complex(f2r, f2i)
            F[m, (n + 3) % 8] = complex(f3r, f3i)
            F[m, (n + 4) % 8] = complex(f4r, f4i)
            F[m, (n + 5) % 8] = complex(f5r, f5i)
            F[m, (n + 6) % 8] = complex(f6r, f6i)
            F[m, (n + 7) % 8] = complex(f7r, f7i)


@numba.njit(cache=True, nogil=True, parallel=True, fastmath=True)
def taps(x, n, inv, start, jd_u, w, ring, F, out, scale, scaled):
    """Shift x_n into every ring and return out[m] = sum_{j < Jd} w_j x_{n-j} + F[m, n % 8]
    (times scale[m] if ``scaled``).

    Modes in their natural order: x, out, the rings, the weights and F are each read or
    written in one sweep.  The ring of mode m (``start[m]``) holds the last Jd inputs
    oldest first (real parts, then imaginary parts); ``w[start[m] // 2 + r]`` is the
    weight of slot r once x_n is in (w_{Jd-1-r}).
    """
    M = x.size
    jrow = n % 8
    for c in numba.prange(64):
        for m in range(c * M // 64, (c + 1) * M // 64):
            J = jd_u[inv[m]]
            b0 = start[m]
            w0 = b0 // 2
            v = x[m]
            f = F[m, jrow]
            accr = f.real + w[w0 + J - 1] * v.real
            acci = f.imag + w[w0 + J - 1] * v.imag
            if J == 8:  # most modes: written out
                a1 = ring[b0 + 1]; a2 = ring[b0 + 2]; a3 = ring[b0 + 3]; a4 = ring[b0 + 4]
                a5 = ring[b0 + 5]; a6 = ring[b0 + 6]; a7 = ring[b0 + 7]
                i1 = ring[b0 + 9]; i2 = ring[b0 + 10]; i3 = ring[b0 + 11]; i4 = ring[b0 + 12]
                i5 = ring[b0 + 13]; i6 = ring[b0 + 14]; i7 = ring[b0 + 15]
                accr += (w[w0] * a1 + w[w0 + 1] * a2 + w[w0 + 2] * a3 + w[w0 + 3] * a4
                         + w[w0 + 4] * a5 + w[w0 + 5] * a6 + w[w0 + 6] * a7)
                acci += (w[w0] * i1 + w[w0 + 1] * i2 + w[w0 + 2] * i3 + w[w0 + 3] * i4
                         + w[w0 + 4] * i5 + w[w0 + 5] * i6 + w[w0 + 6] * i7)
                ring[b0] = a1; ring[b0 + 1] = a2; ring[b0 + 2] = a3; ring[b0 + 3] = a4
                ring[b0 + 4] = a5; ring[b0 + 5] = a6; ring[b0 + 6] = a7; ring[b0 + 7] = v.real
                ring[b0 + 8] = i1; ring[b0 + 9] = i2; ring[b0 + 10] = i3; ring[b0 + 11] = i4
                ring[b0 + 12] = i5; ring[b0 + 13] = i6; ring[b0 + 14] = i7; ring[b0 + 15] = v.imag
            else:
                for r in range(J - 1):
                    a = ring[b0 + r + 1]
                    b = ring[b0 + J + r + 1]
                    accr += w[w0 + r] * a
                    acci += w[w0 + r] * b
                    ring[b0 + r] = a
                    ring[b0 + J + r] = b
                ring[b0 + J - 1] = v.real
                ring[b0 + 2 * J - 1] = v.imag
            if scaled:
                accr *= scale[m]
                acci *= scale[m]
            out[m] = complex(accr, acci)
