"""Real FFTs between the plane (x1, x3) and its Fourier modes (Eq. 36).

Layout: real transform along x1 (n1//2 + 1 modes), complex transform along x3;
the plane problem (n3 == 1) uses 1D transforms only.
"""
from __future__ import annotations

import os

import numpy as np
import scipy.fft as sfft


class Transforms:
    """Forward and inverse transforms for one grid (scipy.fft backend)."""

    backend = "scipy"

    def __init__(self, grid, workers: int | None = None):
        self.shape = grid.shape
        self.plane = grid.plane
        self.workers = workers or int(os.environ.get("CRACKLAB_FFT_THREADS", "1"))

    def forward(self, x: np.ndarray) -> np.ndarray:
        if self.plane:
            return sfft.rfft(x[:, 0], workers=self.workers)[:, None]
        return sfft.rfftn(x, axes=(1, 0), workers=self.workers)

    def inverse(self, X: np.ndarray) -> np.ndarray:
        if self.plane:
            return sfft.irfft(X[:, 0], n=self.shape[0], workers=self.workers)[:, None]
        return sfft.irfftn(X, s=(self.shape[1], self.shape[0]), axes=(1, 0), workers=self.workers)
