"""The SEAS platform's files of a BP1-QD run (issue 35 point 4): the on-fault station files
and devol.dat as the BP1 description lays them out, their values those of the run, and the
state at t = 0 the benchmark's initial theta in closed form."""
import numpy as np
import pytest


@pytest.fixture(scope="module")
def run():
    import cracklab

    return cracklab.simulate(cracklab.scenes.bp1(dz=400.0, years=60.0))


def _parse(path):
    lines = path.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    body = [ln for ln in lines if not ln.startswith("#")]
    return head, body


def test_station_files(run, tmp_path):
    from cracklab import stations
    from cracklab.output.seas import FIELDS, export_seas
    from cracklab.scenes import BP1_DEPTHS
    from cracklab.scenes.seas import BP1

    written = export_seas(run, tmp_path, author="tests")
    names = sorted(p.name for p in written)
    assert names == sorted([f"fltst_dp{int(round(10 * d)):03d}" for d in BP1_DEPTHS] + ["devol.dat"])
    st = stations(run)
    p = BP1
    eta = p["rho"] * p["cs"] / 2
    for d in (0.0, 7.5, 35.0):
        name = f"fltst_dp{int(round(10 * d)):03d}"
        head, body = _parse(tmp_path / name)
        assert "# problem=SEAS Benchmark No.1" in head and "# author=tests" in head
        assert any(h.startswith("# location=on fault, ") for h in head)
        assert body[0] == FIELDS
        data = np.array([[float(x) for x in ln.split()] for ln in body[1:]])
        assert data.shape == (run.sizes["t_station"], 5) and np.all(np.diff(data[:, 0]) > 0)
        s = st.sel(station=name)
        np.testing.assert_allclose(data[:, 1], s.delta_3.values, rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(data[:, 2], np.log10(s.v_3.values), rtol=1e-6)
        np.testing.assert_allclose(data[:, 3], s.tau_3.values / 1e6, rtol=1e-6)
        # theta at t = 0 (the BP1 description, section 3): the state that slides at V_init under tau0
        z = 1e3 * d
        a = p["a0"] if z < p["H"] else p["a_max"] if z >= p["H"] + p["h"] else \
            p["a0"] + (p["a_max"] - p["a0"]) * (z - p["H"]) / p["h"]
        Vi, V0, sig = p["V_init"], p["V0"], p["sigma_n"]
        tau0 = sig * p["a_max"] * np.arcsinh(Vi / (2 * V0) * np.exp((p["f0"] + p["b0"] * np.log(V0 / Vi)) / p["a_max"])) \
            + eta * Vi
        theta0 = p["D_c"] / V0 * np.exp(a / p["b0"] * np.log(2 * V0 / Vi * np.sinh((tau0 - eta * Vi) / (a * sig)))
                                        - p["f0"] / p["b0"])
        assert data[0, 4] == pytest.approx(np.log10(theta0), rel=1e-6)     # the 14.6E format


def test_slip_evolution_file(run, tmp_path):
    from cracklab.output.seas import export_seas

    export_seas(run, tmp_path)
    head, body = _parse(tmp_path / "devol.dat")
    assert body[0] == "z" and body[1] == "t max_slip_rate slip"
    z = np.array([float(x) for x in body[2].split()])
    assert z[:2].tolist() == [0.0, 0.0] and len(z) == 83 and z[2] == 0.0 and z[-1] == 40000.0
    rows = np.array([[float(x) for x in ln.split()] for ln in body[3:]])
    assert rows.shape == (run.sizes["t"], 83) and np.all(np.diff(rows[:, 0]) >= 0)
    np.testing.assert_allclose(rows[:, 2:], run.delta_3.isel(x3=0).sel(x1=z[2:], method="nearest").values,
                               rtol=1e-6, atol=1e-12)
    assert np.all(rows[:, 1] >= -9.5)          # log10 of the largest slip rate, at least the plate's
