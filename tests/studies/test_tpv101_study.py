"""The TPV101/TPV103 study's comparison and acceptance (studies/tpv101/rs_compare.py, run.py)
on synthetic data with known answers, and the uguca reference files it reads."""
from __future__ import annotations

import math

import numpy as np
import pytest

from studies.tpv101 import rs_compare as C


def _pulse(dt=1e-3, t_r=2.345, peak=4.0, t_end=15.0, D=5.0):
    """A slip pulse with a known rupture time (the rate rises linearly from 0 at t_r, a
    sample time, to its peak at t_r + 0.1, falls to 0 at t_r + 1.1), peak rate and final slip D."""
    t = np.arange(int(round(t_end / dt)) + 1) * dt
    s = t - t_r
    shape = np.where((s > 0) & (s <= 0.1), s / 0.1, 0.0)
    shape = np.where((s > 0.1) & (s < 1.1), (1.1 - s) / 1.0, shape)
    rate = shape * D / 0.55
    slip = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * dt)])
    return {"t": t, "slip": slip, "rate": rate}, D / 0.55


def test_rupture_time_interpolated_and_first_sample():
    t = np.arange(0.0, 1.0001, 0.01)
    rate = np.where(t >= 0.5, 10.0 * (t - 0.495), 0.0)        # 0.05 m/s at t = 0.5, 0 at 0.49
    assert C.rupture_time(t, rate, interpolate=False) == pytest.approx(0.5)
    assert C.rupture_time(t, rate) == pytest.approx(0.49 + 0.01 * 1e-3 / 0.05)
    assert math.isnan(C.rupture_time(t, np.full_like(t, 1e-3)))   # strictly above 1 mm/s


def test_station_metrics_of_a_known_pulse():
    p, peak = _pulse()
    m = C.station_metrics(p["t"], p["slip"], p["rate"])
    # the crossing of 1 mm/s on the linear rise from t_r: t_r + 1e-3 / (peak / 0.1), exact
    assert m["rupture_time"] == pytest.approx(2.345 + 1e-4 / peak, abs=1e-9)
    assert C.rupture_time(p["t"], p["rate"], interpolate=False) == pytest.approx(2.346)
    assert m["peak_rate"] == pytest.approx(peak, rel=1e-9) and m["peak_time"] == pytest.approx(2.445, abs=1e-9)
    assert m["final_slip"] == pytest.approx(5.0, rel=1e-4)
    assert C.station_metrics(p["t"], p["slip"], p["rate"], at=2.0)["final_slip"] == 0.0
    with pytest.raises(ValueError):
        C.station_metrics(p["t"], p["slip"], p["rate"], at=16.0)


def test_compare_station_known_offsets_on_different_steps():
    """cracklab on 7.2 ms steps, about 0.04 s late with 3 % more slip (and peak), against a
    10.1 ms reference: each is measured on its own steps, the final slip at the common end."""
    ref, p_ref = _pulse(dt=0.0101, t_r=311 * 0.0101)
    sim, p_sim = _pulse(dt=0.0072, t_r=442 * 0.0072, D=5.0 * 1.03)
    cmp = C.compare_station(sim, ref)
    expect = (442 * 0.0072 + 1e-4 / p_sim) - (311 * 0.0101 + 1e-4 / p_ref)        # about +0.04 s
    assert cmp["diff"]["rupture_time"] == pytest.approx(expect, abs=1e-9) and 0.04 < expect < 0.042
    # the peaks fall on samples of both series (t_r + 0.1 is not a sample of either): within a sample's fall
    assert cmp["rel"]["peak_rate"] == pytest.approx(0.03, abs=0.02)
    assert cmp["rel"]["final_slip"] == pytest.approx(0.03, abs=1e-3)
    late = C.compare_station({**sim, "t": sim["t"] + 0.1}, ref)
    assert late["diff"]["rupture_time"] == pytest.approx(expect + 0.1, abs=1e-9)
    assert cmp["t_end"] == pytest.approx(min(sim["t"][-1], ref["t"][-1]))


def test_match_nodes_on_nested_and_reversed_grids():
    coarse = np.arange(-1000.0, 1000.1, 200.0)
    fine = np.arange(-1000.0, 1000.1, 100.0)[::-1]            # decreasing, as uguca's depth
    ia, ib = C.match_nodes(coarse, fine)
    assert np.array_equal(ia, np.arange(coarse.size))
    assert np.allclose(fine[ib], coarse)
    ia, ib = C.match_nodes(fine, coarse)
    assert np.allclose(fine[ia], coarse) and np.allclose(coarse[ib], fine[ia])
    ia, ib = C.match_nodes(coarse + 50.0, fine[::2])           # shifted by half a coarse cell: none shared
    assert ia.size == 0 and ib.size == 0


def _front(x, z, speed=3000.0, t0=0.5):
    """A circular front from the hypocentre: rupture time t0 + r / speed."""
    return t0 + np.hypot(x[:, None], z[None, :]) / speed


def test_field_difference_inside_the_box_where_both_ruptured():
    xa = np.arange(-20000.0, 20000.1, 200.0)
    za = np.arange(-10000.0, 10000.1, 200.0)
    xb = np.arange(-20000.0, 20000.1, 100.0)
    zb = np.arange(10000.0, -10000.1, -100.0)
    A = _front(xa, za)
    B = _front(xb, zb) - 0.03                                   # 0.03 s earlier everywhere
    B[np.abs(xb) > 15000.0, :] += 5.0                           # outside the box: ignored
    d = C.field_difference(xa, za, A, xb, zb, B)
    n_box = int(np.sum(np.abs(xa) <= 15000) * np.sum(np.abs(za) <= 7500))
    assert d["n_box"] == n_box and d["n_both"] == n_box
    assert d["rms"] == pytest.approx(0.03) and d["mean"] == pytest.approx(0.03) and d["max_abs"] == pytest.approx(0.03)
    # where only one ruptured, the node is counted, not compared
    A2 = A.copy()
    A2[np.hypot(xa[:, None], za[None, :]) > 9000.0] = np.nan
    d2 = C.field_difference(xa, za, A2, xb, zb, B)
    assert d2["only_b"] > 0 and d2["only_a"] == 0 and d2["n_both"] + d2["only_b"] == n_box
    assert d2["rms"] == pytest.approx(0.03)
    # a local error: RMS and largest tell it apart
    B2 = _front(xb, zb)
    B2[np.abs(xb - 1000.0) < 1, np.abs(zb - 1000.0) < 1] += 0.5
    d3 = C.field_difference(xa, za, A, xb, zb, B2)
    assert d3["max_abs"] == pytest.approx(0.5) and d3["rms"] == pytest.approx(0.5 / math.sqrt(n_box))


def test_convergence_of_first_and_second_order_sequences():
    first = C.convergence({200.0: 1.0 + 0.4, 100.0: 1.0 + 0.2, 50.0: 1.0 + 0.1})
    assert [p[:2] for p in first["pairs"]] == [(200.0, 100.0), (100.0, 50.0)]
    assert [p[2] for p in first["pairs"]] == pytest.approx([0.2, 0.1])
    assert first["ratios"] == pytest.approx([2.0]) and first["order"] == pytest.approx([1.0])
    second = C.convergence({"50": 1.0 + 0.01, "200": 1.0 + 0.16, "100": 1.0 + 0.04})
    assert second["order"] == pytest.approx([2.0])
    assert C.convergence({100.0: 1.0, 50.0: 2.0})["ratios"] == []


STATIONS9 = ["faultst-120dp030", "faultst000dp030", "faultst120dp030", "faultst-090dp075", "faultst000dp075",
             "faultst090dp075", "faultst-120dp120", "faultst000dp120", "faultst120dp120"]


def _cmp(drt=0.01, dpeak=0.05, dslip=0.01):
    return {"diff": {"rupture_time": drt}, "rel": {"peak_rate": dpeak, "final_slip": dslip}}


def _runs(lag100=0.02, lag200=0.04):
    """Every station's metrics at 200, 100, 50 m: the rupture time late by ``lag``."""
    base = {"rupture_time": 3.0, "peak_rate": 4.0, "final_slip": 5.0}
    return {s: {200.0: {**base, "rupture_time": 3.0 + lag200}, 100.0: {**base, "rupture_time": 3.0 + lag100},
                50.0: dict(base)} for s in STATIONS9}


def _fields(rms100=0.02, rms200=0.04):
    return {(200.0, 100.0): {"rms": rms200}, (100.0, 50.0): {"rms": rms100}}


def _good():
    return {s: _cmp() for s in C.REF_STATIONS}, {"rms": 0.03}, _runs(), _fields()


def test_tpv101_acceptance_passes_on_good_data_and_names_each_failure():
    acc = C.check_tpv101(*_good())
    assert acc["pass"] and acc["checked"] and not acc["failures"]
    assert len(acc["rows"]) == 3 * 3 + 1 + 9 + 1 + 1
    cases = [
        (lambda r: r[0].__setitem__("faultst090dp075", _cmp(drt=-0.11)), "faultst090dp075, 100 m vs uguca: rupture time"),
        (lambda r: r[0].__setitem__("faultst000dp030", _cmp(dpeak=0.16)), "faultst000dp030, 100 m vs uguca: peak slip rate"),
        (lambda r: r[0].__setitem__("faultst000dp075", _cmp(dslip=-0.051)), "faultst000dp075, 100 m vs uguca: final slip"),
        (lambda r: r[1].__setitem__("rms", 0.101), "rupture-time field, 100 m vs uguca"),
        (lambda r: r[2]["faultst120dp120"][100.0].__setitem__("rupture_time", 3.06), "faultst120dp120: rupture time, 100 m vs 50 m"),
        (lambda r: r[3].update({(100.0, 50.0): {"rms": 0.051}, (200.0, 100.0): {"rms": 0.06}}),
         "rupture-time field, 100 m vs 50 m: RMS"),
        (lambda r: r[3][(200.0, 100.0)].__setitem__("rms", 0.015), "smaller than 200-100 m"),
        (lambda r: r[0].__setitem__("faultst000dp075", _cmp(drt=float("nan"))), "faultst000dp075, 100 m vs uguca: rupture time"),
    ]
    for spoil, name in cases:
        args = list(_good())
        spoil(args)
        acc = C.check_tpv101(*args)
        assert not acc["pass"] and acc["checked"], name
        assert len(acc["failures"]) == 1 and name in acc["failures"][0], (name, acc["failures"])


def test_tpv101_acceptance_is_not_checked_without_its_runs():
    stations, field, runs, fields = _good()
    no50 = {s: {k: v for k, v in by.items() if k != 50.0} for s, by in runs.items()}
    acc = C.check_tpv101(stations, field, no50, {(200.0, 100.0): {"rms": 0.04}})
    assert not acc["checked"] and not acc["pass"] and not acc["failures"]
    acc = C.check_tpv101({}, None, runs, fields)
    assert not acc["checked"] and not acc["pass"]


def test_tpv103_acceptance_stability_and_convergence():
    runs, fields = _runs(), {(100.0, 50.0): {"rms": 0.02}}
    ok = C.check_tpv103({"t_end": 12.0, "finite": True}, runs, fields)
    assert ok["pass"] and ok["checked"] and len(ok["rows"]) == 2 + 2 * 9 + 1
    short = C.check_tpv103({"t_end": 11.9, "finite": True}, runs, fields)
    assert not short["pass"] and "short of 12 s" in short["failures"][0]
    nan = C.check_tpv103({"t_end": 12.0, "finite": False}, runs, fields)
    assert not nan["pass"] and "non-finite" in nan["failures"][0]
    slip = _runs()
    slip["faultst000dp120"][100.0]["final_slip"] = 5.0 * 1.06
    bad = C.check_tpv103({"t_end": 12.0, "finite": True}, slip, fields)
    assert not bad["pass"] and bad["failures"] == [
        "faultst000dp120: final slip, 100 m vs 50 m: 6.0 %, not within 5.0 %"]
    assert not C.check_tpv103(None, runs, fields)["checked"]


def test_exit_status_follows_the_acceptance():
    from studies.tpv101 import run
    assert run.exit_status({"acceptance": C.check_tpv101(*_good())}) == 0
    stations, field, runs, fields = _good()
    stations["faultst000dp030"] = _cmp(drt=0.2)
    assert run.exit_status({"acceptance": C.check_tpv101(stations, field, runs, fields)}) == 1
    assert run.exit_status({"acceptance": C.check_tpv101({}, None, runs, fields)}) == 2
    assert run.station_offsets("faultst-120dp030") == (-120, 30)
    with pytest.raises(ValueError):
        run.station_offsets("faultst12dp")


def test_the_page_states_the_verdict_and_the_failures():
    from studies.tpv101 import rs_page as page
    stations, field, runs, fields = _good()
    stations["faultst090dp075"] = _cmp(dpeak=0.2)
    res = {"acceptance": C.check_tpv101(stations, field, runs, fields)}
    text = page.verdict(res)
    assert text.startswith("**Acceptance: FAIL**") and "faultst090dp075, 100 m vs uguca: peak slip rate: 20.0 %" in text
    assert page.verdict({"acceptance": C.check_tpv101(*_good())}).startswith("**Acceptance: PASS** (21 of 21")


def test_the_uguca_reference_reads():
    for s in C.REF_STATIONS:
        ref = C.load_reference(s)
        assert ref["t"][0] == 0.0 and ref["t"][-1] == pytest.approx(15.0, abs=0.011)
        assert ref["rate"][0] == pytest.approx(1e-12) and ref["stress"][0] == pytest.approx(75.0)
    m = C.station_metrics(*(C.load_reference("faultst000dp075")[k] for k in ("t", "slip", "rate")))
    assert m["rupture_time"] == pytest.approx(0.5686, abs=1e-3) and m["final_slip"] == pytest.approx(7.358, abs=1e-2)
    x, z, rt = C.load_reference_field()
    assert rt.shape == (x.size, z.size) == (720, 360)
    i, k = int(np.argmin(np.abs(x))), int(np.argmin(np.abs(z)))
    assert x[i] == 0.0 and z[k] == 0.0 and rt[i, k] == pytest.approx(m["rupture_time"], abs=0.02)
    # the field is symmetric about the hypocentre (the README): 4.5 km up dip and down
    k_up, k_dn = int(np.argmin(np.abs(z + 4500))), int(np.argmin(np.abs(z - 4500)))
    assert rt[i, k_up] == pytest.approx(rt[i, k_dn], abs=1e-6)


def test_the_page_finds_mirrored_stations_and_which_run_is_nearer():
    from studies.tpv101 import rs_page as page
    assert page.mirror("faultst-090dp075") == {"faultst090dp075"}
    assert page.mirror("faultst120dp030") == {"faultst-120dp030", "faultst120dp120", "faultst-120dp120"}
    m = {"rupture_time": 3.0, "peak_rate": 4.0, "final_slip": 5.0}
    run = {"stations": {s: dict(m) for s in STATIONS9}}
    run["stations"]["faultst-120dp120"]["peak_rate"] = 4.25
    assert page.symmetry({"runs": {"100": run}}) == {"rupture_time": 0.0, "peak_rate": 0.25, "final_slip": 0.0}
    # cracklab 100 m 0.01 s from its 50 m run, uguca 0.03 s: cracklab is nearer; the peak
    # slip rate changes more from 100 to 50 m than from 200 to 100 m: undecided
    def cmp(sim, ref):
        return {"sim": sim, "ref": ref}
    uguca = {"100": {}, "50": {}}
    conv = {}
    for s in ("faultst000dp075", "faultst000dp030", "faultst090dp075"):
        uguca["100"][s] = cmp({"rupture_time": 3.01, "peak_rate": 4.0, "final_slip": 5.0},
                              {"rupture_time": 3.03, "peak_rate": 4.4, "final_slip": 5.1})
        uguca["50"][s] = cmp({"rupture_time": 3.00, "peak_rate": 4.3, "final_slip": 5.0}, uguca["100"][s]["ref"])
        conv[s] = {"rupture_time": {"pairs": [(200.0, 100.0, 0.02), (100.0, 50.0, 0.01)]},
                   "peak_rate": {"pairs": [(200.0, 100.0, 0.1), (100.0, 50.0, -0.3)]},
                   "final_slip": {"pairs": [(200.0, 100.0, 0.01), (100.0, 50.0, 0.0)]}}
    res = {"uguca": uguca, "convergence": conv, "fields": {"100-50": {"rms": 0.01, "mean": 0.01}},
           "uguca_field": {"50": {"rms": 0.03, "mean": 0.03}}}
    text = page.which_converges(res)
    rows = [r for r in text.splitlines() if r.startswith("| faultst")]
    assert len(rows) == 9
    assert all(r.endswith("| cracklab |") for r in rows if "rupture time" in r or "final slip" in r)
    assert all("undecided" in r for r in rows if "peak rate" in r)
    assert "nearer its 50 m value in 6, uguca's in 0; 3 cannot be told" in text
    assert "cracklab's 100 m field is the nearer" in text
