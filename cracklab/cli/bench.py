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


def bench_scene(n1, n3, mode, nsteps, engine="direct", threads=1, engine_threads=None, free_surface=False):
    """A traction-free plane under a random load on the components of ``mode`` (with
    ``free_surface``: the half plane of n1 x (n3 + 1) nodes below a free surface, the odd
    component's load zero on its two lines)."""
    grid = Grid(n1=n1, n3=n3, L1=1.0, L3=n3 / n1 if n3 > 1 else 1.0, free_surface=free_surface)
    rng = np.random.default_rng(0)
    load = {f"tau0_{c}": rng.standard_normal(grid.shape) for c in MODES[mode]}
    if free_surface and "tau0_3" in load:
        load["tau0_3"][:, [0, -1]] = 0.0
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


def run(n1, n3, mode, nsteps, engine="direct", progress=False, threads=1, engine_threads=None, fit_steps=None,
        free_surface=False):
    """Time every step of a bench scene; the median over the second half is the figure.

    The FFT baseline is timed in the same stretch (a pair after every PAIR_EVERY-th timed
    step), and the transforms a step runs are counted, so that ``fft_floor_ms`` (their
    cost at the baseline's rate) can be set against the step on the same host, same minute.
    ``fit_steps``: the exponential engine's kernel fits cover that many steps instead of the
    run's (runs of different lengths then carry the same terms: their costs compare the
    history's length alone). ``free_surface``: the half plane below a free surface
    (``Grid(free_surface=True)``: cosine and sine transforms along x3; the FFT baseline is
    then the pair of an even component, cosine transform and real FFT).
    """
    scene = bench_scene(n1, n3, mode, nsteps, engine, threads, engine_threads, free_surface)
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
    pair_ms = 1e3 * float(np.median(pairs)) if pairs else fft_pair_ms(scene.grid, threads=threads,
                                                                      components=scene.components)
    return {
        "n1": n1, "n3": n3, "free_surface": bool(free_surface), "mode": mode, "steps": scene.nsteps + 1,
        "engine": engine,
        "timed_steps": int(timed.size), "ms_per_step": ms,
        "us_per_point_per_step": 1e3 * ms / (scene.grid.shape[0] * scene.grid.shape[1]),
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
