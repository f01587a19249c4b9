"""Object-store URLs as stores (``s3://bucket/run.zarr``, any fsspec URL): the checks a
URL passes before a run, a sweep or ``cracklab verify`` touches it, and a read-only view
of a store there for ``cracklab.output.verify``.

A URL's scheme must name an fsspec implementation whose package is installed (s3fs for
``s3://``). Credentials and the endpoint come from where the implementation reads them
(for s3://: AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY or AWS_PROFILE, AWS_ENDPOINT_URL);
cracklab never writes them anywhere, nor names them but by their variables."""
from __future__ import annotations

import contextlib
import os

from ..errors import StoreError
from .stores.base import is_url, scheme  # noqa: F401  (objectstore.is_url as before)

# schemes whose first path part is a bucket (or container) that must exist
BUCKETS = {"s3", "s3a", "gs", "gcs", "az", "abfs", "abfss"}


def endpoint(url: str) -> str:
    """Where a URL's bucket is looked for, as the environment sets it (for messages)."""
    if scheme(url) in ("s3", "s3a"):
        where = os.environ.get("AWS_ENDPOINT_URL_S3") or os.environ.get("AWS_ENDPOINT_URL")
        return f"at {where}" if where else "on AWS (no AWS_ENDPOINT_URL set)"
    return f"on {scheme(url)}://"


def filesystem(url: str):
    """(fsspec filesystem, path) of ``url``: a fresh instance, so that the credentials are
    those of the environment now (fsspec caches instances), without a listings cache (a
    key another client wrote or deleted is seen at once). StoreError for a scheme fsspec
    does not know or whose package is not installed."""
    import fsspec
    from fsspec.core import url_to_fs

    s = scheme(url)
    try:
        fsspec.get_filesystem_class(s)
    except ValueError:      # cracklab.output.stores.store_for names the schemes a store takes
        raise StoreError(url, f"no fsspec implementation for the scheme '{s}://'; check the URL") from None
    except ImportError as exc:
        raise StoreError(url, f"the scheme '{s}://' needs a package that is not installed ({exc})") from None
    return url_to_fs(url, skip_instance_cache=True, use_listings_cache=False)


def network_errors() -> tuple:
    """The exception classes of a store at a URL that cannot be reached (the server down
    or unreachable, a connection cut or timed out): the client's retries, if any, are
    spent. Those of packages not installed are left out."""
    out: list = [ConnectionError, TimeoutError]
    with contextlib.suppress(ImportError):
        from botocore import exceptions as b

        out += [b.ConnectionError, b.HTTPClientError]
    with contextlib.suppress(ImportError):
        import aiohttp

        out += [aiohttp.ClientConnectionError, aiohttp.ClientPayloadError]
    return tuple(out)


def unreachable(store, exc, doing: str) -> StoreError | None:
    """The one-line StoreError of ``exc``, met ``doing`` a write or read of the store at a
    URL (its URL, or its ``Store``), when it is a network error (``network_errors``); None
    otherwise."""
    target = getattr(store, "target", store)
    if not is_url(target) or not isinstance(exc, network_errors()):
        return None
    msg = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    return StoreError(os.fspath(target), f"cannot be reached while {doing} ({type(exc).__name__}: {msg})")


def _credentials_hint(url: str) -> str:
    if scheme(url) in ("s3", "s3a"):
        return ("set AWS_ACCESS_KEY_ID and AWS_SECRET_ACCESS_KEY (or AWS_PROFILE) in the environment, and "
                "AWS_ENDPOINT_URL for a server other than AWS")
    return f"set them as the fsspec implementation of {scheme(url)}:// reads them from the environment"


def check_url(url: str, *, exists: bool = False):
    """Check ``url`` before anything is written or run: its scheme has a store, its
    credentials are found and accepted, its bucket exists and, with ``exists``, a Zarr
    store is there. One StoreError naming the URL and what to do; returns (fs, path)."""
    fs, path = filesystem(url)
    s = scheme(url)
    bucket = path.strip("/").split("/")[0]
    try:
        if s in BUCKETS:
            fs.info(bucket)
        if exists and not fs.exists(f"{path.rstrip('/')}/zarr.json"):
            raise StoreError(url, f"does not exist (no zarr.json there, {endpoint(url)}); check the URL")
    except StoreError:
        raise
    except FileNotFoundError:
        raise StoreError(url, f"the bucket '{bucket}' does not exist {endpoint(url)}: create it first, or check "
                              f"the URL and the endpoint") from None
    except PermissionError as exc:
        raise StoreError(url, f"access denied ({_first_line(exc)}): check the credentials; "
                              f"{_credentials_hint(url)}") from None
    except Exception as exc:  # noqa: BLE001 - botocore's and others' errors, reported as one line
        name = type(exc).__name__
        if "Credentials" in name:
            raise StoreError(url, f"no credentials found for {s}://: {_credentials_hint(url)}") from None
        raise StoreError(url, f"cannot reach the store {endpoint(url)} ({name}: {_first_line(exc)}); check the "
                              f"URL and the endpoint") from None
    return fs, path


def _first_line(exc) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


class StoredTree:
    """A read-only, path-like view of the store at a URL for ``cracklab.output.verify``:
    its keys are listed once (one listing of the whole store), then ``exists``,
    ``is_dir`` and ``subdirs`` answer from that listing and ``read_text`` reads a key."""

    def __init__(self, fs, path: str, url: str, keys=None, dirs=None):
        self.fs, self.path, self.url = fs, path.rstrip("/"), url.rstrip("/")
        if keys is None:
            keys = set(fs.find(self.path))
            dirs = {k.rsplit("/", n)[0] for k in keys for n in range(1, k.count("/") + 1)}
        self.keys, self.dirs = keys, dirs

    @classmethod
    def listing(cls, fs, path: str, url: str, prefixes) -> "StoredTree":
        """The tree at ``path`` with only the keys below ``prefixes`` (paths below it) listed,
        and the keys right at its root (its zarr.json, the sweep lock): a view of a few
        members of a large store, one listing each."""
        root = path.rstrip("/")
        keys = set()
        for prefix in prefixes:
            try:
                keys |= set(fs.find(f"{root}/{prefix.strip('/')}"))
            except FileNotFoundError:
                pass
        try:
            keys |= {e["name"] for e in fs.ls(root, detail=True, refresh=True) if e.get("type") == "file"}
        except FileNotFoundError:
            pass
        dirs = {k.rsplit("/", n)[0] for k in keys for n in range(1, k.count("/") + 1)}
        return cls(fs, root, url, keys, dirs)

    def _at(self, path, url):
        return StoredTree(self.fs, path, url, self.keys, self.dirs)

    def __truediv__(self, name) -> "StoredTree":
        name = str(name).strip("/")
        return self._at(f"{self.path}/{name}", f"{self.url}/{name}")

    def __str__(self) -> str:
        return self.url

    @property
    def name(self) -> str:
        return self.path.rsplit("/", 1)[-1]

    @property
    def parent(self) -> "StoredTree":
        return self._at(self.path.rsplit("/", 1)[0], self.url.rsplit("/", 1)[0])

    def exists(self) -> bool:
        return self.path in self.keys or self.path in self.dirs

    def is_dir(self) -> bool:
        return self.path in self.dirs

    def subdirs(self) -> list[str]:
        """The names of the directories (key prefixes) right below this one."""
        head = self.path + "/"
        return sorted({d[len(head):] for d in self.dirs if d.startswith(head) and "/" not in d[len(head):]})

    def read_text(self) -> str:
        if self.path not in self.keys:
            raise FileNotFoundError(self.url)
        return self.fs.cat_file(self.path).decode()
