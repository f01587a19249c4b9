"""The constant-friction law, added as docs/developer/developer.md's recipe "Add a law" says: one
file (cracklab/laws/constant_friction.py) and these tests."""
import numpy as np
import pytest

import cracklab
from cracklab import Grid, InputError, Loading, Material, Record, Scene
from cracklab.laws import LAWS, ConstantFriction, SlipWeakening

MAT = Material(mu=1.0, cs=1.0, nu=0.25)


def test_it_registers_by_its_toml_name_and_round_trips():
    assert LAWS["constant_friction"] is ConstantFriction
    sc = Scene(material=MAT, grid=Grid(n1=16, n3=1, L1=1.0, L3=1.0), law=ConstantFriction(mu_f=0.6, sigma_n=2.0),
               loading=Loading(tau0_1=1.5), t_end=0.5, record=Record(fields=("delta_1",)))
    back = Scene.from_toml(sc.to_toml())
    assert back.law == sc.law and back.law.kind == "constant_friction"


@pytest.mark.parametrize("bad", [{"mu_f": -0.1}, {"sigma_n": float("nan")}, {"mu_f": "x"}])
def test_bad_parameters_name_the_field(bad):
    args = {"mu_f": 0.6, "sigma_n": 1.0, **bad}
    with pytest.raises(InputError, match=rf"^law\.{next(iter(bad))}: "):
        ConstantFriction(**args)


@pytest.mark.parametrize("n3", [1, 16])
def test_a_uniform_load_above_friction_slides_at_the_radiation_damping_rate(n3):
    """Uniform shear load tau0 > mu_f sigma_n: only the q = 0 mode is loaded, whose
    elastodynamic response is nil, so Eq. (3) gives v = 2 c_s (tau0 - mu_f sigma_n) / mu
    exactly at every point and step, and the traction stays at the friction level."""
    tau0, mu_f, sigma_n = 1.5, 0.6, 2.0
    grid = Grid(n1=16, n3=n3, L1=1.0, L3=1.0)
    sc = Scene(material=MAT, grid=grid, law=ConstantFriction(mu_f=mu_f, sigma_n=sigma_n),
               loading=Loading(tau0_1=tau0), t_end=0.5, record=Record(fields=("v_1", "tau_1", "delta_1"), every=4))
    ds = cracklab.simulate(sc)
    v = 2 * MAT.cs * (tau0 - mu_f * sigma_n) / MAT.mu
    np.testing.assert_allclose(ds.v_1.values, v, rtol=1e-12)
    np.testing.assert_allclose(ds.tau_1.values, mu_f * sigma_n, rtol=1e-12)
    if "v_3" in ds:
        np.testing.assert_allclose(ds.v_3.values, 0.0, atol=1e-12)


def test_below_friction_nothing_moves():
    sc = Scene(material=MAT, grid=Grid(n1=16, n3=16, L1=1.0, L3=1.0), law=ConstantFriction(mu_f=0.6, sigma_n=2.0),
               loading=Loading(tau0_1=1.1), t_end=0.3, record=Record(fields=("v_1", "v_3"), every=4))
    ds = cracklab.simulate(sc)
    assert float(np.abs(ds.v_1).max()) == 0.0 and float(np.abs(ds.v_3).max()) == 0.0


def test_it_is_slip_weakening_without_weakening():
    """A patch overloaded past friction in 3D (a real elastodynamic run with the product
    scheme): the same numbers as slip weakening with mu_s = mu_d, an independent law."""
    grid = Grid(n1=32, n3=32, L1=1.0, L3=1.0)
    x1, x3 = np.meshgrid(grid.x1, grid.x3, indexing="ij")
    tau0 = np.where(np.hypot(x1 - 0.5, x3 - 0.5) < 0.15, 1.4, 1.0)
    rec = Record(fields=("delta_1", "delta_3", "v_1"), every=10)

    def run(law):
        return cracklab.simulate(Scene(material=MAT, grid=grid, law=law, loading=Loading(tau0_1=tau0),
                                       t_end=0.4, record=rec))

    a = run(ConstantFriction(mu_f=0.6, sigma_n=2.0))
    b = run(SlipWeakening(mu_s=0.6, mu_d=0.6, D_c=1.0, sigma_n=2.0))
    assert float(np.abs(a.delta_1).max()) > 0.01
    for name in ("delta_1", "delta_3", "v_1"):
        np.testing.assert_allclose(a[name].values, b[name].values, rtol=0, atol=1e-13)
