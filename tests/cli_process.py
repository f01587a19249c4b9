"""The command line as a process (``python -m cracklab.cli``), and its one-line errors:
shared by the command-line tests."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def cli(*args, cwd=ROOT, timeout=600):
    """Run ``cracklab ARGS...`` in a fresh process; the CompletedProcess (text)."""
    return subprocess.run([sys.executable, "-m", "cracklab.cli", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=timeout)


def error_line(res) -> str:
    """The stderr of a failed command: one line, 'Error: ...', no traceback."""
    assert res.returncode != 0, res.stdout
    assert "Traceback" not in res.stderr, res.stderr
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("Error: "), res.stderr
    return lines[0]
