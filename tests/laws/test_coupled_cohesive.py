"""The mixed-mode cohesive law (laws/coupled_cohesive.py), checked by its energy: per unit
area it dissipates its fracture energy G = delta_c (tau_c cos phi + tau_s sin phi / beta) / 2
in pure mode I (phi = 0), pure shear (phi = pi/2) and at a mixed angle, and it is the mode I
linear cohesive law when only the normal component is loaded."""
import numpy as np
import pytest

import cracklab as cl
from cracklab import scenes
from cracklab.analysis import energy
from cracklab.laws import CoupledCohesive

MAT = cl.Material(mu=1.0, cs=1.0, nu=0.25)
ETA1 = MAT.mu / (2 * MAT.cs)
ETA2 = MAT.mu * MAT.cd / (2 * MAT.cs**2)


def test_normal_load_only_is_the_linear_cohesive_law():
    sc = scenes.asperity_row(n1=256, n3=1, asperities=False, t_end=0.6,
                             record=cl.Record(fields=("delta_2", "tau_2"), every=10))
    law = sc.law
    coupled = sc.replace(law=CoupledCohesive(tau_c=law.tau_c, tau_s=3.0, delta_c=law.delta_c, beta=0.7,
                                             initial_crack=law.initial_crack, bonded=law.bonded))
    a, b = cl.simulate(sc), cl.simulate(coupled)
    assert float(a["delta_2"].max()) > 2 * np.max(law.delta_c)      # the crack has grown
    for name in ("delta_2", "tau_2", "rupture_time"):
        np.testing.assert_array_equal(b[name].values, a[name].values, err_msg=name)


@pytest.mark.parametrize("load_2, load_1", [(1.5, 0.0), (0.0, 1.5), (1.5, 1.5)],
                         ids=["mode I", "shear", "mixed"])
def test_uniform_breaking_dissipates_the_fracture_energy(load_2, load_1):
    """Uniform loads k tau_c (normal) and k tau_s (shear) break the whole plane at once (the
    q = 0 mode: no history): v_2 = tau_c (k - f) / eta_2, v_1 = tau_s (k - f) / eta_1, a
    proportional path at tan phi = beta tau_s eta_2 / (tau_c eta_1); the work of the
    traction per unit area is G(phi), to O(dt) with the budget's trapezoid rule in delta
    (5e-5 at these 640 steps)."""
    tau_c, tau_s, dc, beta = 1.0, 0.6, 0.2, 1.3
    law = CoupledCohesive(tau_c=tau_c, tau_s=tau_s, delta_c=dc, beta=beta)
    grid = cl.Grid(n1=8, n3=1, L1=1.0, L3=1.0)
    loading = cl.Loading(tau0_1=load_1 * tau_s, tau0_2=load_2 * tau_c)
    sc = cl.Scene(material=MAT, grid=grid, law=law, loading=loading, t_end=0.8, beta=0.01,
                  record=cl.Record(fields=()))
    sc = sc.replace(record=energy.energy_record(sc))
    ds = cl.simulate(sc)
    if load_1 == 0:
        phi = 0.0
    elif load_2 == 0:
        phi = np.pi / 2
    else:
        phi = np.arctan(beta * tau_s * ETA2 / (tau_c * ETA1))
        d1, d2 = ds["delta_1"].values[-1, 0, 0], ds["delta_2"].values[-1, 0, 0]
        assert beta * d1 / d2 == pytest.approx(np.tan(phi), rel=1e-9)    # the path is proportional
    G = 0.5 * dc * (tau_c * np.cos(phi) + tau_s * np.sin(phi) / beta)
    last = {c: ds[f"delta_{c}"].values[-1] if f"delta_{c}" in ds else 0.0 for c in (1, 2)}
    lam = np.sqrt(np.maximum(last[2], 0) ** 2 + (beta * last[1]) ** 2)
    assert lam.min() > 2 * dc                                              # broken everywhere
    b = energy.energy_budget(ds, rule="delta", flux=False)
    area = grid.L1
    assert float(b["dissipation"][-1]) / area == pytest.approx(G, rel=5e-4)
    assert float(b["fracture_energy"][-1]) / area == pytest.approx(G, rel=5e-4)
    np.testing.assert_allclose(b["fracture_energy_density"].values, G, rtol=5e-4)


def test_mixed_mode_crack_budget_closes():
    """A plane crack under uniform tension and shear (0.5 tau_c each) grows from a seed,
    its cohesive zone resolved by about ten cells at 512: the budget closes
    (W = dU + D + E_rad), and the dissipation (the traction's work) converges to the law's
    cohesive work with the cell size (no friction: the faces are open)."""
    ratio = {}
    for n1 in (256, 512):
        grid = cl.Grid(n1=n1, n3=1, L1=1.0, L3=1.0)
        seed = np.abs(grid.x1[:, None] - 0.5) < 0.05
        law = CoupledCohesive(tau_c=1.0, tau_s=1.0, delta_c=2e-2, beta=1.0, initial_crack=seed)
        sc = cl.Scene(material=MAT, grid=grid, law=law, loading=cl.Loading(tau0_1=0.5, tau0_2=0.5), t_end=0.3,
                      numerics=cl.Numerics(engine="exponential"), record=cl.Record(fields=()))
        sc = sc.replace(record=energy.energy_record(sc))
        ds = cl.simulate(sc)
        s = energy.budget_summary(energy.energy_budget(ds))
        broken = (np.sqrt(ds["delta_1"].values[-1] ** 2 + np.maximum(ds["delta_2"].values[-1], 0) ** 2) >= 2e-2) & ~seed
        assert broken.sum() > 0.3 * n1                         # the crack has more than tripled
        assert s["max_abs_closure"] < 1e-3
        ratio[n1] = s["dissipation"] / s["fracture_energy"]
    assert abs(ratio[512] - 1) < 5e-3
    assert abs(ratio[256] - 1) > 2 * abs(ratio[512] - 1)      # converging with the cell size


def test_bad_parameters_are_named():
    with pytest.raises(cl.InputError) as err:
        CoupledCohesive(tau_c=1.0, tau_s=1.0, delta_c=0.0)
    assert err.value.field == "law.delta_c"
    with pytest.raises(cl.InputError) as err:
        CoupledCohesive(tau_c=1.0, tau_s=1.0, delta_c=1.0, beta=-1.0)
    assert err.value.field == "law.beta"
