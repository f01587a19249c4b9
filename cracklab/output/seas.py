"""A sequence run in the SEAS platform's file formats (the SCEC/USGS SEAS exercise's BP1-QD
description, Erickson & Jiang 2018, sections 4 and 5), for upload to the community
comparison: one on-fault time-series file per station (``fltst_dpXXX``: t, slip, log10
slip rate, shear stress in MPa, log10 state theta in s) and the slip evolution
``devol.dat`` (slip at depths every 500 m down to 40 km and the log10 of the largest
slip rate, at the recorded snapshots). For the plane problem with x1 the depth below the
free surface (``cracklab.scenes.bp1``), in SI units."""
from __future__ import annotations

import datetime
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..version import __version__
from .simulate import scene_of, stations

FIELDS = "t slip slip_rate shear_stress state"
COLUMNS = ("Time (s)", "Slip (m)", "Slip rate (log10 m/s)", "Shear stress (MPa)", "State (log10 s)")


def _theta(law, psi, node):
    """theta (s) of the ageing law's state psi = f0 + b ln(V0 theta / L) at the grid node
    ``node`` (docs/reference/equations.md, "Rate-and-state friction")."""
    def at(name):
        v = np.asarray(getattr(law, name), dtype=float)
        return float(v[node] if v.ndim else v)

    return at("L") / at("V0") * np.exp((psi - at("f0")) / at("b"))


def _header(problem, author, code, ds, dx):
    return [f"# problem={problem}", f"# author={author}", f"# date={datetime.date.today():%Y/%m/%d}",
            f"# code={code}", f"# code version={__version__}", f"# element size={dx:g} m",
            f"# minimum time step={ds.attrs.get('smallest_step', float('nan')):.6g}",
            f"# maximum time step={ds.attrs.get('largest_step', float('nan')):.6g}"]


def export_seas(ds, directory, *, author="", code="cracklab", problem="SEAS Benchmark No.1", depth_step=500.0,
                depth_max=40e3) -> list[Path]:
    """Write the SEAS files of the sequence run ``ds`` (its stations and its ``delta_3``
    snapshots) into ``directory``; returns the paths written."""
    scene = scene_of(ds)
    if scene.sequence is None or not scene.grid.plane or 3 not in scene.sequence.plate:
        raise InputError("ds", "the SEAS files are those of an antiplane sequence (a plane scene with sequence set "
                               "and plate_rate_3, e.g. cracklab.scenes.bp1)")
    if scene.units != {"length": "m", "time": "s", "stress": "Pa"}:
        raise InputError("units", f"the SEAS files are in SI units: the scene's must be m, s and Pa, got "
                                  f"{scene.units}")
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    head = _header(problem, author, code, ds, scene.grid.dx1)
    st = stations(ds)
    t = st.t.values
    for name in st.station.values:
        s = st.sel(station=name)
        node = scene.grid.nearest_node(float(s.x1), float(s.x3))
        with np.errstate(divide="ignore"):
            rate = np.log10(np.abs(s.v_3.values))
        data = np.column_stack([t, s.delta_3.values, rate, s.tau_3.values / 1e6,
                                np.log10(_theta(scene.law, s.psi.values, node))])
        lines = head + [f"# num time steps={len(t)}", f"# location=on fault, {float(s.x1) / 1e3:g} km depth"]
        lines += [f"# Column #{i + 1} = {c}" for i, c in enumerate(COLUMNS)]
        lines += ["#", FIELDS]
        lines += [f"{row[0]:21.13E} " + " ".join(f"{v:14.6E}" for v in row[1:]) for row in data]
        path = out / str(name)
        path.write_text("\n".join(lines) + "\n")
        written.append(path)
    # the slip evolution: depths every depth_step m, at the snapshots
    z = np.arange(0.0, depth_max + 0.5 * depth_step, depth_step)
    x1 = ds.x1.values
    idx = [int(np.argmin(np.abs(x1 - d))) for d in z]
    slip = ds.delta_3.isel(x3=0).values[:, idx]
    ts = ds.t.values
    vmax = np.interp(ts, ds.t_station.values, ds.max_slip_rate.values)
    lines = head + [f"# computational domain: the periodic line of {scene.grid.L1:g} m (the fault and its mirror "
                    f"image), creeping below {depth_max:g} m"]
    lines += ["# Column #1 = Time (s)", "# Column #2 = Max slip rate (log10 m/s)", "# Column #3 = Slip (m)",
              "z", "t max_slip_rate slip"]
    lines.append(" ".join(f"{v:14.6E}" for v in np.concatenate([[0.0, 0.0], x1[idx]])))
    with np.errstate(divide="ignore"):
        lv = np.log10(vmax)
    lines += [f"{tt:21.13E} {v:14.6E} " + " ".join(f"{d:14.6E}" for d in row) for tt, v, row in zip(ts, lv, slip)]
    path = out / "devol.dat"
    path.write_text("\n".join(lines) + "\n")
    written.append(path)
    return written
