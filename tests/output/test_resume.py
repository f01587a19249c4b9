"""Checkpoint / resume of long runs (docs/guide/reliability.md, "Long runs"): a run killed with
SIGKILL, also in the middle of a checkpoint write, resumes to the same results, bit for bit."""
import importlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import cracklab
from cracklab import Grid, Loading, Material, Numerics, Record, Scene, TractionFree
from cracklab.output import checkpoint as ck
from cracklab.model.scene_io import scene_to_toml
from interrupt import interrupted_run

SIM = importlib.import_module("cracklab.output.simulate")
ROOT = Path(__file__).resolve().parents[2]
STATIONS = {"centre": (0.5, 0.5), "edge": (0.75, 0.5)}


def assert_same(ref, res, rtol=0.0):
    """Every variable and coordinate identical (bit for bit with rtol = 0, NaN where NaN)."""
    assert set(ref.data_vars) == set(res.data_vars)
    for name in list(ref.data_vars) + list(ref.coords):
        a, b = ref[name].values, res[name].values
        assert a.shape == b.shape, name
        if a.dtype.kind == "f" and rtol:
            scale = np.nanmax(np.abs(a)) if np.isfinite(a).any() else 1.0
            np.testing.assert_allclose(a, b, rtol=0, atol=rtol * scale, err_msg=name)
        elif a.dtype.kind == "f":
            np.testing.assert_array_equal(a, b, err_msg=name)
        else:
            assert (a == b).all(), name


# ---------------------------------------------------------------------------- serialisation
def test_checkpoint_file_round_trips_nested_state_exactly(tmp_path):
    state = {"n": 7, "x": 0.1 + 0.2, "inf": -np.inf, "none": None, "s": "numba", "flag": True,
             "comp": {1: np.arange(3.0), 3: np.array([1 + 2j, np.nan])}, "list": [1, 2.5, None],
             "nested": {"I": {"engine": {"buf0": np.ones((2, 3), dtype=np.complex128), "n": 3}}}}
    ck.write(tmp_path, state)
    back = ck.read(tmp_path)
    assert back["n"] == 7 and back["x"] == 0.1 + 0.2 and back["inf"] == -np.inf
    assert back["none"] is None and back["s"] == "numba" and back["flag"] is True
    assert set(back["comp"]) == {1, 3}
    np.testing.assert_array_equal(back["comp"][3], state["comp"][3])
    assert back["nested"]["I"]["engine"]["buf0"].dtype == np.complex128
    assert back["list"] == [1, 2.5, None]
    assert not list((tmp_path / ck.GROUP).glob("*.tmp"))


# ---------------------------------------------------------------------------- in process
def _ellipse(engine="direct", t_end=1.5):
    return cracklab.scenes.elliptical_crack(
        n=32, a=0.25, b=0.2, t_end=t_end, numerics=Numerics(engine=engine),
        record=Record(fields=("delta_2", "v_2"), every=3, stations=STATIONS))


def _shear(engine="auto"):
    """3D shear crack: product scheme, components 1 and 3."""
    g = Grid(n1=32, n3=32, L1=1.0, L3=1.0)
    crack = cracklab.scenes.ellipse_mask(g, 0.25, 0.2)
    return Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=g,
                 law=TractionFree(contact=False, bonded=~crack),
                 loading=Loading(tau0_1=np.where(crack, 1.0, 0.0)), t_end=1.0, beta=0.25,
                 record=Record(fields=("delta_1", "v_3", "tau_1"), every=4, stations=STATIONS),
                 numerics=Numerics(formulation="auto", engine=engine))


def _asperity():
    """Linear cohesive law, constant-K loading with l0 measured from the initial crack."""
    return cracklab.scenes.asperity_row(n1=64, n3=32, t_end=1.0,
                                        record=Record(fields=("delta_2", "strength"), every=5,
                                                      stations={"a": (0.6, 0.5)}))


CASES = {"ellipse-direct": lambda: _ellipse("direct"), "ellipse-exponential": lambda: _ellipse("exponential"),
         "shear-product": _shear, "shear-product-direct": lambda: _shear("direct"),
         "asperity-constantK": _asperity}
# Every case resumes bit for bit (the exponential engine's state includes the powers its
# product-rule start term E_0(n) advances from).
RTOL = {}


@pytest.mark.parametrize("case", list(CASES))
def test_interrupted_run_resumes_bit_for_bit(case, tmp_path, monkeypatch):
    scene = CASES[case]()
    assert scene.nsteps > 40
    ref = cracklab.simulate(scene)
    stop = scene.nsteps // 2 + 1
    store = interrupted_run(scene, tmp_path / "run.zarr", monkeypatch, stop=stop, checkpoint_every=9)
    killed = xr.open_zarr(store, consolidated=False)      # readable as it was left
    assert killed.attrs["cracklab_status"] == "running"
    assert killed.attrs["cracklab_checkpoint_step"] == (stop // 9) * 9
    assert (store / ck.GROUP / ck.FILE).exists()
    res = cracklab.simulate(scene, store=store, resume=True).load()
    assert res.attrs["cracklab_status"] == "complete"
    assert not (store / ck.GROUP).exists()                 # removed once complete
    assert_same(ref, res, RTOL.get(case, 0.0))
    # resuming a complete store returns it without running
    again = cracklab.simulate(scene, store=store, resume=True)
    assert_same(res, again.load())


def test_resume_removes_zarrs_temporary_files_before_reading_the_store(tmp_path, monkeypatch):
    """A kill inside a zarr write leaves zarr's temporary <name>.<uuid>.partial files; the
    resume removes them before it lists the hierarchy (which would warn about them)."""
    import warnings

    scene = CASES["ellipse-direct"]()
    store = interrupted_run(scene, tmp_path / "run.zarr", monkeypatch, stop=scene.nsteps // 2, checkpoint_every=9)
    (store / "zarr.964a485b4a804cfa88a0c3108366a64f.partial").write_bytes(b"{")
    (store / "delta_2" / "c.0a1b.partial").write_bytes(b"\0")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = cracklab.simulate(scene, store=store, resume=True).load()
    assert res.attrs["cracklab_status"] == "complete"
    assert not list(store.rglob("*.partial"))


def test_resume_checks_the_scene_and_the_arguments(tmp_path):
    scene = _ellipse(t_end=0.3)
    store = tmp_path / "run.zarr"
    cracklab.simulate(scene, store=store, checkpoint_every=5)
    with pytest.raises(cracklab.errors.StoreError, match="different scene"):
        cracklab.simulate(scene.replace(t_end=0.35), store=store, resume=True)
    with pytest.raises(cracklab.InputError, match="resume"):
        cracklab.simulate(scene, resume=True)
    for bad in (-1, "abc", "0s", 1.5, "-3s"):
        with pytest.raises(cracklab.InputError, match="checkpoint_every"):
            cracklab.simulate(scene, store=tmp_path / "x.zarr", checkpoint_every=bad)
    # nothing to resume: the run starts over
    res = cracklab.simulate(scene, store=tmp_path / "new.zarr", resume=True)
    assert res.attrs["cracklab_status"] == "complete"


def test_checkpoints_by_wall_time(tmp_path, monkeypatch):
    scene = _ellipse(t_end=0.4)
    seen = []
    real = SIM.Recorder.checkpoint
    monkeypatch.setattr(SIM.Recorder, "checkpoint", lambda self, st, n: seen.append(n) or real(self, st, n))
    cracklab.simulate(scene, store=tmp_path / "a.zarr", checkpoint_every="1e-9s")
    assert seen == list(range(scene.nsteps))      # every step (but the last) is due
    seen.clear()
    cracklab.simulate(scene, store=tmp_path / "b.zarr", checkpoint_every=0)
    cracklab.simulate(scene, store=tmp_path / "c.zarr")   # default: 60 s, not reached here
    assert seen == []


# ---------------------------------------------------------------------------- real kills
def _long_scene():
    """1200 steps of a 64 x 64 crack (constant cost per step): a few seconds."""
    return cracklab.scenes.elliptical_crack(
        n=64, a=0.25, b=0.2, t_end=1200 * 0.5 / 64, numerics=Numerics(engine="exponential"),
        record=Record(fields=("delta_2",), every=20, stations=STATIONS))


def _start(toml, out, *extra, env=None):
    cmd = [sys.executable, "-m", "cracklab.cli", "run", str(toml), "-o", str(out), "--no-progress", *extra]
    return subprocess.Popen(cmd, cwd=ROOT, env={**os.environ, **(env or {})},
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def _checkpoint_step(out):
    try:
        return json.loads((Path(out) / "zarr.json").read_text())["attributes"].get("cracklab_checkpoint_step")
    except (OSError, ValueError, KeyError):
        return None


def _wait(proc, cond, timeout=360):
    """Poll ``cond`` until it holds (True), the process exits or ``timeout`` s pass (False).
    Generous: a fresh process may first compile the numba loops (no disk cache yet), on a
    machine shared with other jobs."""
    deadline = time.time() + timeout
    while time.time() < deadline:
        if cond():
            return True
        if proc.poll() is not None:
            return False
        time.sleep(0.01)
    return False


@pytest.fixture(scope="module")
def long_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("long")
    scene = _long_scene()
    toml = d / "scene.toml"
    toml.write_text(scene_to_toml(scene))
    # the reference is an uninterrupted `cracklab run` in a fresh process, as the runs it is
    # compared with bit for bit; this test process has run other tests (other caches, plans
    # and compiled loops), which may round the last bit differently (1 ulp seen in CI)
    proc = _start(toml, d / "ref.zarr")
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err.decode()[-2000:]
    ref = xr.open_zarr(d / "ref.zarr", consolidated=False).load()
    # the same physics in process, to round-off (fields of order 1 or below: tractions that
    # are zero at broken points carry round-off of 1e-16 there)
    res = cracklab.simulate(scene).load()
    for name in ref.data_vars:
        np.testing.assert_allclose(res[name].values, ref[name].values, rtol=0, atol=1e-12, err_msg=name)
    return scene, toml, ref


def test_sigkill_mid_run_then_resume(long_run, tmp_path):
    """kill -9 three times at checkpoints of a running `cracklab run`; each resume continues."""
    scene, toml, ref = long_run
    out = tmp_path / "out.zarr"
    kills, last = 0, -1
    rng = np.random.default_rng(0)
    for attempt in range(3):
        proc = _start(toml, out, "--checkpoint-every", "40", *(["--resume"] if attempt else []))
        ok = _wait(proc, lambda: (_checkpoint_step(out) or -1) > last)
        assert ok, proc.communicate()[1].decode()[-2000:]
        time.sleep(rng.uniform(0.0, 0.3))         # somewhere after a checkpoint, maybe in a flush
        proc.send_signal(signal.SIGKILL)
        assert proc.wait() == -signal.SIGKILL
        kills += 1
        last = _checkpoint_step(out)
        assert 0 < last < scene.nsteps
        # the killed store stays readable; the snapshots up to the checkpoint are the run's
        partial = xr.open_zarr(out, consolidated=False)
        assert partial.attrs["cracklab_status"] == "running"
        k = partial.attrs["cracklab_checkpoint_snapshots"]
        info = {a: v for a, v in partial.attrs.items() if a.startswith("cracklab_") and a != "cracklab_scene_digest"}
        assert k == last // 20 + 1, (last, info)
        assert partial.sizes["t"] == ref.sizes["t"], (partial.sizes, info)
        np.testing.assert_array_equal(partial["delta_2"].values[:k], ref["delta_2"].values[:k])
    proc = _start(toml, out, "--resume", "--checkpoint-every", "40")
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err.decode()[-2000:]
    res = xr.open_zarr(out, consolidated=False).load()
    assert kills == 3
    assert_same(ref, res)


def test_sigkill_inside_a_checkpoint_write(long_run, tmp_path):
    """The test hook sleeps with the new checkpoint written but not yet in place: a kill
    there leaves the previous checkpoint (and snapshots flushed past it) and resumes."""
    scene, toml, ref = long_run
    out = tmp_path / "out.zarr"
    proc = _start(toml, out, "--checkpoint-every", "150", env={ck.SLEEP_ENV: "1.5"})
    tmp = out / ck.GROUP
    ok = _wait(proc, lambda: (tmp / ck.FILE).exists() and any(tmp.glob("*.tmp")))
    assert ok, proc.communicate()[1].decode()[-2000:]
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert list(tmp.glob("*.tmp")), "the kill was meant to land inside the write"
    step = _checkpoint_step(out)
    assert step == 150
    state = ck.read(out)
    assert state["n"] == 150
    # the write in progress had flushed the snapshots of steps up to 300 first
    written = ~np.isnan(xr.open_zarr(out, consolidated=False)["delta_2"].values).all(axis=(1, 2))
    assert state["nsnap"] == 8 and written.sum() == 16 and written[:16].all()
    proc = _start(toml, out, "--resume")
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err.decode()[-2000:]
    assert_same(ref, xr.open_zarr(out, consolidated=False).load())


# ---------------------------------------------------------------------------- numerical faults
def _unstable(factor=3.0, nsteps=400):
    """Plane mode I crack at ``factor`` times the stable beta (forced past the Scene's check)."""
    sc = cracklab.scenes.periodic_cracks(n=64, c=0.2, mode="I", beta=0.1, t_end=1.0,
                                         record=Record(fields=("delta_2", "v_2"), every=2,
                                                       stations={"tip": (0.7, 0.0)}))
    bmax = sc.beta_max
    if factor * bmax > sc.beta:
        object.__setattr__(sc, "beta", factor * bmax)
    object.__setattr__(sc, "t_end", nsteps * sc.dt)
    return sc, bmax


def test_exponential_growth_is_stopped_before_overflow():
    sc, bmax = _unstable()
    with pytest.raises(cracklab.SimulationError) as info:
        for _ in cracklab.solver.stepper.steps(sc):
            pass
    msg = str(info.value)
    assert msg.startswith("exponential growth of v_2 at step ")
    import re

    m = re.search(r"at step (\d+) \(t = ([-0-9.e+]+)\) at node \((\d+), 0\), x1 = ([0-9.e+-]+), x3 = 0\b", msg)
    assert m, msg
    n, t, i, x1 = int(m[1]), float(m[2]), int(m[3]), float(m[4])
    assert 0 < n < sc.nsteps and t == pytest.approx(n * sc.dt, rel=1e-5)
    assert x1 == pytest.approx(sc.grid.x1[i], rel=1e-5)
    assert f"beta = {sc.beta:g}" in msg and f"stable limit {bmax:.4g}" in msg
    peak = float(re.search(r"max \|v_2\| = ([0-9.e+]+)", msg)[1])
    assert np.isfinite(peak) and peak < 1e12          # caught long before an overflow


@pytest.mark.parametrize("use_store", [False, True], ids=["memory", "store"])
def test_growth_keeps_what_was_recorded(tmp_path, use_store):
    sc, _ = _unstable()
    store = tmp_path / "bad.zarr" if use_store else None
    with pytest.raises(cracklab.SimulationError, match="exponential growth") as info:
        cracklab.simulate(sc, store=store, checkpoint_every=10)
    part = info.value.partial
    assert part.sizes["t"] >= 2 and np.isfinite(part["delta_2"].values).all()
    assert cracklab.stations(part).sizes["t"] >= 2
    if use_store:
        back = xr.open_zarr(store, consolidated=False)
        assert back.attrs["cracklab_status"] == "failed"
        assert back.attrs["cracklab_error"].startswith("exponential growth of v_2")
        assert back.sizes["t"] == part.sizes["t"] and "rupture_time" in back
        assert not (store / ck.GROUP).exists()


def test_growth_detector_is_silent_at_the_stable_limit():
    """At beta = beta_max the same crack runs 3000 steps without a fault."""
    sc, bmax = _unstable(factor=1.0, nsteps=3000)
    object.__setattr__(sc, "beta", bmax)
    object.__setattr__(sc, "t_end", 3000 * sc.dt)
    assert sc.nsteps == 3000
    last = None
    for last in cracklab.solver.stepper.steps(sc):
        pass
    assert last.n == 3000 and np.isfinite(last.v[2]).all()
