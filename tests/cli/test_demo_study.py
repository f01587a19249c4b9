"""`cracklab demo` finds the study it runs in the source checkout."""
from pathlib import Path

from cracklab.cli.demo import STUDY

ROOT = Path(__file__).resolve().parents[2]


def test_demo_study_is_the_checkouts_study_file():
    assert STUDY == ROOT / "studies" / "asperity_ensemble" / "study.toml"
    assert STUDY.is_file()
