"""Compiled elementwise loops of the time step: one pass over the grid, no temporaries.

Two operations run several times per step on every mode or node and, written as numpy
expressions, cost more in temporaries than in arithmetic (docs/studies/performance.md):

* :func:`rotate`: the shear rotation of Eq. (28) between the components (1, 3) of a mode
  and its channels (II, III), and back;
* :func:`product_predict`: the product scheme's predictor for one channel
  (cracklab.response), D, H and F of every mode in one pass;
* :func:`shear_correct`, :func:`shear_predict`: the product scheme's corrector and
  predictor for the 3D shear channels with the rotations of Eq. (28) in the same pass;
* :func:`plus_scaled` (x + a y), :func:`plus_mean` (y + a (x1 + x2); in place,
  :func:`add_mean_step`),
  :func:`plus_product` (H + K V) for the product scheme's trial slips and corrector.

Step (v)'s passes (shear_velocity, normal_velocity, add_scaled) are the laws'
(cracklab.laws.loops; importable from here too). Each is a numba loop registered with
cracklab.jit (compiled on first use, cached on disk); without numba the callers
use the numpy expressions, which give the same numbers to the last bit (the same
operations in the same order, no fast-math).
"""
from __future__ import annotations

import numpy as np

from ..jit import available as compiled, compiled_loop as _compiled, loop, python_only  # noqa: F401
from ..laws.loops import add_scaled, fusable_load, normal_velocity, shear_velocity  # noqa: F401


@loop("rotate")
def _rotate_loop(c, s, a, b, sign, o1, o2):
    for i in range(c.size):
        cc = c[i]
        ss = sign * s[i]
        x = a[i]
        y = b[i]
        o1[i] = cc * x + ss * y
        o2[i] = cc * y - ss * x


@loop("predict")
def _predict_loop(V, S, e0, v0, dknown, static, pre, K, dt, H, F):
    for i in range(V.size):
        d = dknown[i] + dt * V[i]
        dknown[i] = d
        h = static[i] * d + pre[i] * (S[i] + e0[i] * v0[i])
        H[i] = h
        F[i] = h + K[i] * V[i]


@loop("xpay")
def _xpay_loop(out, x, a, y):
    for i in range(out.size):
        out[i] = x[i] + a * y[i]


@loop("plus_mean")
def _plus_mean_loop(out, y, a, x1, x2):
    for i in range(out.size):
        out[i] = y[i] + a * (x1[i] + x2[i])


@loop("hkv")
def _hkv_loop(out, H, K, V):
    for i in range(out.size):
        out[i] = H[i] + K[i] * V[i]


@loop("shear_correct")
def _shear_correct_loop(c, s, X1, X3, H2, K2, H3, K3, nrm, F1, F3):
    for i in range(c.size):
        cc = c[i]
        ss = 1.0 * s[i]          # Eq. (28): components -> channels (rotate)
        x = X1[i]
        y = X3[i]
        v2 = cc * x + ss * y
        v3 = cc * y - ss * x
        f2 = H2[i] + K2[i] * v2  # the corrector, each channel (plus_product)
        f3 = H3[i] + K3[i] * v3
        ss = -1.0 * s[i]         # and back (rotate, inverse), times the inverse FFT's 1/N
        F1[i] = (cc * f2 + ss * f3) * nrm
        F3[i] = (cc * f3 - ss * f2) * nrm


@loop("shear_predict")
def _shear_predict_loop(c, s, V2, S2, e02, v02, dk2, st2, pre2, K2, V3, S3, e03, v03, dk3, st3, pre3, K3, dt,
                        nrm, H2, H3, F1, F3):
    for i in range(c.size):
        d = dk2[i] + dt * V2[i]  # the predictor, each channel (product_predict)
        dk2[i] = d
        h = st2[i] * d + pre2[i] * (S2[i] + e02[i] * v02[i])
        H2[i] = h
        f2 = h + K2[i] * V2[i]
        d = dk3[i] + dt * V3[i]
        dk3[i] = d
        h = st3[i] * d + pre3[i] * (S3[i] + e03[i] * v03[i])
        H3[i] = h
        f3 = h + K3[i] * V3[i]
        cc = c[i]
        ss = -1.0 * s[i]         # channels -> components (rotate, inverse), times 1/N
        F1[i] = (cc * f2 + ss * f3) * nrm
        F3[i] = (cc * f3 - ss * f2) * nrm


@loop("mirror_pack")
def _mirror_pack_loop(e, o, has_e, has_o, z):
    # the doubled cell's field z (n1, 2 n3) of an even field e and an odd one o on the half
    # plane (n1, n3 + 1): z_k = e_k + o_k, z_{2 n3 - k} = e_k - o_k (o vanishes at k = 0, n3)
    n1, two = z.shape
    m = two // 2
    for i in range(n1):
        z[i, 0] = e[i, 0] if has_e else 0.0
        z[i, m] = e[i, m] if has_e else 0.0
        for k in range(1, m):
            x = e[i, k] if has_e else 0.0
            y = o[i, k] if has_o else 0.0
            z[i, k] = x + y
            z[i, two - k] = x - y


@loop("mirror_separate")
def _mirror_separate_loop(W, has_e, has_o, E, O):
    # the doubled cell's spectrum W (n1, n3 + 1) of z = e + o -> E, O (n1//2 + 1, n3 + 1):
    # E(k) = (W(k) + conj W(-k)) / 2 (even about x3 = 0: Hermitian in k), O(k) = (W(k) - conj W(-k)) / 2
    n1, m = W.shape
    for k in range(n1 // 2 + 1):
        kk = (n1 - k) % n1
        for j in range(m):
            w = W[k, j]
            v = W[kk, j].conjugate()
            if has_e:
                E[k, j] = 0.5 * (w + v)
            if has_o:
                O[k, j] = 0.5 * (w - v)


@loop("mirror_join")
def _mirror_join_loop(E, O, has_e, has_o, top, bottom):
    # inverse of the separation: W(k) = E(k) + O(k), W(-k) = conj(E(k) - O(k)); on the rows
    # k = 0 and n1/2 (their own conjugates) the even part's real and the odd part's imaginary
    # part. W's rows 0 .. n1/2 are ``top``, the others ``bottom`` (two arrays: stores into two
    # rows of one array keep the loop from vectorising)
    h, m = top.shape
    h -= 1
    for k in range(h + 1):
        edge = k == 0 or k == h
        for j in range(m):
            a = E[k, j] if has_e else 0.0j
            b = O[k, j] if has_o else 0.0j
            top[k, j] = complex(a.real, b.imag) if edge else a + b
            if not edge:
                bottom[h - 1 - k, j] = (a - b).conjugate()


@loop("mirror_split")
def _mirror_split_loop(z, scale, has_e, has_o, e, o):
    # the half plane's even and odd parts of the doubled field z, times scale
    n1, two = z.shape
    m = two // 2
    for i in range(n1):
        if has_e:
            e[i, 0] = z[i, 0] * scale
            e[i, m] = z[i, m] * scale
        if has_o:
            o[i, 0] = 0.0
            o[i, m] = 0.0
        for k in range(1, m):
            p = z[i, k]
            q = z[i, two - k]
            if has_e:
                e[i, k] = 0.5 * (p + q) * scale
            if has_o:
                o[i, k] = 0.5 * (p - q) * scale


@loop("mirror_rotate")
def _mirror_rotate_loop(c, s, W, o1, o2):
    # mirror_separate, then rotate (Eq. 28), in one pass: W (n1, n3 + 1) -> channels (h, n3 + 1)
    n1, m = W.shape
    for k in range(n1 // 2 + 1):
        kk = (n1 - k) % n1
        for j in range(m):
            w = W[k, j]
            v = W[kk, j].conjugate()
            x = 0.5 * (w + v)
            y = 0.5 * (w - v)
            cc = c[k, j]
            ss = 1.0 * s[k, j]
            o1[k, j] = cc * x + ss * y
            o2[k, j] = cc * y - ss * x


@loop("mirror_shear_correct")
def _mirror_shear_correct_loop(c, s, W, H2, K2, H3, K3, nrm, top, bottom):
    # shear_correct with mirror_separate before it and mirror_join after it, in one pass
    n1, m = W.shape
    h = n1 // 2
    for k in range(h + 1):
        edge = k == 0 or k == h
        kk = (n1 - k) % n1
        for j in range(m):
            w = W[k, j]
            v = W[kk, j].conjugate()
            x = 0.5 * (w + v)
            y = 0.5 * (w - v)
            cc = c[k, j]
            ss = 1.0 * s[k, j]
            v2 = cc * x + ss * y
            v3 = cc * y - ss * x
            f2 = H2[k, j] + K2[k, j] * v2
            f3 = H3[k, j] + K3[k, j] * v3
            ss = -1.0 * s[k, j]
            g1 = (cc * f2 + ss * f3) * nrm   # back to components, then mirror_join
            g3 = (cc * f3 - ss * f2) * nrm
            # (a select and a guarded store: an if/else of two stores keeps the loop from vectorising)
            top[k, j] = complex(g1.real, g3.imag) if edge else g1 + g3
            if not edge:
                bottom[h - 1 - k, j] = (g1 - g3).conjugate()


@loop("mirror_shear_predict")
def _mirror_shear_predict_loop(c, s, V2, S2, e02, v02, dk2, st2, pre2, K2, V3, S3, e03, v03, dk3, st3, pre3, K3,
                               dt, nrm, H2, H3, top, bottom):
    # shear_predict with mirror_join after it, in one pass (the channel arrays are (h, n3 + 1))
    m = c.shape[1]
    h = c.shape[0] - 1
    for k in range(h + 1):
        edge = k == 0 or k == h
        for j in range(m):
            d = dk2[k, j] + dt * V2[k, j]
            dk2[k, j] = d
            hh = st2[k, j] * d + pre2[k, j] * (S2[k, j] + e02[k, j] * v02[k, j])
            H2[k, j] = hh
            f2 = hh + K2[k, j] * V2[k, j]
            d = dk3[k, j] + dt * V3[k, j]
            dk3[k, j] = d
            hh = st3[k, j] * d + pre3[k, j] * (S3[k, j] + e03[k, j] * v03[k, j])
            H3[k, j] = hh
            f3 = hh + K3[k, j] * V3[k, j]
            cc = c[k, j]
            ss = -1.0 * s[k, j]
            g1 = (cc * f2 + ss * f3) * nrm   # back to components, then mirror_join
            g3 = (cc * f3 - ss * f2) * nrm
            # (a select and a guarded store: an if/else of two stores keeps the loop from vectorising)
            top[k, j] = complex(g1.real, g3.imag) if edge else g1 + g3
            if not edge:
                bottom[h - 1 - k, j] = (g1 - g3).conjugate()


# -- the bimaterial interface (solver/interfaces/bimaterial.py): both faces' five channels,
# their combination and the interface's join in one pass per stage.  Arrays per face (first
# index: 0 top, 1 bottom), then part (L, N, T) or channel (L, N, LN, NL, T; an absent
# channel has zero rows).  Per face, f_L = s F_L + i F_LN, f_N = s F_N - i F_NL, f_T = s F_T
# (solver/face.py); the interface's F = wp f+ + wm f- per part, back to components (Eq. 28
# inverse) times nrm; and for a jump rate V, v+ = [(f+ - f-) + em V]/den, v- = v+ - V.
# Without numba the interface runs its numpy expressions (the same numbers to round-off).
_BIM_BLOCK = 256


@loop("bim_predict")
def _bim_predict_loop(M, V, S, e0, v0, dk, st, pre, dt, H):
    """The predictor's channel updates (modes 0 .. M-1): dknown += dt V, and each channel's
    running term H; the faces' f then follow from _bim_correct_loop with v = V."""
    # blocks of modes: within one, a loop per channel over a few rows (the hardware prefetches
    # a handful of streams, not the sixty rows of a pass that takes every channel per mode)
    for b0 in range(0, M, _BIM_BLOCK):
        b1 = min(M, b0 + _BIM_BLOCK)
        for a in range(2):
            for k in range(3):
                for i in range(b0, b1):
                    dk[a, k, i] = dk[a, k, i] + dt * V[a, k, i]
            # channels L (on v_L), N (v_N), LN (v_N), NL (v_L, with the start-up weight of LN), T (v_T)
            for j in range(5):
                k = 0 if (j == 0 or j == 3) else (2 if j == 4 else 1)
                je = 2 if j == 3 else j
                for i in range(b0, b1):
                    H[a, j, i] = st[a, j, i] * dk[a, k, i] + pre[a, j, i] * (S[a, j, i] + e0[a, je, i] * v0[a, k, i])


@loop("bim_settle")
def _bim_settle_loop(X1, X2, X3, c, s, f, em, den, v):
    for k in range(3):
        for i in range(c.size):
            if k == 0:
                Vk = c[i] * X1[i] + s[i] * X3[i]
            elif k == 1:
                Vk = X2[i]
            else:
                Vk = c[i] * X3[i] - s[i] * X1[i]
            p = ((f[0, k, i] - f[1, k, i]) + em[k, i] * Vk) / den[k, i]
            v[0, k, i] = p
            v[1, k, i] = p - Vk


@loop("bim_correct")
def _bim_correct_loop(M, H, K, sign, v, f):
    """The faces' f = H + K v (modes 0 .. M-1) for their velocities ``v``: the predictor's V,
    or the split's (_bim_settle_loop) in the corrector."""
    F = np.empty((5, _BIM_BLOCK), dtype=np.complex128)
    for b0 in range(0, M, _BIM_BLOCK):
        b1 = min(M, b0 + _BIM_BLOCK)
        for a in range(2):
            for j in range(5):
                k = 0 if (j == 0 or j == 3) else (2 if j == 4 else 1)
                for i in range(b0, b1):
                    F[j, i - b0] = H[a, j, i] + K[a, j, i] * v[a, k, i]
            sg = sign[a]
            for i in range(b0, b1):
                F2 = F[2, i - b0]
                F3 = F[3, i - b0]
                f[a, 0, i] = sg * F[0, i - b0] + complex(-F2.imag, F2.real)
                f[a, 1, i] = sg * F[1, i - b0] - complex(-F3.imag, F3.real)
                f[a, 2, i] = sg * F[4, i - b0]


@loop("bim_join")
def _bim_join_loop(f, wp, wm, c, s, nrm, O1, O2, O3):
    """The interface's F = wp f+ + wm f- per part, back to components, times nrm."""
    for i in range(c.size):
        FL = wp[0, i] * f[0, 0, i] + wm[0, i] * f[1, 0, i]
        FN = wp[1, i] * f[0, 1, i] + wm[1, i] * f[1, 1, i]
        FT = wp[2, i] * f[0, 2, i] + wm[2, i] * f[1, 2, i]
        cc = c[i]
        ss = -s[i]
        O1[i] = (cc * FL + ss * FT) * nrm
        O3[i] = (cc * FT - ss * FL) * nrm
        O2[i] = FN * nrm




def rotate(c, s, a, b, inverse=False, out=None):
    """(c a + s b, -s a + c b), Eq. (28): components (1, 3) -> channels (II, III) of each
    mode (c = k1/q, s = k3/q); ``inverse`` gives (c a - s b, s a + c b), channels ->
    components. The compiled pass needs a, b, c, s of one shape; other shapes broadcast
    in numpy. ``out``: two arrays to write into (not a or b)."""
    sign = -1.0 if inverse else 1.0
    f = _compiled("rotate")
    a, b = np.asarray(a), np.asarray(b)
    if f is None or not (a.shape == b.shape == np.shape(c) == np.shape(s)) or a.dtype != b.dtype:
        return c * a + sign * s * b, c * b - sign * s * a  # broadcasting (e.g. over time)
    ok = out is not None and all(o.shape == a.shape and o.dtype == a.dtype and o.flags.c_contiguous for o in out)
    o1, o2 = out if ok else (np.empty_like(a), np.empty_like(a))
    f(c.ravel(), s.ravel(), np.ascontiguousarray(a).ravel(), np.ascontiguousarray(b).ravel(), sign,
      o1.ravel(), o2.ravel())
    return o1, o2


def product_predict(V, S, e0, v0, dknown, static, pre, K, dt):
    """Product scheme, one channel, step n >= 2 (cracklab.response): ``dknown += dt V`` in
    place, ``H = static dknown + pre (S + e0 v0)`` and ``F = H + K V``; returns (H, F)."""
    f = _compiled("predict")
    if f is None or not dknown.flags.c_contiguous:
        dknown += dt * V
        H = static * dknown + pre * (S + e0 * v0)
        return H, H + K * V
    H, F = np.empty_like(V), np.empty_like(V)
    f(*(np.ascontiguousarray(a).ravel() for a in (V, S, e0, v0)), dknown.ravel(),
      *(np.ascontiguousarray(np.broadcast_to(a, V.shape)).ravel() for a in (static, pre, K)), float(dt),
      H.ravel(), F.ravel())
    return H, F


def _same(*arrays):
    shape = arrays[0].shape
    return all(isinstance(a, np.ndarray) and a.shape == shape and a.flags.c_contiguous for a in arrays)


def plus_scaled(x, a, y, out=None):
    """x + a y, as a new array or into ``out`` (the same numbers as ``x + a * y``)."""
    f = _compiled("xpay")
    if f is None or not _same(x, y) or x.dtype != float or y.dtype != float:
        return np.add(x, a * y, out=out)
    if out is None:
        out = np.empty_like(x)
    f(out.ravel(), x.ravel(), float(a), y.ravel())
    return out


def plus_mean(y, a, x1, x2, out=None):
    """y + a (x1 + x2), as a new array or into ``out`` (the same numbers as ``y + a * (x1 + x2)``)."""
    f = _compiled("plus_mean")
    if f is None or not _same(y, x1, x2) or not (y.dtype == x1.dtype == x2.dtype == float) or \
            (out is not None and not _same(y, out)):
        return np.add(y, a * (x1 + x2), out=out)
    if out is None:
        out = np.empty_like(y)
    f(out.ravel(), y.ravel(), float(a), x1.ravel(), x2.ravel())
    return out


def add_mean_step(y, a, x1, x2):
    """y += a (x1 + x2) in place (the same numbers as ``y += a * (x1 + x2)``)."""
    return plus_mean(y, a, x1, x2, out=y)


def plus_product(H, K, V, out=None):
    """H + K V (complex H, V; real K per mode), into ``out`` when given (the same numbers as
    ``H + K * V``)."""
    f = _compiled("hkv")
    K = np.broadcast_to(K, V.shape)
    if f is None or not _same(H, V) or not K.flags.c_contiguous:
        return H + K * V
    if out is None or not _same(out, H) or out.dtype != H.dtype:
        out = np.empty_like(H)
    f(out.ravel(), H.ravel(), K.ravel(), V.ravel())
    return out


def shear_correct(c, s, X1, X3, H2, K2, H3, K3, out, scale=1.0):
    """Corrector for 3D shear in one pass: V = rotate(X1, X3) (Eq. 28), F = H + K V per
    channel, and F back to components times ``scale``, into ``out`` = (F1, F3); the same
    numbers as :func:`rotate`, :func:`plus_product`, :func:`rotate` (inverse) and
    ``*= scale`` in turn.  Returns None when the pass cannot run (no numba, or arrays it
    cannot take)."""
    f = _compiled("shear_correct")
    arrs = (c, s, X1, X3, H2, K2, H3, K3) + tuple(out)
    if f is None or not _same(*arrs) or X1.dtype != complex or H2.dtype != complex or out[0].dtype != complex:
        return None
    f(*(a.ravel() for a in arrs[:8]), float(scale), *(a.ravel() for a in arrs[8:]))
    return out


def shear_predict(c, s, ch2, ch3, dt, out, H=(None, None), scale=1.0):
    """Predictor for 3D shear in one pass: for each channel ``(V, S, e0, v0, dknown, static,
    pre, K)`` dknown += dt V, H = static dknown + pre (S + e0 v0), F = H + K V (as
    :func:`product_predict`), then F back to components times ``scale`` into ``out`` =
    (F1, F3).  Returns (H2, H3), written into the arrays ``H`` where given, or None when
    the pass cannot run."""
    f = _compiled("shear_predict")
    if f is None:
        return None
    shape = np.shape(c)
    chans = [[np.ascontiguousarray(np.broadcast_to(a, shape)) if i >= 5 else a for i, a in enumerate(ch)]
             for ch in (ch2, ch3)]
    arrs = [c, s, *chans[0], *chans[1], *out]
    if not _same(*arrs) or any(a.dtype != complex for a in (chans[0][0], chans[0][4], chans[1][4], out[0])):
        return None
    H2, H3 = (h if isinstance(h, np.ndarray) and h.shape == shape and h.dtype == complex and h.flags.c_contiguous
              else np.empty(shape, dtype=complex) for h in H)
    f(c.ravel(), s.ravel(), *(a.ravel() for a in chans[0]), *(a.ravel() for a in chans[1]), float(dt), float(scale),
      H2.ravel(), H3.ravel(), out[0].ravel(), out[1].ravel())
    return H2, H3


# -- the free surface's mirror (solver/spectral.py): the half plane's even and odd fields and
# the doubled cell's field and spectrum.  Each is one compiled pass (numpy without numba:
# the same numbers, the same operations in the same order).
_NONE_R = np.zeros((1, 1))
_NONE_C = np.zeros((1, 1), dtype=complex)


def _check_shapes(what, shape, *arrays):
    """A ValueError unless every array has ``shape`` (the compiled passes do not check bounds)."""
    for a in arrays:
        if np.shape(a) != tuple(shape):
            raise ValueError(f"a {what} of shape {np.shape(a)} where the free surface's transform needs {tuple(shape)}")


def mirror_pack(even, odd, z):
    """z (n1, 2 n3): the doubled cell's field of ``even`` and ``odd`` (n1, n3 + 1; either may
    be None), z_k = e_k + o_k and z_{2 n3 - k} = e_k - o_k (o taken as 0 at k = 0 and n3)."""
    f = _compiled("mirror_pack")
    e = _NONE_R if even is None else np.ascontiguousarray(even, dtype=float)
    o = _NONE_R if odd is None else np.ascontiguousarray(odd, dtype=float)
    half = (z.shape[0], z.shape[1] // 2 + 1)
    _check_shapes("field", half, *(a for a, given in ((e, even), (o, odd)) if given is not None))
    if f is not None:
        f(e, o, even is not None, odd is not None, z)
        return z
    m = z.shape[1] // 2
    x = e if even is not None else np.zeros((z.shape[0], m + 1))
    y = o[:, 1:m] if odd is not None else 0.0
    z[:, 0], z[:, m] = x[:, 0], x[:, m]
    z[:, 1:m] = x[:, 1:m] + y
    z[:, m + 1:] = (x[:, 1:m] - y)[:, ::-1]
    return z


def mirror_separate(W, E=None, O=None):
    """From the doubled cell's spectrum W (n1, n3 + 1) of z = e + o, the spectra of the even
    part E = (W(k1) + conj W(-k1)) / 2 and of the odd part O = (W(k1) - conj W(-k1)) / 2 on
    k1 = 0 .. n1/2, into ``E`` and ``O`` (either may be None)."""
    f = _compiled("mirror_separate")
    _check_shapes("spectrum", (W.shape[0] // 2 + 1, W.shape[1]), *(a for a in (E, O) if a is not None))
    if f is not None:
        f(W, E is not None, O is not None, _NONE_C if E is None else E, _NONE_C if O is None else O)
        return E, O
    n1 = W.shape[0]
    k = np.arange(n1 // 2 + 1)
    w, v = W[k], W[(n1 - k) % n1].conj()
    if E is not None:
        E[...] = 0.5 * (w + v)
    if O is not None:
        O[...] = 0.5 * (w - v)
    return E, O


def mirror_join(E, O, W):
    """Inverse of :func:`mirror_separate`: W (n1, n3 + 1) from the half spectra E (even part)
    and O (odd part), either may be None; on the rows k1 = 0 and n1/2 (each its own
    conjugate) W takes the real part of E and the imaginary part of O."""
    f = _compiled("mirror_join")
    _check_shapes("spectrum", (W.shape[0] // 2 + 1, W.shape[1]), *(a for a in (E, O) if a is not None))
    if f is not None:
        h = W.shape[0] // 2
        f(_NONE_C if E is None else E, _NONE_C if O is None else O, E is not None, O is not None, W[:h + 1], W[h + 1:])
        return W
    n1, h = W.shape[0], W.shape[0] // 2
    a = E if E is not None else np.zeros((h + 1, W.shape[1]), dtype=complex)
    b = O if O is not None else np.zeros((h + 1, W.shape[1]), dtype=complex)
    W[1:h] = a[1:h] + b[1:h]
    W[n1 - 1:h:-1] = (a[1:h] - b[1:h]).conj()
    for k in (0, h):
        W[k] = a[k].real + 1j * b[k].imag
    return W


def mirror_split(z, scale, even=None, odd=None):
    """The half plane's even part (z_k + z_{2 n3 - k}) / 2 and odd part (z_k - z_{2 n3 - k}) / 2
    of the doubled field z, times ``scale``, into ``even`` and ``odd`` (n1, n3 + 1; either
    may be None; the odd part is 0 at k = 0 and n3)."""
    f = _compiled("mirror_split")
    _check_shapes("field", (z.shape[0], z.shape[1] // 2 + 1), *(a for a in (even, odd) if a is not None))
    if f is not None:
        f(z, float(scale), even is not None, odd is not None, _NONE_R if even is None else even,
          _NONE_R if odd is None else odd)
        return even, odd
    m = z.shape[1] // 2
    p, q = z[:, 1:m], z[:, :m:-1]
    if even is not None:
        even[:, 0], even[:, m] = z[:, 0] * scale, z[:, m] * scale
        even[:, 1:m] = 0.5 * (p + q) * scale
    if odd is not None:
        odd[:, 0] = odd[:, m] = 0.0
        odd[:, 1:m] = 0.5 * (p - q) * scale
    return even, odd


def _spectra(shape, *arrays) -> bool:
    """Whether ``arrays`` are C-contiguous complex arrays of ``shape``."""
    return all(isinstance(a, np.ndarray) and a.shape == tuple(shape) and a.dtype == complex and a.flags.c_contiguous
               for a in arrays)


def mirror_rotate(c, s, W, out=None):
    """The channels (II, III) of Eq. (28) of the doubled cell's spectrum W of delta_1 (even)
    plus delta_3 (odd) (solver/spectral.py): :func:`mirror_separate`, then :func:`rotate`,
    in one pass, into ``out`` where given (the same numbers)."""
    f = _compiled("mirror_rotate")
    shape = np.shape(c)
    if f is None or out is None or not (_spectra(shape, *out) and _spectra(W.shape, W) and
                                        c.flags.c_contiguous and s.flags.c_contiguous):
        X1, X3 = mirror_separate(W, np.empty(shape, dtype=complex), np.empty(shape, dtype=complex))
        return rotate(c, s, X1, X3, out=out)
    f(c, s, W, out[0], out[1])
    return out


def mirror_shear_correct(c, s, W, H2, K2, H3, K3, Wout, scale=1.0):
    """:func:`shear_correct` on the doubled cell's spectrum W (delta_1 + delta_3, as from
    :func:`mirror_pack`), its result joined into the doubled spectrum ``Wout`` of the
    inverse transform (:func:`mirror_join`), in one pass; None when it cannot run."""
    f = _compiled("mirror_shear_correct")
    shape = np.shape(c)
    if f is None or not (_same(c, s) and _spectra(shape, H2, H3) and _same(c, K2, K3) and _spectra(W.shape, W, Wout)):
        return None
    h = Wout.shape[0] // 2
    f(c, s, W, H2, K2, H3, K3, float(scale), Wout[:h + 1], Wout[h + 1:])
    return Wout


def mirror_shear_predict(c, s, ch2, ch3, dt, Wout, H=(None, None), scale=1.0):
    """:func:`shear_predict`, its result joined into the doubled spectrum ``Wout`` of the
    inverse transform (:func:`mirror_join`), in one pass; returns (H2, H3) as
    shear_predict does, or None when it cannot run."""
    f = _compiled("mirror_shear_predict")
    if f is None:
        return None
    shape = np.shape(c)
    chans = [[np.ascontiguousarray(np.broadcast_to(a, shape)) if i >= 5 else a for i, a in enumerate(ch)]
             for ch in (ch2, ch3)]
    if not (_same(c, s, *chans[0], *chans[1]) and _spectra(Wout.shape, Wout)) or \
            any(a.dtype != complex for a in (chans[0][0], chans[0][4], chans[1][4])):
        return None
    H2, H3 = (h if isinstance(h, np.ndarray) and h.shape == shape and h.dtype == complex and h.flags.c_contiguous
              else np.empty(shape, dtype=complex) for h in H)
    h = Wout.shape[0] // 2
    f(c, s, *chans[0], *chans[1], float(dt), float(scale), H2, H3, Wout[:h + 1], Wout[h + 1:])
    return H2, H3
