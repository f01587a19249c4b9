"""Shared helpers of the paper study: paths, timing, tables, JSON summaries."""
from __future__ import annotations

import json
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "out" / "paper"
DOCS = ROOT / "docs"
FIGS = DOCS / "figures"

for p in (ROOT, ROOT / "studies"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))


def plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as _plt

    return _plt


def save(fig, name):
    """Save a figure as docs/figures/<name>.png; returns the path relative to docs/."""
    FIGS.mkdir(parents=True, exist_ok=True)
    path = FIGS / f"{name}.png"
    fig.savefig(path, dpi=110)
    plt().close(fig)
    return f"figures/{path.name}"


class Timer:
    """Wall-clock sections: with timer("name"): ...; timer.seconds is a dict."""

    def __init__(self):
        self.seconds = {}

    def __call__(self, name):
        timer = self

        class _Section:
            def __enter__(self):
                self.t0 = time.perf_counter()

            def __exit__(self, *exc):
                timer.seconds[name] = timer.seconds.get(name, 0.0) + time.perf_counter() - self.t0

        return _Section()


def simulate_or_reuse(sc, store, timer, reuse, label):
    """Run ``sc`` into ``store`` (timed as "simulate"), or, with ``reuse``, open the store of
    an earlier run and take its recorded run time."""
    import shutil

    import xarray as xr
    from cracklab import simulate

    runtime = store.with_name(store.stem + "_runtime.json")
    if reuse and store.exists() and runtime.exists():
        timer.seconds["simulate"] = json.loads(runtime.read_text())["simulate"]
        return xr.open_zarr(str(store), consolidated=False)
    if store.exists():
        shutil.rmtree(store)
    store.parent.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    with timer("simulate"):
        ds = simulate(sc, store=str(store))
    runtime.write_text(json.dumps({"simulate": timer.seconds["simulate"], "steps": sc.nsteps}))
    print(f"{label}: {sc.nsteps} steps in {time.perf_counter() - t0:.1f} s")
    return ds


def machine():
    import os

    return f"{platform.machine()}, {os.cpu_count()} cores (shared), Python {platform.python_version()}"


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        x = float(x)
        return x if math.isfinite(x) else repr(x)  # "inf", "nan"
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    return x


def write_summary(part, summary):
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / f"{part}_summary.json"
    path.write_text(json.dumps(_jsonable(summary), indent=1))
    return path


def read_summary(part):
    path = OUT / f"{part}_summary.json"
    if not path.exists():
        raise SystemExit(f"{path} does not exist: run `studies/paper/run.py {part}` first")
    return json.loads(path.read_text())


def num(x):
    """Float from a summary value ("inf"/"nan" strings included)."""
    return float(x)


def fmt(x, digits=3):
    x = float(x)
    if math.isnan(x):
        return "n/a"
    if math.isinf(x):
        return "overflow" if x > 0 else "-inf"
    return f"{x:.{digits}g}"


def table(header, rows):
    """Markdown table from a header list and rows of cells (already strings)."""
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)


def write_page(name, text):
    path = DOCS / "studies" / name
    path.write_text(text.rstrip() + "\n")
    return path
