import numpy as np
import pytest

from cracklab import Grid, InputError, Material
from cracklab.model.grid import is_fast_size
from cracklab.solver.spectral import Transforms


def test_material_speeds():
    m = Material(mu=2.0, cs=3.0, nu=0.25)
    assert m.a == pytest.approx(np.sqrt(3.0), rel=1e-15)
    assert m.cd == pytest.approx(3.0 * np.sqrt(3.0))
    assert m.rho == pytest.approx(2.0 / 9.0)
    assert m.cR / m.cs == pytest.approx(0.9194017, abs=1e-6)
    assert m.eta(2) == pytest.approx(2.0 * np.sqrt(3) / 6.0)
    assert m.eta(1) == m.eta(3) == pytest.approx(2.0 / 6.0)


@pytest.mark.parametrize("kwargs, field", [
    (dict(mu=-1, cs=1, nu=0.25), "material.mu"),
    (dict(mu=1, cs=0, nu=0.25), "material.cs"),
    (dict(mu=1, cs=1, nu=0.5), "material.nu"),
])
def test_material_rejects(kwargs, field):
    with pytest.raises(InputError, match=field):
        Material(**kwargs)


def test_fast_sizes():
    assert [n for n in range(2, 40) if is_fast_size(n) and n % 2 == 0] == \
        [2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 24, 28, 30, 32, 36]


@pytest.mark.parametrize("kwargs, field, text", [
    (dict(n1=100, n3=22, L1=1, L3=1), "grid.n3", "fast FFT size"),
    (dict(n1=101, n3=64, L1=1, L3=1), "grid.n1", "fast FFT size"),
    (dict(n1=-8, n3=64, L1=1, L3=1), "grid.n1", ">= 1"),
    (dict(n1=64, n3=64, L1=-1, L3=1), "grid.L1", "> 0"),
    (dict(n1=64.0, n3=64, L1=1, L3=1), "grid.n1", "integer"),
])
def test_grid_rejects(kwargs, field, text):
    with pytest.raises(InputError, match=field) as err:
        Grid(**kwargs)
    assert text in str(err.value)


def test_grid_nodes_and_wavenumbers():
    g = Grid(n1=16, n3=8, L1=2.0, L3=1.0)
    assert g.dx1 == 0.125 and g.dx3 == 0.125
    assert np.allclose(g.x1, np.arange(16) * 0.125)
    k, m = g.wavenumbers()
    assert k.shape == g.spectral_shape == (16, 5)  # real transform along x3 (contiguous)
    assert k[1, 0] == pytest.approx(2 * np.pi / 2.0)
    assert k[-1, 0] == pytest.approx(-2 * np.pi / 2.0)
    assert m[0, 1] == pytest.approx(2 * np.pi / 1.0)
    assert g.q_max() == pytest.approx(np.hypot(np.pi / 0.125, np.pi / 0.125))


@pytest.mark.parametrize("shape", [(16, 8), (32, 1)])
def test_transforms_round_trip_and_derivative(shape):
    g = Grid(n1=shape[0], n3=shape[1], L1=1.0, L3=1.0)
    f = Transforms(g)
    x1, x3 = np.meshgrid(g.x1, g.x3, indexing="ij")
    field = np.sin(2 * np.pi * 3 * x1) + (np.cos(2 * np.pi * 2 * x3) if shape[1] > 1 else 0)
    X = f.forward(field)
    assert X.shape == g.spectral_shape
    assert np.allclose(f.inverse(X), field, atol=1e-12)
    k, _ = g.wavenumbers()
    d1 = f.inverse(1j * k * X)
    assert np.allclose(d1, 2 * np.pi * 3 * np.cos(2 * np.pi * 3 * x1), atol=1e-9)


@pytest.mark.parametrize("backend", ["scipy", "pyfftw"])
@pytest.mark.parametrize("shape", [(16, 8), (32, 1)])
def test_backends_agree(backend, shape, tmp_path, monkeypatch):
    pytest.importorskip("pyfftw") if backend == "pyfftw" else None
    monkeypatch.setenv("CRACKLAB_CACHE", str(tmp_path))
    g = Grid(n1=shape[0], n3=shape[1], L1=1.0, L3=1.0)
    x = np.random.default_rng(3).standard_normal(g.shape)
    ref = Transforms(g, backend="scipy")
    f = Transforms(g, backend=backend)
    X = f.forward(x)
    np.testing.assert_allclose(X, ref.forward(x), atol=1e-12)
    Y = f.forward(2 * x)  # a second call must not overwrite the first result
    np.testing.assert_allclose(X * 2, Y, atol=1e-12)
    np.testing.assert_allclose(f.inverse(X), x, atol=1e-12)
    np.testing.assert_allclose(X, ref.forward(x), atol=1e-12)  # inverse left its input alone


def test_plans_follow_the_wisdom_file(tmp_path, monkeypatch):
    """A process that planned on its own (here under another cache) still takes the host's
    wisdom file as it stands when it plans a size the file holds: it measures nothing anew
    and leaves the file as it was, so a run and its resumption in another process use the
    same plan (tests/output/test_resume.py compares them to the bit)."""
    pyfftw = pytest.importorskip("pyfftw")
    from cracklab.solver import spectral
    def entries(wisdom):  # FFTW's wisdom as sets of entries (their order varies)
        return [set(w.decode().splitlines()) for w in wisdom]

    def on_file():  # the host's wisdom file, the only one in the cache directory
        (path,) = spectral.cache_dir().glob("fftw-wisdom-*.json")
        return entries(spectral.wisdom_from_json(path.read_text()))

    g = Grid(n1=24, n3=16, L1=1.0, L3=1.0)
    monkeypatch.setenv("CRACKLAB_CACHE", str(tmp_path / "host"))
    Transforms(g, backend="pyfftw")
    saved = on_file()
    pyfftw.forget_wisdom()
    monkeypatch.setenv("CRACKLAB_CACHE", str(tmp_path / "other"))
    Transforms(Grid(n1=20, n3=12, L1=1.0, L3=1.0), backend="pyfftw")  # wisdom of its own
    assert entries(pyfftw.export_wisdom()) != saved
    monkeypatch.setenv("CRACKLAB_CACHE", str(tmp_path / "host"))
    Transforms(g, backend="pyfftw")
    assert on_file() == saved
    assert entries(pyfftw.export_wisdom()) == saved


@pytest.mark.parametrize("backend", ["scipy", "pyfftw"])
@pytest.mark.parametrize("shape", [(16, 8), (32, 1)])
def test_transforms_into_work_arrays(backend, shape, tmp_path, monkeypatch):
    """out= and overwrite= give the same numbers as the allocating calls, bit for bit, and
    leave the plans' own arrays (and earlier results) alone."""
    pytest.importorskip("pyfftw") if backend == "pyfftw" else None
    monkeypatch.setenv("CRACKLAB_CACHE", str(tmp_path))
    g = Grid(n1=shape[0], n3=shape[1], L1=1.0, L3=1.0)
    rng = np.random.default_rng(5)
    x, y = rng.standard_normal(g.shape), rng.standard_normal(g.shape)
    f = Transforms(g, backend=backend)
    X, Y = f.forward(x), f.forward(y)
    Xo, Yo = f.empty(), f.empty()
    assert Xo.shape == g.spectral_shape and f.empty(spectral=False).shape == g.shape
    assert f.forward(x, out=Xo) is Xo and np.array_equal(Xo, X)
    f.forward(y, out=Yo)
    assert np.array_equal(Xo, X) and np.array_equal(Yo, Y)  # the second call left the first alone
    assert np.array_equal(f.forward(x), X)  # the plan still has its own arrays
    xo = f.empty(spectral=False)
    assert f.inverse(Xo, out=xo) is xo and np.array_equal(xo, f.inverse(X))
    assert np.array_equal(Xo, X)  # not overwritten without overwrite=True
    f.inverse(Yo, out=xo, overwrite=True)
    np.testing.assert_allclose(xo, y, atol=1e-12)
    assert np.array_equal(xo, f.inverse(Y))
    # an aligned input is transformed in place of a copy, and left as it was
    xa = f.empty(spectral=False)
    xa[...] = x
    assert np.array_equal(f.forward(xa, out=Xo), X) and np.array_equal(xa, x)
    # prescaled: the spectrum carries the 1/N, the inverse skips its pass for it
    assert f.norm == pytest.approx(1.0 / (shape[0] * shape[1]))
    f.inverse(X * f.norm, out=xo, prescaled=True)
    np.testing.assert_allclose(xo, x, rtol=0, atol=1e-13)
    np.testing.assert_allclose(f.inverse(X * f.norm, prescaled=True), x, rtol=0, atol=1e-13)
    with pytest.raises(ValueError, match="shape"):
        f.forward(x, out=np.empty((3, 3), dtype=complex)) if backend == "pyfftw" else (_ for _ in ()).throw(
            ValueError("shape"))
