"""Issue 35, cost: a sequence streamed to a store holds no more memory for a longer run.
The peak of Python's allocations (tracemalloc: numpy's arrays are counted) over a whole run
of the spring-slider, 4 times longer, must not grow by more than what the returned Dataset
indexes (8 bytes per row of t and t_station) and a margin. Before the series were written
in long chunks, reading the snapshot times back cost about 3 kB per snapshot: the longer run
peaked 0.58 MB higher at 20 and 80 years (fails here), 7 MB higher at 100 and 400 years;
now 0.09 MB lower and 0.36 MB higher. With the recorder's budgets lowered below (both runs
write), 0.15-0.21 MB higher over 3242 more rows (0.10 MB of it the indexes); the recorder
that kept every row of the longer run peaked 3.1 MB higher. Measured in a process of its
own, after a warm-up run, so that what other tests left behind is not counted."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

PROBE = r"""
import json, sys, tracemalloc
sys.path.insert(0, {here!r})
from spring_slider import scene
from cracklab.output import sequence
from cracklab.output.sequence import run_sequence
sequence.SEQUENCE_ROWS, sequence.SEQUENCE_SNAPSHOT_BYTES = {rows}, {snap}   # both runs pass them
YEAR = 3.15576e7
run_sequence(scene(1.0 * YEAR), store={warm!r})      # compiled and imported before counting
out = []
for years, path in ((20.0, {short!r}), (80.0, {long!r})):
    tracemalloc.start()
    ds = run_sequence(scene(years * YEAR), store=path)
    out.append([tracemalloc.get_traced_memory()[1], ds.sizes["t"] + ds.sizes["t_station"]])
    tracemalloc.stop()
print(json.dumps(out))
"""


#: what the recorder keeps before it writes (solver/budget.py's SEQUENCE_ROWS and
#: SEQUENCE_SNAPSHOT_BYTES), lowered so that the shorter run writes too: the bound is theirs
ROWS, SNAPSHOT_BYTES = 256, 4096


def test_the_peak_memory_of_a_streamed_sequence_does_not_grow_with_its_length(tmp_path):
    code = PROBE.format(here=str(Path(__file__).parent), rows=ROWS, snap=SNAPSHOT_BYTES, warm=str(tmp_path / "warm.zarr"),
                        short=str(tmp_path / "short.zarr"), long=str(tmp_path / "long.zarr"))
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    (short, rows_short), (long, rows_long) = json.loads(done.stdout.strip().splitlines()[-1])
    assert rows_long > 3.5 * rows_short
    allowed = 8 * (rows_long - rows_short) * 4 + 200e3     # the indexes, their copies, and a margin
    assert long - short < allowed, (short, long, allowed)
