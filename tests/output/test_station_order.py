"""``cracklab.stations`` lists its variables in the recorder's order, from memory and from
a store alike."""
import cracklab
from cracklab import Record


def test_station_variables_come_in_the_recorders_order(tmp_path):
    rec = Record(fields=("delta_2",), every=8, stations={"A": (0.5, 0.5)})
    scene = cracklab.scenes.lamb(n=16, t_end=0.1, record=rec)
    want = ["delta_2", "v_2", "tau_2", "strength"]
    assert list(cracklab.stations(cracklab.simulate(scene)).data_vars) == want
    ds = cracklab.simulate(scene, store=tmp_path / "r.zarr", checkpoint_every=0)
    assert list(cracklab.stations(ds).data_vars) == want
