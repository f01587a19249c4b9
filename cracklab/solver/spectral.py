"""Real FFTs between the plane (x1, x3) and its Fourier modes (Eq. 36).

Layout (Grid.spectral_shape): in 3D a real transform along x3, the contiguous axis
(n3//2 + 1 modes), and a complex one along x1; the plane problem (n3 == 1) uses 1D real
transforms along x1 only.

Backends: pyfftw when it is installed (plans made once per grid with FFTW_MEASURE,
wisdom cached per host under the user cache directory), otherwise scipy.fft.
Choose with the environment variable CRACKLAB_FFT=pyfftw|scipy; threads with
``workers`` or CRACKLAB_FFT_THREADS.
"""
from __future__ import annotations

import contextlib
import os
import pickle
import socket
import tempfile
from pathlib import Path

import numpy as np
import scipy.fft as sfft

try:  # optional fast backend
    import pyfftw
except ImportError:  # pragma: no cover - exercised on machines without pyfftw
    pyfftw = None


def cache_dir() -> Path:
    """Per-user cache directory ($CRACKLAB_CACHE, else $XDG_CACHE_HOME/cracklab)."""
    root = os.environ.get("CRACKLAB_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME", os.path.expanduser("~/.cache")), "cracklab")
    return Path(root)


def _wisdom_path() -> Path:
    return cache_dir() / f"fftw-wisdom-{socket.gethostname()}.pickle"


def _load_wisdom():
    """Make the host's wisdom file the process's wisdom (when it can be read): every plan is
    then the one the file holds for its size, whichever process measured it first, so that
    a run and its resumption in another process transform with the same plan (and give the
    same numbers to the bit).  Without a readable file the process keeps its own wisdom."""
    try:
        with open(_wisdom_path(), "rb") as fh:
            wisdom = pickle.load(fh)
    except (OSError, EOFError, pickle.UnpicklingError, ValueError, TypeError):
        return  # no or unreadable wisdom: plan afresh
    pyfftw.forget_wisdom()
    try:
        pyfftw.import_wisdom(wisdom)
    except (ValueError, TypeError):
        pass


def _save_wisdom():
    path = _wisdom_path()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".wisdom-")
        with os.fdopen(fd, "wb") as fh:
            pickle.dump(pyfftw.export_wisdom(), fh)
        os.replace(tmp, path)  # atomic: concurrent writers never leave a torn file
    except OSError:
        pass  # a read-only cache only costs planning time


@contextlib.contextmanager
def _wisdom_lock():
    """Plans are made one process at a time per host (a lock file beside the wisdom): the
    first to plan a size measures it and saves it, the others then read it (_load_wisdom)."""
    try:
        import fcntl

        path = _wisdom_path().with_suffix(".lock")
        path.parent.mkdir(parents=True, exist_ok=True)
        fh = open(path, "a")
    except (ImportError, OSError):
        yield  # no locking here (another platform, or a read-only cache)
        return
    try:
        fcntl.flock(fh, fcntl.LOCK_EX)
        yield
    finally:
        fh.close()  # releases the lock


def backend_name() -> str:
    choice = os.environ.get("CRACKLAB_FFT", "pyfftw" if pyfftw is not None else "scipy")
    return "pyfftw" if choice == "pyfftw" and pyfftw is not None else "scipy"


class Transforms:
    """Forward and inverse transforms for one grid."""

    def __init__(self, grid, workers: int | None = None, backend: str | None = None):
        self.shape = grid.shape
        self.plane = grid.plane
        self.workers = int(workers or os.environ.get("CRACKLAB_FFT_THREADS", "1"))
        self.backend = backend or backend_name()
        self.spectral_shape = grid.spectral_shape
        #: 1/N, the factor of the inverse transform (see ``inverse(prescaled=True)``)
        self.norm = 1.0 / (self.shape[0] * self.shape[1])
        #: transforms run so far, forward and inverse (``cracklab bench`` counts them per step)
        self.count = 0
        if self.backend == "pyfftw":
            self._plan()

    def _plan(self):
        with _wisdom_lock():
            _load_wisdom()
            self._make_plans()
            _save_wisdom()

    def _make_plans(self):
        n1, n3 = self.shape
        flags = ("FFTW_MEASURE",)
        if self.plane:
            a = pyfftw.empty_aligned(n1, dtype="float64")
            b = pyfftw.empty_aligned(n1 // 2 + 1, dtype="complex128")
            self._fwd = pyfftw.FFTW(a, b, threads=self.workers, flags=flags)
            self._inv = pyfftw.FFTW(b.copy(), a.copy(), direction="FFTW_BACKWARD", threads=self.workers,
                                    flags=flags)
        else:
            a = pyfftw.empty_aligned((n1, n3), dtype="float64")
            b = pyfftw.empty_aligned((n1, n3 // 2 + 1), dtype="complex128")
            self._fwd = pyfftw.FFTW(a, b, axes=(0, 1), threads=self.workers, flags=flags)
            self._inv = pyfftw.FFTW(pyfftw.empty_aligned(b.shape, dtype="complex128"),
                                    pyfftw.empty_aligned(a.shape, dtype="float64"), axes=(0, 1),
                                    direction="FFTW_BACKWARD", threads=self.workers, flags=flags)

    def empty(self, spectral: bool = True) -> np.ndarray:
        """A work array the transforms read or write in place (``out=``, ``overwrite=``):
        complex of the spectral shape, or real of the grid's shape (aligned for FFTW)."""
        shape, dtype = (self.spectral_shape, complex) if spectral else (self.shape, float)
        if self.backend == "pyfftw":
            return pyfftw.empty_aligned(shape, dtype=dtype)
        return np.empty(shape, dtype=dtype)

    def forward(self, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Spectrum of the real field x: a new array, or written into ``out`` (spectral shape)."""
        self.count += 1
        if self.backend == "pyfftw":
            fwd = self._fwd
            src = x[:, 0] if self.plane else x
            if out is None:
                fwd.input_array[...] = src
                fwd.execute()
                res = fwd.output_array.copy()
                return res[:, None] if self.plane else res
            # a real-to-complex plan leaves its input alone: run it from x itself when it can
            if not (src.dtype == np.float64 and src.flags.c_contiguous and src.shape == fwd.input_array.shape
                    and pyfftw.is_byte_aligned(src, fwd.input_alignment)):
                fwd.input_array[...] = src
                src = fwd.input_array
            self._execute_into(fwd, src, out)
            return out
        if self.plane:
            res = sfft.rfft(x[:, 0], workers=self.workers)[:, None]
        else:
            res = sfft.rfftn(x, axes=(0, 1), workers=self.workers)
        if out is None:
            return res
        out[...] = res
        return out

    def inverse(self, X: np.ndarray, out: np.ndarray | None = None, overwrite: bool = False,
                prescaled: bool = False) -> np.ndarray:
        """Real field of the spectrum X (normalised by 1/N like scipy's inverse): a new array,
        or written into ``out``; ``overwrite=True`` lets the transform destroy X (no copy in);
        ``prescaled=True``: X already carries the factor :attr:`norm` = 1/N (no pass for it)."""
        self.count += 1
        if self.backend == "pyfftw":
            inv = self._inv
            src = X[:, 0] if self.plane else X
            if not (overwrite and out is not None and pyfftw.is_byte_aligned(src, inv.input_alignment)
                    and src.flags.c_contiguous):
                inv.input_array[...] = src  # a complex-to-real transform overwrites its input
                src = inv.input_array
            if out is None:
                inv.execute()
                res = inv.output_array.copy() if prescaled else inv.output_array * self.norm
                return res[:, None] if self.plane else res
            self._execute_into(inv, src, out)
            if not prescaled:
                np.multiply(out, self.norm, out=out)
            return out
        norm = "forward" if prescaled else "backward"
        if self.plane:
            res = sfft.irfft(X[:, 0], n=self.shape[0], workers=self.workers, norm=norm)[:, None]
        else:
            res = sfft.irfftn(X, s=self.shape, axes=(0, 1), workers=self.workers, norm=norm)
        if out is None:
            return res
        out[...] = res
        return out

    def _execute_into(self, plan, src, out):
        """Run ``plan`` from src into out (in place when out has the plan's alignment)."""
        view = out[:, 0] if self.plane else out
        own_in, own_out = plan.input_array, plan.output_array
        if view.shape != own_out.shape:
            raise ValueError(f"out has shape {out.shape}, the transform gives {own_out.shape}")
        if not ((pyfftw.is_byte_aligned(view, plan.output_alignment) and pyfftw.is_byte_aligned(src, plan.input_alignment)) and view.flags.c_contiguous):
            if src is not own_in:
                own_in[...] = src
            plan.execute()
            view[...] = own_out
            return
        plan.update_arrays(src, view)
        try:
            plan.execute()
        finally:
            plan.update_arrays(own_in, own_out)  # the plan keeps its own arrays between calls
