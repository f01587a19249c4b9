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
