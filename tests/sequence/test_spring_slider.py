"""Verification 1 of the sequences (issue 35): the quasi-dynamic run of a uniform fault
loaded through a spring is the spring-slider ODE; its events against an independent Radau
solution within 1e-6 relative, and the error shrinking with the step's tolerance."""
import numpy as np
import pytest

from spring_slider import reference, scene

T_END = 1.2e9        # three events


@pytest.fixture(scope="module")
def exact():
    return reference(T_END)


def test_events_match_the_ode_within_1e_6(exact):
    from cracklab import analysis, simulate

    starts, peaks = exact
    ev = analysis.events(simulate(scene(T_END)))
    assert ev.sizes["event"] == len(starts) == 3
    np.testing.assert_allclose(ev.t_start.values, starts, rtol=1e-6)
    np.testing.assert_allclose(ev.peak_slip_rate.values, peaks[:, 1], rtol=1e-6)
    np.testing.assert_allclose(ev.t_peak.values, peaks[:, 0], rtol=1e-6)
    # the uniform fault slips as a whole: mean slip = slip at the station's node, area = the line
    assert np.all(ev.rupture_area.values == 4.0)


def test_the_error_follows_the_tolerance(exact):
    """The step control's order: the event-time error at tolerance 1e-5, 1e-6, 1e-7 falls
    by about a decade per decade (a local error per unit step held at the tolerance)."""
    from cracklab import analysis, simulate

    starts, _ = exact
    errors = []
    for tol in (1e-5, 1e-6, 1e-7):
        ev = analysis.events(simulate(scene(T_END, tolerance=tol)))
        errors.append(np.max(np.abs(ev.t_start.values / starts - 1)))
    slopes = -np.diff(np.log10(errors))
    assert np.all(slopes > 0.5), errors
    assert errors[-1] < 1e-7, errors


def test_the_third_order_pair_and_the_slip_law_also_match():
    from cracklab import analysis, simulate

    starts, peaks = reference(6e8, evolution="slip")
    ev = analysis.events(simulate(scene(6e8, tolerance=1e-9, pair="bogacki_shampine", evolution="slip")))
    assert ev.sizes["event"] == len(starts) >= 1
    np.testing.assert_allclose(ev.t_start.values, starts, rtol=1e-6)
    np.testing.assert_allclose(ev.peak_slip_rate.values, peaks[:, 1], rtol=1e-5)


def test_the_fully_dynamic_response_is_the_same_ode(exact):
    """The uniform fault has only the q = 0 mode, which has no wave-mediated history: the
    fully dynamic run (predictor-corrector, history exact at a variable step) is the same
    ODE. Events within 1e-6 relative at tolerance 1e-6 (1e-7 here), and the error falls
    with it (order 2: about a decade per decade of tolerance); both evolution laws."""
    import dataclasses

    from cracklab import analysis, simulate

    starts, peaks = exact
    errors = []
    for tol in (1e-5, 1e-6):
        sc = scene(T_END, tolerance=tol)
        sc = sc.replace(sequence=dataclasses.replace(sc.sequence, response="dynamic"))
        ev = analysis.events(simulate(sc))
        assert ev.sizes["event"] == len(starts) == 3
        errors.append(np.max(np.abs(ev.t_start.values / starts - 1)))
    np.testing.assert_allclose(ev.t_start.values, starts, rtol=1e-6)
    np.testing.assert_allclose(ev.peak_slip_rate.values, peaks[:, 1], rtol=1e-6)
    np.testing.assert_allclose(ev.t_peak.values, peaks[:, 0], rtol=1e-6)
    assert errors[1] < errors[0] / 5, errors
    # the slip law too (its dpsi/dt from the same compiled pass)
    starts, peaks = reference(6e8, evolution="slip")
    sc = scene(6e8, tolerance=1e-6, evolution="slip")
    ev = analysis.events(simulate(sc.replace(sequence=dataclasses.replace(sc.sequence, response="dynamic"))))
    assert ev.sizes["event"] == len(starts) >= 1
    np.testing.assert_allclose(ev.t_start.values, starts, rtol=1e-6)
    np.testing.assert_allclose(ev.peak_slip_rate.values, peaks[:, 1], rtol=1e-6)


def test_the_dynamic_response_steps_by_the_pair_while_the_plane_is_slow(exact):
    """Between events the fully dynamic run steps by the order-5 pair (Sequence.slow_rate):
    the same events as the ODE within 1e-6 at tolerance 1e-6, with and without the pair in
    the slow phases, and fewer steps with the pair (61 521 against 105 001 here: this
    fault's events, stepped by the predictor-corrector either way, take most of them)."""
    import dataclasses

    from cracklab import analysis, simulate

    starts, peaks = exact
    steps = {}
    for slow in (None, 0.0):
        sc = scene(T_END, tolerance=1e-6)
        sc = sc.replace(sequence=dataclasses.replace(sc.sequence, response="dynamic", slow_rate=slow))
        ds = simulate(sc)
        ev = analysis.events(ds)
        assert ev.sizes["event"] == len(starts) == 3
        np.testing.assert_allclose(ev.t_start.values, starts, rtol=1e-6)
        np.testing.assert_allclose(ev.peak_slip_rate.values, peaks[:, 1], rtol=1e-6)
        steps[slow] = int(ds.attrs["accepted_steps"])
    assert steps[None] * 1.5 < steps[0.0], steps
