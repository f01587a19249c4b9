"""The SEAS benchmarks (the SCEC/USGS Sequences of Earthquakes and Aseismic Slip exercise,
Erickson et al. 2020, Seismol. Res. Lett. 91): BP1, an antiplane strike-slip fault in a half
space, as a sequence scene (cracklab.model.sequence), with its stations named as SEAS names
them; SI units."""
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

YEAR = 365.0 * 24.0 * 3600.0     # s, as SEAS counts years

#: BP1's on-fault stations: depths in km (SEAS names them fltst_dp<depth in 100 m>)
BP1_DEPTHS = (0.0, 2.5, 5.0, 7.5, 10.0, 12.5, 15.0, 17.5, 20.0, 25.0, 30.0, 35.0)

#: BP1's parameters (Erickson et al. 2020, Table 1)
BP1 = {"rho": 2670.0, "cs": 3464.0, "sigma_n": 50e6, "a0": 0.010, "a_max": 0.025, "b0": 0.015, "D_c": 0.008,
       "V_p": 1e-9, "V_init": 1e-9, "V0": 1e-6, "f0": 0.6, "H": 15e3, "h": 3e3, "W_f": 40e3}


def bp1_station_name(depth_km: float) -> str:
    return f"fltst_dp{int(round(depth_km * 10)):03d}"


def bp1_a(depth, H=BP1["H"]):
    """a(z) of BP1: a0 down to H, rising linearly to a_max over h, a_max below."""
    p = BP1
    z = np.asarray(depth, dtype=float)
    return np.where(z < H, p["a0"], np.where(z < H + p["h"], p["a0"] + (p["a_max"] - p["a0"]) * (z - H) / p["h"],
                                             p["a_max"]))


def bp1(*, dz=25.0, years=1500.0, dynamic=False, record=None, numerics=None, depth=320e3, tolerance=None,
        H=15e3, D_c=0.008):
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
    history exact at a variable step, no step shorter than beta dz / c_s). ``tolerance``:
    the step's relative error (cracklab.Sequence; None: 1e-7 for the quasi-dynamic pair of
    order 5, 1e-5 for the dynamic predictor-corrector of order 2). ``H`` (the depth of the
    velocity-weakening zone, m) and ``D_c`` (m) replace the benchmark's 15 km and 8 mm, for
    parameter studies (the transition below H stays h = 3 km; H + h below W_f)."""
    dz = check_positive("dz", dz)
    H, D_c = check_positive("H", H), check_positive("D_c", D_c)
    if H + BP1["h"] >= BP1["W_f"]:
        raise InputError("H", f"must leave the 3 km transition above W_f = {BP1['W_f']:g} m: H < "
                              f"{BP1['W_f'] - BP1['h']:g}, got {H!r}")
    years = check_positive("years", years)
    tolerance = (1e-5 if dynamic else 1e-7) if tolerance is None else tolerance
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
    tau0 = p["sigma_n"] * a_max * np.arcsinh(V_init / (2 * p["V0"]) * np.exp(
        (p["f0"] + p["b0"] * np.log(p["V0"] / V_init)) / a_max)) + eta * V_init
    creep = z >= p["W_f"]
    law = RateState(a=bp1_a(z, H), b=p["b0"], L=D_c, V0=p["V0"], f0=p["f0"], sigma_n=p["sigma_n"], V_ini=V_init,
                    evolution="ageing")
    if record is None:
        record = Record(fields=("delta_3", "v_3", "tau_3", "psi"), region={"x1": (0.0, depth)},
                        stations={bp1_station_name(d): (1e3 * d,) for d in BP1_DEPTHS})
    seq = Sequence(response="dynamic" if dynamic else "quasi_dynamic", plate_rate_3=p["V_p"], creep=creep,
                   tolerance=tolerance, slow_interval=5 * YEAR, fast_interval=0.1 if dynamic else 1.0, dt_max=YEAR)
    kw = {} if numerics is None else {"numerics": numerics}
    return Scene(material=mat, grid=grid, law=law, loading=Loading(tau0_3=float(tau0)), t_end=years * YEAR,
                 record=record, sequence=seq, units={"length": "m", "time": "s", "stress": "Pa"}, name="bp1", **kw)
