"""studies/cycles/stiff.py, which the cycles page quotes on what a stiffly stable step would
save: the pairs' stability polynomials and regions against their known values, and the
Jacobian it gives scipy's Radau against central differences of the rates."""
from __future__ import annotations

import numpy as np


def test_the_stability_polynomials_and_regions_of_the_pairs():
    """Any explicit pair of order 3 with three stages that count has R(z) = 1 + z + z^2/2 +
    z^3/6 (Bogacki-Shampine's fourth stage has no weight); Dormand-Prince 5(4) adds z^6/600
    (Hairer & Wanner, Solving ODEs II, IV.2). The region of the first reaches sqrt(3) along
    the imaginary axis; along the negative axis both reach what run.real_stability finds."""
    from cracklab.solver.sequence.pairs import BOGACKI_SHAMPINE, DORMAND_PRINCE
    from studies.cycles.run import real_stability, stability_polynomial
    from studies.cycles.stiff import _reach

    np.testing.assert_allclose(stability_polynomial(BOGACKI_SHAMPINE), [1, 1, 1 / 2, 1 / 6, 0], atol=1e-15)
    np.testing.assert_allclose(stability_polynomial(DORMAND_PRINCE),
                               [1, 1, 1 / 2, 1 / 6, 1 / 24, 1 / 120, 1 / 600, 0], atol=1e-15)
    for pair in (BOGACKI_SHAMPINE, DORMAND_PRINCE):
        theta, reach = _reach(pair)
        assert abs(reach[-1] - real_stability(pair)) < 3e-4, pair.name
    theta, reach = _reach(BOGACKI_SHAMPINE)
    assert abs(reach[0] - np.sqrt(3.0)) < 3e-4


def test_the_jacobian_is_the_rates_central_differences():
    """At the start and after 40 accepted steps of BP1-QD at 800 m, column by column, to 1e-6
    of the largest entry (the helper's differences are exact in the slip: the traction is
    affine in it; in the load and the state they are central, of step 1e-5)."""
    from studies.cycles.stiff import explicit

    p, rows, _ = explicit(800.0, 5.0, keep=True)
    for t, _, _, _, y in (rows[0], rows[min(40, len(rows) - 1)]):
        J = p.jacobian(t, y)
        scale = np.concatenate([p.L, p.a])
        F = np.empty_like(J)
        for j in range(y.size):
            e = np.zeros(y.size)
            e[j] = 1e-4 * scale[j]
            F[:, j] = (p.rates(t, y + e) - p.rates(t, y - e)) / (2 * e[j])
        assert np.abs(J - F).max() <= 1e-6 * np.abs(F).max(), np.abs(J - F).max() / np.abs(F).max()
