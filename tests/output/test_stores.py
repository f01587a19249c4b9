"""The store protocol (cracklab.output.stores, docs/guide/reliability.md "Kinds of storage"):
the kind of storage chosen from the path or URL, one error for a scheme no kind takes,
the kinds installed by the entry-point group "cracklab.stores", a run into a local store
(every file written through ``LocalStore.write``), its lock, and a run into an S3 store
on the loopback S3 server (tests/s3_server.py; no client mocked)."""
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import cracklab
from cracklab import Record
from cracklab.errors import StoreError
from cracklab.output import stores
from cracklab.output.verify import verify
from cracklab.output.stores import FsspecStore, LocalStore, Store, StoreLocked, store_for


def _scene():
    return cracklab.scenes.elliptical_crack(n=16, a=0.25, b=0.2, t_end=0.05,
                                            record=Record(fields=("delta_2",), every=2, stations={"c": (0.5, 0.5)}))


class TupleStore(Store):
    """A kind of storage as an installed package would add it (for the tests below)."""

    kind = "tuple"
    accepts = "tuple:// URLs"

    @classmethod
    def handles(cls, scheme):
        return scheme in ("tuple", "s3")

    def check(self, *, exists=False):
        return None

    def zarr_store(self):
        return self.target


def _installed(monkeypatch, tmp_path, value):
    """Install a package on sys.path whose metadata declares the entry point "tuple" =
    ``value`` in the group "cracklab.stores", as pip would."""
    info = tmp_path / "site" / "tuplestore-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: tuplestore\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[{stores.ENTRY_POINT_GROUP}]\ntuple = {value}\n")
    monkeypatch.syspath_prepend(str(tmp_path / "site"))


@pytest.mark.parametrize("target, kind", [("run.zarr", LocalStore), (Path("a/b.zarr"), LocalStore),
                                          ("~/x.zarr", LocalStore), ("s3://bucket/run.zarr", FsspecStore),
                                          ("memory://run.zarr", FsspecStore), ("S3://bucket/x", FsspecStore)])
def test_the_kind_is_chosen_from_the_path_or_url(target, kind):
    store = store_for(target)
    assert type(store) is kind and str(store) == str(target)
    assert store.local == (kind is LocalStore) and stores.is_url(target) == (kind is FsspecStore)
    assert (store.path == Path(str(target)).expanduser()) if store.local else store.path is None


def test_a_scheme_no_store_takes_is_one_error_naming_it_and_the_accepted_ones():
    with pytest.raises(StoreError) as info:
        store_for("foo://bucket/x.zarr")
    assert str(info.value) == ("store foo://bucket/x.zarr: no store for the scheme 'foo://': cracklab writes to "
                               "local paths and fsspec URLs (s3://, gs://, az://, memory://, ...); check the URL")


def test_the_kinds_listed_and_an_installed_one_taking_its_schemes_first(monkeypatch, tmp_path):
    assert list(stores.kinds()) == ["local", "fsspec"]
    _installed(monkeypatch, tmp_path, f"{__name__}:TupleStore")
    assert list(stores.kinds()) == ["tuple", "local", "fsspec"]
    assert type(store_for("tuple://x/y")) is TupleStore and type(store_for("s3://b/x")) is TupleStore
    assert type(store_for("x.zarr")) is LocalStore and type(store_for("gs://b/x")) is FsspecStore
    with pytest.raises(StoreError, match=r"writes to tuple:// URLs and local paths and fsspec URLs"):
        store_for("foo://x")


def test_an_entry_point_that_is_not_a_store_is_refused(monkeypatch, tmp_path):
    _installed(monkeypatch, tmp_path, "cracklab.output.stores:store_for")
    with pytest.raises(StoreError, match=r"tuple: the entry point 'cracklab.output.stores:store_for' of the group "
                                         r"'cracklab.stores' is not a cracklab.output.stores.Store subclass"):
        store_for("x.zarr")


def test_a_local_store_round_trip_writes_every_file_through_the_store(tmp_path, monkeypatch):
    written, real = [], LocalStore.write

    def write(self, path, value, exclusive=False):
        written.append(Path(path))
        return real(self, path, value, exclusive)

    monkeypatch.setattr(LocalStore, "write", write)
    path = tmp_path / "run.zarr"
    ref = cracklab.simulate(_scene())
    res = cracklab.simulate(_scene(), store=str(path)).load()
    for name in ref.data_vars:
        np.testing.assert_array_equal(ref[name].values, res[name].values, err_msg=name)
    on_disk = {p for p in path.rglob("*") if p.is_file()}
    assert on_disk and on_disk <= set(written), sorted(map(str, on_disk - set(written)))[:5]
    assert xr.open_zarr(path).attrs["cracklab_status"] == "complete"
    store_for(path).check(exists=True)
    with pytest.raises(StoreError, match="does not exist"):
        store_for(tmp_path / "none.zarr").check(exists=True)


def test_a_local_store_is_held_by_one_sweep_at_a_time(tmp_path):
    store = store_for(str(tmp_path / "ens.zarr"))
    with store.lock() as held:
        assert held == tmp_path / "ens.zarr" / ".cracklab-sweep.lock" and held.exists()
        with pytest.raises(StoreLocked, match="is in use by another sweep"):
            with store_for(str(tmp_path / "ens.zarr")).lock():
                pass
    assert not held.exists()


def test_an_s3_store_round_trip(s3_env):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/run.zarr"
    store = store_for(url)
    assert type(store) is FsspecStore and not store.local and store.path is None
    store.check()
    with pytest.raises(StoreError, match="does not exist \\(no zarr.json there"):
        store.check(exists=True)
    with store.lock() as held:          # a lock object (tests/output/test_object_store_lock.py)
        assert held == f"{url}/.cracklab-sweep.lock"
    ref = cracklab.simulate(_scene())
    res = cracklab.simulate(_scene(), store=url).load()
    for name in ref.data_vars:
        np.testing.assert_array_equal(ref[name].values, res[name].values, err_msg=name)
    fs, path = store.check(exists=True)
    assert fs.exists(f"{path}/zarr.json") and verify(url).ok
    with pytest.raises(StoreError, match=f"the bucket '{bucket}x' does not exist"):
        store_for(f"s3://{bucket}x/run.zarr").check()
