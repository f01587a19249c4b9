"""The exponential engine's compiled step: the recursive states advanced eight steps at a time.

:class:`cracklab.history.exponential.ExponentialEngine` keeps, per mode, the last Jd >= 8
inputs in a ring (the direct taps) and, per term p, the states s_p of Re x and Im x
(``s_p(n) = rho_p s_p(n-1) + x_{n-Jd}``, tail sum ``Re sum_p e_p s_p``).  Because the
input that enters the states at step n is Jd >= 8 steps old, the states of a mode can be
advanced through the next :data:`BLOCK` steps at once, from inputs already in its ring:
:func:`advance` does so for one eighth of the modes at every step (the modes sorted by
gamma, eighth n mod 8 at step n), keeping the states in registers for the eight steps and
storing the eight tail sums in ``F``; :func:`taps` then, for every mode, stores x_n in
the ring and returns ``S_n = sum_j w_j x_{n-j}`` (j < Jd) plus the tail sum of step n.
The sums are those of the per-step recursion, reordered (fast-math); the states and the
coefficient tables are read once per eight steps instead of every step, and no loop
makes array views (each view costs reference counting per mode).

The eight steps of :func:`advance` are written out: the term loop then vectorises with
the sixteen partial sums in registers (a loop over the steps inside it does not).
"""
from __future__ import annotations

import numba

# BLOCK: steps per call of advance (every ring holds at least this many inputs; the eight
# steps are written out below).  ROTATED_MAX: rings of up to this many taps use a weight
# row per ring position, longer ones index the ring modulo its length.
from .exponential import _BLOCK as BLOCK, _ROTATED_MAX as ROTATED_MAX

assert BLOCK == 8


@numba.njit(cache=True, nogil=True, parallel=True, fastmath=True)
def advance(n, lo, hi, us, start, jd_u, pos_u, ring, RR, RI, ER, EI, Ar, Ai, Br, Bi, F):
    """Advance the states of modes lo..hi-1 (sorted order) through steps n..n+7; F[(n+j) % 8, i] = tail sum of step n+j.

    Inputs: x_{n+j-Jd} = ring[(pos + j) % Jd] (real parts, then the imaginary parts at +Jd),
    read before step n stores x_n.  RR/RI: rho_p, ER/EI: e_p per unique gamma (rows ``us``).
    """
    P = RR.shape[1]
    nc = 16
    for c in numba.prange(nc):
        for i in range(lo + c * (hi - lo) // nc, lo + (c + 1) * (hi - lo) // nc):
            u = us[i]
            J = jd_u[u]
            b0 = start[i]
            p = pos_u[u]
            k = p + 0 - J if p + 0 >= J else p + 0
            x0r = ring[b0 + k]
            x0i = ring[b0 + J + k]
            k = p + 1 - J if p + 1 >= J else p + 1
            x1r = ring[b0 + k]
            x1i = ring[b0 + J + k]
            k = p + 2 - J if p + 2 >= J else p + 2
            x2r = ring[b0 + k]
            x2i = ring[b0 + J + k]
            k = p + 3 - J if p + 3 >= J else p + 3
            x3r = ring[b0 + k]
            x3i = ring[b0 + J + k]
            k = p + 4 - J if p + 4 >= J else p + 4
            x4r = ring[b0 + k]
            x4i = ring[b0 + J + k]
            k = p + 5 - J if p + 5 >= J else p + 5
            x5r = ring[b0 + k]
            x5i = ring[b0 + J + k]
            k = p + 6 - J if p + 6 >= J else p + 6
            x6r = ring[b0 + k]
            x6i = ring[b0 + J + k]
            k = p + 7 - J if p + 7 >= J else p + 7
            x7r = ring[b0 + k]
            x7i = ring[b0 + J + k]
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
            F[(n + 0) % 8, i] = complex(f0r, f0i)
            F[(n + 1) % 8, i] = complex(f1r, f1i)
            F[(n + 2) % 8, i] = complex(f2r, f2i)
            F[(n + 3) % 8, i] = complex(f3r, f3i)
            F[(n + 4) % 8, i] = complex(f4r, f4i)
            F[(n + 5) % 8, i] = complex(f5r, f5i)
            F[(n + 6) % 8, i] = complex(f6r, f6i)
            F[(n + 7) % 8, i] = complex(f7r, f7i)


@numba.njit(cache=True, nogil=True, parallel=True, fastmath=True)
def taps(x, n, order, us, start, jd_u, pos_u, wrow_u, wtab, ring, F, out):
    """Store x_n in every ring and return out[m] = sum_{j < Jd} w_j x_{n-j} + F[n % 8, i].

    ``order[i]`` is the mode (index into x and out) at sorted position i.  Rings of
    Jd <= ROTATED_MAX taps use wtab[wrow_u[u] + pos * Jd + r], the weight of ring slot r
    when x_n sits in slot pos; longer ones wtab[wrow_u[u] + j] = w_j.
    """
    M = order.size
    jrow = n % 8
    for c in numba.prange(64):
        for i in range(c * M // 64, (c + 1) * M // 64):
            m = order[i]
            u = us[i]
            J = jd_u[u]
            b0 = start[i]
            p = pos_u[u]
            v = x[m]
            ring[b0 + p] = v.real
            ring[b0 + J + p] = v.imag
            f = F[jrow, i]
            accr = f.real
            acci = f.imag
            if J <= ROTATED_MAX:
                w0 = wrow_u[u] + p * J
                for r in range(J):
                    wj = wtab[w0 + r]
                    accr += wj * ring[b0 + r]
                    acci += wj * ring[b0 + J + r]
            else:
                w0 = wrow_u[u]
                r = p
                for j in range(J):
                    wj = wtab[w0 + j]
                    accr += wj * ring[b0 + r]
                    acci += wj * ring[b0 + J + r]
                    r = r - 1 if r > 0 else J - 1
            out[m] = complex(accr, acci)
