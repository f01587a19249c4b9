"""The time stepping of scenes.tpv3 and scenes.tpv5 without ``numerics``: the second-order
product scheme ("product2", docs/reference/stability.md "The order of a rupture front") at beta =
0.125, i.e. dt = 0.125 dx / c_s, inside the scheme's stable range; an explicit
``numerics`` or ``beta`` is taken as given."""
import pytest

from cracklab import Numerics, scenes
from cracklab.solver.stability import beta_max

CS = 3464.0


@pytest.mark.parametrize("build", [scenes.tpv3, scenes.tpv5])
@pytest.mark.parametrize("dx", [500.0, 1000.0])
def test_default_is_product2_at_beta_0125(build, dx):
    sc = build(dx=dx, t_end=0.5)
    assert sc.numerics.formulation == "product2" and sc.formulation == "product2"
    assert sc.numerics.rupture_threshold == 1e-3
    assert sc.beta == 0.125 and sc.dt == pytest.approx(0.125 * dx / CS, rel=1e-12)
    assert sc.beta < beta_max(sc.grid, *sc.numerics.scheme((1, 3)), (1, 3), nu=sc.material.nu)


@pytest.mark.parametrize("build", [scenes.tpv3, scenes.tpv5])
def test_explicit_numerics_and_beta_win(build):
    first = build(dx=1000.0, t_end=0.5, numerics=Numerics(formulation="product", rupture_threshold=1e-3))
    assert first.formulation == "product" and first.beta == 0.125
    disp = build(dx=1000.0, t_end=0.5, numerics=Numerics(formulation="displacement"))
    assert disp.formulation == "displacement" and disp.numerics.rupture_threshold == 0.0
    assert disp.beta < 0.125            # the displacement scheme's limit with shear is below 0.125
    small = build(dx=1000.0, t_end=0.5, beta=0.0625)
    assert small.formulation == "product2" and small.beta == 0.0625
