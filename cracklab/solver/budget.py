"""The memory and the time a run needs, known before it starts.

``run_memory(scene)`` estimates the bytes of a run from the scene alone (no array of the
grid's size is made): the history engines' states (the largest part), the work arrays of
a step (fields, spectra, the law's and the load's fields, FFT buffers) and what the
recorder keeps in memory (station series, pending snapshots, rupture times; every
snapshot for a run into memory). ``available_memory()`` is what this machine (and this
process's limits) can give; ``check_memory`` refuses a run, or a sweep's workers, that
does not fit, with one ``MemoryBudgetError`` giving both figures. ``calibrate`` times a
few steps of the run and extrapolates its run time.

The estimate is checked against the peak resident memory of real runs, of one material
and of two, with slip weakening and with rate and state (tests/solver/test_budget.py:
within a factor 1.5 above the interpreter's own memory), and against the arrays a
bimaterial and a rate-and-state run allocate (tracemalloc): the arrays held while
stepping within -5 %/+25 %, the total never under the run's peak and at most 1.5 times it.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass

import numpy as np

from ..errors import MemoryBudgetError
from ..elastic.modes import gammas_sample, modes  # noqa: F401  (budget.modes, as before)

#: resident memory of a fresh process running a member (interpreter, numpy, xarray,
#: zarr, numba, pyfftw and the compiled loops): the baseline of a sweep's worker
PROCESS_BYTES = 400 << 20
#: env variable capping the memory cracklab counts as available ("8GB", "512MB", bytes)
LIMIT_ENV = "CRACKLAB_MEMORY_LIMIT"
_FLUSH = 8              # snapshots the recorder keeps before writing them to the store
#: what a sequence's recorder keeps before it writes to its store (output/sequence.py): its
#: snapshots up to this many bytes, its rows of station series up to this many (a write
#: costs about a tenth of a second whatever it holds; a checkpoint writes them too)
SEQUENCE_SNAPSHOT_BYTES = 32 << 20
SEQUENCE_ROWS = 16384


@dataclass(frozen=True)
class MemoryEstimate:
    """Estimated bytes of one run, by part: ``history`` (the engines' states), ``work``
    (work arrays of a step), ``setup`` (what the engines' temporaries add above the history
    at their peak: an engine's set-up, its exact weights and fits, beside the states of the
    engines built before it and its own, freed before the first step; or the direct
    engine's growth), ``records`` (what the recorder keeps in memory); ``steps``: the run's
    number of steps."""

    history: int
    work: int
    records: int
    steps: int
    setup: int = 0

    @property
    def total(self) -> int:
        """Bytes of the run's arrays at their peak (the interpreter's own memory not
        included): the set-up's excess over the history on top of the rest."""
        return self.history + self.work + self.setup + self.records

    def describe(self) -> str:
        """"about 1.2 GB (history 1.0 GB, work arrays 150 MB, set-up 30 MB, records 20 MB)"."""
        setup = f", set-up {fmt_bytes(self.setup)}" if self.setup else ""
        return (f"about {fmt_bytes(self.total)} (history {fmt_bytes(self.history)}, work arrays "
                f"{fmt_bytes(self.work)}{setup}, records {fmt_bytes(self.records)})")


def fmt_bytes(n: float) -> str:
    """Bytes in the largest unit that keeps the number >= 1 (kB, MB, GB, TB; powers of 1024)."""
    for unit, size in (("TB", 1 << 40), ("GB", 1 << 30), ("MB", 1 << 20), ("kB", 1 << 10)):
        if abs(n) >= size:
            return f"{n / size:.3g} {unit}"
    return f"{int(n)} B"


def parse_bytes(text) -> int:
    """Bytes from "8GB", "512 MB", "1.5g" or a plain number of bytes; ValueError otherwise."""
    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:e[+-]?[0-9]+)?)\s*([kmgt]?)i?b?\s*", str(text).lower())
    if not m:
        raise ValueError(f"not a size: {text!r} (give bytes, or a number with kB, MB, GB or TB)")
    return int(float(m.group(1)) * 1024 ** " kmgt".index(m.group(2) or " "))


def run_memory(scene, *, store=True) -> MemoryEstimate:
    """The memory a run of ``scene`` needs, estimated from the scene (``store``: the run
    streams its snapshots to a store and keeps a few in memory; False: it keeps them all)."""
    from ..history import ENGINES, resolve_engine
    from .interfaces import interface_type
    from .schemes import scheme_of

    if scene.sequence is not None:
        return _sequence_memory(scene, store)
    grid = scene.grid
    comps = scene.components
    scheme = scheme_of(scene.formulation)
    engine = ENGINES[resolve_engine(scene.numerics.engine, scene.numerics.window)]
    iface = interface_type(scene.materials)
    # (kernel, material) of each engine the scene's interface builds, in the order it builds
    # them (the identical pair: one per channel the active components drive; two materials:
    # each face's channels of its own material). An engine's set-up temporaries come while
    # the engines built before it and its own states are held (extra_at_build); an engine
    # whose extra comes as its history grows has every engine beside it then. An engine of
    # the kernel and material of one built before it shares what the engine says it shares
    # (the bimaterial face's two coupling channels: the exact taps and the start-up weight)
    history, peak, grows, built = 0, 0, 0, []
    for kernel, material in iface.engine_channels(scene):
        held, extra = engine.memory(scene, kernel, scheme, material, shared=(kernel, material) in built)
        built.append((kernel, material))
        history += held
        if engine.extra_at_build:
            peak = max(peak, history + extra)
        else:
            grows = max(grows, extra)
    building = max(peak - history, grows)
    N = grid.shape[0] * grid.shape[1]
    M = modes(grid)
    nc = len(comps)
    # per component: slip, rate, traction, f, trial slip and two temporaries of a step; the
    # interface's arrays of one value per mode besides its engines (its spectra and prefactors)
    spectra, reals = iface.mode_arrays(scene)
    work = (nc * 7 + 6) * N * 8 + spectra * M * 16 + reals * M * 8
    # the law's field parameters, its state (Law.state_fields) and four temporaries of a step
    law_fields = sum(1 for v in vars(scene.law).values() if np.ndim(v) == 2) + scene.law.state_fields() + 4
    load_fields = sum(1 for v in vars(scene.loading).values() if np.ndim(v) == 2)
    work += (law_fields + load_fields) * N * 8
    rec = scene.record
    n1r, n3r = (len(range(*s.indices(n))) for s, n in zip(rec.region_slices(grid), grid.shape))
    frame = n1r * n3r * 8 * len(rec.fields)
    nsnap = rec.snapshot_count(scene.nsteps, scene.dt) if rec.fields else 0
    kept = min(nsnap, _FLUSH) * 2 if store else nsnap * 2
    nstations = len(rec.stations or {})
    series = (scene.nsteps + 1) * nstations * (3 * nc + 1) * 8 * (2 if nstations else 0)
    # the recorder's set-up: the snapshot steps, their times and the store's time coordinate
    # (and its copy as it is written), 8 bytes each per snapshot
    index = 4 * 8 * nsnap
    records = kept * frame + series + 2 * N * 8 + index
    return MemoryEstimate(int(history), int(work), int(records), int(scene.nsteps), setup=int(building))


def _meminfo(key):
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


def _cgroup_room():
    """Bytes left under this process's cgroup memory limit (v2, then v1); None without one."""
    for limit_file, usage_file in (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                                   ("/sys/fs/cgroup/memory/memory.limit_in_bytes",
                                    "/sys/fs/cgroup/memory/memory.usage_in_bytes")):
        try:
            with open(limit_file) as fh:
                text = fh.read().strip()
            if text == "max" or int(text) >= 1 << 60:
                return None
            with open(usage_file) as fh:
                used = int(fh.read().strip())
            return max(0, int(text) - used)
        except (OSError, ValueError):
            continue
    return None


def available_memory() -> tuple[int, str]:
    """(bytes, where the figure comes from): the least of MemAvailable (/proc/meminfo, or
    the physical memory), the room under a cgroup memory limit, and env CRACKLAB_MEMORY_LIMIT."""
    candidates = []
    avail = _meminfo("MemAvailable")
    if avail is None:
        try:
            avail = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (ValueError, OSError, AttributeError):
            avail = None
    if avail is not None:
        candidates.append((avail, "available on this machine"))
    room = _cgroup_room()
    if room is not None:
        candidates.append((room, "left under this process's cgroup memory limit"))
    env = os.environ.get(LIMIT_ENV)
    if env:
        try:
            candidates.append((parse_bytes(env), f"set by {LIMIT_ENV}={env}"))
        except ValueError as exc:
            raise MemoryBudgetError(LIMIT_ENV, str(exc)) from None
    if not candidates:
        return 1 << 62, "unknown"
    return min(candidates)


def check_memory(estimate: MemoryEstimate, *, processes: int = 1, what: str = "the run",
                 hint: str = "") -> tuple[int, str]:
    """Raise MemoryBudgetError when ``processes`` runs of ``estimate`` (a sweep's workers,
    each with its interpreter, ``PROCESS_BYTES``) do not fit in the available memory;
    return (available bytes, its source) otherwise."""
    avail, source = available_memory()
    need = estimate.total if processes <= 1 else processes * (estimate.total + PROCESS_BYTES)
    if need > avail:
        per = "" if processes <= 1 else f" ({processes} workers, each {fmt_bytes(estimate.total + PROCESS_BYTES)})"
        raise MemoryBudgetError("memory", f"{what} needs {fmt_bytes(need) if processes > 1 else estimate.describe()}"
                                          f"{per}, but {fmt_bytes(avail)} is {source}; refused before any step"
                                          f"{'; ' + hint if hint else ''}")
    return avail, source


def calibrate(scene, *, steps: int = 12, seconds: float = 3.0) -> dict:
    """Time the first steps of ``scene`` (at most ``steps``, or ``seconds`` of wall time)
    and extrapolate: {"steps_timed", "ms_per_step", "setup_s", "run_s"}. The exponential
    engine costs the same every step (the median step is the figure); the direct engine's
    step grows with the history (a line through the timed steps, summed over the run)."""
    import time

    from ..history import resolve_engine
    from .stepper import Stepper

    t0 = time.perf_counter()
    stepper = Stepper(scene)
    setup = time.perf_counter() - t0
    times = []
    t = time.perf_counter()
    for state in stepper:
        now = time.perf_counter()
        times.append(now - t)
        t = now
        if len(times) >= steps or sum(times) > seconds or state.n >= scene.nsteps:
            break
    timed = np.asarray(times[1:] if len(times) > 2 else times)     # the first step compiles
    n = scene.nsteps + 1
    med = float(np.median(timed))
    total = med * n
    if resolve_engine(scene.numerics.engine, scene.numerics.window) == "direct" and timed.size >= 4:
        idx = np.arange(timed.size) + (len(times) - timed.size)
        slope, icpt = np.polyfit(idx, timed, 1)
        slope = max(float(slope), 0.0)
        total = max(total, float(icpt) * n + 0.5 * slope * n * n)
    return {"steps_timed": len(times), "ms_per_step": 1e3 * med, "setup_s": setup, "run_s": total}


def _sequence_memory(scene, store) -> MemoryEstimate:
    """A sequence run (solver/sequence): the unknowns and the pair's stages, the traction
    and the transforms' arrays, the history at a variable step of the dynamic response,
    the snapshots kept (all of them without a store, else up to SEQUENCE_SNAPSHOT_BYTES; the
    expected count, ``Sequence.expected_rows``) and the station rows (up to SEQUENCE_ROWS)."""
    grid, rec = scene.grid, scene.record
    N = grid.shape[0] * grid.shape[1]
    nc = len([c for c in scene.components if c in (1, 3)]) or 1
    stages = 8                                     # Dormand-Prince: seven stages and the new point
    work = (nc + 1) * N * 8 * (stages + 4) + (nc * 6 + 10) * N * 8 + 4 * modes(grid) * 16
    n1r, n3r = (len(range(*s.indices(n))) for s, n in zip(rec.region_slices(grid), grid.shape))
    history = _dynamic_history(scene) if scene.sequence.response == "dynamic" else 0
    nsnap, rows = scene.sequence.expected_rows(scene)
    one = n1r * n3r * 8 * len(rec.fields)          # a snapshot's bytes
    kept = min(nsnap, SEQUENCE_SNAPSHOT_BYTES // max(one, 1) + 1) if store else nsnap
    snapshots = 2 * kept * one                      # and their stacked copy while they are written
    series = min(rows, SEQUENCE_ROWS if store else rows) * (len(rec.stations or {}) * (3 * nc + 1) + 5) * 8 * 2
    return MemoryEstimate(int(history), int(work), int(snapshots + series), int(rows))


def _dynamic_history(scene) -> int:
    """The variable-step histories of a fully dynamic sequence (history/variable.py): one per
    channel the slipping components drive, over the modes of q > 0."""
    from ..elastic.modes import directions
    from ..history.variable import memory
    from .sequence.run import components_of, steps_of
    from .sequence.static import CHANNEL

    grid, mat = scene.grid, scene.material
    q = np.broadcast_to(directions(grid)[0], grid.spectral_shape).ravel()
    r = q[q > 0] * mat.cs
    dt_min = steps_of(scene)[0]
    return sum(memory(CHANNEL[c], mat.nu, r, dt_min) for c in components_of(scene))
