"""studies/cycles/cost.py, which the cycles page's "Against the target" paragraph quotes:
its breakdown of a BP1-QD rate evaluation and step runs, and its parts add up."""
from __future__ import annotations

from studies.cycles.cost import breakdown


def test_the_cost_breakdown_runs_and_its_parts_add_up():
    b = breakdown(800.0, years=0.5, repeats=3)
    assert b["nodes"] == 800 and 0 < b["sliding_points"] < b["nodes"]
    for key in ("rates_s", "transforms_s", "solve_s", "step_own_s"):
        assert b[key] > 0, key
    assert b["transforms_s"] + b["solve_s"] + b["glue_s"] == b["rates_s"]
    assert b["step_s"] == 6 * b["rates_s"] + b["step_own_s"]
