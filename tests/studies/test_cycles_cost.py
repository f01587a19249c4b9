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
    assert b["step_s"] == b["evaluations"] * b["rates_s"] + b["step_own_s"]
    assert b["evaluations"] == {"dormand_prince": 6, "bogacki_shampine": 3}[b["pair"]]


def test_the_pairs_reach_along_the_negative_axis_is_their_stability_polynomials():
    """The cycles page's stability limit of the steps in events (run.real_stability, from the
    tableau's stability polynomial) against the stability polynomial of each pair, found independently: any
    three-stage pair of order 3 has R(z) = 1 + z + z^2/2 + z^3/6 (Bogacki-Shampine, 2.5127),
    Dormand-Prince 5(4)'s six stages add z^6/600 to the Taylor series to z^5 (3.3066;
    Hairer & Wanner, Solving ODEs II, IV.2)."""
    import math

    import numpy as np

    from cracklab.solver.sequence.pairs import BOGACKI_SHAMPINE, DORMAND_PRINCE
    from studies.cycles.run import real_stability

    for pair, extra in ((BOGACKI_SHAMPINE, ()), (DORMAND_PRINCE, (1 / 600,))):
        taylor = [1 / math.factorial(k) for k in range(pair.order + 1)] + list(extra)
        in_x = np.array([c * (-1) ** k for k, c in enumerate(taylor)])      # R(-x), x^0 first
        roots = []
        for target in (1.0, -1.0):           # |R(-x)| = 1
            p = in_x.copy()
            p[0] -= target
            roots += [r.real for r in np.roots(p[::-1]) if abs(r.imag) < 1e-9 and r.real > 1e-9]
        x = min(roots)
        assert abs(real_stability(pair) - x) < 1e-5, (pair.name, real_stability(pair), x)
    assert abs(real_stability(DORMAND_PRINCE) - 3.3066) < 1e-3
    assert abs(real_stability(BOGACKI_SHAMPINE) - 2.5127) < 1e-3
