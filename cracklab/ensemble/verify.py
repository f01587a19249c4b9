"""``cracklab verify`` of a run or an ensemble store: ``cracklab.output.verify.verify``
(each run or member, the consolidated metadata) and, for an ensemble, each complete
member's parameters (``checks.check_params``) and the member table at the root
(``members_table.check_table``)."""
from __future__ import annotations

from ..output import verify as V
from .checks import check_params
from .members_table import check_table


def verify(store, *, read: bool = True):
    """The ``Report`` of a run or ensemble store (a local path or a URL, the same checks):
    ``cracklab.output.verify.verify`` and, for an ensemble, each complete member's
    parameters and the member table."""
    root = V.store_tree(store)          # a URL: checked, and its keys listed once
    report = V.verify(root, read=read)
    if report.kind != "ensemble" or not (root / "zarr.json").exists():
        return report
    for mid, state in list(report.members.items()):
        if state in ("sound", "damaged"):   # complete ones
            check_params(root, mid, report)
            if any(d.member == mid for d in report.damage):
                report.members[mid] = "damaged"
    check_table(root, report)
    return report
