"""How often a run into a store checkpoints: ``checkpoint_every`` of ``simulate``."""
from __future__ import annotations

import numpy as np

from ..errors import InputError

CHECKPOINT_SECONDS = 60.0


def checkpoint_policy(value):
    """(every N steps, every S seconds of wall time) from ``checkpoint_every``."""
    err = InputError("checkpoint_every", f"must be an integer >= 0 (steps; 0: never) or a duration "
                                         f"like '60s' (seconds of wall time, > 0), got {value!r}")
    if value is None:
        return None, CHECKPOINT_SECONDS
    if isinstance(value, str):
        text = value.strip().lower()
        if text.endswith("s"):
            try:
                sec = float(text[:-1])
            except ValueError:
                raise err from None
            if not (sec > 0 and np.isfinite(sec)):
                raise err
            return None, sec
        try:
            value = int(text)
        except ValueError:
            raise err from None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise err
    return (int(value) or None), None
