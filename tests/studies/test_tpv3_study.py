"""The TPV3 study's comparison machinery (studies/tpv3/compare.py, docs/studies/tpv3.md) on
synthetic series with known answers, the builder's nucleation patch, and a coarse run."""
from __future__ import annotations

import numpy as np
import pytest

from studies.tpv3 import compare as C


def _synthetic(dt=1e-3, t_r=2.3456, peak=2.5, t_end=6.0, D=3.0):
    """A slip pulse with known rupture time, peak rate and final slip: the rate rises
    linearly from t_r to a peak at t_r + 0.1 and decays to zero at t_r + 1.1; the slip
    is its integral, scaled to D."""
    t = np.arange(0.0, t_end + dt / 2, dt)
    s = t - t_r
    rate = np.where((s > 0) & (s <= 0.1), peak * s / 0.1, 0.0)
    rate = np.where((s > 0.1) & (s < 1.1), peak * (1.1 - s) / 1.0, rate)
    area = 0.5 * peak * 1.1
    rate *= D / area
    slip = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * dt)])
    stress = 70.0 - 7.0 * np.clip(slip / 0.4, 0, 1)
    return t, slip, rate, stress, peak * D / area


def test_rupture_time_first_sample_and_interpolated():
    t = np.arange(0.0, 1.0001, 0.01)
    rate = np.where(t >= 0.5, 10.0 * (t - 0.495), 0.0)   # 0.05 m/s at t = 0.5
    assert C.rupture_time(t, rate) == pytest.approx(0.5)
    # linear crossing between 0.49 (rate 0) and 0.50 (rate 0.05): 0.49 + 0.01 * 1e-3 / 0.05
    assert C.rupture_time(t, rate, interpolate=True) == pytest.approx(0.49 + 0.01 * 0.02)
    assert np.isnan(C.rupture_time(t, np.zeros_like(t)))
    # the threshold is strict: a rate of exactly 1 mm/s has not ruptured
    assert np.isnan(C.rupture_time(t, np.full_like(t, 1e-3)))


def test_metrics_on_a_synthetic_pulse():
    t, slip, rate, stress, peak = _synthetic()
    m = C.metrics(t, slip, rate, stress)
    assert m["rupture_time"] == pytest.approx(2.3456, abs=1e-3)
    # linear interpolation across the kink at t_r: between the last zero sample and the first above
    i = int(np.argmax(rate > 1e-3))
    assert m["rupture_time_interp"] == pytest.approx(t[i - 1] + 1e-3 / rate[i] * (t[i] - t[i - 1]))
    assert t[i - 1] <= m["rupture_time_interp"] <= m["rupture_time"]
    assert m["peak_rate"] == pytest.approx(peak, rel=1e-2)
    assert m["peak_time"] == pytest.approx(2.4456, abs=1e-3)
    assert m["final_slip"] == pytest.approx(3.0, rel=1e-3)
    assert m["final_stress"] == pytest.approx(63.0)
    assert C.final_value(t, slip, at=2.0) == 0.0
    with pytest.raises(ValueError):
        C.final_value(t, slip, at=7.0)


def test_compare_station_known_offsets():
    """A simulation shifted by 0.03 s, with 2 % more slip, against a 0.01 s reference."""
    tr, sr, rr, pr, peak = _synthetic(dt=0.01, t_r=2.341)
    ts, ss, rs, ps, _ = _synthetic(dt=1e-3, t_r=2.371)
    sim = {"t": ts, "slip": 1.02 * ss, "rate": 1.02 * rs, "stress": ps}
    ref = {"t": tr, "slip": sr, "rate": rr, "stress": pr}
    cmp = C.compare_station(sim, ref)
    assert cmp["diff"]["rupture_time"] == pytest.approx(0.03, abs=1e-9)   # both on the 0.01 s samples
    assert cmp["fine"]["rupture_time_interp"] == pytest.approx(2.371, abs=1e-3)
    assert cmp["rel"]["final_slip"] == pytest.approx(0.02, abs=1e-3)
    assert cmp["rel"]["peak_rate"] == pytest.approx(0.02, abs=2e-2)
    assert C.acceptance(cmp) == {"rupture_time": True, "final_slip": True, "peak_rate": True}
    # a shorter simulation is compared at its own end time
    short = {k: (v[ts <= 3.0] if k != "t" else v[v <= 3.0]) for k, v in sim.items()}
    c2 = C.compare_station(short, ref)
    assert c2["t_end"] == pytest.approx(3.0)
    assert c2["ref"]["final_slip"] == pytest.approx(np.interp(3.0, tr, sr))
    bad = C.compare_station({**sim, "t": ts + 0.1}, ref)
    assert C.acceptance(bad)["rupture_time"] is False


def test_reference_files_read():
    ref = C.load_reference("faultst075dp000")
    assert ref["t"][0] == 0.0 and ref["t"][-1] == pytest.approx(12.0, abs=1e-5)
    assert ref["h_stress"][0] == pytest.approx(70.0)
    m = C.metrics(ref["t"], ref["h_slip"], ref["h_rate"], ref["h_stress"])
    assert m["rupture_time"] == pytest.approx(2.99, abs=1e-5)
    assert m["final_slip"] == pytest.approx(3.118, abs=1e-3)


def test_tpv3_nucleation_patch_is_cell_averaged():
    """The builder puts the 3 km square on the grid by cell area (MDSBI's 'box'): 9 km^2 of
    11.6 MPa overstress at any dx, half on edge nodes; nodes whose cell leaves the fault are bonded."""
    from cracklab.scenes import tpv3

    for dx in (100.0, 300.0, 1000.0, 2000.0):
        sc = tpv3(dx=dx, t_end=0.1)
        over = (sc.loading.tau0_1 - 70e6) / 11.6e6
        assert over.sum() * dx * dx == pytest.approx(9.0e6)
        assert np.count_nonzero(~sc.law.bonded) * dx * dx <= 450e6 + 1
        if dx == 100.0:
            sc100 = sc
    sc = sc100
    g = sc.grid
    i, k = g.n1 // 2, g.n3 // 2
    tau = sc.loading.tau0_1 / 1e6
    assert tau[i, k] == pytest.approx(81.6)
    assert tau[i + 15, k] == pytest.approx(75.8)        # on the edge x1 = 1.5 km
    assert tau[i + 15, k + 15] == pytest.approx(72.9)   # corner
    assert tau[i + 16, k] == pytest.approx(70.0)
    assert not sc.law.bonded[i + 149, k] and sc.law.bonded[i + 150, k]


def test_coarse_tpv3_rupture_time():
    """600 m, 4 s (a few seconds): the in-plane station ruptures within 0.3 s of MDSBI's
    2.99 s. Loose: at 600 m the static cohesive zone (about 0.6-0.8 km) spans about one
    cell and the coarse front is late (3.17 s at 600 m, 3.14 s at 400 m; docs/studies/tpv3.md).
    The displacement scheme (beta = 0.049): at this resolution the product scheme's
    beta = 0.25 delays the front by another 0.35 s or more (docs/studies/tpv3.md, "Numerics")."""
    from studies.tpv3 import run
    from cracklab.model.record import Record
    from cracklab.scenes import tpv3
    from cracklab.output.simulate import simulate, stations

    sc = tpv3(dx=600.0, t_end=4.0, domain=(48000.0, 24000.0), numerics=run.numerics("displacement"))
    sc = sc.replace(record=Record(fields=(), stations={"faultst075dp000": sc.record.stations["faultst075dp000"]}))
    st = stations(simulate(sc))
    t = st.t.values
    v = st.v_1.sel(station="faultst075dp000").values
    assert abs(C.rupture_time(t, v) - 2.99) < 0.3


# ---------------------------------------------------------------------------- the acceptance check
def _reference_as_sim(station, *, shift=0.0, slip_scale=1.0, rate_scale=1.0):
    """A 'simulation' that is the MDSBI record itself, on a finer time step, shifted in
    time and with its slip and slip rate scaled: the known perturbation of a real series."""
    ref = C.load_reference(station)
    t = np.arange(0.0, 12.0 + 5e-4, 1e-3)
    slip = slip_scale * np.interp(t - shift, ref["t"], ref["h_slip"], left=0.0)
    rate = rate_scale * np.interp(t - shift, ref["t"], ref["h_rate"], left=0.0)
    stress = np.interp(t - shift, ref["t"], ref["h_stress"], left=ref["h_stress"][0])
    return {"t": t, "slip": slip, "rate": rate, "stress": stress}


def _cmp(station, **perturb):
    ref = C.load_reference(station)
    return C.compare_station(_reference_as_sim(station, **perturb),
                             {"t": ref["t"], "slip": ref["h_slip"], "rate": ref["h_rate"],
                              "stress": ref["h_stress"]})


def test_acceptance_passes_on_the_reference_and_fails_on_perturbed_series():
    from studies.tpv3 import run
    assert run.REF_STATIONS == ("faultst075dp000", "faultst000dp-030")
    same = {s: {"100": _cmp(s)} for s in run.REF_STATIONS}
    ok = C.check_acceptance(same)
    assert ok["pass"] and ok["checked"] and not ok["failures"] and len(ok["checks"]) == 6
    # each criterion fails alone, at either station
    for perturb, quantity in (({"shift": 0.06}, "rupture_time"), ({"slip_scale": 1.04}, "final_slip"),
                              ({"rate_scale": 1.2}, "peak_rate")):
        for s in run.REF_STATIONS:
            bad = {**same, s: {"100": _cmp(s, **perturb)}}
            verdict = C.check_acceptance(bad)
            assert not verdict["pass"], (perturb, s)
            failed = [(r["station"], r["quantity"]) for r in verdict["checks"] if not r["pass"]]
            assert failed == [(s, quantity)], (perturb, failed)
            assert len(verdict["failures"]) == 1 and s in verdict["failures"][0]
    # within the limits: a 0.03 s lag, 2 % slip, 10 % peak rate pass
    near = {s: {"100": _cmp(s, shift=0.03, slip_scale=1.02, rate_scale=1.1)} for s in run.REF_STATIONS}
    assert C.check_acceptance(near)["pass"]
    # a station that never ruptures fails (NaN rupture time)
    flat = {**same, "faultst075dp000": {"100": _cmp("faultst075dp000", shift=20.0)}}
    assert not C.check_acceptance(flat)["pass"]


def test_acceptance_at_50_m_needs_differences_no_larger_than_at_100_m():
    s = "faultst075dp000"
    at100 = _cmp(s, shift=0.03, slip_scale=1.02, rate_scale=1.05)
    shrink = C.check_acceptance({s: {100.0: at100, 50.0: _cmp(s, shift=0.01, slip_scale=1.01, rate_scale=1.02)}})
    assert shrink["pass"]
    same = C.check_acceptance({s: {100.0: at100, 50.0: _cmp(s, shift=0.03, slip_scale=1.02, rate_scale=1.05)}})
    assert same["pass"]                                    # equal differences are not larger
    grow = C.check_acceptance({s: {100.0: at100, 50.0: _cmp(s, shift=0.04, slip_scale=1.01, rate_scale=1.02)}})
    assert not grow["pass"]
    assert [(r["dx"], r["quantity"]) for r in grow["checks"] if not r["pass"]] == [(50.0, "rupture_time")]
    # larger than at 100 m but inside the tolerance still fails: the differences must not grow
    peak = C.check_acceptance({s: {100.0: at100, 50.0: _cmp(s, shift=0.01, slip_scale=1.01, rate_scale=1.08)}})
    assert [(r["dx"], r["quantity"]) for r in peak["checks"] if not r["pass"]] == [(50.0, "peak_rate")]
    # a 50 m run alone cannot be checked against the 100 m differences; 600 m is not checked at all
    alone = C.check_acceptance({s: {50.0: at100}})
    assert not alone["pass"] and not alone["checked"]
    coarse = C.check_acceptance({s: {600.0: _cmp(s, shift=0.5)}})
    assert not coarse["checked"] and coarse["checks"] == []


def test_study_reports_fail_and_exits_nonzero_on_a_perturbed_run():
    """The study's own path from station series to verdict (run.compare_run on a stations
    Dataset, the acceptance, the page's verdict line, the exit status), fed the reference
    records with one of them perturbed."""
    import xarray as xr

    from studies.tpv3 import run

    def dataset(**perturb):
        names = ["faultst000dp000", "faultst075dp000", "faultst000dp-030", "faultst000dp030"]
        pos = {"faultst000dp000": (0.0, 0.0), "faultst075dp000": (7500.0, 0.0),
               "faultst000dp-030": (0.0, -3000.0), "faultst000dp030": (0.0, 3000.0)}
        series = {n: _reference_as_sim("faultst000dp-030" if "dp-030" in n or "dp030" in n
                                       else "faultst075dp000") for n in names}
        series["faultst075dp000"] = _reference_as_sim("faultst075dp000", **perturb)
        t = series["faultst000dp000"]["t"]
        stack = lambda k: np.stack([series[n][k] for n in names])  # noqa: E731
        return xr.Dataset({"delta_1": (("station", "t"), stack("slip")), "v_1": (("station", "t"), stack("rate")),
                           "tau_1": (("station", "t"), 1e6 * stack("stress")),
                           "v_3": (("station", "t"), np.zeros((len(names), t.size)))},
                          coords={"station": names, "t": t, "x1": ("station", [pos[n][0] for n in names]),
                                  "x3": ("station", [pos[n][1] for n in names])})

    refs = {s: C.load_reference(s) for s in run.REF_STATIONS}
    for perturb, expect in (({}, 0), ({"shift": 0.1}, 1)):
        cmp = run.compare_run(dataset(**perturb), refs)
        assert cmp["faultst000dp-030"]["offset_km"] == pytest.approx([0.0, -3.0])
        assert cmp["faultst000dp-030"]["mirror"]["max_rate_diff"] == 0.0
        res = {"runs": {"100": {}}, "stations": {s: {"100": c} for s, c in cmp.items()}}
        res["acceptance"] = C.check_acceptance(res["stations"])
        assert run.exit_status(res) == expect
        line = run.verdict_lines(res, [100.0])
        assert line.startswith("**Acceptance: FAIL**" if expect else "**Acceptance: PASS**")
        assert ("FAIL" in line) == bool(expect)
        if expect:
            assert "faultst075dp000 at 100 m: rupture time" in line


def test_the_main_runs_are_the_builders_default_time_stepping():
    """A plain `run.py` runs scenes.tpv3 as the builder steps it without numerics
    (product2 at beta 0.125); `--formulation product` is the first-order check."""
    from studies.tpv3 import run
    from cracklab.scenes import tpv3

    main, builder = run.build_scene(1000.0, 0.5), tpv3(dx=1000.0, t_end=0.5)
    assert main.formulation == builder.formulation == "product2"
    assert main.beta == builder.beta == 0.125 and main.dt == builder.dt
    first = run.build_scene(1000.0, 0.5, formulation="product")
    assert first.formulation == "product" and first.beta == 0.125
