"""cracklab.analysis on synthetic fields whose answer is known, and on a tiny run."""
import numpy as np
import pytest
import xarray as xr

from cracklab import Record, analysis, scenes, simulate

N1, N3 = 256, 32
X1 = np.arange(N1) * 2.0 / N1
X3 = np.arange(N3) / N3
DX = X1[1]
T = np.linspace(0.5, 3.0, 26)
A = 0.01


def exact_front(t, x3=X3, a=A):
    return 0.1 + 0.3 * np.asarray(t)[:, None] + a * np.sin(2 * np.pi * x3)[None, :]


def coords(units="1"):
    return {"x1": ("x1", X1, {"units": units}), "x3": ("x3", X3, {"units": units}),
            "t": ("t", T, {"units": "s" if units == "m" else "1"})}


def rupture_dataset(units="1"):
    x1, x3 = np.meshgrid(X1, X3, indexing="ij")
    rt = (x1 - 0.1 - A * np.sin(2 * np.pi * x3)) / 0.3
    rt[rt < 0] = 0.0                      # the initial crack, failed at t = 0
    rt[x1 > 1.5] = np.nan                 # never reached
    return xr.Dataset({"rupture_time": (("x1", "x3"), rt)}, coords=coords(units))


def opening_dataset(zone=0.05, delta_c=0.02):
    """Opening falling linearly from delta_c at the tip to 0 a distance ``zone`` ahead."""
    x1 = X1[None, :, None]
    tip = exact_front(T)[:, None, :]
    d = np.clip(delta_c * (1 + (tip - x1) / zone), 0.0, None)
    return xr.Dataset({"delta_2": (("t", "x1", "x3"), d)}, coords=coords())


def test_front_from_rupture_time_is_exact():
    ds = rupture_dataset()
    front = analysis.front_position(ds, start=0.0)
    assert front.dims == ("t", "x3") and front.name == "front"
    np.testing.assert_allclose(front.values, exact_front(T), atol=1e-12)
    # a bare DataArray and explicit times
    times = np.array([0.7, 1.9])
    f2 = analysis.front_position(ds["rupture_time"], times=times, start=0.0)
    np.testing.assert_allclose(f2.values, exact_front(times), atol=1e-12)
    # the start line may vary along x3
    start = xr.DataArray(np.full(N3, 0.05), dims="x3", coords={"x3": X3})
    np.testing.assert_allclose(analysis.front_position(ds, start=start).values, exact_front(T), atol=1e-12)


def test_front_stops_where_nothing_fails_and_at_the_record_end():
    ds = rupture_dataset()
    late = analysis.front_position(ds, times=[10.0], start=0.0)      # reached x1 = 1.5, no further
    assert np.all(late.values <= 1.5) and np.all(late.values >= 1.5 - DX)
    broken = ds.assign(rupture_time=xr.zeros_like(ds["rupture_time"]))
    np.testing.assert_array_equal(analysis.front_position(broken, times=[1.0]).values, X1[-1])


def test_front_from_opening_is_exact():
    ds = opening_dataset()
    front = analysis.front_position(ds, delta_c=0.02, start=0.0)
    np.testing.assert_allclose(front.values, exact_front(T), atol=1e-12)
    # a delta_c field works the same
    dc = xr.DataArray(np.full((N1, N3), 0.02), dims=("x1", "x3"))
    np.testing.assert_allclose(analysis.front_position(ds["delta_2"], delta_c=dc, start=0.0).values,
                               exact_front(T), atol=1e-12)


def test_opening_front_does_not_heal():
    """A point that reached delta_c stays broken when its opening later drops."""
    ds = opening_dataset()
    d = ds["delta_2"].values.copy()
    d[-1] = 0.0
    front = analysis.front_position(ds.copy(data={"delta_2": d}), delta_c=0.02, start=0.0)
    np.testing.assert_allclose(front.values[-1], front.values[-2], atol=DX)


def test_mean_length_and_speed():
    front = analysis.front_position(rupture_dataset(units="m"), start=0.0)
    length = analysis.mean_crack_length(front)
    np.testing.assert_allclose(length.values, 0.1 + 0.3 * T, atol=1e-12)
    assert length.attrs["units"] == "m"
    for window in (None, 0.5):
        v = analysis.front_speed(length, window=window)
        np.testing.assert_allclose(v.values, 0.3, atol=1e-9)
        assert v.attrs["units"] == "m s-1"
    # per-x3 speed of the whole front
    np.testing.assert_allclose(analysis.front_speed(front).values, 0.3, atol=1e-9)


def test_speed_of_an_accelerating_front_with_noise():
    x = 0.1 + 0.3 * T + 0.05 * T**2
    da = xr.DataArray(x, dims="t", coords={"t": T})
    np.testing.assert_allclose(analysis.front_speed(da, window=0.5).values, 0.3 + 0.1 * T, atol=1e-9)
    noisy = da + 1e-3 * np.random.default_rng(0).standard_normal(T.size)
    raw = analysis.front_speed(noisy).values - (0.3 + 0.1 * T)
    smooth = analysis.front_speed(noisy, window=1.0).values - (0.3 + 0.1 * T)
    assert np.abs(smooth).max() < np.abs(raw).max()
    with pytest.raises(ValueError, match="uniformly spaced"):
        analysis.front_speed(da.assign_coords(t=T**2), window=0.5)


def test_cohesive_zone_size():
    for zone in (0.05, 0.1):
        cz = analysis.cohesive_zone(opening_dataset(zone=zone), delta_c=0.02, start=0.0)
        assert cz.dims == ("t", "x3") and cz.name == "cohesive_zone"
        assert np.all(np.abs(cz.values - zone) <= DX)
        assert abs(float(cz.mean()) - zone) < 0.6 * DX


def test_roughness_and_its_growth():
    front = analysis.front_position(rupture_dataset(), start=0.0)
    r = analysis.roughness(front)
    np.testing.assert_allclose(r["width"].values, A / np.sqrt(2), rtol=1e-9)
    np.testing.assert_allclose(r["advance"].values, 0.3 * (T - T[0]), atol=1e-12)
    # amplitude growing with the distance run: width proportional to the advance
    amp = 0.02 * (T - T[0])
    h = 0.1 + 0.3 * T[:, None] + amp[:, None] * np.sin(2 * np.pi * X3)[None, :]
    grown = xr.DataArray(h, dims=("t", "x3"), coords={"t": T, "x3": X3})
    r = analysis.roughness(grown).swap_dims(t="advance")
    slope = np.polyfit(r["advance"].values, r["width"].values, 1)[0]
    assert slope == pytest.approx(0.02 / 0.3 / np.sqrt(2), rel=1e-9)


def test_structure_function():
    front = analysis.front_position(rupture_dataset(), start=0.0)
    S = analysis.structure_function(front)
    assert S.dims == ("t", "lag") and S.sizes["lag"] == N3 // 2
    r = S["lag"].values
    np.testing.assert_allclose(S.values, np.broadcast_to(A**2 * (1 - np.cos(2 * np.pi * r)), S.shape),
                               rtol=1e-9, atol=1e-18)


def test_on_a_run_with_a_recorded_region():
    """Defaults from the run's scene: start at the tip of the initial crack, delta_c."""
    sc = scenes.asperity_row(n1=64, n3=32, t_end=0.75,
                             record=Record(fields=("delta_2",), every=12, region={"x1": (0.0, 1.0)}))
    res = simulate(sc)
    tip0 = analysis.initial_front(sc)
    np.testing.assert_allclose(tip0.values, 0.25 - sc.grid.dx1)      # last node of the crack
    lead = analysis.front_position(res)
    tip = analysis.front_position(res, method="opening")
    np.testing.assert_allclose(tip.isel(t=0).values, 0.25 - sc.grid.dx1)
    assert np.all(lead.values >= tip.values - 1e-12), "the zone's leading edge runs ahead of the tip"
    assert np.all(np.diff(tip.values, axis=0) >= 0), "the crack never shortens"
    assert float(analysis.mean_crack_length(tip).isel(t=-1)) > 0.3
    cz = analysis.cohesive_zone(res)
    late = cz.isel(t=-1)
    assert np.all(np.isfinite(late)) and np.all((late > 0) & (late < 0.2))
