"""The SEAS benchmarks (the SCEC/USGS Sequences of Earthquakes and Aseismic Slip exercise,
Erickson et al. 2020, Seismol. Res. Lett. 91; Jiang et al. 2022, J. Geophys. Res. 127): BP1,
an antiplane strike-slip fault in a half space, and BP5, a 3D strike-slip fault below a free
surface with a velocity-weakening patch and a nucleation zone, as sequence scenes
(cracklab.model.sequence), with their stations named as SEAS names them; SI units."""
from __future__ import annotations

import numpy as np

from ..errors import InputError, check_positive
from ..laws import RateState
from ..model.grid import Grid, accepted_size
from ..model.loading import Loading
from ..model.material import Material
from ..model.record import Record
from ..model.scene import Scene
from ..model.sequence import Sequence
from .common import check_stations, spacing_grid

YEAR = 365.0 * 24.0 * 3600.0     # s, as SEAS counts years

#: BP1's on-fault stations: depths in km (SEAS names them fltst_dp<depth in 100 m>)
BP1_DEPTHS = (0.0, 2.5, 5.0, 7.5, 10.0, 12.5, 15.0, 17.5, 20.0, 25.0, 30.0, 35.0)

#: BP1's parameters (Erickson et al. 2020, Table 1)
BP1 = {"rho": 2670.0, "cs": 3464.0, "sigma_n": 50e6, "a0": 0.010, "a_max": 0.025, "b0": 0.015, "D_c": 0.008,
       "V_p": 1e-9, "V_init": 1e-9, "V0": 1e-6, "f0": 0.6, "H": 15e3, "h": 3e3, "W_f": 40e3}


def steady_prestress(p, a, V, V_state, eta):
    """The SEAS initial shear stress: the traction under which a point of direct effect ``a``
    slides at V with the state of steady sliding at ``V_state``,
    sigma_n a asinh[V / (2 V0) exp((f0 + b0 ln(V0 / V_state)) / a)] + eta V, with sigma_n,
    V0, f0 and b0 of the benchmark's parameters ``p`` (BP1, BP5)."""
    return p["sigma_n"] * a * np.arcsinh(V / (2 * p["V0"]) * np.exp(
        (p["f0"] + p["b0"] * np.log(p["V0"] / V_state)) / a)) + eta * V


def seas_sequence(dynamic, tolerance, V_p, creep, mirror=False, pair="dormand_prince"):
    """A SEAS benchmark's Sequence: the plate rate V_p along x1 or x3 (``V_p`` = {component:
    rate}), the ``creep`` mask, fields every 5 years between events and every second during
    them (0.1 s in the fully dynamic response, ``dynamic``), steps of at most a year;
    ``mirror``: the plane even about x1 = 0 (Sequence.mirror); ``pair``: Sequence.pair."""
    return Sequence(response="dynamic" if dynamic else "quasi_dynamic",
                    **{f"plate_rate_{c}": v for c, v in V_p.items()}, creep=creep, tolerance=tolerance,
                    slow_interval=5 * YEAR, fast_interval=0.1 if dynamic else 1.0, dt_max=YEAR, mirror=mirror,
                    pair=pair)


def bp1_station_name(depth_km: float) -> str:
    return f"fltst_dp{int(round(depth_km * 10)):03d}"


def bp1_a(depth, H=BP1["H"]):
    """a(z) of BP1: a0 down to H, rising linearly to a_max over h, a_max below."""
    p = BP1
    z = np.asarray(depth, dtype=float)
    return np.where(z < H, p["a0"], np.where(z < H + p["h"], p["a0"] + (p["a_max"] - p["a0"]) * (z - H) / p["h"],
                                             p["a_max"]))


def bp1(*, dz=25.0, years=1500.0, dynamic=False, record=None, numerics=None, depth=320e3, tolerance=None,
        H=15e3, D_c=0.008, pair=None):
    """SEAS BP1-QD and BP1-FD (docs/studies/cycles.md): a vertical strike-slip fault in a half space,
    antiplane (the plane problem, slip along x3), rate-and-state friction with the ageing
    law as the benchmark states it (Erickson et al. 2020, Table 1): velocity weakening down
    to H = 15 km, the transition to a_max over h = 3 km, friction down to W_f = 40 km and
    creep at V_p = 1e-9 m/s below; tau0 uniform, the state from V_init = V_p. The free
    surface is a mirror: the grid is the periodic line x1 in [0, 2 depth) holding the
    fault and its image, at depth z = min(x1, 2 depth - x1), and records the physical half
    (``record.region``, x1 in [0, depth]); ``depth``: how deep the creeping region reaches
    (m): the periodic images of the locked fault, 2 depth apart, slow its loading (the
    first event comes 7 % later at 80 km than on an unbounded fault, 0.3 % later at the
    default 320 km; docs/studies/cycles.md). Stations ``BP1_DEPTHS`` named
    ``fltst_dp<depth in 100 m>``; slip, slip rate, traction and state recorded every 5 years
    between events and every second during them (every 0.1 s in BP1-FD; ``record`` replaces the fields and
    stations). ``dynamic``: BP1-FD, the same fault with the fully dynamic response (its
    history exact at a variable step, no step shorter than beta dz / c_s). ``pair`` and
    ``tolerance``: the embedded pair and the step's relative error (cracklab.Sequence). The
    tolerance is 1e-4 by default; the pair (None) is Bogacki-Shampine 3(2) above 1e-5 in the
    quasi-dynamic response, Dormand-Prince 5(4) otherwise: where the pair's stability sets
    the steps (events at 25 m, the slow phases) the pair of order 3 takes three rate
    evaluations a step to the other's six, and below 1e-5 the pair of order 5 takes fewer
    steps (the fully dynamic response steps events by its predictor-corrector of order 2
    and takes the pair in the slow phases). Event times within 0.01 years of Dormand-Prince
    5(4) at 1e-7 at 25 m over 1500 years (quasi-dynamic), within 0.004 years of 1e-6's at
    50 m (fully dynamic): docs/studies/cycles.md. ``H`` (the depth of the
    velocity-weakening zone, m) and ``D_c`` (m) replace the benchmark's 15 km and 8 mm, for
    parameter studies (the transition below H stays h = 3 km; H + h below W_f)."""
    dz = check_positive("dz", dz)
    H, D_c = check_positive("H", H), check_positive("D_c", D_c)
    if H + BP1["h"] >= BP1["W_f"]:
        raise InputError("H", f"must leave the 3 km transition above W_f = {BP1['W_f']:g} m: H < "
                              f"{BP1['W_f'] - BP1['h']:g}, got {H!r}")
    years = check_positive("years", years)
    tolerance = 1e-4 if tolerance is None else tolerance
    if pair is None:
        pair = "bogacki_shampine" if not dynamic and tolerance > 1e-5 else "dormand_prince"
    depth = check_positive("depth", depth)
    p = BP1
    n1 = int(round(2.0 * depth / dz))
    if not accepted_size(n1) or abs(n1 * dz - 2.0 * depth) > 1e-6 * depth:
        raise InputError("dz", f"must divide 2 depth = {2 * depth:g} m into an even fast FFT size of nodes, got "
                               f"{dz!r} ({2 * depth / dz:g} nodes); e.g. 25, 50 or 100 m at the default depth")
    if depth < p["W_f"] + 4 * dz:
        raise InputError("depth", f"must reach below W_f = {p['W_f']:g} m (a creeping region), got {depth!r}")
    grid = Grid(n1=n1, n3=1, L1=2.0 * depth, L3=1.0)
    z = np.minimum(grid.x1, 2.0 * depth - grid.x1)[:, None]
    mu = p["rho"] * p["cs"] ** 2
    mat = Material(mu=mu, cs=p["cs"], nu=0.25)
    eta = mu / (2.0 * p["cs"])
    a_max, V_init = p["a_max"], p["V_init"]
    tau0 = steady_prestress(p, a_max, V_init, V_init, eta)
    creep = z >= p["W_f"]
    law = RateState(a=bp1_a(z, H), b=p["b0"], L=D_c, V0=p["V0"], f0=p["f0"], sigma_n=p["sigma_n"], V_ini=V_init,
                    evolution="ageing")
    if record is None:
        record = Record(fields=("delta_3", "v_3", "tau_3", "psi"), region={"x1": (0.0, depth)},
                        stations={bp1_station_name(d): (1e3 * d,) for d in BP1_DEPTHS})
    seq = seas_sequence(dynamic, tolerance, {3: p["V_p"]}, creep, mirror=True, pair=pair)
    kw = {} if numerics is None else {"numerics": numerics}
    return Scene(material=mat, grid=grid, law=law, loading=Loading(tau0_3=float(tau0)), t_end=years * YEAR,
                 record=record, sequence=seq, units={"length": "m", "time": "s", "stress": "Pa"}, name="bp1", **kw)


# ---------------------------------------------------------------------------- SEAS BP5
#: BP5's parameters (Jiang & Erickson 2020, "SEAS Benchmark Problems BP5-QD and BP5-FD", the
#: supplement S02 of Jiang et al. 2022, its table of parameters; lengths in m): c_s, sigma_n,
#: the rate-and-state parameters a0, a_max, b0, D_c (D_c_nuc in the nucleation zone), V_p,
#: V_init, V0, f0; the fault's zones h_s (shallow velocity strengthening), h_t (transition), H
#: and l (the uniform velocity-weakening patch's width and length), W_f and l_f (the
#: rate-and-state fault's width and length), w (the nucleation zone's side), its initial slip
#: rate V_i, and the duration t_f (years). The description's text past its first page was not
#: at hand: the nucleation zone's place, D_c_nuc and V_i are those of its authors' set-ups
#: (Thrase's BP5-QD; tandem's BP5 takes V_i = 0.01 m/s), docs/reference/scenes.md
BP5 = {"rho": 2670.0, "cs": 3464.0, "nu": 0.25, "sigma_n": 25e6, "a0": 0.004, "a_max": 0.04, "b0": 0.03,
       "D_c": 0.14, "D_c_nuc": 0.13, "V_p": 1e-9, "V_init": 1e-9, "V_i": 0.03, "V0": 1e-6, "f0": 0.6,
       "h_s": 2e3, "h_t": 2e3, "H": 12e3, "l": 60e3, "W_f": 40e3, "l_f": 100e3, "w": 12e3, "t_f": 1800.0}

#: BP5's on-fault stations: (along strike, depth) in km, strike from the fault's centre
#: (SEAS names them fltst_strk<strike>dp<depth>, signed, in km)
BP5_STATIONS = ((-36, 0), (-16, 0), (0, 0), (16, 0), (36, 0), (-24, 10), (-16, 10), (0, 10), (16, 10), (0, 22))


def bp5_station_name(strike_km: float, depth_km: float) -> str:
    return f"fltst_strk{int(round(strike_km)):+03d}dp{int(round(depth_km)):+03d}"


def bp5_a(strike, depth):
    """a(x2, x3) of BP5 (x2 along strike from the fault's centre, x3 the depth, m): a0 on the
    velocity-weakening patch (|x2| <= l/2, h_s + h_t <= x3 <= h_s + h_t + H), a_max beyond
    h_t from it, linear in between in r = max(|x3 - h_s - h_t - H/2| - H/2, |x2| - l/2) / h_t."""
    p = BP5
    x2, x3 = np.asarray(strike, dtype=float), np.asarray(depth, dtype=float)
    r = np.maximum(np.abs(x3 - p["h_s"] - p["h_t"] - p["H"] / 2) - p["H"] / 2, np.abs(x2) - p["l"] / 2) / p["h_t"]
    return p["a0"] + np.clip(r, 0.0, 1.0) * (p["a_max"] - p["a0"])


def bp5_nucleation(strike, depth):
    """BP5's nucleation zone (a mask): the w x w square at the velocity-weakening patch's
    end, -l/2 <= x2 <= -l/2 + w, h_s + h_t <= x3 <= h_s + h_t + H (edges included)."""
    p, eps = BP5, 1e-6
    x2, x3 = np.asarray(strike, dtype=float), np.asarray(depth, dtype=float)
    top = p["h_s"] + p["h_t"]
    return ((x2 >= -p["l"] / 2 - eps) & (x2 <= -p["l"] / 2 + p["w"] + eps) & (x3 >= top - eps)
            & (x3 <= top + p["H"] + eps))


def bp5(*, dx=1000.0, years=1800.0, dynamic=False, record=None, numerics=None, tolerance=None,
        domain=(200e3, 100e3)):
    """SEAS BP5-QD and BP5-FD (Jiang & Erickson 2020, "SEAS Benchmark Problems BP5-QD and
    BP5-FD", in the supplement of Jiang et al. 2022, J. Geophys. Res. 127; parameters
    ``BP5``): a vertical strike-slip fault below a free surface, 3D (x1 along strike, x3
    the depth; slip along both), rate-and-state friction with the ageing law. The
    rate-and-state fault is l_f = 100 km along strike (|x2| <= 50 km, x2 = x1 - L1/2 from
    the fault's centre, the node x1 = L1/2) and W_f = 40 km deep; the plane outside creeps
    at V_p = 1e-9 m/s along strike (``Sequence(creep=)``). On it a(x2, x3) (``bp5_a``): a0 =
    0.004 on the velocity-weakening patch, 60 km along strike from 4 to 16 km depth
    (h_s = 2 km of velocity strengthening above it, H = 12 km wide), a_max = 0.04 beyond the
    h_t = 2 km around it, linear in between; b0 = 0.03, sigma_n = 25 MPa, V0 = 1e-6 m/s,
    f0 = 0.6, D_c = 0.14 m, 0.13 m in the nucleation zone (``bp5_nucleation``, the 12 km x
    12 km square at the patch's end x2 in [-30, -18] km). The initial state is steady
    sliding at V_init = 1e-9 m/s everywhere, psi = f0 + b0 ln(V0 / V_init); the prestress
    along strike slides at V_init, and at V_i = 0.03 m/s in the nucleation zone, under it
    (``steady_prestress``: sigma_n a asinh[V / (2 V0) exp(psi / a)] + eta V, eta = mu /
    (2 c_s)); the law takes the initial slip rate as the field ``V_ini`` (V_init, V_i in the
    zone), from which it recovers that psi. The free surface is a mirror
    (``Grid(free_surface=True)``): the grid is the half plane x3 in [0, L3] standing for the
    fault and its image above the surface; ``domain`` = (L1, L3) (m): the periodic length
    along strike and how deep the creeping region reaches (its bottom is a mirror too).
    Stations ``BP5_STATIONS`` named ``fltst_strk<strike>dp<depth>`` (km) record at every
    accepted step; slip, slip rate and traction along both components and the state on the
    rate-and-state fault every 5 years between events and every second during them (0.1 s
    in BP5-FD; ``record`` replaces the fields and stations). ``years``: the duration (the
    benchmark's 1800). ``dx``: the grid spacing (m), the benchmark's suggested 1000 m by
    default (docs/reference/scenes.md states the cost per step and the grid that runs in
    an hour here). ``dynamic``: BP5-FD (the fully dynamic response, its history exact at a
    variable step). ``tolerance``: the step's relative error (None: 1e-7 quasi-dynamic,
    1e-5 dynamic; tighter than ``bp1``'s, whose defaults were set by BP1's tolerance study)."""
    p = BP5
    years = check_positive("years", years)
    tolerance = (1e-5 if dynamic else 1e-7) if tolerance is None else tolerance
    needs = (f"must hold the {p['l_f'] / 1e3:g} km x {p['W_f'] / 1e3:g} km rate-and-state fault with creeping "
             f"plane around it (L1 >= l_f + 4 dx, L3 >= W_f + 4 dx)")
    grid = spacing_grid("bp5", dx, domain, free_surface=True, needs=needs,
                        holds=lambda L1, L3, d: L1 >= p["l_f"] + 4 * d and L3 >= p["W_f"] + 4 * d)
    x2 = (grid.x1 - grid.x1[grid.n1 // 2])[:, None]
    x3 = grid.x3[None, :]
    mu = p["rho"] * p["cs"] ** 2
    mat = Material(mu=mu, cs=p["cs"], nu=p["nu"])
    eta = mu / (2.0 * p["cs"])
    a = bp5_a(x2, x3)
    nucleation = bp5_nucleation(x2, x3)
    V_ini = np.where(nucleation, p["V_i"], p["V_init"])
    tau0 = steady_prestress(p, a, V_ini, p["V_init"], eta)
    eps = 1e-6 * grid.dx1
    creep = (np.abs(x2) > p["l_f"] / 2 + eps) | (x3 > p["W_f"] + eps)
    law = RateState(a=a, b=p["b0"], L=np.where(nucleation, p["D_c_nuc"], p["D_c"]), V0=p["V0"], f0=p["f0"],
                    sigma_n=p["sigma_n"], V_ini=V_ini, evolution="ageing")
    if record is None:
        xc = grid.x1[grid.n1 // 2]
        stations = check_stations("bp5", {bp5_station_name(s, d): (xc + 1e3 * s, 1e3 * d) for s, d in BP5_STATIONS},
                                  grid, ~creep)
        record = Record(fields=("delta_1", "delta_3", "v_1", "v_3", "tau_1", "tau_3", "psi"),
                        region={"x1": (xc - p["l_f"] / 2, xc + p["l_f"] / 2), "x3": (0.0, p["W_f"])},
                        stations=stations)
    seq = seas_sequence(dynamic, tolerance, {1: p["V_p"]}, creep)
    kw = {} if numerics is None else {"numerics": numerics}
    return Scene(material=mat, grid=grid, law=law, loading=Loading(tau0_1=tau0), t_end=years * YEAR,
                 record=record, sequence=seq, units={"length": "m", "time": "s", "stress": "Pa"}, name="bp5", **kw)
