"""Fast checks of the helper functions of studies/asperity_front (Freund's equation of
motion, Palmer-Rice zone) and studies/toughness_ensemble (front roughness statistics)."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

STUDIES = Path(__file__).resolve().parents[2] / "studies"


def _load(path, name):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


theory = _load(STUDIES / "asperity_front" / "theory.py", "asperity_front_theory")
rough = _load(STUDIES / "toughness_ensemble" / "roughness.py", "toughness_roughness")


# ---------------------------------------------------------------------------- Freund, Palmer-Rice
def test_rayleigh_speed_nu_quarter():
    # nu = 1/4: c_R / c_s = sqrt(2 - 2/sqrt(3)) = 0.919402 (closed form for a Poisson solid)
    assert theory.rayleigh_speed(0.25) == pytest.approx(np.sqrt(2 - 2 / np.sqrt(3)), rel=1e-9)
    # nu = 0.3: the returned speed is a root of the Rayleigh function
    x = theory.rayleigh_speed(0.3) ** 2
    k2 = (1 - 0.6) / (2 * 0.7)
    assert (2 - x) ** 2 == pytest.approx(4 * np.sqrt(1 - x) * np.sqrt(1 - x * k2), rel=1e-10)
    assert 0.92 < np.sqrt(x) < 0.935


def test_freund_speed_hand_solved():
    # (1 - v/c_R) * 1.25 Gc = Gc  =>  v = 0.2 c_R; for nu = 1/4 that is 0.18388 c_s
    cR = theory.rayleigh_speed(0.25)
    v = float(theory.freund_speed(1.25, cR))
    assert v == pytest.approx(0.2 * cR, rel=1e-12)
    assert v == pytest.approx(0.18388, abs=1e-5)
    # the energy balance holds at the returned speed
    assert float(theory.freund_g(v, cR)) * 1.25 == pytest.approx(1.0, rel=1e-12)
    # G_static = 2 Gc gives half the Rayleigh speed; no growth at or below Gc
    assert float(theory.freund_speed(2.0, 1.0)) == pytest.approx(0.5)
    assert np.all(theory.freund_speed([0.5, 1.0], cR) == 0.0)
    # the ERRATA's "about 0.18 c_s" is not 0.56 c_s
    assert abs(v - 0.56) > 0.3


def test_periodic_factor_limits():
    assert float(theory.periodic_factor(1e-6, 2.0)) == pytest.approx(1.0, abs=1e-10)
    # a / L = 1/4: tan(pi/4) / (pi/4) = 4/pi
    assert float(theory.periodic_factor(0.5, 2.0)) == pytest.approx(4 / np.pi, rel=1e-12)
    # initial symmetric crack of section 4: half length Z/4, period 2Z
    assert float(theory.static_G_ratio(0.5)) == pytest.approx(1.25 * np.tan(np.pi / 8) / (np.pi / 8), rel=1e-12)
    assert float(theory.static_G_ratio(0.5, periodic=False)) == 1.25


def test_A_I_limits_and_value():
    nu = 0.25
    cR = theory.rayleigh_speed(nu)
    assert float(theory.A_I(0.0, nu)) == 1.0
    assert float(theory.A_I(1e-3, nu)) == pytest.approx(1.0, rel=1e-4)   # continuous at v = 0
    assert float(theory.A_I(0.999 * cR, nu)) > 50                        # blows up at c_R
    # hand value at v = 0.5 c_s: alpha_d = sqrt(1 - 0.25/3), alpha_s = sqrt(0.75)
    ad, as_ = np.sqrt(1 - 0.25 / 3), np.sqrt(0.75)
    D = 4 * ad * as_ - (1 + as_**2) ** 2
    assert float(theory.A_I(0.5, nu)) == pytest.approx(0.25 * ad / (0.75 * D), rel=1e-12)
    assert np.all(np.diff(theory.A_I(np.linspace(0.01, 0.9, 50), nu)) > 0)


def test_palmer_rice_zone_formula():
    # R0 = (9 pi / 32) E' Gc / tau_c^2 with E' = 2 mu / (1 - nu)
    R0 = float(theory.palmer_rice_zone(mu=2.0, nu=0.2, Gc=0.03, tau_c=1.5))
    assert R0 == pytest.approx(9 * np.pi / 32 * (2 * 2.0 / 0.8) * 0.03 / 1.5**2, rel=1e-12)
    # in terms of delta_c (Gc = tau_c delta_c / 2): (9 pi / 32) mu delta_c / ((1 - nu) tau_c),
    # the form of cracklab.scenes.cohesive_zone_size; delta_c = 0.0849 gives 0.1 Z
    dc = 0.0849
    assert float(theory.palmer_rice_zone(mu=1.0, nu=0.25, Gc=0.5 * dc, tau_c=1.0)) == \
        pytest.approx(9 * np.pi / 32 * dc / 0.75, rel=1e-12)
    assert float(theory.palmer_rice_zone(mu=1.0, nu=0.25, Gc=0.5 * dc, tau_c=1.0)) == pytest.approx(0.1, abs=1e-4)
    # a running crack has a shorter zone, by 1 / A_I(v)
    Rv = float(theory.palmer_rice_zone(mu=1.0, nu=0.25, Gc=0.05, tau_c=1.0, v=0.6))
    R0 = float(theory.palmer_rice_zone(mu=1.0, nu=0.25, Gc=0.05, tau_c=1.0))
    assert Rv == pytest.approx(R0 / float(theory.A_I(0.6, 0.25)), rel=1e-12)
    assert Rv < R0


def test_semi_infinite_step_K_and_steady_speed():
    # nu = 1/4: K = 2 p sqrt(sqrt(3) t / 2 / pi) / 0.75
    K = float(theory.semi_infinite_step_K(2.0, 0.5, 0.25))
    assert K == pytest.approx(2 * 2.0 * np.sqrt(np.sqrt(3) * 0.5 * 0.5 / np.pi) / 0.75, rel=1e-12)
    assert float(theory.semi_infinite_step_K(1.0, -1.0, 0.25)) == 0.0
    t = np.linspace(0, 2, 81)
    x = 0.25 + 0.6 * t + 1e-3 * np.sin(40 * t)
    v, r = theory.steady_speed(t, x, 0.5, 1.5)
    assert v == pytest.approx(0.6, abs=2e-3)
    assert r < 2e-3
    assert np.isnan(theory.steady_speed(t, x, 5, 6)[0])


# ---------------------------------------------------------------------------- roughness
def test_front_rms_and_spectrum_of_a_sine():
    n, L3 = 128, 1.0
    x3 = np.arange(n) * L3 / n
    A, m = 0.03, 5
    h = 0.7 + A * np.cos(2 * np.pi * m * x3 / L3 + 0.3)
    assert float(rough.front_rms(h)) == pytest.approx(A / np.sqrt(2), rel=1e-12)
    k, P = rough.front_spectrum(h, L3)
    assert k[0] == pytest.approx(2 * np.pi / L3)
    assert int(np.argmax(P)) == m - 1
    assert P[m - 1] == pytest.approx(A**2 / 2, rel=1e-12)
    assert P.sum() == pytest.approx(float(rough.front_rms(h)) ** 2, rel=1e-12)


def test_spectrum_parseval_random_and_nyquist():
    rng = np.random.default_rng(3)
    h = rng.standard_normal((4, 64))                   # 4 fronts, one per row
    k, P = rough.front_spectrum(h, 2.0)
    assert P.shape == (4, 32)
    np.testing.assert_allclose(P.sum(axis=1), rough.front_rms(h) ** 2, rtol=1e-12)
    alt = (-1.0) ** np.arange(64)                      # pure Nyquist mode, rms 1
    assert rough.front_spectrum(alt, 1.0)[1][-1] == pytest.approx(1.0, rel=1e-12)


def test_rms_of_a_random_front_with_known_rms():
    rng = np.random.default_rng(0)
    h = 1.0 + 0.02 * rng.standard_normal((200, 256))
    w = rough.front_rms(h, axis=1)
    assert np.mean(w) == pytest.approx(0.02, rel=0.01)


def test_on_grid_band_and_power_law():
    adv = np.array([0.0, 0.0, 0.1, 0.2, 0.2, 0.4])     # a stalled front repeats its advance
    w = np.array([0.0, 1.0, 2.0, 3.0, 4.0, 6.0])
    g = rough.on_grid(adv, w, np.array([-0.1, 0.0, 0.15, 0.2, 0.3, 0.5]))
    np.testing.assert_allclose(g[1:5], [1.0, 3.0, 4.0, 5.0])   # 0.15: between (0.1, 2) and the last (0.2, 4)
    assert np.isnan(g[0]) and np.isnan(g[5])
    vals = np.arange(1.0, 12.0)[:, None] * np.ones((1, 3))
    vals[0, 2] = np.nan
    m, lo, hi = rough.band(vals)
    assert m[0] == pytest.approx(6.0)
    assert lo[0] == pytest.approx(2.0) and hi[0] == pytest.approx(10.0)
    assert m[2] == pytest.approx(6.5)
    x = np.linspace(0.1, 2, 20)
    p, c = rough.power_law_fit(x, 3.0 * x**0.5)
    assert p == pytest.approx(0.5, rel=1e-10) and c == pytest.approx(3.0, rel=1e-10)
