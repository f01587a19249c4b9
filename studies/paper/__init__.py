"""Reproduction of Geubelle & Rice (1995), figures 5 to 11, as one study.

    .venv/bin/python studies/paper/run.py modal|lamb|ellipse|all [--docs-only]

Parts: :mod:`paper.modal_part` (Figs. 5-7), :mod:`paper.lamb_part` (Figs. 8-9),
:mod:`paper.ellipse_part` (Figs. 10-11); shared helpers in :mod:`paper.common`.
Each part writes a Zarr store under out/paper/, PNG figures under
docs/figures/paper_*.png, a summary JSON next to the store, and its docs page
(docs/paper_*.md) from that summary.
"""
