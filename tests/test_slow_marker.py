"""The ``slow`` marker: registered, and its list (tests/conftest.py, SLOW) names tests
that exist, so that it cannot silently mark nothing."""
from __future__ import annotations

import re
import tomllib
from pathlib import Path

import conftest

ROOT = Path(__file__).resolve().parents[1]


def test_the_marker_is_registered():
    ini = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    assert any(m.split(":", 1)[0] == "slow" for m in ini["markers"])


def test_every_listed_slow_test_exists():
    assert conftest.SLOW
    for entry in sorted(conftest.SLOW):
        path, _, name = entry.partition("::")
        source = ROOT / path
        assert source.is_file() and path.startswith("tests/") and path.endswith(".py"), entry
        if name:
            assert re.search(rf"^\s*(async )?def {re.escape(name)}\(", source.read_text(), flags=re.M), entry


def test_node_ids_match_a_file_or_a_test_with_its_parametrizations():
    saved = conftest.SLOW
    try:
        conftest.SLOW = frozenset({"tests/a/test_x.py", "tests/b/test_y.py::test_run"})
        assert conftest.is_slow("tests/a/test_x.py::test_anything[1]")
        assert conftest.is_slow("tests/b/test_y.py::test_run")
        assert conftest.is_slow("tests/b/test_y.py::test_run[100.0-product]")
        assert not conftest.is_slow("tests/b/test_y.py::test_run_quick")
        assert not conftest.is_slow("tests/b/test_y.py::test_other[test_run]")
        assert not conftest.is_slow("tests/a/test_x2.py::test_anything")
    finally:
        conftest.SLOW = saved
