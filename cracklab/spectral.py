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


_WISDOM_LOADED = False


def _load_wisdom():
    global _WISDOM_LOADED
    if _WISDOM_LOADED:
        return
    _WISDOM_LOADED = True
    try:
        with open(_wisdom_path(), "rb") as fh:
            pyfftw.import_wisdom(pickle.load(fh))
    except (OSError, EOFError, pickle.UnpicklingError, ValueError, TypeError):
        pass  # no or unreadable wisdom: plan afresh


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
        if self.backend == "pyfftw":
            self._plan()

    def _plan(self):
        _load_wisdom()
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
        _save_wisdom()

    def forward(self, x: np.ndarray) -> np.ndarray:
        if self.backend == "pyfftw":
            self._fwd.input_array[...] = x[:, 0] if self.plane else x
            out = self._fwd().copy()
            return out[:, None] if self.plane else out
        if self.plane:
            return sfft.rfft(x[:, 0], workers=self.workers)[:, None]
        return sfft.rfftn(x, axes=(0, 1), workers=self.workers)

    def inverse(self, X: np.ndarray) -> np.ndarray:
        if self.backend == "pyfftw":
            # copy in: a complex-to-real transform overwrites its input array
            self._inv.input_array[...] = X[:, 0] if self.plane else X
            out = self._inv().copy()  # normalised by 1/N like scipy's inverse
            return out[:, None] if self.plane else out
        if self.plane:
            return sfft.irfft(X[:, 0], n=self.shape[0], workers=self.workers)[:, None]
        return sfft.irfftn(X, s=self.shape, axes=(0, 1), workers=self.workers)
