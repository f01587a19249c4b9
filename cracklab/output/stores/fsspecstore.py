"""Stores at fsspec URLs (``s3://bucket/run.zarr``, ``gs://``, ``memory://``, ...): checked
by ``cracklab.output.objectstore.check_url``, written by zarr through an fsspec file
system of their own (no listings cache: what another process or another client wrote is
seen at once).

Checkpoints: an object store has no rename, so a checkpoint is committed by a pointer.
The checkpoint's bytes go to a fresh key, ``_checkpoint/state-<time>-<token>.npz``; then a
small pointer object, ``_checkpoint/checkpoint.json``, names that key with its size and
SHA-256, written last (one PUT: the server stores it whole or not at all). A reader
follows the pointer and checks size and digest before it uses the bytes, so a kill in the
middle of a checkpoint write leaves the previous checkpoint in use, and bytes that do not
match their pointer are never used. Checkpoint objects no pointer names (a write that was
killed before its pointer) are deleted by the next checkpoint or resume.

Not locked yet (see docs/guide/reliability.md)."""
from __future__ import annotations

import contextlib
import hashlib
import json
import os
import tempfile
import time
from pathlib import Path

from ...errors import StoreError
from .base import CHECKPOINT_GROUP, CHECKPOINT_GROUP_DOC, Store

POINTER = "checkpoint.json"
POINTER_FORMAT = 1
STATE_PREFIX = "state-"


class FsspecStore(Store):
    """A store at a URL whose scheme names an fsspec implementation."""

    kind = "fsspec"
    accepts = "fsspec URLs (s3://, gs://, az://, memory://, ...)"
    checkpoints = True

    def __init__(self, target):
        super().__init__(os.fspath(target).rstrip("/"))
        self._fs = None

    @classmethod
    def handles(cls, scheme: str) -> bool:
        import fsspec

        if not scheme:
            return False
        try:
            fsspec.get_filesystem_class(scheme)
        except ValueError:
            return False
        except ImportError:
            return True       # known, its package missing: check says so
        return True

    def check(self, *, exists: bool = False):
        """``objectstore.check_url``: its scheme's package, credentials, bucket (and, with
        ``exists``, its zarr.json); returns (fsspec filesystem, path)."""
        from ..objectstore import check_url

        self._fs = check_url(self.target, exists=exists)
        return self._fs

    @property
    def fs(self):
        """(fsspec filesystem, path of the store's root in it), made once per store."""
        if self._fs is None:
            from ..objectstore import filesystem

            self._fs = filesystem(self.target)
        return self._fs

    def zarr_store(self):
        """zarr's fsspec store at the URL, without a listings cache (s3fs caches listings
        otherwise, and would list keys that another client deleted)."""
        from zarr.storage import FsspecStore as ZarrFsspec

        return ZarrFsspec.from_url(self.target, storage_options={"use_listings_cache": False})

    def key(self, name: str) -> str:
        """The path in the file system of ``name`` below the store's root."""
        return f"{self.fs[1].rstrip('/')}/{name.strip('/')}"

    # -- the layout of a run --------------------------------------------------------------
    def tree(self):
        from ..objectstore import StoredTree

        fs, path = self.fs
        return StoredTree(fs, path, self.target)

    def children(self) -> list[str] | None:
        fs, path = self.fs
        try:
            entries = fs.ls(path, detail=True, refresh=True)
        except FileNotFoundError:
            return None
        if not entries:
            return None
        return sorted(e["name"].rstrip("/").rsplit("/", 1)[-1] for e in entries if e.get("type") == "directory")

    def remove(self, name: str) -> None:
        fs, _ = self.fs
        with contextlib.suppress(FileNotFoundError):
            fs.rm(self.key(name), recursive=True)

    def clear(self) -> None:
        fs, path = self.fs
        with contextlib.suppress(FileNotFoundError):
            fs.rm(path.rstrip("/"), recursive=True)

    # -- checkpoints: bytes under a fresh key, then the pointer ---------------------------
    def _pointer(self) -> dict | None:
        fs, _ = self.fs
        where = self.key(f"{CHECKPOINT_GROUP}/{POINTER}")
        try:
            text = fs.cat_file(where)
        except FileNotFoundError:
            return None
        try:
            doc = json.loads(text)
            if not isinstance(doc, dict) or doc.get("format") != POINTER_FORMAT or \
                    not str(doc.get("object", "")).startswith(STATE_PREFIX):
                raise ValueError("not a checkpoint pointer of this cracklab")
            return doc
        except (ValueError, UnicodeDecodeError) as exc:
            raise StoreError(self.target, f"its checkpoint pointer {self.target}/{CHECKPOINT_GROUP}/{POINTER} is "
                                          f"unreadable ({exc}); run again without resume") from None

    def write_checkpoint(self, fill, before_commit=None) -> None:
        fs, _ = self.fs
        group = self.key(CHECKPOINT_GROUP)
        if not fs.exists(f"{group}/zarr.json"):
            # a Zarr group: readers of the store then ignore the prefix silently
            fs.pipe_file(f"{group}/zarr.json", CHECKPOINT_GROUP_DOC.encode())
        name = f"{STATE_PREFIX}{time.time_ns():020d}-{os.urandom(4).hex()}.npz"
        with tempfile.TemporaryDirectory(prefix="cracklab-checkpoint-") as tmp:
            local = Path(tmp) / "state.npz"
            with open(local, "wb") as fh:
                fill(fh)
            digest, size = _digest(local)
            fs.put_file(str(local), f"{group}/{name}")
        if before_commit is not None:
            before_commit()
        pointer = {"format": POINTER_FORMAT, "object": name, "bytes": size, "sha256": digest}
        fs.pipe_file(f"{group}/{POINTER}", json.dumps(pointer).encode())     # the commit
        self._drop_states(keep=name)

    def _drop_states(self, keep: str | None) -> None:
        """Delete the checkpoint objects but ``keep`` (those of earlier checkpoints, and
        of writes killed before their pointer)."""
        fs, _ = self.fs
        try:
            names = fs.ls(self.key(CHECKPOINT_GROUP), detail=False, refresh=True)
        except FileNotFoundError:
            return
        for key in names:
            base = key.rstrip("/").rsplit("/", 1)[-1]
            if base.startswith(STATE_PREFIX) and base != keep:
                with contextlib.suppress(FileNotFoundError):
                    fs.rm_file(key)

    @contextlib.contextmanager
    def checkpoint_file(self):
        pointer = self._pointer()
        if pointer is None:
            yield None
            return
        fs, _ = self.fs
        where = self.key(f"{CHECKPOINT_GROUP}/{pointer['object']}")
        with tempfile.TemporaryDirectory(prefix="cracklab-checkpoint-") as tmp:
            local = Path(tmp) / "state.npz"
            try:
                fs.get_file(where, str(local))
            except FileNotFoundError:
                raise StoreError(self.target, f"its checkpoint {self.target}/{CHECKPOINT_GROUP}/{pointer['object']} "
                                              f"named by {POINTER} is missing; run again without resume") from None
            digest, size = _digest(local)
            if (digest, size) != (pointer.get("sha256"), pointer.get("bytes")):
                raise StoreError(self.target, f"its checkpoint {self.target}/{CHECKPOINT_GROUP}/{pointer['object']} "
                                              f"does not match the size and SHA-256 in {POINTER} (changed or torn); "
                                              f"run again without resume")
            yield local

    def remove_checkpoint(self) -> None:
        self.remove(CHECKPOINT_GROUP)

    def clean(self) -> None:
        """Checkpoint objects no pointer names (a write killed before its pointer)."""
        try:
            pointer = self._pointer()
        except StoreError:
            return
        self._drop_states(keep=pointer["object"] if pointer else None)


def _digest(path: Path) -> tuple[str, int]:
    h, size = hashlib.sha256(), 0
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
            size += len(block)
    return h.hexdigest(), size
