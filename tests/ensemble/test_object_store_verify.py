"""An ensemble store on object storage is checked as a local one (issue 32, points 2 and 4;
docs/guide/reliability.md, "Object storage"), against the S3 API server on loopback
(tests/s3_server.py; no client mocked):

* ``cracklab verify s3://...`` of an ensemble runs the checks of a local ensemble (member
  chunks and their checksums, the consolidated metadata against the members present,
  member parameters and scenes, array shapes, the member table): the same damage, done
  to a local copy and to the copy on the server, gives the same lines, store path and
  remedy included (it was refused: "checks ensembles on a local disk only");
* a sweep into the URL checks its complete members before it skips them: a member
  damaged or changed on the server is recomputed, never served (it was skipped);
* the readers (``open_ensemble``, ``open_member``, ``cracklab export``, ``summary`` and
  ``plot``) read a store at a URL through the store protocol with the guarantees of a
  local one: a member whose metadata does not match what is stored is refused, naming it."""
import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import zarr
from click.testing import CliRunner

from cracklab import ensemble as E
from cracklab.cli import main
from cracklab.errors import StoreError
from cracklab.output.stores import zarr_of
from small_ensemble import BUILDER, SWEEP, member_ids, sound_ensemble


@pytest.fixture(scope="module")
def sound(tmp_path_factory):
    return sound_ensemble(tmp_path_factory, "s3verify")


def _client(server):
    import boto3

    from s3_server import KEYS

    return boto3.client("s3", endpoint_url=server.endpoint, region_name="us-east-1",
                        aws_access_key_id=KEYS["AWS_ACCESS_KEY_ID"], aws_secret_access_key=KEYS["AWS_SECRET_ACCESS_KEY"])


class Local:
    """The files of a local store, by their paths below it."""

    def __init__(self, root: Path):
        self.root, self.where = root, str(root)

    def read(self, rel):
        return (self.root / rel).read_bytes()

    def write(self, rel, data):
        (self.root / rel).write_bytes(data)

    def delete(self, rel):
        import shutil

        shutil.rmtree(self.root / rel)


class Bucket:
    """The objects of a store on the server, by their keys below it."""

    def __init__(self, server, bucket, prefix="ens.zarr"):
        self.client, self.bucket, self.prefix = _client(server), bucket, prefix
        self.where = f"s3://{bucket}/{prefix}"

    def read(self, rel):
        return self.client.get_object(Bucket=self.bucket, Key=f"{self.prefix}/{rel}")["Body"].read()

    def write(self, rel, data):
        self.client.put_object(Bucket=self.bucket, Key=f"{self.prefix}/{rel}", Body=data)

    def delete(self, rel):
        listed = self.client.list_objects_v2(Bucket=self.bucket, Prefix=f"{self.prefix}/{rel}/").get("Contents", [])
        for o in listed:
            self.client.delete_object(Bucket=self.bucket, Key=o["Key"])

    def upload(self, local: Path):
        for f in sorted(local.rglob("*")):
            if f.is_file():
                self.write(f.relative_to(local).as_posix(), f.read_bytes())
        return self


def _copies(sound, tmp_path, s3_env):
    """(a local copy, a copy on the server) of the sound ensemble."""
    import shutil

    local = tmp_path / "ens.zarr"
    shutil.copytree(sound[0], local)
    return Local(local), Bucket(s3_env, s3_env.make_bucket()).upload(local)


def _edit(files, rel, change):
    doc = json.loads(files.read(rel))
    change(doc)
    files.write(rel, json.dumps(doc).encode())


def _params(doc):
    p = json.loads(doc["attributes"]["member_params"])
    doc["attributes"]["member_params"] = json.dumps({**p, "p": 5.0})


def _nu(doc):
    scene = json.loads(doc["attributes"]["scene"])
    scene["material"]["nu"] = 0.3
    doc["attributes"]["scene"] = json.dumps(scene)


def _flip(files, rel):
    data = bytearray(files.read(rel))
    data[len(data) // 2] ^= 0xFF
    files.write(rel, bytes(data))


def _table_status(files, ids):
    root = zarr.open_group(zarr_of(files.where), mode="a", use_consolidated=False)
    values = root["status"][:]
    values[0] = "failed"
    root["status"][:] = values


#: a damage (files, member ids) and the member it damages (None: the store's root)
DAMAGE = {
    "deleted member": (lambda f, ids: f.delete(f"members/{ids[0]}"), 0),
    "member parameters": (lambda f, ids: _edit(f, f"members/{ids[1]}/zarr.json", _params), 1),
    "member scene": (lambda f, ids: _edit(f, f"members/{ids[2]}/zarr.json", _nu), 2),
    "array shape": (lambda f, ids: _edit(f, f"members/{ids[2]}/delta_2/zarr.json",
                                         lambda d: d.update(shape=[d["shape"][0] - 2, *d["shape"][1:]])), 2),
    "chunk bytes": (lambda f, ids: _flip(f, f"members/{ids[1]}/delta_2/c/0/0/0"), 1),
    "member table": (_table_status, None),
}
#: damages done together (one member each, and the table): every check of an ensemble
#: in two stores
TOGETHER = {"metadata": ("deleted member", "member parameters", "array shape"),
            "data, scene and table": ("chunk bytes", "member scene", "member table")}
#: what names each damage in cracklab verify's lines
NAMED = {"deleted member": "members/{0}: listed in the consolidated metadata",
         "member parameters": "members/{1}/zarr.json: its parameters (attribute member_params) do not give its id",
         "array shape": "members/{2}/delta_2/zarr.json: array delta_2 has shape (4, 16, 16)",
         "member table": "status: the member table gives status = 'failed' for member {0}",
         "chunk bytes": "members/{1}/delta_2/c/0/0/0: chunk (0, 0, 0) of delta_2 cannot be read (checksum mismatch",
         "member scene": "members/{2}/zarr.json: the run's scene (its 'scene' attribute and input arrays) does not "
                         "match the digest"}


def _damage(files, ids, together):
    for name in TOGETHER[together]:
        DAMAGE[name][0](files, ids)


def _verify_lines(where):
    res = CliRunner().invoke(main, ["verify", where])
    assert not res.exception or isinstance(res.exception, SystemExit), repr(res.exception)
    return res.exit_code, res.output.splitlines()


@pytest.mark.parametrize("together", sorted(TOGETHER))
def test_verify_of_an_ensemble_at_a_url_names_what_a_local_verify_names(together, sound, tmp_path, s3_env):
    local, bucket = _copies(sound, tmp_path, s3_env)
    ids = member_ids(local.root)
    sound_lines = _verify_lines(local.where)
    assert sound_lines[0] == 0 and sound_lines[1][0].endswith(": ensemble, 3 member groups (3 complete and sound), "
                                                              "45 arrays, 45 chunks read: sound"), sound_lines
    assert _verify_lines(bucket.where) == (0, [sound_lines[1][0].replace(local.where, bucket.where)])
    for files in (local, bucket):
        _damage(files, ids, together)
    code, lines = _verify_lines(local.where)
    assert code == 1, lines
    at_url = _verify_lines(bucket.where)
    assert at_url == (1, [line.replace(local.where, bucket.where) for line in lines]), (at_url, lines)
    damaged = [line for line in at_url[1] if line.startswith("  DAMAGED ")]
    for name in TOGETHER[together]:     # each named, in one line with its store path and remedy
        what = f"{bucket.where}/{NAMED[name].format(*ids)}"
        assert [line for line in damaged if what in line and "remedy" in line or what in line and
                "checksum" in line], (name, damaged)
    assert "cracklab-test-secret" not in "\n".join(at_url[1])


@pytest.mark.parametrize("together", sorted(TOGETHER))
def test_a_sweep_into_a_url_recomputes_what_verify_names(together, sound, tmp_path, s3_env):
    """Before, a sweep into a URL skipped its complete members unchecked: "0 ran" with the
    changed members served."""
    _, bucket = _copies(sound, tmp_path, s3_env)
    url = bucket.where
    ids = member_ids(url)
    _damage(bucket, ids, together)
    res = E.run(BUILDER, SWEEP, url, scheduler="synchronous", progress=False)
    assert res.ok, res.summary()
    names = TOGETHER[together]
    complete_damaged = sorted({ids[DAMAGE[n][1]] for n in names if DAMAGE[n][1] is not None and n != "deleted member"})
    assert sorted(res.damaged) == complete_damaged, res.summary()
    assert sorted(res.ran) == sorted(complete_damaged + ([ids[0]] if "deleted member" in names else []))
    assert _verify_lines(url)[0] == 0
    ens = E.open_ensemble(url).load()
    assert list(ens.member.values) == list(sound[1].member.values)
    np.testing.assert_array_equal(ens["delta_2"].values, sound[1]["delta_2"].values)
    assert ens.attrs["scenes"] == sound[1].attrs["scenes"]
    table = xr.open_zarr(url)            # plain xarray: the consolidated metadata, rewritten
    assert list(table.status.values) == ["complete"] * 3 and list(table.p.values) == [1.0, 2.0, 3.0]


def test_readers_at_a_url_refuse_a_member_whose_metadata_was_changed(sound, tmp_path, s3_env):
    _, bucket = _copies(sound, tmp_path, s3_env)
    url = bucket.where
    ids = member_ids(url)
    DAMAGE["array shape"][0](bucket, ids)
    DAMAGE["member parameters"][0](bucket, ids)
    for mid, what in ((ids[1], "its parameters"), (ids[2], "array delta_2 has shape")):
        with pytest.raises(StoreError, match=f"member {mid} is damaged: {url}/members/{mid}/zarr.json: {what}"
                           if "param" in what else f"member {mid} is damaged: {url}/members/{mid}/delta_2/zarr.json"):
            E.open_member(url, mid)
    with pytest.raises(StoreError, match=f"member {ids[1]} is damaged"):     # once: served, or "conflicting sizes"
        E.open_ensemble(url)
    assert E.open_member(url, ids[0]).attrs["complete"] is True        # the others are served
    out = tmp_path / "e.nc"
    res = CliRunner().invoke(main, ["export", url, "-o", str(out)])
    assert res.exit_code == 1 and f"{url}/members/{ids[1]}/" in res.output and not out.exists(), res.output


def test_export_summary_and_plot_read_an_ensemble_at_a_url(sound, tmp_path, s3_env, monkeypatch):
    _, bucket = _copies(sound, tmp_path, s3_env)
    url = bucket.where
    ids = member_ids(url)
    out = tmp_path / "e.nc"
    res = CliRunner().invoke(main, ["export", url, "-o", str(out)])
    assert res.exit_code == 0, res.output
    with xr.open_dataset(out) as nc:
        np.testing.assert_array_equal(nc["delta_2"].values, sound[1]["delta_2"].values)
    res = CliRunner().invoke(main, ["export", url, "--member", ids[1], "-o", str(tmp_path / "m.nc")])
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(main, ["summary", url])
    assert res.exit_code == 0 and all(m in res.output for m in ids), res.output
    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(main, ["plot", url, "--kind", "length"])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "ens_length.png").stat().st_size > 0      # a store at a URL: in the current directory
    res = CliRunner().invoke(main, ["plot", url, "--kind", "snapshot", "--member", ids[0], "-o",
                                    str(tmp_path / "s.png")])
    assert res.exit_code == 0 and (tmp_path / "s.png").exists(), res.output


def test_a_member_deleted_on_the_server_is_not_served(sound, tmp_path, s3_env):
    _, bucket = _copies(sound, tmp_path, s3_env)
    url = bucket.where
    ids = member_ids(url)
    xr.open_zarr(zarr_of(url), group=f"members/{ids[0]}").load()        # read once: listings are not cached
    bucket.delete(f"members/{ids[0]}")
    assert [s["id"] for s in E.member_status(url)] == ids[1:]
    assert list(E.open_ensemble(url).member.values) == ids[1:]
