"""Static limits of dynamic runs: penny-shaped crack (Sneddon) and the plane periodic
row of cracks (ERRATA section 5). The load rises smoothly (C1 ramp) so that the run ends
near equilibrium; the comparison is at the end of the run."""
import numpy as np
import pytest
from verification import check

from cracklab import Loading, Record, simulate
from cracklab.analysis.exact import penny_opening, periodic_row_opening
from cracklab.scenes import elliptical_crack, periodic_cracks


def smooth(load, comp, ramp):
    return Loading(**{f"tau0_{comp}": load.field(comp)}, time="smooth", ramp_time=ramp)


def test_penny_crack_reaches_sneddon():
    """Centre opening within 2% of Sneddon's for the area-equivalent radius of the
    staircase crack (12.8 cells; periodic images at 10 radii change it by ~0.1%)."""
    n, c, t_end = 128, 0.1, 1.5
    scene = elliptical_crack(n=n, a=c, b=c, t_end=t_end, record=Record(fields=("delta_2",), times=(t_end,)))
    c_eff = np.sqrt(np.count_nonzero(~scene.law.bonded) / np.pi) * scene.grid.dx1
    ds = simulate(scene.replace(loading=smooth(scene.loading, 2, 1.0)))
    centre = float(ds.delta_2.isel(t=-1).sel(x1=0.5, x3=0.5, method="nearest"))
    exact = penny_opening(0.0, c_eff, 1.0, 1.0, 0.25)
    check("penny", abs(centre / exact - 1), f"centre {centre!r}, exact {exact!r}")


@pytest.mark.parametrize("mode, n, beta, t_end", [("I", 512, 0.5, 3.5), ("II", 256, 0.07, 3.0),
                                                 ("III", 512, 0.5, 3.5)])
def test_periodic_row_reaches_exact_opening(mode, n, beta, t_end):
    """Mode II runs at the small beta of its measured stable range (cracklab.stability)."""
    c = 0.25
    comp = {"I": 2, "II": 1, "III": 3}[mode]
    scene = periodic_cracks(n=n, c=c, mode=mode, t_end=t_end, beta=beta,
                            record=Record(fields=(f"delta_{comp}",), times=(t_end,)))
    ds = simulate(scene.replace(loading=smooth(scene.loading, comp, t_end - 1.0)))
    d = ds[f"delta_{comp}"].isel(t=-1, x3=0).values
    x = scene.grid.x1 - 0.5
    # the crack covers the nodes |x| <= c: its half length on the grid is half their count
    c_eff = (np.count_nonzero(np.abs(x) <= c) / 2) * scene.grid.dx1
    exact = periodic_row_opening(x, c_eff, 1.0, 1.0, 1.0, 0.25, mode)
    inner = np.abs(x) <= 0.5 * c
    err = np.max(np.abs(d[inner] - exact[inner])) / exact.max()
    check(f"periodic-{mode}", err, f"mode {mode}: max error {err:.4f} of the peak opening")
