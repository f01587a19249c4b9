"""BP1-FD converges with the step's tolerance (issue 35, point 1): the first event of a
fully dynamic BP1 run is the same at the builder's tolerance 1e-4 and at 1e-6 (its duration,
where the afterslip decays slowly through the event threshold, to 1 %). Its rupture runs at the
dynamic step beta dz / c_s, where h V / L reaches 7 (V = 5.8 m/s); the state is stepped
exactly at the step's mean slip rate (solver/sequence/dynamic.py, ``advance``). A rule on
dpsi/dt there (Heun's, before) gave peak slip rates 3.3 m/s at 1e-5 against 5.8 here.

D_c = 32 mm (four times BP1's) puts about three cells of 400 m in the cohesive zone, so
that a grid of 400 nodes (creep to 80 km) resolves the rupture: about 15 s of CPU (the
slow phases stepped by the order-5 pair, predictor_corrector.py)."""
import numpy as np

YEAR = 365.25 * 86400.0


def test_the_first_event_of_bp1_fd_is_the_same_at_tolerances_1e_4_and_1e_6():
    from cracklab import Record, analysis, simulate
    from cracklab.scenes import bp1

    events = []
    assert bp1(dz=400.0, depth=80e3, dynamic=True).sequence.tolerance == 1e-4
    for tol in (1e-4, 1e-6):
        sc = bp1(dz=400.0, years=340.0, dynamic=True, tolerance=tol, depth=80e3, D_c=0.032,
                 record=Record(fields=("v_3", "delta_3"), region={"x1": (0.0, 80e3)}, stations={}))
        ev = analysis.events(simulate(sc))
        assert ev.sizes["event"] == 1, ev.t_start.values / YEAR
        events.append(ev.isel(event=0))
    a, b = events
    assert 330 * YEAR < float(a.t_start) < 340 * YEAR
    assert abs(float(a.t_start) - float(b.t_start)) < 1e-6 * float(b.t_start)
    # the peak is the largest of the values at the accepted steps: a front crosses a node of
    # 400 m in a few dynamic steps, so its sampled peak moves by a few per cent with the
    # steps taken (5.71, 5.84, 5.76 m/s at 1e-5, 1e-6, 1e-7), not with the solution
    assert abs(float(a.peak_slip_rate) / float(b.peak_slip_rate) - 1) < 0.03
    assert float(b.peak_slip_rate) > 5.0          # full dynamics: above the quasi-dynamic 4.5 m/s of BP1
    np.testing.assert_allclose(float(a.mean_slip), float(b.mean_slip), rtol=1e-3)
    # the event ends where the afterslip decays through 1 mm/s, tens of seconds per 6 % of
    # slip rate, stepped at 1e-4 by the order-5 pair (V < 0.1 sigma a / eta): an error of 0.5 %
    # in V moves the end by 2 s (262.4, 261.0 and 260.4 s at 1e-4, 1e-5 and 1e-6; the
    # predictor-corrector alone, at 1e-4: 260.4 s)
    np.testing.assert_allclose(float(a.duration), float(b.duration), rtol=1e-2)
