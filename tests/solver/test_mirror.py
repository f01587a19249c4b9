"""A free surface on x3 = 0 by mirror symmetry (Grid(free_surface=True)): the half plane's
transforms against the doubled periodic cell, the response of a half space, whole runs
against the doubled whole-space run with mirrored loads and laws, and the bad inputs.

The doubled cell of a half plane n1 x (n3 + 1) is the periodic grid n1 x 2 n3 of depth
2 L3; a field f of the half plane is mirrored there as f(x3) on x3 in [0, L3] and
+-f(2 L3 - x3) beyond (even components 1, 2; odd component 3)."""
import numpy as np
import pytest
import scipy.fft as sfft

from cracklab import (Grid, InputError, Loading, Material, Numerics, Record, Scene, SlipWeakening, TractionFree,
                      simulate)
from cracklab.laws import LinearCohesive
from cracklab.model.scene_io import scene_from_dataset, scene_to_toml, scenes_equal
from cracklab.solver.halfspace import HalfSpace
from cracklab.solver.spectral import Transforms
from verification import check

MAT = Material(mu=1.0, cs=1.0, nu=0.25)
N1, N3, L1, L3 = 32, 16, 1.0, 0.5
HALF = Grid(N1, N3, L1, L3, free_surface=True)
DOUBLED = Grid(N1, 2 * N3, L1, 2 * L3)
TOL = 1e-12


def mirror(f, odd=False):
    """The doubled cell's field (n1, 2 n3) of a half-plane field (n1, n3 + 1)."""
    f = np.asarray(f)
    back = f[:, -2:0:-1]
    return np.concatenate([f, -back if odd else back], axis=1)


def rel(a, b):
    """max |a - b| / max |b| (0 when both are 0)."""
    scale = np.max(np.abs(b))
    return float(np.max(np.abs(a - b)) / scale) if scale > 0 else float(np.max(np.abs(a)))


def random_fields(rng, grid=HALF):
    f = {c: rng.standard_normal(grid.shape) for c in (1, 2, 3)}
    f[3][:, [0, -1]] = 0.0     # odd about x3 = 0 and x3 = L3
    return f


# ----------------------------------------------------------------------------- the grid
def test_grid_layout_is_the_doubled_cell_half():
    g = HALF
    assert g.shape == (N1, N3 + 1) and g.spectral_shape == (N1 // 2 + 1, N3 + 1)
    assert g.x3[0] == 0.0 and g.x3[-1] == pytest.approx(L3) and g.dx3 == DOUBLED.dx3
    assert np.array_equal(g.x3, DOUBLED.x3[:N3 + 1])
    k, m = g.wavenumbers()
    kd, md = DOUBLED.wavenumbers()
    assert np.array_equal(m[0], np.pi * np.arange(N3 + 1) / L3) or np.allclose(m[0], np.pi * np.arange(N3 + 1) / L3,
                                                                                 rtol=1e-15)
    assert np.array_equal(m, md[:N1 // 2 + 1])                        # the doubled cell's m
    assert np.array_equal(k[:, 0], np.abs(kd[:N1 // 2 + 1, 0]))       # k1 >= 0
    assert g.q_max() == DOUBLED.q_max()
    # the same number of modes as the periodic n1 x n3 grid
    plain = Grid(N1, N3, L1, L3)
    assert abs(np.prod(g.spectral_shape) - np.prod(plain.spectral_shape)) <= N1
    # nearest nodes: the surface is node 0; a point beyond L3 folds back (its image)
    assert g.nearest_node(0.1, 0.0) == (3, 0) and g.nearest_node(0.1, L3) == (3, N3)
    assert g.nearest_node(0.1, L3 + 2 * g.dx3)[1] == N3 - 2


# ----------------------------------------------------------------------------- transforms
@pytest.mark.parametrize("backend", ["scipy", "pyfftw"])
def test_transforms_are_the_doubled_cells_fft_and_invert(backend, tmp_path, monkeypatch):
    """forward = the doubled cell's FFT of the mirrored field on k1 >= 0, for an even and an
    odd component, alone or as a pair; inverse(forward(f)) = f; round-off only."""
    if backend == "pyfftw":
        pytest.importorskip("pyfftw")
    monkeypatch.setenv("CRACKLAB_CACHE", str(tmp_path))
    rng = np.random.default_rng(1)
    f = random_fields(rng)
    T, Td = Transforms(HALF, backend=backend), Transforms(DOUBLED, backend="scipy")
    h = N1 // 2 + 1
    ref = {c: Td.forward(mirror(f[c], odd=c == 3))[:h] for c in (1, 2, 3)}
    alone = {c: T.forward(f[c], component=c) for c in (1, 2, 3)}
    pair = T.forward_components({1: f[1], 3: f[3], 2: f[2]})
    for c in (1, 2, 3):
        assert alone[c].shape == HALF.spectral_shape
        assert rel(alone[c], ref[c]) < TOL and rel(pair[c], ref[c]) < TOL
        assert np.max(np.abs(T.inverse(alone[c].copy(), component=c) - f[c])) < TOL * np.max(np.abs(f[c]))
    back = T.inverse_components({c: X.copy() for c, X in pair.items()})
    for c in (1, 2, 3):
        assert np.max(np.abs(back[c] - f[c])) < TOL * np.max(np.abs(f[c]))
    assert np.all(back[3][:, [0, -1]] == 0.0)           # odd: zero on both lines
    # into work arrays, prescaled inverse
    X = {c: T.empty() for c in (1, 3)}
    y = {c: T.empty(spectral=False) for c in (1, 3)}
    T.forward_components({1: f[1], 3: f[3]}, X)
    assert all(np.array_equal(X[c], pair[c]) for c in (1, 3))
    T.inverse_components({c: X[c] * T.norm for c in X}, y, prescaled=True)
    assert all(np.max(np.abs(y[c] - f[c])) < TOL * np.max(np.abs(f[c])) for c in (1, 3))
    assert T.norm == 1.0 / (N1 * 2 * N3)


def test_the_odd_transform_is_minus_i_times_the_sine_transform():
    """The -i trick: the spectrum of the odd component is -i times the x1 FFT of its sine
    (DST-I) coefficients; of an even one, the x1 FFT of its cosine (DCT-I) coefficients."""
    rng = np.random.default_rng(2)
    f = random_fields(rng)
    T = Transforms(HALF)
    S = np.zeros(HALF.shape)
    S[:, 1:-1] = sfft.dst(f[3][:, 1:-1], type=1, axis=1)
    assert rel(T.forward(f[3], component=3), -1j * sfft.rfft(S, axis=0)) < TOL
    assert rel(T.forward(f[1], component=1), sfft.rfft(sfft.dct(f[1], type=1, axis=1), axis=0)) < TOL


def _no_nyquist_row(f):
    """f without its content on the x1-Nyquist row k1 = n1/2."""
    F = np.fft.rfft(f, axis=0)
    F[-1] = 0.0
    return np.fft.irfft(F, n=f.shape[0], axis=0)


def _reflect_x1(f):
    """f(-x1), periodically."""
    return np.roll(f[::-1], 1, axis=0)


@pytest.mark.parametrize("formulation", ["displacement", "velocity", "product"])
def test_a_half_space_answers_as_the_doubled_cell(formulation):
    """The response f_j of a half space on the half plane (3D shear and mode I, the rotation
    of Eq. 28 untouched) against the doubled cell's with mirrored fields, over a few steps:
    equal to round-off where the doubled fields carry nothing on the x1-Nyquist row. There
    the periodic FFT gives k1 the sign -pi/dx1, and the cross terms c s (C_II - C_III) of
    the rotation then break the mirror (the doubled cell's f_3 is not zero on the surface);
    the half plane takes the row's real part, which is the average of the doubled cell's
    response and that of its reflection x1 -> -x1 (which flips the sign): checked too."""
    rng = np.random.default_rng(4)
    dt = 0.3 * HALF.dx_min / MAT.cs
    comps = (1, 2, 3)

    def run(grid, steps, transform=lambda f, c: f, untransform=lambda f, c: f):
        hs = HalfSpace(MAT, grid, dt, comps, scale=0.5, formulation=formulation, engine="direct")
        out = []
        for n, fields in enumerate(steps):
            given = {c: transform(fields[c], c) for c in comps}
            if formulation == "displacement":
                f = hs.functional(given)
            elif formulation == "velocity":
                f = hs.functional(given, given)
            else:
                f = hs.predict(given)
                if n > 0:
                    f = {c: f[c].copy() for c in comps}
                    g = hs.correct(given)
                    f = {c: f[c] + g[c] for c in comps}
            out.append({c: untransform(f[c].copy(), c) for c in comps})
        return out

    steps = [random_fields(rng) for _ in range(4)]
    smooth = [{c: _no_nyquist_row(s[c]) for c in comps} for s in steps]
    for fields, nyquist in ((smooth, False), (steps, True)):
        half = run(HALF, fields)
        dbl = run(DOUBLED, fields, lambda f, c: mirror(f, c == 3), lambda f, c: f[:, :N3 + 1])
        if nyquist:  # the doubled cell and its reflection in x1 (delta_1 -> -delta_1), averaged
            sign = {1: -1.0, 2: 1.0, 3: 1.0}
            refl = run(DOUBLED, fields, lambda f, c: sign[c] * _reflect_x1(mirror(f, c == 3)),
                       lambda f, c: sign[c] * _reflect_x1(f)[:, :N3 + 1])
            # the periodic Nyquist row breaks the mirror: f_3 on the surface is not zero there
            assert max(np.max(np.abs(d[3][:, 0])) / np.max(np.abs(d[3])) for d in dbl[1:]) > 1e-3
            dbl = [{c: 0.5 * (a[c] + b[c]) for c in comps} for a, b in zip(dbl, refl)]
        for h, d in zip(half, dbl):
            for c in comps:
                assert rel(h[c], d[c]) < TOL, (formulation, nyquist, c)
            assert np.all(h[3][:, [0, -1]] == 0.0)


# ----------------------------------------------------------------------------- whole runs
FIELDS_SHEAR = ("delta_1", "delta_3", "v_1", "v_3", "tau_1", "tau_3", "slip")


def _pair(make, fields, engine="exponential"):
    """The run on the half plane and the doubled run with mirrored loads and laws; the
    largest relative difference over the recorded fields, the station series and the
    rupture time."""
    x1, x3 = np.meshgrid(HALF.x1, HALF.x3, indexing="ij")
    stations = {"surface": (0.25, 0.0), "deep": (0.3125, 0.25), "bottom": (0.75, L3)}
    runs = []
    for grid, mk in ((HALF, lambda f, odd=False: f), (DOUBLED, mirror)):
        sc = make(grid, x1, x3, mk, record=Record(fields=fields, every=1, stations=stations),
                  numerics=Numerics(engine=engine, rupture_threshold=1e-3))
        runs.append(simulate(sc))
    half, dbl = runs
    assert half.sizes["x3"] == N3 + 1 and float(half["x3"][-1]) == pytest.approx(L3)
    worst = 0.0
    for f in fields:
        worst = max(worst, rel(half[f].values, dbl[f].values[:, :, :N3 + 1]))
    for v in half.data_vars:
        if v.startswith("station_") and half[v].dtype.kind == "f" and v not in ("station_x1", "station_x3"):
            worst = max(worst, rel(half[v].values, dbl[v].values))
    rt_h, rt_d = half["rupture_time"].values, dbl["rupture_time"].values[:, :N3 + 1]
    assert np.array_equal(np.isnan(rt_h), np.isnan(rt_d))
    return worst, half


def _antiperiodic(x1):
    """+1 on the first half of the period in x1, -1 on the second: with every load and law
    odd under x1 -> x1 + L1/2 the run stays so, and the x1-Nyquist row (n1 / 2 even) stays
    empty, where the periodic cell's sign convention would break the mirror."""
    return np.where(x1 < L1 / 2, 1.0, -1.0), x1 % (L1 / 2)


def shear_scene(grid, x1, x3, mk, **options):
    """Slip weakening, 3D shear (product scheme), a nucleation patch below the surface, a
    dip load tau0_3 odd about it, a bonded zone at depth."""
    sgn, u = _antiperiodic(x1)
    patch = (np.abs(u - 0.25) <= 0.06) & (np.abs(x3 - 0.15) <= 0.08)
    tau1 = sgn * (0.7 + 0.2 * patch)
    tau3 = sgn * 0.1 * np.sin(np.pi * x3 / L3) * np.cos(4 * np.pi * u)
    law = SlipWeakening(mu_s=0.8, mu_d=0.5, D_c=mk(0.02 + 0.01 * x3), sigma_n=1.0, bonded=mk(x3 > 0.4))
    return Scene(material=MAT, grid=grid, law=law, loading=Loading(tau0_1=mk(tau1), tau0_3=mk(tau3, True)),
                 t_end=0.6, **options)


def test_3d_shear_run_equals_the_doubled_whole_space_run():
    worst, half = _pair(shear_scene, FIELDS_SHEAR)
    check("mirror-shear", worst)
    assert float(np.nanmax(np.abs(half["slip"].values))) > 0.02          # it ruptured
    assert np.all(half["tau_3"].values[:, :, 0] == 0.0)                 # free surface: tau_3 = 0 there
    assert float(np.max(np.abs(half["station_v_1"].sel(station="surface").values))) > 0  # reached the surface


def test_3d_shear_run_with_the_direct_engine():
    worst, _ = _pair(shear_scene, ("delta_1", "v_3", "tau_1"), engine="direct")
    assert worst < TOL, worst


def mode1_scene(grid, x1, x3, mk, **options):
    patch = (np.abs(x1 - 0.5) <= 0.12) & (x3 <= 0.1)
    law = LinearCohesive(tau_c=1.0, delta_c=0.02, initial_crack=mk(patch))
    return Scene(material=MAT, grid=grid, law=law, loading=Loading(tau0_2=mk(0.8 + 0.1 * np.cos(2 * np.pi * x1))),
                 t_end=0.6, **options)


def test_mode_i_run_equals_the_doubled_whole_space_run():
    worst, half = _pair(mode1_scene, ("delta_2", "v_2", "tau_2"))
    check("mirror-mode-I", worst)
    assert float(np.max(half["delta_2"].values)) > 0.0


def all_scene(grid, x1, x3, mk, **options):
    """All three components: friction that follows the normal traction (no sigma_n)."""
    sgn, u = _antiperiodic(x1)
    patch = (np.abs(u - 0.25) <= 0.06) & (np.abs(x3 - 0.15) <= 0.08)
    law = SlipWeakening(mu_s=0.8, mu_d=0.5, D_c=0.02)
    return Scene(material=MAT, grid=grid, law=law,
                 loading=Loading(tau0_1=mk(sgn * (0.7 + 0.2 * patch)), tau0_2=mk(-1.0 - 0.1 * np.cos(2 * np.pi * x3)),
                                 tau0_3=mk(sgn * 0.1 * np.sin(2 * np.pi * x3 / L3), True)),
                 t_end=0.4, **options)


def test_three_component_run_equals_the_doubled_whole_space_run():
    worst, _ = _pair(all_scene, ("delta_1", "delta_2", "delta_3", "tau_1", "tau_2", "tau_3"))
    assert worst < TOL, worst


# ----------------------------------------------------------------------------- scene data
def _scene(**changes):
    base = dict(material=MAT, grid=HALF, law=TractionFree(), loading=Loading(tau0_2=1.0), t_end=0.05,
                record=Record(fields=()))
    base.update(changes)
    return Scene(**base)


def test_the_option_round_trips_and_is_left_out_when_off():
    sc = _scene(loading=Loading(tau0_2=np.ones(HALF.shape)), law=TractionFree(),
                record=Record(stations={"faultst000dp000": (0.5, 0.0), "dp030": (0.5, 0.3)}))
    text = scene_to_toml(sc)
    assert "free_surface = true" in text
    assert scenes_equal(Scene.from_toml(text), sc)
    ds = sc.to_dataset()
    assert ds.attrs["grid.free_surface"] == "true" and ds.sizes["x3"] == N3 + 1
    assert scenes_equal(scene_from_dataset(ds), sc)
    plain = _scene(grid=Grid(N1, N3, L1, L3))
    assert "free_surface" not in scene_to_toml(plain) and "grid.free_surface" not in plain.to_dataset().attrs


def test_a_station_on_the_surface_records_its_node():
    sc = _scene(record=Record(fields=(), stations={"faultst000dp000": (0.5, 0.0), "dp": (0.5, 0.3)}))
    assert sc.record.station_nodes(HALF) == {"faultst000dp000": (16, 0), "dp": (16, 10)}


# ----------------------------------------------------------------------------- bad input
def test_a_plane_grid_refuses_the_mirror():
    with pytest.raises(InputError) as err:
        Grid(64, 1, 1.0, 1.0, free_surface=True)
    assert err.value.field == "grid.free_surface" and "3D grid" in str(err.value)
    with pytest.raises(InputError) as err:
        Grid(64, 16, 1.0, 1.0, free_surface="yes")
    assert err.value.field == "grid.free_surface"
    text = scene_to_toml(_scene(grid=Grid(N1, N3, L1, L3))).replace("[grid]\n", "[grid]\nfree_surface = true\n")
    assert scenes_equal(Scene.from_toml(text), _scene())
    with pytest.raises(InputError) as err:
        Scene.from_toml(text.replace("n3 = 16", "n3 = 1"))
    assert err.value.field == "grid.free_surface"


@pytest.mark.parametrize("shape", [(N1, N3), (N1, 2 * N3), (N1 // 2 + 1, N3 + 1)])
def test_a_field_not_on_the_half_plane_is_named(shape):
    with pytest.raises(InputError) as err:
        _scene(loading=Loading(tau0_2=np.ones(shape)))
    assert err.value.field == "loading.tau0_2"
    assert f"(n1, n3 + 1) = ({N1}, {N3 + 1})" in str(err.value) and "free surface" in str(err.value)
    with pytest.raises(InputError) as err:
        _scene(law=TractionFree(bonded=np.zeros(shape, dtype=bool)))
    assert err.value.field == "law.bonded"


def test_an_odd_load_must_vanish_on_the_mirror_lines():
    x3 = np.broadcast_to(HALF.x3, HALF.shape)
    ok = Loading(tau0_1=1.0, tau0_3=np.sin(np.pi * x3 / L3))        # 1.2e-16 at x3 = L3: round-off
    _scene(loading=ok, law=SlipWeakening(mu_s=2.0, mu_d=1.0, D_c=1.0, sigma_n=1.0))
    for bad in (np.cos(np.pi * x3 / L3), 0.5):
        with pytest.raises(InputError) as err:
            _scene(loading=Loading(tau0_1=1.0, tau0_3=bad), law=SlipWeakening(mu_s=2.0, mu_d=1.0, D_c=1.0,
                                                                              sigma_n=1.0))
        assert err.value.field == "loading.tau0_3" and "free surface" in str(err.value)


@pytest.mark.parametrize("where, field, text", [
    ({"stations": {"sky": (0.5, -0.1)}}, "record.stations.sky", "above the free surface"),
    ({"stations": {"deep": (0.5, L3 + 0.01)}}, "record.stations.deep", "outside the half plane"),
    ({"region": {"x3": (-0.3, -0.1)}}, "record.region.x3", "above the free surface"),
])
def test_a_station_or_region_above_the_surface_is_refused(where, field, text):
    with pytest.raises(InputError) as err:
        _scene(record=Record(fields=("delta_2",), **where))
    assert err.value.field == field and text in str(err.value)


@pytest.mark.parametrize("formulation", ["product", "displacement"])
def test_the_mirror_passes_give_the_numpy_numbers(monkeypatch, formulation):
    """The compiled passes of the free surface (loops.mirror_*: packing, separation and
    joining, fused with the rotation and the product scheme's predictor and corrector) give
    the numbers of the numpy path, bit for bit, in a 3D shear run and a mode I run."""
    from cracklab.solver import loops

    def run(make):
        x1, x3 = np.meshgrid(HALF.x1, HALF.x3, indexing="ij")
        fields = ("delta_1", "delta_3", "tau_1") if make is shear_scene else ("delta_2", "tau_2")
        sc = make(HALF, x1, x3, lambda f, odd=False: f, record=Record(fields=fields, every=4),
                  numerics=Numerics(formulation=formulation if make is shear_scene else "auto"))
        sc = sc.replace(t_end=0.2)
        return simulate(sc)

    for make in (shear_scene, mode1_scene):
        fused = run(make)
        with loops.python_only():
            plain = run(make)
        for f in fused.data_vars:
            if fused[f].dtype.kind == "f":
                np.testing.assert_array_equal(fused[f].values, plain[f].values, err_msg=f)
