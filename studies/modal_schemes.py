"""Precision factor and long-time growth of the 12 modal schemes (section 3.1, Figs. 5-6).

For each (formulation, convolution, integration) scheme of cracklab.analysis.modal.SCHEMES,
mode I (nu = 1/4), and gamma = q c_s dt in {0.5, 1, 2, 2.3}:

* the precision factor of Fig. 6: largest |r| sampled in the 10th period of the
  Rayleigh oscillation over the long-time amplitude 0.5844 of Eq. (B.5)
  (cracklab.analysis.modal.precision_factor, method "max");
* the long-time growth rate per unit T, ln(max|r| over [1900, 2000] / max|r| over
  [1000, 1100]) / 900 (the window of cracklab.stability); "overflow" when the
  recurrence overflowed before T = 2000.

Prints both tables in Markdown (they are copied into docs/studies/verification.md) and writes
docs/figures/modal_precision.png: the precision factor against gamma for all 12
schemes (the counterpart of Fig. 6). Runs in well under a minute:

    python3 studies/modal_schemes.py
"""
from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
try:
    import cracklab  # noqa: F401
except ImportError:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))

from cracklab.analysis.modal import SCHEMES, long_time_period, modal_response, precision_factor  # noqa: E402

MODE = "I"
NU = 0.25
GAMMAS = (0.5, 1.0, 2.0, 2.3)
PERIOD = 10
EARLY, LATE = (1000.0, 1100.0), (1900.0, 2000.0)
FIGURE = ROOT / "docs" / "figures" / "modal_precision.png"


def response(scheme, gamma, T_end):
    f, c, i = scheme
    return modal_response(MODE, gamma=gamma, T_end=T_end, nu=NU, formulation=f, convolution=c,
                          integration=i)


def pf(scheme, gamma):
    P = long_time_period(MODE, NU)
    return precision_factor(response(scheme, gamma, PERIOD * P), NU, period=PERIOD)


def growth(scheme, gamma):
    """Growth rate of the envelope per unit T (inf if the recurrence overflowed)."""
    r = response(scheme, gamma, LATE[1])
    T, y = r["T"].values, np.abs(r.values)
    if not np.all(np.isfinite(y)):
        return math.inf
    early = y[(T >= EARLY[0]) & (T <= EARLY[1])].max()
    late = y[(T >= LATE[0]) & (T <= LATE[1])].max()
    if early == 0.0 or late == 0.0:
        return -math.inf
    return math.log(late / early) / (LATE[0] - EARLY[0])


def label(scheme):
    return " / ".join(scheme)


def fmt_pf(x):
    return "overflow" if not math.isfinite(x) else f"{x:.3g}"


def fmt_growth(x):
    if x == math.inf:
        return "overflow"
    if x == -math.inf:
        return "decays to 0"
    return f"{x:+.1e}"


def markdown(values, fmt):
    head = "| scheme (formulation / convolution / integration) | " + \
        " | ".join(f"gamma = {g:g}" for g in GAMMAS) + " |"
    lines = [head, "|---|" + "---|" * len(GAMMAS)]
    for scheme in SCHEMES:
        lines.append(f"| {label(scheme)} | " + " | ".join(fmt(values[scheme, g]) for g in GAMMAS) + " |")
    return "\n".join(lines)


def figure(path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    gammas = np.round(np.arange(0.1, 2.5001, 0.05), 10)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    styles = {"explicit": "-", "semi-implicit": "--"}
    colours = {"discretized": "C0", "trapezoid": "C1", "simpson": "C2"}
    for ax, formulation in zip(axes, ("displacement", "velocity")):
        for scheme in SCHEMES:
            if scheme[0] != formulation:
                continue
            y = np.array([pf(scheme, g) for g in gammas])
            y = np.where(np.isfinite(y), y, 1e3)
            ax.semilogy(gammas, np.clip(y, 1e-3, 1e3), styles[scheme[2]], color=colours[scheme[1]],
                        label=f"{scheme[1]}, {scheme[2]}")
        ax.axhline(1.0, color="0.6", lw=0.8)
        for g in GAMMAS:
            ax.axvline(g, color="0.85", lw=0.8)
        ax.set_ylim(1e-3, 1e3)
        ax.set_xlabel(r"$\gamma = q c_s \Delta t$")
        ax.set_title(f"{formulation} formulation, mode I")
        ax.legend(fontsize=8)
    axes[0].set_ylabel("precision factor, 10th period")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    t0 = time.perf_counter()
    pfs = {(s, g): pf(s, g) for s in SCHEMES for g in GAMMAS}
    rates = {(s, g): growth(s, g) for s in SCHEMES for g in GAMMAS}
    print(f"Precision factor, mode I, nu = {NU}, period {PERIOD} (cracklab.analysis.modal.precision_factor):\n")
    print(markdown(pfs, fmt_pf))
    print(f"\nGrowth rate of max|r| per unit T, T in {list(EARLY)} -> {list(LATE)} "
          "(negative: decays):\n")
    print(markdown(rates, fmt_growth))
    figure(FIGURE)
    print(f"\nwrote {FIGURE.relative_to(ROOT)} ({time.perf_counter() - t0:.1f} s)")


if __name__ == "__main__":
    main()
