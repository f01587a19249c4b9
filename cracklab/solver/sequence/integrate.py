"""Adaptive integration of a sequence system (quasi_dynamic.py) with an embedded pair
(pairs.py) under a step control (control.py): each step is tried, its error estimated by
the pair, accepted when the largest scaled error is at most 1 and retried shorter when not
(docs/reference/equations.md, "Sequences: the time step")."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import SimulationError
from ...jit import njit


@dataclass(frozen=True)
class Accepted:
    """One accepted step: it ended at ``t`` with the unknowns ``y`` after a step ``dt``;
    ``dt_next`` is the step to try next, ``rejected`` the tries this step threw away."""

    n: int
    t: float
    y: np.ndarray
    dt: float
    dt_next: float
    rejected: int
    rates: np.ndarray       # dy/dt at (t, y): the next step's first stage


def error_norm(system, y_new, err, tolerance):
    """(largest scaled error, its index) of the error estimate ``err`` at the new unknowns:
    |err| / (tolerance * scale) over the points the system integrates (system.error_weights:
    slip against L + |slip|, state against a), in one compiled pass; the first error that is
    not finite when there is one."""
    L, a, keep = system.error_weights()
    size, where = _largest_ratio(err, y_new, L, a, keep, float(tolerance))
    return float(size), int(where)


@njit()
def _largest_ratio(err, y, L, a, keep, tolerance):
    """(largest |err| / (tolerance scale), its index) over the unknowns whose points ``keep``
    holds: scale L + |y| in the slip blocks (one per component), a in the last (psi); the
    first ratio that is not finite when there is one; (0, -1) with none kept."""
    n = keep.size
    blocks = y.size // n
    best, where = 0.0, -1
    for b in range(blocks):
        for i in range(n):
            if not keep[i]:
                continue
            j = b * n + i
            scale = a[i] if b == blocks - 1 else L[i] + abs(y[j])
            r = abs(err[j]) / (tolerance * scale)
            if not (r <= 1e308):            # NaN or inf: this one
                return r, j
            if r > best or where < 0:
                best, where = r, j
    return best, where


def end_step(t, t_end, h, dt_min, split=False):
    """(step, whether it ends the run) for a step of ``h`` from ``t``: the rest of the run when
    h reaches t_end or would leave less than dt_min of it, unless ``split`` (that step
    failed: steps of h until the end)."""
    if split:
        return h, t + h >= t_end * (1 - 1e-15)
    last = t + h >= t_end * (1 - 1e-15) or t_end - (t + h) < dt_min
    return (t_end - t if last else h), last


def integrate(system, y0, t0, t_end, pair, control, *, dt=None, n0=0, rates=None):
    """Accepted steps from (t0, y0) until t_end (the last step ends on it): a generator of
    :class:`Accepted`. ``dt``: the first step to try (default ``control.dt_first``); ``n0``:
    the number of the first step (a resumed run's); ``rates``: dy/dt at (t0, y0) when known
    (a resumed run's: the same numbers as the run that was stopped, whose last stage gave
    them).
    A step that misses the tolerance at ``control.dt_min`` raises SimulationError naming
    the time, the unknown and its values."""
    A, b, e = tableau(pair)
    t, y = float(t0), np.array(y0, dtype=float)
    h = float(dt or control.dt_first)
    k = np.empty((pair.stages, y.size))     # the stages' rates, a row each: a stage's sum is one product
    k[0] = system.rates(t, y) if rates is None else np.asarray(rates, dtype=float)
    n = n0
    while t < t_end:
        rejected, split = 0, False
        while True:
            step, last = end_step(t, t_end, h, control.dt_min, split)
            y_new, err, ok = try_step(system, pair, A, b, e, k, t, y, step)
            size, where = error_norm(system, y_new, err, control.tolerance) if ok else (np.inf, -1)
            if size <= 1.0:
                break
            rejected += 1
            if step <= control.dt_min * (1 + 1e-12):
                raise SimulationError(_failure(system, t, step, y, y_new, err, where, control.tolerance))
            h = control.next_step(step, size, pair.order, accepted=False)
            if last and not split:      # the step that reaches t_end failed: try shorter ones
                h, split = min(h, 0.5 * step), True
        h_next = control.next_step(step, size, pair.order, accepted=True) if not last else h
        t, y = (t_end if last else t + step), y_new
        if pair.fsal:
            k[0] = k[-1]          # the last stage ran at (t, y): system.last is the new point's
        else:
            k[0] = system.rates(t, y)
        n += 1
        yield Accepted(n, t, y, step, h_next, rejected, k[0].copy())
        h = h_next


def tableau(pair):
    """(A rows, b, e) of ``pair`` as arrays: row i of A holds the weights of stages 0 .. i - 1."""
    A = [np.asarray(row, dtype=float)[:i] for i, row in enumerate(pair.a)]
    return A, np.asarray(pair.b, dtype=float), np.asarray(pair.e, dtype=float)


def try_step(system, pair, A, b, e, k, t, y, h):
    """(y_new, error estimate, whether every stage gave finite rates) of one step of ``h``
    from ``y`` with the rates ``k[0]`` there; each stage i is announced to the system
    (``system.stage``: c_i h into the step, the rates of the stages before it, c_0 .. c_i)
    before its rates."""
    try:
        for i in range(1, pair.stages):
            system.stage(pair.c[i] * h, k[:i], pair.c[:i + 1])
            yi = system.stage_rates(t + pair.c[i] * h, y, h, A[i], k, i)
        y_new = yi if pair.fsal else weighted(y, h, b, k)
        err = weighted(None, h, e, k)
    except (SimulationError, FloatingPointError):
        return y, np.full_like(y, np.nan), False
    return y_new, err, bool(np.all(np.isfinite(y_new)))


@njit()
def weighted(y, h, w, k):
    """y + h sum_l w_l k_l (a new array; without y when it is None): a stage's unknowns or
    the error estimate, from the stages' rates (the rows of k, the first w.size of them)."""
    n = k.shape[1]
    acc = np.zeros(n)
    for i in range(w.size):         # row by row: each pass runs along a row of k
        wi = w[i]
        for j in range(n):
            acc[j] += wi * k[i, j]
    if y is None:
        for j in range(n):
            acc[j] *= h
    else:
        for j in range(n):
            acc[j] = y[j] + h * acc[j]
    return acc


def place(system, where) -> str:
    """'node (i, k) (x1 = .., x3 = ..), <unknown>' of the index ``where`` of the unknowns y."""
    part, i = divmod(max(where, 0), system.n)
    names = [f"slip delta_{c}" for c in system.comps] + ["state psi"]
    node = tuple(int(v) for v in np.unravel_index(i, system.grid.shape))
    return (f"node {node} (x1 = {system.grid.x1[node[0]]:g}, x3 = {system.grid.x3[node[1]]:g}), "
            f"{names[min(part, len(names) - 1)]}")


def _failure(system, t, h, y, y_new, err, where, tolerance) -> str:
    return (f"the step cannot meet its tolerance {tolerance:g} at the smallest step allowed, dt_min = {h:.3g} s: at "
            f"t = {t:.9g} s, {place(system, where)} = {y[where]:.6g} -> {y_new[where]:.6g}, error estimate "
            f"{err[where]:.3g}; loosen sequence.tolerance or lower sequence.dt_min")
