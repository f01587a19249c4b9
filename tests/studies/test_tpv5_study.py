"""The TPV5 study's pure parts (studies/tpv5/compare.py and run.py, docs/studies/tpv5.md) on
synthetic data with known answers: the acceptance on the MDSBI records and on perturbed
copies of them, the lag fit over beta, the cell check, the free-surface station's check,
and the study's path from a stations Dataset to its verdict, page and exit status."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from cracklab.solver.schemes import SCHEMES

from studies.tpv5 import compare as C
from studies.tpv5 import run


def _reference_as_sim(station, *, shift=0.0, slip_scale=1.0, rate_scale=1.0):
    """The MDSBI record itself on a 1 ms step, shifted in time, slip and rate scaled."""
    ref = C.load_reference(station)
    t = np.arange(0.0, 12.0 + 5e-4, 1e-3)
    slip = slip_scale * np.interp(t - shift, ref["t"], ref["h_slip"], left=0.0)
    rate = rate_scale * np.interp(t - shift, ref["t"], ref["h_rate"], left=0.0)
    stress = np.interp(t - shift, ref["t"], ref["h_stress"], left=ref["h_stress"][0])
    return {"t": t, "slip": slip, "rate": rate, "stress": stress}


def _cmp(station, **perturb):
    return C.compare_station(_reference_as_sim(station, **perturb), run.ref_series(C.load_reference(station)))


def test_reference_files_read_with_the_initial_stresses_of_the_problem():
    assert run.REF_STATIONS == ("faultst000dp000", "faultst000dp030", "faultst000dp075", "faultst-075dp075",
                                "faultst075dp075")
    initial = {"faultst000dp000": 70.0, "faultst000dp030": 70.0, "faultst000dp075": 0.677 * 120.0,
               "faultst-075dp075": 78.0, "faultst075dp075": 62.0}
    for s in run.REF_STATIONS:
        ref = C.load_reference(s)
        assert ref["t"][0] == 0.0 and ref["t"][-1] == pytest.approx(12.0, abs=1e-5)
        assert ref["h_stress"][0] == pytest.approx(initial[s], abs=1e-4), s
    # the surface record: dip slip odd about the free surface, so zero there
    surf = C.load_reference("faultst000dp000")
    assert np.max(np.abs(surf["v_rate"])) < 1e-12 < np.max(surf["h_rate"])
    assert C.default_reference_dir().name == "tpv5_mdsbi"


def test_acceptance_passes_on_the_reference_and_fails_on_each_perturbation():
    same = {s: {"100": _cmp(s)} for s in run.REF_STATIONS}
    ok = C.check_acceptance(same)
    assert ok["pass"] and ok["checked"] and len(ok["checks"]) == 15
    for perturb, quantity in (({"shift": 0.06}, "rupture_time"), ({"slip_scale": 1.04}, "final_slip"),
                              ({"rate_scale": 1.2}, "peak_rate")):
        for s in run.REF_STATIONS:
            verdict = C.check_acceptance({**same, s: {"100": _cmp(s, **perturb)}})
            failed = [(r["station"], r["quantity"]) for r in verdict["checks"] if not r["pass"]]
            assert not verdict["pass"] and failed == [(s, quantity)], (perturb, s, failed)
    near = {s: {"100": _cmp(s, shift=0.03, slip_scale=1.02, rate_scale=1.1)} for s in run.REF_STATIONS}
    assert C.check_acceptance(near)["pass"]
    # 50 m: the differences must not grow
    s = "faultst075dp075"
    grow = C.check_acceptance({s: {100.0: _cmp(s, shift=0.02), 50.0: _cmp(s, shift=0.04)}})
    assert [(r["dx"], r["quantity"]) for r in grow["checks"] if not r["pass"]] == [(50.0, "rupture_time")]


def test_lag_fit_recovers_a_linear_lag_and_what_it_costs():
    # lag = 10 ms + 0.4 s x beta: 60 ms at beta 0.125 (over 0.05 s), within it for beta <= 0.1
    f = C.lag_fit([0.125, 0.0625], [0.06, 0.035])
    assert f["a"] == pytest.approx(0.01) and f["b"] == pytest.approx(0.4)
    assert f["beta_within"] == pytest.approx(0.1) and f["steps_factor"] == pytest.approx(1.25)
    # already within: factor 1; three betas, least squares
    g = C.lag_fit([0.125, 0.0625, 0.03125], [0.03, 0.02, 0.015])
    assert g["steps_factor"] == 1.0 and g["beta_within"] > 0.125
    # a lag the grid leaves (a > limit): no beta is enough
    k = C.lag_fit([0.125, 0.0625], [0.10, 0.08])
    assert k["a"] == pytest.approx(0.06) and k["beta_within"] == 0.0 and math.isinf(k["steps_factor"])
    # an early front that grows earlier with beta (b < 0)
    m = C.lag_fit([0.125, 0.0625], [-0.07, -0.04])
    assert m["b"] == pytest.approx(-0.48) and m["beta_within"] == pytest.approx((0.05 - 0.01) / 0.48)
    # a lag that does not depend on beta
    assert math.isinf(C.lag_fit([0.125, 0.0625], [0.02, 0.02])["beta_within"])
    for betas, lags in (([0.125], [0.05]), ([0.125, 0.125], [0.05, 0.04]), ([0.1, 0.0], [0.0, 0.0]),
                        ([0.1, 0.05], [float("nan"), 0.0])):
        with pytest.raises(ValueError):
            C.lag_fit(betas, lags)


def test_lag_fit_of_a_second_order_scheme():
    """order=2 fits lag = a + b beta^2 (product2's front_order): exact on a quadratic lag, where the
    linear fit of the same two points would put the dt -> 0 lag elsewhere."""
    assert (SCHEMES["product"].front_order, SCHEMES["product2"].front_order) == (1, 2)
    # lag = 2 ms + 2.56 s x beta^2: 42 ms at 0.125, 12 ms at 0.0625; within 50 ms for beta^2 <= 0.048 / 2.56
    betas, lags = [0.125, 0.0625], [0.002 + 2.56 * 0.125**2, 0.002 + 2.56 * 0.0625**2]
    f = C.lag_fit(betas, lags, order=2)
    assert f["order"] == 2 and f["a"] == pytest.approx(0.002) and f["b"] == pytest.approx(2.56)
    assert f["beta_within"] == pytest.approx(math.sqrt(0.048 / 2.56)) and f["steps_factor"] == 1.0
    assert C.lag_fit(betas, lags)["a"] == pytest.approx(0.002 - 2.56 * 0.125 * 0.0625)   # the linear fit's
    over = C.lag_fit([0.25, 0.125], [0.002 + 2.56 * 0.0625, 0.002 + 2.56 * 0.125**2], order=2)
    assert over["beta_within"] == pytest.approx(math.sqrt(0.048 / 2.56))
    assert over["steps_factor"] == pytest.approx(0.25 / math.sqrt(0.048 / 2.56))
    with pytest.raises(ValueError):
        C.lag_fit(betas, lags, order=3)


def test_domain_change_is_the_largest_move_over_stations():
    a = {s: _cmp(s) for s in ("faultst000dp000", "faultst075dp075")}
    b = {"faultst000dp000": _cmp("faultst000dp000", shift=0.02, slip_scale=1.01),
         "faultst075dp075": _cmp("faultst075dp075", slip_scale=0.97, rate_scale=1.05)}
    d = C.domain_change(a, b)
    assert d["stations"]["faultst000dp000"]["rupture_time"] == pytest.approx(0.02, abs=1e-6)   # float32 times
    assert d["stations"]["faultst075dp075"]["rupture_time"] == 0.0
    assert d["max"]["final_slip"] == pytest.approx(0.03, rel=1e-6)
    assert d["max"]["peak_rate"] == pytest.approx(0.05, rel=1e-6)
    assert C.domain_change(a, a)["max"] == {"rupture_time": 0.0, "final_slip": 0.0, "peak_rate": 0.0,
                                            "final_stress": 0.0}


def test_surface_check_needs_exactly_zero_dip_slip_and_a_rupture():
    t = np.linspace(0.0, 5.0, 501)
    rate = np.where(t > 2.0, 1.0, 0.0)
    assert C.surface_check(t, rate, np.zeros_like(t)) == {"max_abs_dip_rate": 0.0,
                                                          "rupture_time": pytest.approx(2.01), "pass": True}
    assert not C.surface_check(t, rate, np.full_like(t, 1e-18))["pass"]
    assert not C.surface_check(t, np.zeros_like(t), np.zeros_like(t))["pass"]


def _dataset(**perturb):
    """A stations Dataset as the study reads it: the reference records (one perturbed) at
    the reference stations' positions on a 48 km cell."""
    import xarray as xr

    names = list(run.REF_STATIONS)
    series = {n: _reference_as_sim(n, **(perturb if n == "faultst-075dp075" else {})) for n in names}
    t = series[names[0]]["t"]
    stack = lambda k: np.stack([series[n][k] for n in names])  # noqa: E731
    x1 = [24000.0 + 1e3 * run.POSITION_KM[n][0] for n in names]
    x3 = [1e3 * run.POSITION_KM[n][1] for n in names]
    return xr.Dataset({"delta_1": (("station", "t"), stack("slip")), "v_1": (("station", "t"), stack("rate")),
                       "tau_1": (("station", "t"), 1e6 * stack("stress")),
                       "v_3": (("station", "t"), np.zeros((len(names), t.size)))},
                      coords={"station": names, "t": t, "x1": ("station", x1), "x3": ("station", x3)})


def test_study_path_from_stations_to_verdict_page_and_exit_status(tmp_path):
    refs = {s: C.load_reference(s) for s in run.REF_STATIONS}
    meta = {"dx": 100.0, "t_end": 12.0, "n1": 480, "n3": 240, "shape": [480, 241], "beta": 0.125,
            "dt": 3.6e-3, "nsteps": 3326, "wall_s": 300.0, "domain": [48000.0, 24000.0], "s_per_step": 0.09,
            "formulation": "product2", "engine": "exponential", "ruptured_fraction": 1.0,
            "surface_rupture_time": 4.5}
    for perturb, expect in (({}, 0), ({"shift": 0.1}, 1)):
        cmp = run.compare_run(_dataset(**perturb), refs)
        assert cmp["faultst-075dp075"]["position_km"] == pytest.approx([-7.5, 7.5])
        assert cmp[run.SURFACE]["surface"]["pass"]
        res = {"runs": {"100": dict(meta)}, "stations": {s: {"100": c} for s, c in cmp.items()}}
        res["acceptance"] = C.check_acceptance(res["stations"])
        assert run.exit_status(res) == expect
        line = run.verdict_lines(res, [100.0])
        assert line.startswith("**Acceptance: FAIL**" if expect else "**Acceptance: PASS**")
        if expect:
            assert "faultst-075dp075 at 100 m: rupture time" in line
        # the page: every placeholder of discussion.md filled, the tables written
        page = run.write_page(res, [100.0], tmp_path / "tpv5.md", "figures")
        text = Path(page).read_text()
        assert "{" not in text and "}" not in text
        assert text.count("| faultst") >= 3 * len(run.REF_STATIONS)
        assert ("At 100 m the five stations meet all three acceptance numbers" in text) == (not expect)
    assert run.exit_status({"runs": {"600": {}}, "acceptance": C.check_acceptance({})}) == 0
    assert run.exit_status({"runs": {"100": {}}, "acceptance": C.check_acceptance({})}) == 2


def test_the_main_runs_are_the_builders_default_time_stepping():
    """A plain `run.py` runs scenes.tpv5 as the builder steps it without numerics
    (product2 at beta 0.125, as tpv3); `--formulation product` is the first-order check."""
    from cracklab.scenes import tpv5

    main, builder = run.build_scene(1000.0, 0.5), tpv5(dx=1000.0, t_end=0.5)
    assert main.formulation == builder.formulation == "product2"
    assert main.beta == builder.beta == 0.125 and main.dt == builder.dt
    first = run.build_scene(1000.0, 0.5, formulation="product")
    assert first.formulation == "product" and first.beta == 0.125


def test_scheme_check_and_second_order_lag_fit_on_the_page(tmp_path):
    """A first-order check (OUT/product) 0.06 s late at one station is reported as missing
    one of the 15 numbers next to the main run; beta checks of a product2 main run are
    fitted at order 2 (lag = a + b beta^2), so a lag of 30 ms at beta 0.125 and 7.5 ms at
    0.0625 is all time step (a = 0)."""
    refs = {s: C.load_reference(s) for s in run.REF_STATIONS}
    meta = {"dx": 100.0, "t_end": 12.0, "n1": 480, "n3": 240, "shape": [480, 241], "beta": 0.125,
            "dt": 3.6e-3, "nsteps": 3326, "wall_s": 300.0, "domain": [48000.0, 24000.0], "s_per_step": 0.09,
            "formulation": "product2", "engine": "exponential", "ruptured_fraction": 1.0,
            "surface_rupture_time": 4.5}

    def analysed(shift, **extra):
        cmp = run.compare_run(_dataset(shift=shift) if shift else _dataset(), refs)
        r = {"runs": {"100": {**meta, **extra}}, "stations": {s: {"100": c} for s, c in cmp.items()}}
        r["acceptance"] = C.check_acceptance(r["stations"])
        return r

    res = analysed(0.03)
    res["variants"] = {"product": analysed(0.06, formulation="product"),
                       "beta0.0625": analysed(0.0075, beta=0.0625, nsteps=6652)}
    res["baselines"] = {"runs": res["runs"], "stations": res["stations"]}
    s = "faultst-075dp075"
    lags = [run.lag(res["stations"][s]["100"]), run.lag(res["variants"]["beta0.0625"]["stations"][s]["100"])]
    lag = {s: {**C.lag_fit([0.125, 0.0625], lags, beta_now=0.125, order=SCHEMES["product2"].front_order),
               "betas": [0.125, 0.0625], "lags": lags}}
    assert lag[s]["order"] == 2 and abs(lag[s]["a"]) < 2e-3 and lag[s]["b"] * 0.125**2 == pytest.approx(0.03, abs=2e-3)
    res["lag"] = lag
    sentence = run.scheme_sentence(res)
    assert "first-order product scheme" in sentence and "misses 1 of the 15" in sentence
    assert "with product2 at beta = 0.125" in sentence
    text = run.variant_section(res)
    assert "| product, beta 0.1250, 48 km x 24 km |" in text and "lag = a + b beta^2" in text
    page = Path(run.write_page(res, [100.0], tmp_path / "tpv5.md", "figures")).read_text()
    assert "{" not in page and "}" not in page and "product2 is second order in dt. Fitted over beta^2" in page
    assert "`run.py --dx 100 --formulation product`" in page and "`run.py --dx 100 --beta 0.0625`" in page
