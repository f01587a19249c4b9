"""The paper's test problems: Lamb's problem (section 3.2), the suddenly loaded elliptical
crack (section 4), and the plane problems of verification (a periodic row of cracks,
Kostrov's crack growing at a prescribed speed)."""
from __future__ import annotations

import numpy as np

from ..laws import PrescribedRupture, TractionFree
from ..model.loading import Loading, point_load
from ..model.record import Record
from ..model.scene import Numerics, Scene
from .common import UNIT, node_grid


def lamb(*, n, beta=0.5, t_end, record=None, numerics=None):
    """Lamb's problem (section 3.2): unit square, point load P = 1 at node (n//2, n//2),
    step in time, traction-free plane without contact constraint."""
    grid = node_grid("lamb", {"n1": "n", "n3": "n"}, n1=n, n3=n, L1=1.0, L3=1.0)
    load = point_load(grid, 1.0, grid.x1[n // 2], grid.x3[n // 2])
    return Scene(material=UNIT, grid=grid, law=TractionFree(contact=False), loading=Loading(tau0_2=load),
                 t_end=t_end, beta=beta, record=record or Record(fields=("delta_2",)),
                 numerics=numerics or Numerics(), name="lamb")


def ellipse_mask(grid, a, b, centre=(0.5, 0.5)):
    x1, x3 = np.meshgrid(grid.x1, grid.x3, indexing="ij")
    return ((x1 - centre[0]) / a) ** 2 + ((x3 - centre[1]) / b) ** 2 <= 1.0


def elliptical_crack(*, n, a, b, p=1.0, beta=0.5, t_end, record=None, numerics=None):
    """Suddenly loaded elliptical crack (section 4, Figs. 10-11): unit square, semi-axes
    a (x1) and b (x3) centred at (0.5, 0.5), faces under pressure p from t = 0; the
    plane outside the ellipse stays bonded."""
    grid = node_grid("elliptical_crack", {"n1": "n", "n3": "n"}, n1=n, n3=n, L1=1.0, L3=1.0)
    crack = ellipse_mask(grid, a, b)
    return Scene(material=UNIT, grid=grid, law=TractionFree(contact=True, bonded=~crack),
                 loading=Loading(tau0_2=np.where(crack, float(p), 0.0)), t_end=t_end, beta=beta,
                 record=record or Record(fields=("delta_2",)), numerics=numerics or Numerics(),
                 name="elliptical_crack")


def periodic_cracks(*, n, c, p=1.0, mode="I", beta=None, t_end, record=None, numerics=None):
    """Plane (2D) periodic row of cracks of half length c in the unit period, centred
    at x1 = 0.5, under a suddenly applied uniform load p (opening for mode I, slip for
    modes II and III); bonded outside the crack."""
    grid = node_grid("periodic_cracks", {"n1": "n"}, n1=n, n3=1, L1=1.0, L3=1.0)
    crack = (np.abs(grid.x1 - 0.5) <= c)[:, None]
    comp = {"I": 2, "II": 1, "III": 3}[mode]
    load = Loading(**{f"tau0_{comp}": np.where(crack, float(p), 0.0)})
    return Scene(material=UNIT, grid=grid, law=TractionFree(contact=False, bonded=~crack), loading=load,
                 t_end=t_end, beta=beta, record=record or Record(fields=(f"delta_{comp}",)),
                 numerics=numerics or Numerics(), name=f"periodic_cracks_{mode}")


def kostrov(*, n, speed, dtau=1.0, L=1.0, beta=None, t_end, record=None, numerics=None):
    """Plane mode III crack forced to grow from the line x1 = L/2 at ``speed``
    (prescribed rupture; stress drop dtau, zero residual strength, each node released
    over the time the tip takes to cross 1.75 cells: among release times of 0, 1, 1.25,
    1.5, 1.75 and 2 cells this one rings least at the centre; see docs/studies/verification.md)."""
    grid = node_grid("kostrov", {"n1": "n", "L1": "L"}, n1=n, n3=1, L1=L, L3=1.0)
    law = PrescribedRupture(speed=speed, origin=(grid.x1[n // 2], 0.0), residual=0.0,
                            weakening_time=1.75 * grid.dx1 / speed)
    centre = {"centre": (grid.x1[n // 2], 0.0)}
    return Scene(material=UNIT, grid=grid, law=law, loading=Loading(tau0_3=float(dtau)), t_end=t_end,
                 beta=beta, record=record or Record(fields=("delta_3",), stations=centre),
                 numerics=numerics or Numerics(), name="kostrov")
