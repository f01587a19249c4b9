"""Fast checks of the study helpers (studies/accuracy_vs_cost/run.py, studies/stability_grid.py)
on cases with a known answer: the Pareto front of hand-made points, growth-rate fits of
synthetic exponentials, the Lamb and modal error measures on perturbed exact solutions, the
engine-driven modal recurrences against cracklab.analysis.modal.modal_response, and the stability
verdicts on hand-made rows."""
from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _load(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


acc = _load("accuracy_vs_cost_run", ROOT / "studies" / "accuracy_vs_cost" / "run.py")
stab = _load("stability_grid_study", ROOT / "studies" / "stability_grid.py")


# ----------------------------------------------------------------------------- Pareto front
def test_pareto_front_of_hand_made_points():
    cost = [1.0, 2.0, 3.0, 4.0, 2.5, 0.5, 5.0]
    err = [5.0, 3.0, 4.0, 1.0, 3.0, 9.0, 1.0]
    # (0.5, 9) cheapest; (1, 5); (2, 3); (4, 1); (2.5, 3) ties in error but costs more;
    # (3, 4) is dominated by (2, 3); (5, 1) ties (4, 1) in error and costs more
    assert acc.pareto_front(cost, err) == [5, 0, 1, 3]


def test_pareto_front_skips_non_finite_and_keeps_first_duplicate():
    cost = [1.0, 1.0, float("nan"), 0.1, 2.0]
    err = [2.0, 2.0, 0.0, float("inf"), 1.0]
    assert acc.pareto_front(cost, err) == [0, 4]
    assert acc.pareto_front([], []) == []


def test_pareto_front_single_dominating_point():
    assert acc.pareto_front([3.0, 1.0, 2.0], [3.0, 0.5, 1.0]) == [1]


# ----------------------------------------------------------------------------- growth fit
def test_growth_rate_of_a_synthetic_exponential():
    n = np.arange(0, 3001, 5)
    v = 2.0 * np.exp(3e-3 * n)
    assert stab.growth_rate(n, v) == pytest.approx(3e-3, rel=1e-9)
    # an oscillation on top: the late-half fit still finds the rate
    w = v * (1.0 + 0.2 * np.sin(0.37 * n))
    assert stab.growth_rate(n, w) == pytest.approx(3e-3, rel=0.05)
    # decay, and the early half does not count: a fast early transient then growth
    z = np.where(n < 1500, 100.0 * np.exp(-1e-2 * n), 1e-4 * np.exp(-2e-4 * n))
    assert stab.growth_rate(n, z) == pytest.approx(-2e-4, rel=1e-6)


def test_growth_rate_stops_at_a_blow_up():
    n = np.arange(0, 100, 1.0)
    v = np.exp(0.5 * n)
    v[60:] = np.inf
    # the usable series ends at step 59; the fit runs over its late half
    assert stab.growth_rate(n, v) == pytest.approx(0.5, rel=1e-9)
    assert math.isnan(stab.growth_rate([0, 1], [1.0, 2.0]))


def test_classify_and_limits():
    assert stab.classify(1e-4, False) == "stable"
    assert stab.classify(1e-3, False) == "unstable"
    assert stab.classify(-1.0, True) == "unstable"
    assert stab.classify(float("nan"), False) == "unstable"
    rows = {0.1: {"status": "stable"}, 0.25: {"status": "stable"}, 0.5: {"status": "unstable"},
            0.75: {"status": "stable"}}
    assert stab.measured_limit(rows, (0.1, 0.25, 0.5, 0.75)) == (0.25, 0.5)
    assert stab.agreement(0.3, 0.25, 0.5) == "agrees"
    assert stab.agreement(0.6, 0.25, 0.5).startswith("DISAGREES")
    assert stab.agreement(0.1, 0.25, 0.5).startswith("conservative")


def test_predicted_beta_max_follows_gamma_max():
    from cracklab import Grid
    from cracklab.solver.stability import gamma_max

    g3 = Grid(n1=64, n3=64, L1=1.0, L3=1.0)
    g2 = Grid(n1=256, n3=1, L1=1.0, L3=1.0)
    gm = {m: gamma_max("displacement", m, 0.25) for m in ("I", "II", "III")}
    assert stab.predicted_beta_max("displacement", "I", g3) == pytest.approx(gm["I"] / (math.pi * math.sqrt(2)))
    assert stab.predicted_beta_max("displacement", "III", g2) == pytest.approx(gm["III"] / math.pi)
    assert stab.predicted_beta_max("displacement", "shear", g3) == pytest.approx(
        min(gm["II"], gm["III"]) / (math.pi * math.sqrt(2)))


def test_forced_beta_scene_runs_past_the_check():
    scene = stab.build("III", "displacement", 1.2, 7, n=16)
    assert scene.beta == 1.2 and scene.nsteps == 7
    assert scene.dt == pytest.approx(1.2 / 16)


# ----------------------------------------------------------------------------- error measures
def test_lamb_error_of_the_exact_solution_and_of_an_offset():
    from cracklab.analysis.exact import lamb_opening

    r = acc.LAMB_R
    t = np.linspace(0.0, 1.7 * r, 400)
    d = lamb_opening(r, t)
    d = np.where(np.isfinite(d), d, 0.0)  # the singular sample is in a left-out window
    rms, mx = acc.lamb_error(t, d)
    assert rms == 0.0 and mx == 0.0
    static = 3.0 / (4.0 * np.pi * r)
    rms, mx = acc.lamb_error(t, d + 0.01 * static)
    assert rms == pytest.approx(0.01, rel=1e-9) and mx == pytest.approx(0.01, rel=1e-9)
    # an error confined to the left-out window around the Rayleigh arrival does not count
    tau_R = 1.0876638
    bump = np.where(np.abs(t / r - tau_R) < 0.05, 1.0, 0.0)
    assert acc.lamb_error(t, d + bump)[1] == 0.0


def test_modal_error_mode_III_against_j0():
    from scipy.special import j0

    T = np.arange(0.0, 50 * 2 * np.pi + 0.2, 0.1)
    eps = 3e-3
    r = j0(T) + eps * np.sqrt(2.0 / (np.pi * np.maximum(T, 1e-9)))
    assert acc.modal_error(T, r, "III", ref={}) == pytest.approx(eps, rel=1e-9)
    r[10] = np.nan  # a blow-up before the window
    assert acc.modal_error(T, r, "III", ref={}) == math.inf


def test_modal_error_mode_I_with_the_reference_fit():
    ref_coef = np.zeros(10)
    ref_coef[1] = 0.5844
    ref = {"I": {"coef": ref_coef.tolist()}}
    P = acc.rayleigh_period("I")
    T = np.arange(48 * P, 50 * P + 0.1, 0.1)
    exact_long = acc.ref_basis(T, "I") @ ref_coef
    assert acc.modal_error(T, exact_long, "I", ref) == 0.0
    from cracklab.analysis.modal import long_time_amplitude

    amp = long_time_amplitude("I")
    assert acc.modal_error(T, exact_long + 0.02, "I", ref) == pytest.approx(0.02 / amp, rel=1e-9)


@pytest.mark.parametrize("formulation, scheme", [
    ("displacement", ("displacement", "trapezoid", "explicit")),
    ("velocity", ("velocity", "discretized", "semi-implicit")),
    ("product", ("velocity", "product", "predictor-corrector")),
])
def test_engine_modal_recurrence_matches_modal_response(formulation, scheme):
    from cracklab.analysis.modal import modal_response

    for mode in ("I", "II"):
        r = acc.modal_run(mode, 0.4, formulation, "direct", 30.0)
        f, c, i = scheme
        ref = modal_response(mode, gamma=0.4, T_end=30.0, formulation=f, convolution=c, integration=i).values
        assert np.max(np.abs(r - ref)) < 1e-12


def test_truncated_engine_differs_and_exponential_agrees(monkeypatch):
    monkeypatch.setenv("CRACKLAB_EXP_BACKEND", "numpy")  # no numba compilation for one mode
    r = acc.modal_run("I", 0.5, "displacement", "direct", 150.0)
    r50 = acc.modal_run("I", 0.5, "displacement", "direct T50", 150.0)
    rexp = acc.modal_run("I", 0.5, "displacement", "exponential", 150.0)
    n50 = int(50 / 0.5)
    assert np.max(np.abs(r50[:n50] - r[:n50])) < 1e-14  # identical before T = 50
    assert np.max(np.abs(r50 - r)) > 1e-3  # truncation shows after
    assert np.max(np.abs(rexp - r)) < 1e-3
    for f in ("velocity", "product"):  # the same through the other two schemes
        d = acc.modal_run("II", 0.5, f, "direct", 150.0)
        e = acc.modal_run("II", 0.5, f, "exponential", 150.0)
        assert np.max(np.abs(e - d)) < 1e-3


def test_performance_study_quick_writes_one_table_per_thread_count(tmp_path):
    """studies/performance/run.py --quick: one `cracklab bench --json` per row and thread
    setting (1 thread; 2 engine threads with 1 FFT thread); bench.json holds every row
    with its thread counts and the fields the page quotes
    (no timing is asserted: speed is a benchmark, not a test)."""
    perf = _load("performance_study", ROOT / "studies" / "performance" / "run.py")
    perf.main(["--quick", "--threads", "1", "2/1", "--out", str(tmp_path)])
    import json

    rows = json.loads((tmp_path / "bench.json").read_text())
    assert [(r["n1"], r["steps"], r["engine_threads"], r["threads"]) for r in rows] == [
        (128, 101, 1, 1), (128, 401, 1, 1), (128, 101, 2, 1), (128, 401, 2, 1)]
    for r in rows:
        assert r["ms_per_step"] > 0 and r["fft_pair_ms"] > 0 and r["peak_rss_mb"] > 0
        assert r["us_per_point_per_step"] == pytest.approx(1e3 * r["ms_per_step"] / (128 * 128))
        assert r["overlap"] == (r["engine_threads"] >= 2)  # the engine's worker thread, as reported
    md = (tmp_path / "bench.md").read_text()
    assert md.count("| 128 x 128 | I |") == 4 and "1 thread:" in md
    assert "2 engine threads, 1 FFT thread (the engine's advance overlapped with the FFTs and the law):" in md


def test_performance_study_stages_quick(tmp_path):
    """studies/performance/run.py --stages --quick: every case of the breakdown by stage (mode
    I, shear with slip weakening and with rate and state, bimaterial, the overlap) as one
    `cracklab bench --json` each; stages.md has a row per case with every stage
    (no timing is asserted)."""
    import json

    from cracklab.cli.bench import STAGES

    perf = _load("performance_study", ROOT / "studies" / "performance" / "run.py")
    perf.main(["--stages", "--quick", "--rounds", "1", "--out", str(tmp_path)])
    rows = json.loads((tmp_path / "stages.json").read_text())
    assert [r["case"] for r in rows] == [c[0] for c in perf.STAGE_CASES]
    assert [(r["law"], r["bimaterial"], r["overlap"]) for r in rows] == [
        ("traction_free", False, False), ("slip_weakening", False, False), ("rate_state", False, False),
        ("slip_weakening", True, False), ("slip_weakening", False, True)]
    for r in rows:
        assert tuple(r["stages_ms"]) == STAGES and r["stage_steps"] > 0
    md = (tmp_path / "stages.md").read_text().splitlines()
    assert len(md) == 2 + len(rows) and all(s in md[0] for s in STAGES)


def test_performance_scaling_table_from_medians():
    """studies/performance/run.py --scaling: each setting's median step over the rounds and
    its speed-up on the one-thread median, and the one-thread step by stage (synthetic
    results: no bench here)."""
    from cracklab.cli.bench import STAGES

    perf = _load("performance_study", ROOT / "studies" / "performance" / "run.py")
    stages = {s: 1.0 for s in STAGES}
    rows = []
    for k, (one, two, eng) in enumerate([(26.0, 15.0, 14.0), (25.0, 16.0, 13.0), (30.0, 14.0, 15.0)]):
        for (name, _, _), ms in zip(perf.SCALING, (one, two, eng)):
            rows.append({"setting": name, "round": k, "load": 0.5, "ms_per_step": ms, "fft_pair_ms": 2.0,
                         "stages_ms": stages, "stages_total_ms": float(len(STAGES))})
    md = perf.scaling_table(rows).splitlines()
    assert md[2].startswith("| 1 thread | 26.00, 25.00, 30.00 | 26.00 | 1.00x | 2.00 | 13.0 |")
    assert md[3].startswith("| 2 threads | 15.00, 16.00, 14.00 | 15.00 | 1.73x |")
    assert md[4].startswith("| 2 engine threads, 1 FFT thread | 14.00, 13.00, 15.00 | 14.00 | 1.86x |")
    assert md[-1].startswith("one thread, by stage (ms per step): transforms 1.00")


def test_mirror_cost_study_summary():
    """studies/performance/mirror.py: medians, per-round and fastest ratios of the half plane
    against the periodic and the doubled grids (synthetic runs: no bench here)."""
    study = _load("performance_mirror", ROOT / "studies" / "performance" / "mirror.py")
    runs = {"half": [{"ms_per_step": 2.0, "fft_pair_ms": 0.2}, {"ms_per_step": 3.0, "fft_pair_ms": 0.3}],
            "periodic": [{"ms_per_step": 2.0, "fft_pair_ms": 0.1}, {"ms_per_step": 2.0, "fft_pair_ms": 0.1}],
            "doubled": [{"ms_per_step": 4.0, "fft_pair_ms": 0.4}, {"ms_per_step": 5.0, "fft_pair_ms": 0.4}]}
    s = study.summary(runs)
    assert s["ms_per_step"] == {"half": 2.5, "periodic": 2.0, "doubled": 4.5}
    assert s["half_over_periodic"] == 1.25 and s["per_round_half_over_periodic"] == [1.0, 1.5]
    assert s["fastest_half_over_periodic"] == 1.0 and s["fastest_half_over_doubled"] == 0.5
