"""`cracklab bench`: cost per step of the time loop, against a same-process FFT baseline.

``law``: "traction_free" (the default: a traction-free plane under a random load),
"slip_weakening" (a TPV3-like rupture: slip weakening, 120 MPa, a 3 km overstressed
patch) or "rate_state" (a TPV101-like rupture: the ageing law, V_ini 1e-12 m/s, the
forced nucleation) on a plane of 100 m cells, both along x1 (x3 for mode III), with the
same time-step rule; the rate-and-state bench reports its Newton evaluations."""
from __future__ import annotations

import dataclasses

import resource
import threading
import time

import numpy as np

from ..model.grid import Grid
from ..laws import RateState, SlipWeakening, TractionFree
from ..model.loading import Loading
from ..model.material import Material
from ..model.record import Record
from ..solver.interfaces import for_scene as interface_for_scene
from ..model.scene import Numerics, Scene
from ..solver.spectral import Transforms, backend_name
from ..solver.stability import beta_max
from ..solver.stepper import Stepper
from ..errors import InputError

MODES = {"I": (2,), "II": (1,), "III": (3,), "shear": (1, 3), "mixed": (1, 2, 3)}
LAWS = ("traction_free", "slip_weakening", "rate_state")


#: the bottom of the bimaterial bench, per unit top (mu = cs = 1, nu = 1/4): a compliant side
BIMATERIAL_BOTTOM = dict(mu=0.6, cs=0.8, nu=0.3)


def bench_scene(n1, n3, mode, nsteps, engine="direct", threads=1, engine_threads=None, law="traction_free",
                free_surface=False, bimaterial=False):
    """A traction-free plane under a random load on the components of ``mode`` (with
    ``free_surface``: the half plane of n1 x (n3 + 1) nodes below a free surface, the odd
    component's load zero on its two lines); or, with ``law`` "slip_weakening" or
    "rate_state", a rupture on a plane of 100 m cells (module docstring), loaded along x1
    (x3 for mode III). ``bimaterial``: the bottom half space of another material
    (BIMATERIAL_BOTTOM, scaled with the top's), product scheme; the traction-free bench
    then takes the pair's stable limit (Scene.beta_max) where that is lower."""
    scene = _bench_scene(n1, n3, mode, nsteps, engine, threads, engine_threads, law, free_surface)
    if not bimaterial:
        return scene
    top = scene.material
    bottom = Material(mu=top.mu * BIMATERIAL_BOTTOM["mu"], cs=top.cs * BIMATERIAL_BOTTOM["cs"],
                      nu=BIMATERIAL_BOTTOM["nu"])
    two = scene.replace(materials=(top, bottom), numerics=dataclasses.replace(scene.numerics, formulation="product"),
                        beta=None)
    # the same steps, at the pair's own stable limit where it is below the one material's beta
    beta = min(scene.beta, two.beta_max)
    return two.replace(beta=beta, t_end=scene.nsteps * beta * two.grid.dx_min / two.material.cs * (1 - 1e-9))


def _bench_scene(n1, n3, mode, nsteps, engine, threads, engine_threads, law, free_surface):
    if law not in LAWS:
        raise InputError("law", f"must be one of {', '.join(LAWS)}, got {law!r}")
    if law != "traction_free" and mode == "I":
        raise InputError("mode", f"the {law} bench is a shear rupture: mode II, III or shear, got I")
    if law != "traction_free" and mode == "mixed":
        raise InputError("mode", f"the {law} bench is a shear rupture: mode II, III or shear, got mixed")
    if law != "traction_free" and free_surface:
        raise InputError("free_surface", f"the {law} bench is a whole-space rupture; --free-surface goes with "
                                         f"the traction_free bench")
    numerics = Numerics(engine=engine, fft_threads=int(threads),
                        engine_threads=None if engine_threads is None else int(engine_threads))
    if law == "traction_free":
        grid = Grid(n1=n1, n3=n3, L1=1.0, L3=n3 / n1 if n3 > 1 else 1.0, free_surface=free_surface)
        rng = np.random.default_rng(0)
        load = {f"tau0_{c}": rng.standard_normal(grid.shape) for c in MODES[mode]}
        if free_surface and "tau0_3" in load:
            load["tau0_3"][:, [0, -1]] = 0.0
        comps = tuple(sorted({c for c in MODES[mode]} | ({1, 3} if mode == "shear" and n3 > 1 else set())))
        beta = 0.9 * beta_max(grid, *numerics.scheme(comps), comps, nu=0.25)
        dt = beta * grid.dx_min
        return Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=grid, law=TractionFree(),
                     loading=Loading(**load), t_end=nsteps * dt * (1 - 1e-9), beta=beta,
                     record=Record(fields=()), numerics=numerics, name="bench")
    dx = 100.0
    grid = Grid(n1=n1, n3=n3, L1=n1 * dx, L3=n3 * dx if n3 > 1 else 1.0)
    mat = Material(mu=2670.0 * 3464.0**2, cs=3464.0, nu=0.25)
    c = 3 if mode == "III" else 1
    comps = (1, 3) if n3 > 1 else (c,)
    beta = 0.9 * beta_max(grid, *numerics.scheme(comps), comps, nu=0.25)
    xc, zc = grid.x1[n1 // 2], grid.x3[n3 // 2]
    x1, x3 = np.meshgrid(grid.x1 - xc, grid.x3 - zc, indexing="ij")
    if law == "slip_weakening":      # TPV3's friction and load, the whole plane a fault
        patch = (np.abs(x1) <= 1500.0) & (np.abs(x3) <= 1500.0)
        rule = SlipWeakening(mu_s=0.677, mu_d=0.525, D_c=0.40, sigma_n=120.0e6)
        load = Loading(**{f"tau0_{c}": np.where(patch, 81.6e6, 70.0e6)})
    else:                            # TPV101's friction (the velocity-weakening box) and nucleation
        from ..scenes import taper

        box = taper(x1, 15000.0, 3000.0) * taper(x3, 7500.0, 3000.0)
        rule = RateState(a=0.008 + 0.008 * (1.0 - box), b=0.012, L=0.02, V0=1e-6, f0=0.6, sigma_n=120e6,
                         V_ini=1e-12)
        load = Loading(**{f"tau0_{c}": 75e6, f"nucleation_dtau_{c}": 25e6}, nucleation_radius=3000.0,
                       nucleation_time=1.0, nucleation_x1=float(xc), nucleation_x3=float(zc))
    dt = beta * grid.dx_min / mat.cs
    return Scene(material=mat, grid=grid, law=rule, loading=load, t_end=nsteps * dt * (1 - 1e-9), beta=beta,
                 record=Record(fields=()), numerics=numerics, units={"length": "m", "time": "s", "stress": "Pa"},
                 name=f"bench_{law}")


class _Pair:
    """One forward and one inverse transform of the grid as a step runs them (into work
    arrays, the inverse destroying its input and carrying 1/N: no copy, no scaling pass).

    With a free surface and ``components`` holding the odd one (3D shear), the transforms of
    a step take an even and the odd component together (``Transforms.forward_components``):
    the pair is then half the time of that pair of components, the cost per component."""

    def __init__(self, grid, threads=1, components=(2,)):
        self.f = f = Transforms(grid, threads)
        self.comps = (1, 3) if f.mirror and 3 in components else (2,)
        rng = np.random.default_rng(1)
        self.x = {c: f.empty(spectral=False) for c in self.comps}
        for c, x in self.x.items():
            x[...] = rng.standard_normal(grid.shape)
            if f.mirror and c == 3:
                x[:, [0, -1]] = 0.0
        self.X = {c: f.empty() for c in self.comps}
        self.y = {c: f.empty(spectral=False) for c in self.comps}

    def __call__(self) -> float:
        """Seconds for one pair."""
        f = self.f
        if len(self.comps) == 1:
            c = self.comps[0]
            t0 = time.perf_counter()
            f.forward(self.x[c], out=self.X[c])
            f.inverse(self.X[c], out=self.y[c], overwrite=True, prescaled=True)
            return time.perf_counter() - t0
        t0 = time.perf_counter()
        f.forward_components(self.x, self.X)
        f.inverse_components(self.X, self.y, prescaled=True)
        return 0.5 * (time.perf_counter() - t0)


def fft_pair_ms(grid, repeats=50, threads=1, components=(2,)):
    """Median of ``repeats`` transform pairs (:class:`_Pair`), ms."""
    pair = _Pair(grid, threads, components)
    return 1e3 * float(np.median([pair() for _ in range(repeats)]))


#: in the timed half of a bench, one FFT pair is timed after every PAIR_EVERY-th step
PAIR_EVERY = 10

#: the stages of a step that ``run`` reports (``stages_ms``), in order: the transforms
#: (Transforms' calls), the engines' advance of their states (push's advance, launch), the
#: product rule's start-up weights E_0 (start_weight, and its value computed ahead with the
#: advance: zero in the displacement scheme), the caller's wait for an advance that runs on
#: the engines' worker thread (the engine's join less any advance the caller does in it:
#: zero without the overlap), the taps (push less its advance and wait), the law (update,
#: strength, solve, applied_strength) and the glue (the rest of the step: the scheme's
#: passes, the load, the growth check)
STAGES = ("transforms", "advance", "start", "wait", "taps", "law", "glue")
#: in the timed half, the steps alternate in blocks of STAGE_BLOCK: plain (the median
#: ``ms_per_step``), then timed by stage (``stages_ms``); a block spans every eighth of the
#: exponential engine's staggered advance
STAGE_BLOCK = 8
#: the step timed by stage (``stages_total_ms``, what the stages sum to) against the plain
#: step (``ms_per_step``): within this fraction on a host that is not overloaded (the
#: clock's own cost is a few microseconds per wrapped call, tens of calls per step; the
#: two are different steps of one run, means and medians of a noisy host). ``stages_vs_step``
#: is the ratio; the text report says when it is outside.
STAGE_SLACK = 0.25


class StageClock:
    """Exclusive time per stage on the thread that made it (a stage's call inside another's
    counts for the inner one only), through wrappers that :meth:`install` sets on the
    instances a step calls and :meth:`remove` takes off again: only a bench's timed steps
    carry them, and the library's code is not touched. A wrapped call on another thread
    (the engines' worker) is summed in ``worker`` instead."""

    def __init__(self, stepper):
        self.thread = threading.get_ident()
        self.spent = dict.fromkeys(STAGES[:-1], 0.0)
        self.worker = 0.0
        self._stack, self._mark = [], 0.0
        response, law = stepper.response, stepper.scene.law
        engines = [ch.engine for ch in response.channels.values()]
        targets = [(response.fft, name, "transforms") for name in
                   ("forward", "inverse", "forward_components", "inverse_components", "forward_pair", "inverse_pair")]
        targets += [(law, name, "law") for name in ("update", "strength", "solve", "applied_strength")]
        for engine in engines:
            targets += [(engine, "push", "taps"), (engine, "launch", "advance")]
            targets += [(engine, name, stage) for name, stage in
                        (("_advance", "advance"), ("_join", "wait"), ("start_weight", "start"),
                         ("_start_into", "start"))
                        if hasattr(engine, name)]
        self._targets = [t for t in targets if hasattr(t[0], t[1])]
        self.installed = False

    def _timed(self, stage, fn):
        clock = self

        def call(*args, **kwargs):
            if threading.get_ident() != clock.thread:
                t0 = time.perf_counter()
                try:
                    return fn(*args, **kwargs)
                finally:
                    clock.worker += time.perf_counter() - t0
            now = time.perf_counter()
            if clock._stack:
                clock.spent[clock._stack[-1]] += now - clock._mark
            clock._stack.append(stage)
            clock._mark = now
            try:
                return fn(*args, **kwargs)
            finally:
                now = time.perf_counter()
                clock.spent[clock._stack.pop()] += now - clock._mark
                clock._mark = now

        return call

    def install(self) -> None:
        """Time the stages from now on (instance attributes over the classes' methods; a
        frozen law takes them through object.__setattr__)."""
        for obj, name, stage in self._targets:
            object.__setattr__(obj, name, self._timed(stage, getattr(obj, name)))
        self.installed = True

    def remove(self) -> None:
        """Back to the classes' own methods."""
        for obj, name, _ in self._targets:
            object.__delattr__(obj, name)
        self.installed = False

    def read(self) -> dict:
        """Seconds spent so far per stage (but glue) on the clock's thread."""
        return dict(self.spent)


def run(n1, n3, mode, nsteps, engine="direct", progress=False, threads=1, engine_threads=None, fit_steps=None,
        law="traction_free", free_surface=False, bimaterial=False):
    """Time every step of a bench scene; the median over the second half is the figure.

    The FFT baseline is timed in the same stretch (a pair after every PAIR_EVERY-th timed
    step), and the transforms a step runs are counted, so that ``fft_floor_ms`` (their
    cost at the baseline's rate) can be set against the step on the same host, same minute.
    ``fit_steps``: the exponential engine's kernel fits cover that many steps instead of the
    run's (runs of different lengths then carry the same terms: their costs compare the
    history's length alone). ``law``: the bench scene's law (:func:`bench_scene`); the
    rate-and-state one reports the Newton evaluations and solves per point and step of the
    second half and the most evaluations one solve took. ``free_surface``: the half plane
    below a free surface (``Grid(free_surface=True)``: cosine and sine transforms along x3;
    the FFT baseline is then the pair of an even component, cosine transform and real FFT).

    Where the time goes: the timed half alternates blocks of STAGE_BLOCK plain steps (the
    median ``ms_per_step``, ``timed_steps``) with blocks timed by stage (:class:`StageClock`):
    ``stages_ms``, the mean ms per step of each of STAGES over the steps whose totals are in
    the middle half, ``stages_total_ms`` the mean of those totals (the stages sum to it, and
    it is the plain step's cost plus the clock's own, a few microseconds per wrapped call),
    ``stages_vs_step`` that total over ``ms_per_step`` (1 within STAGE_SLACK),
    ``stages_fft_pairs`` each stage in units of the in-run FFT pair (``fft_pair_ms``),
    ``stage_steps`` the steps timed by stage.
    With the overlap (two or more engine threads) the advance on the worker is not in the
    step's stages; the caller's ``wait`` for it is, and ``worker_ms`` is the worker's busy
    time per step (the wrapped advances and start-up weights it ran).
    """
    scene = bench_scene(n1, n3, mode, nsteps, engine, threads, engine_threads, law, free_surface, bimaterial)
    stepper = Stepper(scene, interface_for_scene(scene, Transforms(scene.grid, threads), nsteps=fit_steps))
    response = stepper.response
    overlap = any(ch.engine.overlap for ch in response.channels.values())
    pair = _Pair(scene.grid, threads, scene.components)
    it = iter(stepper)
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(it, total=scene.nsteps + 1, unit="step", desc="bench")
    half = (scene.nsteps + 1) // 2  # the second half is timed
    durations, pairs, counted, skip = [], [], 0, False
    clock, staged, before = StageClock(stepper), [], None
    newton = (None, None)
    t0 = time.perf_counter()
    for n, _ in enumerate(it):
        elapsed = time.perf_counter() - t0
        if clock.installed:
            if not skip:   # this step by stage: its total, then each stage's share
                after = clock.read()
                staged.append([elapsed] + [after[s] - before[s] for s in STAGES[:-1]])
            durations.append(np.nan)
            clock.remove()
        else:
            durations.append(np.nan if skip else elapsed)
        skip = False
        if n == half - 1:
            counted = response.fft.count
            newton = _newton_counts(stepper.lstate)
        elif n >= half and (n - half) % PAIR_EVERY == PAIR_EVERY - 1:
            # the baseline in the same stretch of time as the steps it is compared with,
            # the engines' worker idle; the step after it (its advance done here) is not timed
            response.wait()
            pairs.append(pair())
            skip = True
        if n + 1 >= half and ((n + 1 - half) // STAGE_BLOCK) % 2 == 1:
            clock.install()
            before = clock.read()
        t0 = time.perf_counter()
    if clock.installed:
        clock.remove()
    timed = np.asarray(durations[half:])
    transforms = (response.fft.count - counted) / max(1, timed.size)
    evaluations, solves = (None, None)
    if newton[0] is not None:
        points_steps = max(1, timed.size) * n1 * n3
        end = _newton_counts(stepper.lstate)
        evaluations, solves = ((end[i] - newton[i]) / points_steps for i in (0, 1))
    timed = timed[np.isfinite(timed)]
    ms = 1e3 * float(np.median(timed))
    stages = stage_breakdown(staged)
    pair_ms = 1e3 * float(np.median(pairs)) if pairs else fft_pair_ms(scene.grid, threads=threads,
                                                                      components=scene.components)
    staged_total = stage_total(staged)
    return {
        "n1": n1, "n3": n3, "free_surface": bool(free_surface), "bimaterial": bool(bimaterial), "mode": mode,
        "law": law, "formulation": scene.formulation,
        "steps": scene.nsteps + 1, "engine": engine,
        "timed_steps": int(timed.size), "ms_per_step": ms,
        "us_per_point_per_step": 1e3 * ms / (scene.grid.shape[0] * scene.grid.shape[1]),
        "threads": int(threads), "engine_threads": scene.numerics.history_threads,
        "overlap": overlap,
        "fft_pair_ms": pair_ms,
        "fft_pairs_timed": len(pairs),
        "transforms_per_step": transforms,
        "fft_floor_ms": 0.5 * transforms * pair_ms,
        "fit_steps": max(scene.nsteps, fit_steps or 0),
        "stage_steps": len(staged),
        "stages_ms": stages,
        "stages_total_ms": staged_total,
        "stages_vs_step": None if staged_total is None else staged_total / ms,
        "stages_fft_pairs": None if stages is None else {stage: v / pair_ms for stage, v in stages.items()},
        "worker_ms": 1e3 * clock.worker / len(staged) if overlap and staged else None,
        "terms": {name: getattr(ch.engine, "pairs", None) for name, ch in response.channels.items()},
        "fft_backend": backend_name(),
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "newton_evaluations_per_point_step": evaluations,
        "newton_solves_per_point_step": solves,
        "newton_most_evaluations": stepper.lstate.get("newton_most") if evaluations is not None else None,
    }


def stage_table(result) -> str:
    """The text report of where a bench's step goes: a row per stage (ms per step, in units
    of the in-run FFT pair, share of the step timed by stage), their sum, and that sum set
    against the plain step (``ms_per_step``) with STAGE_SLACK; with the overlap, the
    worker's time beside the step. "" for a result without stages."""
    stages, pair = result.get("stages_ms"), result["fft_pair_ms"]
    if not stages:
        return ""
    total = result["stages_total_ms"]
    lines = [f"where the time goes, by stage: ms per step (the mean of the {result['stage_steps']} steps timed "
             f"by stage whose totals are in the middle half)",
             f"and in units of the in-run FFT pair ({pair:.4g} ms)",
             f"  {'stage':<12}{'ms':>10}{'x FFT pair':>12}{'share':>9}"]
    rows = list(stages.items()) + [("sum", total)]
    for stage, ms in rows:
        lines.append(f"  {stage:<12}{ms:>10.3f}{ms / pair:>12.2f}{100 * ms / total:>7.1f} %")
    if result.get("worker_ms") is not None:
        ms = result["worker_ms"]
        lines.append(f"  {'(worker)':<12}{ms:>10.3f}{ms / pair:>12.2f}{'-':>7}    the engines' advance, "
                     f"beside the step")
    ratio = total / result["ms_per_step"]
    within = abs(ratio - 1) <= STAGE_SLACK
    lines.append(f"  the stages sum to {total:.4g} ms, the plain step's median is {result['ms_per_step']:.4g} ms: "
                 f"{100 * (ratio - 1):+.1f} %, " + (f"within the {100 * STAGE_SLACK:.0f} % slack" if within else
                                                    f"outside the {100 * STAGE_SLACK:.0f} % slack (a busy host: "
                                                    f"rerun, or time more --steps)"))
    return "\n".join(lines)


def _middle(rows):
    """The rows of the steps timed by stage whose totals are in the middle half (the
    outliers of a shared host left out), as an array."""
    a = np.asarray(rows, dtype=float)
    lo, hi = np.percentile(a[:, 0], [25, 75])
    keep = (a[:, 0] >= lo) & (a[:, 0] <= hi)
    return a[keep] if keep.any() else a


def stage_breakdown(rows) -> dict | None:
    """{stage: ms per step} of the steps timed by stage, ``rows`` of [total, then the
    seconds of each stage of STAGES but glue]; glue is each step's total less its stages.
    Means over the steps whose totals are in the middle half: they sum to
    ``stage_total(rows)`` (a per-stage median would not: the spread of a loaded host falls
    in one stage or another from step to step)."""
    if not rows:
        return None
    a = _middle(rows)
    per = np.column_stack([a[:, 1:], a[:, 0] - a[:, 1:].sum(axis=1)])
    return {stage: 1e3 * float(np.mean(per[:, i])) for i, stage in enumerate(STAGES)}


def stage_total(rows) -> float | None:
    """ms per step of the steps ``stage_breakdown`` averages."""
    return 1e3 * float(np.mean(_middle(rows)[:, 0])) if rows else None


def _newton_counts(state):
    """(Newton evaluations, Newton solves) of a rate-and-state law's state so far, (None, None) for other laws."""
    return (state["newton_evaluations"], state["newton_solves"]) if "newton_solves" in state else (None, None)
