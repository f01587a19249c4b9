"""An S3 API server on loopback for the object-store tests: moto's server mode
(``python -m moto.server``) in a process of its own on 127.0.0.1 and a free port.

Clients reach it the way users reach theirs, through the environment (``s3_env``):
AWS_ENDPOINT_URL, AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY and AWS_DEFAULT_REGION. The
keys are made up (moto accepts any); the AWS config and credentials files are pointed at
nothing, so that a developer's own ~/.aws is never read. No client is mocked: s3fs,
zarr and cracklab talk HTTP to the server."""
from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys
import threading
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


class Proxy:
    """A TCP relay on 127.0.0.1:``port`` to a server's port (``backend``), run by threads of
    this process. ``down()`` closes the listening socket and every connection through it:
    clients are refused, or lose the connection they had, as when the server is down or
    unreachable; ``up(backend)`` listens again on the same port."""

    def __init__(self, backend: int, port: int | None = None):
        self.port = port or free_port()
        self.backend = backend
        self._lock = threading.Lock()
        self._conns: set = set()
        self._listener = None
        self._thread = None

    def up(self, backend: int | None = None) -> "Proxy":
        if backend is not None:
            self.backend = backend
        listener = socket.socket()
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        listener.bind(("127.0.0.1", self.port))
        listener.listen(64)
        listener.settimeout(0.1)
        self._listener = listener
        self._thread = threading.Thread(target=self._accept, args=(listener,), daemon=True, name="s3-proxy")
        self._thread.start()
        return self

    def down(self) -> None:
        listener, self._listener = self._listener, None
        if listener is not None:
            listener.close()
        if self._thread is not None:
            self._thread.join(5)
        with self._lock:
            conns, self._conns = self._conns, set()
        for c in conns:
            with contextlib.suppress(OSError):
                c.shutdown(socket.SHUT_RDWR)
            c.close()

    def _accept(self, listener) -> None:
        while self._listener is listener:
            try:
                client, _ = listener.accept()
            except socket.timeout:
                continue
            except OSError:
                return
            try:
                server = socket.create_connection(("127.0.0.1", self.backend), timeout=5)
            except OSError:
                client.close()
                continue
            server.settimeout(None)
            client.settimeout(None)
            with self._lock:
                self._conns.update((client, server))
            for a, b in ((client, server), (server, client)):
                threading.Thread(target=self._pump, args=(a, b), daemon=True).start()

    def _pump(self, src, dst) -> None:
        try:
            while data := src.recv(1 << 16):
                dst.sendall(data)
        except OSError:
            pass
        finally:
            for s in (src, dst):
                with contextlib.suppress(OSError):
                    s.shutdown(socket.SHUT_RDWR)


class RestartableS3Server(S3Server):
    """An S3 API server whose data outlives it: moto's server records every request it
    is sent to a file in ``data_dir`` (moto's recorder), and ``restart()`` kills the server
    (SIGKILL), starts a new one and replays the file into it before clients reach it
    again. Clients reach it through a ``Proxy`` on a port of its own (``endpoint``), which
    stays the same; ``outage(seconds)`` makes it unreachable for a while (the server
    itself left running)."""

    def __init__(self, data_dir):
        self.data_dir = os.fspath(data_dir)
        self.log = os.path.join(self.data_dir, "requests.jsonl")
        self.proxy = None
        super().__init__()

    def start(self, timeout: float = 60.0) -> "RestartableS3Server":
        self._start_backend(timeout)
        self.proxy = Proxy(self.port).up()
        self.endpoint = f"http://127.0.0.1:{self.proxy.port}"
        return self

    def _start_backend(self, timeout: float) -> None:
        self.port = free_port()
        env = {**os.environ, "MOTO_ENABLE_RECORDING": "true", "MOTO_RECORDER_FILEPATH": self.log}
        self.proc = subprocess.Popen([sys.executable, "-m", "moto.server", "-H", "127.0.0.1", "-p", str(self.port)],
                                     stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                     env=env)
        backend = f"http://127.0.0.1:{self.port}"
        deadline = time.monotonic() + timeout
        while True:
            if self.proc.poll() is not None:
                raise RuntimeError(f"moto server exited with status {self.proc.returncode}")
            try:
                urllib.request.urlopen(backend + "/moto-api/", timeout=1).close()
                return
            except OSError:
                if time.monotonic() > deadline:
                    raise RuntimeError(f"moto server did not answer on {backend} within {timeout} s") from None
                time.sleep(0.1)

    def restart(self, down_s: float = 0.0) -> None:
        """Kill the server (SIGKILL: a crash), start another, replay what the first was
        sent, and let clients reach it again after ``down_s`` seconds at least."""
        t0 = time.monotonic()
        self.proxy.down()
        self.proc.kill()
        self.proc.wait()
        self._start_backend(60.0)
        req = urllib.request.Request(f"http://127.0.0.1:{self.port}/moto-api/recorder/replay-recording",
                                     method="POST", data=b"")
        urllib.request.urlopen(req, timeout=300).close()
        time.sleep(max(0.0, down_s - (time.monotonic() - t0)))
        self.proxy.up(self.port)

    def outage(self, seconds: float) -> None:
        """The server unreachable for ``seconds`` (connections refused, those open cut)."""
        self.proxy.down()
        time.sleep(seconds)
        self.proxy.up()

    def stop(self) -> None:
        if self.proxy is not None:
            self.proxy.down()
        super().stop()
