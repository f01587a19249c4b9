"""Kernel tables shared by every run in a process: the convolution weights of the
direct history engine, memoised by what determines them.

A weight table w_j(gamma) (rows j, columns the distinct gamma = q c_s dt of a grid) is
a pure function of (kernel, the distinct gamma values, the j range, nu, rule,
formulation). Every run on the same grid, material and time step asks for the same
tables, so an ensemble worker computes them once and every later member on that grid
reuses them (``DirectEngine._weights`` calls :func:`weight_table`; the exponential
engine's exact direct taps go through :func:`memoised`). The cache is an
LRU bounded by the total size of the tables it holds (``CRACKLAB_KERNEL_CACHE_MB``,
default 256 MB; 0 turns caching off). Cached tables are read-only.

``stats`` counts kernel evaluations (``computed``), cache hits (``hits``) and the bytes
held; :func:`clear` empties the cache and resets the counters.
"""
from __future__ import annotations

import hashlib
import os
import threading
from collections import OrderedDict

import numpy as np

DEFAULT_MB = 256.0

_cache: OrderedDict = OrderedDict()
_lock = threading.Lock()
stats = {"computed": 0, "hits": 0, "bytes": 0, "entries": 0}


def max_bytes() -> int:
    """The cache bound in bytes (env CRACKLAB_KERNEL_CACHE_MB, default 256 MB)."""
    try:
        mb = float(os.environ.get("CRACKLAB_KERNEL_CACHE_MB", DEFAULT_MB))
    except ValueError:
        mb = DEFAULT_MB
    return max(0, int(mb * 2**20))


def digest(a) -> str:
    """A digest of an array's dtype, shape and bytes."""
    a = np.ascontiguousarray(a)
    h = hashlib.sha1(f"{a.dtype.str}:{a.shape}:".encode())
    h.update(a.tobytes())
    return h.hexdigest()


def _compute(kernel, gamma, j0, j1, nu, rule, formulation):
    j = np.arange(j0, j1)[:, None]
    if rule == "product":
        from ..elastic.weights import product_weights

        w = product_weights(kernel, gamma[None, :], j, nu=nu, order=1, part="lag")
    else:
        from ..elastic.weights import convolution_weights

        w = convolution_weights(kernel, gamma[None, :], j, nu=nu, rule=rule, formulation=formulation)
    return np.ascontiguousarray(np.broadcast_to(w, (j1 - j0, gamma.size)), dtype=float)


def memoised(key: tuple, compute):
    """``compute()`` (an array), memoised under ``key`` in the same bounded LRU cache as
    :func:`weight_table` (the result is read-only)."""
    limit = max_bytes()
    with _lock:
        hit = _cache.get(key)
        if hit is not None:
            _cache.move_to_end(key)
            stats["hits"] += 1
            return hit
    w = np.ascontiguousarray(compute())
    w.setflags(write=False)
    with _lock:
        stats["computed"] += 1
        if 0 < w.nbytes <= limit and key not in _cache:
            _cache[key] = w
            stats["bytes"] += w.nbytes
            while stats["bytes"] > limit and _cache:
                _, old = _cache.popitem(last=False)
                stats["bytes"] -= old.nbytes
        stats["entries"] = len(_cache)
    return w


def weight_table(kernel, gamma, j0: int, j1: int, *, nu, rule="trapezoid",
                 formulation="displacement") -> np.ndarray:
    """w_j(gamma) for j in [j0, j1) (rows) and each value of the 1-D array ``gamma``
    (columns): ``convolution_weights`` for the rules of Eqs. (45)-(47), or the
    product-integration lag weights for rule "product". Memoised (read-only result)."""
    gamma = np.ascontiguousarray(gamma, dtype=float).ravel()
    j0, j1 = int(j0), int(j1)
    key = (str(kernel), digest(gamma), j0, j1, float(nu), str(rule), str(formulation))
    return memoised(key, lambda: _compute(kernel, gamma, j0, j1, nu, rule, formulation))


def cached_tables() -> list:
    """The tables the cache holds (read-only arrays), least recently used first."""
    with _lock:
        return list(_cache.values())


def clear() -> None:
    """Empty the cache and reset the counters."""
    with _lock:
        _cache.clear()
        stats.update(computed=0, hits=0, bytes=0, entries=0)
