"""SEAS BP5 (scenes.bp5): its parameters at points of each region against the benchmark's
values (Jiang & Erickson 2020, the parameter table), bad input, and a short coarse run whose
first event starts in the nucleation zone and whose free surface is the mirror."""
import math

import numpy as np
import pytest

from cracklab import InputError, analysis, scenes, simulate

YEAR = 365.0 * 24 * 3600
# the benchmark's values, typed from its table
SIGMA_N, A0, A_MAX, B0, V0, F0, V_P, V_I = 25e6, 0.004, 0.04, 0.03, 1e-6, 0.6, 1e-9, 0.03
ETA = 2670.0 * 3464.0**2 / (2 * 3464.0)


def _at(scene, field, strike_km, depth_km):
    """A field of ``scene`` at the node (strike from the fault's centre, depth) in km."""
    g = scene.grid
    i, k = g.nearest_node(g.x1[g.n1 // 2] + 1e3 * strike_km, 1e3 * depth_km)
    return np.broadcast_to(np.asarray(field, dtype=float), g.shape)[i, k]


def _tau0(a, V):
    # steady sliding at V_p's state, psi = f0 + b0 ln(V0 / V_init), loaded to slide at V
    return SIGMA_N * a * math.asinh(V / (2 * V0) * math.exp((F0 + B0 * math.log(V0 / V_P)) / a)) + ETA * V


@pytest.fixture(scope="module")
def bp5():
    return scenes.bp5(dx=1000.0)


# (strike km, depth km, a, D_c, initial slip rate, creeping): one point or more of each region
POINTS = [
    (0.0, 10.0, A0, 0.14, V_P, False),            # the velocity-weakening patch
    (29.0, 15.0, A0, 0.14, V_P, False),
    (0.0, 3.0, 0.022, 0.14, V_P, False),          # the transitions: r = 1/2
    (0.0, 17.0, 0.022, 0.14, V_P, False),
    (31.0, 10.0, 0.022, 0.14, V_P, False),
    (-31.0, 10.0, 0.022, 0.14, V_P, False),
    (31.0, 17.0, 0.022, 0.14, V_P, False),        # r = max(1/2, 1/2)
    (0.0, 1.0, A_MAX, 0.14, V_P, False),          # velocity strengthening: shallow, deep, the ends
    (0.0, 0.0, A_MAX, 0.14, V_P, False),
    (0.0, 30.0, A_MAX, 0.14, V_P, False),
    (45.0, 10.0, A_MAX, 0.14, V_P, False),
    (50.0, 40.0, A_MAX, 0.14, V_P, False),        # the rate-and-state fault's corner
    (0.0, 41.0, A_MAX, 0.14, V_P, True),          # creeping: below W_f, beyond l_f / 2
    (51.0, 10.0, A_MAX, 0.14, V_P, True),
    (-60.0, 0.0, A_MAX, 0.14, V_P, True),
    (-24.0, 10.0, A0, 0.13, V_I, False),          # the nucleation zone: corners and centre
    (-30.0, 4.0, A0, 0.13, V_I, False),
    (-18.0, 16.0, A0, 0.13, V_I, False),
    (-17.0, 10.0, A0, 0.14, V_P, False),          # just outside it
    (-24.0, 17.0, 0.022, 0.14, V_P, False),
]


@pytest.mark.parametrize("strike, depth, a, D_c, V, creeping", POINTS)
def test_bp5_parameters_at_points_of_each_region(bp5, strike, depth, a, D_c, V, creeping):
    law = bp5.law
    assert _at(bp5, law.a, strike, depth) == pytest.approx(a, rel=1e-12)
    assert _at(bp5, law.b, strike, depth) == B0
    assert _at(bp5, law.L, strike, depth) == D_c
    assert _at(bp5, law.V_ini, strike, depth) == V
    assert _at(bp5, law.sigma_n, strike, depth) == SIGMA_N
    assert (law.V0, law.f0, law.evolution) == (V0, F0, "ageing")
    assert bool(_at(bp5, bp5.sequence.creep, strike, depth)) is creeping
    assert _at(bp5, bp5.loading.tau0_1, strike, depth) == pytest.approx(_tau0(a, V), rel=1e-12)
    assert _at(bp5, bp5.loading.tau0_3, strike, depth) == 0.0


def test_bp5_scene(bp5):
    g, seq = bp5.grid, bp5.sequence
    assert g.free_surface and (g.dx1, g.dx3) == (1000.0, 1000.0)
    assert (bp5.material.cs, bp5.material.mu, bp5.material.nu) == (3464.0, 2670.0 * 3464.0**2, 0.25)
    assert (seq.response, seq.plate_rate_1, seq.plate_rate_3) == ("quasi_dynamic", V_P, 0.0)
    assert bp5.t_end == 1800 * YEAR
    assert (seq.slow_interval, seq.fast_interval) == (5 * YEAR, 1.0)
    assert sorted(bp5.record.stations) == sorted([
        "fltst_strk-36dp+00", "fltst_strk-16dp+00", "fltst_strk+00dp+00", "fltst_strk+16dp+00",
        "fltst_strk+36dp+00", "fltst_strk-24dp+10", "fltst_strk-16dp+10", "fltst_strk+00dp+10",
        "fltst_strk+16dp+10", "fltst_strk+00dp+22"])
    xc = g.x1[g.n1 // 2]
    assert bp5.record.stations["fltst_strk-24dp+10"] == (xc - 24e3, 10e3)
    fd = scenes.bp5(dx=2000.0, years=10.0, dynamic=True)
    assert (fd.sequence.response, fd.sequence.fast_interval, fd.sequence.tolerance) == ("dynamic", 0.1, 1e-5)


@pytest.mark.parametrize("kwargs, field", [
    ({"dx": 3000.0}, "dx"),                   # 66.7 x 33.3 nodes: not an even fast size
    ({"dx": -1.0}, "dx"),
    ({"dx": 20000.0}, "dx"),                  # 10 x 5 nodes: too coarse to hold the fault with creep around
    ({"domain": (100e3, 100e3)}, "domain"),   # no room along strike for the creeping plane
    ({"domain": (200e3, 40e3)}, "domain"),    # nor below W_f
    ({"years": 0.0}, "years"),
    ({"tolerance": 2.0}, "sequence.tolerance"),
])
def test_bp5_bad_input_names_the_field(kwargs, field):
    with pytest.raises(InputError) as err:
        scenes.bp5(**kwargs)
    assert err.value.field == field


def test_bp5_short_run_nucleates_in_the_zone_under_a_free_surface():
    """BP5-QD at dx = 4 km for 15 minutes: the nucleation zone slides at V_i from the start, so the
    first event's hypocentre lies in it; the state starts steady at V_init everywhere; slip
    along x3, odd about the mirror, vanishes on the surface while slip along strike does not."""
    ds = simulate(scenes.bp5(dx=4000.0, years=900.0 / YEAR, domain=(192e3, 96e3)))
    xc = 96e3
    ev = analysis.events(ds)
    assert ev.sizes["event"] >= 1
    x2, x3 = float(ev.hypocentre_x1[0]) - xc, float(ev.hypocentre_x3[0])
    assert -30e3 <= x2 <= -18e3 and 4e3 <= x3 <= 16e3
    assert float(ev.t_start[0]) < 1.0
    assert np.allclose(ds.psi.isel(t=0), F0 + B0 * math.log(V0 / V_P), rtol=1e-9)
    last = ds.isel(t=-1)
    assert np.all(last.delta_3.sel(x3=0.0) == 0.0) and np.all(last.v_3.sel(x3=0.0) == 0.0)
    assert float(abs(last.delta_3).max()) > 0.0
    assert float(last.delta_1.sel(x1=xc - 24e3, x3=0.0)) > 0.0


def _unfold(field, n3):
    """A half-plane field (n1, n3 + 1) on the doubled periodic cell (n1, 2 n3): depth
    min(k, 2 n3 - k) at node k, the fault and its image above the surface."""
    k = np.arange(2 * n3)
    return np.asarray(field)[:, np.minimum(k, 2 * n3 - k)]


def test_bp5_mirror_is_the_fault_and_its_image_on_the_doubled_cell():
    """The free surface of bp5 (Grid(free_surface=True)) against the same fault and its image
    written out on the periodic cell of twice the depth: there slip along strike at a point
    and at its image are equal (and dip slip opposite), and both equal bp5's, over the first
    5 s of the first event. Equal to 1e-5 of the largest slip (measured: 1.6e-6 between
    the doubled cell's sides, 1e-6 against bp5), not to round-off: the two sides differ
    from the first step by about the friction solve's tolerance, which the nucleating event
    amplifies (1e-4 of the largest slip after a minute). Dip slip, 1.4e-3 of the largest
    slip, is odd to 8e-5 of the largest slip, and zero on the surface."""
    t_end = 5.0
    half = scenes.bp5(dx=4000.0, years=t_end / YEAR, domain=(192e3, 96e3))
    g, law, n3 = half.grid, half.law, half.grid.n3
    full_grid = type(g)(n1=g.n1, n3=2 * n3, L1=g.L1, L3=2 * g.L3)
    full = half.replace(
        grid=full_grid,
        law=type(law)(**{**{f: getattr(law, f) for f in ("b", "V0", "f0", "sigma_n", "evolution")},
                         **{f: _unfold(np.broadcast_to(getattr(law, f), g.shape), n3)
                            for f in ("a", "L", "V_ini")}}),
        loading=type(half.loading)(tau0_1=_unfold(half.loading.tau0_1, n3)),
        sequence=type(half.sequence)(**{**{f: getattr(half.sequence, f) for f in (
            "response", "plate_rate_1", "tolerance", "slow_interval", "fast_interval", "dt_max")},
            "creep": _unfold(half.sequence.creep, n3)}),
        record=type(half.record)(fields=("delta_1", "delta_3")))
    a, b = simulate(half).isel(t=-1), simulate(full).isel(t=-1)
    assert float(a.t) == float(b.t) == t_end
    d1 = b.delta_1.values                  # (x1, x3) on the doubled cell
    k = np.arange(1, n3)
    top = float(d1.max())
    assert top > 0.1                       # the event slips
    np.testing.assert_allclose(d1[:, k], d1[:, 2 * n3 - k], rtol=0, atol=1e-5 * top)
    d3 = b.delta_3.values
    assert float(abs(d3).max()) > 1e-3 * top
    np.testing.assert_allclose(d3[:, k], -d3[:, 2 * n3 - k], rtol=0, atol=2e-4 * top)
    assert float(abs(d3[:, 0]).max()) < 1e-9 * top
    # bp5's half plane is the doubled cell's upper half: the same slip (region x3 in [0, 40 km])
    nz = a.sizes["x3"]
    i0 = int(np.argmin(np.abs(b.x1.values - float(a.x1[0]))))
    np.testing.assert_allclose(a.delta_1.values, d1[i0:i0 + a.sizes["x1"], :nz], rtol=0, atol=1e-5 * top)
