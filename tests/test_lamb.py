"""Lamb's problem (section 3.2) against Pekeris (1955), ERRATA section 2."""
import numpy as np
import pytest

from cracklab import Record, simulate, stations
from cracklab.exact import lamb_arrivals, lamb_opening
from cracklab.scenes import lamb

N = 128
R_CELLS = 32


@pytest.fixture(scope="module")
def run():
    r = R_CELLS / N
    scene = lamb(n=N, t_end=1.7 * r, record=Record(fields=("delta_2",), every=50,
                                                   stations={"r32": (0.5 + r, 0.5)}))
    ds = simulate(scene)
    st = stations(ds).sel(station="r32")
    return r, st.t.values, st.delta_2.values


def test_opening_follows_pekeris(run):
    """Within 5% of the static value, away from +-0.03 in tau around the P, S, R arrivals."""
    r, t, d = run
    tau = t / r
    static = 3.0 / (4.0 * np.pi * r)
    exact = lamb_opening(r, t)
    away = np.ones_like(tau, dtype=bool)
    for ta in lamb_arrivals():
        away &= np.abs(tau - ta) > 0.03
    err = np.max(np.abs(d[away] - exact[away])) / static
    assert err < 0.05, f"max error {err:.4f} of the static value"


def test_opening_reaches_static_value(run):
    r, t, d = run
    static = 3.0 / (4.0 * np.pi * r)
    late = t / r > 1.45
    err = np.max(np.abs(d[late] - static)) / static
    assert err < 0.02, f"late-time error {err:.4f} of the static value"


def test_nothing_moves_before_p_wave(run):
    r, t, d = run
    early = t / r < lamb_arrivals()[0] - 0.1
    static = 3.0 / (4.0 * np.pi * r)
    assert np.max(np.abs(d[early])) < 0.01 * static
