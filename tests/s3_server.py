"""An S3 API server on loopback for the object-store tests: moto's server mode
(``python -m moto.server``) in a process of its own on 127.0.0.1 and a free port.

Clients reach it the way users reach theirs, through the environment (``s3_env``):
AWS_ENDPOINT_URL, AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY and AWS_DEFAULT_REGION. The
keys are made up (moto accepts any); the AWS config and credentials files are pointed at
nothing, so that a developer's own ~/.aws is never read. No client is mocked: s3fs,
zarr and cracklab talk HTTP to the server."""
from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
import urllib.request
import uuid

KEYS = {"AWS_ACCESS_KEY_ID": "cracklab-test-key", "AWS_SECRET_ACCESS_KEY": "cracklab-test-secret"}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class S3Server:
    """``python -m moto.server`` on 127.0.0.1: ``start()`` waits until it answers,
    ``stop()`` ends it (the process this object started, by its pid)."""

    def __init__(self, port: int | None = None):
        self.port = port or free_port()
        self.endpoint = f"http://127.0.0.1:{self.port}"
        self.proc = None

    def start(self, timeout: float = 60.0) -> "S3Server":
        self.proc = subprocess.Popen([sys.executable, "-m", "moto.server", "-H", "127.0.0.1", "-p", str(self.port)],
                                     stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError(f"moto server exited with status {self.proc.returncode}")
            try:
                urllib.request.urlopen(self.endpoint + "/moto-api/", timeout=1).close()
                return self
            except OSError:
                time.sleep(0.1)
        self.stop()
        raise RuntimeError(f"moto server did not answer on {self.endpoint} within {timeout} s")

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc = None

    def env(self, home) -> dict:
        """The environment variables that point a client at this server (``home``: a
        directory for the AWS config files, which are left absent)."""
        return {"AWS_ENDPOINT_URL": self.endpoint, "AWS_DEFAULT_REGION": "us-east-1",
                "AWS_CONFIG_FILE": os.path.join(home, "aws-config-absent"),
                "AWS_SHARED_CREDENTIALS_FILE": os.path.join(home, "aws-credentials-absent"),
                "AWS_EC2_METADATA_DISABLED": "true", **KEYS}

    def make_bucket(self, name: str | None = None) -> str:
        """Create a bucket (a fresh name by default) over HTTP; its name."""
        import boto3

        name = name or f"cracklab-{uuid.uuid4().hex[:12]}"
        boto3.client("s3", endpoint_url=self.endpoint, region_name="us-east-1",
                     aws_access_key_id=KEYS["AWS_ACCESS_KEY_ID"],
                     aws_secret_access_key=KEYS["AWS_SECRET_ACCESS_KEY"]).create_bucket(Bucket=name)
        return name
