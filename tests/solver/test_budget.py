"""The memory budget of a run and of a sweep, checked before any work starts
(cracklab.solver.budget): the estimate against measured peak resident memory, the refusal
of a run that cannot fit, the dry runs, and the checks of a sweep's members."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import cracklab
from cracklab.laws import LAWS
from cracklab.errors import MemoryBudgetError
from cracklab.solver import budget

ROOT = Path(__file__).resolve().parents[2]


def cli(*args, env=None, timeout=600):
    return subprocess.run([sys.executable, "-m", "cracklab.cli", *map(str, args)], cwd=ROOT,
                          env={**os.environ, **(env or {})}, capture_output=True, text=True, timeout=timeout)


def error_line(res):
    assert res.returncode != 0, res.stdout
    assert "Traceback" not in res.stderr, res.stderr
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("Error: "), res.stderr
    return lines[0]


BIG = """
t_end = 1.0
name = "big"
[material]
mu = 1.0
cs = 1.0
nu = 0.25
[grid]
n1 = 8192
n3 = 8192
L1 = 1.0
L3 = 1.0
[law]
kind = "linear_cohesive"
tau_c = 1.0
delta_c = 0.01
[loading]
tau0_2 = 1.2
[record]
fields = ["delta_2"]
"""


def test_sizes_and_limits(monkeypatch):
    assert budget.parse_bytes("8GB") == 8 << 30 and budget.parse_bytes("512 MB") == 512 << 20
    assert budget.parse_bytes("1.5g") == int(1.5 * (1 << 30)) and budget.parse_bytes("1000") == 1000
    with pytest.raises(ValueError):
        budget.parse_bytes("lots")
    assert budget.fmt_bytes(3 << 30) == "3 GB" and budget.fmt_bytes(1536 << 10) == "1.5 MB"
    monkeypatch.setenv(budget.LIMIT_ENV, "123MB")
    avail, source = budget.available_memory()
    assert avail == 123 << 20 and budget.LIMIT_ENV in source
    monkeypatch.setenv(budget.LIMIT_ENV, "much")
    with pytest.raises(MemoryBudgetError, match="CRACKLAB_MEMORY_LIMIT: not a size"):
        budget.available_memory()


def test_the_estimate_grows_as_the_arrays_do():
    """The history of the direct engine grows with the steps, the exponential one's does
    not; everything grows with the grid; in-memory runs keep every snapshot."""
    lamb = cracklab.scenes.lamb
    direct = cracklab.Numerics(engine="direct")
    short = budget.run_memory(lamb(n=64, t_end=2.0).replace(numerics=direct))
    longer = budget.run_memory(lamb(n=64, t_end=8.0).replace(numerics=direct))
    assert longer.history > 3 * short.history
    exp_short = budget.run_memory(lamb(n=64, t_end=2.0))
    exp_long = budget.run_memory(lamb(n=64, t_end=8.0))
    assert exp_long.history < 1.5 * exp_short.history
    assert budget.run_memory(lamb(n=128, t_end=2.0)).work > 3.5 * exp_short.work
    rec = cracklab.Record(fields=("delta_2",), every=1)
    scene = lamb(n=64, t_end=1.0, record=rec)
    assert budget.run_memory(scene, store=False).records > 10 * budget.run_memory(scene, store=True).records


MEASURE = textwrap.dedent("""
    import json, os, sys, tempfile
    import cracklab
    from cracklab import Numerics, Record
    from cracklab.solver.budget import run_memory

    engine, n, t_end = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    rec = Record(fields=("delta_2",), every=20)
    # a small run first: imports, compiled loops, FFTW: the interpreter's own memory
    small = cracklab.scenes.lamb(n=32, t_end=0.3, record=rec).replace(numerics=Numerics(engine=engine))
    cracklab.simulate(small, store=os.path.join(tempfile.mkdtemp(), "s.zarr"), checkpoint_every=0)
    with open("/proc/self/status") as fh:      # resident now (the warm-up's peak may be higher)
        base = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmRSS"))
    scene = cracklab.scenes.lamb(n=n, t_end=t_end, record=rec).replace(numerics=Numerics(engine=engine))
    estimate = run_memory(scene).total
    cracklab.simulate(scene, store=os.path.join(tempfile.mkdtemp(), "r.zarr"), checkpoint_every=0)
    with open("/proc/self/status") as fh:      # this process's own peak (its rusage counts the parent's too)
        peak = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmHWM"))
    print(json.dumps({"estimate": estimate, "used": peak - base}))
""")


@pytest.mark.parametrize("engine, n, t_end", [("exponential", 512, 0.1), ("direct", 256, 0.6)])
def test_the_estimate_agrees_with_the_peak_resident_memory(engine, n, t_end):
    """Within a factor 1.5 of the peak resident memory a run adds to the interpreter's
    (measured: 1.15 for the exponential engine on 512 x 512, 1.02 for the direct one on
    256 x 256 over 600 steps)."""
    _within_half_of_the_peak(MEASURE, engine, n, t_end)


def _within_half_of_the_peak(script, *args):
    """Run ``script`` (it prints the estimate and the peak it measured, JSON, last line) and
    check the estimate within a factor 1.5 of the peak."""
    res = subprocess.run([sys.executable, "-c", script, *map(str, args)], cwd=ROOT,
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    m = json.loads(res.stdout.strip().splitlines()[-1])
    ratio = m["estimate"] / m["used"]
    assert m["used"] > 150 << 20            # a run whose arrays dominate
    assert 1 / 1.5 < ratio < 1.5, m


SCENE_PEAK = textwrap.dedent("""
    import json, os, sys, tempfile
    import cracklab
    from cracklab import Record
    from cracklab.solver.budget import run_memory

    builder, dx, t_end = getattr(cracklab.scenes, sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
    # a small run of the same builder first: imports, compiled loops, FFTW, the kernel fits
    small = builder(dx=4 * dx, t_end=0.05, record=Record(fields=()))
    cracklab.simulate(small, store=os.path.join(tempfile.mkdtemp(), "s.zarr"), checkpoint_every=0)
    with open("/proc/self/status") as fh:
        base = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmRSS"))
    scene = builder(dx=dx, t_end=t_end)
    estimate = run_memory(scene)
    cracklab.simulate(scene, store=os.path.join(tempfile.mkdtemp(), "r.zarr"), checkpoint_every=0)
    with open("/proc/self/status") as fh:
        peak = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmHWM"))
    print(json.dumps({"estimate": estimate.total, "setup": estimate.setup, "work": estimate.work,
                      "used": peak - base}))
""")


@pytest.mark.parametrize("builder, dx, t_end", [("tpv6", 250.0, 0.1), ("tpv101", 125.0, 0.1)])
def test_the_estimate_agrees_with_the_peak_of_a_bimaterial_and_a_rate_state_run(builder, dx, t_end):
    """TPV6 (two materials: each face's five engines of its own material, 320 x 161) and
    TPV101 (rate and state, product scheme, 576 x 288), exponential engine: within a factor
    1.5 of the peak a run adds to the interpreter's (measured: 1.25 and 1.25; the resident
    peak varies from run to run by 20 %: the traced test below is the closer one). The engines
    are built one after another, so the set-up's peak is one engine's temporaries beside
    the engines built before it: for TPV6 less than the largest engine's temporaries on top
    of all ten (as the estimate had it, 1.23), and more work arrays (the faces' compiled
    passes hold 56 spectra and 54 real rows per mode)."""
    _within_half_of_the_peak(SCENE_PEAK, builder, dx, t_end)


TRACED = textwrap.dedent("""
    import json, sys, tracemalloc
    from cracklab.cli.bench import bench_scene
    from cracklab.solver.budget import run_memory
    from cracklab.solver.stepper import Stepper

    n, law, bimaterial, steps = int(sys.argv[1]), sys.argv[2], sys.argv[3] == "1", int(sys.argv[4])
    kw = dict(mode="shear", law=law, bimaterial=bimaterial, engine="exponential")
    for _ in Stepper(bench_scene(32, 32, nsteps=12, **kw)):    # compiled loops, FFTW, fits
        pass
    scene = bench_scene(n, n, nsteps=steps, **kw)
    est = run_memory(scene)
    tracemalloc.start()
    stepper = Stepper(scene)
    setup = tracemalloc.get_traced_memory()[1]      # the engines built, their temporaries freed
    tracemalloc.reset_peak()
    for _ in stepper:
        pass
    stepping = tracemalloc.get_traced_memory()[1]
    print(json.dumps({"steady": est.history + est.work + est.records, "total": est.total,
                      "stepping": stepping, "peak": max(setup, stepping)}))
""")


@pytest.mark.parametrize("law, bimaterial", [("slip_weakening", True), ("rate_state", False)])
def test_the_estimate_holds_the_traced_peak_of_a_bimaterial_and_a_rate_state_run(law, bimaterial):
    """Every array a run allocates (tracemalloc: numpy's allocations, not the interpreter's
    own memory nor the allocator's pages, so no noise of the host), for the bench's 3D
    shear ruptures on 128 x 128 over 60 steps: a bimaterial pair with slip weakening (ten
    engines, the faces' passes) and rate and state (the ageing law's state). The arrays
    held while stepping (history, work arrays, records) are estimated within -5 %/+25 %
    of the stepping's traced peak (measured 0.99 and 1.00; the estimate before it counted
    the product rule's start-up weights E_0, the fits' factors per distinct gamma and the
    law's state fields: 0.90 and 0.85), and the estimate's total (the set-up's temporaries
    included) is never under the run's traced peak and at most 1.5 times it (measured
    1.08 and 1.18; before: 0.99, under the peak, for the bimaterial run)."""
    res = subprocess.run([sys.executable, "-c", TRACED, "128", law, "1" if bimaterial else "0", "60"], cwd=ROOT,
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    m = json.loads(res.stdout.strip().splitlines()[-1])
    assert m["stepping"] > 20 << 20, m          # the run's arrays, not the interpreter's objects
    assert 0.95 < m["steady"] / m["stepping"] < 1.25, m
    assert 1.0 <= m["total"] / m["peak"] < 1.5, m


def _arrays(x):
    if isinstance(x, np.ndarray):
        yield x
    elif isinstance(x, dict):
        for v in x.values():
            yield from _arrays(v)
    elif isinstance(x, (list, tuple)):
        for v in x:
            yield from _arrays(v)


LAW_VARIANTS = [(kind, {}) for kind in sorted(LAWS)] + [
    ("slip_weakening", {"normal_time": 1e-3, "sigma_n": None}),      # sigma*: three more fields
    ("rate_state", {"evolution": "slip"}),
    ("rate_state", {"a": "field", "L": "field"}),                    # 1 / a, dt / L, V0 dt / L
    ("rate_state", {"V0": "field", "normal_slip_scale": 1e-3, "sigma_n": None}),
]


@pytest.mark.parametrize("kind, change", LAW_VARIANTS)
def test_the_estimate_counts_the_law_state(kind, change):
    """Law.state_fields, which the estimate counts, is what the law's state holds after a
    few steps of its example scene (its init_state, the work arrays its steps keep there,
    and the pass's parameters a law derives from its fields), in arrays of the grid's size."""
    import dataclasses
    import math

    from cracklab.solver.stepper import Stepper

    scene = cracklab.Scene.from_toml(LAWS[kind].example)
    if change:
        law = scene.law
        values = {k: (np.full(scene.grid.shape, float(np.mean(getattr(law, k)))) if v == "field" else v)
                  for k, v in change.items()}
        # without sigma_n the strength follows the normal traction: the opening component runs
        loading = dataclasses.replace(scene.loading, tau0_2=-law.sigma_n) if "sigma_n" in change else scene.loading
        scene = scene.replace(law=dataclasses.replace(law, **values), loading=loading)
    stepper = Stepper(scene)
    for n, _ in enumerate(stepper):
        if n == 4:
            break
    N = math.prod(scene.grid.shape)
    held = {id(a): a for a in _arrays(stepper.lstate)}
    params = [v for v in vars(scene.law).values() if isinstance(v, np.ndarray)]
    for a in _arrays(list(getattr(scene.law, "_cache", {}).values())):
        if a.size == N and not any(np.shares_memory(a, p) for p in params):
            held[id(a)] = a
    # the rate-and-state predictor's work arrays (and the ageing law's flags), counted
    # always, are not made where the predictor solves for the traction too (the strength
    # following the normal traction)
    unused = 0.0
    if kind == "rate_state" and "work" not in stepper.lstate:
        unused = 2 + (1 / 8 if scene.law.evolution == "ageing" else 0)
    assert scene.law.state_fields() == sum(a.nbytes for a in held.values()) / (N * 8) + unused


def test_the_set_up_peak_follows_the_engines_build_order():
    """An engine's set-up temporaries come beside the engines built before it: the estimate's
    set-up is the largest of (states of the engines built so far + one's temporaries) over
    the history, at most the largest temporaries (the bound the estimate took before) and
    for a single engine exactly its temporaries; the bimaterial interface counts the rows of
    its compiled passes (Bimaterial.BOUND_ROWS) as they are bound."""
    import numpy as np

    from cracklab.history import ENGINES
    from cracklab.solver.interfaces import Bimaterial, for_scene
    from cracklab.solver.schemes import scheme_of
    from cracklab.cli.bench import bench_scene

    exp = ENGINES["exponential"]
    two = bench_scene(32, 32, "shear", 10, engine="exponential", bimaterial=True)
    for order in (1, -1):      # the compliant side (more taps: larger temporaries) built last, then first
        scene = two.replace(materials=two.materials[::order])
        channels = Bimaterial.engine_channels(scene)
        # the second coupling channel of a face shares the first's taps and start-up weight
        sizes = [exp.memory(scene, k, scheme_of(scene.formulation), mat, shared=(k, mat) in channels[:i])
                 for i, (k, mat) in enumerate(channels)]
        assert sum((k, mat) in channels[:i] for i, (k, mat) in enumerate(channels)) == 2
        held = np.cumsum([h for h, _ in sizes])
        est = budget.run_memory(scene)
        assert est.history == held[-1]
        assert est.setup == max(max(h + e for h, (_, e) in zip(held, sizes)) - held[-1], 0)
        largest = max(e for _, e in sizes)
        assert est.setup == largest if order == 1 else est.setup < largest
    one = bench_scene(32, 32, "I", 10, engine="exponential")
    assert budget.run_memory(one).setup == exp.memory(one, "I", scheme_of(one.formulation), one.material)[1]
    # the rows the compiled passes bind, counted against BOUND_ROWS
    iface = for_scene(two)
    for _ in range(2):          # step 0, then step 1 binds the passes' arrays
        iface.predict({c: np.zeros(two.grid.shape) for c in two.components})
    rows = [a for a in iface._fused.values() if isinstance(a, np.ndarray) and a.ndim >= 2]
    count = {kind: sum(int(np.prod(a.shape[:-1])) for a in rows if (a.dtype == complex) == (kind == "c"))
             for kind in "cr"}
    assert (count["c"], count["r"]) == Bimaterial.BOUND_ROWS


def test_an_8192_squared_scene_is_refused_before_any_step(tmp_path):
    toml = tmp_path / "big.toml"
    toml.write_text(BIG)
    out = tmp_path / "big.zarr"
    t0 = time.perf_counter()
    res = cli("run", toml, "-o", out, env={budget.LIMIT_ENV: "4GB"})
    elapsed = time.perf_counter() - t0
    line = error_line(res)
    assert line.startswith("Error: memory: the run of 'big' needs about "), line
    assert "(history " in line and ", set-up " in line and "GB is set by CRACKLAB_MEMORY_LIMIT=4GB; refused before any step" in line
    total = budget.parse_bytes(line.split("needs about ")[1].split(" (")[0].replace(" ", ""))
    assert total > 40 << 30             # 33.6 M Fourier modes, 20 fitted terms each
    assert elapsed < 60, elapsed
    assert not out.exists()
    # the Python API refuses it the same way
    scene = cracklab.Scene.from_toml(BIG)
    # the step's arrays (7 fields of 8192^2 doubles and a few spectra, about 15 GB) apart
    # from the set-up's temporaries (the exact weights of every distinct |q|)
    est = budget.run_memory(scene)
    assert 8 << 30 < est.work < 20 << 30 and est.setup > est.work, est.describe()
    with pytest.raises(MemoryBudgetError, match="refused before any step"):
        os.environ[budget.LIMIT_ENV] = "4GB"
        try:
            cracklab.simulate(scene, store=out)
        finally:
            del os.environ[budget.LIMIT_ENV]
    assert not out.exists()


def test_dry_runs_print_the_estimate_steps_and_time(tmp_path):
    toml = tmp_path / "big.toml"
    toml.write_text(BIG)
    res = cli("run", toml, "--dry-run", env={budget.LIMIT_ENV: "4GB"})
    assert res.returncode == 1
    assert "steps     16384 of dt" in res.stdout and "does NOT fit" in res.stdout and "not calibrated" in res.stdout
    big = budget.run_memory(cracklab.Scene.from_toml(BIG))
    assert f"memory    {big.describe()}; 4 GB set by {budget.LIMIT_ENV}=4GB: does NOT fit" in res.stdout
    small = tmp_path / "small.toml"
    small.write_text(BIG.replace("8192", "32"))
    res = cli("run", small, "--dry-run", "-o", tmp_path / "s.zarr")
    assert res.returncode == 0, res.stderr
    assert "steps     64 of dt = 0.01562" in res.stdout and ": fits" in res.stdout
    est = budget.run_memory(cracklab.Scene.from_toml(small))
    assert f"memory    {est.describe()}; " in res.stdout, res.stdout      # the estimate, then the memory available
    assert "run time  about " in res.stdout and "ms per step over 12 timed steps" in res.stdout
    assert not (tmp_path / "s.zarr").exists()
    study = tmp_path / "study.toml"
    study.write_text('[study]\nname = "dry"\nbuilder = "elliptical_crack"\n[base]\nn = 32\na = 0.25\nb = 0.2\n'
                     't_end = 0.5\n[sweep]\np = [1.0, 1.1, 1.2]\n')
    res = cli("sweep", study, "--dry-run", "--workers", "2")
    assert res.returncode == 0, res.stderr
    assert "members   3" in res.stdout and "steps     32 per member" in res.stdout
    assert "memory    largest member about " in res.stdout and "available on this machine: fits" in res.stdout
    assert "2 worker processes" in res.stdout and "run time  about" in res.stdout and ": fits" in res.stdout


STUDY = """
[study]
name = "checks"
builder = "asperity_row"
[base]
n1 = 32
n3 = 16
t_end = 0.5
[sweep]
"""


def test_a_sweep_checks_every_member_before_the_cluster_starts(tmp_path):
    study = tmp_path / "study.toml"
    out = tmp_path / "ens.zarr"
    study.write_text(STUDY + '"law.tauc" = [1.0, 2.0]\n')
    t0 = time.perf_counter()
    line = error_line(cli("sweep", study, "-o", out))
    assert line.startswith("Error: sweep.law.tauc: unknown key for LinearCohesive; did you mean law.tau_c?"), line
    assert time.perf_counter() - t0 < 30 and not out.exists()
    study.write_text(STUDY + 'diameter = ["0.1"]\n')
    line = error_line(cli("sweep", study, "-o", out))
    assert line.startswith("Error: sweep.diameter: must be a number, got the text '0.1'"), line
    study.write_text(STUDY + '"law.tau_c" = ["1.0"]\n')
    assert "sweep.law.tau_c: must be a number" in error_line(cli("sweep", study, "-o", out))
    study.write_text(STUDY + 'contrast = [true]\n')
    assert "sweep.contrast: must be a number (the builder's default is 3.0)" in error_line(
        cli("sweep", study, "-o", out))
    assert not out.exists()


def test_a_sweep_whose_workers_do_not_fit_is_refused(tmp_path):
    study = tmp_path / "study.toml"
    study.write_text(STUDY + "contrast = [1.5, 3.0]\n")
    out = tmp_path / "ens.zarr"
    line = error_line(cli("sweep", study, "-o", out, "--workers", "2", env={budget.LIMIT_ENV: "600MB"}))
    assert line.startswith("Error: memory: the sweep on 2 worker processes needs "), line
    assert "600 MB is set by CRACKLAB_MEMORY_LIMIT" in line and "--workers" in line
    assert not out.exists()
    # without --workers the cluster gets as many as fit: here one, which fits in 600 MB
    res = cli("sweep", study, "--dry-run", env={budget.LIMIT_ENV: "600MB"})
    assert res.returncode == 0 and "1 worker process:" in res.stdout, res.stdout


def test_the_member_checks_come_before_any_cluster(tmp_path, monkeypatch):
    """A bad scene path or a text for a number is refused in this process: no dask cluster
    or client is made, and no store written (the cluster is made to fail if it is tried)."""
    import distributed

    from cracklab import ensemble as E
    from cracklab.errors import InputError

    def no_cluster(*args, **kwargs):
        raise AssertionError("a dask cluster was started before the members were checked")

    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    monkeypatch.setattr(distributed, "Client", no_cluster)
    base = E.Builder("asperity_row", n1=32, n3=16, t_end=0.5)
    out = tmp_path / "ens.zarr"
    for sweep, field in (({"law.tauc": [1.0, 2.0]}, "sweep.law.tauc"), ({"diameter": ["0.1"]}, "sweep.diameter")):
        with pytest.raises(InputError) as err:
            E.run(base, E.Sweep(product=sweep), out, workers=2, progress=False)
        assert err.value.field == field, str(err.value)
    assert not out.exists()
