"""studies/cycles/run.py's section on the step's tolerance: the largest change of an event's
start and peak against the page's run, from the checks of studies/cycles/tolerance.py."""
from __future__ import annotations

from studies.cycles.run import YEAR, _tolerance_section


def test_the_tolerance_table_states_the_largest_changes():
    base = {"dz": 25.0, "tolerance": 1e-5, "accepted_steps": 100, "wall_s": 10.0, "steps_below_1e-7": 40,
            "events": {"t_start": [100 * YEAR, 200 * YEAR], "peak_slip_rate": [4.0, 5.0]}}
    checks = {"1e-06": {"dz": 25.0, "years": 1500.0, "tolerance": 1e-6, "accepted_steps": 150, "wall_s": 15.0,
                        "t_start_s": [100 * YEAR, 200.002 * YEAR, 300 * YEAR], "peak_slip_rate": [4.0, 5.05, 6.0]}}
    text = "\n".join(_tolerance_section(checks, base, 0.1))
    assert "| 1e-6 | 150 | - | 15 s | 0.002 years | 0.01 |" in text, text
    assert _tolerance_section(checks, {**base, "dz": 50.0}, 0.1) == []      # another grid's run: no table
    assert _tolerance_section(None, base, 0.1) == []
