"""studies/cycles/bp5.py: the page built from synthetic results (no run): earthquakes above
0.1 m/s tabulated with their magnitude, slower events counted apart, and the grids'
earthquakes paired in order for self-convergence."""
from studies.cycles import bp5

YEAR = 365.0 * 24.0 * 3600.0


def _run(starts_yr, peaks, dx):
    n = len(starts_yr)
    ev = {"t_start": [s * YEAR for s in starts_yr], "t_end": [s * YEAR + 400.0 for s in starts_yr],
          "duration": [400.0] * n, "hypocentre_x1": [80e3] * n, "hypocentre_x3": [10e3] * n,
          "peak_slip_rate": peaks, "mean_slip": [4.0] * n, "rupture_area": [1.2e9] * n, "moment": [1e20] * n}
    big = [s for s, p in zip(starts_yr, peaks) if p > bp5.BIG]
    return {"dx": dx, "years": 1800.0, "wall_s": 600.0, "nodes": [200, 100], "resumed_from": None,
            "accepted_steps": 1000, "smallest_step": 0.02, "largest_step": YEAR, "wall_time_in_events": 400.0,
            "wall_time_between_events": 150.0, "events": ev, "x2_centre": 100e3, "earthquakes_yr": big,
            "recurrence_yr": [b - a for a, b in zip(big[:-1], big[1:])], "time_in_events_s": 800.0,
            "steps_in_events": 600}


def test_the_page_tabulates_earthquakes_and_pairs_the_grids(tmp_path):
    res = {"runs": {"1000": _run([0.0, 240.0, 40.0, 485.0], [1.1, 1.2, 0.01, 1.2], 1000.0),
                    "500": _run([0.0, 241.5, 487.0], [1.0, 1.1, 1.1], 500.0)}}
    page = tmp_path / "bp5.md"
    bp5.write_page(res, [1000.0, 500.0], page, [], "python -m studies.cycles.bp5")
    text = page.read_text()
    # Mw of 1e20 N m: 2/3 (20 - 9.1) = 7.27; x2 from the centre: 80 - 100 km
    assert "| 1 | 240.000 | 400.0 | -20.0 | 10.0 | 1.200 | 4.000 | 1200 | 1e+20 | 7.27 |" in text
    assert "1 slower events (peak at most 0.1 m/s) are left out of the table." in text
    assert "| 1000 m | 200 x 100 | 1800 | 600 s | 1000 | 0.02 s | 1 yr | 600 | 400 s / 150 s |" in text
    # 0 - 0, 241.5 - 240, 487 - 485; mean recurrence after the first interval: 245 and 245.5
    assert "the first 3 start +0.00, +1.50, +2.00 years apart" in text
    assert "mean recurrence 245.00 and 245.50 years" in text
    assert "took 10 min for 1800 years: within the hour" in text
