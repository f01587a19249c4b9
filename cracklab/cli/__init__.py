"""Command-line entry point (``cracklab``).

Every command takes ``-h`` / ``--help``, writes its output where ``-o`` says, reports a bad
input as one line naming the option typed (``Error: --n1: ...``), refuses to replace an
output that holds another scene's results unless ``--overwrite``, and ends on Ctrl-C with
exit status 130 and one line saying where to pick up.

Modules: one per command (``cmd_new``, ``cmd_run``, ``cmd_sweep``, ``cmd_plot``, ``cmd_export``,
``cmd_summary``, ``cmd_verify``, ``cmd_bench``, ``cmd_demo``), each adding its command
to the group ``main`` of ``common`` (with the helpers the commands share); ``bench`` and
``demo`` run the bench and the demonstration.
"""
from .common import CONTEXT, INTERRUPTED, fail, main
# the commands, in the order main.commands lists them (docs/reference/api.md)
from .cmd_demo import demo
from .cmd_new import new
from .cmd_run import RUN_FLAGS, run
from .cmd_sweep import SWEEP_FLAGS, sweep
from .cmd_plot import PLOT_KINDS, plot
from .cmd_export import export
from .cmd_summary import summary
from .cmd_verify import verify
from .cmd_bench import BENCH_FLAGS, bench

__all__ = ["main", "fail", "CONTEXT", "INTERRUPTED", "demo", "new", "run", "sweep", "plot", "export", "summary",
           "verify", "bench", "RUN_FLAGS", "SWEEP_FLAGS", "PLOT_KINDS", "BENCH_FLAGS"]
