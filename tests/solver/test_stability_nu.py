"""Stability limits for every Poisson ratio (cracklab.stability, docs/reference/stability.md) and the
growth detectors of the Stepper (docs/guide/reliability.md, "Numerical faults").

Three checks of the tabulated limits, each against a computation that does not use them:
the single-mode response (cracklab.modal_response) grows just above the measured limit and
not below the limit a scene is held to; full-grid runs of a traction-free plane under a
random load stay bounded for thousands of steps at the limit a scene is held to; and the
same runs forced 2 % past the measured limit stop with a SimulationError.
"""
from __future__ import annotations

import math
import re

import numpy as np
import pytest

import cracklab
from cracklab import Grid, Loading, Material, Numerics, Record, Scene
from cracklab.errors import InputError, SimulationError
from cracklab.laws import TractionFree
from cracklab.analysis.modal import envelope_growth, scheme_response
from cracklab.solver.stability import GROWTH_TOLERANCE, SAFETY, SCHEMES, beta_max, gamma_max

NUS = (0.1, 0.25, 0.3, 0.35, 0.45)
#: the kernel that limits each scheme as a scene uses it: mode I for the displacement and
#: velocity schemes (opening), mode II for the product schemes (shear in 3D)
LIMITING = {"displacement": "I", "velocity": "I", "product": "II", "product2": "II"}
LOAD = {"displacement": (2,), "velocity": (2,), "product": (1, 3), "product2": (1, 3)}


def modal_growth(scheme, mode, gamma, nu, T_end=2000.0):
    """Growth per unit T of the envelope over [T_end/2, T_end] (studies/stability_nu.py's measure)."""
    return envelope_growth(scheme_response(scheme, mode, gamma=gamma, T_end=T_end, nu=nu))


@pytest.mark.parametrize("nu", NUS)
@pytest.mark.parametrize("scheme", sorted(SCHEMES))
def test_the_modal_response_grows_past_the_measured_limit_and_not_within_the_held_one(scheme, nu):
    mode = LIMITING[scheme]
    measured = gamma_max(scheme, mode, nu, measured=True)
    assert gamma_max(scheme, mode, nu) == pytest.approx(SAFETY * measured)
    assert modal_growth(scheme, mode, SAFETY * measured, nu) <= GROWTH_TOLERANCE
    assert modal_growth(scheme, mode, 1.05 * measured, nu) > GROWTH_TOLERANCE


def random_scene(scheme, nu, *, n=16, seed=1):
    """Traction-free plane under a zero-mean random step load on the scheme's components."""
    grid = Grid(n1=n, n3=n, L1=1.0, L3=1.0)
    rng = np.random.default_rng(seed)
    load = Loading(**{f"tau0_{c}": rng.standard_normal(grid.shape) for c in LOAD[scheme]})
    return Scene(material=Material(mu=1.0, cs=1.0, nu=nu), grid=grid, law=TractionFree(), loading=load,
                 t_end=1.0, record=Record(fields=()), numerics=Numerics(formulation=scheme))


def forced(scene, beta, steps):
    """The scene at a beta its validation may refuse, for ``steps`` steps (tests only)."""
    object.__setattr__(scene, "beta", float(beta))
    object.__setattr__(scene, "t_end", steps * scene.dt * (1 - 1e-9))
    assert scene.nsteps == steps
    return scene


def peak_history(scene):
    return np.array([max(float(np.abs(a).max()) for a in st.v.values()) for st in cracklab.solver.stepper.steps(scene)])


@pytest.mark.parametrize("nu", NUS)
@pytest.mark.parametrize("scheme", sorted(SCHEMES))
def test_a_grid_run_at_the_limit_stays_bounded_and_past_it_is_refused(scheme, nu):
    sc = random_scene(scheme, nu)
    bmax = sc.beta_max
    measured = beta_max(sc.grid, scheme, None, sc.components, nu=nu, measured=True)
    assert bmax == pytest.approx(SAFETY * measured)
    with pytest.raises(InputError, match=r"^beta: must be in \(0, ") as info:
        sc.replace(beta=1.05 * measured)
    assert f"nu = {nu:g}" in str(info.value)
    steps = 3000 if not scheme.startswith("product") else 2000
    peaks = peak_history(forced(sc.replace(beta=bmax), bmax, steps))
    assert np.all(np.isfinite(peaks))
    late = peaks[steps // 2:]
    rate = np.polyfit(np.arange(late.size), np.log(late), 1)[0]  # per step
    gamma_m = sc.grid.q_max() * bmax * sc.grid.dx_min
    assert rate / gamma_m <= GROWTH_TOLERANCE
    assert late[-200:].max() <= peaks[:200].max()


def test_default_beta_is_half_or_the_limit():
    """A scene without beta takes 0.5, or its limit where that is lower (square grid, mode I)."""
    assert random_scene("displacement", 0.25).beta == 0.5
    sc = random_scene("displacement", 0.3)
    assert sc.beta == sc.beta_max < 0.5
    assert Scene.from_toml(sc.to_toml()).beta == sc.beta


# the schemes and Poisson ratios whose single-mode growth rises steeply past the limit
# (the velocity scheme's mode I grows slowly at every gamma below nu = 0.35: 1.02 times
# its limit grows at about its tolerance, 5e-4 per unit T, which no test run can tell)
STEEP = [("displacement", nu) for nu in NUS] + [("product", nu) for nu in NUS] + \
        [("velocity", nu) for nu in (0.35, 0.45)]


@pytest.mark.parametrize("scheme,nu", STEEP)
def test_a_run_forced_past_the_limit_is_stopped(scheme, nu):
    sc = random_scene(scheme, nu)
    measured = beta_max(sc.grid, scheme, None, sc.components, nu=nu, measured=True)
    sc = forced(sc, 1.02 * measured, 4000)
    with pytest.raises(SimulationError) as info:
        peak_history(sc)
    msg = str(info.value)
    assert re.match(r"exponential growth of v_\d at step \d+ ", msg), msg
    assert re.search(r"grew [0-9.e+]+-fold over the last \d+ steps", msg), msg
    assert f"exceeds the stable limit {sc.beta_max:.4g} of the {scheme} scheme at nu = {nu:g}" in msg
    peak = float(re.search(r"max \|v_\d\| = ([0-9.e+]+)", msg)[1])
    assert peak < 1e12   # caught long before an overflow


def test_slow_growth_is_stopped_with_its_rate():
    """0.3 % past the limit the grid grows by about 1 % per step: too slow for the fast
    detector (1e3-fold in 50 steps), caught by the steady rise of block maxima."""
    sc = random_scene("displacement", 0.3)
    measured = beta_max(sc.grid, "displacement", None, sc.components, nu=0.3, measured=True)
    sc = forced(sc, 1.003 * measured, 4000)
    with pytest.raises(SimulationError) as info:
        peak_history(sc)
    msg = str(info.value)
    m = re.search(r"steadily: ([0-9.e+-]+) % per step \(e-fold in ([0-9.e+]+) steps; ([0-9.e+-]+) per unit T", msg)
    assert m, msg
    per_step = float(m[1]) / 100
    assert 1e-3 < per_step < 0.14  # below what the fast detector needs
    assert float(m[2]) == pytest.approx(1 / math.log1p(per_step), rel=0.02)
    gamma_m = sc.grid.q_max() * sc.dt
    assert float(m[3]) == pytest.approx(math.log1p(per_step) / gamma_m, rel=0.02)
