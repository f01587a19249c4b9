"""The SCEC benchmarks: TPV3, TPV5 (a free surface by mirror symmetry), TPV6 (a bimaterial
fault under a free surface) and TPV101-TPV104 (rate-and-state friction; TPV102 and TPV104
below a free surface), with their stations named as SCEC names them.

Every builder here takes the spacing ``dx`` and the ``domain`` (L1, L3) in m and puts
round(L / dx) nodes of dx along each axis (scenes/common.py, ``spacing_grid``): a dx that
gives no even fast FFT size of nodes, or too coarse a grid for the fault, is refused as an
InputError of "dx" naming the nearest spacings that divide the domain; a dx that does not
divide the domain rounds it to n dx with a ``BuilderWarning`` naming the requested and the
actual domain (the fault, its loads and stations are placed from the hypocentre node, so
the problem is the same). A default station whose node cannot slip at the chosen grid
(outside the fault or on its bonded edge) is left out of the recording with a
``BuilderWarning`` naming it, its node and the grid (``check_stations``)."""
from __future__ import annotations

import numpy as np

from ..errors import InputError, check_positive
from ..laws import RateState, SlipWeakening
from ..model.loading import Loading
from ..model.material import Material
from ..model.record import Record
from ..model.scene import Numerics, Scene
from ..solver.interfaces import interface_type
from ..solver.stability import beta_max
from .common import check_stations, spacing_grid


def tpv3_station_name(strike: int, dip: int) -> str:
    def fmt(v):
        return ("-" if v < 0 else "") + f"{abs(v):03d}"

    return f"faultst{fmt(strike)}dp{fmt(dip)}"


#: (strike, dip) offsets from the hypocentre in units of 100 m, dip along x3, every one
#: inside the 30 km x 15 km fault (|strike| < 15 km, |dip| < 7.5 km): along strike at the
#: hypocentre's depth; along dip through it, up to 6 km (Day et al. 2005's anti-plane point;
#: the fault's edge, 7.5 km along dip, is bonded and would record zero); off both axes.
#: faultst075dp000 and faultst000dp-030 (3.0 km along dip) are the MDSBI reference's two
#: records (the MDSBI results of the SCEC/USGS benchmark); the problem is symmetric along dip, so
#: faultst000dp030 carries the same series as faultst000dp-030.
TPV3_STATIONS = [(s, 0) for s in (-120, -75, -45, 0, 45, 75, 120)] + \
    [(0, d) for d in (-60, -45, -30, 30, 45, 60)] + [(45, -45), (75, -60), (-45, 45)]


def _tpv3_cell_fraction(x, dx, half_width):
    """Fraction of the cell [x - dx/2, x + dx/2] that lies inside |x| <= half_width."""
    lo = np.maximum(x - 0.5 * dx, -half_width)
    hi = np.minimum(x + 0.5 * dx, half_width)
    return np.clip((hi - lo) / dx, 0.0, 1.0)


def tpv3(*, dx=100.0, t_end=12.0, beta=None, record=None, numerics=None, domain=(48000.0, 24000.0)):
    """SCEC TPV3 (the SCEC/USGS benchmark; docs/studies/tpv3.md): 30 km x 15 km fault
    centred in a periodic domain, slip-weakening friction, bonded outside the fault;
    SI units. Records the on-fault stations ``TPV3_STATIONS`` (named by their strike and
    dip offsets from the hypocentre in units of 100 m, all inside the fault), among them
    the reference's faultst075dp000 (7.5 km along strike) and faultst000dp-030 (3.0 km
    along dip), and the rupture time (slip rate above 1 mm/s). ``dx`` and ``domain``: see
    the module docstring (the domain must hold the fault and two cells of bonded plane
    around it).

    The square nucleation patch and the fault edge are put on the grid as MDSBI does
    with its 'box' asperities (the reference code): each node stands for the cell
    dx x dx around it and takes the area fraction of that cell inside the 3 km x 3 km
    square, so the initial shear stress is 70 + 11.6 f MPa (75.8 MPa on the nodes that
    lie exactly on the patch edge, 72.9 MPa at its corners; the patch carries exactly
    9 km^2 of overstress at any dx). Likewise a node whose cell is partly outside the
    30 km x 15 km fault has a partly infinite (i.e. infinite) strength: it is bonded.

    Time stepping without ``numerics``: ``Numerics(formulation="product2")``, the product
    scheme with the law's slip path advanced by the trapezoid rule, S_n = S_{n-1} +
    dt |v_{n-1} + v*_n|/2 (rupture times second order in dt; docs/reference/stability.md, "The order
    of a rupture front"), at beta = min(0.125, 0.95 beta_max). See docs/studies/tpv3.md."""
    grid = spacing_grid("tpv3", dx, domain, holds=lambda L1, L3, d: _holds_fault(L1, L3, d, 2.0),
                        needs="must hold the 30 km x 15 km fault with bonded plane around it (L1 >= 30 km + 2 dx, "
                              "L3 >= 15 km + 2 dx)")
    n1, n3 = grid.n1, grid.n3
    mat = Material(mu=2670.0 * 3464.0**2, cs=3464.0, nu=0.25)
    xc, zc = grid.x1[n1 // 2], grid.x3[n3 // 2]
    f1 = _tpv3_cell_fraction(grid.x1 - xc, grid.dx1, 1500.0)
    f3 = _tpv3_cell_fraction(grid.x3 - zc, grid.dx3, 1500.0)
    patch = np.outer(f1, f3)                       # area fraction of each cell in the patch
    tau0 = 70.0e6 + (81.6e6 - 70.0e6) * patch
    fault = np.outer(_tpv3_cell_fraction(grid.x1 - xc, grid.dx1, 15000.0),
                     _tpv3_cell_fraction(grid.x3 - zc, grid.dx3, 7500.0)) >= 1.0 - 1e-9
    law = SlipWeakening(mu_s=0.677, mu_d=0.525, D_c=0.40, sigma_n=120.0e6, bonded=~fault)
    if record is None:
        record = Record(fields=(), stations=check_stations("tpv3", {
            tpv3_station_name(s, d): (xc + 100.0 * s, zc + 100.0 * d) for s, d in TPV3_STATIONS}, grid, fault))
    numerics = numerics or Numerics(formulation="product2", rupture_threshold=1e-3)
    if beta is None:  # at most 0.125: the rupture times within 0.05 s at 100 m (docs/studies/tpv3.md, "Rupture time")
        beta = min(0.125, 0.95 * beta_max(grid, *numerics.scheme((1, 3)), (1, 3), nu=mat.nu))
    return Scene(material=mat, grid=grid, law=law, loading=Loading(tau0_1=tau0), t_end=t_end,
                 beta=beta,
                 record=record, numerics=numerics,
                 units={"length": "m", "time": "s", "stress": "Pa"}, name="tpv3")


# ---------------------------------------------------------------------------- SCEC TPV5
#: (strike offset from the hypocentre, depth below the free surface) in units of 100 m.
#: The first five are the MDSBI reference's records (the MDSBI results of the SCEC/USGS benchmark):
#: faultst000dp000 on the surface above the hypocentre, faultst000dp030 3 km below it,
#: faultst000dp075 the hypocentre, faultst-075dp075 and faultst075dp075 the centres of the
#: 78 MPa and 62 MPa patches. The others sample the rest of the fault (surface, deep edge).
TPV5_REFERENCE_STATIONS = [(0, 0), (0, 30), (0, 75), (-75, 75), (75, 75)]
TPV5_STATIONS = TPV5_REFERENCE_STATIONS + [(-75, 0), (75, 0), (-120, 0), (120, 0), (0, 120), (-120, 75),
                                           (120, 75), (-120, 120), (120, 120)]

#: the three 3 km x 3 km squares of TPV5 at depth 7.5 km: (strike centre in m, initial shear stress in Pa)
TPV5_PATCHES = ((0.0, 81.6e6), (-7500.0, 78.0e6), (7500.0, 62.0e6))


def _holds_fault(L1, L3, dx, cells3):
    """Whether the domain L1 x L3 holds the 30 km x 15 km fault with bonded plane around
    it on a grid of spacing dx: two cells along strike, ``cells3`` along x3 (2 for the whole
    space, 1 below a free surface)."""
    return round(L1 / dx) * dx >= 30000.0 + 2 * dx and round(L3 / dx) * dx >= 15000.0 + cells3 * dx


def _surface_fault_grid(builder, dx, domain):
    """The half plane below a free surface of ``tpv5`` and ``tpv6``: ``domain`` = (L1, L3) in
    m, holding the 30 km x 15 km fault with bonded plane around it."""
    return spacing_grid(builder, dx, domain, free_surface=True, holds=lambda L1, L3, d: _holds_fault(L1, L3, d, 1.0),
                        needs="must hold the 30 km x 15 km fault with bonded plane around it (L1 >= 30 km + 2 dx, "
                              "L3 >= 15 km + dx)")


def tpv5(*, dx=100.0, t_end=12.0, beta=None, record=None, numerics=None, domain=(48000.0, 24000.0)):
    """SCEC TPV5 (the SCEC/USGS benchmark; docs/studies/tpv5.md): TPV3's fault reaching a free
    surface, with two more stress patches; SI units.

    The free surface is the line x3 = 0 by mirror symmetry (``Grid(free_surface=True)``):
    the grid is the half plane x3 = depth in [0, L3] below it, ``domain`` = (L1, L3) with
    L1 the periodic length along strike and L3 the depth of the half plane (the line
    x3 = L3 is a mirror too, so the fault's image below it lies 2 (L3 - 15 km) from the
    fault). The fault is 30 km along strike, centred on the node x1 = L1/2 (the hypocentre's
    strike), from the surface to 15 km depth; the plane outside it is bonded. Initial shear
    stress 70 MPa along strike except in three 3 km x 3 km squares centred at 7.5 km depth:
    81.6 MPa at the hypocentre (nucleation: above the static strength 81.24 MPa), 78.0 MPa
    at strike -7.5 km and 62.0 MPa at +7.5 km. Friction, normal stress and material as
    :func:`tpv3`. Patches and fault edges are put on the grid by cell area as in ``tpv3``
    (each node takes the fraction of its dx x dx cell inside the square; a node whose cell
    leaves the fault is bonded; the surface node's cell is cut by the surface, whose image
    continues the fault, so the fault's top row slips). Records the stations
    ``TPV5_STATIONS``, named ``faultst<strike>dp<depth>`` in units of 100 m (faultst000dp000
    on the surface above the hypocentre), and the rupture time (slip rate above 1 mm/s).
    Time stepping without ``numerics`` as ``tpv3``: ``formulation="product2"`` (second
    order in dt) at beta = min(0.125, 0.95 beta_max); the first-order product scheme needed
    beta = 0.09 to keep every station's rupture time within 0.05 s of the reference at
    100 m. See docs/studies/tpv5.md."""
    grid = _surface_fault_grid("tpv5", dx, domain)
    n1 = grid.n1
    mat = Material(mu=2670.0 * 3464.0**2, cs=3464.0, nu=0.25)
    xc = grid.x1[n1 // 2]
    depth = grid.x3
    rows = _tpv3_cell_fraction(depth - 7500.0, grid.dx3, 1500.0)
    tau0 = np.full(grid.shape, 70.0e6)
    for centre, stress in TPV5_PATCHES:
        tau0 += (stress - 70.0e6) * np.outer(_tpv3_cell_fraction(grid.x1 - xc - centre, grid.dx1, 1500.0), rows)
    # the fault is |x1 - xc| <= 15 km, |x3| <= 15 km on the doubled cell: depth 0 to 15 km here
    fault = np.outer(_tpv3_cell_fraction(grid.x1 - xc, grid.dx1, 15000.0),
                     _tpv3_cell_fraction(depth, grid.dx3, 15000.0)) >= 1.0 - 1e-9
    law = SlipWeakening(mu_s=0.677, mu_d=0.525, D_c=0.40, sigma_n=120.0e6, bonded=~fault)
    if record is None:
        record = Record(fields=(), stations=check_stations("tpv5", {
            tpv3_station_name(s, d): (xc + 100.0 * s, 100.0 * d) for s, d in TPV5_STATIONS}, grid, fault))
    numerics = numerics or Numerics(formulation="product2", rupture_threshold=1e-3)
    if beta is None:  # at most 0.125, as tpv3 (docs/studies/tpv5.md, "Rupture time")
        beta = min(0.125, 0.95 * beta_max(grid, *numerics.scheme((1, 3)), (1, 3), nu=mat.nu))
    return Scene(material=mat, grid=grid, law=law, loading=Loading(tau0_1=tau0), t_end=t_end, beta=beta,
                 record=record, numerics=numerics,
                 units={"length": "m", "time": "s", "stress": "Pa"}, name="tpv5")


# ---------------------------------------------------------------------------- SCEC TPV6
#: (strike offset from the hypocentre, depth below the free surface) in units of 100 m. The
#: first five are the MDSBI reference's (the MDSBI results of the SCEC/USGS benchmark: its files
#: farstSSSdpDDD.txt and nearstSSSdpDDD.txt are the two sides of faultstSSSdpDDD).
TPV6_REFERENCE_STATIONS = [(0, 0), (-120, 0), (120, 0), (-120, 75), (120, 75)]
TPV6_STATIONS = TPV6_REFERENCE_STATIONS + [(0, 75), (-75, 75), (75, 75), (0, 120)]

#: TPV6's two sides: the near, stiff one (x2 < 0, TPV3's rock) and the far, compliant one
#: (x2 > 0: c_s and c_p 1.6 times smaller, density 1.2 times smaller)
TPV6_NEAR = Material(mu=2670.0 * 3464.0**2, cs=3464.0, nu=0.25)
TPV6_FAR = Material(mu=(2670.0 / 1.2) * (3464.0 / 1.6)**2, cs=3464.0 / 1.6, nu=0.25)


def tpv6(*, dx=100.0, t_end=12.0, beta=None, record=None, numerics=None, domain=(80000.0, 40000.0),
         materials=None):
    """SCEC TPV6 (the SCEC/USGS benchmark; docs/studies/tpv6.md): a vertical strike-slip fault
    between two materials, reaching a free surface; SI units.

    ``materials`` = (far, near): the compliant far side is the top (x2 > 0), rho 2225 kg/m^3,
    c_s 2165 m/s, c_p 3750 m/s; the near side below is TPV3's rock (2670, 3464, 6000). The
    free surface is the line x3 = 0 by mirror symmetry (``Grid(free_surface=True)``): the
    grid is the half plane x3 = depth in [0, L3], ``domain`` = (L1, L3) as in ``tpv5``; the
    default 80 km x 40 km keeps the periodic images' effect on final slip under 0.5 % at
    TPV6's and TPV7's contrasts (48 km x 24 km: up to 2.6 % and 5.4 %; docs/studies/
    tpv7_contrast.md). The
    fault is 30 km along strike centred on the node x1 = L1/2, from the surface to 15 km
    depth; the plane outside it is bonded. Initial tractions: tau0_1 = 70 MPa (the far side
    moves in +x1), 81.6 MPa in the 3 km x 3 km nucleation square centred at the hypocentre
    (strike 0, depth 7.5 km), put on the grid by cell area as in ``tpv3``; tau0_2 = -120 MPa
    (compression). Linear slip weakening, mu_s 0.677, mu_d 0.525, D_c 0.40 m, with the
    strength following the current normal traction (no sigma_n: slip changes the normal
    stress on a bimaterial fault). Records ``TPV6_STATIONS`` (``faultst<strike>dp<depth>``
    in units of 100 m, ``TPV6_REFERENCE_STATIONS`` the reference's) and the rupture time
    (slip rate above 1 mm/s); ``record`` replaces that (add the faces' fields ``u_1_top``,
    ... to record each side's motion). beta: at most 0.125 as ``tpv3``, relative to the
    near side's c_s (it sets dt). Time stepping: the scheme ``product2`` (rupture fronts at
    second order in dt, docs/reference/stability.md); ``numerics`` replaces it. ``materials`` = (top,
    bottom) replaces the pair (None: (``TPV6_FAR``, ``TPV6_NEAR``)). See docs/studies/tpv6.md."""
    grid = _surface_fault_grid("tpv6", dx, domain)
    n1 = grid.n1
    xc, depth = grid.x1[n1 // 2], grid.x3
    patch = np.outer(_tpv3_cell_fraction(grid.x1 - xc, grid.dx1, 1500.0),
                     _tpv3_cell_fraction(depth - 7500.0, grid.dx3, 1500.0))
    tau0 = 70.0e6 + (81.6e6 - 70.0e6) * patch
    # |x1 - xc| <= 15 km, |x3| <= 15 km on the doubled cell: depth 0 to 15 km here
    fault = np.outer(_tpv3_cell_fraction(grid.x1 - xc, grid.dx1, 15000.0),
                     _tpv3_cell_fraction(depth, grid.dx3, 15000.0)) >= 1.0 - 1e-9
    law = SlipWeakening(mu_s=0.677, mu_d=0.525, D_c=0.40, bonded=~fault)
    if record is None:
        record = Record(fields=(), stations=check_stations("tpv6", {
            tpv3_station_name(s, d): (xc + 100.0 * s, 100.0 * d) for s, d in TPV6_STATIONS}, grid, fault))
    numerics = numerics or Numerics(formulation="product2", rupture_threshold=1e-3)
    comps = (1, 2, 3)
    pair = (TPV6_FAR, TPV6_NEAR) if materials is None else materials
    if not isinstance(pair, (tuple, list)) or len(pair) != 2 or not all(isinstance(m, Material) for m in pair):
        raise InputError("materials", f"must be (top, bottom), two cracklab.Material, got {materials!r}")
    if beta is None:  # at most 0.125, as tpv3 (docs/studies/tpv3.md, "Rupture time"), for the side that sets dt
        fast = max(pair, key=lambda m: m.cs)
        beta = min(0.125, 0.95 * beta_max(grid, *numerics.scheme(comps, interface_type(pair)), comps, nu=fast.nu))
    return Scene(materials=tuple(pair), grid=grid, law=law,
                 loading=Loading(tau0_1=tau0, tau0_2=-120.0e6), t_end=t_end, beta=beta,
                 record=record, numerics=numerics,
                 units={"length": "m", "time": "s", "stress": "Pa"}, name="tpv6")


# ---------------------------------------------------------------------------- SCEC TPV101-104
def taper(x, W, w):
    """The tanh transition of SCEC TPV101-104, B(x; W, w): 1 for |x| <= W,
    0.5 [1 + tanh(w / (|x| - W - w) + w / (|x| - W))] for W < |x| < W + w, 0 beyond (smooth:
    every derivative vanishes at |x| = W and W + w). ``x`` a number or an array."""
    W = check_positive("W", W, allow_zero=True)
    w = check_positive("w", w)
    x = np.abs(np.asarray(x, dtype=float))
    B = np.where(x <= W, 1.0, 0.0)
    mid = (x > W) & (x < W + w)
    r = x[mid]
    with np.errstate(over="ignore"):
        B[mid] = 0.5 * (1.0 + np.tanh(w / (r - W - w) + w / (r - W)))
    return B if B.ndim else float(B)


#: SCEC's on-fault stations of TPV101-104: (along strike, depth below the top of the 15 km
#: fault), in units of 100 m; the hypocentre is faultst000dp075
TPV101_STATIONS = [(s, d) for d in (30, 75, 120) for s in ((-120, 0, 120) if d != 75 else (-90, 0, 90))]


#: depth of the hypocentre, the centre of the 15 km fault, below its top (and below the free
#: surface of TPV102 and TPV104)
TPV_HYPO_DEPTH = 7500.0


def _tpv_rate_state(name, *, dx, t_end, beta, record, numerics, domain, law, tau0, dtau0, free_surface=False):
    """The geometry, load and records TPV101-104 share. Whole space (TPV101, TPV103): the
    periodic ``domain`` with the hypocentre at its centre node. Half space (TPV102, TPV104):
    the half plane of ``domain`` = (L1, depth L3) below the free surface x3 = 0 (mirror
    symmetry), the hypocentre at the centre along strike and 7.5 km deep, so the fault's
    top is the surface. ``law`` maps the velocity-weakening box
    B(x; 15 km, 3 km) B(z; 7.5 km, 3 km) (x, z from the hypocentre) to the law."""
    deep = 2 * TPV_HYPO_DEPTH + 3000.0      # the half space reaches below the fault's transition
    grid = spacing_grid(name, dx, domain, free_surface=free_surface,
                        holds=(lambda L1, L3, d: round(L3 / d) * d >= deep) if free_surface else None,
                        needs=f"must reach below the fault and its 3 km transition (depth L3 >= {deep:g} m)")
    n1, n3 = grid.n1, grid.n3
    mat = Material(mu=2670.0 * 3464.0**2, cs=3464.0, nu=0.25)       # c_p = sqrt(3) c_s = 6000 m/s
    xc = grid.x1[n1 // 2]
    if free_surface:
        zc = TPV_HYPO_DEPTH              # x3 is the depth; the hypocentre need not lie on a node
    else:
        zc = grid.x3[n3 // 2]
    box = np.outer(taper(grid.x1 - xc, 15000.0, 3000.0), taper(grid.x3 - zc, 7500.0, 3000.0))
    loading = Loading(tau0_1=tau0, nucleation_dtau_1=dtau0, nucleation_radius=3000.0, nucleation_time=1.0,
                      nucleation_x1=float(xc), nucleation_x3=float(zc))
    # dp: depth below the top of the fault, 7.5 km above the hypocentre (x3 grows with depth)
    if record is None:   # the velocity-weakening fault, B B = 1
        record = Record(fields=(), stations=check_stations(name, {
            tpv3_station_name(s, d): (xc + 100.0 * s, zc + 100.0 * (d - 75)) for s, d in TPV101_STATIONS},
            grid, box >= 1.0))
    numerics = numerics or Numerics(formulation="auto", rupture_threshold=1e-3)
    if beta is None:
        beta = min(0.25, 0.95 * beta_max(grid, *numerics.scheme((1, 3)), (1, 3), nu=mat.nu))
    return Scene(material=mat, grid=grid, law=law(box), loading=loading, t_end=t_end, beta=beta,
                 record=record, numerics=numerics,
                 units={"length": "m", "time": "s", "stress": "Pa"}, name=name)


def _tpv101_law(box):
    return RateState(a=0.008 + 0.008 * (1.0 - box), b=0.012, L=0.02, V0=1e-6, f0=0.6, sigma_n=120e6,
                     V_ini=1e-12, evolution="ageing")


def _tpv103_law(box):
    outside = 1.0 - box
    return RateState(a=0.01 + 0.01 * outside, b=0.014, L=0.4, V0=1e-6, f0=0.6, sigma_n=120e6, V_ini=1e-16,
                     evolution="slip", f_w=0.2, V_w=0.1 + 0.9 * outside)


def tpv101(*, dx=100.0, t_end=15.0, beta=None, record=None, numerics=None, domain=(72000.0, 36000.0)):
    """SCEC TPV101 (the SCEC/USGS benchmark; docs/studies/tpv101.md): rate-and-state friction,
    ageing law, in a whole space. a = 0.008 + 0.008 (1 - B(x; 15 km, 3 km) B(z; 7.5 km, 3 km))
    (velocity weakening in the 30 km x 15 km box, strengthening outside), b 0.012, L 0.02 m,
    V0 1e-6 m/s, f0 0.6, sigma_n 120 MPa; tau0 75 MPa along strike with V_ini = 1e-12 m/s
    (the initial state slides at V_ini under it); nucleation 25 MPa F(r) G(t), R 3 km, T 1 s,
    at the hypocentre, the centre node of the periodic ``domain`` (72 km x 36 km: uguca's).
    SI units; records SCEC's on-fault stations (faultst000dp075 the hypocentre; dp the depth
    below the top of the fault, x3 growing with depth) and the rupture time (slip rate above
    1 mm/s). beta: at most 0.25."""
    return _tpv_rate_state("tpv101", dx=dx, t_end=t_end, beta=beta, record=record, numerics=numerics,
                           domain=domain, law=_tpv101_law, tau0=75e6, dtau0=25e6)


def tpv102(*, dx=100.0, t_end=15.0, beta=None, record=None, numerics=None, domain=(72000.0, 36000.0)):
    """SCEC TPV102: :func:`tpv101` (ageing law) below a free surface. The grid is the half
    plane of ``domain`` = (L1, depth L3) under the surface x3 = 0 (``Grid(free_surface=True)``,
    mirror symmetry; x3 the depth, n3 + 1 nodes along it); the hypocentre lies at the centre
    along strike, 7.5 km deep, so the velocity-weakening box reaches from the surface to
    15 km depth, its transition B(z; 7.5 km, 3 km) below to 18 km. Stations by SCEC's names
    at depth dp x 100 m (faultst000dp075 the hypocentre; each at its nearest node); the
    rupture time. L3 at least 18 km (the default 36 km: the fault's image in the mirror line
    x3 = L3 lies 36 km below it)."""
    return _tpv_rate_state("tpv102", dx=dx, t_end=t_end, beta=beta, record=record, numerics=numerics,
                           domain=domain, law=_tpv101_law, tau0=75e6, dtau0=25e6, free_surface=True)


def tpv103(*, dx=100.0, t_end=12.0, beta=None, record=None, numerics=None, domain=(72000.0, 36000.0)):
    """SCEC TPV103: rate-and-state friction, slip law with strong velocity weakening, in a
    whole space; the geometry, stations and records of :func:`tpv101`. a = 0.01 + 0.01 (1 - B B),
    b 0.014, L 0.4 m, f_w 0.2, V_w = 0.1 + 0.9 (1 - B B) m/s, V0 1e-6 m/s, f0 0.6, sigma_n
    120 MPa; tau0 40 MPa with V_ini = 1e-16 m/s; nucleation 45 MPa F(r) G(t), R 3 km, T 1 s."""
    return _tpv_rate_state("tpv103", dx=dx, t_end=t_end, beta=beta, record=record, numerics=numerics,
                           domain=domain, law=_tpv103_law, tau0=40e6, dtau0=45e6)


def tpv104(*, dx=100.0, t_end=12.0, beta=None, record=None, numerics=None, domain=(72000.0, 36000.0)):
    """SCEC TPV104: :func:`tpv103` (slip law, strong velocity weakening) below a free
    surface, with the half-plane geometry, depth convention and stations of :func:`tpv102`."""
    return _tpv_rate_state("tpv104", dx=dx, t_end=t_end, beta=beta, record=record, numerics=numerics,
                           domain=domain, law=_tpv103_law, tau0=40e6, dtau0=45e6, free_surface=True)
