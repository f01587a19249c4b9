"""The step of the fully dynamic sequences (dynamic.py; docs/reference/equations.md,
"Sequences: the dynamic response at a variable step"): a predictor-corrector in the manner
of Lapusta et al. (2000), with y = (slip, state) and f = dy/dt = (slip rate, state rate):

    predict:  y* = y_n + h f_n,              f* = f(t_n + h, y*; history with V(t_n + h) = V_n)
    correct:  y' = y_n + h (f_n + f*) / 2,   f' = f(t_n + h, y'; history with V(t_n + h) = V*)

for the slip, the state psi exactly at the constant slip rate V_n (predict) and (V_n + V*) / 2
(correct) by the law's state update (``system.advance``), and the end's slip rate V' = f'
is pushed into the history. The error of the step is y' - y* (on slip h (f* - f_n) / 2:
Euler against the trapezoid, an embedded pair of order 2),
held within the tolerance as the quasi-dynamic pairs are (integrate.py); but no step is
shorter than ``control.dt_min``, the dynamic step beta dx / c_s: a step there is taken
whatever its estimate, as the fixed-step ruptures are (it is their step).

While the plane is slow (its largest slip rate below ``slow_rate``) a step is one of the
embedded ``pair`` (integrate.py's, of order 5 by default) on the same system: stage i is
evaluated at t_n + c_i h with the history prepared for a step of c_i h and the end's slip
rate in its newest piece extrapolated from stages i - 2 and i - 1 (dynamic.FullyDynamic.stage).
That rate enters the traction only through the radiation-damping term, whose effect on the
solved slip rate is the factor eta V / (sigma a) or less (0.1 at the default ``slow_rate``),
so its error, of order 3 in h, is not seen by the pair's estimate but stays about the
tolerance (tests/sequence/test_dynamic_response.py), and the long slow phases take the
pair's long steps instead of the second-order ones'."""
from __future__ import annotations

import numpy as np

from ...errors import SimulationError
from .integrate import Accepted, end_step, error_norm, place, tableau, try_step

ORDER = 2


#: a slow step of the pair shorter than this many dynamic steps is left to the predictor-corrector
SLOW_STEPS = 10


def integrate_dynamic(system, y0, t0, t_end, control, *, dt=None, n0=0, rates=None, pair=None, slow_rate=0.0):
    """Accepted steps of the fully dynamic ``system`` from (t0, y0) until t_end: a generator
    of :class:`integrate.Accepted`, as :func:`integrate.integrate`. ``rates``: f at (t0, y0)
    when known (a resumed run's; its history is the system's state). ``pair`` (an
    :class:`pairs.EmbeddedPair`, or None): the step while the largest slip rate is below
    ``slow_rate`` and the step at least SLOW_STEPS dynamic steps long."""
    t, y = float(t0), np.array(y0, dtype=float)
    h = max(float(dt or control.dt_first), control.dt_min)
    if rates is None:
        f = system.rates(t, y)
        system.start(f)
    else:
        f = np.array(rates, dtype=float)
    n = n0
    floor = control.dt_min * (1 + 1e-12)
    tab = None if pair is None else tableau(pair)
    k = None if pair is None else np.empty((pair.stages, y.size))
    while t < t_end:
        rejected, split = 0, False
        slow = tab is not None and h >= SLOW_STEPS * control.dt_min and _slow(system, f, slow_rate)
        while True:
            step, last = end_step(t, t_end, h, control.dt_min, split)
            if slow:
                y_new, f_new, err, ok = _try_pair(system, pair, tab, k, t, y, f, step)
            else:
                y_new, f_new, err, ok = _try(system, t, y, f, step)
            size, where = error_norm(system, y_new, err, control.tolerance) if ok else (np.inf, -1)
            if size <= 1.0 or (ok and step <= floor):
                break
            if step <= floor:
                raise SimulationError(_failure(system, t, step, y_new, f_new))
            rejected += 1
            h = control.next_step(step, size, pair.order if slow else ORDER, accepted=False)
            if slow and h < SLOW_STEPS * control.dt_min:     # too short for the pair: the dynamic step
                slow = False
            if last and not split:      # the step that reaches t_end failed: try shorter ones
                h, split = min(h, 0.5 * step), True
        h_next = control.next_step(step, size, pair.order if slow else ORDER, accepted=True) if not last else h
        system.response.commit(system.rate_fields(f_new))
        t, y, f = (t_end if last else t + step), y_new, f_new
        n += 1
        yield Accepted(n, t, y, step, h_next, rejected, f)
        h = h_next


def _try(system, t, y, f, h):
    """(y', f', error estimate, whether the rates stayed finite) of one step of ``h``."""
    system.response.prepare(h)
    try:
        system.v_end = system.rate_fields(f)
        y_p = system.advance(y, f, f, h)
        f_p = system.rates(t + h, y_p)
        y_c = system.advance(y, f, f_p, h)
        system.v_end = system.rate_fields(f_p)
        f_c = system.rates(t + h, y_c)
    except (SimulationError, FloatingPointError):
        return y, f, np.full_like(y, np.nan), False
    return y_c, f_c, y_c - y_p, bool(np.all(np.isfinite(y_c)) and np.all(np.isfinite(f_c)))


def _slow(system, f, slow_rate) -> bool:
    """Whether the largest slip rate of the rates ``f`` is below ``slow_rate``."""
    speed = system._speed(f)
    return bool(speed.size == 0 or speed.max() < slow_rate)


def _try_pair(system, pair, tab, k, t, y, f, h):
    """(y', f', error estimate, whether the rates stayed finite) of one step of ``pair``
    (integrate.try_step, each stage preparing the history: ``FullyDynamic.stage``), f' at
    (t + h, y') with the history prepared for h (what :meth:`DynamicResponse.commit` then pushes)."""
    k[0] = f
    y_new, err, ok = try_step(system, pair, *tab, k, t, y, h)
    if not ok:
        return y, f, err, False
    try:
        if pair.fsal:
            f_new = k[-1].copy()
        else:
            system.stage(h, k[-1:], (1.0,))
            f_new = system.rates(t + h, y_new)
    except (SimulationError, FloatingPointError):
        return y, f, np.full_like(y, np.nan), False
    return y_new, f_new, err, bool(np.all(np.isfinite(f_new)))


def _failure(system, t, h, y_new, f_new) -> str:
    """The message of a step at the floor whose values are not finite, at the first such unknown."""
    bad = np.flatnonzero(~(np.isfinite(y_new) & np.isfinite(f_new)))
    where = (f"{place(system, int(bad[0]))} = {y_new[bad[0]]:.6g}, rate {f_new[bad[0]]:.6g}" if bad.size
             else "the interface law's solve failed")
    return (f"the fully dynamic step gave non-finite values at the dynamic step dt = {h:.3g} s: at t = {t:.9g} s, "
            f"{where}; lower beta")
