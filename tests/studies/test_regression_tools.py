"""The tools that show a restructuring changes no result and costs no speed:
studies/regression/hashes.py (digests of every output array, compared across
recordings) and studies/performance/compare.py (cracklab bench of two checkouts)."""
from __future__ import annotations

import importlib.util
import io
import json
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _load(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


hashes = _load("regression_hashes", ROOT / "studies" / "regression" / "hashes.py")
perf = _load("performance_compare", ROOT / "studies" / "performance" / "compare.py")


# ----------------------------------------------------------------------------- digests
def test_digest_sees_one_ulp_dtype_shape_and_sign_of_zero():
    a = np.linspace(0.0, 1.0, 12)
    d = hashes.array_digest(a)
    assert hashes.array_digest(a.copy()) == d
    b = a.copy()
    b[5] = np.nextafter(b[5], np.inf)
    assert hashes.array_digest(b) != d
    assert hashes.array_digest(a.astype(np.float32)) != d
    assert hashes.array_digest(a.reshape(3, 4)) != d
    assert hashes.array_digest(a.reshape(3, 4)) != hashes.array_digest(a.reshape(4, 3))
    assert hashes.array_digest(np.array([0.0])) != hashes.array_digest(np.array([-0.0]))
    # the bytes in C order: a transposed view hashes as its copy, not as its buffer
    m = a.reshape(3, 4)
    assert hashes.array_digest(m.T) == hashes.array_digest(np.ascontiguousarray(m.T))
    assert hashes.array_digest(m.T) != hashes.array_digest(m.reshape(4, 3))
    # object arrays (strings as Python objects) by their values
    assert hashes.array_digest(np.array(["a", "bc"], dtype=object)) == \
        hashes.array_digest(np.array(["a", "bc"], dtype=object).copy())
    assert hashes.array_digest(np.array(["a", "bc"], dtype=object)) != \
        hashes.array_digest(np.array(["a", "bd"], dtype=object))


def test_difference_reports_size_and_nan_pattern():
    base = np.array([1.0, 2.0, np.nan, 0.0])
    new = np.array([1.0, 2.0 * (1 + 1e-12), 3.0, 0.0])
    max_abs, max_rel, nan = hashes.difference(new, base)
    assert max_abs == pytest.approx(2e-12, rel=1e-3)
    assert max_rel == pytest.approx(1e-12, rel=1e-3)
    assert nan == 1
    assert hashes.difference(new, base[:3]) is None


# ----------------------------------------------------------------------------- comparing recordings
def _recording(path, arrays, toml="t = 1", package=None):
    """A recording of one case 'c' holding ``arrays``, written as the tool writes it."""
    entry = {"case": "c", "seconds": 0.0, "wall_seconds": 0.0,
             "arrays": {k: {"sha256": hashes.array_digest(a), "dtype": a.dtype.str, "shape": list(a.shape)}
                        for k, a in arrays.items()},
             hashes.SCENE_KEY: hashes.text_digest(toml), "package": package or {"commit": "x"}}
    data = {"format": hashes.FORMAT, "package": entry["package"], "environment": {}, "cache": {},
            "cases": {"c": entry}}
    Path(path).write_text(json.dumps(data))
    np.savez_compressed(hashes.npz_path(path), **{f"c/{k}": a for k, a in arrays.items()})
    return data


def _compare(a, b, **kw):
    out = io.StringIO()
    ok = hashes.compare_recordings(hashes.load(a), hashes.load(b), a, b, verbose=True, out=out, **kw)
    return ok, out.getvalue()


def test_compare_flags_a_changed_array_with_its_size(tmp_path):
    x = np.linspace(0.0, 1.0, 50).reshape(5, 10)
    y = x.copy()
    y[2, 3] = np.nextafter(y[2, 3], np.inf)
    _recording(tmp_path / "a.json", {"ds/u": x, "ds/t": np.arange(5.0)})
    _recording(tmp_path / "b.json", {"ds/u": y, "ds/t": np.arange(5.0)})
    _recording(tmp_path / "c.json", {"ds/u": x.copy(), "ds/t": np.arange(5.0)})
    ok, text = _compare(tmp_path / "a.json", tmp_path / "b.json")
    assert not ok
    row = next(line for line in text.splitlines() if "ds/u" in line)
    assert "DIFFERENT" in row and f"max abs {np.spacing(x[2, 3]):.3e}" in row
    assert next(line for line in text.splitlines() if "ds/t" in line).split()[2] == "same"
    assert _compare(tmp_path / "a.json", tmp_path / "c.json")[0]
    # the command line: exit 1 on a difference, 0 when identical
    assert hashes.main(["compare", str(tmp_path / "a.json"), str(tmp_path / "b.json")]) == 1
    assert hashes.main(["compare", str(tmp_path / "a.json"), str(tmp_path / "c.json")]) == 0


def test_compare_flags_missing_and_new_arrays_dtype_and_scene(tmp_path):
    x = np.arange(6.0)
    _recording(tmp_path / "a.json", {"ds/u": x, "ds/v": x})
    _recording(tmp_path / "b.json", {"ds/u": x.astype(np.float32), "ds/w": x})
    ok, text = _compare(tmp_path / "a.json", tmp_path / "b.json")
    assert not ok
    assert "MISSING" in text and "NEW" in text and "dtype/shape <f8(6,) -> <f4(6,)" in text
    _recording(tmp_path / "s.json", {"ds/u": x, "ds/v": x}, toml="t = 2")
    ok, text = _compare(tmp_path / "a.json", tmp_path / "s.json")
    assert not ok and "scene_toml" in text
    assert _compare(tmp_path / "a.json", tmp_path / "s.json", ignore_scene=True)[0]


def test_notes_on_the_caches_the_recordings_saw():
    base = {"environment": {"host": "h"}, "cache": {"dir": "/c", "files": {"expfit-1.npz": "a"},
                                                    "wisdom": {"fftw-wisdom-h.pickle": ["e1", "e2"]}}}
    grown = {"environment": {"host": "h"}, "cache": {"dir": "/c", "files": {"expfit-1.npz": "a"},
                                                     "wisdom": {"fftw-wisdom-h.pickle": ["e1", "e2", "e3"]}}}
    assert hashes.provenance_warnings(base, grown) == []  # plans of new sizes only
    replanned = {"environment": {"host": "h"}, "cache": {"dir": "/c", "files": {"expfit-1.npz": "b"},
                                                         "wisdom": {"fftw-wisdom-h.pickle": ["e1", "e3"]}}}
    notes = " ".join(hashes.provenance_warnings(base, replanned))
    assert "kernel-fit cache files changed" in notes and "wisdom entries of the base are gone" in notes
    other = {"environment": {"host": "g"}, "cache": {"dir": "/d", "files": {}, "wisdom": {}}}
    notes = " ".join(hashes.provenance_warnings(base, other))
    assert "different hosts" in notes and "different caches" in notes
    data = b"x(fftw_codelet_n1_4 0 #x10bdd)\n  (fftw_rdft_rank0_register 3 #x1)y(fftw_codelet_n1_4 0 #x10bdd)"
    assert len(hashes.wisdom_entries(data)) == 2


# ----------------------------------------------------------------------------- a real case, two processes
def test_tiny_case_is_identical_across_fresh_processes(tmp_path, capsys):
    a = hashes.record(tmp_path / "a.json", ["tiny_lamb", "tiny_modal"], progress=False)
    b = hashes.record(tmp_path / "b.json", ["tiny_lamb", "tiny_modal"], progress=False)
    assert a["package"]["source"] == str(ROOT / "cracklab")  # the package of this checkout ran
    lamb = a["cases"]["tiny_lamb"]["arrays"]
    assert {"ds/delta_2", "ds/rupture_time", "ds/t", "stations/delta_2", "stations/x1"} <= set(lamb)
    assert a["cases"]["tiny_lamb"][hashes.SCENE_KEY]
    assert hashes.compare_recordings(a, b, tmp_path / "a.json", tmp_path / "b.json", out=io.StringIO())
    with np.load(tmp_path / "a.npz") as z:  # the arrays are kept for the sizes of differences
        assert hashes.array_digest(z["tiny_lamb/ds/delta_2"]) == lamb["ds/delta_2"]["sha256"]
    # check: rerun (a third process) against the first recording
    assert hashes.main(["check", str(tmp_path / "a.json"), "--only", "tiny_lamb"]) == 0
    assert "IDENTICAL" in capsys.readouterr().out


# ----------------------------------------------------------------------------- speed comparison
def test_summary_of_alternated_benches():
    def run(ms, pair, rss):
        return {"ms_per_step": ms, "fft_pair_ms": pair, "peak_rss_mb": rss}

    a = [run(10.0, 2.0, 500), run(12.0, 3.0, 510), run(11.0, 2.0, 505)]
    b = [run(9.0, 2.0, 490), run(12.0, 2.0, 520), run(10.0, 2.0, 500)]
    s = perf.summarise(a, b)
    assert s["ms_per_step_a"] == 11.0 and s["ms_per_step_b"] == 10.0
    assert s["ratio"] == pytest.approx(10.0 / 11.0)
    assert s["ratio_min"] == pytest.approx(0.9) and s["ratio_max"] == pytest.approx(1.0)
    assert s["ratio_per_fft_pair"] == pytest.approx(10.0 / 11.0)  # rounds 0.9, 1.5, 10/11
    assert s["ratio_per_fft_pair_max"] == pytest.approx(1.5)
    assert s["ratio_best"] == pytest.approx(0.9)
    assert s["peak_rss_mb_a"] == 510 and s["peak_rss_mb_b"] == 520
    assert "| 512x512 I | 7 | 11.00 | 10.00 | 0.909 (0.900-1.000) |" in perf.table({"512x512 I": s},
                                                                                  {"512x512 I": 7})


def test_bench_runs_from_the_checkout():
    res = perf.bench(ROOT, (32, 32, "I"), 20)
    assert res["n1"] == 32 and res["engine_threads"] == 2 and res["ms_per_step"] > 0
    assert res["fft_pair_ms"] > 0 and res["peak_rss_mb"] > 0
    with pytest.raises(SystemExit):
        perf.checkout(ROOT / "docs")
