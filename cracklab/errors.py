"""Errors raised for bad input and failed runs."""


class InputError(ValueError):
    """A scene or argument is invalid; ``field`` names the offending input."""

    def __init__(self, field: str, message: str):
        self.field = field
        super().__init__(f"{field}: {message}")


class SimulationError(RuntimeError):
    """A run stopped because the solution became non-finite or grew without bound."""


def check_positive(field: str, value, *, allow_zero: bool = False) -> float:
    """Return ``value`` as float, or raise InputError naming ``field``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(field, f"must be a number, got {value!r}") from None
    if not x == x or x in (float("inf"), float("-inf")):
        raise InputError(field, f"must be finite, got {value!r}")
    if x < 0 or (x == 0 and not allow_zero):
        raise InputError(field, f"must be {'>= 0' if allow_zero else '> 0'}, got {value!r}")
    return x


class StoreError(RuntimeError):
    """A run's Zarr store cannot be used: not a cracklab store, another format, not
    writable, disk full, nothing to resume, damaged (the message names the damaged file
    and what to do). ``path`` names the store."""

    def __init__(self, path, message: str):
        self.path = str(path)
        super().__init__(f"store {self.path}: {message}")


class StoreWarning(UserWarning):
    """A store was found damaged and is being repaired (a run redone from the start, an
    ensemble member recomputed); the message names the damaged files."""
