"""Object-store URLs as stores (docs/guide/reliability.md, "Object storage"), against an S3
API server on loopback (moto, tests/s3_server.py; real HTTP, no client mocked):

* bad input, each one line naming the URL and what to do, before any member or step
  runs, for ``cracklab run -o URL``, ``cracklab sweep -o URL`` and ``cracklab verify URL``:
  a scheme with no store implementation, no credentials for s3://, a bucket that does
  not exist;
* ``cracklab verify`` of a run written to the server reads and checks every chunk as it
  does for a local store."""
import os

import pytest
from click.testing import CliRunner

import cracklab
from cracklab import Record
from cracklab.cli import main
from cracklab.errors import StoreError
from small_ensemble import STUDY


def _run_args(url):
    return ["run", "elliptical_crack", "--set", "n=16", "--set", "a=0.25", "--set", "b=0.2",
            "--set", "t_end=0.05", "--no-progress", "-o", url]


def _sweep_args(tmp_path, url):
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    return ["sweep", str(study), "--no-progress", "-o", url]


COMMANDS = {"run": lambda tmp_path, url: _run_args(url),
            "sweep": _sweep_args,
            "verify": lambda tmp_path, url: ["verify", url]}


def one_error_line(args) -> str:
    """The output of a command that fails: exit status 1, one line 'Error: ...', no traceback."""
    res = CliRunner().invoke(main, args)
    out = res.output.strip()
    assert res.exit_code == 1, out
    assert "Traceback" not in out and not isinstance(res.exception, (AssertionError, NameError, TypeError)), \
        (out, res.exception)
    lines = out.splitlines()
    assert len(lines) == 1 and lines[0].startswith("Error: "), out
    return lines[0]


def keys(server, bucket):
    """The keys in ``bucket`` (read with the server's credentials)."""
    import boto3

    from s3_server import KEYS

    client = boto3.client("s3", endpoint_url=server.endpoint, region_name="us-east-1",
                          aws_access_key_id=KEYS["AWS_ACCESS_KEY_ID"],
                          aws_secret_access_key=KEYS["AWS_SECRET_ACCESS_KEY"])
    return [o["Key"] for o in client.list_objects_v2(Bucket=bucket).get("Contents", [])]


# ---------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_a_scheme_with_no_store_is_one_line(command, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    url = "foo://bucket/x.zarr"
    line = one_error_line(COMMANDS[command](tmp_path, url))
    assert url in line and "foo://" in line and "no store" in line, line
    assert "s3://" in line          # what works instead
    assert os.listdir(tmp_path) in ([], ["study.toml"])     # nothing written here either


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_missing_credentials_for_s3_are_one_line(command, s3_env, tmp_path, monkeypatch):
    bucket = s3_env.make_bucket()
    monkeypatch.delenv("AWS_ACCESS_KEY_ID")
    monkeypatch.delenv("AWS_SECRET_ACCESS_KEY")
    url = f"s3://{bucket}/x.zarr"
    line = one_error_line(COMMANDS[command](tmp_path, url))
    assert url in line and "credentials" in line, line
    assert "AWS_ACCESS_KEY_ID" in line and "AWS_SECRET_ACCESS_KEY" in line, line     # what to set
    assert keys(s3_env, bucket) == []


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_a_bucket_that_does_not_exist_is_one_line(command, s3_env, tmp_path):
    url = "s3://cracklab-no-such-bucket/x.zarr"
    line = one_error_line(COMMANDS[command](tmp_path, url))
    assert url in line and "bucket 'cracklab-no-such-bucket' does not exist" in line, line
    assert s3_env.endpoint in line          # where it was looked for (AWS_ENDPOINT_URL)
    assert "cracklab-no-such-bucket" not in [b for b in _buckets(s3_env)]       # not created


def _buckets(server):
    import boto3

    from s3_server import KEYS

    client = boto3.client("s3", endpoint_url=server.endpoint, region_name="us-east-1",
                          aws_access_key_id=KEYS["AWS_ACCESS_KEY_ID"],
                          aws_secret_access_key=KEYS["AWS_SECRET_ACCESS_KEY"])
    return [b["Name"] for b in client.list_buckets()["Buckets"]]


def test_verify_of_a_store_that_is_not_there_names_the_url(s3_env):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/nothing.zarr"
    line = one_error_line(["verify", url])
    assert url in line and "does not exist" in line, line


def test_simulate_refuses_a_bad_url_before_any_step(s3_env, monkeypatch):
    sc = cracklab.scenes.elliptical_crack(n=16, a=0.25, b=0.2, t_end=0.05, record=Record(fields=("delta_2",)))
    monkeypatch.delenv("AWS_SECRET_ACCESS_KEY")
    bucket = s3_env.make_bucket()
    with pytest.raises(StoreError, match="credentials"):
        cracklab.simulate(sc, store=f"s3://{bucket}/run.zarr")
    assert keys(s3_env, bucket) == []
    with pytest.raises(StoreError, match="no store"):
        cracklab.simulate(sc, store="foo://bucket/run.zarr")


# ---------------------------------------------------------------------------- verify
def _s3(server):
    import boto3

    from s3_server import KEYS

    return boto3.client("s3", endpoint_url=server.endpoint, region_name="us-east-1",
                        aws_access_key_id=KEYS["AWS_ACCESS_KEY_ID"], aws_secret_access_key=KEYS["AWS_SECRET_ACCESS_KEY"])


def test_verify_reads_every_chunk_of_a_run_on_the_object_store(s3_env, tmp_path):
    bucket = s3_env.make_bucket()
    url = f"s3://{bucket}/run.zarr"
    res = CliRunner().invoke(main, _run_args(url) + ["--set", "record.fields=['delta_2']"])
    assert res.exit_code == 0, res.output
    local = tmp_path / "run.zarr"
    res = CliRunner().invoke(main, _run_args(str(local)) + ["--set", "record.fields=['delta_2']"])
    assert res.exit_code == 0, res.output

    res = CliRunner().invoke(main, ["verify", url])
    assert res.exit_code == 0, res.output
    head = res.output.splitlines()[0]
    assert head.startswith(f"cracklab verify: {url}: run (status complete)") and head.endswith(": sound"), head
    assert head.split(": run")[1] == CliRunner().invoke(main, ["verify", str(local)]).output.splitlines()[0] \
        .split(": run")[1]                              # as many arrays and chunks read as from a local disk

    client = _s3(s3_env)
    key = "run.zarr/delta_2/c/0/0/0"
    data = bytearray(client.get_object(Bucket=bucket, Key=key)["Body"].read())
    data[len(data) // 2] ^= 0xFF                        # a changed byte in a chunk
    client.put_object(Bucket=bucket, Key=key, Body=bytes(data))
    client.delete_object(Bucket=bucket, Key="run.zarr/x1/c/0")     # a chunk gone
    res = CliRunner().invoke(main, ["verify", url])
    assert res.exit_code == 1, res.output
    out = res.output
    assert f"DAMAGED {url}/delta_2/c/0/0/0: chunk (0, 0, 0) of delta_2 cannot be read (checksum mismatch" in out, out
    assert f"DAMAGED {url}/x1/c/0: chunk (0,) of x1 is missing" in out, out
    assert f"what to do: run it again from its scene file: cracklab run SCENE.toml -o STORE" in out
    assert "--resume" not in out                         # a URL store has no checkpoints to resume from
    assert "cracklab-test-secret" not in out and "cracklab-test-key" not in out
    res = CliRunner().invoke(main, ["verify", "--quick", url])     # the listing only: the missing chunk
    assert res.exit_code == 1 and f"DAMAGED {url}/x1/c/0: chunk (0,) of x1 is missing" in res.output, res.output
    assert "delta_2/c/0/0/0" not in res.output


def test_a_scheme_whose_package_is_not_installed_names_it(tmp_path):
    pytest.importorskip("fsspec")
    try:
        import gcsfs  # noqa: F401
        pytest.skip("gcsfs is installed")
    except ImportError:
        pass
    line = one_error_line(_run_args("gs://bucket/x.zarr"))
    assert "gs://bucket/x.zarr" in line and "not installed" in line and "gcsfs" in line, line
