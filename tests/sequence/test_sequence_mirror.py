"""Sequence.mirror (a free surface of the plane problem, the grid holding the fault and its
image, as scenes.bp1 builds it): the traction is made exactly even before each solve.
Without it the transforms' round-off grows through the events (1e-13 of the slip rate before
the first, 4e-5 after it, the whole slip rate by the second at 200 m), the fault and its
image rupture at different times, and from the third earthquake on BP1's ruptures stop at
depth and start again at the surface; with it BP1's earthquakes stay whole, as uguca's and
as the benchmark's description says (about 5 m/s at the surface in every one)."""
import dataclasses

import numpy as np
import pytest

from cracklab import Record, analysis, simulate
from cracklab.errors import InputError
from cracklab.scenes import bp1

YEAR = 365.25 * 86400.0


def _odd_part(ds, n1):
    v = ds.v_3.values[:, :, 0]
    image = (-np.arange(n1)) % n1
    return float(np.max(np.abs(v - v[:, image])))


def _scene(**kw):
    return bp1(dz=200.0, depth=50e3, record=Record(fields=("v_3",), region={"x1": (0.0, 100e3)}, stations={}), **kw)


def test_the_mirror_keeps_the_slip_rate_exactly_even_through_an_event():
    sc = _scene(years=250.0)
    ds = simulate(sc)
    assert float(ds.max_slip_rate.max()) > 1.0       # the first earthquake (246.9 yr) happened
    assert _odd_part(ds, sc.grid.n1) == 0.0
    off = sc.replace(sequence=dataclasses.replace(sc.sequence, mirror=False))
    assert _odd_part(simulate(off), off.grid.n1) > 0.0   # without it, round-off parts the halves


def test_bp1s_earthquakes_stay_whole_with_the_mirror():
    """Three earthquakes at 200 m, each nucleating at depth (12-15 km) and reaching the surface
    at more than 3.5 m/s (without the mirror the third stops at depth: 0.7 m/s there)."""
    ds = simulate(_scene(years=460.0).replace(record=Record(fields=("v_3",), region={"x1": (0.0, 50e3)},
                                                            stations={})))
    ev = analysis.events(ds).load()
    big = ev.peak_slip_rate.values > 0.1
    assert big.sum() == 3, ev.t_start.values / YEAR
    assert np.all(ev.peak_slip_rate.values[big] > 3.5), ev.peak_slip_rate.values
    assert np.all((ev.hypocentre_x1.values[big] > 12e3) & (ev.hypocentre_x1.values[big] < 15e3))


def test_a_field_that_is_not_even_is_refused_with_its_name():
    sc = _scene(years=10.0)
    a = np.array(np.broadcast_to(sc.law.a, sc.grid.shape))
    a[3, 0] += 1e-4          # node 3 against its image n1 - 3
    with pytest.raises(InputError, match=r"law\.a.*even about x1 = 0.*node \(3, 0\)"):
        sc.replace(law=dataclasses.replace(sc.law, a=a))
