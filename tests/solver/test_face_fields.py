"""Each face's own motion on a bimaterial interface (Record fields u_<j>_<side>,
v_<j>_<side>; Bimaterial.face_fields): the faces' difference is the jump, a uniform
overload radiates a plane wave into each side at its own impedance, and two identical
faces through the bimaterial path move as -+ delta/2 in shear."""
import numpy as np
import pytest

import cracklab
from cracklab import Grid, InputError, Loading, Material, Numerics, Record, Scene, SlipWeakening, simulate, stations
from cracklab.laws import ConstantFriction
from cracklab.model.record import FACE_FIELDS
from cracklab.solver.interfaces import Bimaterial
from cracklab.solver.stepper import Stepper

PRODUCT = Numerics(formulation="product")
TOP = Material(mu=1.0, cs=1.0, nu=0.25)
BOTTOM = Material(mu=2.5, cs=1.4, nu=0.28)


def rupture_scene(grid, record, t_end=0.4):
    """3D slip weakening with the strength following the normal traction: a nucleation
    patch ruptures part of the plane, so slip, opening traction and the faces' normal
    motion all change."""
    x1, x3 = np.meshgrid(grid.x1, grid.x3, indexing="ij")
    r = np.hypot(x1 - 0.5, x3 - (0.0 if grid.free_surface else 0.5))
    tau0 = np.where(r < 0.12, 0.75, 0.55)
    law = SlipWeakening(mu_s=0.7, mu_d=0.4, D_c=0.01, bonded=(r > 0.4))
    return Scene(materials=(TOP, BOTTOM), grid=grid, law=law, loading=Loading(tau0_1=tau0, tau0_2=-1.0),
                 t_end=t_end, beta=0.25, record=record, numerics=PRODUCT)


@pytest.mark.parametrize("free_surface", [False, True])
def test_faces_differ_by_the_jump_at_snapshots_and_stations(free_surface):
    grid = Grid(n1=32, n3=16, L1=1.0, L3=0.5 if free_surface else 1.0, free_surface=free_surface)
    fields = ("delta_1", "delta_2", "delta_3", "v_1", "v_3") + FACE_FIELDS
    rec = Record(fields=fields, every=4, stations={"a": (0.5, 0.1), "b": (0.7, 0.25)})
    ds = simulate(rupture_scene(grid, rec))
    scale = {k: float(np.max(np.abs(ds[f"{k}_1"].values))) for k in ("delta", "v")}
    assert scale["delta"] > 1e-3                                   # it slipped
    for c in (1, 2, 3):
        for k, u in (("delta", "u"), ("v", "v")):
            diff = ds[f"{u}_{c}_top"] - ds[f"{u}_{c}_bottom"]
            jump = ds[f"{k}_{c}"] if f"{k}_{c}" in ds else 0.0 * diff
            assert float(np.max(np.abs(diff - jump))) < 1e-12 * scale[k], (u, c)
    # the faces move apart in shear (top along +x1 where delta_1 > 0) and together normally:
    # slip on a bimaterial interface moves both faces along x2
    i = np.unravel_index(np.argmax(ds.delta_1.values[-1]), ds.delta_1.shape[1:])
    assert ds.u_1_top.values[-1][i] > 0 > ds.u_1_bottom.values[-1][i]
    assert float(np.max(np.abs(ds.u_2_top.values))) > 1e-3 * scale["delta"]
    st = stations(ds)
    for c in (1, 2, 3):
        a, b = st[f"u_{c}_top"].values, st[f"u_{c}_bottom"].values
        want = st[f"delta_{c}"].values
        assert np.max(np.abs(a - b - want)) < 1e-12 * scale["delta"]
        assert np.isfinite(a).all()
    # the series at the snapshot steps are the snapshots' values at the station's node
    i, k = round(0.5 / grid.dx1), round(0.1 / grid.dx3)
    np.testing.assert_array_equal(st.u_1_top.sel(station="a").values[::4], ds.u_1_top.values[:, i, k])


def test_a_uniform_overload_radiates_into_each_side_at_its_own_impedance():
    """Uniform sliding under a uniform overload dtau = tau0 - mu_f sigma_n: each half space
    carries a plane shear wave away, tau0 - eta+ v+ = tau0 + eta- v- = mu_f sigma_n with
    eta = mu / c_s of that side, so v+ = dtau c_s+ / mu+ and v- = -dtau c_s- / mu- (the
    uniform mode, which the rotated spectra do not carry)."""
    grid = Grid(n1=8, n3=8, L1=1.0, L3=1.0)
    law = ConstantFriction(mu_f=0.5, sigma_n=1.0)
    sc = Scene(materials=(TOP, BOTTOM), grid=grid, law=law, loading=Loading(tau0_1=0.8, tau0_3=0.1), t_end=0.2,
               beta=0.3, record=Record(fields=FACE_FIELDS, every=1), numerics=PRODUCT)
    ds = simulate(sc)
    tau = np.hypot(0.8, 0.1)
    drop = (tau - 0.5) / tau                      # the slip rate is collinear with the traction
    for c, t0 in ((1, 0.8), (3, 0.1)):
        np.testing.assert_allclose(ds[f"v_{c}_top"].values[1:], drop * t0 * TOP.cs / TOP.mu, rtol=1e-12)
        np.testing.assert_allclose(ds[f"v_{c}_bottom"].values[1:], -drop * t0 * BOTTOM.cs / BOTTOM.mu, rtol=1e-12)
        t = ds.t.values
        # the trapezoid of the slip update from delta_0 = 0 at a constant rate (v_0 too)
        np.testing.assert_allclose(ds[f"u_{c}_top"].values[:, 0, 0], drop * t0 * TOP.cs / TOP.mu * t, rtol=1e-12)
    for side in ("top", "bottom"):
        assert np.max(np.abs(ds[f"v_2_{side}"].values)) < 1e-14


def _identical_run(scene):
    """(delta, v, faces' u, faces' v) after each step, through the bimaterial path with one
    material on both sides."""
    m = scene.material
    response = Bimaterial(m, m, scene.grid, scene.dt, scene.components, nsteps=scene.nsteps)
    for st in Stepper(scene, response=response):
        yield ({c: a.copy() for c, a in st.delta.items()}, {c: a.copy() for c, a in st.v.items()},
               st.faces("u"), st.faces("v"))


def test_identical_faces_antiplane_move_as_half_the_jump():
    sc = cracklab.scenes.periodic_cracks(n=64, c=0.15, mode="III", beta=0.3, t_end=0.3, numerics=PRODUCT)
    worst = 0.0
    for delta, v, u, w in _identical_run(sc):
        assert set(u) == {("top", 3), ("bottom", 3)}
        for side, s in (("top", 0.5), ("bottom", -0.5)):
            worst = max(worst, np.max(np.abs(u[side, 3] - s * delta[3])), np.max(np.abs(w[side, 3] - s * v[3])))
    scale = np.max(np.abs(delta[3]))
    assert scale > 0.1
    assert worst < 1e-13 * scale


def test_identical_faces_in_plane_split_the_slip_and_share_the_normal_motion():
    """Mode II between identical materials: u_1 is odd about the plane (+-delta_1/2) and
    u_2 even (both faces move alike, and do move: the in-plane coupling H12)."""
    sc = cracklab.scenes.periodic_cracks(n=64, c=0.15, mode="II", beta=0.3, t_end=0.3, numerics=PRODUCT)
    worst = 0.0
    for delta, v, u, w in _identical_run(sc):
        assert set(u) == {(side, c) for side in ("top", "bottom") for c in (1, 2)}
        worst = max(worst, np.max(np.abs(u["top", 1] - 0.5 * delta[1])),
                    np.max(np.abs(u["bottom", 1] + 0.5 * delta[1])),
                    np.max(np.abs(u["top", 2] - u["bottom", 2])), np.max(np.abs(w["top", 1] - 0.5 * v[1])))
    scale = np.max(np.abs(delta[1]))
    assert worst < 1e-13 * scale
    assert np.max(np.abs(u["top", 2])) > 0.05 * scale


def test_face_fields_need_two_materials_and_the_components_the_faces_carry():
    g = Grid(n1=16, n3=16, L1=1.0, L3=1.0)
    with pytest.raises(InputError, match="two different materials"):
        Scene(material=TOP, grid=g, law=ConstantFriction(mu_f=0.5, sigma_n=1.0), loading=Loading(tau0_1=0.8),
              t_end=0.1, record=Record(fields=("u_1_top",)), numerics=PRODUCT)
    plane = Grid(n1=16, n3=1, L1=1.0, L3=1.0)
    with pytest.raises(InputError, match="v_3_bottom.*not computed"):
        Scene(materials=(TOP, BOTTOM), grid=plane, law=ConstantFriction(mu_f=0.5, sigma_n=1.0),
              loading=Loading(tau0_1=0.8), t_end=0.1, record=Record(fields=("v_3_bottom",)), numerics=PRODUCT)
    with pytest.raises(InputError, match="unknown field 'u_4_top'"):
        Record(fields=("u_4_top",))
