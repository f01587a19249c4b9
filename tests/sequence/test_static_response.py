"""The quasi-dynamic response (solver/sequence/static.py) against the static traction of a
slip mode between two identical half spaces in closed form: -mu q / 2 for antiplane
slip, -mu q / (2 (1 - nu)) in plane, and the 3D pair with its coupling nu k m / (1 - nu);
a free surface as the doubled cell; the spring on the mean slip."""
import numpy as np
import pytest

MU, NU = 30e9, 0.25


def material():
    from cracklab import Material

    return Material(mu=MU, cs=3000.0, nu=NU)


def rel(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


@pytest.mark.parametrize("c, factor", [(3, 1.0), (1, 1.0 / (1 - NU))])
def test_plane_modes(c, factor):
    from cracklab import Grid
    from cracklab.solver.sequence.static import StaticResponse

    g = Grid(n1=64, n3=1, L1=640.0, L3=1.0)
    q = 2 * np.pi * 5 / 640.0
    d = (np.cos(q * g.x1) + 0.25)[:, None]
    t = StaticResponse(material(), g, (c,), stiffness=2e6).traction({c: d})[c]
    assert rel(t, -MU * q / 2 * factor * (d - 0.25) - 2e6 * 0.25) < 1e-12


@pytest.mark.parametrize("free_surface", [False, True])
def test_the_3d_shear_pair(free_surface):
    from cracklab import Grid
    from cracklab.solver.sequence.static import StaticResponse

    g = Grid(n1=32, n3=16, L1=32.0, L3=16.0, free_surface=free_surface)
    X1, X3 = np.meshgrid(g.x1, g.x3, indexing="ij")
    k, m = 2 * np.pi * 2 / 32, 2 * np.pi / 16 * (0.5 if free_surface else 1.0)
    q = np.hypot(k, m)
    d1 = np.cos(k * X1) * np.cos(m * X3)
    t = StaticResponse(material(), g, (1, 3)).traction({1: d1, 3: 0 * d1})
    assert rel(t[1], -MU / (2 * q) * (k * k / (1 - NU) + m * m) * d1) < 1e-12
    assert rel(t[3], MU / (2 * q) * NU / (1 - NU) * k * m * np.sin(k * X1) * np.sin(m * X3)) < 1e-12


def test_it_is_the_long_time_limit_of_the_dynamic_response():
    """A slip ramped up and held: the displacement scheme's traction tends to the static
    one (the history's integral of C_III), to 1e-3 after T = q c_s t = 400."""
    from cracklab import Grid
    from cracklab.solver.halfspace import HalfSpace
    from cracklab.solver.sequence.static import StaticResponse

    g = Grid(n1=16, n3=1, L1=16.0, L3=1.0)
    mat = material()
    q = 2 * np.pi / 16.0
    dt = 0.25 / mat.cs
    d = np.cos(q * g.x1)[:, None]
    hs = HalfSpace(mat, g, dt, (3,), scale=0.5, formulation="displacement", engine="exponential")
    steps = int(400 / (q * mat.cs * dt))
    f = None
    for n in range(steps):
        f = hs.functional({3: d * min(1.0, n / 10)}, n)
    static = StaticResponse(mat, g, (3,)).traction({3: d})[3]
    assert rel(f[3], static) < 1e-3
