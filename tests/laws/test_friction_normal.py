"""Friction that follows the normal traction (laws/friction.py): a friction law without
sigma_n takes coefficient x max(0, -tau_2), with opening and contact on component 2."""
import dataclasses

import numpy as np
import pytest

from cracklab.laws import ConstantFriction
from cracklab import (Grid, InputError, Loading, Material, Record, Scene, SlipWeakening,
                      scenes, simulate, stations)

MAT = Material(mu=1.0, cs=1.0, nu=0.25)
FIELDS = ("delta_1", "delta_2", "v_1", "v_2", "tau_1", "tau_2", "strength")


def uniform(loading, law, n3=8, t_end=0.2):
    grid = Grid(n1=8, n3=n3, L1=1.0, L3=1.0)
    return simulate(Scene(material=MAT, grid=grid, law=law, loading=loading, t_end=t_end,
                          record=Record(fields=FIELDS[:-1] + ("v_3",) * (n3 > 1) + ("strength",), every=1)))


def test_tpv3_with_the_normal_traction_followed_is_the_constant_sigma_n_run():
    """Identical materials, planar fault: slip does not change the normal traction, so
    loading tau0_2 = -120 MPa and following it gives the run with sigma_n = 120 MPa."""
    base = scenes.tpv3(dx=600.0, t_end=3.0)
    base = base.replace(record=dataclasses.replace(base.record, fields=("delta_1", "tau_1", "strength"),
                                                   every=20))
    coupled = base.replace(law=dataclasses.replace(base.law, sigma_n=None),
                           loading=dataclasses.replace(base.loading, tau0_2=-120.0e6))
    assert coupled.components == (1, 2, 3) and coupled.dt == base.dt
    a, b = simulate(base), simulate(coupled)
    assert float(a["delta_1"].max()) > 0.5          # the rupture has grown well beyond the patch
    for name in ("delta_1", "tau_1", "strength", "rupture_time"):
        x, y = a[name].values, b[name].values
        scale = np.nanmax(np.abs(x))
        np.testing.assert_allclose(y, x, rtol=0, atol=1e-12 * scale, err_msg=name)
    np.testing.assert_array_equal(b["rupture_time"].isnull(), a["rupture_time"].isnull())
    sa, sb = stations(a), stations(b)
    for name in ("delta_1", "v_1", "tau_1", "delta_3", "v_3", "tau_3"):
        scale = float(np.abs(sa[name]).max())
        np.testing.assert_allclose(sb[name].values, sa[name].values, rtol=0, atol=1e-12 * scale, err_msg=name)
    np.testing.assert_array_equal(sb["delta_2"].values, 0.0)     # the faces stay closed
    np.testing.assert_array_equal(sb["tau_2"].values, -120.0e6)


@pytest.mark.parametrize("law", [ConstantFriction(mu_f=0.6),
                                 SlipWeakening(mu_s=0.6, mu_d=0.6, D_c=1.0)])
def test_pressed_faces_slide_against_mu_sigma(law):
    """Uniform load (the q = 0 mode, no history): tau_1 = mu sigma and v_1 = (tau0_1 - mu sigma) / eta."""
    r = uniform(Loading(tau0_1=0.8, tau0_2=-1.0), law)
    eta1 = MAT.mu / (2 * MAT.cs)
    np.testing.assert_allclose(r["v_1"].values[1:], (0.8 - 0.6) / eta1, rtol=1e-12)
    np.testing.assert_allclose(r["tau_1"].values[1:], 0.6, rtol=1e-12)
    np.testing.assert_allclose(r["strength"].values[1:], 0.6, rtol=1e-12)
    np.testing.assert_array_equal(r["delta_2"].values, 0.0)
    np.testing.assert_allclose(r["tau_2"].values[1:], -1.0, rtol=1e-15)
    # below the strength: stuck
    r = uniform(Loading(tau0_1=0.5, tau0_2=-1.0), law)
    np.testing.assert_array_equal(r["v_1"].values, 0.0)


def test_faces_under_tension_open_and_slide_freely():
    """Tension: no tensile strength, so v_2 = tau0_2 / eta_2, tau_2 = 0, and zero friction."""
    r = uniform(Loading(tau0_1=0.3, tau0_2=0.5), ConstantFriction(mu_f=0.6))
    eta1, eta2 = MAT.mu / (2 * MAT.cs), MAT.mu * MAT.cd / (2 * MAT.cs**2)
    np.testing.assert_allclose(r["v_2"].values[1:], 0.5 / eta2, rtol=1e-12)
    np.testing.assert_allclose(r["tau_2"].values[1:], 0.0, atol=1e-14)
    np.testing.assert_allclose(r["v_1"].values[1:], 0.3 / eta1, rtol=1e-12)
    np.testing.assert_allclose(r["strength"].values[1:], 0.0, atol=1e-14)


@pytest.mark.parametrize("shear", [False, True])
def test_faces_open_and_close_without_interpenetrating(shear):
    """A normal load tensile around x1 = 0.5 on a compressive mean, ramped up, in the
    plane: the faces never interpenetrate, the normal traction is compressive where they
    are closed and vanishes where they are open, and points that opened close again (the
    dynamic overshoot). Normal load only: the displacement scheme; with shear: the
    product scheme. At the step a point closes, step (v) presses the faces together
    (compressive traction) while the recorded opening is the one before the closing
    velocity acts (displacement: delta_n, closed at n + 1; product: the trapezoid of
    (50) can take two steps): such points close within two steps."""
    grid = Grid(n1=256, n3=1, L1=1.0, L3=1.0)
    x = grid.x1[:, None]
    tau0_2 = -0.2 + 0.5 * np.exp(-((x - 0.5) / 0.05) ** 2)
    law = SlipWeakening(mu_s=0.6, mu_d=0.3, D_c=0.01)
    load = Loading(tau0_1=0.1 * np.ones(grid.shape) if shear else 0.0, tau0_2=tau0_2, time="smooth", ramp_time=0.2)
    sc = Scene(material=MAT, grid=grid, law=law, loading=load, t_end=1.2,
               record=Record(fields=("delta_2", "tau_2", "strength"), every=1))
    assert sc.formulation == ("product" if shear else "displacement")
    r = simulate(sc)
    d2, t2 = r["delta_2"].values[..., 0], r["tau_2"].values[..., 0]
    scale = float(np.abs(t2).max())
    assert d2.min() >= -1e-12 * d2.max()
    open_ = d2 > 1e-9 * d2.max()
    assert open_.sum() > 1000
    assert t2[~open_].max() <= 1e-9 * scale
    bad = open_ & (np.abs(t2) > 1e-9 * scale)
    for n, i in np.argwhere(bad):
        assert not open_[n + 1: n + (3 if shear else 2), i].all(), (n, i)
        assert t2[n, i] < 0
    assert bad.sum() <= 0.001 * open_.sum()
    opened_then_closed = open_[: open_.shape[0] // 2].any(axis=0) & ~open_[-1]
    assert opened_then_closed.any()
    # no friction where the faces are open
    strength = np.broadcast_to(r["strength"].values[..., 0], open_.shape)
    assert np.abs(strength[open_ & ~bad]).max() <= 1e-9 * scale


def test_scene_checks_the_normal_load():
    grid = Grid(n1=8, n3=8, L1=1.0, L3=1.0)
    with pytest.raises(InputError) as err:
        Scene(material=MAT, grid=grid, law=SlipWeakening(mu_s=0.6, mu_d=0.5, D_c=0.1),
              loading=Loading(tau0_1=1.0), t_end=0.1)
    assert err.value.field == "loading.tau0_2"
    with pytest.raises(InputError) as err:
        Scene(material=MAT, grid=grid, law=SlipWeakening(mu_s=0.6, mu_d=0.5, D_c=0.1, sigma_n=1.0),
              loading=Loading(tau0_1=1.0, tau0_2=-1.0), t_end=0.1)
    assert err.value.field == "loading.tau0_2" and "sigma_n" in str(err.value)
