"""A scene's field files: only regular files from the scene file's folder (or folders the
user allows) are read, special files are refused at once, and where each field came from
is kept in the output (cracklab/model/field_files.py)."""
from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import xarray as xr

from cracklab import InputError, Record, Scene, simulate
from field_scene import GRID, toml

TAU_C = 1.0 + np.random.default_rng(3).random(GRID.shape)



def scene_file(folder, ref):
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "scene.toml"
    path.write_text(toml(f"tau_c = {ref}"))
    return path


def refused(path, **kw):
    with pytest.raises(InputError) as err:
        Scene.from_toml(path, **kw)
    assert err.value.field == "law.tau_c", str(err.value)
    return str(err.value)


@pytest.fixture
def elsewhere(tmp_path):
    """A .npy field in a folder beside the scene's, not below it."""
    other = tmp_path / "elsewhere"
    other.mkdir()
    np.save(other / "x.npy", TAU_C)
    return other / "x.npy"


@pytest.mark.parametrize("how", ["absolute", "relative"])
def test_a_file_outside_the_scene_folder_is_refused(tmp_path, elsewhere, how):
    ref = f'{{ file = "{elsewhere}" }}' if how == "absolute" else '{ file = "../elsewhere/x.npy" }'
    msg = refused(scene_file(tmp_path / "scene", ref))
    assert "outside the scene file's folder" in msg
    assert "--allow-files" in msg and "CRACKLAB_ALLOW_FILES" in msg


def test_a_link_out_of_the_scene_folder_is_refused(tmp_path, elsewhere):
    folder = tmp_path / "scene"
    folder.mkdir()
    (folder / "x.npy").symlink_to(elsewhere)
    assert "outside" in refused(scene_file(folder, '{ file = "x.npy" }'))


def test_allowed_folders_are_read(tmp_path, elsewhere, monkeypatch):
    path = scene_file(tmp_path / "scene", '{ file = "../elsewhere/x.npy" }')
    sc = Scene.from_toml(path, allow=[elsewhere.parent])
    np.testing.assert_array_equal(sc.law.tau_c, TAU_C)
    monkeypatch.setenv("CRACKLAB_ALLOW_FILES", os.pathsep.join(["/nonexistent", str(elsewhere.parent)]))
    np.testing.assert_array_equal(Scene.from_toml(path).law.tau_c, TAU_C)


def test_a_file_below_the_scene_folder_is_read(tmp_path):
    folder = tmp_path / "scene"
    (folder / "data").mkdir(parents=True)
    np.save(folder / "data" / "x.npy", TAU_C)
    sc = Scene.from_toml(scene_file(folder, f'{{ file = "{folder / "data" / "x.npy"}" }}'))
    np.testing.assert_array_equal(sc.law.tau_c, TAU_C)


@pytest.mark.parametrize("suffix", [".npy", ".nc"])
def test_a_fifo_is_refused_without_blocking(tmp_path, suffix):
    """Opening a FIFO for reading blocks until a writer comes: the scene is refused instead,
    in a child process that is killed if it blocks."""
    folder = tmp_path / "scene"
    folder.mkdir()
    os.mkfifo(folder / f"x{suffix}")
    var = ', var = "tau_c"' if suffix == ".nc" else ""
    path = scene_file(folder, f'{{ file = "x{suffix}"{var} }}')
    code = textwrap.dedent(f"""
        from cracklab import InputError, Scene
        try:
            Scene.from_toml({str(path)!r})
        except InputError as exc:
            print(exc.field, "|", exc)
    """)
    try:
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail("reading a scene whose field file is a FIFO blocked")
    assert out.stdout.startswith("law.tau_c |"), out.stdout + out.stderr
    assert "a FIFO" in out.stdout


def test_a_zarr_field_holding_a_fifo_is_refused(tmp_path):
    folder = tmp_path / "scene"
    folder.mkdir()
    xr.Dataset({"tau_c": (("x1", "x3"), TAU_C)}, coords={"x1": GRID.x1, "x3": GRID.x3}).to_zarr(
        folder / "f.zarr", consolidated=False)
    os.mkfifo(folder / "f.zarr" / "extra")
    msg = refused(scene_file(folder, '{ file = "f.zarr", var = "tau_c" }'))
    assert "a FIFO" in msg and "extra" in msg


def test_a_device_is_refused(tmp_path):
    folder = tmp_path / "scene"
    folder.mkdir()
    (folder / "x.npy").symlink_to("/dev/zero")
    msg = refused(scene_file(folder, '{ file = "x.npy" }'), allow=["/dev"])
    assert "character device" in msg


def test_the_output_says_where_a_field_came_from(tmp_path):
    folder = tmp_path / "scene"
    folder.mkdir()
    np.save(folder / "toughness.npy", TAU_C)
    sc = Scene.from_toml(scene_file(folder, '{ file = "toughness.npy" }'))
    digest = hashlib.sha256((folder / "toughness.npy").read_bytes()).hexdigest()
    assert sc.sources == {"law.tau_c": f"file reference {{file = 'toughness.npy'}}, sha256 {digest}"}
    ds = simulate(sc.replace(record=Record(fields=("delta_2",), every=10)))
    source = ds["input_law_tau_c"].attrs["source"]
    assert "toughness.npy" in source and digest in source
    # a replaced law no longer claims the file's provenance
    law = sc.law.__class__(tau_c=2.0, delta_c=0.01)
    assert sc.replace(law=law).sources == {}
