"""Lamb's problem (section 3.2) against Pekeris (1955), ERRATA section 2."""
import numpy as np
import pytest
from verification import check

from cracklab import Record, simulate, stations
from cracklab.analysis.exact import lamb_arrivals, lamb_opening
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


# Half-widths in tau of the windows left out around the P, S and R arrivals. Around R
# the point load's flat spectrum rings (Gibbs) over about 2.5 cells at 32 cells from
# the load, so the R window is wider than the 0.03 of P and S (docs/studies/verification.md).
WINDOWS = (0.03, 0.03, 0.08)


def test_opening_follows_pekeris(run):
    """Within 5% of the static value away from the wave arrivals."""
    r, t, d = run
    tau = t / r
    static = 3.0 / (4.0 * np.pi * r)
    exact = lamb_opening(r, t)
    away = np.ones_like(tau, dtype=bool)
    for ta, w in zip(lamb_arrivals(), WINDOWS):
        away &= np.abs(tau - ta) > w
    err = np.max(np.abs(d[away] - exact[away])) / static
    check("lamb-pekeris", err, f"max error {err:.4f} of the static value")


def test_opening_reaches_static_value(run):
    r, t, d = run
    static = 3.0 / (4.0 * np.pi * r)
    late = t / r > 1.45
    err = np.max(np.abs(d[late] - static)) / static
    check("lamb-static", err, f"late-time error {err:.4f} of the static value")


def test_history_engines_agree():
    """The exponential and the direct (untruncated) engine give the same opening history
    16 cells from the load, to 1e-3 of the static value (64 x 64, to t = 2.5 r / c_s)."""
    from cracklab import Numerics

    n, cells = 64, 16
    r = cells / n
    out = {}
    for engine in ("direct", "exponential"):
        scene = lamb(n=n, t_end=2.5 * r, record=Record(fields=("delta_2",), every=1000,
                                                       stations={"A": (0.5 + r, 0.5)}),
                     numerics=Numerics(engine=engine))
        out[engine] = stations(simulate(scene)).sel(station="A").delta_2.values
    static = 3.0 / (4.0 * np.pi * r)
    assert np.ptp(out["direct"]) > 0.5 * static  # the wave has passed the station
    assert np.max(np.abs(out["exponential"] - out["direct"])) / static <= 1e-3
