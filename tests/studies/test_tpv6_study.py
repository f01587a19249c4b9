"""The TPV6 study's comparison machinery (studies/tpv6/compare.py, run.py's verdict) on
synthetic series and files with known answers, and the reference read as its README
describes it."""
from __future__ import annotations

import numpy as np
import pytest

from studies.benchmarks.harness import reference_dir
from studies.tpv6 import compare as C


def _reference():
    try:
        return reference_dir("tpv6_mdsbi")
    except FileNotFoundError:
        return None


REF = _reference()


def pulse(dt, t_r, peak=10.0, D=6.0, t_end=12.0):
    """Slip rate rising linearly from t_r to ``peak`` at t_r + 0.1, back to 0 at t_r + 1.1,
    scaled so that the slip (its integral) ends at D; returns t, slip, rate, the true peak."""
    t = np.arange(0.0, t_end + dt / 2, dt)
    s = t - t_r
    rate = np.where((s > 0) & (s <= 0.1), peak * s / 0.1, 0.0)
    rate = np.where((s > 0.1) & (s < 1.1), peak * (1.1 - s), rate)
    rate *= D / (0.5 * peak * 1.1)
    slip = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * dt)])
    return t, slip, rate, peak * D / (0.5 * peak * 1.1)


def normal_history(t, t_r, swing=20.0):
    return -120.0 + swing * np.sin(np.clip(t - t_r, 0, None)) * (t > t_r)


def reference(t_r=5.0, ratio=3.0):
    """A synthetic reference station: the far face takes ratio / (1 + ratio) of the slip."""
    t, slip, rate, peak = pulse(0.005, t_r)
    far = {k: np.zeros_like(t) for k in C.COLUMNS}
    near = {k: np.zeros_like(t) for k in C.COLUMNS}
    for side, share in ((far, ratio / (1 + ratio)), (near, -1 / (1 + ratio))):
        side["t"] = t
        side["h_disp"], side["h_vel"] = share * slip, share * rate
        side["n_stress"] = normal_history(t, t_r)
    return {"t": t, "slip": slip, "rate": rate, "normal": far["n_stress"], "far": far, "near": near}, peak


def simulation(t_r=5.0, slip_factor=1.0, normal_offset=0.0, ratio=3.0, dt=1e-3):
    t, slip, rate, _ = pulse(dt, t_r)
    slip, rate = slip_factor * slip, slip_factor * rate
    return {"t": t, "slip": slip, "rate": rate, "normal": normal_history(t, t_r) + normal_offset,
            "far_disp": ratio / (1 + ratio) * slip, "near_disp": -slip / (1 + ratio)}


def test_compare_station_known_offsets():
    ref, peak = reference(t_r=5.0)
    sim = simulation(t_r=5.04, slip_factor=1.03, normal_offset=2.0)
    c = C.compare_station(sim, ref)
    assert c["ref"]["rupture_time"] == pytest.approx(5.005, abs=1e-9)        # first 0.005 s sample above 1 mm/s
    assert c["diff"]["rupture_time"] == pytest.approx(0.04, abs=1e-9)
    assert c["rel"]["final_slip"] == pytest.approx(0.03, abs=1e-9)
    assert c["ref"]["peak_rate"] == pytest.approx(peak, rel=1e-3)
    assert c["rel"]["peak_rate"] == pytest.approx(0.03, abs=2e-3)
    # a constant offset of 2 MPa, except over the 0.04 s the swing starts later (a small extra)
    assert 1.9 < c["normal_rms"] < 2.1
    assert c["faces"]["far"]["rel"] == pytest.approx(0.03, abs=1e-9)
    assert c["faces"]["near"]["sim"] == pytest.approx(-1.03 * 6.0 / 4.0, rel=1e-3)
    assert c["t_end"] == pytest.approx(12.0)


def test_ripple_is_the_oscillation_about_the_running_mean():
    t = np.arange(0.0, 12.0, 0.005)
    trend = -120.0 + 3.0 * np.tanh(t - 6.0)
    wave = 2.0 * np.sin(2 * np.pi * t / 0.05) * (t > 5.0)        # 0.05 s period, amplitude 2, from 5 s
    assert C.ripple(t, trend, 5.5) < 1e-2      # a smooth history has next to none (its curvature: 3e-3)
    assert C.ripple(t, trend + wave, 5.5) == pytest.approx(2.0 / np.sqrt(2.0), rel=2e-2)
    assert C.ripple(t, trend + wave, 0.0) < C.ripple(t, trend + wave, 5.5)   # quiet before 5 s
    ref, _ = reference()
    sim = simulation()
    sim["normal"] = sim["normal"] + np.interp(sim["t"], t, wave)
    c = C.compare_station(sim, ref)
    assert c["ripple"]["normal"]["ref"] < 0.2 < 1.2 < c["ripple"]["normal"]["sim"] < 1.6


def test_acceptance_holds_within_the_limits_and_fails_each_one_outside():
    ref, _ = reference()
    good = C.compare_station(simulation(t_r=5.06, slip_factor=1.04, normal_offset=4.0), ref)
    acc = C.check_acceptance({"a": {100.0: good}, "b": {"100": good}})
    assert acc["pass"] and not acc["failures"] and len(acc["checks"]) == 8
    cases = {"rupture_time": simulation(t_r=5.16), "final_slip": simulation(slip_factor=1.06),
             "peak_rate": simulation(slip_factor=0.75), "normal_rms": simulation(normal_offset=6.0)}
    for quantity, sim in cases.items():
        acc = C.check_acceptance({"a": {100.0: good}, "b": {100.0: C.compare_station(sim, ref)}})
        assert not acc["pass"]
        failed = {(r["station"], r["quantity"]) for r in acc["checks"] if not r["pass"]}
        assert ("b", quantity) in failed and not any(s == "a" for s, _ in failed), (quantity, failed)
        assert any(C.QUANTITY[quantity] in f for f in acc["failures"])
    # a station without a comparison at this spacing, or one that never ruptures, fails
    assert not C.check_acceptance({"a": {200.0: good}})["pass"]
    still = dict(simulation(), rate=np.zeros_like(simulation()["rate"]))
    assert not C.check_acceptance({"a": {100.0: C.compare_station(still, ref)}})["pass"]
    # at another spacing the same limits apply to that spacing's comparisons
    assert C.check_acceptance({"a": {200.0: good, 100.0: C.compare_station(simulation(t_r=5.3), ref)}},
                              dx=200.0)["pass"]


def test_reference_files_named_and_read_by_side(tmp_path):
    ref, _ = reference(ratio=2.0)
    for side in ("far", "near"):
        cols = np.column_stack([ref[side][k] for k in C.COLUMNS])
        np.savetxt(tmp_path / f"{side}st-120dp075.txt", cols, header=" ".join(C.COLUMNS), comments="  ")
    assert C.reference_file("faultst-120dp075", "far", tmp_path).name == "farst-120dp075.txt"
    got = C.load_reference("faultst-120dp075", tmp_path)
    np.testing.assert_allclose(got["slip"], ref["slip"], atol=1e-12)
    np.testing.assert_allclose(got["normal"], ref["normal"])
    with pytest.raises(ValueError, match="side"):
        C.reference_file("faultst000dp000", "top")
    np.savetxt(tmp_path / "farst000dp000.txt", np.zeros((3, 7)), header="t", comments="  ")
    np.savetxt(tmp_path / "nearst000dp000.txt", np.zeros((3, 7)), header="t", comments="  ")
    with pytest.raises(ValueError, match="10 columns"):
        C.load_reference("faultst000dp000", tmp_path)


def test_contours_parsed_by_level(tmp_path):
    text = ("# problem=TPV6\n# Column #1 = strike\n\nj  k\n\nContour   5.000000e-001\n-1.0e+003 6.0e+003\n"
            "-9.0e+002 5.9e+003\n\nContour   1.000000e+000\n1.0 2.0\n3.0 4.0\n5.0 6.0\n")
    (tmp_path / "contour.dat").write_text(text)
    got = C.load_contours(tmp_path / "contour.dat")
    assert sorted(got) == [0.5, 1.0]
    np.testing.assert_array_equal(got[0.5][0], [[-1000.0, 6000.0], [-900.0, 5900.0]])
    assert got[1.0][0].shape == (3, 2)
    (tmp_path / "empty.dat").write_text("# nothing\n")
    with pytest.raises(ValueError, match="Contour"):
        C.load_contours(tmp_path / "empty.dat")


@pytest.mark.skipif(REF is None or not REF.is_dir(), reason="the MDSBI reference is not on this machine")
def test_the_reference_reads_as_its_readme_says():
    """README: at (0, 0) the final h-disp is +7.92 m far and -2.51 m near (10.43 m of slip);
    n-stress swings between -147 and -71 MPa at (12 km, 0); contours every 0.5 s (the file's
    24 'Contour' blocks: 15 levels, 0.5 s to 7.5 s, some in several pieces)."""
    r = C.load_reference("faultst000dp000")
    assert r["far"]["h_disp"][-1] == pytest.approx(7.92, abs=0.005)
    assert r["near"]["h_disp"][-1] == pytest.approx(-2.51, abs=0.005)
    assert r["slip"][-1] == pytest.approx(10.43, abs=0.005)
    r = C.load_reference("faultst120dp000")
    assert (r["normal"].min(), r["normal"].max()) == pytest.approx((-147.2, -71.4), abs=0.1)
    levels = C.load_contours()
    assert sorted(levels) == pytest.approx(list(np.arange(0.5, 7.51, 0.5)))
    assert sum(len(lines) for lines in levels.values()) == 24 and len(levels[6.5]) == 4


def test_verdict_without_the_100_m_run_is_not_checked():
    from studies.tpv6 import run as R
    ref, _ = reference()
    good = C.compare_station(simulation(t_r=5.06), ref)
    res = {"runs": {"200": {"error": None}}, "stations": {s: {"200": good} for s in R.REF_STATIONS},
           "acceptance": None}
    res["indicative"] = C.check_acceptance(res["stations"], dx=200.0)
    assert R.verdict_status(res) == ("NOT CHECKED (no 100 m run)", 2)
    assert "NOT CHECKED" in R.verdict(res) and "20 of 20 hold" in R.verdict(res)
    res["runs"]["200"]["error"] = "exponential growth of v_1"
    assert R.verdict_status(res)[1] == 2
    res = {"runs": {"100": {"error": None}}, "stations": {s: {"100": good} for s in R.REF_STATIONS},
           "indicative": None}
    res["acceptance"] = C.check_acceptance(res["stations"])
    assert R.verdict_status(res) == ("PASS", 0) and "PASS" in R.verdict(res)
    bad = C.compare_station(simulation(t_r=5.2), ref)
    res["stations"]["faultst120dp075"]["100"] = bad
    res["acceptance"] = C.check_acceptance(res["stations"])
    assert R.verdict_status(res) == ("FAIL", 1) and "faultst120dp075" in R.verdict(res)


def test_the_page_names_the_law_setting_and_compares_another_setting():
    from studies.tpv6 import run as R
    ref, _ = reference()
    reg = C.compare_station(simulation(t_r=5.06), ref)
    unreg = C.compare_station(simulation(t_r=5.06, slip_factor=1.5), ref)
    res = {"runs": {"100": {"error": None, "normal": {}}},
           "stations": {s: {"100": unreg} for s in R.REF_STATIONS}}
    assert "no regularisation" in R.law_setting(res)
    assert R.other_rows(res, [100.0]) == ""
    res["other"] = {"runs": {"100": {"error": None, "normal": {"normal_slip_scale": 0.1}}},
                    "stations": {s: {"100": reg} for s in R.REF_STATIONS},
                    "acceptance": C.check_acceptance({s: {"100": reg} for s in R.REF_STATIONS})}
    assert '"Another law setting"' in R.law_setting(res)
    text = R.other_rows(res, [100.0])
    assert "| peak, as stated | peak, L* = 0.1 m |" in text
    row = [line for line in text.splitlines() if line.startswith("| faultst120dp075 | 100 |")][0]
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert float(cells[2]) == pytest.approx(1.5 * float(cells[3]), rel=1e-2)     # the peaks, 1.5 times apart
    assert cells[7] == "+50.0"                                                  # final slip, as stated
    assert "With L* = 0.1 m the acceptance at 100 m is" in text
    assert "`normal_slip_scale` = 0.1 m" in R.law_setting(res["other"])


def test_the_surface_section_reads_the_surface_study():
    from studies.tpv6 import run as R
    run = {f"st{s}_z{z}": {"x3": float(z), "peak": p + (s == "+0") * 5.0, "rupture_time": 3.5}
           for s in ("+0", "-12", "+12") for z, p in (("0", 20.0), ("100", 11.0), ("400", 9.5), ("800", 9.0))}
    const = {k: dict(v, peak=v["peak"] + 1.0) for k, v in run.items()}
    meet = {"meet": {"peak": 42.0, "rupture_time": 6.7}, "quarter": {"peak": 17.0, "rupture_time": 3.3}}
    res = {"surface": {"t_end": 7.0, "runs": {"law": {"100": run}, "constant_normal": {"100": const}},
                       "analogue": {"tpv6": {"100": meet}}}}
    text = R.surface_rows(res)
    row = [line for line in text.splitlines() if line.startswith("| +0 km | 100 m |")][0]
    assert "| 25.0 / 26.0 | 16.0 / 17.0 | 14.5 / 15.5 | 14.0 / 15.0 |" in row     # by depth, law / constant
    assert "| the TPV6 pair | 100 m | 42.0 | 17.0 |" in text
    res["surface"]["inplane"] = {"as stated": {"100": {f"{k:+d}": {"peak": 10.0 + k, "rupture_time": 1.0,
                                                                   "normal": [-150.0, -80.0]}
                                                     for k in (-12, -6, 6, 12)}},
                                 "0.1": {"100": {"error": "grew"}}}
    text = R.surface_rows(res)
    assert "| as stated | 100 m | -2.0 | 4.0 | 16.0 | 22.0 | -150 to -80 |" in text
    assert "| L* = 0.1 m | 100 m | stopped by the solver |" in text
    d = R.surface_numbers(res["surface"])
    assert (d["ilaw_p12_100"], d["ilaw_m6_100_nmin"]) == ("22.0", "-150") and "iL0p1_p12_100" not in d
    assert (d["s0_0_law_100"], d["s0_below_const_100"], d["s12_800_law_100"]) == ("25.0", "17.0", "9.0")
    assert R.surface_rows({}) == ""


def test_the_scene_takes_the_regularisation():
    from studies.tpv6 import scene as S
    sc = S.build_scene(400.0, t_end=1.0, normal={"normal_slip_scale": 0.1, "normal_time": 0.05})
    assert (sc.law.normal_slip_scale, sc.law.normal_time, sc.law.sigma_n) == (0.1, 0.05, None)
    assert S.build_scene(400.0, t_end=1.0).law.normal_slip_scale is None


def test_the_surface_studys_analogues_are_the_scenes_it_describes():
    from studies.tpv6 import surface as S
    from cracklab.scenes import TPV6_FAR, TPV6_NEAR

    one = S.scene_2d(200.0, "one_speed")
    top, bottom = one.materials
    assert (top.mu, top.cs, bottom) == (TPV6_FAR.mu, TPV6_NEAR.cs, TPV6_NEAR)     # one shear speed, two moduli
    rock = S.scene_2d(200.0, "rock")
    assert rock.material == TPV6_NEAR and not rock.two_materials and one.two_materials
    assert one.law.sigma_n == S.SIGMA_N and one.components == (3,)
    inp = S.scene_inplane(200.0, slip_scale=0.1)
    assert inp.materials == (TPV6_FAR, TPV6_NEAR) and inp.law.sigma_n is None and inp.law.normal_slip_scale == 0.1
    assert inp.components == (1, 2) and inp.formulation == "product2"
    assert sorted(inp.record.stations) == ["+12", "+6", "-12", "-6"]
    t = np.linspace(0.0, 1.0, 201)
    m = S.measure(t, np.where(t >= 0.5, 2.0, 0.0))
    assert m["peak"] == 2.0 and m["rupture_time"] == pytest.approx(0.5)
