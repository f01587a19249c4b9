"""cracklab plot refuses a damaged run store instead of drawing blank pictures."""
import shutil

import pytest
from click.testing import CliRunner

from cracklab.cli import main

from tests.cli.test_cli import scene_toml


@pytest.fixture
def run_store(tmp_path):
    store = tmp_path / "a.zarr"
    res = CliRunner().invoke(main, ["run", str(scene_toml(tmp_path)), "-o", str(store)])
    assert res.exit_code == 0, res.output
    return store


def _chunks(array_dir):
    return sorted(p for p in (array_dir / "c").rglob("*") if p.is_file())


@pytest.mark.parametrize("damage", ["chunk", "variable"])
def test_plot_refuses_a_damaged_run(run_store, tmp_path, damage):
    if damage == "chunk":
        chunks = _chunks(run_store / "delta_2")
        assert chunks
        chunks[0].unlink()
    else:
        shutil.rmtree(run_store / "v_2")
    out = tmp_path / "figs"
    res = CliRunner().invoke(main, ["plot", str(run_store), "-o", str(out)])
    assert res.exit_code != 0
    assert str(run_store) in res.output
    assert "is damaged" in res.output and "--resume" in res.output   # what and the remedy
    assert len([line for line in res.output.splitlines() if line.strip()]) == 1
    assert not out.exists() or not any(out.iterdir())


def test_plot_of_an_intact_run_still_draws(run_store, tmp_path):
    out = tmp_path / "figs"
    res = CliRunner().invoke(main, ["plot", str(run_store), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert list(out.glob("*.png"))
