"""The mirror of a sequence's plane about x1 = 0 (``Sequence.mirror``: a free surface of the
plane problem, the grid holding the fault and its image)."""
from __future__ import annotations

import numpy as np


def mirror_index(shape) -> np.ndarray:
    """The flat index of each node's image about x1 = 0 on a grid of ``shape``: (i, k) -> (n1 - i, k)."""
    n1, n3 = shape
    i = (-np.arange(n1)) % n1
    return (i[:, None] * n3 + np.arange(n3)[None, :]).ravel()
