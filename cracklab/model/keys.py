"""What every TOML key of a scene outside ``[law]`` means: its unit kind, its accepted
range and a one-line meaning. The laws declare theirs with their parameters
(``laws.base.parameter``). docs/tools/toml_page.py writes docs/reference/toml.md from both, and
tests/docs/test_toml_page.py holds them true: every key of the dataclasses is here, and
each value listed in ``refused`` is refused by the scene's validation with an InputError
naming that key.

Unit kinds are those of ``laws.base.UNITS`` ("stress", "length", "velocity", "time", "1":
a pure number, in the scene's ``[units]``; "stiffness", stress per length), or "-" for what is not a quantity (a name,
a count, a switch).
"""
from __future__ import annotations

from dataclasses import dataclass

from ..errors import SCALE_RANGE
from ..history import ENGINES
from .grid import MAX_NODES, MAX_NODES_PER_AXIS
from .loading import TIME_FUNCTIONS
from .record import FIELDS
from .scene import FORMULATIONS, MAX_FFT_THREADS
from .sequence import PAIRS, RESPONSES

INF = float("inf")
NAN = float("nan")


@dataclass(frozen=True)
class Key:
    """One TOML key: its unit kind, accepted range, meaning, and values its checks refuse."""

    unit: str
    accepted: str
    doc: str
    refused: tuple = ()


def _choices(values) -> str:
    return ", ".join(f'"{v}"' for v in values)


SCALE = f"> 0, in {SCALE_RANGE}"
FAST = f"an even fast FFT size 2^a 3^b 5^c 7^d, 2 .. {MAX_NODES_PER_AXIS}"

#: the top-level keys of a scene file
TOP_KEYS = {
    "name": Key("-", "a string", "the scene's name (the output's attr `scene`)", (1.0,)),
    "t_end": Key("time", f"{SCALE}; at least one and at most 1e8 time steps", "duration of the run",
                 (0.0, -1.0, INF, "1")),
    "beta": Key("1", "(0, the stable limit of the scheme on the grid at nu] (docs/reference/stability.md)",
                "time-step factor, dt = beta min(dx1, dx3) / cs; default min(0.5, the limit)", (0.0, -0.5, 10.0)),
}

#: {section: {key: Key}} of the sections other than [law]
SECTION_KEYS = {
    "material": {
        "mu": Key("stress", SCALE, "shear modulus", (0.0, -1.0, INF)),
        "cs": Key("velocity", SCALE, "shear wave speed", (0.0, -1.0, INF)),
        "nu": Key("1", "(-1, 0.5)", "Poisson ratio", (0.5, -1.0, 0.7)),
    },
    "grid": {
        "n1": Key("-", FAST, "nodes along x1", (0, 7, 22, 2 * MAX_NODES_PER_AXIS, 16.0)),
        "n3": Key("-", f"{FAST}, or 1 (the plane problem); n1 n3 <= {MAX_NODES}", "nodes along x3 "
                  "(with free_surface: intervals, n3 + 1 nodes)", (0, 7, 22, 16.0)),
        "L1": Key("length", SCALE, "period along x1: x1_i = i L1 / n1", (0.0, -1.0, INF)),
        "L3": Key("length", SCALE, "period along x3: x3_k = k L3 / n3 (with free_surface: the depth)",
                  (0.0, -1.0, INF)),
        "free_surface": Key("-", "true or false (3D only)", "a free surface on x3 = 0 by mirror symmetry; the "
                            "grid is then the half plane x3 in [0, L3]", ("yes", 1)),
    },
    "loading": {
        **{f"tau0_{c}": Key("stress", "finite", f"traction on component {c} if the plane were welded "
                            + ("(opening: tension > 0)" if c == 2 else "(shear)"), (INF, NAN, "1"))
           for c in (1, 2, 3)},
        "time": Key("-", _choices(TIME_FUNCTIONS), "time function of the load: H(t), min(t / ramp_time, 1), "
                    "or the C1 ramp 3 s^2 - 2 s^3", ("sudden",)),
        "ramp_time": Key("time", f">= 0 (> 0 for \"ramp\" and \"smooth\"), in {SCALE_RANGE} or 0",
                         "duration of the ramp", (-1.0, INF)),
        "constant_K": Key("-", "true or false", "scale the load by sqrt(l0 / l(t)), l the mean crack length "
                          "(a constant nominal K)", (1,)),
        "l0": Key("length", SCALE, "initial mean crack length of constant_K (default: measured from the law's "
                  "initial crack)", (0.0, -1.0)),
        "nucleation_dtau_1": Key("stress", "finite", "forced nucleation's peak shear perturbation along x1 "
                                 "(TPV101-104)", (INF,)),
        "nucleation_dtau_3": Key("stress", "finite", "forced nucleation's peak shear perturbation along x3", (INF,)),
        "nucleation_radius": Key("length", SCALE, "radius R of the nucleation patch", (0.0, -1.0)),
        "nucleation_time": Key("time", ">= 0", "time T over which the nucleation grows", (-1.0,)),
        "nucleation_x1": Key("length", "finite", "centre of the nucleation patch, x1", (INF,)),
        "nucleation_x3": Key("length", "finite", "centre of the nucleation patch, x3", (INF,)),
    },
    "record": {
        "fields": Key("-", f"names among {', '.join(FIELDS)}, or a state variable of the law; computed by "
                      "the scene", "grid fields to record ([] for none; absent: the slip of every active component, delta_2 in mode I)", (["speed"],)),
        "every": Key("-", "an integer >= 1 (at most 1e7 snapshots)", "record every this many steps "
                     "(default: about 20 snapshots)", (0, 2.5)),
        "times": Key("time", "in [0, t_end]; not with every", "record at these times", ([-1.0], ["a"])),
        "region": Key("length", "{x1 = [lo, hi], x3 = [lo, hi]}, lo <= hi, holding a node",
                      "record the fields on this sub-region only", ({"x1": [0.9, 0.1]}, {"x2": [0.0, 1.0]})),
        "stations": Key("length", "{name = [x1, x3]} (or [x1] in 2D), inside the grid", "time series every step "
                        "at these points", ({"s": [1e9, 0.0]}, {"s": [0.0, 0.0, 0.0]})),
    },
    "numerics": {
        "formulation": Key("-", '"auto", ' + _choices(FORMULATIONS),
                           "time scheme; auto: product with a shear component, displacement otherwise "
                           "(docs/reference/stability.md)", ("implicit",)),
        "engine": Key("-", '"auto", ' + _choices(sorted(ENGINES)), "history engine; auto: exponential, direct "
                      "with a window (docs/reference/fast_engine.md)", ("fast",)),
        "window": Key("1", f"{SCALE}; engine direct or auto", "truncate the history at T = q cs t (absent: the "
                      "whole history)", (0.0, -1.0)),
        "rupture_threshold": Key("velocity", f">= 0, in {SCALE_RANGE} or 0", "a point has failed when its slip "
                                 "rate first exceeds this (the output's rupture_time)", (-1.0,)),
        "fft_threads": Key("-", f"an integer, 1 .. {MAX_FFT_THREADS}", "threads of the FFTs (and of the engine without "
                           "engine_threads)", (0, 2000, 1.5)),
        "engine_threads": Key("-", f"an integer, 1 .. {MAX_FFT_THREADS}", "threads of the history engine (absent: as "
                              "fft_threads)", (0, 1.5)),
    },
    "sequence": {
        "response": Key("-", _choices(RESPONSES), "the elastic response: \"quasi_dynamic\" (the static one plus "
                        "radiation damping) or \"dynamic\" (the full history, exact at a variable step)", ("qd", 1)),
        "plate_rate_1": Key("velocity", f">= 0, in {SCALE_RANGE} or 0; this or plate_rate_3 > 0", "plate rate along x1",
                            (-1e-9, NAN)),
        "plate_rate_3": Key("velocity", f">= 0, in {SCALE_RANGE} or 0", "plate rate along x3", (-1e-9, INF)),
        "creep": Key("-", "a mask; not the whole plane", "points that creep at the plate rate (kinematic)",
                     (1.5,)),
        "stiffness": Key("stiffness", f">= 0, in {SCALE_RANGE} or 0", "spring on the mean slip: tau += k "
                         "(V_p t - mean slip)", (-1.0,)),
        "tolerance": Key("1", "in (0, 1)", "relative error of a step: slip against L + |slip|, state against a",
                         (0.0, 1.5)),
        "dt_min": Key("time", f"{SCALE}; <= dt_max", "smallest step (absent: 1e-3 dx / cs); a step that cannot meet "
                      "the tolerance at it stops the run", (0.0,)),
        "dt_max": Key("time", f"{SCALE}; >= dt_min", "largest step (absent: t_end / 50)", (-1.0,)),
        "dt_first": Key("time", f"{SCALE}; in [dt_min, dt_max]", "first step tried (absent: dx / cs)", (0.0,)),
        "pair": Key("-", _choices(PAIRS), "embedded Runge-Kutta pair (orders 5 and 3)", ("euler",)),
        "slow_rate": Key("velocity", f">= 0, in {SCALE_RANGE} or 0", "dynamic response: the pair steps while the "
                         "largest slip rate is below this (absent: 0.1 of the least sigma a / eta; 0: never)",
                         (-1.0,)),
        "event_threshold": Key("velocity", SCALE, "an event lasts while the largest slip rate exceeds this", (0.0,)),
        "slow_interval": Key("time", SCALE, "fields recorded this often between events (absent: t_end / 100)", (0.0,)),
        "fast_interval": Key("time", SCALE, "fields recorded this often during events (absent: 100 dx / cs)", (0.0,)),
        "station_every": Key("-", "an integer >= 1", "stations and the largest slip rate every this many accepted "
                             "steps", (0, 1.5)),
        "mirror": Key("-", "true or false; every field even about x1 = 0", "the plane is even about x1 = 0 (a free "
                      "surface of the plane problem, the grid holding the fault and its image): the traction is made "
                      "exactly even before each solve", (1, "yes")),
    },
}

#: the [units] table: all three keys or none (default: "1" each, a dimensionless scene)
UNIT_KEYS = {
    "length": Key("-", "a UDUNITS unit of length (\"m\", \"km\", \"mm\", ...) or \"1\"",
                  "unit of lengths (and so of x1, x3 in the output), e.g. \"m\"", (1.0, "banana", "Pa", "m @ 5")),
    "time": Key("-", "a UDUNITS unit of time (\"s\", \"ms\", ...) or \"1\"", "unit of times, e.g. \"s\"",
                (1.0, "banana", "m", "s since 2000-01-01")),
    "stress": Key("-", "a UDUNITS unit of stress (\"Pa\", \"kPa\", \"MPa\", \"GPa\", ...) or \"1\"",
                  "unit of stresses, e.g. \"Pa\"", (1.0, "banana", "m", "-1 Pa")),
}

#: the keys of a file reference, ``{ file = "x.nc", var = "tau_c" }``
FILE_KEYS = {
    "file": Key("-", "a path, relative to the scene file's directory: .nc (netCDF), .zarr (Zarr), .npy",
                "the file holding the field"),
    "var": Key("-", "a variable of the file (netCDF and Zarr only)", "the variable on dims (x1, x3) whose x1, "
               "x3 coordinates are the grid's nodes"),
}
