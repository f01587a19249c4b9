"""Reproduce figures 5 to 11 of Geubelle & Rice (1995): one command per part, or all.

    nice -n 10 .venv/bin/python studies/paper/run.py modal      # Figs. 5-7   (docs/studies/paper_modal.md)
    nice -n 10 .venv/bin/python studies/paper/run.py lamb       # Figs. 8-9   (docs/studies/paper_lamb.md)
    nice -n 10 .venv/bin/python studies/paper/run.py ellipse    # Figs. 10-11 (docs/studies/paper_elliptical.md)
    nice -n 10 .venv/bin/python studies/paper/run.py all
    .venv/bin/python studies/paper/run.py PART --docs-only       # rewrite the page from out/paper/

Stores and summaries go to out/paper/, figures to docs/figures/paper_*.png.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies/ -> package "paper"

from paper import ellipse_part, lamb_part, modal_part  # noqa: E402

PARTS = {"modal": modal_part, "lamb": lamb_part, "ellipse": ellipse_part}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("part", choices=sorted(PARTS) + ["all"])
    ap.add_argument("--docs-only", action="store_true", help="rewrite the docs page from the saved summary")
    ap.add_argument("--reuse", action="store_true",
                    help="lamb, ellipse: analyse the existing store in out/paper/ instead of simulating again")
    args = ap.parse_args(argv)
    names = list(PARTS) if args.part == "all" else [args.part]
    for name in names:
        t0 = time.perf_counter()
        if args.docs_only:
            PARTS[name].docs()
        elif name == "modal":
            PARTS[name].run()
        else:
            PARTS[name].run(reuse=args.reuse)
        print(f"{name}: done in {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
