import math
import os
import sys
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

# the verification registry (tests/verification.py) is imported by name by the tests
if str(Path(__file__).resolve().parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
import verification  # noqa: E402

DOC = Path(__file__).resolve().parent.parent / "docs" / "studies" / "verification.md"

# Collected in the process that runs pytest_sessionfinish (the controller under
# pytest-xdist, which receives every report with its user_properties).
_VALUES: dict[str, float] = {}
_OUTCOMES: dict[str, bool] = {}  # nodeid -> failed in some phase


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    for row_id, value in verification.drain():
        report.user_properties.append(("verification", (row_id, value)))


def pytest_runtest_logreport(report):
    for name, value in report.user_properties:
        if name == "verification":
            row_id, achieved = value
            achieved = float(achieved)
            _VALUES[row_id] = verification.worse(_VALUES.get(row_id, achieved), achieved)
    if report.skipped and report.when == "setup":
        return
    _OUTCOMES[report.nodeid] = _OUTCOMES.get(report.nodeid, False) or report.failed


def _achieved_now() -> dict:
    """Row id -> value (or "failed") for the rows whose tests ran in this session."""
    out = {}
    for rid, nodeid, *_rest, tol in verification.ROWS:
        ran = [failed for n, failed in _OUTCOMES.items() if verification.matches(nodeid, n)]
        if not ran:
            continue
        if rid in verification.OUTCOME_ROWS:
            out[rid] = sum(ran)
        elif rid in _VALUES:
            value = _VALUES[rid]
            # a failure elsewhere in the test must not show as a pass
            out[rid] = "failed" if any(ran) and not (math.isnan(value) or value > tol) else value
        elif any(ran):
            out[rid] = "failed"
    return out


def pytest_sessionfinish(session, exitstatus):
    if os.environ.get("CRACKLAB_WRITE_VERIFICATION") != "1":
        return
    if hasattr(session.config, "workerinput"):  # a pytest-xdist worker
        return
    now = _achieved_now()
    if not now:
        return
    text = DOC.read_text()
    old = {rid: cells["achieved"] for rid, cells in verification.parse_table(text).items()}
    achieved = {row[0]: now.get(row[0], old.get(row[0], "not run")) for row in verification.ROWS}
    DOC.write_text(verification.replace_table(text, verification.render_table(achieved)))
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.write(f"\ncracklab: wrote {len(now)} verification rows to {DOC}\n")
