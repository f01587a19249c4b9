"""`cracklab bench`: cost per step of the time loop, against a same-process FFT baseline."""
from __future__ import annotations

import resource
import time

import numpy as np

from ..model.grid import Grid
from ..laws import TractionFree
from ..model.loading import Loading
from ..model.material import Material
from ..model.record import Record
from ..solver.interfaces import for_scene as interface_for_scene
from ..model.scene import Numerics, Scene
from ..solver.spectral import Transforms, backend_name
from ..solver.stability import beta_max
from ..solver.stepper import Stepper

MODES = {"I": (2,), "II": (1,), "III": (3,), "shear": (1, 3)}


def bench_scene(n1, n3, mode, nsteps, engine="direct", threads=1, engine_threads=None):
    """A traction-free plane under a random load on the components of ``mode``."""
    grid = Grid(n1=n1, n3=n3, L1=1.0, L3=n3 / n1 if n3 > 1 else 1.0)
    rng = np.random.default_rng(0)
    load = {f"tau0_{c}": rng.standard_normal(grid.shape) for c in MODES[mode]}
    comps = tuple(sorted({c for c in MODES[mode]} | ({1, 3} if mode == "shear" and n3 > 1 else set())))
    numerics = Numerics(engine=engine, fft_threads=int(threads),
                        engine_threads=None if engine_threads is None else int(engine_threads))
    beta = 0.9 * beta_max(grid, *numerics.scheme(comps), comps, nu=0.25)
    dt = beta * grid.dx_min
    return Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=grid, law=TractionFree(),
                 loading=Loading(**load), t_end=nsteps * dt * (1 - 1e-9), beta=beta,
                 record=Record(fields=()), numerics=numerics, name="bench")


class _Pair:
    """One forward and one inverse transform of the grid as a step runs them (into work
    arrays, the inverse destroying its input and carrying 1/N: no copy, no scaling pass)."""

    def __init__(self, grid, threads=1):
        self.f = f = Transforms(grid, threads)
        self.x = f.empty(spectral=False)
        self.x[...] = np.random.default_rng(1).standard_normal(grid.shape)
        self.X, self.y = f.empty(), f.empty(spectral=False)

    def __call__(self) -> float:
        """Seconds for one pair."""
        f = self.f
        t0 = time.perf_counter()
        f.forward(self.x, out=self.X)
        f.inverse(self.X, out=self.y, overwrite=True, prescaled=True)
        return time.perf_counter() - t0


def fft_pair_ms(grid, repeats=50, threads=1):
    """Median of ``repeats`` transform pairs (:class:`_Pair`), ms."""
    pair = _Pair(grid, threads)
    return 1e3 * float(np.median([pair() for _ in range(repeats)]))


#: in the timed half of a bench, one FFT pair is timed after every PAIR_EVERY-th step
PAIR_EVERY = 10


def run(n1, n3, mode, nsteps, engine="direct", progress=False, threads=1, engine_threads=None, fit_steps=None):
    """Time every step of a bench scene; the median over the second half is the figure.

    The FFT baseline is timed in the same stretch (a pair after every PAIR_EVERY-th timed
    step), and the transforms a step runs are counted, so that ``fft_floor_ms`` (their
    cost at the baseline's rate) can be set against the step on the same host, same minute.
    ``fit_steps``: the exponential engine's kernel fits cover that many steps instead of the
    run's (runs of different lengths then carry the same terms: their costs compare the
    history's length alone).
    """
    scene = bench_scene(n1, n3, mode, nsteps, engine, threads, engine_threads)
    stepper = Stepper(scene, interface_for_scene(scene, Transforms(scene.grid, threads), nsteps=fit_steps))
    response = stepper.response
    overlap = any(ch.engine.overlap for ch in response.channels.values())
    pair = _Pair(scene.grid, threads)
    it = iter(stepper)
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(it, total=scene.nsteps + 1, unit="step", desc="bench")
    half = (scene.nsteps + 1) // 2  # the second half is timed
    durations, pairs, counted, skip = [], [], 0, False
    t0 = time.perf_counter()
    for n, _ in enumerate(it):
        durations.append(np.nan if skip else time.perf_counter() - t0)
        skip = False
        if n == half - 1:
            counted = response.fft.count
        elif n >= half and (n - half) % PAIR_EVERY == PAIR_EVERY - 1:
            # the baseline in the same stretch of time as the steps it is compared with,
            # the engines' worker idle; the step after it (its advance done here) is not timed
            response.wait()
            pairs.append(pair())
            skip = True
        t0 = time.perf_counter()
    timed = np.asarray(durations[half:])
    transforms = (response.fft.count - counted) / max(1, timed.size)
    timed = timed[np.isfinite(timed)]
    ms = 1e3 * float(np.median(timed))
    pair_ms = 1e3 * float(np.median(pairs)) if pairs else fft_pair_ms(scene.grid, threads=threads)
    return {
        "n1": n1, "n3": n3, "mode": mode, "steps": scene.nsteps + 1, "engine": engine,
        "timed_steps": int(timed.size), "ms_per_step": ms,
        "us_per_point_per_step": 1e3 * ms / (n1 * n3),
        "threads": int(threads), "engine_threads": scene.numerics.history_threads,
        "overlap": overlap,
        "fft_pair_ms": pair_ms,
        "fft_pairs_timed": len(pairs),
        "transforms_per_step": transforms,
        "fft_floor_ms": 0.5 * transforms * pair_ms,
        "fit_steps": max(scene.nsteps, fit_steps or 0),
        "terms": {name: getattr(ch.engine, "pairs", None) for name, ch in response.channels.items()},
        "fft_backend": backend_name(),
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }
