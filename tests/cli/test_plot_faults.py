"""cracklab plot of a fault run: slip and rupture-time figures, station series."""
import dataclasses

import pytest
from click.testing import CliRunner

import cracklab
from cracklab.cli import main


@pytest.fixture(scope="module")
def fault_store(tmp_path_factory):
    scene = cracklab.scenes.tpv3(dx=1500.0, t_end=3.0)
    scene = scene.replace(record=dataclasses.replace(scene.record, fields=("delta_1", "delta_3")))
    path = tmp_path_factory.mktemp("fault") / "tpv3.zarr"
    cracklab.simulate(scene, store=str(path))
    return path


def test_fault_run_default_figures_are_slip_and_rupture(fault_store, tmp_path):
    out = tmp_path / "figs"
    res = CliRunner().invoke(main, ["plot", str(fault_store), "-o", str(out)])
    assert res.exit_code == 0, res.output
    names = sorted(p.name for p in out.glob("*.png"))
    assert "rupture_time_contours.png" in names and "final_slip.png" in names
    assert "station_slip_rate.png" in names
    assert not any("crack_length" in n for n in names)
    assert all((out / n).stat().st_size > 1000 for n in names)


def test_station_plot(fault_store, tmp_path):
    out = tmp_path / "st.png"
    res = CliRunner().invoke(main, ["plot", str(fault_store), "--kind", "stations", "--station", "faultst000dp000",
                                    "--station", "faultst075dp000", "--field", "v_1", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert out.stat().st_size > 1000
    res = CliRunner().invoke(main, ["plot", str(fault_store), "--kind", "stations", "--station", "nowhere",
                                    "-o", str(tmp_path / "x.png")])
    assert res.exit_code != 0 and "nowhere" in res.output
