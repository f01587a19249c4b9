"""The SCEC TPV101 and TPV103 builders (rate-and-state friction, whole space)."""
import numpy as np
import pytest

import cracklab
from cracklab import scenes
from cracklab.laws import RateState
from cracklab.model.scene_io import scenes_equal

NAMES = ["faultst-120dp030", "faultst000dp030", "faultst120dp030", "faultst-090dp075", "faultst000dp075",
         "faultst090dp075", "faultst-120dp120", "faultst000dp120", "faultst120dp120"]


@pytest.mark.parametrize("build", [scenes.tpv101, scenes.tpv103])
def test_the_builders_validate_and_have_scec_stations(build):
    sc = build(dx=1000.0)
    assert build.__name__ in scenes.BUILDERS and sc.name == build.__name__
    assert sc.grid.shape == (72, 36) and sc.grid.L1 == 72000.0 and sc.grid.L3 == 36000.0
    assert sc.components == (1, 3) and sc.formulation == "product" and sc.beta == 0.25
    assert sc.material.cs == 3464.0 and abs(sc.material.cd - 6000.0) < 0.2 and sc.material.rho == pytest.approx(2670.0)
    xc, zc = sc.grid.x1[36], sc.grid.x3[18]
    assert sorted(sc.record.stations) == sorted(NAMES)
    assert sc.record.stations["faultst000dp075"] == (xc, zc)                  # the hypocentre
    assert sc.record.stations["faultst000dp030"] == (xc, zc - 4500.0)         # 3 km below the top
    assert sc.record.stations["faultst090dp075"] == (xc + 9000.0, zc)
    assert sc.record.stations["faultst-120dp120"] == (xc - 12000.0, zc + 4500.0)
    load = sc.loading
    assert (load.nucleation_radius, load.nucleation_time, load.nucleation_x1, load.nucleation_x3) == \
        (3000.0, 1.0, xc, zc)
    assert isinstance(sc.law, RateState) and sc.law.sigma_n == 120e6 and sc.law.V0 == 1e-6 and sc.law.f0 == 0.6
    a = np.asarray(sc.law.a)
    i, k = np.meshgrid(np.arange(72), np.arange(36), indexing="ij")
    inside = (np.abs(sc.grid.x1[i] - xc) <= 15000) & (np.abs(sc.grid.x3[k] - zc) <= 7500)
    outside = (np.abs(sc.grid.x1[i] - xc) >= 18000) | (np.abs(sc.grid.x3[k] - zc) >= 10500)
    if build is scenes.tpv101:
        assert sc.law.evolution == "ageing" and (sc.law.b, sc.law.L, sc.law.V_ini) == (0.012, 0.02, 1e-12)
        assert load.tau0_1 == 75e6 and load.nucleation_dtau_1 == 25e6 and sc.t_end == 15.0
        lo, hi = 0.008, 0.016
    else:
        assert sc.law.evolution == "slip" and (sc.law.b, sc.law.L, sc.law.V_ini, sc.law.f_w) == (0.014, 0.4, 1e-16, 0.2)
        assert load.tau0_1 == 40e6 and load.nucleation_dtau_1 == 45e6 and sc.t_end == 12.0
        lo, hi = 0.01, 0.02
        Vw = np.asarray(sc.law.V_w)
        assert np.all(Vw[inside] == 0.1) and np.all(Vw[outside] == 1.0)
    assert np.all(a[inside] == lo) and np.all(a[outside] == hi) and np.all((a >= lo) & (a <= hi))
    assert scenes_equal(cracklab.Scene.from_toml(sc.to_toml()), sc)


def test_tpv101_nucleates_at_the_hypocentre_on_a_coarse_grid():
    """2 km cells, 3 s: the slip rate at the hypocentre rises from V_ini = 1e-12 m/s past
    1 m/s once the nucleation stress is on, and the run stays finite."""
    sc = scenes.tpv101(dx=2000.0, t_end=3.0)
    st = cracklab.stations(cracklab.simulate(sc))
    v = st["v_1"].sel(station="faultst000dp075").values
    assert v[0] == pytest.approx(1e-12, rel=1e-9) and v.max() > 1.0 and np.all(np.isfinite(v))
    assert np.all(np.abs(st["v_1"].sel(station="faultst120dp120").values) < 1e-6)   # not there yet


# ---------------------------------------------------------------------------- TPV102, TPV104: below a free surface
@pytest.mark.parametrize("build, twin", [(scenes.tpv102, scenes.tpv101), (scenes.tpv104, scenes.tpv103)])
def test_the_half_space_builders_geometry_parameters_and_stations(build, twin):
    sc, ws = build(dx=500.0), twin(dx=500.0)
    g = sc.grid
    assert build.__name__ in scenes.BUILDERS and sc.name == build.__name__
    assert g.free_surface and (g.n1, g.n3) == (144, 72) and g.shape == (144, 73)
    assert (g.L1, g.L3) == (72000.0, 36000.0) and g.x3[0] == 0.0 and g.x3[-1] == 36000.0
    assert "free_surface = true" in sc.to_toml()
    xc = g.x1[72]
    # the law, load and time stepping are the whole-space problem's, the fields on the half plane
    assert (sc.law.evolution, sc.law.b, sc.law.L, sc.law.V_ini, sc.law.f_w, sc.law.sigma_n) == \
        (ws.law.evolution, ws.law.b, ws.law.L, ws.law.V_ini, ws.law.f_w, ws.law.sigma_n)
    assert (sc.loading.tau0_1, sc.loading.nucleation_dtau_1, sc.t_end, sc.beta) == \
        (ws.loading.tau0_1, ws.loading.nucleation_dtau_1, ws.t_end, ws.beta)
    load = sc.loading
    assert (load.nucleation_radius, load.nucleation_time, load.nucleation_x1, load.nucleation_x3) == \
        (3000.0, 1.0, xc, 7500.0)                        # the hypocentre 7.5 km below the surface
    # stations by SCEC's names at dp x 100 m depth, every one below the surface
    assert sorted(sc.record.stations) == sorted(NAMES)
    for name, (x1, depth) in sc.record.stations.items():
        st, dp = int(name[7:-5]), int(name[-3:])
        assert (x1, depth) == (xc + 100.0 * st, 100.0 * dp) and depth > 0
    nodes = sc.record.station_nodes(g)
    assert nodes["faultst000dp075"] == (72, 15) and nodes["faultst000dp030"] == (72, 6)
    assert nodes["faultst-120dp120"] == (72 - 24, 24)
    # the velocity-weakening box reaches the surface; strengthening beyond 18 km depth and 18 km along strike
    a = np.asarray(sc.law.a)
    lo = 0.008 if build is scenes.tpv102 else 0.01
    depth = g.x3[None, :]
    strike = np.abs(g.x1 - xc)[:, None]
    inside = (strike <= 15000) & (depth <= 15000)
    outside = (strike >= 18000) | (depth >= 18000)
    assert a.shape == g.shape and np.all(a[inside] == lo) and np.all(a[outside] == 2 * lo)
    assert np.all(a[strike[:, 0] <= 15000, 0] == lo)                          # on the surface
    mid = a[72, (g.x3 > 15000) & (g.x3 < 18000)]
    assert np.all((mid > lo) & (mid < 2 * lo)) and np.all(np.diff(mid) > 0)  # the transition below
    if build is scenes.tpv104:
        Vw = np.asarray(sc.law.V_w)
        assert np.all(Vw[inside] == 0.1) and np.all(Vw[outside] == 1.0)
    assert scenes_equal(cracklab.Scene.from_toml(sc.to_toml()), sc)


def test_the_half_space_builders_need_room_below_the_fault():
    with pytest.raises(cracklab.InputError, match="domain"):
        scenes.tpv102(dx=500.0, domain=(72000.0, 15000.0))
    with pytest.raises(cracklab.InputError, match="dx"):
        scenes.tpv104(dx=-1.0)


@pytest.mark.parametrize("build", [scenes.tpv102, scenes.tpv104])
def test_a_coarse_half_space_run_nucleates(build):
    """2 km cells, 3 s: the slip rate at the hypocentre (7.5 km deep) rises from V_ini past
    1 m/s once the nucleation stress is on; the far stations have not moved; finite throughout."""
    sc = build(dx=2000.0, t_end=3.0)
    st = cracklab.stations(cracklab.simulate(sc))
    v = st["v_1"].sel(station="faultst000dp075").values
    assert v[0] == pytest.approx(sc.law.V_ini, rel=1e-6) and v.max() > 1.0
    assert all(np.all(np.isfinite(st[f].values)) for f in ("v_1", "v_3", "delta_1", "tau_1"))
    assert np.all(np.abs(st["v_1"].sel(station="faultst120dp120").values) < 1e-6)
