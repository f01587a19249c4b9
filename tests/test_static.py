"""Static limits of dynamic runs: penny-shaped crack (Sneddon) and the plane periodic
row of cracks (ERRATA section 5). The load is ramped slowly so that the run ends near
equilibrium; the comparison is at the end of the run."""
import numpy as np
import pytest

from cracklab import Loading, Record, simulate
from cracklab.exact import penny_opening, periodic_row_opening
from cracklab.scenes import elliptical_crack, periodic_cracks


def test_penny_crack_reaches_sneddon():
    n, c = 64, 0.2
    scene = elliptical_crack(n=n, a=c, b=c, t_end=3.0, record=Record(fields=("delta_2",), times=(3.0,)))
    crack = ~scene.law.bonded
    # area-equivalent radius of the staircase crack on the grid
    c_eff = np.sqrt(crack.sum() / np.pi) * scene.grid.dx1
    scene = scene.replace(loading=Loading(tau0_2=scene.loading.tau0_2, time="ramp", ramp_time=2.0))
    ds = simulate(scene)
    centre = float(ds.delta_2.isel(t=-1).sel(x1=0.5, x3=0.5, method="nearest"))
    exact = penny_opening(0.0, c_eff, 1.0, 1.0, 0.25)
    assert abs(centre / exact - 1) < 0.02, (centre, exact)


@pytest.mark.parametrize("mode", ["I", "II", "III"])
def test_periodic_row_reaches_exact_opening(mode):
    n, c = 256, 0.25
    comp = {"I": 2, "II": 1, "III": 3}[mode]
    scene = periodic_cracks(n=n, c=c, mode=mode, t_end=8.0,
                            record=Record(fields=(f"delta_{comp}",), times=(8.0,)))
    load = scene.loading
    scene = scene.replace(loading=Loading(**{f"tau0_{comp}": load.field(comp)}, time="ramp", ramp_time=5.0))
    ds = simulate(scene)
    d = ds[f"delta_{comp}"].isel(t=-1, x3=0).values
    x = scene.grid.x1 - 0.5
    # the crack covers the nodes |x| <= c; its effective half length is half a cell longer
    c_eff = (np.count_nonzero(np.abs(x) <= c) / 2) * scene.grid.dx1
    exact = periodic_row_opening(x, c_eff, 1.0, 1.0, 1.0, 0.25, mode)
    inner = np.abs(x) <= 0.5 * c
    err = np.max(np.abs(d[inner] - exact[inner])) / exact.max()
    assert err < 0.005, f"mode {mode}: max error {err:.4f} of the peak opening"
