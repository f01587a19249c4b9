"""Where the benchmark studies find their reference (studies/benchmarks/harness.py,
docs/developer/developer.md "Add a benchmark study"): the command line's folder first, then
$CRACKLAB_REFERENCE/<name>, then shared/reference/<name> beside the repository."""
from __future__ import annotations

import pytest

from studies.benchmarks import harness as H


def test_the_reference_folder_given_wins(tmp_path, monkeypatch):
    monkeypatch.setenv(H.REFERENCE_ENV, str(tmp_path / "env"))
    assert H.reference_dir("tpv3_mdsbi", tmp_path / "given") == tmp_path / "given"


def test_the_environment_names_the_folder_of_the_references(tmp_path, monkeypatch):
    monkeypatch.setenv(H.REFERENCE_ENV, str(tmp_path))
    assert H.reference_dir("tpv5_mdsbi") == tmp_path / "tpv5_mdsbi"


def test_beside_the_repository_or_an_error(tmp_path, monkeypatch):
    monkeypatch.delenv(H.REFERENCE_ENV, raising=False)
    repo = tmp_path / "work" / "cracklab"
    repo.mkdir(parents=True)
    monkeypatch.setattr(H, "ROOT", repo)
    with pytest.raises(FileNotFoundError, match=H.REFERENCE_ENV):
        H.reference_dir("tpv6_mdsbi")
    beside = tmp_path / "work" / "shared" / "reference" / "tpv6_mdsbi"
    beside.mkdir(parents=True)
    assert H.reference_dir("tpv6_mdsbi") == beside
