"""`cracklab bench`: cost per step of the time loop, against a same-process FFT baseline."""
from __future__ import annotations

import resource
import time

import numpy as np

from .grid import Grid
from .laws import TractionFree
from .loading import Loading
from .material import Material
from .record import Record
from .scene import Numerics, Scene
from .spectral import Transforms, backend_name
from .stability import beta_max
from .stepper import Stepper

MODES = {"I": (2,), "II": (1,), "III": (3,), "shear": (1, 3)}


def bench_scene(n1, n3, mode, nsteps, engine="direct", threads=1, engine_threads=None):
    """A traction-free plane under a random load on the components of ``mode``."""
    grid = Grid(n1=n1, n3=n3, L1=1.0, L3=n3 / n1 if n3 > 1 else 1.0)
    rng = np.random.default_rng(0)
    load = {f"tau0_{c}": rng.standard_normal(grid.shape) for c in MODES[mode]}
    comps = tuple(sorted({c for c in MODES[mode]} | ({1, 3} if mode == "shear" and n3 > 1 else set())))
    numerics = Numerics(engine=engine, fft_threads=int(threads),
                        engine_threads=None if engine_threads is None else int(engine_threads))
    beta = 0.9 * beta_max(grid, *numerics.scheme(comps), comps)
    dt = beta * grid.dx_min
    return Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=grid, law=TractionFree(),
                 loading=Loading(**load), t_end=nsteps * dt * (1 - 1e-9), beta=beta,
                 record=Record(fields=()), numerics=numerics, name="bench")


def fft_pair_ms(grid, repeats=50, threads=1):
    f = Transforms(grid, threads)
    x = np.random.default_rng(1).standard_normal(grid.shape)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f.inverse(f.forward(x))
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def run(n1, n3, mode, nsteps, engine="direct", progress=False, threads=1, engine_threads=None):
    scene = bench_scene(n1, n3, mode, nsteps, engine, threads, engine_threads)
    durations = []
    stepper = Stepper(scene)
    overlap = any(ch.engine.overlap for ch in stepper.response.channels.values())
    it = iter(stepper)
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(it, total=scene.nsteps + 1, unit="step", desc="bench")
    t0 = time.perf_counter()
    for _ in it:
        t1 = time.perf_counter()
        durations.append(t1 - t0)
        t0 = t1
    timed = np.asarray(durations[len(durations) // 2:])
    grid = scene.grid
    ms = 1e3 * float(np.median(timed))
    return {
        "n1": n1, "n3": n3, "mode": mode, "steps": scene.nsteps + 1, "engine": engine,
        "timed_steps": int(timed.size), "ms_per_step": ms,
        "us_per_point_per_step": 1e3 * ms / (n1 * n3),
        "threads": int(threads), "engine_threads": scene.numerics.history_threads,
        "overlap": overlap,
        "fft_pair_ms": fft_pair_ms(grid, threads=threads),
        "fft_backend": backend_name(),
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }
