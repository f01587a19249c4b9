"""Figures of a run and of an ensemble: files are written and not empty; crack length."""
import warnings

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


# ---------------------------------------------------------------------------- conventions
def _assert_nothing_clipped(fig):
    """Everything drawn (labels, titles, legends, colour bars) lies inside the figure."""
    fig.canvas.draw()
    drawn, box = fig.get_tightbbox(fig.canvas.get_renderer()), fig.bbox_inches
    tol = 0.01      # inches
    assert drawn.x0 >= box.x0 - tol and drawn.y0 >= box.y0 - tol and drawn.x1 <= box.x1 + tol \
        and drawn.y1 <= box.y1 + tol, f"clipped: {drawn} outside {box}"


def _legend_texts(fig):
    out = []
    for a in fig.axes:
        if a.get_legend() is not None:
            out += [t.get_text() for t in a.get_legend().get_texts()]
    out += [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    return out


def _plain(text):
    """No internal names: underscores only inside mathtext ($...$)."""
    outside = "".join(part for i, part in enumerate(text.split("$")) if i % 2 == 0)
    return "_" not in outside


def test_ensemble_figures_speak_plain_words_without_warnings(ens_store):
    import matplotlib.pyplot as plt

    ens = E.open_ensemble(ens_store)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        figs = [P.ensemble_summary(ens), P.ensemble_panels(ens), P.crack_length_plot(ens)]
    legends = _legend_texts(figs[0])
    assert "contrast = 1.5" in legends and "diameter = 0.25" in legends, legends
    assert all(_plain(t) for t in legends) and not any("correlation_length" in t for t in legends), legends
    assert any(P.FAILED_EDGE in t for t in _legend_texts(figs[1]))
    assert figs[0].axes[1].get_xlabel() == "diameter"
    for fig in figs:
        _assert_nothing_clipped(fig)
        assert all(_plain(a.get_title()) for a in fig.axes)
        plt.close(fig)


def test_parameter_labels():
    ds = xr.Dataset(coords={"law_delta_c": ("member", [0.1], {"parameter": "law.delta_c"}),
                            "record_every": ("member", [2], {"parameter": "record.every"}),
                            "loading_tau0_2": ("member", [1.0], {"parameter": "loading.tau0_2", "units": "Pa"}),
                            "correlation_length": ("member", [0.2])})
    assert P.parameter_label(ds, "law_delta_c") == r"$\delta_{c}$"
    assert P.parameter_label(ds, "record_every") == "record every"
    assert P.parameter_label(ds, "loading_tau0_2") == r"$\tau^{0}_{2}$ [Pa]"
    assert P.parameter_label(ds, "correlation_length") == "correlation length"


def _si_run(n3=8, nan=False):
    """A small run's Dataset in SI units (m, s): a straight front and a tau_c field of 1-2."""
    x1 = np.arange(16) * 10.0
    x3 = np.arange(n3) * 10.0
    rt = np.tile((x1 / 100.0)[:, None], (1, n3))
    rt[12:] = np.nan
    tau_c = 1.0 + (np.arange(16)[:, None] % 3 == 0) * np.ones((1, n3))
    t = np.array([0.0, 0.5, 1.0])
    d2 = np.where(np.isnan(rt)[None] | nan, np.nan, np.maximum(t[:, None, None] - np.nan_to_num(rt)[None], 0))
    coords = {"t": ("t", t, {"units": "s", "long_name": "time"}),
              "x1": ("x1", x1, {"units": "m", "long_name": "distance along x1"}),
              "x3": ("x3", x3, {"units": "m", "long_name": "distance along x3"})}
    return xr.Dataset({"rupture_time": (("x1", "x3"), rt, {"units": "s", "long_name": "first time the point failed"}),
                       "delta_2": (("t", "x1", "x3"), d2, {"units": "m", "long_name": "opening"}),
                       "input_law_tau_c": (("input_x1", "input_x3"), tau_c,
                                           {"units": "Pa", "long_name": "scene input law.tau_c"})},
                      coords=coords, attrs={"scene": '{"grid": {"n1": 16, "n3": %d, "L1": 160.0, "L3": %r}, '
                                                     '"t_end": 1.0}' % (n3, 10.0 * n3)})


def test_axes_carry_units_and_the_background_its_own_range():
    import matplotlib.pyplot as plt

    ds = _si_run()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = P.rupture_contours(ds)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "distance along x1 [m]" and ax.get_ylabel() == "distance along x3 [m]"
    labels = [a.get_ylabel() for a in fig.axes[1:]]
    assert "first time the point failed [s]" in labels and "tau_c [Pa]" in labels, labels
    mesh = ax.collections[0]
    assert (mesh.norm.vmin, mesh.norm.vmax) == (1.0, 2.0)       # the field's range, not beyond it
    _assert_nothing_clipped(fig)
    plt.close(fig)
    fig = P.crack_length_plot(ds)
    assert fig.axes[0].get_xlabel() == "time [s]" and fig.axes[0].get_ylabel().endswith("[m]")
    plt.close(fig)


def test_plane_snapshots_are_lines_and_nan_fields_do_not_warn(tmp_path):
    import matplotlib.pyplot as plt
    from matplotlib.collections import QuadMesh

    plane = _si_run(n3=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = P.snapshot(plane)
        ax = fig.axes[0]
        assert len(ax.lines) == 1 and len(ax.lines[0].get_xdata()) == 16
        assert not [c for c in ax.collections if isinstance(c, QuadMesh)]
        assert ax.get_xlabel() == "distance along x1 [m]" and ax.get_ylabel() == "opening [m]"
        plt.close(fig)
        gif = P.animate(plane, tmp_path / "plane.gif")
        with Image.open(gif) as im:
            assert im.n_frames == 3
        fig = P.rupture_contours(plane)
        assert len(fig.axes[0].lines) == 1 and fig.axes[0].get_ylabel() == "first time the point failed [s]"
        plt.close(fig)
        unfinished = _si_run(nan=True)           # snapshots not written yet: all NaN
        plt.close(P.snapshot(unfinished))
        P.animate(unfinished, tmp_path / "nan.gif")


def test_a_3d_snapshot_carries_units_and_fits_the_figure(tmp_path):
    import matplotlib.pyplot as plt

    ds = _si_run()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = P.snapshot(ds, t=0.5)
    ax, bar = fig.axes
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("distance along x1 [m]", "distance along x3 [m]")
    assert bar.get_ylabel() == "opening [m]" and ax.get_title() == "opening at t = 0.5"
    _assert_nothing_clipped(fig)
    plt.close(fig)
    fig = P.snapshot(_si_run(n3=1))
    _assert_nothing_clipped(fig)
    plt.close(fig)


def test_the_toughness_background_of_a_real_run_spans_its_own_range(run_store):
    """The asperity run's tau_c is 1 outside the asperities and 3 (the contrast) inside:
    the grey background and its colour bar span exactly that."""
    import matplotlib.pyplot as plt

    ds = xr.open_zarr(run_store, consolidated=False)
    tau_c = cracklab.scene_of(ds).law.tau_c
    lo, hi = float(tau_c.min()), float(tau_c.max())
    assert (lo, hi) == (1.0, 3.0)
    fig = P.rupture_contours(ds)
    mesh = fig.axes[0].collections[0]
    assert (mesh.norm.vmin, mesh.norm.vmax) == (lo, hi)
    bar = next(a for a in fig.axes[1:] if a.get_ylabel().startswith("tau_c"))
    assert bar.get_ylim() == (lo, hi), bar.get_ylim()
    plt.close(fig)


def test_figures_of_an_ensemble_padded_with_nan_do_not_warn(tmp_path):
    """Members recorded every 2 and every 4 steps: open_ensemble pads the sparser ones with
    NaN snapshots; every figure of it, and of those members, draws without a warning (no
    "All-NaN slice") and the padded member's snapshot is its own last one."""
    import matplotlib.pyplot as plt

    store = tmp_path / "pad.zarr"
    res = E.run(E.Builder("asperity_row", n1=32, n3=16, t_end=22 * 0.03125, diameter=0.25),      # 22 steps
                E.Sweep(product={"contrast": [1.5, 3.0], "record.every": [2, 4]}), store,
                scheduler="synchronous", progress=False)
    assert res.ok, res.summary()
    ens = E.open_ensemble(store)
    sparse = int(np.nonzero(ens.record_every.values == 4)[0][0])
    assert np.isnan(ens.delta_2.isel(member=sparse).values).any()          # the padding is there
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        paths = P.summary_figures(ens, tmp_path / "figs", gif_member=sparse)
        fig = P.snapshot(ens, member=sparse)
    assert len(paths) == 3 and all(p.stat().st_size > 2000 for p in paths)
    own = E.open_member(store, str(ens.member.values[sparse]))
    assert float(own.t[-1]) < float(ens.t[-1])                             # it ends before the others
    assert fig.axes[0].get_title().endswith(f" at t = {float(own.t[-1]):.3g}"), fig.axes[0].get_title()
    plt.close(fig)
