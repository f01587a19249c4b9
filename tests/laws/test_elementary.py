"""laws/elementary.py: exp, expm1, log and log1p in straight-line arithmetic, against the
library's (math) over the ranges the module states, compiled and as Python."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cracklab.laws import elementary as el

RNG = np.random.default_rng(7)
#: function -> (arguments, bound in ulp of the library's result)
CASES = {
    "exp": (np.concatenate([RNG.uniform(-707.9, 708.9, 40000), RNG.uniform(-1.0, 1.0, 20000)]), 1.0),
    "expm1": (np.concatenate([RNG.uniform(-707.9, -0.35, 20000), RNG.uniform(-0.35, 0.0, 20000),
                              -np.geomspace(1e-300, 1.0, 10000)]), 2.0),
    "log": (np.concatenate([np.exp(RNG.uniform(-708.0, 709.0, 40000)), RNG.uniform(0.5, 2.0, 20000)]), 1.0),
    "log1p": (np.concatenate([RNG.uniform(-0.999, 10.0, 40000), np.geomspace(1e-2, 1e3, 10000),
                              -np.geomspace(1e-2, 0.999, 10000)]), 1.0),
}


def _ulp(got, want):
    return np.max(np.abs(got - want) / np.spacing(np.abs(want)))


@pytest.mark.parametrize("name", sorted(CASES))
def test_each_function_is_within_its_ulp_bound_of_the_library_compiled_and_as_python(name):
    numba = pytest.importorskip("numba")
    x, bound = CASES[name]
    want = np.array([getattr(math, name)(v) for v in x])
    python = getattr(el, name)
    el.compile_functions()
    f = getattr(el, name)

    @numba.njit
    def run(x, out):
        for i in range(x.size):
            out[i] = f(x[i])

    got = np.empty_like(x)
    run(x, got)
    assert _ulp(got, want) <= bound
    assert np.mean(got == want) > 0.8          # most values the library's bits
    some = x[::50]
    assert np.array_equal(np.array([python(v) for v in some]), got[::50])   # Python and compiled agree


def test_expm1_keeps_its_relative_accuracy_where_e_to_the_x_minus_one_would_lose_it():
    x = -np.geomspace(1e-12, 1e-4, 200)
    got = np.array([el.expm1(v) for v in x])
    want = np.array([math.expm1(v) for v in x])
    assert _ulp(got, want) <= 2.0
    assert _ulp(np.exp(x) - 1.0, want) > 1e3     # what the series is for
