"""Stored data that cannot be silently wrong (docs/guide/reliability.md, "Stored data:
checksums, verification and the order of writes"): every chunk carries a crc32c
checksum; ``cracklab verify`` and every rerun or resume find a deleted chunk, a changed
byte or damaged metadata and name the file; a damaged store or member is recomputed,
never served; errors on damaged stores name the file and what to do; the status of a
run is written last (a kill -9 during the final write leaves a store that is not
complete, and ``--resume`` finishes it); a member's replacement is atomic for readers."""
import importlib
import json
import os
import signal
import subprocess
import sys
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import zarr
from click.testing import CliRunner

import cracklab
from cracklab import Record
from cracklab.output import checkpoint as ck
from cracklab import ensemble as E
from small_ensemble import copy_of, member_ids, sound_ensemble, sweep
from cracklab.output import verify as V
from cracklab.cli import main
from cracklab.errors import StoreError, StoreWarning
from cracklab.model.scene_io import scene_to_toml
from interrupt import interrupted_run

SIM = importlib.import_module("cracklab.output.simulate")
ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent


def _scene(t_end=0.5):
    return cracklab.scenes.elliptical_crack(n=32, a=0.25, b=0.2, t_end=t_end,
                                            record=Record(fields=("delta_2",), every=2,
                                                          stations={"c": (0.5, 0.5)}))


def _same(ref, res):
    assert set(ref.data_vars) == set(res.data_vars)
    for name in list(ref.data_vars) + list(ref.coords):
        a, b = np.asarray(ref[name].values), np.asarray(res[name].values)
        if a.dtype.kind == "f":
            np.testing.assert_array_equal(a, b, err_msg=name)
        else:
            assert (a == b).all(), name


def _flip(path, at=None):
    """Change one byte of the file ``path`` (in the middle of it by default)."""
    data = bytearray(Path(path).read_bytes())
    i = len(data) // 2 if at is None else at
    data[i] ^= 0x10
    Path(path).write_bytes(bytes(data))


def _chunk(store, name, *index):
    return Path(store) / name / "c" / "/".join(map(str, index))


def _verify_cli(store, *extra):
    res = CliRunner().invoke(main, ["verify", str(store), *extra])
    return res.exit_code, res.output


@pytest.fixture(scope="module")
def reference():
    return cracklab.simulate(_scene()).load()


@pytest.fixture
def run_store(tmp_path):
    store = tmp_path / "run.zarr"
    cracklab.simulate(_scene(), store=store)
    return store


# ---------------------------------------------------------------------------- checksums
def test_every_array_is_checksummed_and_a_changed_byte_raises(run_store, reference):
    arrays = [d for d in run_store.iterdir() if (d / "zarr.json").exists()]
    assert {"delta_2", "t", "rupture_time", "station_delta_2", "station", "input_loading_tau0_2"} <= \
        {d.name for d in arrays}
    for d in arrays:
        codecs = [c["name"] for c in json.loads((d / "zarr.json").read_text())["codecs"]]
        assert codecs[-1] == "crc32c", (d.name, codecs)
    code, out = _verify_cli(run_store)
    assert code == 0 and out.splitlines()[0].endswith(": sound"), out
    _flip(_chunk(run_store, "delta_2", 1, 0, 0))
    with pytest.raises(ValueError, match="checksum"):          # raises, never wrong values
        xr.open_zarr(run_store, consolidated=False)["delta_2"].values
    code, out = _verify_cli(run_store)
    assert code == 1, out
    assert f"DAMAGED {_chunk(run_store, 'delta_2', 1, 0, 0)}: chunk (1, 0, 0) of delta_2 cannot be read " \
           f"(checksum mismatch" in out
    assert "what to do: " in out and "--resume" in out
    # --quick reads no data: the changed byte is not seen, a missing chunk is
    assert _verify_cli(run_store, "--quick")[0] == 0
    _chunk(run_store, "station_v_2", 0, 0).unlink()
    code, out = _verify_cli(run_store, "--quick")
    assert code == 1 and f"{_chunk(run_store, 'station_v_2', 0, 0)}: chunk (0, 0) of station_v_2 is missing" in out


def test_chunks_holding_only_nan_are_written(tmp_path):
    """A point that never breaks keeps rupture_time NaN: its chunk is stored anyway, so a
    missing chunk always means damage (a store written with Zarr's default would not)."""
    import dataclasses

    sc = _scene(0.05)
    sc = sc.replace(numerics=dataclasses.replace(sc.numerics, rupture_threshold=1e12))     # nothing breaks
    store = tmp_path / "run.zarr"
    res = cracklab.simulate(sc, store=store)
    assert np.isnan(res["rupture_time"].values).all()
    assert _chunk(store, "rupture_time", 0, 0).exists()
    assert V.verify(store).ok


def test_a_store_written_without_checksums_is_read_and_reported(tmp_path, monkeypatch):
    monkeypatch.setattr(ck, "encoding", lambda ds, skip=(): {})
    store = tmp_path / "old.zarr"
    cracklab.simulate(_scene(0.05), store=store)
    monkeypatch.undo()
    report = V.verify(store)
    assert report.ok and len(report.unchecksummed) >= 10
    code, out = _verify_cli(store)
    assert code == 0 and "no checksums in" in out and "written by an older cracklab" in out


# ---------------------------------------------------------------------------- run stores
def test_resume_of_a_damaged_complete_store_recomputes_it(run_store, reference, tmp_path):
    missing = _chunk(run_store, "delta_2", 2, 0, 0)
    missing.unlink()
    with pytest.warns(StoreWarning, match=f"store {run_store} is damaged: {missing}: chunk .* is missing"):
        res = cracklab.simulate(_scene(), store=run_store, resume=True).load()
    _same(reference, res)
    assert V.verify(run_store).ok
    # the command line says so, and ends with a sound store
    _flip(_chunk(run_store, "station_tau_2", 0, 0))
    toml = tmp_path / "scene.toml"
    toml.write_text(scene_to_toml(_scene()))
    out = CliRunner().invoke(main, ["run", str(toml), "-o", str(run_store), "--resume", "--no-progress"])
    assert out.exit_code == 0, out.output
    assert f"is damaged: {_chunk(run_store, 'station_tau_2', 0, 0)}: chunk (0, 0) of station_tau_2 cannot be " \
           f"read (checksum mismatch" in out.output
    assert "done again from the start" in out.output and f"cracklab: wrote {run_store}" in out.output
    assert V.verify(run_store).ok
    _same(reference, xr.open_zarr(run_store, consolidated=False).load())
    # a sound complete store is returned as it is, without a warning
    before = {p: p.stat().st_mtime_ns for p in run_store.rglob("*") if p.is_file()}
    with warnings.catch_warnings():
        warnings.simplefilter("error", StoreWarning)
        cracklab.simulate(_scene(), store=run_store, resume=True)
    assert {p: p.stat().st_mtime_ns for p in run_store.rglob("*") if p.is_file()} == before


@pytest.mark.parametrize("damage", ["changed byte", "deleted chunk", "deleted metadata"])
def test_damage_before_a_checkpoint_is_not_carried_into_a_complete_store(damage, tmp_path, monkeypatch,
                                                                          reference):
    sc = _scene()
    store = interrupted_run(sc, tmp_path / "run.zarr", monkeypatch, stop=25, checkpoint_every=10)
    assert ck.read(store)["nsnap"] == 11
    target = {"changed byte": _chunk(store, "delta_2", 0, 0, 0), "deleted chunk": _chunk(store, "delta_2", 1, 0, 0),
              "deleted metadata": store / "delta_2" / "zarr.json"}[damage]
    if damage == "changed byte":
        _flip(target)
    else:
        target.unlink()      # resumed as it was, this crashed: "dataset contains non-pre-existing variables"
    report = V.verify(store)
    assert [d.path for d in report.damage] == [str(target)] and report.status == "running"
    with pytest.warns(StoreWarning, match=f"is damaged: {target}.*checkpoint after step 20 cannot be resumed"):
        res = cracklab.simulate(sc, store=store, resume=True).load()
    _same(reference, res)
    assert res.attrs["cracklab_status"] == "complete" and V.verify(store).ok


def test_damage_past_the_checkpoint_is_rewritten_by_the_resume(tmp_path, monkeypatch, reference):
    sc = _scene()
    store = interrupted_run(sc, tmp_path / "run.zarr", monkeypatch, stop=25, checkpoint_every=10)
    # snapshots 0-10 belong to the checkpoint; chunk 2 (snapshots 16-23) is past it
    _chunk(store, "delta_2", 2, 0, 0).unlink(missing_ok=True)
    assert V.verify(store).ok
    with warnings.catch_warnings():
        warnings.simplefilter("error", StoreWarning)
        res = cracklab.simulate(sc, store=store, resume=True).load()
    _same(reference, res)


def test_a_garbled_root_metadata_is_named(run_store):
    (run_store / "zarr.json").write_text('{"zarr_format": 3, "node_type": "gro')
    with pytest.raises(StoreError, match=f"its metadata file {run_store / 'zarr.json'} is damaged"):
        cracklab.simulate(_scene(), store=run_store, resume=True)
    code, out = _verify_cli(run_store)
    assert code == 1 and f"{run_store / 'zarr.json'}: the store's root metadata is not valid JSON" in out


def test_export_of_a_damaged_run_names_the_file(run_store, tmp_path):
    bad = _chunk(run_store, "delta_2", 0, 0, 0)
    bad.write_bytes(bad.read_bytes()[:40])      # truncated: once "Zstd decompression error", no file
    res = CliRunner().invoke(main, ["export", str(run_store), "--netcdf", str(tmp_path / "a.nc")])
    assert res.exit_code == 1 and len(res.output.strip().splitlines()) == 1, res.output
    assert f"Error: store {run_store}: is damaged: {bad}: chunk (0, 0, 0) of delta_2 cannot be read" in res.output
    assert "--resume" in res.output and not (tmp_path / "a.nc").exists()
    bad.unlink()
    res = CliRunner().invoke(main, ["export", str(run_store), "--netcdf", str(tmp_path / "a.nc")])
    assert res.exit_code == 1 and f"{bad}: chunk (0, 0, 0) of delta_2 is missing" in res.output


# ---------------------------------------------------------------------------- status last
def test_the_status_is_written_after_every_array(tmp_path, monkeypatch):
    from cracklab.output.stores import LocalStore

    writes = []
    real = LocalStore.write

    def put(self, path, value, exclusive=False):
        path = Path(path)
        status = None
        if path.name == "zarr.json" and path.parent == store:
            status = json.loads(bytes(value.as_buffer_like()))["attributes"].get("cracklab_status")
        writes.append((path, status))
        return real(self, path, value, exclusive)

    store = tmp_path / "run.zarr"
    monkeypatch.setattr(LocalStore, "write", put)
    cracklab.simulate(_scene(), store=store)
    done = [i for i, (_, s) in enumerate(writes) if s == "complete"]
    assert done, "the status was never written"
    data = [i for i, (p, _) in enumerate(writes) if p.parent != store]
    assert done[0] > max(data), [(str(p.relative_to(store)), s) for p, s in writes[-12:]]
    finals = {p.relative_to(store).parts[0] for p, _ in writes[data[0]:] if p.parent != store}
    assert {"rupture_time", "station_delta_2", "t_station"} <= finals


KILLER = r"""
import os, signal, sys
import importlib
from cracklab.output.stores import LocalStore
from cracklab import cli
S = importlib.import_module("cracklab.output.simulate")

state = {"armed": False, "n": 0}
real_finish, real_put = S.Recorder.finish, LocalStore.write
after = int(os.environ["KILL_AFTER"])

def finish(self, *a, **k):
    state["armed"] = True
    return real_finish(self, *a, **k)

def put(self, path, value, exclusive=False):
    if state["armed"] and "/station_" in str(path) and str(path).endswith("zarr.json") is False:
        state["n"] += 1
        if state["n"] > after:
            os.kill(os.getpid(), signal.SIGKILL)      # kill -9 in the middle of the final write
    return real_put(self, path, value, exclusive)

S.Recorder.finish, LocalStore.write = finish, put
sys.argv = ["cracklab"] + sys.argv[1:]
cli.main()
"""


def _cli(*args, env=None, script=None):
    cmd = [sys.executable, "-c", script, *args] if script else [sys.executable, "-m", "cracklab.cli", *args]
    return subprocess.run(cmd, cwd=ROOT, env={**os.environ, **(env or {})}, capture_output=True, text=True,
                          timeout=300)


@pytest.fixture(scope="module")
def cli_reference(tmp_path_factory):
    """The scene as TOML and its uninterrupted `cracklab run` in a fresh process."""
    d = tmp_path_factory.mktemp("cli")
    toml = d / "scene.toml"
    toml.write_text(scene_to_toml(_scene()))
    ref = _cli("run", str(toml), "-o", str(d / "ref.zarr"), "--no-progress")
    assert ref.returncode == 0, ref.stderr
    return toml, xr.open_zarr(d / "ref.zarr", consolidated=False).load()


@pytest.mark.parametrize("checkpoints", [True, False], ids=["with-checkpoint", "no-checkpoint"])
def test_kill_during_the_final_write_leaves_a_store_not_complete(checkpoints, tmp_path, cli_reference):
    toml, ref = cli_reference
    out = tmp_path / "out.zarr"
    every = ["--checkpoint-every", "10" if checkpoints else "0"]
    killed = _cli("run", str(toml), "-o", str(out), "--no-progress", *every, script=KILLER,
                  env={"KILL_AFTER": "2"})
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    attrs = json.loads((out / "zarr.json").read_text())["attributes"]
    assert attrs["cracklab_status"] == "running"                 # not complete
    # the final write had begun (station chunks written), and was not finished
    written = {p.name for p in out.iterdir()
               if p.name.startswith("station_") and (p / "c").exists() and any((p / "c").rglob("*"))}
    assert written and not {"station_delta_2", "station_v_2", "station_tau_2", "station_strength",
                            "station_x1", "station_x3"} <= written, written
    assert (out / ck.GROUP / ck.FILE).exists() == checkpoints
    code, report = _verify_cli(out)
    assert code == 0 and "has not finished (status running" in report
    res = _cli("run", str(toml), "-o", str(out), "--no-progress", "--resume")
    assert res.returncode == 0, res.stderr
    assert "damaged" not in res.stderr and f"cracklab: wrote {out}" in res.stdout
    _same(ref, xr.open_zarr(out, consolidated=False).load())
    assert V.verify(out).ok and not (out / ck.GROUP).exists()


def test_a_full_disk_during_the_final_write_leaves_a_store_not_complete(tmp_path, monkeypatch, reference):
    import errno

    from cracklab.output.stores import LocalStore

    real = LocalStore.write
    state = {"finishing": False, "n": 0}
    real_finish = SIM.Recorder.finish

    def finish(self, *a, **k):
        state["finishing"] = True
        return real_finish(self, *a, **k)

    def put(self, path, value, exclusive=False):
        if state["finishing"] and "/station_" in str(path):
            state["n"] += 1
            if state["n"] > 3:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        return real(self, path, value, exclusive)

    store = tmp_path / "run.zarr"
    monkeypatch.setattr(SIM.Recorder, "finish", finish)
    monkeypatch.setattr(LocalStore, "write", put)
    with pytest.raises(StoreError, match="no space left on device while writing the station series"):
        cracklab.simulate(_scene(), store=store, checkpoint_every=10)
    monkeypatch.undo()                                       # space was freed
    assert json.loads((store / "zarr.json").read_text())["attributes"]["cracklab_status"] == "running"
    res = cracklab.simulate(_scene(), store=store, resume=True).load()
    _same(reference, res)
    assert V.verify(store).ok


def test_killed_after_the_status_before_the_clean_up(tmp_path, monkeypatch, reference):
    """A kill between the status and the removal of the checkpoint leaves a complete
    store with a checkpoint: the resume verifies it, returns it and removes the checkpoint."""
    store = tmp_path / "run.zarr"
    monkeypatch.setattr(ck, "remove", lambda path: None)
    cracklab.simulate(_scene(), store=store, checkpoint_every=10)
    monkeypatch.undo()
    assert (store / ck.GROUP / ck.FILE).exists()
    res = cracklab.simulate(_scene(), store=store, resume=True).load()
    _same(reference, res)
    assert not (store / ck.GROUP).exists()


# ---------------------------------------------------------------------------- ensembles
@pytest.fixture(scope="module")
def ensemble_ref(tmp_path_factory):
    return sound_ensemble(tmp_path_factory, "ens")


@pytest.fixture
def ens_store(ensemble_ref, tmp_path):
    return copy_of(ensemble_ref, tmp_path)


def test_damaged_members_are_named_never_served_and_recomputed(ens_store, ensemble_ref):
    a, b, c = member_ids(ens_store)
    mdir = ens_store / "members"
    _flip(_chunk(mdir / a, "delta_2", 0, 0, 0))
    _chunk(mdir / b, "station_v_2", 0, 0).unlink()
    (mdir / c / "delta_2" / "zarr.json").unlink()      # once NaN in open_ensemble
    code, out = _verify_cli(ens_store)
    assert code == 1, out
    assert f"DAMAGED member {a}: {_chunk(mdir / a, 'delta_2', 0, 0, 0)}: chunk (0, 0, 0) of delta_2 cannot be " \
           f"read (checksum mismatch" in out
    assert f"DAMAGED member {b}: {_chunk(mdir / b, 'station_v_2', 0, 0)}: chunk (0, 0) of station_v_2 is missing" \
        in out
    assert f"DAMAGED member {c}: {mdir / c / 'delta_2' / 'zarr.json'}: array delta_2: metadata missing" in out
    assert "3 damaged members" in out and "rerun the sweep" in out
    # readers: never the damaged data
    with pytest.raises(StoreError, match=f"member {b} is damaged: {_chunk(mdir / b, 'station_v_2', 0, 0)}"):
        E.open_ensemble(ens_store)
    with pytest.raises(StoreError, match=f"member {c} is damaged: .*delta_2/zarr.json"):
        E.open_member(ens_store, c)
    with pytest.raises(ValueError, match="checksum"):
        E.open_member(ens_store, a)["delta_2"].values
    # the rerun finds all three, says so, and recomputes them
    res = sweep(ens_store)
    assert res.ok and sorted(res.ran) == sorted([a, b, c]) and res.skipped == []
    assert set(res.damaged) == {a, b, c}
    assert "3 ran, 0 already complete, 0 failed" in res.summary()
    assert f"DAMAGED {c} (was complete; run again): {mdir / c / 'delta_2' / 'zarr.json'}" in res.summary()
    assert _verify_cli(ens_store)[0] == 0
    ens = E.open_ensemble(ens_store).load()
    np.testing.assert_allclose(ens["delta_2"].values, ensemble_ref[1]["delta_2"].values, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ens["station_v_2"].values, ensemble_ref[1]["station_v_2"].values, rtol=0, atol=1e-12)
    again = sweep(ens_store)
    assert again.ran == [] and len(again.skipped) == 3 and not again.damaged


def test_a_garbled_members_group_is_named_and_repaired(ens_store):
    meta = ens_store / "members" / "zarr.json"
    meta.write_text("{not json")                        # once a JSONDecodeError traceback
    for read in (E.member_status, E.open_ensemble):
        with pytest.raises(StoreError, match=f"its metadata file {meta} is not valid JSON.*rerun the sweep"):
            read(ens_store)
    res = CliRunner().invoke(main, ["export", str(ens_store), "--netcdf", str(ens_store.parent / "e.nc")])
    assert res.exit_code == 1 and str(meta) in res.output and len(res.output.strip().splitlines()) == 1
    assert _verify_cli(ens_store)[0] == 1
    res = sweep(ens_store)                             # repairs the group; the members are sound
    assert res.ran == [] and len(res.skipped) == 3
    assert E.open_ensemble(ens_store).sizes["member"] == 3


def test_a_garbled_member_group_is_named_and_recomputed(ens_store, ensemble_ref):
    a = member_ids(ens_store)[1]
    meta = ens_store / "members" / a / "zarr.json"
    meta.write_text(meta.read_text()[:-30])
    assert [s["status"] for s in E.member_status(ens_store)].count("damaged") == 1
    with pytest.raises(StoreError, match=f"member {a} is damaged: {meta}: the member's metadata cannot be read"):
        E.open_ensemble(ens_store)
    code, out = _verify_cli(ens_store)
    assert code == 1 and f"DAMAGED member {a}: {meta}: the member's group metadata is not valid JSON" in out
    res = sweep(ens_store)
    assert res.ran == [a] and res.ok
    ens = E.open_ensemble(ens_store).load()
    np.testing.assert_allclose(ens["delta_2"].values, ensemble_ref[1]["delta_2"].values, rtol=0, atol=1e-12)


def test_a_member_whose_time_axis_is_lost_is_named_not_misaligned(ens_store):
    a = member_ids(ens_store)[0]
    t = _chunk(ens_store / "members" / a, "t", 0)
    t.unlink()                  # t reads NaN: once "cannot reindex or align along dimension 't'"
    with pytest.raises(StoreError, match=f"member {a} is damaged: {t}: chunk \\(0,\\) of t is missing"):
        E.open_ensemble(ens_store)
    assert f"{t}: chunk (0,) of t is missing" in _verify_cli(ens_store)[1]


# ---------------------------------------------------------------------------- atomic members
def test_a_member_being_rewritten_is_read_whole_by_readers(ens_store, ensemble_ref, monkeypatch):
    """--no-resume: a reader that listed the members before the rewrite started, and opens
    them while their new run is being written, reads the old complete members, whole."""
    listed = [s["id"] for s in E.member_status(ens_store) if s["complete"]]
    old = ensemble_ref[1]
    seen = []
    real_flush = SIM.Recorder.flush

    def flush(self):
        real_flush(self)
        if self.nsnap and len(seen) < 6:        # a member's new run is half written now
            for mid in listed:
                ds = E.open_member(ens_store, mid).load()
                assert ds.attrs["complete"] is True
                np.testing.assert_array_equal(ds["delta_2"].values, old["delta_2"].sel(member=mid).values)
                assert np.isfinite(ds["station_delta_2"].values).all()
            ens = E.open_ensemble(ens_store).load()
            assert list(ens.member.values) == listed and np.isfinite(ens["delta_2"].values).all()
            seen.append(self.nsnap)

    monkeypatch.setattr(SIM.Recorder, "flush", flush)
    res = sweep(ens_store, resume=False)
    assert res.ok and len(res.ran) == 3 and seen
    assert not [p for p in (ens_store / "members").iterdir() if p.name.startswith(".")]   # no leftovers
    assert V.verify(ens_store).ok


def test_readers_racing_a_no_resume_sweep_never_see_a_partial_member(ens_store, ensemble_ref):
    study = ens_store.parent / "study.toml"
    study.write_text('[study]\nname = "race"\nbuilder = "elliptical_crack"\n'
                     '[base]\nn = 16\na = 0.25\nb = 0.2\nt_end = 1.0\nrecord.every = 2\n'
                     '[sweep]\np = [1.0, 2.0, 3.0]\n')
    out = ens_store.parent / "race.zarr"
    assert E.run_study(study, out, scheduler="synchronous", progress=False).ok
    ref = E.open_ensemble(out).load()
    done = threading.Event()
    reads, errors = [], []

    def reader():
        while not done.is_set():
            try:
                ens = E.open_ensemble(out).load()
            except Exception as exc:  # noqa: BLE001 - collected, the test fails on any
                errors.append(repr(exc))
                continue
            for mid in ens.member.values:
                got = ens["delta_2"].sel(member=mid).values
                if not np.allclose(got, ref["delta_2"].sel(member=mid).values, rtol=0, atol=1e-12):
                    errors.append(f"member {mid}: {np.isnan(got).sum()} NaN")
            reads.append(ens.sizes["member"])

    thread = threading.Thread(target=reader)
    thread.start()
    try:
        again = _cli("sweep", str(study), "-o", str(out), "--scheduler", "synchronous", "--no-progress",
                     "--no-resume")
        assert again.returncode == 0, again.stderr
        assert "3 ran, 0 already complete, 0 failed" in again.stdout
    finally:
        done.set()
        thread.join()
    assert not errors, errors[:5]
    assert len(reads) >= 10 and all(n == 3 for n in reads), reads
