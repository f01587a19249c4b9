"""Half spaces and the interface between them (solver/halfspace.py, solver/interfaces/),
and a scene's materials (one for both sides, or (top, bottom))."""
import numpy as np
import pytest

from cracklab import Grid, InputError, Loading, Material, Numerics, Record, Scene, TractionFree, simulate
from cracklab.model.scene_io import scenes_equal
from cracklab.solver.halfspace import HalfSpace
from cracklab.solver.interfaces import Bimaterial, Identical, for_scene, interface

MAT = Material(mu=2.0, cs=1.5, nu=0.3)
PLANE = Grid(n1=64, n3=1, L1=1.0, L3=1.0)


def scene(**changes):
    base = dict(material=MAT, grid=Grid(n1=16, n3=16, L1=1.0, L3=1.0), law=TractionFree(),
                loading=Loading(tau0_2=1.0), t_end=0.05)
    base.update(changes)
    return Scene(**base)


def test_one_material_or_the_same_pair_is_one_scene():
    one = scene()
    pair = scene(material=None, materials=(MAT, MAT))
    assert scenes_equal(one, pair)
    assert pair.material == MAT and one.materials == (MAT, MAT)
    assert isinstance(for_scene(one), Identical)


def test_replace_a_material_replaces_both_sides():
    other = Material(mu=1.0, cs=1.0, nu=0.25)
    sc = scene().replace(material=other)
    assert sc.materials == (other, other)
    sc = scene().replace(materials=(other, other))
    assert sc.material == other


@pytest.mark.parametrize("changes, field", [
    (dict(material=None), "material"),
    (dict(material=None, materials=(MAT,)), "materials"),
    (dict(material=None, materials=(MAT, "granite")), "materials.bottom"),
    # two materials need the product scheme: an explicit other one is refused
    (dict(material=None, materials=(Material(mu=1.0, cs=1.0, nu=0.25), MAT),
          numerics=Numerics(formulation="displacement")), "numerics.formulation"),
    (dict(materials=(Material(mu=1.0, cs=1.0, nu=0.25),) * 2), "material"),
    (dict(material={"mu": 1.0}), "material"),
])
def test_bad_materials_are_named(changes, field):
    with pytest.raises(InputError) as err:
        scene(**changes)
    assert err.value.field == field


def test_a_half_space_face_answers_twice_what_the_identical_pair_does():
    """The pair answers delta as one half space answers delta/2 (u+ = -u- = delta/2):
    the face response is linear, so per unit field it is exactly half (a power of two:
    the same bits, doubled), for every scheme."""
    rng = np.random.default_rng(3)
    grid = Grid(n1=32, n3=16, L1=1.0, L3=0.5)
    dt = 0.4 * grid.dx_min / MAT.cs
    fields = [{c: rng.standard_normal(grid.shape) for c in (1, 2, 3)} for _ in range(6)]
    for formulation in ("displacement", "velocity", "product"):
        pair = interface(MAT, grid, dt, (1, 2, 3), formulation=formulation, engine="direct")
        half = HalfSpace(MAT, grid, dt, (1, 2, 3), formulation=formulation, engine="direct")
        for n, d in enumerate(fields):
            if formulation == "product":
                fp = {c: a.copy() for c, a in pair.predict(d).items()}
                fh = half.predict(d)
                for c in d:
                    np.testing.assert_array_equal(fh[c], 2.0 * fp[c])
                if n == 0:       # the first step has no corrector (f_0 = 0)
                    continue
                fp, fh = pair.correct(d), half.correct(d)
            else:
                fp = {c: a.copy() for c, a in pair.functional(d, d).items()}
                fh = half.functional(d, d)
            for c in d:
                np.testing.assert_array_equal(fh[c], 2.0 * fp[c])


def test_a_half_space_face_has_the_static_stiffness_of_elasticity():
    """Anti-plane: a face displacement u3 = U cos(k x1) held still is answered by
    tau = mu dot du3/dx2 at x2 = 0 = -mu |k| u3 (u3 = U cos(k x1) exp(-|k| x2)); the
    convolution reaches it as int_0^T C_III -> 1, the tail falling as T^(-3/2)."""
    dt = 0.5 * PLANE.dx_min / MAT.cs
    half = HalfSpace(MAT, PLANE, dt, (3,), formulation="displacement", engine="direct")
    k = 2 * np.pi * 3 / PLANE.L1
    u = {3: np.cos(k * PLANE.x1)[:, None]}
    for _ in range(800):
        f = half.functional(u)
    T = k * MAT.cs * dt * 800
    assert T > 100
    np.testing.assert_allclose(f[3], -MAT.mu * k * u[3], atol=2e-3 * MAT.mu * k)


def test_the_pair_takes_the_radiation_damping_of_eq4():
    pair = interface((MAT, MAT), PLANE, 0.01, (1, 2, 3))
    a = MAT.cd / MAT.cs
    assert pair.eta[1] == pytest.approx(MAT.mu / (2 * MAT.cs), rel=1e-15)
    assert pair.eta[2] == pytest.approx(MAT.mu * a / (2 * MAT.cs), rel=1e-15)
    # a uniform load on a traction-free plane: v = tau0 / eta at once (the q = 0 mode has no history)
    grid = Grid(n1=8, n3=8, L1=1.0, L3=1.0)
    run = simulate(scene(grid=grid, loading=Loading(tau0_2=0.7), t_end=0.02,
                         record=Record(fields=("v_2",), every=1)))
    np.testing.assert_allclose(run["v_2"].values[1:], 0.7 / pair.eta[2], rtol=1e-12)


def test_toml_takes_one_material_or_the_two_sides():
    text = scene().to_toml()
    head, rest = text.split("[material]\n", 1)
    body, tail = rest.split("\n\n", 1)
    pair = head + f"[materials.top]\n{body}\n\n[materials.bottom]\n{body}\n\n" + tail
    assert scenes_equal(Scene.from_toml(pair), scene())
    with pytest.raises(InputError) as err:
        Scene.from_toml(pair.replace("[materials.bottom]\nmu = 2.0", "[materials.bottom]\nmu = -2.0"))
    assert err.value.field == "materials.bottom.mu"
    with pytest.raises(InputError) as err:
        Scene.from_toml(head + f"[materials.top]\n{body}\n\n" + tail)
    assert err.value.field == "materials"


def test_auto_takes_a_scheme_the_pair_of_materials_runs():
    """Numerics() (formulation "auto") on two different materials in mode I: the interface
    runs the product schemes only, so "auto" takes the product scheme, not the displacement
    scheme it takes for one material; an explicit scheme the pair does not run is refused
    with the accepted ones named."""
    other = Material(mu=1.0, cs=1.0, nu=0.25)
    sc = scene(material=None, materials=(other, MAT))
    assert sc.numerics.formulation == "auto" and sc.formulation == "product"
    assert sc.components == (2,)
    assert np.isfinite(simulate(sc).delta_2.values).all()
    for name in ("displacement", "velocity"):
        with pytest.raises(InputError) as err:
            sc.replace(numerics=Numerics(formulation=name))
        assert err.value.field == "numerics.formulation"
        assert f"got {name!r}" in str(err.value) and "'product' or 'product2'" in str(err.value)
    assert sc.replace(numerics=Numerics(formulation="product2")).formulation == "product2"
    assert Bimaterial.auto_scheme("displacement") == "product" and Bimaterial.auto_scheme("product2") == "product2"


@pytest.mark.parametrize("loading, expected", [(Loading(tau0_2=1.0), "displacement"),
                                               (Loading(tau0_1=1.0), "product"),
                                               (Loading(tau0_3=1.0), "product")])
def test_auto_on_one_material_is_unchanged(loading, expected):
    """One material: "auto" is the displacement scheme in mode I, product with shear
    (the interface of one material runs every scheme)."""
    sc = scene(loading=loading)
    assert sc.formulation == expected
    assert Identical.auto_scheme(expected) == expected
