"""The rewrite of an ensemble member on object storage (ensemble/running.py, no rename
there): a complete member that a sweep runs again is marked incomplete before any of its
arrays is touched, and complete only last, so that no reader (cracklab's nor plain
xarray's) is served a member marked complete while it is being rewritten. Against the S3
API server on loopback (tests/s3_server.py; no client mocked)."""
import importlib
import json

import numpy as np
import xarray as xr
from click.testing import CliRunner

from cracklab.cli import main
from cracklab.ensemble import member_status
from cracklab.ensemble.store import is_complete
from small_ensemble import STUDY

SIM = importlib.import_module("cracklab.output.simulate")


def _sweep(study, url, *extra):
    res = CliRunner().invoke(main, ["sweep", str(study), "--no-progress", "-o", url, "--scheduler", "synchronous",
                                    *extra])
    assert res.exit_code == 0, res.output
    return res


def _as_readers_see_it(url, mid) -> dict:
    """What the readers say of member ``mid``: cracklab's own, and plain xarray's (the
    member's group, and the whole store as a DataTree, consolidated metadata as found)."""
    status = {s["id"]: s for s in member_status(url)}
    tree = xr.open_datatree(url, engine="zarr")
    return {"is_complete": is_complete(url, mid),
            "member_status": status[mid]["complete"] if mid in status else None,
            "xarray": xr.open_zarr(url, group=f"members/{mid}").attrs.get("complete"),
            "datatree": tree[f"members/{mid}"].attrs.get("complete") if f"members/{mid}" in tree.groups or
            f"/members/{mid}" in tree.groups else None}


def test_a_member_rewritten_on_s3_is_never_served_as_complete(s3_env, tmp_path, monkeypatch):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/ens.zarr"
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    _sweep(study, url)
    ids = [s["id"] for s in member_status(url)]
    assert len(ids) == 2 and all(is_complete(url, m) for m in ids)
    before = {m: xr.open_zarr(url, group=f"members/{m}").load() for m in ids}
    assert _as_readers_see_it(url, ids[0])["datatree"] is True      # a complete member, seen as such

    seen = []
    real_create, real_finish = SIM.Recorder.create, SIM.Recorder.finish

    def look(rec, when):
        mid = rec.kept_attrs.get("member_id")
        if mid is not None:
            seen.append((mid, when, _as_readers_see_it(url, mid)))

    def create(self):
        look(self, "created")            # the group cleared and remade, no array yet
        real_create(self)
        look(self, "running")            # the arrays at their final size, NaN

    def finish(self, *args, **kwargs):
        look(self, "finishing")
        out = real_finish(self, *args, **kwargs)
        look(self, "run written, status complete")      # the member's own 'complete' still False
        return out

    monkeypatch.setattr(SIM.Recorder, "create", create)
    monkeypatch.setattr(SIM.Recorder, "finish", finish)
    _sweep(study, url, "--no-resume")                    # every complete member is run again
    monkeypatch.setattr(SIM.Recorder, "create", real_create)
    monkeypatch.setattr(SIM.Recorder, "finish", real_finish)
    assert {mid for mid, _, _ in seen} == set(ids) and len(seen) == 8, [s[:2] for s in seen]
    for mid, when, readers in seen:
        assert not any(v is True for v in readers.values()), (mid, when, readers)
    for m in ids:                                         # complete again, the same numbers
        assert is_complete(url, m)
        after = xr.open_zarr(url, group=f"members/{m}").load()
        for name in before[m].data_vars:
            np.testing.assert_array_equal(before[m][name].values, after[name].values, err_msg=name)
    attrs = json.loads(json.dumps(xr.open_zarr(url, group=f"members/{ids[0]}").attrs, default=str))
    assert attrs["complete"] is True and attrs["status"] == "complete"
