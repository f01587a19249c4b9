"""What the scene builders share: the unit material, the check of a builder's argument, the
grid of a builder that takes a spacing, and the check of its stations."""
from __future__ import annotations

import sys
import warnings
from pathlib import Path

from ..errors import InputError, check_positive
from ..model.grid import MAX_NODES, MAX_NODES_PER_AXIS, Grid, accepted_size, is_fast_size
from ..model.material import Material

UNIT = Material(mu=1.0, cs=1.0, nu=0.25)


class BuilderWarning(UserWarning):
    """A builder changed what it was asked for (a rounded domain) or recorded less (a
    station outside the fault at this grid)."""


def _warn(message: str) -> None:
    """A BuilderWarning attributed to the first caller outside the cracklab package."""
    package = str(Path(__file__).resolve().parents[1])
    level, frame = 2, sys._getframe(1)
    while frame is not None and str(Path(frame.f_code.co_filename).resolve()).startswith(package):
        level, frame = level + 1, frame.f_back
    warnings.warn(BuilderWarning(message), stacklevel=level)


def require(name, ok, message):
    if not ok:
        raise InputError(name, message)


def node_grid(builder, names, **grid_args) -> Grid:
    """``Grid(**grid_args)`` of ``builder``, whose InputError of a grid field built from a
    builder's argument names that argument: ``names`` = {grid field: argument}, e.g.
    {"n1": "n", "n3": "n"}."""
    try:
        return Grid(**grid_args)
    except InputError as err:
        key = err.field.removeprefix("grid.")
        if key not in names:
            raise
        raise InputError(names[key], f"{str(err)[len(err.field) + 2:]} (the grid {key} = {names[key]} of "
                                     f"{builder})") from None


def _fits(n1, n3) -> bool:
    return accepted_size(n1) and accepted_size(n3) and n1 * n3 <= MAX_NODES


def _exact(n, dx, L) -> bool:
    return abs(n * dx - L) <= 1e-9 * L


def accepted_spacings(L1, L3, dx, holds=None) -> list:
    """The spacings nearest ``dx`` (at most one below and one above) that divide the domain
    L1 x L3 exactly into an even fast FFT size of nodes along each axis (and, with
    ``holds(L1, L3, d)``, for which it is true): [(dx, n1, n3), ...], ascending."""
    below, above = None, None
    for n1 in range(2, MAX_NODES_PER_AXIS + 1, 2):
        if not is_fast_size(n1):
            continue
        d = L1 / n1
        n3 = int(round(L3 / d))
        if not (_fits(n1, n3) and _exact(n3, d, L3)) or (holds is not None and not holds(L1, L3, d)):
            continue
        if d <= dx and (below is None or d > below[0]):
            below = (d, n1, n3)
        if d >= dx and (above is None or d < above[0]):
            above = (d, n1, n3)
    return sorted({c for c in (below, above) if c is not None})


def _spacings_text(cands) -> str:
    return " or ".join(f"dx = {d:.6g} ({n1} x {n3} nodes)" for d, n1, n3 in cands) or "none"


def spacing_grid(builder, dx, domain, *, free_surface=False, unit="m", holds=None, needs=""):
    """The grid of ``builder``(dx=, domain=): n = round(L / dx) nodes of dx along each
    axis of ``domain`` = (L1, L3). A dx that gives a node count the grid cannot take (not an
    even fast FFT size 2^a 3^b 5^c 7^d, fewer than 2, too many) is refused as an InputError
    of "dx" naming the nearest spacings that divide the domain; a dx that does not divide
    the domain exactly rounds it to n dx, with a BuilderWarning naming the requested and the
    actual domain (the periodic images' distance; the builders place the fault, its loads
    and stations from the hypocentre node, so the problem itself is unchanged).
    ``holds(L1, L3, d)``: whether the domain holds the builder's fault at spacing d; when it
    does not, an InputError of "dx" if a finer spacing would (dx too coarse), else of
    "domain", saying what it ``needs``. The spacings offered hold it too."""
    try:
        L1, L3 = (float(x) for x in domain)
    except (TypeError, ValueError, OverflowError):
        raise InputError("domain", f"must be (L1, L3) in {unit}, got {domain!r}") from None
    L1, L3 = check_positive("domain", L1), check_positive("domain", L3)
    try:
        dx = check_positive("dx", dx)
    except InputError as err:
        offered = _spacings_text(accepted_spacings(L1, L3, min(L1, L3) / 64, holds))
        raise InputError("dx", f"the grid spacing of {builder} in {unit}: a number > 0 that divides the domain "
                               f"{L1:g} x {L3:g} {unit} into an even fast FFT size of nodes along each axis (e.g. "
                               f"{offered}); {str(err)[len('dx: '):]}") from None
    if holds is not None and not holds(L1, L3, dx):
        # a domain that holds the fault at a finer spacing: dx is what is too large
        require("domain", holds(L1, L3, min(L1, L3) * 1e-6), f"{needs}, got {domain!r}")
        raise InputError("dx", f"is too coarse for {builder}: on a grid of dx = {dx:g} the domain {L1:g} x {L3:g} "
                               f"{unit} would not {needs.removeprefix('must ')}; nearest accepted: "
                               f"{_spacings_text(accepted_spacings(L1, L3, dx, holds))}")
    n1, n3 = int(round(L1 / dx)), int(round(L3 / dx))
    if not _fits(n1, n3):
        raise InputError("dx", f"must divide the domain {L1:g} x {L3:g} {unit} of {builder} into an even fast FFT "
                               f"size of nodes along each axis (2^a 3^b 5^c 7^d, 2 to {MAX_NODES_PER_AXIS}, at most "
                               f"2^26 nodes in all), got dx = {dx:g}: {n1} x {n3} nodes; nearest accepted: "
                               f"{_spacings_text(accepted_spacings(L1, L3, dx, holds))} "
                               f"(or a domain that dx divides so)")
    if not (_exact(n1, dx, L1) and _exact(n3, dx, L3)):
        exact = accepted_spacings(L1, L3, dx, holds)
        _warn(
            f"{builder}: dx = {dx:g} does not divide the domain {L1:g} x {L3:g} {unit}; the grid is {n1} x {n3} "
            f"nodes of dx, the domain {n1 * dx:g} x {n3 * dx:g} {unit} (spacings that divide it: "
            f"{_spacings_text(exact)})")
    return Grid(n1=n1, n3=n3, L1=n1 * dx, L3=n3 * dx, free_surface=free_surface)


def check_stations(builder, stations, grid, slips) -> dict:
    """The builder's default ``stations`` = {name: (x1, x3)} whose nearest node is one of
    the ``slips`` mask (a node of the fault that can slip). A station whose node is not (on
    a bonded node it would record zero at every step: outside the fault at this grid, or
    on its edge) is left out, with a BuilderWarning naming it, its node and the grid."""
    kept, off = {}, []
    for name, (x1, x3) in stations.items():
        i, k = grid.nearest_node(x1, x3)
        if slips[i, k]:
            kept[name] = (x1, x3)
        else:
            off.append(f"{name} (node x1 = {grid.x1[i]:g}, x3 = {grid.x3[k]:g})")
    if off:
        _warn(
            f"{builder}: on the grid of {grid.n1} x {grid.n3} nodes (dx = {grid.dx1:g}) the default station"
            f"{'s' if len(off) > 1 else ''} {', '.join(off)} {'lie' if len(off) > 1 else 'lies'} outside the "
            f"fault or on its bonded edge and would record nothing but zero: left out of the recording "
            f"(record= sets the stations)")
    return kept
