"""Verification registry: the rows of the table in docs/studies/verification.md.

Each row names the test that measures it, the reference solution, the measured
quantity and its tolerance. A test ends with ``check(row_id, achieved)``, which
records the achieved value and asserts ``achieved <= tolerance``. The tolerance lives
here and only here: the tests take it from ``check`` and tests/docs/test_docs.py makes
sure docs/studies/verification.md shows the same tolerances, and achieved values within them.

When the suite runs with ``CRACKLAB_WRITE_VERIFICATION=1``, tests/conftest.py
rewrites the table in docs/studies/verification.md from the values recorded in the run
(rows whose tests did not run keep their old values).

Rows in ``OUTCOME_ROWS`` are pass/fail rows: their achieved value is the number of
failing tests under the row's node id (a module or a test), counted by conftest.py.
"""
from __future__ import annotations

import math

# (id, test node id, reference, quantity, tolerance)
# Text must not contain "|" (it goes into a Markdown table).
ROWS = [
    ("kernel-laplace",
     "tests/solver/test_kernels.py::test_laplace_matches_numerical_transform",
     "exact Laplace transforms of C_I, C_II, C_III (Appendix A, corrected)",
     "max abs(L_num - L_exact) / max(1, abs(L_exact)); nu = 0.2, 0.25, 0.35; s = 0.5, 1, 2, 5, 1+2i",
     1e-9),
    ("kernel-C0",
     "tests/solver/test_kernels.py::test_C_at_zero_is_exact",
     "Eq. (26) at T = 0: 4a - 4 - a^3/2, 7/2 - 4/a (corrected), 1/2",
     "max abs(C(0) - closed form) / max(abs(closed form), 0.1); three kernels, three nu",
     1e-13),
    ("kernel-static-integral",
     "tests/solver/test_kernels.py::test_static_integrals",
     "int_0^inf C dT = 1/(1-nu) for I and II, 1 for III (after Eq. 33)",
     "max abs(numerical integral - exact); three kernels, three nu",
     1e-9),
    ("modal-III-J0",
     "tests/analysis/test_modal.py::test_mode_III_matches_J0",
     "single-mode response of mode III, r = J0(q c_s t)",
     "max abs(r - J0) for T <= 30, explicit scheme, gamma = 0.05",
     0.02),
    ("modal-I-amplitude",
     "tests/analysis/test_modal.py::test_mode_I_long_time_form",
     "Eq. (B.5): r ~ 0.5844 sin(q c_R t)",
     "abs(A / 0.5844 - 1), A fitted over 150 <= T <= 200, gamma = 0.05",
     0.02),
    ("modal-I-period",
     "tests/analysis/test_modal.py::test_mode_I_long_time_form",
     "Eq. (B.5): period 2 pi c_s / c_R = 6.834 in T",
     "relative error of the period from zero crossings, 150 <= T <= 200, gamma = 0.05",
     0.005),
    ("modal-convergence-I",
     "tests/analysis/test_modal.py::test_first_order_convergence[I]",
     "exact r(T) of Eq. (41) (numerical Laplace inversion); first order in gamma",
     "max abs(e(gamma) / e(gamma/2) - 2), gamma = 0.2 to 0.025, e = max error for T <= 10",
     0.3),
    ("modal-convergence-II",
     "tests/analysis/test_modal.py::test_first_order_convergence[II]",
     "exact mode II r(T) (numerical Laplace inversion); first order in gamma",
     "max abs(e(gamma) / e(gamma/2) - 2), gamma = 0.2 to 0.025, e = max error for T <= 10",
     0.3),
    ("modal-convergence-III",
     "tests/analysis/test_modal.py::test_first_order_convergence[III]",
     "r = J0(T); first order in gamma",
     "max abs(e(gamma) / e(gamma/2) - 2), gamma = 0.2 to 0.025, e = max error for T <= 10",
     0.3),
    ("lamb-pekeris",
     "tests/physics/test_lamb.py::test_opening_follows_pekeris",
     "Lamb's problem, Pekeris (1955) (section 3.2, corrected)",
     "max abs(opening - exact) / static value, 32 cells from the load (n = 128, beta = 0.5), "
     "away from the P, S (0.03 in tau) and R (0.08) arrivals",
     0.05),
    ("lamb-static",
     "tests/physics/test_lamb.py::test_opening_reaches_static_value",
     "Lamb's problem, static opening 3P/(4 pi mu r) (corrected)",
     "max abs(opening - static) / static for tau > 1.45, 32 cells from the load",
     0.02),
    ("penny",
     "tests/physics/test_static.py::test_penny_crack_reaches_sneddon",
     "penny-shaped crack, Sneddon: (4(1-nu) p / (pi mu)) sqrt(c^2 - r^2)",
     "abs(centre opening / exact - 1), area-equivalent radius 12.8 cells, n = 128",
     0.02),
    ("periodic-I",
     "tests/physics/test_static.py::test_periodic_row_reaches_exact_opening[I-512-0.5-3.5]",
     "2D periodic row of cracks, exact static opening, mode I",
     "max abs(opening - exact) / peak for abs(x) <= c/2, n = 512, beta = 0.5",
     0.005),
    ("periodic-II",
     "tests/physics/test_static.py::test_periodic_row_reaches_exact_opening[II-256-0.07-3.0]",
     "2D periodic row of cracks, exact static slip, mode II",
     "max abs(slip - exact) / peak for abs(x) <= c/2, n = 256, beta = 0.07",
     0.005),
    ("periodic-III",
     "tests/physics/test_static.py::test_periodic_row_reaches_exact_opening[III-512-0.5-3.5]",
     "2D periodic row of cracks, exact static slip, mode III",
     "max abs(slip - exact) / peak for abs(x) <= c/2, n = 512, beta = 0.5",
     0.005),
    ("kostrov-0.5",
     "tests/physics/test_kostrov.py::test_kostrov_centre_slip[0.5]",
     "Kostrov (1964) self-similar mode III crack, v = 0.5 c_s",
     "max relative error of the centre slip once the crack spans >= 40 cells (n = 256)",
     0.02),
    ("kostrov-0.7",
     "tests/physics/test_kostrov.py::test_kostrov_centre_slip[0.7]",
     "Kostrov (1964) self-similar mode III crack, v = 0.7 c_s",
     "max relative error of the centre slip once the crack spans >= 40 cells (n = 256)",
     0.02),
    ("kostrov-0.9",
     "tests/physics/test_kostrov.py::test_kostrov_centre_slip[0.9]",
     "Kostrov (1964) self-similar mode III crack, v = 0.9 c_s",
     "max relative error of the centre slip once the crack spans >= 40 cells (n = 256)",
     0.02),
    ("mirror-shear",
     "tests/solver/test_mirror.py::test_3d_shear_run_equals_the_doubled_whole_space_run",
     "free surface by mirror symmetry: the doubled whole-space run (n1 x 2 n3) with mirrored loads and laws",
     "max over the recorded fields and station series of max abs(half - doubled) / max abs(doubled); 3D shear, "
     "slip weakening, product scheme, 32 x 16 half plane",
     1e-12),
    ("mirror-mode-I",
     "tests/solver/test_mirror.py::test_mode_i_run_equals_the_doubled_whole_space_run",
     "free surface by mirror symmetry: the doubled whole-space run (n1 x 2 n3) with mirrored loads and laws",
     "max over the recorded fields and station series of max abs(half - doubled) / max abs(doubled); mode I, "
     "linear cohesive, 32 x 16 half plane",
     1e-12),
    ("bad-input",
     "tests/model/test_validation.py",
     "API.md: a bad input ends with one clear error naming the field",
     "number of failing tests (pass/fail row)",
     0),
]

#: pass/fail rows: achieved = number of failing tests under the node id (conftest.py)
OUTCOME_ROWS = frozenset({"bad-input"})

BY_ID = {row[0]: row for row in ROWS}
if len(BY_ID) != len(ROWS):  # pragma: no cover - guards edits of ROWS
    raise RuntimeError("duplicate row id in tests/verification.py ROWS")

#: worst achieved value per row id recorded in this process
ACHIEVED: dict[str, float] = {}
# values recorded since conftest.py last collected them (it attaches them to the report,
# which carries them from pytest-xdist workers to the controller)
_PENDING: list[tuple[str, float]] = []


def tolerance(row_id: str) -> float:
    return float(_row(row_id)[4])


def worse(a: float, b: float) -> float:
    """The worse of two achieved values (NaN counts as worst)."""
    if math.isnan(a) or math.isnan(b):
        return math.nan
    return max(a, b)


def _row(row_id: str):
    try:
        return BY_ID[row_id]
    except KeyError:
        raise KeyError(f"unknown verification row {row_id!r}; rows: {', '.join(BY_ID)}") from None


def check(row_id: str, achieved, detail: str = "") -> None:
    """Record ``achieved`` for row ``row_id`` and assert it is within the row's tolerance."""
    rid, test, reference, quantity, tol = _row(row_id)
    if rid in OUTCOME_ROWS:
        raise ValueError(f"{rid!r} is a pass/fail row; its value is counted by conftest.py")
    value = float(achieved)
    ACHIEVED[rid] = worse(ACHIEVED.get(rid, value), value)
    _PENDING.append((rid, value))
    assert value <= tol, (
        f"verification row {rid!r} ({test}): {quantity} = {value:.4g} exceeds the tolerance "
        f"{tol:g} (reference: {reference})" + (f"; {detail}" if detail else ""))


def drain() -> list[tuple[str, float]]:
    """Values recorded since the last call (used by conftest.py)."""
    out = list(_PENDING)
    _PENDING.clear()
    return out


def matches(row_nodeid: str, nodeid: str) -> bool:
    """True when the test ``nodeid`` belongs to a row's node id (a module, a test
    function covering all its parameters, or one parametrized test)."""
    if nodeid == row_nodeid:
        return True
    if "::" not in row_nodeid:
        return nodeid.startswith(row_nodeid + "::")
    return "[" not in row_nodeid and nodeid.startswith(row_nodeid + "[")


# ----------------------------------------------------------------------------- the table
START = "<!-- verification-table:start -->"
END = "<!-- verification-table:end -->"
HEADER = ("test", "reference", "quantity", "tolerance", "achieved")


def format_value(value) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, int):
        return str(value)
    return f"{value:.3g}"


def first_cell(row) -> str:
    return f"`{row[0]}` (`{row[1]}`)"


def render_table(achieved: dict) -> str:
    """The Markdown table for all ROWS; ``achieved`` maps row id -> value or text."""
    lines = ["| " + " | ".join(HEADER) + " |", "|" + "---|" * len(HEADER)]
    for row in ROWS:
        value = achieved.get(row[0], "not run")
        lines.append(f"| {first_cell(row)} | {row[2]} | {row[3]} | {row[4]:g} | {format_value(value)} |")
    return "\n".join(lines)


def parse_table(text: str) -> dict:
    """Rows of the table between the markers: id -> dict(test, reference, quantity,
    tolerance, achieved), all as the strings written there."""
    if START not in text or END not in text:
        raise ValueError(f"the markers {START} and {END} are missing")
    body = text.split(START, 1)[1].split(END, 1)[0]
    rows = {}
    for line in body.strip().splitlines():
        line = line.strip()
        if not line.startswith("|") or set(line) <= set("|-: "):
            continue
        cells = [c.strip() for c in line.strip("|").split("|")]
        if cells[0] == HEADER[0]:
            continue
        if len(cells) != len(HEADER):
            raise ValueError(f"table row with {len(cells)} cells instead of {len(HEADER)}: {line}")
        rid = cells[0].split("`")[1] if cells[0].count("`") >= 2 else cells[0]
        rows[rid] = dict(zip(HEADER, cells))
    return rows


def replace_table(text: str, table: str) -> str:
    head, rest = text.split(START, 1)
    _, tail = rest.split(END, 1)
    return f"{head}{START}\n{table}\n{END}{tail}"
