"""studies/cycles/uguca.py: uguca's catalogues read as its README defines them, and the
page's comparison built from both codes' earthquakes (no run: synthetic catalogues)."""
from studies.cycles import uguca


def _cat(starts, peaks, hypo):
    return {"start_yr": starts, "peak_slip_rate": peaks, "hypo_depth_km": hypo, "duration_s": [1.0] * len(starts)}


def test_a_uguca_catalogue_is_read_with_its_comment_line(tmp_path):
    path = tmp_path / "bp1qd_N1000_xi0.0625_events.csv"
    path.write_text("# start_yr,duration_s,hypo_depth_km,peak_slip_rate_m_per_s,depth_of_peak_km,time_of_peak_yr\n"
                    "250.985862,140.3243,13.700,4.719728e+00,0.000,250.985864\n"
                    "340.869018,132.3313,13.200,4.569791e+00,0.000,340.869019\n")
    cat = uguca.read_uguca(path)
    assert cat["start_yr"] == [250.985862, 340.869018]
    assert cat["peak_slip_rate"] == [4.719728, 4.569791]
    assert cat["hypo_depth_km"] == [13.7, 13.2]


def test_the_section_pairs_the_earthquakes_and_states_the_largest_gap():
    ug = {"bp1qd_N1000_xi0.0625": {"dz": 100.0, "S": 0.0625,
                                   "catalogue": _cat([251.0, 341.0, 430.0], [4.7, 4.6, 4.5], [13.7, 13.2, 13.1])}}
    # cracklab: a small event (left out), two whole ruptures, then one stopped at depth and restarted
    ck = {"100": _cat([100.0, 250.0, 339.5, 428.7, 428.7], [0.01, 4.46, 4.36, 0.72, 2.98], [13.0, 13.7, 13.2, 13.2, 0.4])}
    lines = uguca.section({"uguca": ug, "cracklab": ck})
    text = "\n".join(lines)
    assert "| 0 | 250.00 | 4.46 | 13.7 | 251.00 | 4.70 | 13.7 |" in text
    assert "| 3 | 428.70 | 2.98 | 0.4 | - | - | - |" in text
    # the earthquakes above 0.1 m/s paired in order: 250.0-251.0, 339.5-341.0, 428.7-430.0
    assert "differ by -1.50 to -1.00 years" in text
    assert "4 earthquakes here and 3 in uguca" in text and "3 of cracklab's nucleate at depth" in text


def test_the_uguca_section_is_kept_from_the_page_when_its_runs_are_not_at_hand():
    from studies.cycles.run import kept_section

    page = "# T\n\n## Events\n\nx\n\n## Against uguca\n\nline 1\n\n### sub\n\nline 2\n\n## An ensemble\n\ny\n"
    assert kept_section(page, "## Against uguca") == ["## Against uguca", "", "line 1", "", "### sub", "",
                                                      "line 2", ""]
    assert kept_section(page, "## Missing") == []
    assert kept_section("# T\n\n## Against uguca\nlast\n", "## Against uguca") == ["## Against uguca", "last"]
