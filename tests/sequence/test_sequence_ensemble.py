"""An ensemble of sequences (issue 35, point 6): a sweep of BP1-QD over the depth of the
velocity-weakening zone runs into one store, opens with `open_ensemble`, and gives every
member's event catalogue as one tidy table."""
import numpy as np


def test_a_sweep_of_bp1_gives_a_tidy_event_table(tmp_path):
    import cracklab
    from cracklab import ensemble

    study = tmp_path / "study.toml"
    study.write_text('[study]\nname = "vw"\nbuilder = "bp1"\n[base]\ndz = 400.0\nyears = 250.0\ntolerance = 1e-6\n'
                     '[sweep]\nH = [12500.0, 15000.0]\n')
    result = ensemble.run_study(study, tmp_path / "ens.zarr", scheduler="synchronous", progress=False)
    assert result.summary().startswith("2 members: 2 ran")
    ens = cracklab.open_ensemble(tmp_path / "ens.zarr")
    table = cracklab.analysis.events(ens).to_dataframe().dropna(subset=["t_start"]).reset_index()
    assert set(table["H"]) == {12500.0, 15000.0}
    for H, rows in table.groupby("H"):
        alone = cracklab.analysis.events(cracklab.simulate(cracklab.scenes.bp1(dz=400.0, years=250.0,
                                                                                tolerance=1e-6, H=H)))
        np.testing.assert_array_equal(rows["t_start"].values, alone.t_start.values)   # each member's own run
        assert len(rows) >= 1 and np.all(rows["peak_slip_rate"] > 1e-3)
