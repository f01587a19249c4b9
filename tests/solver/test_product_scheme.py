"""The product scheme on the full grid (velocity formulation, Z integrated exactly
against the piecewise-linear velocity history, one predictor-corrector pass):
identical to the single-mode recurrence of cracklab.modal, and stable in mode II
where the paper's explicit scheme grows (docs/reference/stability.md)."""
import numpy as np
import pytest

from cracklab import Grid, Loading, Material, Record, Scene, TractionFree, modal_response, simulate
from cracklab.analysis.exact import periodic_row_opening
from cracklab.model.scene import Numerics
from cracklab.scenes import periodic_cracks, tpv3

MAT = Material(mu=1.0, cs=1.0, nu=0.25)
SCHEME = dict(formulation="velocity", convolution="product", integration="predictor-corrector")


# the direct engine reproduces the recurrence to round-off; the exponential engine to its
# fitted representation of Z (about 1e-5 of Z(0), docs/reference/fast_engine.md)
ENGINES = [("direct", 1e-10), ("exponential", 2e-5)]


def single_wave(comp, beta=0.4, steps=80, engine="direct"):
    g = Grid(n1=16, n3=8, L1=1.0, L3=0.5)
    x1, x3 = np.meshgrid(g.x1, g.x3, indexing="ij")
    k, m = 2 * np.pi * 3 / g.L1, 2 * np.pi * 2 / g.L3
    sc = Scene(material=MAT, grid=g, law=TractionFree(),
               loading=Loading(**{f"tau0_{comp}": np.cos(k * x1 + m * x3)}),
               t_end=steps * beta * g.dx_min * (1 - 1e-9), beta=beta,
               record=Record(fields=(f"v_{comp}",), every=1),
               numerics=Numerics(formulation="product", engine=engine))
    ds = simulate(sc)
    q = np.hypot(k, m)
    return sc, ds, k / q, m / q, q * sc.dt


@pytest.mark.parametrize("engine,tol", ENGINES)
def test_mode_I_matches_modal(engine, tol):
    sc, ds, _, _, gamma = single_wave(2, engine=engine)
    r = modal_response("I", gamma=gamma, T_end=gamma * sc.nsteps, **SCHEME).values
    v = ds.v_2.values[:, 0, 0] * MAT.eta(2)
    assert np.max(np.abs(v - r[:v.size])) < tol


@pytest.mark.parametrize("engine,tol", ENGINES)
def test_oblique_shear_matches_modal_rotation(engine, tol):
    sc, ds, c, s, gamma = single_wave(1, engine=engine)
    rII = modal_response("II", gamma=gamma, T_end=gamma * sc.nsteps, **SCHEME).values
    rIII = modal_response("III", gamma=gamma, T_end=gamma * sc.nsteps, **SCHEME).values
    v = ds.v_1.values[:, 0, 0] * MAT.eta(1)
    assert np.max(np.abs(v - (c * c * rII + s * s * rIII)[:v.size])) < tol


def test_mode_II_periodic_row_at_beta_half():
    """Mode II at beta = 0.5 (gamma_M = pi/2, where the explicit scheme grows by
    e^0.04 per step) reaches the exact periodic opening within 0.5%."""
    n, c, t_end = 512, 0.25, 3.5
    scene = periodic_cracks(n=n, c=c, mode="II", t_end=t_end, beta=0.5,
                            record=Record(fields=("delta_1",), times=(t_end,)),
                            numerics=Numerics(formulation="product"))
    scene = scene.replace(loading=Loading(tau0_1=scene.loading.tau0_1, time="smooth", ramp_time=t_end - 1))
    d = simulate(scene).delta_1.isel(t=-1, x3=0).values
    x = scene.grid.x1 - 0.5
    c_eff = (np.count_nonzero(np.abs(x) <= c) / 2) * scene.grid.dx1
    exact = periodic_row_opening(x, c_eff, 1.0, 1.0, 1.0, 0.25, "II")
    inner = np.abs(x) <= 0.5 * c
    assert np.max(np.abs(d[inner] - exact[inner])) / exact.max() < 0.005


def test_displacement_scheme_refuses_the_same_beta():
    with pytest.raises(Exception, match="beta"):
        periodic_cracks(n=64, c=0.25, mode="II", t_end=1.0, beta=0.5,
                        numerics=Numerics(formulation="displacement"))


def test_tpv3_uses_a_stable_shear_scheme():
    """tpv3 steps with the product scheme's second-order variant (product2, whose limits
    are the product scheme's) at beta = 0.125, inside its stable range (docs/studies/tpv3.md)."""
    from cracklab.solver.stability import beta_max

    sc = tpv3(dx=1000.0, t_end=0.5)
    assert sc.formulation == "product2" and sc.beta == 0.125
    assert sc.beta < beta_max(sc.grid, *sc.numerics.scheme((1, 3)), (1, 3), nu=sc.material.nu)


@pytest.mark.parametrize("law_kind", ["slip_weakening", "prescribed"])
def test_laws_that_read_no_slip_skip_the_trial_slips(monkeypatch, law_kind):
    """A law whose update reads v, t and tau but not the slip (reads_slip = False) is
    updated once per step instead of on a copy for the predictor and again for the step:
    the run is the same to the last bit as with the trial slips and the copy."""
    from cracklab import PrescribedRupture, SlipWeakening

    from cracklab.solver import stepper
    g = Grid(n1=32, n3=16, L1=2.0, L3=1.0)
    x1, x3 = np.meshgrid(g.x1, g.x3, indexing="ij")
    patch = (np.abs(x1 - 1.0) < 0.2) & (np.abs(x3 - 0.5) < 0.2)
    if law_kind == "slip_weakening":
        law = SlipWeakening(mu_s=0.6, mu_d=0.5, D_c=0.01, sigma_n=1.0)
    else:
        law = PrescribedRupture(speed=0.8, origin=(1.0, 0.5), residual=0.5, strength_before=0.6,
                                weakening_time=0.1)
    assert law.reads_slip is False
    sc = Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=g, law=law,
               loading=Loading(tau0_1=np.where(patch, 0.62, 0.55), tau0_3=0.05), t_end=0.8, beta=0.4,
               record=Record(fields=("delta_1", "delta_3", "v_1", "tau_3"), every=5),
               numerics=Numerics(engine="exponential", formulation="product"))
    fast = simulate(sc)
    monkeypatch.setattr(stepper, "reads_slip", lambda law, comps: True)
    slow = simulate(sc)
    assert float(np.abs(fast.delta_1).max()) > 1e-3
    for f in ("delta_1", "delta_3", "v_1", "tau_3"):
        assert np.array_equal(fast[f].values, slow[f].values), f


def test_which_laws_read_the_slip():
    from cracklab import LinearCohesive, SlipWeakening
    from cracklab.solver.stepper import reads_slip

    assert reads_slip(LinearCohesive(tau_c=1.0, delta_c=0.1), (2,))
    assert not reads_slip(SlipWeakening(mu_s=0.6, mu_d=0.5, D_c=0.01, sigma_n=1.0), (1, 3))
    assert reads_slip(TractionFree(contact=True), (1, 2, 3))      # contact reads the opening
    assert not reads_slip(TractionFree(contact=True), (1, 3))
    assert not reads_slip(TractionFree(), (1, 2, 3))

    class Custom:  # a law that does not say: taken to read it
        pass

    assert reads_slip(Custom(), (1, 3))
