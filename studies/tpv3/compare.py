"""Comparison of cracklab TPV3 station series with the MDSBI reference (docs/studies/tpv3.md).

The measures and the acceptance check are the slip-weakening benchmarks' own
(``studies.benchmarks.measures``, named here too); this module adds the reference
(``shared/reference/tpv3_mdsbi``, found by ``studies.benchmarks.harness.reference_dir``):
two stations, tab-separated, two header lines, columns t, h-slip, h-rate, h-stress,
v-slip, v-rate, v-stress in s, m, m/s, MPa.
"""
from __future__ import annotations

from studies.benchmarks.harness import mdsbi_station, reference_dir
from studies.benchmarks.measures import (  # noqa: F401 - the study's measures, under one name
    ACCEPT_DX, COLUMNS, QUANTITY, THRESHOLD, TIE, TOL_FINAL_SLIP, TOL_PEAK_RATE, TOL_RUPTURE_TIME, TOLERANCES,
    acceptance, check_acceptance, compare_station, differences, final_value, fmt_tol, metrics, peak, resample,
    read_mdsbi, rupture_time, series_errors)

REFERENCE = "tpv3_mdsbi"


def default_reference_dir():
    """The reference's folder when no ``--reference`` is given (``harness.reference_dir``)."""
    return reference_dir(REFERENCE)


def load_reference(station: str, directory=None) -> dict:
    """The MDSBI series of one station: dict of numpy arrays keyed by ``COLUMNS``
    (stress in MPa as in the file)."""
    return mdsbi_station(REFERENCE, station, directory)
