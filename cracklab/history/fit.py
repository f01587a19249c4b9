"""Sums of complex exponentials for the convolution kernels, T >= T0.

The history engine :class:`cracklab.history.exponential.ExponentialEngine` needs,
for each kernel K (C_I, C_II, C_III of eq. 26, or Z = int_T^inf C for the
velocity formulation),

    K(T) ~ sum_p c_p exp(lambda_p T),   Re lambda_p < 0,   T >= T0,

with an absolute error below ``tol * scale`` over the *whole* half line T >= T0,
``scale = max(|K(0)|, max_T |K(T)| / 4)``: |K(0)| for every kernel at nu = 1/4,
but C_I(0) = 4a - 4 - a^3/2 vanishes at nu = 1/3 while C_I itself does not.
This module builds that representation from the exact Laplace transforms.

1. Branch cuts.  L[K](s) is analytic except for the branch points s = +-i and
   s = +-i a (a = c_d/c_s) of sqrt(1 + s^2) = sqrt(s + i) sqrt(s - i) and
   sqrt(1 + s^2/a^2) = sqrt(s + i a) sqrt(s - i a) / a.  With every cut running
   to the left (Re s -> -inf), the Bromwich integral folds onto the cuts and

       K(T) = 2 Re sum_{b in {1, a}} exp(i b T) g_b(T),
       g_b(T) = int_0^inf rho_b(x) exp(-x T) dx,
       rho_b(x) = [F(ib - x - i0) - F(ib - x + i0)] / (2 pi i),

   (the cuts at -i b give the complex conjugates, K being real).  Across the cut
   from i b only the factor sqrt(s - i b) changes sign (+- i sqrt(x)), so the
   jump is evaluated exactly, with no limit.  C_III has the cut at b = 1 only.
   The term -eta s of L[C] is entire and drops out; for Z, L[Z] = (Z(0) - L[C])/s
   has no pole at s = 0 (L[C](0) = Z(0)) and the pole of the formula is off the cuts.
2. Quadrature.  x = exp(u), trapezoid rule in u (step 0.2 over u in [-46, 4.5]),
   which reproduces K to ~1e-11 for T >= 0.5: about 250 real decay rates x_k
   per cut, with complex weights.
3. Reduction.  Each g_b, a smooth non-oscillating function of T, is reduced
   separately by a balanced truncation of the diagonal system
   (A = diag(-x_k), B = weights, C = 1) with log-weighted Gramians
   G_ij = int_{T0/4}^inf exp(-(x_i + x_j) t) dt / t = E1((x_i + x_j) T0/4) (the
   weight dt/t gives every decade of T the same importance, which is what a
   uniform absolute tolerance on T^(-1/2) tails needs; the plain Gramians are
   dominated by the slowest rates).  The reduced exponents are the eigenvalues
   of the projected A; the amplitudes are then refitted by linear least squares
   on log-spaced samples of g_b over [T0, T_fit].  The orders start where each
   cut alone is within tol scale / 4; the cut with the larger error is then
   raised until the combined error is within tol scale / 2 on the check grid.
4. Range.  The reduction works on [T0, T_fit = 1e14]; the result is checked
   (:func:`check_fit`) on a dense grid over [T0, 200], a dense stretch before
   T = 1e5 and 240 log-spaced points per decade up to T = 1e14, and the bound
   2 sum_p |c_p| exp(Re lambda_p 1e14) of the fitted terms beyond is added.  The
   kernels' envelopes (0.35 T^-1/2 for C_I, 0.8 T^-1/2 for C_II and Z_II,
   0.2 T^-1/2 for Z_I, T^-3/2 for mode III, at nu = 1/4) are below 1e-7 past
   1e14, so the representation holds on the whole half line T >= T0: the kernel
   is not truncated, whatever the run length.
5. Tolerance.  The default is 1e-5 scale (5e-6 for C_II and Z_II), ten times
   tighter than a plain 1e-4:
   the error of the transform, Delta L(i w) = int_T0^inf (K_fit - K) e^{-i w T} dT,
   is about ten times the time-domain error near w = c_R/c_s = 0.919 (the Rayleigh
   pole sits 0.08 below the branch point at w = 1, so slow errors add up over
   T ~ 12), and the single-mode response shifts its Rayleigh frequency by
   ~0.1 Delta L(i c_R).  With 1e-4 the amplitude at the 50th Rayleigh period differs
   from the direct engine's by ~6e-3 (mode I, gamma = 0.1); with 1e-5 by <= 3e-4.
   Mode II is more sensitive (|C_II(0)| = 1.19 makes the same relative tolerance
   3.6 times looser in absolute terms): 5e-6 keeps it at ~2.5e-4.

The fit depends only on (kernel, nu, formulation) (and the constants above); it
takes about a second, and :func:`get_fit` caches it in memory and on disk.
"""
from __future__ import annotations

import hashlib
import math
import os
import tempfile
import threading
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import special as sp

from ..elastic import cuts as _cuts
from ..elastic import kernels as _k

__all__ = [
    "ExpFit",
    "FIT_VERSION",
    "DEFAULT_T0",
    "DEFAULT_TOL",
    "T_FIT",
    "cut_density",
    "cut_quadrature",
    "fit_kernel",
    "evaluate",
    "check_fit",
    "get_fit",
    "cache_dir",
    "cache_key",
    "cache_path",
    "load_cached",
    "store_cached",
    "clear_memory_cache",
]

#: bump when anything that changes the fitted numbers changes
FIT_VERSION = 2
#: start of the exponential representation, in T = q c_s t
DEFAULT_T0 = 1.0
#: target absolute error of the representation, relative to the kernel's scale, per kernel
#: (module docstring, item 5)
DEFAULT_TOL = {"I": 1e-5, "II": 5e-6, "III": 1e-5, "H11": 5e-6, "H22": 5e-6, "H12": 5e-6}
#: upper end of the least-squares samples (the check grid ends there too, item 4)
T_FIT = 1e14
#: each cut starts at the order where its own error is within 2 * _CUT_SHARE * tol * scale
_CUT_SHARE = 1.0 / 8.0
#: quadrature in u = log x
_H, _UMIN, _UMAX = 0.2, -46.0, 4.5
#: samples per decade for the least-squares refit and the checks
_PER_DECADE = 60
_MAX_ORDER = 40


@dataclass(frozen=True)
class ExpFit:
    """K(T) ~ Re sum_p coef_p exp(lam_p T) * 2 for T >= T0 (conjugate terms implied).

    ``lam`` and ``coef`` hold one member of each complex-conjugate pair (the
    exponents lie near i b, b in {1, a}): the real kernel is
    ``2 Re sum_p coef_p exp(lam_p T)``, i.e. 2 * len(lam) complex exponentials.
    ``err`` is the maximum absolute error measured on the check grid, ``k0`` = K(0),
    ``scale`` = max(|K(0)|, max_T |K(T)| / 4): the error target is ``tol * scale``.
    """

    kernel: str
    nu: float
    formulation: str
    T0: float
    tol: float
    lam: np.ndarray
    coef: np.ndarray
    err: float
    k0: float
    orders: tuple
    scale: float = math.nan
    T_end: float = math.inf

    @property
    def pairs(self) -> int:
        """Number of conjugate pairs (terms of the upper half plane)."""
        return int(self.lam.size)

    @property
    def P(self) -> int:
        """Number of complex exponentials, conjugates included."""
        return 2 * int(self.lam.size)

    def __call__(self, T):
        return evaluate(self, T)


# ----------------------------------------------------------------------------- cuts
def _check(kernel, formulation):
    if kernel not in _k.ALL_KERNELS:
        raise ValueError(f"kernel must be one of {_k.ALL_KERNELS}, got {kernel!r}")
    if formulation not in ("displacement", "velocity"):
        raise ValueError(f"formulation must be 'displacement' or 'velocity', got {formulation!r}")


def _branch_points(kernel, nu):
    a = _k.wave_speed_ratio(nu)
    return (1.0,) if kernel == "III" else (1.0, a)


def _transform(kernel, s, A, B, a, z0, formulation):
    """L[K](s) in terms of explicit branch values A = sqrt(1+s^2), B = sqrt(1+s^2/a^2)."""
    f = _k.branch_transform(kernel, s, A, B, a)
    if formulation == "velocity":
        f = (z0 - f) / s
    return f


def cut_density(kernel, b, x, *, nu=0.25, formulation="displacement"):
    """rho_b(x) = [F(ib - x - i0) - F(ib - x + i0)] / (2 pi i), x > 0 (complex array).

    ``b`` is 1 or a = c_d/c_s; g_b(T) = int_0^inf rho_b(x) exp(-x T) dx (elastic/cuts.py).
    """
    _check(kernel, formulation)
    a = _k.wave_speed_ratio(nu)
    z0 = _k.static_integral(kernel, nu)
    if b not in (1.0, a):
        raise ValueError(f"b must be 1 or a = {a}, got {b!r}")
    return _cuts.density(lambda s, A, B, aa: _transform(kernel, s, A, B, aa, z0, formulation), b, x, a)


def cut_quadrature(kernel, *, nu=0.25, formulation="displacement", h=_H, umin=_UMIN, umax=_UMAX):
    """[(b, x_k, w_k)] per cut: g_b(T) ~ sum_k w_k exp(-x_k T) (trapezoid rule in log x)."""
    _check(kernel, formulation)
    u = np.arange(umin, umax + 0.5 * h, h)
    x = np.exp(u)
    return [(b, x, cut_density(kernel, b, x, nu=nu, formulation=formulation) * x * h)
            for b in _branch_points(kernel, nu)]


# ----------------------------------------------------------------------------- reduction
def _lowrank_factor(M, rtol=1e-15):
    """F with F F^H ~ M for a Hermitian positive semi-definite M (eigenvalues > rtol max kept)."""
    M = 0.5 * (M + M.conj().T)
    w, V = np.linalg.eigh(M)
    keep = w > rtol * w.max()
    return V[:, keep] * np.sqrt(w[keep])


class _Reducer:
    """Log-weighted balanced truncation of g(T) = sum_k w_k exp(-x_k T), T >= T0."""

    def __init__(self, x, w, T0, T_end=math.inf):
        self.x = x
        bb = w * np.exp(-x * T0 / 2.0)
        z = x[:, None] + x[None, :]
        G = sp.exp1(z * (T0 / 4.0))
        if math.isfinite(T_end):  # log weight on [T0/4, 2 T_end] only
            G = G - sp.exp1(z * (2.0 * T_end))
        lp = _lowrank_factor(G * (bb[:, None] * bb.conj()[None, :]))
        lq = _lowrank_factor(G.astype(complex))
        U, s, Vh = np.linalg.svd(lq.conj().T @ lp)
        self.lp, self.lq, self.U, self.s, self.V = lp, lq, U, s, Vh.conj().T

    def exponents(self, r):
        r = min(r, self.s.size)
        sr = np.sqrt(self.s[:r])
        Tm = self.lp @ self.V[:, :r] / sr
        Wm = self.lq @ self.U[:, :r] / sr
        Ar = Wm.conj().T @ (-self.x[:, None] * Tm)
        return np.linalg.eigvals(Ar)


def _samples(T0, T1, per_decade=_PER_DECADE):
    n = int(math.ceil(per_decade * math.log10(T1 / T0))) + 1
    return np.geomspace(T0, T1, n)


def _sum_exp(lam, coef, T, chunk=4096):
    """sum_p coef_p exp(lam_p T) for real T (array), in chunks."""
    T = np.asarray(T, dtype=float)
    flat = T.ravel()
    out = np.empty(flat.shape, dtype=complex)
    for i in range(0, flat.size, chunk):
        t = flat[i:i + chunk]
        out[i:i + chunk] = np.exp(np.outer(t, lam)) @ coef
    return out.reshape(T.shape)


class _Cut:
    """One branch cut: the quadrature sum g_b and its reductions of increasing order."""

    def __init__(self, b, x, w, T0, T1, T_check, T_end=math.inf):
        self.b, self.x, self.w = b, x, w
        self.T = _samples(T0, T1, _PER_DECADE)
        self.g = _sum_exp(-x + 0j, w, self.T)
        self.T_check = T_check
        self.g_check = _sum_exp(-x + 0j, w, T_check)
        self.red = _Reducer(x, w, T0, T_end)
        self._fits = {}

    def fit(self, r):
        """(lam, coef, error on the check grid) of the order-r reduction."""
        if r not in self._fits:
            lam = self.red.exponents(r)
            # balanced truncation preserves stability; guard against round-off anyway
            lam = np.where(lam.real < 0, lam, -np.abs(lam.real) - 1e-12 + 1j * lam.imag)
            c, *_ = np.linalg.lstsq(np.exp(np.outer(self.T, lam)), self.g, rcond=None)
            err = _sum_exp(lam, c, self.T_check) - self.g_check
            self._fits[r] = (lam, c, err)
        return self._fits[r]

    def smallest(self, target):
        """Smallest order whose maximum error on the check grid is <= target."""
        for r in range(1, _MAX_ORDER + 1):
            if np.abs(self.fit(r)[2]).max() <= target:
                return r
        return _MAX_ORDER


_T_CHECK_END = 1e14


def _check_grid(T0, T_end=_T_CHECK_END):
    """Dense over [T0, 200] (step 0.05), log-spaced to T_end, and a dense stretch of 50 before
    1e5 (whole half line) or before T_end (a finite range)."""
    last = 1e5 if T_end == _T_CHECK_END else T_end
    return np.unique(np.concatenate([np.arange(T0, min(200.0, T_end), 0.05),
                                     _samples(T0, T_end, 4 * _PER_DECADE),
                                     np.arange(max(T0, last - 50.0), last, 0.25), [T_end]]))


def fit_kernel(kernel, *, nu=0.25, formulation="displacement", T0=DEFAULT_T0, tol=None,
               T_fit=T_FIT, T_end=math.inf):
    """Fit K (C or Z of ``kernel``) on [T0, inf) with absolute error <= tol * scale (module doc).

    ``T_end`` (finite) restricts the representation to [T0, T_end], the range a run of known
    length uses: the reduction weights, the samples and the checks stop there.
    The orders of the cuts start where each cut alone is within ``tol scale / 4`` and
    the cut with the larger error is raised until the combined error
    2 |Re sum_b exp(i b T) (g_b,fit - g_b)| is within ``tol scale / 2`` on the check grid;
    :func:`check_fit` then measures the final error against the kernel itself.
    """
    _check(kernel, formulation)
    nu = float(nu)
    T0 = float(T0)
    tol = float(DEFAULT_TOL[kernel] if tol is None else tol)
    if not T0 >= 0.25:
        raise ValueError(f"T0 must be >= 0.25, got {T0!r}")
    k0 = _kernel_at_zero(kernel, nu, formulation)
    scale = _scale(kernel, nu, formulation)
    target = 0.5 * tol * scale
    T_end = float(T_end)
    finite = math.isfinite(T_end)
    Tc = _check_grid(T0, T_end if finite else _T_CHECK_END)
    cuts = [_Cut(b, x, w, T0, T_end if finite else T_fit, Tc, T_end)
            for b, x, w in cut_quadrature(kernel, nu=nu, formulation=formulation)]
    orders = [c.smallest(_CUT_SHARE * 2.0 * tol * scale) for c in cuts]
    while True:
        parts = [np.exp(1j * c.b * Tc) * c.fit(r)[2] for c, r in zip(cuts, orders)]
        err = 2.0 * np.abs(np.sum(parts, axis=0).real).max()
        if err <= target or max(orders) >= _MAX_ORDER:
            break
        worst = int(np.argmax([np.abs(c.fit(r)[2]).max() for c, r in zip(cuts, orders)]))
        orders[worst] += 1
    lam = np.concatenate([c.fit(r)[0] + 1j * c.b for c, r in zip(cuts, orders)])
    coef = np.concatenate([c.fit(r)[1] for c, r in zip(cuts, orders)])
    fit = ExpFit(kernel, nu, formulation, T0, float(tol), lam, coef, math.nan, k0, tuple(orders), scale,
                 T_end)
    err = check_fit(fit)
    if not err <= tol * scale:
        raise RuntimeError(f"exponential fit of {kernel}/{formulation} (nu={nu}) reached only "
                           f"{err / scale:.3g} of the kernel scale (target {tol})")
    return ExpFit(kernel, nu, formulation, T0, float(tol), lam, coef, err, k0, tuple(orders), scale, T_end)


def _scale(kernel, nu, formulation):
    """max(|K(0)|, max_T |K(T)| / 4): C_I(0) vanishes near nu = 1/3 while C_I does not."""
    T = np.linspace(0.0, 30.0, 3001)
    return float(max(abs(_kernel_at_zero(kernel, nu, formulation)),
                     0.25 * np.abs(_kernel(kernel, T, nu, formulation)).max()))


def _kernel_at_zero(kernel, nu, formulation):
    if formulation == "displacement":
        return float(_k.C0(kernel, nu))
    return float(_k.static_integral(kernel, nu))


def _kernel(kernel, T, nu, formulation):
    if formulation == "displacement":
        return np.asarray(_k.C(kernel, T, nu), dtype=float)
    return np.asarray(_k.Z(kernel, T, nu), dtype=float)


def evaluate(fit: ExpFit, T):
    """The fitted kernel 2 Re sum_p coef_p exp(lam_p T) (meaningful for T >= fit.T0)."""
    return 2.0 * _sum_exp(fit.lam, fit.coef, T).real


def check_fit(fit: ExpFit, T=None):
    """Max |K_fit - K| over T (default: the check grid of :func:`fit_kernel`, up to T = 1e14).

    With the default grid, the bound 2 sum |c_p| exp(Re lambda_p 1e14) on the fitted
    terms beyond the grid is added (|K| itself is below 1e-7 there).
    """
    tail = 0.0
    if T is None and math.isfinite(fit.T_end):
        T = _check_grid(fit.T0, fit.T_end)
    elif T is None:
        T = _check_grid(fit.T0)
        tail = float(2.0 * np.sum(np.abs(fit.coef) * np.exp(fit.lam.real * _T_CHECK_END)))
    T = np.asarray(T, dtype=float)
    return float(np.abs(evaluate(fit, T) - _kernel(fit.kernel, T, fit.nu, fit.formulation)).max()) + tail


# ----------------------------------------------------------------------------- cache
_MEMORY: dict = {}
_LOCK = threading.Lock()


def clear_memory_cache():
    """Forget the fits held in memory (the disk cache is kept)."""
    with _LOCK:
        _MEMORY.clear()


def cache_dir() -> Path:
    """$CRACKLAB_CACHE, else $XDG_CACHE_HOME/cracklab, else ~/.cache/cracklab."""
    env = os.environ.get("CRACKLAB_CACHE")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg else Path.home() / ".cache"
    return base / "cracklab"


def cache_key(kernel, nu, formulation, T0, tol, T_end=math.inf) -> tuple:
    """What a fit's numbers depend on (the fit's arguments, FIT_VERSION and the constants of
    the method): the key stored in its cache file and hashed into its name."""
    key = (FIT_VERSION, kernel, float(nu).hex(), formulation, float(T0).hex(), float(tol).hex(),
           float(T_FIT).hex(), _CUT_SHARE, _H, _UMIN, _UMAX)
    return key if not math.isfinite(T_end) else key + (float(T_end).hex(),)


#: a finite range is rounded up to a half decade (>= 1e3); beyond 1e8 the whole half line is fitted
T_END_MIN, T_END_MAX = 1e3, 1e8


def range_bucket(T_end) -> float:
    """The fitted range used for a run that needs [T0, T_end]: a half decade at or above it."""
    if T_end is None or not math.isfinite(T_end) or T_end > T_END_MAX:
        return math.inf
    b = 10.0 ** (math.ceil(2.0 * math.log10(max(float(T_end), T_END_MIN)) - 1e-9) / 2.0)
    return math.inf if b > T_END_MAX else float(b)


def cache_path(key) -> Path:
    """The cache file of the fit of ``key`` (:func:`cache_key`) in :func:`cache_dir`."""
    digest = hashlib.sha256(repr(key).encode()).hexdigest()[:16]
    return cache_dir() / f"expfit-v{FIT_VERSION}-{key[1]}-{key[3]}-{digest}.npz"


def load_cached(path: Path, key, kernel, nu, formulation, T0, tol, T_end=math.inf):
    """The fit cached in ``path`` under ``key``, or None if missing, unreadable, foreign or
    inaccurate (a spot check against the kernel itself)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            if str(z["key"]) != repr(key):
                return None
            lam = np.array(z["lam"], dtype=complex)
            coef = np.array(z["coef"], dtype=complex)
            orders = tuple(int(o) for o in np.array(z["orders"]))
            err = float(z["err"])
    except Exception:  # missing, truncated, corrupt, wrong format: refit
        return None
    if (lam.ndim != 1 or lam.shape != coef.shape or lam.size == 0 or sum(orders) != lam.size
            or not np.all(np.isfinite(lam)) or not np.all(np.isfinite(coef))
            or not np.all(lam.real < 0)):
        return None
    k0 = _kernel_at_zero(kernel, nu, formulation)
    scale = _scale(kernel, nu, formulation)
    fit = ExpFit(kernel, nu, formulation, T0, tol, lam, coef, err, k0, orders, scale, T_end)
    # cheap spot check against the kernel itself (catches silent corruption)
    T = np.concatenate([np.linspace(T0, 60.0, 400), np.geomspace(60.0, min(1e6, T_end), 200)])
    if not np.abs(evaluate(fit, T) - _kernel(kernel, T, nu, formulation)).max() <= tol * scale:
        return None
    return fit


def store_cached(path: Path, key, fit: ExpFit, replace: bool = True):
    """Store ``fit`` in the cache file ``path`` under ``key``, atomically (temp file in the
    same directory, then os.replace); never raises.  ``replace=False``: leave a file that
    another process wrote in the meantime (the first fit stored is the one every process
    then reads, see get_fit)."""
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent)
        with os.fdopen(fd, "wb") as f:
            np.savez(f, key=np.array(repr(key)), lam=fit.lam, coef=fit.coef,
                     orders=np.array(fit.orders), err=np.array(fit.err))
            f.flush()
            os.fsync(f.fileno())
        if not replace:
            try:
                os.link(tmp, path)  # fails if the file is there
            except FileExistsError:
                pass
            except OSError:  # no hard links on this file system
                replace = True
        if replace:
            os.replace(tmp, path)
            tmp = None
    except OSError as exc:
        warnings.warn(f"cracklab: could not write the kernel-fit cache {path}: {exc}", RuntimeWarning,
                      stacklevel=3)
    finally:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass


def get_fit(kernel, nu=0.25, formulation="displacement", *, T0=DEFAULT_T0, tol=None,
            use_disk=True, T_end=None) -> ExpFit:
    """The exponential fit of (kernel, nu, formulation), from memory, disk, or computed.

    ``tol`` defaults to ``DEFAULT_TOL[kernel]``.  ``T_end``: the largest T the caller needs
    (None: the whole half line); the fit covers :func:`range_bucket` (T_end).
    """
    _check(kernel, formulation)
    _k.wave_speed_ratio(nu)  # validates nu
    tol = DEFAULT_TOL[kernel] if tol is None else tol
    nu, T0, tol = float(nu), float(T0), float(tol)
    T_end = range_bucket(T_end)
    key = cache_key(kernel, nu, formulation, T0, tol, T_end)
    path = None
    if use_disk:
        try:
            path = cache_path(key)
        except Exception:  # no usable home directory: memory cache only
            path = None
    # the fits in memory are those of their cache file: the last bits of a fit depend on the
    # process that computed it (BLAS threads), and a run resumed in another process reads
    # the file, so a process must not keep one of its own beside it (nor one of another cache)
    mkey = (str(path), key)
    with _LOCK:
        fit = _MEMORY.get(mkey)
    if fit is not None:
        return fit
    if path is not None:
        existed = path.exists()
        fit = load_cached(path, key, kernel, nu, formulation, T0, tol, T_end)
    if fit is None:
        fit = fit_kernel(kernel, nu=nu, formulation=formulation, T0=T0, tol=tol, T_end=T_end)
        if path is not None:
            # a bad file is replaced; a new one only if no other process stored its fit first,
            # whose fit is then read back and used here too
            store_cached(path, key, fit, replace=existed)
            fit = load_cached(path, key, kernel, nu, formulation, T0, tol, T_end) or fit
    with _LOCK:
        _MEMORY[mkey] = fit
    return fit
