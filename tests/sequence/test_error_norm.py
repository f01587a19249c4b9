"""The step control's error norm (solver/sequence/integrate.py, ``error_norm``): the largest
|err| / (tolerance scale) over the points integrated, slip against L + |slip| and state
against a, computed here with numpy from that definition; the first error that is not
finite wins."""
import numpy as np
import pytest


class _System:
    def __init__(self, L, a, keep):
        self.L, self.a, self.keep = L, a, keep

    def error_weights(self):
        return self.L, self.a, self.keep


def _reference(y, err, L, a, keep, tol, comps):
    scale = np.concatenate([L + np.abs(y[i * L.size:(i + 1) * L.size]) for i in range(comps)] + [a])
    mask = np.concatenate([keep] * (comps + 1))
    ratio = np.abs(err[mask]) / (tol * scale[mask])
    i = int(np.argmax(ratio)) if np.all(np.isfinite(ratio)) else int(np.flatnonzero(~np.isfinite(ratio))[0])
    return ratio[i], int(np.flatnonzero(mask)[i])


@pytest.mark.parametrize("comps", [1, 2])
@pytest.mark.parametrize("bad", [None, np.nan, np.inf])
def test_the_error_norm_is_the_largest_scaled_error_over_the_points_kept(comps, bad):
    from cracklab.solver.sequence.integrate import error_norm

    rng = np.random.default_rng(3 + comps)
    n = 50
    L, a = rng.uniform(0.01, 0.1, n), rng.uniform(0.005, 0.02, n)
    keep = rng.random(n) < 0.7
    y = rng.standard_normal(n * (comps + 1))
    err = 1e-6 * rng.standard_normal(y.size)
    err[np.flatnonzero(~keep)[0]] = 1.0             # the largest error, at a point not integrated
    if bad is not None:
        err[n * comps + np.flatnonzero(keep)[3]] = bad     # a state's error
        err[np.flatnonzero(keep)[5]] = bad                  # a slip's, before it in y: this one wins
    size, where = error_norm(_System(L, a, keep), y, err, 1e-5)
    ref_size, ref_where = _reference(y, err, L, a, keep, 1e-5, comps)
    assert where == ref_where
    assert (size == ref_size) if bad is None else (np.isnan(size) if np.isnan(bad) else size == np.inf)
    if bad is None:
        assert keep[where % n] and size < 1e5        # not the point left out


def test_nothing_kept_has_no_error():
    from cracklab.solver.sequence.integrate import error_norm

    n = 4
    assert error_norm(_System(np.ones(n), np.ones(n), np.zeros(n, bool)), np.zeros(2 * n), np.ones(2 * n),
                      1e-5) == (0.0, -1)
