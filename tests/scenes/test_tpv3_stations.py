"""scenes.tpv3 records the MDSBI reference's two stations where the reference took them
(shared/reference/tpv3_mdsbi/README.md): faultst075dp000 7.5 km along strike and
faultst000dp-030 3.0 km along dip from the hypocentre, with its mirror image faultst000dp030."""
import pytest

from cracklab import scenes


@pytest.mark.parametrize("dx", [100.0, 300.0])
def test_tpv3_reference_stations_relative_to_the_hypocentre(dx):
    sc = scenes.tpv3(dx=dx, t_end=0.1)
    g = sc.grid
    xc, zc = g.x1[g.n1 // 2], g.x3[g.n3 // 2]          # the hypocentre, centre of the patch
    st = sc.record.stations
    rel = {name: (x1 - xc, x3 - zc) for name, (x1, x3) in st.items()}
    assert rel["faultst000dp-030"] == pytest.approx((0.0, -3000.0), abs=1e-6)
    assert rel["faultst000dp030"] == pytest.approx((0.0, 3000.0), abs=1e-6)
    assert rel["faultst075dp000"] == pytest.approx((7500.0, 0.0), abs=1e-6)
    assert rel["faultst000dp000"] == pytest.approx((0.0, 0.0), abs=1e-6)
    # the names give the offsets in units of 100 m, dip along x3
    assert scenes.tpv3_station_name(0, -30) == "faultst000dp-030"
    # both lie on grid nodes inside the fault, so the station series is a node's
    for name in ("faultst000dp-030", "faultst000dp030"):
        x1, x3 = st[name]
        i, k = round(x1 / g.dx1), round(x3 / g.dx3)
        assert (g.x1[i], g.x3[k]) == pytest.approx((x1, x3), abs=1e-6)
        assert not sc.law.bonded[i, k]
