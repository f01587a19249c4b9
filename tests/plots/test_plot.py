"""Figures of a run and of an ensemble: files are written and not empty; crack length."""
import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner
from PIL import Image

import cracklab
from cracklab import ensemble as E
from cracklab import plots as P
from cracklab.cli import main

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def run_store(tmp_path_factory):
    store = tmp_path_factory.mktemp("run") / "run.zarr"
    scene = cracklab.scenes.asperity_row(n1=32, n3=16, t_end=0.6, diameter=0.25,
                                         record=cracklab.Record(fields=("delta_2", "v_2"), every=2))
    cracklab.simulate(scene, store=str(store))
    return store


@pytest.fixture(scope="module")
def ens_store(tmp_path_factory):
    store = tmp_path_factory.mktemp("ens") / "ens.zarr"
    sweep = E.Sweep(product={"diameter": [0.25, 0.375], "contrast": [1.5, 3.0]},
                    members=[{"builder": "random_toughness", "cov": 0.1, "correlation_length": 0.25}],
                    entropy=1, base={"record.every": 4})
    res = E.run(E.Builder("asperity_row", n1=32, n3=16, t_end=0.6), sweep, store, scheduler="synchronous",
                progress=False)
    assert res.ok, res.summary()
    return store


def _png(path):
    data = path.read_bytes()
    assert len(data) > 2000 and data[:8] == PNG
    with Image.open(path) as im:
        assert im.size[0] > 200 and im.size[1] > 100
        return np.asarray(im.convert("RGB"))


def test_run_figures(run_store, tmp_path):
    ds = xr.open_zarr(run_store, consolidated=False)
    P.snapshot(ds, "v_2", t=0.3, path=tmp_path / "snap.png")
    img = _png(tmp_path / "snap.png")
    assert img.std() > 10          # not a blank image
    P.rupture_contours(ds, path=tmp_path / "rt.png")
    _png(tmp_path / "rt.png")
    P.crack_length_plot(ds, path=tmp_path / "len.png")
    _png(tmp_path / "len.png")
    gif = P.animate(ds, tmp_path / "d2.gif", "delta_2")
    with Image.open(gif) as im:
        assert im.format == "GIF" and im.n_frames == ds.sizes["t"]
    with pytest.raises(ValueError, match="no field"):
        P.snapshot(ds, "tau_1")


def test_crack_length_is_failed_area_over_L3():
    x1 = np.arange(8) * 0.25
    x3 = np.arange(4) * 0.25
    rt = np.tile(x1[:, None], (1, 4))          # a straight front moving at unit speed
    rt[6:] = np.nan                            # never failed
    rt[0, 0] = 0.1
    ds = xr.Dataset({"rupture_time": (("x1", "x3"), rt)}, coords={"x1": x1, "x3": x3},
                    attrs={"scene": '{"grid": {"n1": 8, "n3": 4, "L1": 2.0, "L3": 1.0}, "t_end": 2.0}'})
    L = P.crack_length(ds, t=[0.0, 0.05, 0.1, 0.5, 2.0])
    cell = 0.25 * 0.25 / 1.0
    np.testing.assert_allclose(L.values, np.array([3, 3, 4, 12, 24]) * cell)


def test_ensemble_figures_and_cli(ens_store, run_store, tmp_path):
    ens = E.open_ensemble(ens_store)
    L = P.crack_length(ens)
    assert L.dims == ("member", "t") and "contrast" in L.coords
    assert np.all(np.diff(L.values, axis=1) >= 0) and np.all(L.values[:, 0] > 0)
    P.ensemble_summary(ens, path=tmp_path / "summary.png")
    _png(tmp_path / "summary.png")
    P.ensemble_panels(ens, path=tmp_path / "panels.png")
    _png(tmp_path / "panels.png")
    P.snapshot(ens, member=1, path=tmp_path / "member.png")
    _png(tmp_path / "member.png")
    with pytest.raises(ValueError, match="give member="):
        P.snapshot(ens)

    runner = CliRunner()
    res = runner.invoke(main, ["plot", str(ens_store), "-o", str(tmp_path / "all")])
    assert res.exit_code == 0, res.output
    written = sorted(p.name for p in (tmp_path / "all").iterdir())
    assert "crack_length.png" in written and "rupture_panels.png" in written
    assert any(n.endswith(".gif") for n in written)
    for kind, name in (("gif", "m.gif"), ("snapshot", "s.png"), ("length", "l.png")):
        res = runner.invoke(main, ["plot", str(ens_store), "--kind", kind, "--member", "2",
                                   "-o", str(tmp_path / name)])
        assert res.exit_code == 0, res.output
        assert (tmp_path / name).stat().st_size > 2000
    res = runner.invoke(main, ["plot", str(run_store), "--kind", "rupture", "-o", str(tmp_path / "r.png")])
    assert res.exit_code == 0, res.output
    _png(tmp_path / "r.png")
    res = runner.invoke(main, ["plot", str(run_store), "--kind", "summary"])
    assert res.exit_code != 0 and "needs an ensemble" in res.output
