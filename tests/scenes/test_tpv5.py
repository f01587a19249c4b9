"""scenes.tpv5: SCEC TPV5 on the half plane below a free surface (Grid(free_surface=True)):
the geometry, the three stress patches, the MDSBI reference's five stations by their names
(shared/reference/tpv5_mdsbi/README.md: ``st`` strike from the hypocentre, ``dp`` depth
below the surface, in units of 100 m), bad input, and a short coarse run."""
import re
from pathlib import Path

import numpy as np
import pytest

from cracklab import InputError, Loading, Record, scenes, simulate, stations

REFERENCE = Path(__file__).resolve().parents[3] / "shared" / "reference" / "tpv5_mdsbi"
if not REFERENCE.is_dir():
    REFERENCE = Path("/work/shared/reference/tpv5_mdsbi")


def _offsets(name):
    """(strike, depth) in m from a SCEC station name, read independently of the builder."""
    m = re.fullmatch(r"faultst(-?\d{3})dp(-?\d{3})", name)
    assert m, name
    return 100.0 * int(m.group(1)), 100.0 * int(m.group(2))


@pytest.mark.parametrize("dx", [100.0, 300.0])
def test_tpv5_grid_is_the_half_plane_below_the_surface(dx):
    sc = scenes.tpv5(dx=dx, t_end=0.1)
    g = sc.grid
    assert g.free_surface and (g.L1, g.L3) == (48000.0, 24000.0)
    assert g.shape == (round(48000 / dx), round(24000 / dx) + 1) and g.x3[0] == 0.0 and g.x3[-1] == 24000.0
    assert g.dx1 == g.dx3 == dx
    assert sc.loading.tau0_1.shape == g.shape and sc.law.bonded.shape == g.shape
    assert sc.units == {"length": "m", "time": "s", "stress": "Pa"}
    assert sc.t_end == 0.1 and sc.beta == 0.125 and sc.formulation == "product2"
    mat = sc.material
    assert mat.cs == 3464.0 and mat.nu == 0.25 and mat.mu / mat.cs**2 == pytest.approx(2670.0)
    law = sc.law
    assert (law.mu_s, law.mu_d, law.D_c, law.sigma_n) == (0.677, 0.525, 0.40, 120e6)


@pytest.mark.parametrize("dx", [100.0, 250.0, 300.0])
def test_tpv5_fault_reaches_the_surface_and_ends_at_15_km(dx):
    """Free nodes: the surface row (its cell continues into the image of the fault above
    the surface) down to the last node whose whole cell is above 15 km depth; along strike
    the nodes whose whole cell is within 15 km of the hypocentre."""
    sc = scenes.tpv5(dx=dx, t_end=0.1)
    g = sc.grid
    free = ~sc.law.bonded
    xc = g.x1[g.n1 // 2]
    strike = np.abs(g.x1 - xc) + dx / 2 <= 15000.0 + 1e-6
    depth = g.x3 + dx / 2 <= 15000.0 + 1e-6
    assert np.array_equal(free, np.outer(strike, depth))
    assert free[g.n1 // 2, 0]                                   # the fault breaks the surface
    assert not free[:, -1].any()                                # bonded at the bottom of the half plane
    if dx == 100.0:
        assert free[g.n1 // 2].sum() == 150 and free[:, 0].sum() == 299    # 0 .. 14.9 km, +-14.9 km


@pytest.mark.parametrize("dx", [100.0, 300.0, 600.0])
def test_tpv5_three_patches_carry_their_overstress_at_7_5_km(dx):
    """Each 3 km x 3 km square centred at 7.5 km depth carries (stress - 70 MPa) x 9 km^2
    (cell-area weights, as tpv3), at strike 0 (81.6), -7.5 km (78.0) and +7.5 km (62.0)."""
    sc = scenes.tpv5(dx=dx, t_end=0.1)
    g = sc.grid
    x = g.x1 - g.x1[g.n1 // 2]
    dtau = sc.loading.tau0_1 - 70e6
    for centre, stress in ((0.0, 81.6e6), (-7500.0, 78.0e6), (7500.0, 62.0e6)):
        near = np.abs(x - centre) < 3000.0
        assert dtau[near].sum() * dx * dx == pytest.approx((stress - 70e6) * 9e6, rel=1e-12)
        # centred at 7.5 km depth: the overstress is symmetric about it
        rows = dtau[near].sum(axis=0)
        depth_mean = (rows * g.x3).sum() / rows.sum()
        strike_mean = (dtau[near].sum(axis=1) * x[near]).sum() / dtau[near].sum()
        assert depth_mean == pytest.approx(7500.0) and strike_mean == pytest.approx(centre, abs=1e-6)
    far = np.ones(g.shape, dtype=bool)
    for centre in (0.0, -7500.0, 7500.0):
        far &= ~((np.abs(x - centre) < 1500.0 + dx)[:, None] & (np.abs(g.x3 - 7500.0) < 1500.0 + dx)[None, :])
    assert np.all(sc.loading.tau0_1[far] == 70e6)
    if dx == 100.0:
        i, k = g.n1 // 2, 75
        assert sc.loading.tau0_1[i, k] / 1e6 == pytest.approx(81.6)
        assert sc.loading.tau0_1[i - 75, k] / 1e6 == pytest.approx(78.0)
        assert sc.loading.tau0_1[i + 75, k] / 1e6 == pytest.approx(62.0)
        assert sc.loading.tau0_1[i, 0] == 70e6                    # the surface above the hypocentre
        assert sc.loading.tau0_1[i + 15, k] / 1e6 == pytest.approx(75.8)   # edge node: half the cell


def test_tpv5_records_the_reference_stations_by_their_names():
    names = sorted(p.stem for p in REFERENCE.glob("faultst*.txt"))
    assert len(names) == 5 and "faultst000dp000" in names
    for dx in (100.0, 300.0):
        sc = scenes.tpv5(dx=dx, t_end=0.1)
        g = sc.grid
        xc = g.x1[g.n1 // 2]
        st = sc.record.stations
        nodes = sc.record.station_nodes(g)
        for name in names:
            strike, depth = _offsets(name)
            assert st[name] == pytest.approx((xc + strike, depth), abs=1e-6), name
            i, k = nodes[name]
            assert (g.x1[i] - xc, g.x3[k]) == pytest.approx((strike, depth), abs=1e-6)   # on a node
            assert not sc.law.bonded[i, k]
        assert nodes["faultst000dp000"][1] == 0                  # the surface node
    assert set(scenes.tpv3_station_name(s, d) for s, d in scenes.TPV5_REFERENCE_STATIONS) == set(names)


def test_tpv5_bad_input_is_one_input_error():
    sc = scenes.tpv5(dx=1000.0, t_end=0.1)
    g = sc.grid
    # a station above the free surface
    with pytest.raises(InputError) as err:
        scenes.tpv5(dx=1000.0, t_end=0.1, record=Record(fields=(), stations={"sky": (24000.0, -100.0)}))
    assert err.value.field == "record.stations.sky" and "above the free surface" in str(err.value)
    # a field on the periodic n1 x n3 grid, not the half plane's n1 x (n3 + 1)
    with pytest.raises(InputError) as err:
        sc.replace(loading=Loading(tau0_1=np.full((g.n1, g.n3), 70e6)))
    assert err.value.field == "loading.tau0_1" and "free surface" in str(err.value)
    assert f"({g.n1}, {g.n3 + 1})" in str(err.value)
    # a cell that cannot hold the fault, or no cell at all
    for domain in ((30000.0, 24000.0), (48000.0, 15000.0), (48000.0,), "big", None):
        with pytest.raises(InputError) as err:
            scenes.tpv5(dx=1000.0, t_end=0.1, domain=domain)
        assert err.value.field == "domain", domain
    for dx in (0.0, -100.0, float("nan"), "wide"):
        with pytest.raises(InputError) as err:
            scenes.tpv5(dx=dx, t_end=0.1)
        assert err.value.field == "dx"


def test_tpv5_coarse_run_starts_at_the_hypocentre_and_keeps_the_surface_free():
    """1000 m, 1 s. The hypocentre starts above its static strength (81.6 > 81.24 MPa), so
    its slip rate at t = 0 is the radiation-damping one, 2 c_s (tau0 - mu_s sigma_n) / mu =
    0.0778 m/s, under the static strength 81.24 MPa: MDSBI's first record at the hypocentre;
    the patch at -7.5 km does not slip yet; on the surface the dip slip (odd about it) is
    exactly zero."""
    sc = scenes.tpv5(dx=1000.0, t_end=1.0)
    ds = simulate(sc.replace(record=Record(fields=("tau_3",), every=10, stations=dict(sc.record.stations))))
    st = stations(ds)
    hypo = st.sel(station="faultst000dp075")
    v0 = 2 * 3464.0 * (81.6e6 - 0.677 * 120e6) / (2670.0 * 3464.0**2)
    assert v0 == pytest.approx(0.0778, abs=1e-4)
    assert float(hypo.v_1[0]) == pytest.approx(v0, rel=1e-9)
    assert float(hypo.tau_1[0]) == pytest.approx(0.677 * 120e6, rel=1e-12)
    mdsbi = np.loadtxt(REFERENCE / "faultst000dp075.txt", skiprows=2, max_rows=1)
    assert (float(hypo.v_1[0]), float(hypo.tau_1[0]) / 1e6) == pytest.approx((mdsbi[2], mdsbi[3]), rel=1e-4)
    assert float(hypo.v_1.max()) > 10 * v0 and float(hypo.delta_1[-1]) > 0.5      # it grew
    assert float(ds.rupture_time.sel(x1=hypo.x1, x3=hypo.x3)) < 2 * sc.dt
    assert float(np.max(np.abs(st.sel(station="faultst-075dp075").v_1))) < 1e-3
    surface = st.sel(station="faultst000dp000")
    assert float(surface.x3) == 0.0
    assert np.all(surface.v_3.values == 0.0) and np.all(surface.delta_3.values == 0.0)
    assert np.all(ds.tau_3.values[:, :, 0] == 0.0)
