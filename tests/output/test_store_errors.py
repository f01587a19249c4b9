"""Store errors of single runs (docs/guide/reliability.md): a path that is not a cracklab store,
a store of another format or version, a read-only location and a full disk each end
with one clear StoreError (one line from the CLI), and a full disk can be resumed from."""
import errno
import importlib
import os
import uuid
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import zarr
from click.testing import CliRunner

import cracklab
from cracklab import Record
from cracklab.output import checkpoint as ck
from cracklab.cli import main
from cracklab.errors import StoreError
from cracklab.model.scene_io import scene_to_toml
from interrupt import interrupted_run

SIM = importlib.import_module("cracklab.output.simulate")


def _scene(t_end=0.5):
    return cracklab.scenes.elliptical_crack(n=32, a=0.25, b=0.2, t_end=t_end,
                                            record=Record(fields=("delta_2",), every=2,
                                                          stations={"c": (0.5, 0.5)}))


def _cli_error(args):
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 1, res.output
    out = res.output.strip()
    assert "Traceback" not in out and out.startswith("Error: ") and len(out.splitlines()) == 1, out
    return out


def _interrupted(tmp_path, scene, monkeypatch, stop=30):
    """A store left as by a kill after step ``stop`` (checkpoints every 10 steps)."""
    return interrupted_run(scene, tmp_path / "run.zarr", monkeypatch, stop=stop, checkpoint_every=10)


# ---------------------------------------------------------------------------- not a store
def test_a_path_that_is_not_a_cracklab_store_is_refused_and_kept(tmp_path):
    sc = _scene(0.05)
    mine = tmp_path / "thesis"
    mine.mkdir()
    (mine / "chapter1.tex").write_text("precious")
    for resume in (False, True):
        with pytest.raises(StoreError, match="not a cracklab run store") as info:
            cracklab.simulate(sc, store=mine, resume=resume)
        assert str(mine) in str(info.value)
    assert (mine / "chapter1.tex").read_text() == "precious"     # nothing was deleted
    afile = tmp_path / "notes.txt"
    afile.write_text("x")
    with pytest.raises(StoreError, match="not a cracklab run store"):
        cracklab.simulate(sc, store=afile)
    foreign = tmp_path / "foreign.zarr"
    zarr.open_group(str(foreign), mode="w").create_array("data", shape=(3,), dtype="f8")
    with pytest.raises(StoreError, match="not a cracklab run store"):
        cracklab.simulate(sc, store=foreign, resume=True)
    toml = tmp_path / "scene.toml"
    toml.write_text(scene_to_toml(sc))
    out = _cli_error(["run", str(toml), "-o", str(mine)])
    assert "refusing to overwrite" in out


def test_an_ensemble_store_is_not_a_run_store(tmp_path):
    ens = tmp_path / "ens.zarr"
    zarr.open_group(str(ens), mode="w").attrs["cracklab_ensemble"] = 1
    with pytest.raises(StoreError, match="ensemble store"):
        cracklab.simulate(_scene(0.05), store=ens)


# ---------------------------------------------------------------------------- other format
def test_a_store_of_another_format_or_version(tmp_path, monkeypatch):
    sc = _scene()
    store = _interrupted(tmp_path, sc, monkeypatch)
    g = zarr.open_group(str(store), mode="a")
    g.attrs["cracklab_run_format"] = 99
    with pytest.raises(StoreError, match="store format 99"):
        cracklab.simulate(sc, store=store, resume=True)
    toml = tmp_path / "scene.toml"
    toml.write_text(scene_to_toml(sc))
    assert "store format 99" in _cli_error(["run", str(toml), "-o", str(store), "--resume"])
    # reading the scene from a store of a newer format
    assert "format 99" in _cli_error(["run", str(store), "-o", str(tmp_path / "b.zarr")])
    del g.attrs["cracklab_run_format"]                   # a store from before the format attr
    with pytest.raises(StoreError, match="no cracklab_run_format"):
        cracklab.simulate(sc, store=store, resume=True)
    g.attrs["cracklab_run_format"] = ck.RUN_FORMAT
    monkeypatch.setattr(SIM, "__version__", "0.0.0+other")
    with pytest.raises(StoreError, match=r"checkpoint was written by cracklab .* this is cracklab 0\.0\.0\+other"):
        cracklab.simulate(sc, store=store, resume=True)


def test_an_unreadable_checkpoint(tmp_path, monkeypatch):
    sc = _scene()
    store = _interrupted(tmp_path, sc, monkeypatch)
    f = store / ck.GROUP / ck.FILE
    f.write_bytes(f.read_bytes()[:100])
    with pytest.raises(StoreError, match="checkpoint .* is unreadable"):
        cracklab.simulate(sc, store=store, resume=True)


# ---------------------------------------------------------------------------- read-only
def _read_only_dir(tmp_path):
    if os.geteuid() != 0:
        d = tmp_path / "ro"
        d.mkdir()
        d.chmod(0o555)
        return d
    # root ignores permission bits: use a read-only file system if there is one
    for cand in ("/sys", "/proc/sys"):
        probe = Path(cand) / f"cracklab-probe-{uuid.uuid4().hex}"
        try:
            probe.mkdir()
        except OSError:
            return Path(cand)
        probe.rmdir()
    pytest.skip("no read-only location available to this user")


def test_a_read_only_location(tmp_path):
    where = _read_only_dir(tmp_path)
    target = where / f"cracklab-{uuid.uuid4().hex}.zarr"
    with pytest.raises(StoreError, match=r"(read-only|permission denied|not permitted) .*while creating the store"):
        cracklab.simulate(_scene(0.05), store=target)
    toml = tmp_path / "scene.toml"
    toml.write_text(scene_to_toml(_scene(0.05)))
    assert "while creating the store" in _cli_error(["run", str(toml), "-o", str(target)])


# ---------------------------------------------------------------------------- full disk
@pytest.fixture
def disk_fills_at_step(monkeypatch):
    """Every write of a local store (LocalStore.write) fails with ENOSPC once the run has passed step ``armed["step"]``."""
    from cracklab.output.stores import LocalStore

    armed = {"step": None, "now": -1}
    real_put, real_call = LocalStore.write, SIM.Recorder.__call__

    def put(self, path, value, exclusive=False):
        if armed["step"] is not None and armed["now"] >= armed["step"]:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        return real_put(self, path, value, exclusive)

    def call(self, state):
        armed["now"] = state.n
        real_call(self, state)

    monkeypatch.setattr(LocalStore, "write", put)
    monkeypatch.setattr(SIM.Recorder, "__call__", call)
    return armed


def test_a_full_disk_mid_run_is_one_error_and_resumable(tmp_path, disk_fills_at_step):
    sc = _scene()
    ref = cracklab.simulate(sc)
    store = tmp_path / "run.zarr"
    disk_fills_at_step.update(step=25, now=-1)
    with pytest.raises(StoreError) as info:
        cracklab.simulate(sc, store=store, checkpoint_every=10)
    msg = str(info.value)
    assert msg.startswith(f"store {store}: no space left on device while writing the snapshots")
    assert "checkpoint after step 20" in msg and "resume" in msg
    disk_fills_at_step["step"] = None                          # space was freed
    assert xr.open_zarr(store, consolidated=False).attrs["cracklab_checkpoint_step"] == 20
    res = cracklab.simulate(sc, store=store, resume=True).load()
    for name in ref.data_vars:
        np.testing.assert_array_equal(ref[name].values, res[name].values, err_msg=name)


def test_a_full_disk_while_checkpointing(tmp_path, monkeypatch):
    sc = _scene()
    ref = cracklab.simulate(sc)
    store = tmp_path / "run.zarr"
    real = ck.np.savez
    count = {"n": 0}

    def savez(fh, **arrays):
        count["n"] += 1
        if count["n"] == 3:                               # the third checkpoint: half written
            fh.write(b"\0" * 1000)
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(fh, **arrays)

    monkeypatch.setattr(ck.np, "savez", savez)
    with pytest.raises(StoreError, match="no space left on device while writing the checkpoint after step 30"):
        cracklab.simulate(sc, store=store, checkpoint_every=10)
    assert not list((store / ck.GROUP).glob("*.tmp"))
    assert ck.read(store)["n"] == 20                         # the previous checkpoint is intact
    monkeypatch.setattr(ck.np, "savez", real)
    res = cracklab.simulate(sc, store=store, resume=True).load()
    for name in ref.data_vars:
        np.testing.assert_array_equal(ref[name].values, res[name].values, err_msg=name)
