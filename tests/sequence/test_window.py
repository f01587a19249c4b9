"""The quasi-dynamic response on a window (solver/sequence/window.py): where the plane
creeps at the plate rate, the traction on the window of the other points from the
window's transforms is the whole grid's static traction (static.py) to round-off; a BP1
run on the window gives the events of the run on the whole grid."""
import numpy as np
import pytest

MU, NU = 30e9, 0.25


def material():
    from cracklab import Material

    return Material(mu=MU, cs=3000.0, nu=NU)


@pytest.mark.parametrize("mask_of", ["wraps", "inside", "one"])
def test_periodic_box_is_the_shortest_run_holding_the_mask(mask_of):
    from cracklab.solver.sequence.window import periodic_box

    n = 40
    on = {"wraps": [0, 1, 2, 37, 38, 39, 5], "inside": [10, 14, 20], "one": [7]}[mask_of]
    mask = np.zeros(n, bool)
    mask[on] = True
    start, m = periodic_box(mask)
    held = (start + np.arange(m)) % n
    assert set(on) <= set(held.tolist())
    best = min(len(range(s, s + L)) for s in range(n) for L in range(1, n + 1)
               if set(on) <= {(s + j) % n for j in range(L)})
    assert m == best


@pytest.mark.parametrize("case", ["plane", "3d_shear", "3d_stiff", "3d_one"])
def test_window_traction_is_the_grid_traction(case):
    from cracklab import Grid
    from cracklab.solver.sequence.static import StaticResponse
    from cracklab.solver.sequence.window import WindowedStatic

    rng = np.random.default_rng(3)
    if case == "plane":
        g, comps, k = Grid(n1=480, n3=1, L1=4800.0, L3=1.0), (3,), 0.0
        mask = np.zeros(g.shape, bool)
        mask[:50] = mask[-49:] = True                     # a fault and its image about x1 = 0
    else:
        g, comps, k = Grid(n1=96, n3=80, L1=960.0, L3=800.0), (1, 3), (2e6 if case == "3d_stiff" else 0.0)
        comps = (3,) if case == "3d_one" else comps
        mask = np.zeros(g.shape, bool)
        mask[90:, 10:30] = mask[:12, 10:30] = True
    static = StaticResponse(material(), g, comps, stiffness=k)
    win = WindowedStatic(static, g, mask)
    assert win.worth
    slip = {c: np.where(mask, rng.standard_normal(g.shape), 0.0) for c in comps}
    full = static.traction(slip)
    got = win.traction({c: slip[c].ravel()[win.points] for c in comps})
    for c in comps:
        want = full[c].ravel()[win.points]
        assert np.max(np.abs(got[c] - want)) < 1e-12 * np.max(np.abs(want)), c
    if len(comps) == 1 and win.fftw:    # one component less a shift through FFTW's arrays: the general path's
        c, x = comps[0], slip[comps[0]].ravel()[win.points]
        assert np.array_equal(win.traction({c: x + 0.25}, {c: 0.25})[c], win._traction({c: x + 0.25}, {c: 0.25})[c])


def test_a_window_as_long_as_half_the_axis_takes_the_whole_axis():
    from cracklab import Grid
    from cracklab.solver.sequence.static import StaticResponse
    from cracklab.solver.sequence.window import WindowedStatic

    g = Grid(n1=64, n3=1, L1=64.0, L3=1.0)
    mask = np.zeros(g.shape, bool)
    mask[:33] = True
    win = WindowedStatic(StaticResponse(material(), g, (3,)), g, mask)
    assert not win.worth and win.size == g.shape


def test_bp1_on_the_window_gives_the_run_on_the_whole_grid(monkeypatch):
    """BP1-QD at 200 m to its first event, on the window (400 of 1600 nodes, transforms of 800)
    and on the whole grid: the same events, steps and fields, the creeping region's included."""
    import cracklab.solver.sequence.quasi_dynamic as qd
    from cracklab import simulate
    from cracklab.analysis import events
    from cracklab.scenes import bp1

    scene = bp1(dz=200.0, years=210.0, depth=160e3, tolerance=1e-7)
    on = simulate(scene)

    class Whole(qd.WindowedStatic):
        def __init__(self, *args):
            super().__init__(*args)
            self.worth = False

    monkeypatch.setattr(qd, "WindowedStatic", Whole)
    whole = simulate(scene)
    e_on, e_whole = events(on), events(whole)
    assert e_on.sizes["event"] == e_whole.sizes["event"] >= 1
    for name in ("t_start", "t_end", "peak_slip_rate", "mean_slip"):
        a, b = e_on[name].values, e_whole[name].values
        assert np.max(np.abs(a - b) / np.abs(b)) < 1e-6, name
    assert on.attrs["accepted_steps"] == whole.attrs["accepted_steps"]
    for name in ("delta_3", "tau_3", "psi"):
        a, b = on[name].values, whole[name].values
        assert a.shape == b.shape and np.max(np.abs(a - b)) <= 1e-6 * np.max(np.abs(b)), name
    creeping = on.x1.values > 40e3
    assert np.any(creeping)
    a, b = on.tau_3.values[:, creeping], whole.tau_3.values[:, creeping]
    change = b - b[:1]          # what the slip did to the creeping region's traction
    assert np.max(np.abs(change)) > 1e5
    assert np.max(np.abs(a - b)) <= 1e-6 * np.max(np.abs(change))


def test_a_state_of_a_run_on_the_whole_grid_resumes_on_the_window(monkeypatch):
    """A checkpoint's state written by a run that held the whole grid (before the window) is
    taken at the window's points: the resumed run goes on as the whole grid's run does."""
    import itertools

    import cracklab.solver.sequence.quasi_dynamic as qd
    from cracklab.scenes import bp1
    from cracklab.solver.sequence.run import SequenceRun

    scene = bp1(dz=200.0, years=210.0, depth=160e3)
    windowed = qd.WindowedStatic

    class Whole(windowed):
        def __init__(self, *args):
            super().__init__(*args)
            self.worth = False

    monkeypatch.setattr(qd, "WindowedStatic", Whole)
    whole = SequenceRun(scene)
    for _ in itertools.islice(whole, 300):
        pass
    state = whole.get_state()
    assert state["y"].size == 2 * scene.grid.n1
    ahead = list(itertools.islice(whole, 50))[-1]
    monkeypatch.setattr(qd, "WindowedStatic", windowed)
    resumed = SequenceRun(scene, start=state)
    assert resumed.system.window is not None and resumed.y.size == 2 * resumed.system.n < state["y"].size
    got = list(itertools.islice(resumed, 50))[-1]
    assert got.n == ahead.n and abs(got.t - ahead.t) <= 1e-8 * ahead.t      # the step control: round-off in dt
    for a, b in ((got.delta[3], ahead.delta[3]), (got.psi, ahead.psi), (got.V, ahead.V), (got.tau[3], ahead.tau[3])):
        assert np.max(np.abs(a - b)) <= 1e-7 * np.max(np.abs(b))


def test_fields_at_a_few_nodes_are_the_fields_over_the_grid():
    """A sequence state's fields read at nodes on the window and in the creeping region
    (``SequenceState.at``, what the stations take) are those of the fields over the grid."""
    import itertools

    from cracklab.scenes import bp1
    from cracklab.solver.sequence.run import SequenceRun

    run = SequenceRun(bp1(dz=200.0, years=50.0, depth=160e3))
    assert run.system.window is not None
    states = list(itertools.islice(run, 40))
    off = np.setdiff1d(np.arange(1600), run.system.points)[[0, 1, 400, -1]]     # where the plane creeps
    nodes = np.sort(np.concatenate([run.system.points[[0, 5, 100, -1]], off])).astype(np.int64)
    for state in (states[1], states[-1]):
        for name in ("delta_3", "v_3", "tau_3", "psi", "V"):
            kind, _, c = name.partition("_")
            lazy = state.at(name, nodes)
            x = getattr(state, kind)
            full = (x[int(c)] if c else x).ravel()[nodes]
            assert np.array_equal(lazy, full), name
    assert states[-1].at("delta_3", off[:1])[0] == 1e-9 * states[-1].t          # the plate's slip where it creeps


def test_the_largest_slip_rate_read_on_the_window_is_the_grids():
    """``SequenceState.peak`` (what the recorder takes at every step, without spreading the
    slip rate over the grid) is the largest slip rate over the slices and the first node in
    the grid's order that has it, as ``np.argmax`` over the field on the grid: at t = 0,
    where every node slides at the plate rate to round-off, and later; on the recorded half,
    on regions across the window's edge, inside it, and in the creeping region alone (where
    every node ties at the plate rate)."""
    import itertools

    from cracklab.scenes import bp1
    from cracklab.solver.sequence.run import SequenceRun

    run = SequenceRun(bp1(dz=200.0, years=50.0, depth=160e3))
    states = list(itertools.islice(run, 30))
    n1 = run.scene.grid.n1
    regions = [(slice(0, n1 // 2 + 1), slice(None)), (slice(100, n1 - 3), slice(None)), (slice(5, 60), slice(None)),
               (slice(300, 700), slice(None))]
    for state in (states[0], states[1], states[-1]):
        for s1, s3 in regions:
            V = state.V[s1, s3]
            k = int(np.argmax(V))
            node = tuple(int(i) + (sl.start or 0) for i, sl in zip(np.unravel_index(k, V.shape), (s1, s3)))
            # a state whose field over the grid is not computed yet, as the recorder gets it
            fresh = type(state)(state.n, state.t, state.dt, state.fields)
            assert fresh.peak(s1, s3) == (float(V.flat[k]), node), (state.n, s1)


@pytest.mark.parametrize("stiffness", [0.0, 2e6])
def test_a_stage_on_the_window_is_the_stage_sum_and_the_rates_bit_for_bit(stiffness):
    """``QuasiDynamic.stage_rates`` on a window with FFTW (the stage's sums into the window's
    box, the traction gathered out of it) gives the unknowns and rates of the general path
    (integrate.weighted, then ``rates`` through ``elastic``) bit for bit; with a spring too."""
    from cracklab.scenes import bp1
    from cracklab.solver.sequence.integrate import weighted
    from cracklab.solver.sequence.quasi_dynamic import QuasiDynamic
    from cracklab.solver.sequence.run import components_of

    scene = bp1(dz=200.0, years=50.0, depth=160e3)
    seq, comps = scene.sequence, components_of(scene)
    systems = [QuasiDynamic(scene.material, scene.grid, scene.law, {c: scene.loading.field(c) for c in comps},
                            scene.law.sigma_n, {3: seq.plate_rate_3}, creep=seq.creep, stiffness=stiffness,
                            mirror=seq.mirror, window=True) for _ in range(2)]
    fused, plain = systems
    assert fused._fused and fused.window is not None
    plain._fused = False
    rng = np.random.default_rng(5)
    y = fused.initial()
    n = fused.n
    y[:n] = rng.uniform(0.0, 0.2, n)[np.minimum(np.arange(n), fused.image)]      # even about the mirror
    k = np.empty((4, y.size))
    k[0] = plain.rates(3e9, y)
    k[1], k[2] = k[0] * 1.01, k[0] * 0.98
    t, h, w = 3e9 + 2e5, 4e5, np.array([0.2, 0.3, 0.25])
    for s in systems:
        s.lnV = plain.lnV.copy()
    kf, kp = k.copy(), k.copy()
    yf = fused.stage_rates(t, y, h, w, kf, 3)
    yp = weighted(y, h, w, kp)
    kp[3] = plain.rates(t, yp)
    assert np.array_equal(yf, yp) and np.array_equal(kf, kp)
    assert np.array_equal(fused.lnV, plain.lnV)
    for a, b in zip(fused.last, plain.last):
        a, b = (a, b) if isinstance(a, np.ndarray) else (a[3], b[3])
        assert np.array_equal(a, b)
    assert np.any(kf[3] != k[0])          # the stage moved the rates
