"""The exponential engine's overlap: with two or more engine threads the recursive states are
advanced on a worker thread while the step goes on (ExponentialEngine.launch).  The sums,
the runs and the checkpoints are those of the engine that advances in push, to the bit."""
from __future__ import annotations

import numpy as np
import pytest

from cracklab.history import exponential as X

pytest.importorskip("numba")


def _engine(threads, **kw):
    g = np.linspace(0.0, 1.6, 77).reshape(7, 11)
    return X.ExponentialEngine(kernel=kw.pop("kernel", "I"), gamma=g, nu=0.25, threads=threads, nsteps=300, **kw)


@pytest.mark.parametrize("launch_every", [1, 3])
def test_overlapped_sums_are_the_sums_of_push(launch_every):
    """Pushes with the advance on the worker (launched after every push, or only now and
    then: an advance never launched runs at the next push) give the same S_n, bit for bit,
    as the engine that advances in push; and the worker did the work."""
    if X.backend_choice() != "numba":
        pytest.skip("the overlap is a feature of the numba backend")
    ref, ov = _engine(1), _engine(2)
    assert ov.overlap and not ref.overlap
    rng = np.random.default_rng(4)
    launched = 0
    for n in range(120):
        x = rng.standard_normal(ref.shape) + 1j * rng.standard_normal(ref.shape)
        a, b = ref.push(x), ov.push(x)
        assert np.array_equal(a, b), n
        if n % launch_every == 0:
            ov.launch()
            launched += ov.pending
    assert launched >= 120 // launch_every - 1
    # the state saved by either is the same (the worker's advance is finished first)
    sa, sb = ref.get_state(), ov.get_state()
    for k in sa:
        if isinstance(sa[k], np.ndarray):
            assert np.array_equal(sa[k], sb[k]), k


@pytest.mark.parametrize("share", [0.0, 0.3, 0.5])
def test_the_callers_share_of_the_advance_changes_no_number(share, monkeypatch):
    """With the caller taking the top of each eighth before it waits (``balance``, the
    displacement scheme), the sums are those of the engine that advances in push, to the
    bit, whatever the share."""
    if X.backend_choice() != "numba":
        pytest.skip("the overlap is a feature of the numba backend")
    monkeypatch.setattr(X.ExponentialEngine, "rebalance", lambda self, *a: None)  # hold the share
    ref, ov = _engine(1), _engine(2)
    assert ov.balance and not ref.balance
    ov.share = share
    rng = np.random.default_rng(6)
    split = 0
    for n in range(100):
        x = rng.standard_normal(ref.shape) + 1j * rng.standard_normal(ref.shape)
        assert np.array_equal(ref.push(x), ov.push(x)), n
        ov.launch()
        step, cut = ov.cut
        lo, hi = ov.eighth(step)
        split += cut < hi
        assert hi - cut == int(share * (hi - lo))
    assert (split > 50) == (share > 0)


def test_the_share_follows_the_imbalance():
    """The caller's share grows when the worker ended after the caller arrived to wait,
    shrinks when the worker had finished first, by at most 2 % of an eighth a step, and
    stays within [0, 1/2]; the taps ahead keep the eighth whole."""
    eng = _engine(2)
    if not eng.overlap:
        pytest.skip("the overlap is a feature of the numba backend")
    eng.worker_times = (0.0, 1.0)         # 100 positions in 1 s
    eng.rebalance(0.95, 100, 120)         # the caller waited 0.05 s: a quarter of it moves
    assert eng.share == pytest.approx(0.25 * 0.05 / (0.01 * 120))
    for _ in range(100):
        eng.rebalance(0.0, 100, 120)      # waited 1 s: capped steps, then at most 1/2
    assert eng.share == 0.5
    eng.rebalance(1.5, 100, 120)          # the worker was done 0.5 s before
    assert eng.share == pytest.approx(0.48)
    for _ in range(100):
        eng.rebalance(2.0, 100, 120)
    assert eng.share == 0.0
    assert not _engine(2, formulation="velocity", lag=1).balance


@pytest.mark.parametrize("threads", [1, 2])
def test_taps_ahead_is_a_matter_of_scheduling(threads):
    """The taps 1 <= j < 8 added with the advance (taps_ahead, the velocity-based schemes)
    or in push give the same S_n to rounding, with or without the worker; the default
    follows the formulation."""
    if X.backend_choice() != "numba":
        pytest.skip("taps_ahead is a feature of the numba backend")
    a, b = _engine(threads), _engine(threads)
    assert not a.taps_ahead and _engine(1, formulation="velocity", lag=1).taps_ahead
    b.taps_ahead = True
    rng = np.random.default_rng(5)
    for n in range(60):
        x = rng.standard_normal(a.shape) + 1j * rng.standard_normal(a.shape)
        sa, sb = a.push(x), b.push(x)
        a.launch(), b.launch()
        assert np.allclose(sa, sb, rtol=1e-13, atol=1e-13 * np.abs(sa).max()), n
    assert a.get_state()["layout"] != b.get_state()["layout"]


def test_start_weight_ahead_is_the_start_weight_asked_for():
    """The product rule's start-up weight E_0(n), computed ahead with the advance (on the
    worker with overlap, in launch without), is the value the engine gives when asked
    without launching, to the bit, and the exact E_0(n) to the fit's accuracy; the array of
    one step is not overwritten while that step uses it."""
    if X.backend_choice() != "numba":
        pytest.skip("the overlap is a feature of the numba backend")
    kw = dict(kernel="II", rule="product", formulation="velocity", lag=1)
    plain, ahead, serial = _engine(2, **kw), _engine(2, **kw), _engine(1, **kw)
    rng = np.random.default_rng(7)
    gam = plain.gamma
    for n in range(1, 150):
        x = rng.standard_normal(plain.shape) + 1j * rng.standard_normal(plain.shape)
        plain.push(x)
        ref = plain.start_weight(n).copy()
        got = []
        for eng in (ahead, serial):
            eng.push(x)
            e0 = eng.start_weight(n)
            keep = e0.copy()
            eng.launch()           # E_0(n + 1) is computed now (worker or here) ...
            eng.wait()
            assert np.array_equal(e0, keep), n  # ... into the other buffer
            got.append(keep)
        assert np.array_equal(got[0], ref) and np.array_equal(got[1], ref), n
        if n in (5, 40, 149):
            exact = X.exact_weights("II", gam, np.full(gam.shape, n), nu=0.25, rule="product",
                                    formulation="velocity", part="start0").reshape(plain.shape)
            assert np.max(np.abs(ref - exact)) <= 1e-4 * np.max(np.abs(exact)), n


def test_a_worker_error_reaches_the_caller(monkeypatch):
    """An error inside the worker's advance (the compiled loop blocked.advance) is raised by
    the next push, not lost."""
    if X.backend_choice() != "numba":
        pytest.skip("the overlap is a feature of the numba backend")
    from cracklab.history import blocked

    eng = _engine(2)
    x = np.ones(eng.shape, dtype=complex)
    eng.push(x)

    def boom(n, *args):
        raise FloatingPointError(f"advance of step {n} failed")

    monkeypatch.setattr(blocked, "advance", boom)
    eng.launch()
    with pytest.raises(FloatingPointError, match="advance of step 1 failed"):
        eng.push(x)


def _worker_in_child(parents):
    """In a forked child: (whether worker() is another executor than the parent's
    (id ``parents``, whose thread does not exist here), what that executor computes)."""
    other = X.worker()
    return id(other) != parents, other.submit(lambda: 6 * 7).result(timeout=60)


def test_worker_is_per_process():
    """A forked child does not reuse its parent's worker thread (it does not exist there)."""
    import multiprocessing

    first = X.worker()
    assert X.worker() is first
    with multiprocessing.get_context("fork").Pool(1) as pool:
        other_is_new, answer = pool.apply_async(_worker_in_child, (id(first),)).get(timeout=120)
    assert other_is_new
    assert answer == 42


def _scenes():
    from cracklab import (Grid, LinearCohesive, Loading, Material, Numerics, Record, Scene, SlipWeakening)

    g = Grid(n1=32, n3=16, L1=2.0, L3=1.0)
    x1, x3 = np.meshgrid(g.x1, g.x3, indexing="ij")
    crack = (np.abs(x1 - 1.0) < 0.25) & (np.abs(x3 - 0.5) < 0.2)
    num = Numerics(engine="exponential", fft_threads=1, engine_threads=2)
    mode_i = Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=g,
                   law=LinearCohesive(tau_c=1.0, delta_c=0.02, initial_crack=crack),
                   loading=Loading(tau0_2=np.where(crack, 0.9, 0.6) * np.cos(3 * x3)), t_end=0.8, beta=0.2,
                   record=Record(fields=("delta_2",), every=8), numerics=num)
    bonded = (np.abs(x1 - 1.0) > 0.8) | (np.abs(x3 - 0.5) > 0.4)
    shear = Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=g,
                  law=SlipWeakening(mu_s=0.6, mu_d=0.5, D_c=0.01, sigma_n=1.0, bonded=bonded),
                  loading=Loading(tau0_1=np.where(crack, 0.62, 0.55)), t_end=0.6, beta=0.2,
                  record=Record(fields=("delta_1", "delta_3"), every=10), numerics=num)
    return {"I": mode_i, "shear": shear}


@pytest.mark.parametrize("case", ["I", "shear"])
def test_overlapped_runs_are_the_runs_without(case, monkeypatch):
    """Mode I (displacement scheme) and 3D shear (product scheme) with two engine threads:
    the run with the advance on the worker and the run with it in push agree to the bit,
    and a checkpoint taken from the one continues in the other."""
    if X.backend_choice() != "numba":
        pytest.skip("the overlap is a feature of the numba backend")
    from cracklab import simulate
    from cracklab.solver.stepper import Stepper

    sc = _scenes()[case]
    fields = list(sc.record.fields)
    submitted = []
    real = X.worker

    def counting():
        submitted.append(1)
        return real()

    monkeypatch.setattr(X, "worker", counting)
    over = simulate(sc)
    assert len(submitted) > sc.nsteps  # every step (each channel) was advanced on the worker
    monkeypatch.setenv("CRACKLAB_OVERLAP", "0")
    plain = simulate(sc)
    assert float(np.abs(over[fields[0]]).max()) > 0
    for f in fields:
        assert np.array_equal(over[f].values, plain[f].values), f

    # a checkpoint of the overlapped run, continued without the overlap (and the reverse)
    monkeypatch.delenv("CRACKLAB_OVERLAP")
    a = Stepper(sc)
    it = iter(a)
    for _ in range(25):
        next(it)
    state = a.get_state()
    ref = [{c: d.copy() for c, d in next(it).delta.items()} for _ in range(10)]
    monkeypatch.setenv("CRACKLAB_OVERLAP", "0")
    b = Stepper(sc, start=state)
    assert not any(ch.engine.overlap for ch in b.response.channels.values())
    it_b = iter(b)
    for r in ref:
        g = next(it_b).delta
        for c in r:
            assert np.array_equal(r[c], g[c])
    state = b.get_state()
    ref = [{c: d.copy() for c, d in next(it_b).delta.items()} for _ in range(10)]
    monkeypatch.delenv("CRACKLAB_OVERLAP")
    c3 = Stepper(sc, start=state)
    assert all(ch.engine.overlap for ch in c3.response.channels.values())
    it_c = iter(c3)
    for r in ref:
        g = next(it_c).delta
        for c in r:
            assert np.array_equal(r[c], g[c])
