"""The interface between two different materials (solver/interfaces/bimaterial.py): the
identical pair through it, the generalized Rayleigh wave of a frictionless bimaterial
interface, checkpoints and the scene's checks."""
import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

import cracklab
from cracklab import Grid, Loading, Material, Numerics, Record, Scene
from cracklab.errors import InputError
from cracklab.laws import TractionFree
from cracklab.solver.interfaces import Bimaterial, Identical, for_scene
from cracklab.solver.stepper import Stepper

PRODUCT = Numerics(formulation="product")
M = Material(mu=1.0, cs=1.0, nu=0.25)


def final_slip(scene, response=None):
    st = None
    for st in Stepper(scene, response=response):
        pass
    return {c: st.delta[c].copy() for c in st.delta}


def through_bimaterial(scene):
    m = scene.material
    return Bimaterial(m, m, scene.grid, scene.dt, scene.components, nsteps=scene.nsteps, engine=scene.numerics.engine,
                      window=scene.numerics.window)


def test_identical_pair_through_the_faces_antiplane_is_the_combined_path():
    """Mode III has no coupling: two identical faces move as -+ delta/2 exactly."""
    sc = cracklab.scenes.periodic_cracks(n=64, c=0.15, mode="III", beta=0.3, t_end=0.3, numerics=PRODUCT)
    a, b = final_slip(sc), final_slip(sc, through_bimaterial(sc))
    assert np.max(np.abs(a[3] - b[3])) <= 1e-12 * np.max(np.abs(a[3]))


@pytest.mark.parametrize("mode,c", [("II", 1), ("I", 2)])
def test_identical_pair_through_the_faces_converges_to_the_combined_path(mode, c):
    """In plane the faces' continuous motion is stepped too: the paths differ by the
    scheme's error, which shrinks with the time step at second order."""
    diffs = []
    for beta in (0.4, 0.2):
        sc = cracklab.scenes.periodic_cracks(n=64, c=0.15, mode=mode, beta=beta, t_end=0.3, numerics=PRODUCT)
        a, b = final_slip(sc), final_slip(sc, through_bimaterial(sc))
        diffs.append(np.max(np.abs(a[c] - b[c])) / np.max(np.abs(a[c])))
    assert diffs[0] < 1.5e-3       # measured 8e-4 (II), 2e-4 (I)
    assert diffs[1] < 0.4 * diffs[0]  # measured 0.30


def rayleigh(c, cs, cd):
    x = (c / cs) ** 2
    return (2 - x) ** 2 - 4 * np.sqrt(1 - x) * np.sqrt(1 - (c / cd) ** 2)


def generalized_rayleigh_speed(m1, m2):
    """Root of rho1 cs1^4 R1(c)/sqrt(1 - c^2/cd1^2) + (same for 2) = 0 below both shear
    speeds: the slip wave of a frictionless contact (Weertman 1963; Achenbach & Epstein 1967)."""
    def f(c):
        return sum(m.rho * m.cs**4 * rayleigh(c, m.cs, m.cs * m.a) / np.sqrt(1 - (c / (m.cs * m.a)) ** 2)
                   for m in (m1, m2))

    return brentq(f, 0.5 * min(m1.cs, m2.cs), min(m1.cs, m2.cs) * (1 - 1e-12), xtol=1e-15)


def single_mode_frequency(top, bottom, beta, t_end=24.0):
    """Free oscillation of the mode cos(2 pi x1) of a frictionless interface (shear traction
    free, no opening), after a step load; the frequency times the wavelength 1 is the speed."""
    g = Grid(n1=8, n3=1, L1=1.0, L3=1.0)
    sc = Scene(materials=(top, bottom), grid=g, law=TractionFree(contact=False),
               loading=Loading(tau0_1=np.cos(2 * np.pi * g.x1)[:, None] * np.ones((8, 1))), t_end=t_end, beta=beta,
               record=Record(fields=("delta_1",)), numerics=PRODUCT)
    t, v = [], []
    for st in Stepper(sc):
        t.append(st.t)
        v.append(st.v[1][0, 0])
    t, v = np.array(t), np.array(v)
    keep = t > 0.4 * t_end
    t, v = t[keep], v[keep]

    def misfit(w):  # the wave, plus the decaying transients of the step
        A = np.stack([np.cos(2 * np.pi * w * t), np.sin(2 * np.pi * w * t), np.ones_like(t), t**-1.5,
                      t**-0.5 * np.cos(2 * np.pi * t), t**-0.5 * np.sin(2 * np.pi * t)], 1)
        coef = np.linalg.lstsq(A, v, rcond=None)[0]
        return float(np.sum((A @ coef - v) ** 2))

    ws = np.linspace(0.8, 1.0, 201)
    w0 = ws[int(np.argmin([misfit(w) for w in ws]))]
    return minimize_scalar(misfit, bracket=(w0 - 1e-3, w0, w0 + 1e-3), tol=1e-12).x


@pytest.mark.parametrize("bottom", [Material(mu=0.5, cs=1.0, nu=0.25),
                                    Material(mu=0.5 * 0.95**2, cs=0.95, nu=0.3)])
def test_frictionless_bimaterial_interface_carries_the_generalized_rayleigh_wave(bottom):
    want = generalized_rayleigh_speed(M, bottom)
    got = single_mode_frequency(M, bottom, beta=0.1)
    assert abs(got / want - 1) < 5e-4   # the issue asks 0.5 %; measured ~1e-4


def test_antiplane_pair_of_one_shear_speed_is_one_material_of_the_harmonic_modulus():
    """Anti-plane, each face answers tau = -mu_k sqrt(k^2 + s^2/c_s^2) u_k: with one c_s on
    both sides the jump delta = u_top - u_bottom answers as one material of modulus
    mu = 2 mu_t mu_b / (mu_t + mu_b) (Laplace domain, exact), so a rupture through two
    faces of different mu (different densities) is the one-material run to round-off."""
    from cracklab.laws import SlipWeakening

    g = Grid(n1=128, n3=1, L1=1.0, L3=1.0)
    x = g.x1[:, None]
    top, bottom = Material(mu=1.0, cs=1.0, nu=0.25), Material(mu=0.3, cs=1.0, nu=0.3)
    one = Material(mu=2 * 0.3 / 1.3, cs=1.0, nu=0.2)   # c_p plays no part in mode III
    law = SlipWeakening(mu_s=0.7, mu_d=0.5, D_c=0.01, sigma_n=1.0)
    load = Loading(tau0_3=np.where(np.abs(x - 0.5) < 0.05, 0.75, 0.6))
    base = Scene(material=one, grid=g, law=law, loading=load, t_end=0.6, beta=0.25,
                 record=Record(fields=("delta_3",)), numerics=PRODUCT)
    a = final_slip(base)[3]
    b = final_slip(base.replace(materials=(top, bottom)))[3]
    assert np.max(np.abs(a)) > 0.05 and np.mean(a > 1e-6) > 0.3     # it ruptured beyond the patch
    assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(a))


def test_resume_gives_the_same_run():
    bottom = Material(mu=0.6, cs=0.9, nu=0.3)
    g = Grid(n1=16, n3=1, L1=1.0, L3=1.0)
    sc = Scene(materials=(M, bottom), grid=g, law=TractionFree(contact=False),
               loading=Loading(tau0_1=np.cos(2 * np.pi * g.x1)[:, None] * np.ones((16, 1))), t_end=0.6, beta=0.3,
               record=Record(fields=("delta_1",)), numerics=PRODUCT)
    whole = final_slip(sc)
    stepper = Stepper(sc)
    for st in stepper:
        if st.n == 10:
            break
    rest = Stepper(sc, start=stepper.get_state())
    for st in rest:
        pass
    np.testing.assert_array_equal(st.delta[1], whole[1])


def test_3d_identical_pair_through_the_faces():
    diffs = []
    for beta in (0.5, 0.25):
        sc = cracklab.scenes.elliptical_crack(n=16, a=0.25, b=0.2, beta=beta, t_end=0.15, numerics=PRODUCT)
        a, b = final_slip(sc), final_slip(sc, through_bimaterial(sc))
        diffs.append(np.max(np.abs(a[2] - b[2])) / np.max(np.abs(a[2])))
    assert diffs[0] < 5e-3             # measured 2.7e-3
    assert diffs[1] < 0.35 * diffs[0]  # measured 0.22


def test_scene_takes_two_materials():
    bottom = Material(mu=0.5, cs=0.8, nu=0.3)
    sc = cracklab.scenes.lamb(n=8, t_end=0.05, numerics=PRODUCT).replace(materials=(M, bottom))
    assert isinstance(for_scene(sc), Bimaterial)
    assert sc.material == M   # the faster side sets the time step
    assert sc.dt == pytest.approx(sc.beta * sc.grid.dx_min / 1.0)
    assert isinstance(for_scene(sc.replace(material=M)), Identical)
    with pytest.raises(InputError, match="numerics.formulation"):
        sc.replace(numerics=Numerics(formulation="velocity"))
    # the builder's default numerics ("auto", the displacement scheme for one material in
    # mode I) take the product scheme on the pair
    auto = cracklab.scenes.lamb(n=8, t_end=0.05).replace(materials=(M, bottom))
    assert auto.numerics.formulation == "auto" and auto.formulation == "product"


def test_free_surface_bimaterial_run_equals_the_doubled_whole_space_run():
    """The mirror on a bimaterial interface: the half plane against the doubled cell, to
    round-off, 3D shear under slip weakening at a constant sigma_n (the faces' normal motion
    is stepped all the same: slip moves it on a bimaterial interface). With friction that
    follows the normal traction the bimaterial problem is ill-posed (the Adams instability):
    there round-off grows, to 1e-3 in this run."""
    import test_mirror as tm

    soft = Material(mu=0.6, cs=0.8, nu=0.3)

    def scene(grid, x1, x3, mk, **options):
        sc = tm.shear_scene(grid, x1, x3, mk, **options)
        # within the pair's limit (Scene.beta_max: 0.9 of the smaller side's)
        return sc.replace(materials=(tm.MAT, soft), beta=min(sc.beta, 0.45))

    worst, half = tm._pair(scene, ("delta_1", "delta_3", "tau_1", "tau_3"))
    assert worst < tm.TOL, worst
    assert float(np.max(np.abs(half["delta_1"].values))) > 0.02          # it ruptured


def test_two_materials_round_trip_through_toml_and_the_output():
    from cracklab.model.scene_io import scene_from_dataset, scene_from_toml, scene_to_toml, scenes_equal

    bottom = Material(mu=0.45, cs=0.95, nu=0.3)
    g = Grid(n1=8, n3=1, L1=1.0, L3=1.0)
    sc = Scene(materials=(M, bottom), grid=g, law=TractionFree(contact=False), loading=Loading(tau0_1=1.0),
               t_end=0.1, beta=0.2, record=Record(fields=("delta_1",)), numerics=PRODUCT)
    text = scene_to_toml(sc)
    assert "[materials.bottom]" in text and "[material]" not in text
    assert scenes_equal(scene_from_toml(text), sc)
    assert scene_from_dataset(cracklab.simulate(sc)).materials == (M, bottom)


def test_the_pair_is_held_to_a_margin_below_the_smaller_sides_limit():
    """Scene.beta_max of two materials is the bimaterial interface's margin of the smaller of
    the sides' limits (the coupled faces grew at 0.97-1.0 of it); a beta above it is refused
    before any work, naming the margin; one material keeps its own limit."""
    BIMATERIAL_MARGIN = Bimaterial.margin

    g = Grid(n1=16, n3=16, L1=1.0, L3=1.0)
    soft = Material(mu=0.6, cs=0.8, nu=0.3)
    one = Scene(material=M, grid=g, law=TractionFree(), loading=Loading(tau0_1=1.0, tau0_3=0.5), t_end=0.1,
                numerics=PRODUCT)
    sides = min(one.beta_max, one.replace(material=soft).beta_max)
    two = one.replace(materials=(M, soft), beta=None)
    assert BIMATERIAL_MARGIN == 0.9 and two.beta_max == pytest.approx(0.9 * sides, rel=1e-12)
    assert two.beta == pytest.approx(min(0.5, two.beta_max))
    with pytest.raises(InputError, match=r"beta: .*of two materials 0.9 of the smaller side's limit"):
        one.replace(materials=(M, soft), beta=0.95 * sides)


def _run_with_faces(scene):
    st = None
    for st in Stepper(scene):
        pass
    faces = {kind: st.faces(kind) for kind in ("u", "v")}
    return {c: st.delta[c].copy() for c in st.delta}, faces


@pytest.mark.parametrize("n3,comps", [(8, (1, 2, 3)), (8, (1, 3)), (1, (1, 2)), (1, (3,))])
def test_compiled_passes_give_the_numpy_path(n3, comps):
    """The bimaterial step's compiled passes (loops.bim_*) against the interface's numpy
    expressions (loops.python_only): slip and both faces' motion, to round-off."""
    from cracklab.solver import loops

    bottom = Material(mu=0.6, cs=0.8, nu=0.3)
    g = Grid(n1=16, n3=n3, L1=1.0, L3=n3 / 16 if n3 > 1 else 1.0)
    rng = np.random.default_rng(3)
    load = Loading(**{f"tau0_{c}": rng.standard_normal(g.shape) for c in comps})
    sc = Scene(materials=(M, bottom), grid=g, law=TractionFree(contact=False), loading=load, t_end=0.4, beta=0.3,
               record=Record(fields=()), numerics=PRODUCT)
    got, got_faces = _run_with_faces(sc)
    with loops.python_only():
        want, want_faces = _run_with_faces(sc)
    for c in want:
        assert np.max(np.abs(got[c] - want[c])) <= 1e-12 * np.max(np.abs(want[c]))
    for kind in ("u", "v"):
        for key, w in want_faces[kind].items():
            assert np.max(np.abs(got_faces[kind][key] - w)) <= 1e-12 * np.max(np.abs(w)), (kind, key)
