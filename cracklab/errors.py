"""Errors raised for bad input and failed runs."""


class InputError(ValueError):
    """A scene or argument is invalid; ``field`` names the offending input."""

    def __init__(self, field: str, message: str):
        self.field = field
        super().__init__(f"{field}: {message}")


class SimulationError(RuntimeError):
    """A run stopped because the solution became non-finite or grew without bound."""


# The range of the scalars that set the scales of a problem (moduli, wave speeds, lengths,
# times, beta, ...): wide enough for any unit system, narrow enough that every quantity
# derived from a few of them (a density mu / cs^2, dx = L / n, q_max = pi / dx, the time
# step beta dx / cs, their products) is a finite, normal float.
MIN_SCALE = 1e-100
MAX_SCALE = 1e100
SCALE_RANGE = "[1e-100, 1e100]"


def check_positive(field: str, value, *, allow_zero: bool = False) -> float:
    """Return ``value`` as float, or raise InputError naming ``field``: a finite number
    > 0 (>= 0 with ``allow_zero``) in [MIN_SCALE, MAX_SCALE] (or 0)."""
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InputError(field, f"must be a number, got {_shown(value)}") from None
    if not x == x or x in (float("inf"), float("-inf")):
        raise InputError(field, f"must be finite, got {value!r}")
    if x < 0 or (x == 0 and not allow_zero):
        raise InputError(field, f"must be {'>= 0' if allow_zero else '> 0'}, got {value!r}")
    if x != 0 and not MIN_SCALE <= x <= MAX_SCALE:
        raise InputError(field, f"must be {'0 or ' if allow_zero else ''}in {SCALE_RANGE}, got {x!r}")
    return x


def _shown(value, limit=80) -> str:
    """A short repr for a message (an integer too long for repr as its size)."""
    if isinstance(value, int) and value.bit_length() > 256:
        return f"an integer of about {int(value.bit_length() * 0.30103)} digits"
    try:
        text = repr(value)
    except Exception:  # noqa: BLE001 - a value whose repr fails
        text = f"a {type(value).__name__}"
    return text if len(text) <= limit else text[:limit - 3] + "..."


MAX_NESTING = 32        # levels of lists and tables in an input (a scene needs 4)


def check_nesting(data, where: str = "", limit: int = MAX_NESTING):
    """Raise one InputError naming the field when lists, tuples and dicts in ``data`` nest
    deeper than ``limit`` levels (iterative: any depth is checked without recursion, so
    that no message or check later recurses through the value)."""
    stack = [(data, where, 0)]
    while stack:
        value, path, depth = stack.pop()
        if isinstance(value, dict):
            items = ((f"{path}.{k}" if path else str(k), v) for k, v in value.items())
        elif isinstance(value, (list, tuple)):
            items = ((path, v) for v in value)
        else:
            continue
        if depth >= limit:
            raise InputError(path or "toml", f"must not nest arrays or tables deeper than {limit} levels")
        stack.extend((v, p, depth + 1) for p, v in items if isinstance(v, (dict, list, tuple)))


def check_fields_nesting(obj, section: str = ""):
    """``check_nesting`` over the fields of the dataclass ``obj`` (named <section>.<field>)."""
    import dataclasses

    check_nesting({f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}, section)


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


class DiskBudgetError(InputError):
    """A run's store would need more disk than its file system has free: raised before
    any step, with the bound on the output's size and the free space (cracklab.output.disk)."""


class MemoryBudgetError(InputError):
    """A run (or a sweep's workers) would need more memory than is available: raised
    before any step, with the estimate and the memory available (cracklab.solver.budget)."""


class Interrupted(KeyboardInterrupt):
    """A run stopped by Ctrl-C (SIGINT) between two steps: ``step`` is the last step
    taken, and the store's checkpoint holds the run after it (a resume continues there)."""

    def __init__(self, step: int, store=None):
        self.step = int(step)
        self.store = None if store is None else str(store)
        super().__init__(f"interrupted at step {self.step}")


class SchedulerError(InputError):
    """The dask scheduler of a sweep cannot be reached (raised within a few seconds,
    before the store is touched); ``field`` names the option or variable that gave it."""
