"""Section 4 builders: a row of tough asperities and random toughness (cracklab.scenes)."""
import numpy as np
import pytest
from scipy import ndimage

from cracklab import InputError, Record, analysis, scenes, simulate
from cracklab.model.scene_io import scenes_equal


def G0(scene, l0):
    """Nominal G0 = pi (1 - nu) tau0^2 l0 / (2 mu) of the scene's load."""
    mat = scene.material
    return np.pi * (1 - mat.nu) * scene.loading.tau0_2**2 * l0 / (2 * mat.mu)


def corr_length(g, dx, axis):
    """Lag at which the periodic autocorrelation of g along ``axis`` falls to 1/e."""
    g = g - g.mean()
    acf = np.fft.ifft2(np.abs(np.fft.fft2(g)) ** 2).real / g.size / g.var()
    rho = acf[:, 0] if axis == 0 else acf[0, :]
    k = int(np.argmax(rho < np.exp(-1)))
    return dx * (k - 1 + (rho[k - 1] - np.exp(-1)) / (rho[k - 1] - rho[k]))


# ---------------------------------------------------------------------------- asperity_row
@pytest.fixture(scope="module")
def paper():
    return scenes.asperity_row()


def test_domain_and_defaults(paper):
    g = paper.grid
    assert (g.n1, g.n3, g.L1, g.L3) == (512, 256, 2.0, 1.0)
    assert paper.beta == 0.5 and paper.law.kind == "linear_cohesive"
    assert paper.components == (2,)
    m = paper.material
    assert (m.mu, m.cs, m.nu) == (1.0, 1.0, 0.25)
    # delta_c chosen so that the static cohesive zone is 0.1 Z, 25.6 cells at 512 x 256
    # (the running crack's zone is then ~14 cells, docs/reference/scenes.md)
    R0 = scenes.cohesive_zone_size(m, 1.0, paper.law.delta_c)
    assert R0 == pytest.approx(0.1)
    assert R0 / g.dx1 == pytest.approx(25.6)


def test_asperities_area_centres_and_contrast(paper):
    g = paper.grid
    tau = paper.law.tau_c
    assert np.ndim(paper.law.delta_c) == 0            # delta_c kept
    assert set(np.unique(tau)) == {1.0, 3.0}
    labels, n = ndimage.label(tau == 3.0)
    assert n == 2
    d = 1.0 / 8
    for k in (1, 2):
        blob = labels == k
        area = blob.sum() * g.dx1 * g.dx3
        assert area == pytest.approx(np.pi * d**2 / 4, rel=0.02)
        i, j = np.nonzero(blob)
        c1, c3 = g.x1[i].mean(), g.x3[j].mean()
        assert abs(c1 - 0.578) <= g.dx1 / 2
        assert min(abs(c3 - 0.25), abs(c3 - 0.75)) <= g.dx3 / 2
        assert (g.x1[i].max() - g.x1[i].min()) == pytest.approx(d, abs=g.dx1)


def test_crack_barrier_and_load(paper):
    g, law = paper.grid, paper.law
    x1 = g.x1
    crack = law.initial_crack[:, 0]
    assert (law.initial_crack == crack[:, None]).all()       # straight across x3
    # symmetric (default): -l0 <= x1 < l0, across the periodic boundary
    np.testing.assert_array_equal(crack, (x1 < 0.25) | (x1 >= 2.0 - 0.25))
    barrier = law.bonded[:, 0]
    np.testing.assert_array_equal(barrier, (x1 >= 2.0 - 0.5) & (x1 < 2.0 - 0.25))
    assert not (law.bonded & law.initial_crack).any()
    # the barrier sits right behind the crack's back end, the front at l0 is free
    back = np.argmax(crack & (x1 > 1.0))
    assert barrier[back - 1] and not barrier[np.argmax(~crack)]
    load = paper.loading
    assert load.constant_K and load.time == "step"
    assert load.l0 == pytest.approx(crack.sum() * g.dx1)      # the initial mean crack length
    Gc = 0.5 * 1.0 * law.delta_c
    assert G0(paper, 0.25) / Gc == pytest.approx(1.25, rel=1e-12)


def test_one_sided_crack():
    sc = scenes.asperity_row(n1=64, n3=32, symmetric=False)
    x1 = sc.grid.x1
    np.testing.assert_array_equal(sc.law.initial_crack[:, 0], x1 < 0.25)
    np.testing.assert_array_equal(sc.law.bonded[:, 0], x1 >= 2.0 - 0.25)
    assert sc.loading.l0 == pytest.approx(0.25)
    assert G0(sc, 0.25) / (0.5 * sc.law.delta_c) == pytest.approx(1.25, rel=1e-12)


def test_parameters_and_uniform_case():
    sc = scenes.asperity_row(n1=128, n3=64, Z=2.0, contrast=5.0, diameter=0.5, n_asperities=4,
                             g0_ratio=1.5, tau_c=2.0, delta_c=0.05)
    g = sc.grid
    assert (g.L1, g.L3) == (4.0, 2.0)
    labels, n = ndimage.label(sc.law.tau_c == 10.0)
    assert n == 4
    assert G0(sc, 0.5) / (0.5 * 2.0 * 0.05) == pytest.approx(1.5)
    uni = scenes.asperity_row(n1=64, n3=32, asperities=False)
    assert np.ndim(uni.law.tau_c) == 0 and uni.name == "asperity_row_uniform"
    assert np.ndim(scenes.asperity_row(n1=64, n3=32, contrast=1.0).law.tau_c) == 0
    plane = scenes.asperity_row(n1=64, n3=1, asperities=False)
    assert plane.grid.plane
    custom = scenes.asperity_row(n1=64, n3=32, centres=[(1.0, 0.5)])
    labels, n = ndimage.label(custom.law.tau_c == 3.0)
    assert n == 1


@pytest.mark.parametrize("kwargs, field", [
    (dict(contrast=-1.0), "contrast"),
    (dict(n3=1), "asperities"),
    (dict(g0_ratio=200.0), "g0_ratio"),
    (dict(l0=1.9), "l0"),
    (dict(barrier_width=0.001), "barrier_width"),
    (dict(centres=[(0.1, 0.5)]), "centres"),
    (dict(n1=66), "grid.n1"),
    (dict(delta_c=-0.1), "delta_c"),
    (dict(beta=0.9), "beta"),
])
def test_bad_builder_arguments(kwargs, field):
    base = dict(n1=64, n3=32)
    base.update(kwargs)
    with pytest.raises(InputError) as err:
        scenes.asperity_row(**base)
    assert err.value.field == field, str(err.value)


# ---------------------------------------------------------------------------- random_toughness
def test_random_field_reproducible_and_seeded():
    a = scenes.random_toughness(n1=128, n3=64, seed=7)
    b = scenes.random_toughness(n1=128, n3=64, seed=7)
    c = scenes.random_toughness(n1=128, n3=64, seed=8)
    assert scenes_equal(a, b)
    assert not np.array_equal(a.law.tau_c, c.law.tau_c)
    assert np.corrcoef(a.law.tau_c.ravel(), c.law.tau_c.ravel())[0, 1] < 0.2


@pytest.mark.parametrize("distribution", ["lognormal", "normal"])
@pytest.mark.parametrize("quantity", ["tau_c", "Gc"])
def test_random_field_mean_and_contrast(quantity, distribution):
    sc = scenes.random_toughness(n1=128, n3=64, quantity=quantity, distribution=distribution,
                                 mean=2.0 if quantity == "tau_c" else 0.03, cov=0.2, seed=1)
    law = sc.law
    if quantity == "tau_c":
        field, mean = law.tau_c, 2.0
        assert np.ndim(law.delta_c) == 0
        Gc = 0.5 * field * law.delta_c
    else:
        field, mean = 0.5 * law.tau_c * law.delta_c, 0.03
        assert np.ndim(law.tau_c) == 0 and law.delta_c.shape == sc.grid.shape
        Gc = field
    assert field.mean() == pytest.approx(mean, rel=1e-12)
    assert field.std() / field.mean() == pytest.approx(0.2, rel=1e-9)
    assert field.min() > 0
    # the load: G0 = 1.25 times the mean Gc
    assert G0(sc, 0.25) / Gc.mean() == pytest.approx(1.25, rel=1e-12)
    # same geometry as asperity_row
    ref = scenes.asperity_row(n1=128, n3=64)
    np.testing.assert_array_equal(law.initial_crack, ref.law.initial_crack)
    np.testing.assert_array_equal(law.bonded, ref.law.bonded)


@pytest.mark.parametrize("covariance, tol", [("gaussian", 0.05), ("exponential", 0.10)])
def test_random_field_correlation_length(covariance, tol):
    ell = 1.0 / 32
    estimates = []
    for seed in range(4):
        sc = scenes.random_toughness(n1=512, n3=256, covariance=covariance, correlation_length=ell,
                                     distribution="normal", cov=0.1, seed=seed)
        g = sc.law.tau_c
        estimates.append(0.5 * (corr_length(g, sc.grid.dx1, 0) + corr_length(g, sc.grid.dx3, 1)))
    assert np.mean(estimates) == pytest.approx(ell, rel=tol)
    # twice the length, twice the estimate
    sc = scenes.random_toughness(n1=512, n3=256, covariance=covariance, correlation_length=2 * ell,
                                 distribution="normal", cov=0.1, seed=0)
    assert corr_length(sc.law.tau_c, sc.grid.dx1, 0) == pytest.approx(2 * estimates[0], rel=0.35)


def test_random_bad_arguments():
    for kwargs, field in [(dict(quantity="K"), "quantity"), (dict(covariance="cauchy"), "covariance"),
                          (dict(distribution="normal", cov=0.6), "cov"), (dict(seed=-1), "seed"),
                          (dict(correlation_length=0.0), "correlation_length"),
                          (dict(distribution="weibull"), "distribution")]:
        with pytest.raises(InputError) as err:
            scenes.random_toughness(n1=64, n3=32, **kwargs)
        assert err.value.field == field, str(err.value)


# ---------------------------------------------------------------------------- tiny runs
@pytest.mark.parametrize("build", [scenes.asperity_row, scenes.random_toughness])
def test_tiny_run_crack_advances(build):
    sc = build(n1=64, n3=32, t_end=0.75, record=Record(fields=("delta_2",), every=12))
    res = simulate(sc)
    rt = res.rupture_time.values
    g = sc.grid
    ahead = (g.x1 >= 0.25) & (g.x1 < 0.375)
    assert np.isfinite(rt[ahead]).all(), "rupture_time finite ahead of the initial crack, every row"
    assert np.isnan(rt[sc.law.bonded]).all(), "the barrier never moves"
    tip = analysis.front_position(res, method="opening")
    advance = tip.isel(t=-1) - tip.isel(t=0)
    assert float(advance.min()) >= 2 * g.dx1, "the crack tip (opening = delta_c) moved in every row"


def test_plane_symmetric_crack_runs_and_one_sided_arrests():
    """With the one-sided crack the static G is about G0 / 2 < Gc: it does not grow."""
    out = {}
    for sym in (True, False):
        sc = scenes.asperity_row(n1=128, n3=1, asperities=False, t_end=1.5, symmetric=sym,
                                 record=Record(fields=("delta_2",), every=48))
        tip = analysis.front_position(simulate(sc), method="opening")
        out[sym] = float(tip.isel(t=-1, x3=0) - tip.isel(t=0, x3=0))
    assert out[True] > 0.3
    assert out[False] == 0.0
