"""Fast checks of the helpers of the paper study (studies/paper/): arrival marking,
error tables, precision-factor extraction, stability limits, the static references
of the elliptical crack. No 512 x 512 run here."""
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))

from paper import ellipse_part, lamb_part, modal_part  # noqa: E402

from cracklab import Grid, Material  # noqa: E402
from cracklab.analysis.exact import lamb_opening, penny_opening  # noqa: E402
from cracklab.analysis.modal import long_time_amplitude, long_time_period, precision_factor  # noqa: E402
from cracklab.scenes import ellipse_mask  # noqa: E402

UNIT = Material(mu=1.0, cs=1.0, nu=0.25)


# ----------------------------------------------------------------------------- Lamb
def test_arrival_times_are_distance_over_wave_speeds():
    arr = lamb_part.arrival_times(0.125, UNIT)
    assert arr["P"] == pytest.approx(0.125 / math.sqrt(3.0), rel=1e-12)
    assert arr["S"] == pytest.approx(0.125, rel=1e-12)
    # c_R / c_s = 0.9194017 at nu = 1/4 (Appendix B)
    assert arr["R"] == pytest.approx(0.125 / 0.9194017, rel=1e-6)
    assert arr["P"] < arr["S"] < arr["R"]
    with pytest.raises(ValueError):
        lamb_part.arrival_times(0.0, UNIT)


def test_image_arrival_is_the_nearest_periodic_copy_of_the_load():
    cd = math.sqrt(3.0)
    # station 1/8 to the right of the load: the image one period to the right is 7/8 away
    assert lamb_part.image_arrival((0.625, 0.5), (0.5, 0.5), 1.0, cd) == pytest.approx(0.875 / cd)
    # station on the diagonal
    t = lamb_part.image_arrival((0.6, 0.6), (0.5, 0.5), 1.0, cd)
    assert t == pytest.approx(math.hypot(0.9, 0.1) / cd)
    # rectangular period
    t = lamb_part.image_arrival((0.5, 0.3), (0.5, 0.2), (1.0, 0.5), 1.0)
    assert t == pytest.approx(0.4)


def test_window_mask_leaves_out_the_arrivals():
    tau = np.linspace(0, 2, 201)
    keep = lamb_part.window_mask(tau, {"P": 0.5, "R": 1.0}, {"P": 0.05, "R": 0.1})
    assert not keep[np.abs(tau - 0.5) <= 0.05 - 1e-9].any()
    assert not keep[np.abs(tau - 1.0) <= 0.1 - 1e-9].any()
    assert keep[np.abs(tau - 1.5) < 0.2].all()


def _pekeris_series(dtau=0.004, tau_end=3.0):
    tau = np.arange(0.0, tau_end, dtau)
    r = 1.0
    exact = lamb_opening(r, tau * r)
    static = 3.0 / (4.0 * math.pi * r)
    arr = {"P": 1 / math.sqrt(3), "S": 1.0, "R": math.sqrt(3 + math.sqrt(3)) / 2}
    widths = {"P": 0.02, "S": 0.02, "R": 0.04}
    return tau, exact, static, arr, widths


def test_compare_history_is_zero_on_the_exact_solution():
    tau, exact, static, arr, widths = _pekeris_series()
    e = lamb_part.compare_history(tau, exact, exact, static, arr, widths, tau_end=tau[-1])
    for key in ("pre_P", "P_S", "S_R", "after_R", "late_mean", "late_max", "rms"):
        assert e[key] == pytest.approx(0.0, abs=1e-12), key
    # the exact opening jumps from very negative to the static value at tau_R: the
    # measured arrival is within one sample of it
    assert abs(e["tau_R_num"] - arr["R"]) < 0.004
    assert e["overshoot"] == pytest.approx(0.0, abs=1e-12)
    assert e["min_value"] < -2.0


def test_compare_history_sees_an_error_and_a_delay():
    tau, exact, static, arr, widths = _pekeris_series()
    num = exact.copy()
    late = tau > arr["R"] + widths["R"]
    num[late] *= 1.02
    e = lamb_part.compare_history(tau, num, exact, static, arr, widths, tau_end=tau[-1])
    assert e["after_R"] == pytest.approx(0.02, rel=1e-9)
    assert e["late_mean"] == pytest.approx(0.02, rel=1e-9)
    assert e["overshoot"] == pytest.approx(0.02, rel=1e-9)
    assert e["P_S"] == pytest.approx(0.0, abs=1e-12)
    # a delayed copy of the exact history: the Rayleigh arrival moves with it
    shift = 0.02
    delayed = lamb_opening(1.0, np.clip(tau - shift, 0, None))
    e = lamb_part.compare_history(tau, delayed, exact, static, arr, widths, tau_end=tau[-1])
    assert abs(e["tau_R_num"] - (arr["R"] + shift)) < 0.005
    # the precursor before P is counted
    noisy = exact.copy()
    noisy[tau < 0.3] += 0.01 * static * np.sin(50 * tau[tau < 0.3])
    e = lamb_part.compare_history(tau, noisy, exact, static, arr, widths, tau_end=tau[-1])
    assert e["pre_P"] == pytest.approx(0.01, rel=0.01)


# ----------------------------------------------------------------------------- modal
def _synthetic(amplitude_ratio, decay=0.0, gamma=0.01, periods=11):
    """A sinusoid at the Rayleigh frequency of the long-time form, as modal_response returns."""
    P = long_time_period("I", 0.25)
    T = np.arange(0.0, periods * P, gamma)
    A = amplitude_ratio * long_time_amplitude("I", 0.25)
    r = A * np.exp(-decay * T) * np.sin(2 * np.pi * T / P)
    return xr.DataArray(r, dims=("T",), coords={"T": T}, attrs={"mode": "I", "nu": 0.25}), P


@pytest.mark.parametrize("ratio", [0.3, 1.0, 2.5])
def test_precision_factor_of_a_sinusoid_is_its_amplitude_ratio(ratio):
    r, _ = _synthetic(ratio)
    assert precision_factor(r, 0.25, period=10) == pytest.approx(ratio, rel=1e-4)
    assert precision_factor(r, 0.25, period=10, method="fit") == pytest.approx(ratio, rel=1e-6)


def test_precision_factor_of_a_decaying_sinusoid():
    k = 0.01
    r, P = _synthetic(1.0, decay=k)
    # largest |r| in the 10th period: at the first crest of that period (the decay is slow)
    T = r["T"].values
    win = (T >= 9 * P) & (T <= 10 * P)
    expected = np.abs(r.values[win]).max() / long_time_amplitude("I", 0.25)
    assert precision_factor(r, 0.25, period=10) == pytest.approx(expected, rel=1e-12)
    # close to the envelope a quarter period into the window
    assert expected == pytest.approx(math.exp(-k * 9.25 * P), rel=2e-3)
    # and clearly below 1: the extraction sees the damping
    assert expected < 0.55


def test_study_precision_factors_of_the_paper_scheme():
    # displacement / trapezoid / explicit at small gamma: close to the exact response
    pf10, pf50 = modal_part.precision_factors(("displacement", "trapezoid", "explicit"), 0.1)
    assert 0.9 < pf10 < 1.1
    assert 0.85 < pf50 < 1.1
    # an unstable scheme reads far above 1
    pf10, = modal_part.precision_factors(("velocity", "discretized", "explicit"), 1.0, periods=(10,))
    assert pf10 > 10


def test_velocity_scheme_with_tabulated_Z_damps_like_the_displacement_scheme():
    # with Z = Z(0) - cumulative trapezoid of C the velocity scheme damps (the exact-Z one grows)
    ct10, ct50 = modal_part.cumtrapz_precision_factors(1.0)
    d10, d50 = modal_part.precision_factors(("displacement", "trapezoid", "explicit"), 1.0)
    v10, v50 = modal_part.precision_factors(("velocity", "discretized", "semi-implicit"), 1.0)
    assert ct50 < ct10 < 1.0
    assert abs(ct10 - d10) < 0.1
    assert v50 > v10 > 1.0


def test_stable_limit_and_first_overflow():
    g = np.round(np.arange(0.1, 1.01, 0.1), 10)
    rates = np.array([-1e-3, -1e-4, 2e-6, 3e-4, -1e-3, 6e-4, math.inf, math.inf, -1, -1])
    assert modal_part.stable_limit(g, rates, 1e-5) == pytest.approx(0.3)
    assert modal_part.stable_limit(g, rates, 5e-4) == pytest.approx(0.5)
    assert modal_part.stable_limit(g, np.full(10, math.inf), 5e-4) == 0.0
    assert modal_part.stable_limit(g, np.full(10, math.nan), 5e-4) == 0.0
    assert modal_part.first_overflow(g, rates) == pytest.approx(0.7)
    assert modal_part.first_overflow(g, np.zeros(10)) == math.inf


def test_eq52_on_a_square_grid():
    assert modal_part.gamma_max_of_beta(0.5) == pytest.approx(math.pi * 0.5 * math.sqrt(2))
    assert modal_part.beta_of_gamma_max(modal_part.gamma_max_of_beta(0.37)) == pytest.approx(0.37)
    # the paper: gamma of about 2.3 is beta of about 0.5
    assert modal_part.beta_of_gamma_max(2.3) == pytest.approx(0.518, abs=1e-3)


# ----------------------------------------------------------------------------- ellipse
def test_compare_profile_is_zero_on_the_exact_solution_and_sees_a_scaling():
    x = np.linspace(-0.3, 0.3, 241)
    ref = ellipse_part.green_sneddon(x + 0.5, 0.5)
    e = ellipse_part.compare_profile(x, ref, ref, ellipse_part.A)
    assert all(v == pytest.approx(0.0, abs=1e-14) for v in e.values())
    e = ellipse_part.compare_profile(x, 1.03 * ref, ref, ellipse_part.A)
    assert e["centre"] == pytest.approx(0.03)
    assert e["max_all"] == pytest.approx(0.03)
    assert e["max_inner"] == pytest.approx(0.03)
    assert 0 < e["rms"] < 0.03
    # an error only at the tips counts in "all" but not in "inner"
    tip = np.abs(x) > 0.95 * ellipse_part.A
    bad = ref + np.where(tip & (np.abs(x) <= ellipse_part.A), 0.01, 0.0)
    e = ellipse_part.compare_profile(x, bad, ref, ellipse_part.A)
    assert e["max_inner"] == 0.0
    assert e["max_all"] == pytest.approx(0.01 / ref[120])


def test_green_sneddon_profile_and_centre():
    from scipy.special import ellipe

    d0 = ellipse_part.green_sneddon(0.5, 0.5)
    # 2 (1 - nu) p b / (mu E(k)), k^2 = 1 - (b/a)^2
    assert d0 == pytest.approx(2 * 0.75 * 0.125 / ellipe(1 - 0.25))
    assert ellipse_part.green_sneddon(0.5 + 0.25, 0.5) == 0.0
    assert ellipse_part.green_sneddon(0.5 + 0.125, 0.5) == pytest.approx(d0 * math.sqrt(0.75))


def test_static_periodic_solves_the_discrete_problem_and_is_close_to_penny():
    n, c = 128, 0.1
    grid = Grid(n1=n, n3=n, L1=1.0, L3=1.0)
    mask = ellipse_mask(grid, c, c)
    d, iters, resid = ellipse_part.static_periodic(mask)
    assert resid < 1e-9 and iters < 200
    assert np.all(d[~mask] == 0.0)
    # the traction it implies vanishes on the crack: K d = p there
    k = 2 * np.pi * np.fft.fftfreq(n, d=1 / n)
    m = 2 * np.pi * np.fft.rfftfreq(n, d=1 / n)
    K = np.hypot(k[:, None], m[None, :]) / (2 * 0.75)
    traction = np.fft.irfft2(K * np.fft.rfft2(d), s=d.shape)
    assert np.max(np.abs(traction[mask] - 1.0)) < 1e-8
    # symmetric, and within 3% of the penny-shaped crack (periodic images, node mask)
    assert d[n // 2 + 5, n // 2] == pytest.approx(d[n // 2 - 5, n // 2], rel=1e-8)
    assert d[n // 2, n // 2 + 5] == pytest.approx(d[n // 2 + 5, n // 2], rel=1e-8)
    centre = d[n // 2, n // 2]
    assert centre == pytest.approx(penny_opening(0.0, c, 1.0, 1.0, 0.25), rel=0.03)


def test_overshoot_and_uniform_opening():
    t = np.linspace(0, 10, 1001)
    s = 2.0
    centre = s * (1 - np.exp(-0.3 * t) * np.cos(2 * t))
    os_, t_max = ellipse_part.overshoot(t, centre, s)
    i = int(np.argmax(centre))
    assert os_ == pytest.approx(centre[i] / s - 1)
    assert t_max == pytest.approx(t[i])
    # the first crest, near 2 t = pi: 1 + exp(-0.3 pi / 2) = 1.62
    assert 0.55 < os_ < 0.65
    # plane-wave opening of the q = 0 mode: 2 p c_s t / (a mu), a = sqrt 3 at nu = 1/4
    assert ellipse_part.uniform_opening(0.3) == pytest.approx(2 * 0.3 / math.sqrt(3))
