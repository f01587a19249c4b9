"""What a user meets first in the benchmark builders: their default stations lie on nodes
of the fault that slip, and a builder's spacing is refused or rounded in the builder's own
terms (the argument dx, the domain it asked for), not the grid's."""
import re
import warnings

import numpy as np
import pytest

from cracklab import InputError, Record, scenes
from cracklab.scenes import scec

SLIP_WEAKENING = [scenes.tpv3, scenes.tpv5, scenes.tpv6]
RATE_STATE = [scenes.tpv101, scenes.tpv102, scenes.tpv103, scenes.tpv104]


def offsets(name):
    """(strike, dip or depth) in m from a SCEC station name, read independently of the builder."""
    s, d = re.fullmatch(r"faultst(-?\d+)dp(-?\d+)", name).groups()
    return 100.0 * int(s), 100.0 * int(d)


@pytest.mark.parametrize("build", SLIP_WEAKENING)
@pytest.mark.parametrize("dx", [100.0, 400.0, 1000.0])
def test_default_stations_lie_on_nodes_that_slip(build, dx):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sc = build(dx=dx, t_end=0.1)
    g, bonded = sc.grid, np.asarray(sc.law.bonded)
    assert sc.record.stations
    for name, node in sc.record.station_nodes(g).items():
        assert not bonded[node], (name, node)


def test_tpv3_stations_are_inside_the_fault_and_keep_the_reference_ones():
    sc = scenes.tpv3(dx=100.0, t_end=0.1)
    names = set(sc.record.stations)
    for name in names:   # strike and dip from the hypocentre: strictly inside the 30 km x 15 km fault
        s, d = offsets(name)
        assert abs(s) < 15000.0 and abs(d) < 7500.0, name
    assert {"faultst075dp000", "faultst000dp-030", "faultst000dp030", "faultst000dp000"} <= names
    # the fault's edges, 7.5 km along dip, are bonded: no default station there
    assert not names & {"faultst000dp075", "faultst000dp-075", "faultst075dp-075"}


@pytest.mark.parametrize("build", RATE_STATE)
def test_rate_state_stations_lie_in_the_velocity_weakening_fault(build):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sc = build(dx=1000.0)
    g = sc.grid
    xc = g.x1[g.n1 // 2]
    assert len(sc.record.stations) == 9
    for name, (i, k) in sc.record.station_nodes(g).items():
        s, depth = offsets(name)
        assert abs(g.x1[i] - xc) <= 15000.0 and 0.0 <= depth <= 15000.0, name


def test_a_default_station_off_the_fault_is_left_out_with_a_warning(monkeypatch):
    """A station whose node is bonded at the chosen grid would record zero at every step:
    the builder leaves it out and says which, where and on what grid."""
    monkeypatch.setattr(scec, "TPV3_STATIONS", scec.TPV3_STATIONS + [(0, 75), (160, 0)])
    with pytest.warns(scenes.BuilderWarning) as record:
        sc = scenes.tpv3(dx=400.0, t_end=0.1)
    text = " ".join(str(w.message) for w in record)
    assert "faultst000dp075" in text and "faultst160dp000" in text and "120 x 60" in text and "400" in text
    assert "faultst000dp075" not in sc.record.stations and "faultst160dp000" not in sc.record.stations
    assert "faultst075dp000" in sc.record.stations
    # a record the user gives is taken as given
    mine = scenes.tpv3(dx=400.0, t_end=0.1, record=Record(fields=(), stations={"edge": (24000.0, 19500.0)}))
    assert list(mine.record.stations) == ["edge"]


@pytest.mark.parametrize("build", SLIP_WEAKENING + RATE_STATE)
@pytest.mark.parametrize("dx", [-1.0, 0.0, float("nan"), "wide"])
def test_a_bad_spacing_names_the_builders_argument(build, dx):
    with pytest.raises(InputError) as err:
        build(dx=dx, t_end=0.1)
    assert err.value.field == "dx", str(err.value)
    assert build.__name__ in str(err.value) and "> 0" in str(err.value) and "e.g. dx = " in str(err.value)


@pytest.mark.parametrize("build, dx, nearest", [(scenes.tpv101, 5000.0, (4500.0, 6000.0)),
                                                (scenes.tpv102, 5000.0, (4500.0, 6000.0)),
                                                (scenes.tpv3, 7000.0, (4000.0, None)),
                                                (scenes.tpv5, 1e5, (6000.0, None)),
                                                (scenes.tpv6, 4500.0, (4000.0, 5000.0))])
def test_a_spacing_that_gives_no_fast_grid_is_refused_with_the_nearest_ones(build, dx, nearest):
    with pytest.raises(InputError) as err:
        build(dx=dx, t_end=0.1)
    text = str(err.value)
    assert err.value.field == "dx" and "grid." not in text and build.__name__ in text
    assert ("even fast FFT size" in text or "too coarse" in text) and "nearest accepted" in text
    offered = [float(v) for v in re.findall(r"dx = ([0-9.e+]+) \(", text.split("nearest accepted")[1])]
    assert offered and nearest[0] in offered and (nearest[1] is None or nearest[1] in offered)
    for d in offered:   # each spacing offered builds, without rounding the domain
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            sc = build(dx=d, t_end=0.1)
        assert sc.grid.dx1 == pytest.approx(d, rel=1e-12)


@pytest.mark.parametrize("build, domain", [(scenes.tpv3, (48000.0, 24000.0)), (scenes.tpv5, (48000.0, 24000.0)),
                                           (scenes.tpv101, (72000.0, 36000.0))])
def test_a_spacing_that_does_not_divide_the_domain_says_it_rounds_it(build, domain):
    with pytest.warns(scenes.BuilderWarning) as record:
        sc = build(dx=333.0, t_end=0.1)
    L1, L3 = round(domain[0] / 333.0) * 333.0, round(domain[1] / 333.0) * 333.0
    assert (sc.grid.L1, sc.grid.L3) == pytest.approx((L1, L3))
    text = str(record[0].message)
    assert f"{domain[0]:g} x {domain[1]:g}" in text and f"{L1:g} x {L3:g}" in text and build.__name__ in text


@pytest.mark.parametrize("build", SLIP_WEAKENING + RATE_STATE)
def test_the_default_spacing_divides_the_domain_without_a_word(build):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sc = build(t_end=0.05)
    assert sc.grid.dx1 == 100.0 and sc.grid.dx3 == 100.0


def test_a_domain_that_cannot_hold_the_fault_is_named():
    for build, domain in ((scenes.tpv3, (30000.0, 24000.0)), (scenes.tpv3, (48000.0, 15000.0)),
                          (scenes.tpv102, (72000.0, 12000.0))):
        with pytest.raises(InputError) as err:
            build(dx=1000.0, t_end=0.1, domain=domain)
        assert err.value.field == "domain", domain


@pytest.mark.parametrize("make, field", [(lambda: scenes.lamb(n=22, t_end=0.1), "n"),
                                         (lambda: scenes.elliptical_crack(n=-4, a=0.2, b=0.1, t_end=0.1), "n"),
                                         (lambda: scenes.periodic_cracks(n=66, c=0.1, t_end=0.1), "n"),
                                         (lambda: scenes.kostrov(n=64, speed=0.5, L=-1.0, t_end=0.1), "L")])
def test_the_papers_builders_name_their_own_argument(make, field):
    with pytest.raises(InputError) as err:
        make()
    assert err.value.field == field and "grid" in str(err.value)
