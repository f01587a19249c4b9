"""The check that two sequence runs are the same to the bit: the same variables, each of
the same shape and values (NaN where the other has NaN), and the same accepted steps
(tests/sequence/test_sequence_resume.py, test_sequence_object_store.py)."""
import numpy as np


def assert_same_run(a, b):
    assert set(a.variables) == set(b.variables)
    for name in a.variables:
        x, y = a[name].values, b[name].values
        assert x.shape == y.shape, name
        if x.dtype.kind == "f":
            assert np.array_equal(x, y, equal_nan=True), name
        else:
            assert (x == y).all(), name
    assert a.attrs["accepted_steps"] == b.attrs["accepted_steps"]
