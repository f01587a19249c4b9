"""Compiling cracklab's loops with numba: one compile helper (``njit``) and, for the
elementwise loops of a step, one registry and one decorator (``loop``).

``njit(**options)`` is numba.njit with what every cracklab loop takes: cached on disk and
releasing the GIL; a loop adds its own options (the engine's ``parallel`` and
``fastmath``, the laws' ``error_model="numpy"``).

A loop is a plain Python function over flat arrays, registered with ``@loop(name)``; its
callers take the compiled version with ``compiled_loop(name)`` (None without numba, or
inside ``python_only()``, where they run the numpy expressions that give the same numbers).
Every loop is compiled the same way: on first use, cached on disk, without fast-math, with
numpy's error model (a division by zero gives inf or NaN, as in the numpy expressions,
instead of a check per element that keeps the pass from vectorising). The bottom layer of
cracklab: imports nothing of it.
"""
from __future__ import annotations

import contextlib

#: name -> the loop's Python function; name -> its compiled version (None: not available)
_PY: dict = {}
_JIT: dict = {}
_STATE = {"python_only": False}


def njit(**options):
    """numba.njit(cache=True, nogil=True, **options): the decorator of every compiled loop."""
    import numba

    return numba.njit(**{"cache": True, "nogil": True, **options})


def loop(name: str):
    """Register the decorated function as the loop ``name`` (returned unchanged)."""
    def register(fn):
        if name in _PY and _PY[name] is not fn:
            raise ValueError(f"a loop named {name!r} is registered already ({_PY[name].__module__})")
        _PY[name] = fn
        return fn
    return register


def compiled_loop(name: str):
    """The numba version of loop ``name`` (None without numba, or within ``python_only``)."""
    if _STATE["python_only"]:
        return None
    if name not in _JIT:
        try:
            import numba  # noqa: F401
        except Exception:  # pragma: no cover
            _JIT[name] = None
        else:
            _JIT[name] = njit(error_model="numpy")(_PY[name])
    return _JIT[name]


def available() -> bool:
    """Whether the compiled loops run (numba imports, and not within ``python_only``)."""
    if _STATE["python_only"]:
        return False
    try:
        import numba  # noqa: F401
    except Exception:  # pragma: no cover
        return False
    return True


@contextlib.contextmanager
def python_only():
    """Within the block, every step runs the numpy expressions instead of the compiled loops
    (to check that the two give the same numbers)."""
    saved = _STATE["python_only"]
    _STATE["python_only"] = True
    try:
        yield
    finally:
        _STATE["python_only"] = saved
