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

The sweep lock (``FsspecStore.lock``): an object ``<store>/.cracklab-sweep.lock`` holding
the sweep's host, pid, start time, a random token and its heartbeat. On S3 it is created by
a conditional write (PutObject with ``If-None-Match: *``: the server refuses it when the
object exists, so of two sweeps exactly one creates it), kept alive by a heartbeat (the
object rewritten every ``LOCK_HEARTBEAT_S`` with ``If-Match`` on its own ETag) and deleted
at the end with ``If-Match`` (never another sweep's lock). A lock whose heartbeat is older
than ``LOCK_STALE_S`` (by the server's LastModified against this machine's clock), or
whose process is gone on this host, or which a sweep of this process left (its release
could not reach the store; ``_HELD`` has the tokens this process holds), is stale: it is taken over by a write with
``If-Match`` on the stale lock's ETag, so that of several sweeps taking it over one wins.
Other fsspec schemes have no conditional write: the lock is written, then read back
after ``LOCK_SETTLE_S``; a sweep whose token is not the one read back gives way. Two
sweeps that start within the settle time of each other can both read their own token
only when the store reorders writes (a window of about one write's latency); see
docs/guide/reliability.md, "Object storage".

The members of a sweep stop when their sweep loses the lock (``write_guard``): each
member carries the lock's token, and before a write into the store (at most every
``GUARD_EVERY_S``, and always before it marks itself complete) it reads the lock. It stops
(``SweepLockLost``, nothing more written, not even its failure) when the lock is gone,
holds another sweep's token, or has had no heartbeat for ``LOCK_STALE_S / 2``: its sweep
was killed (a driver killed with ``kill -9`` leaves the workers of a dask scheduler
running its tasks). The last comes before any other sweep may take the lock over by its
age; a sweep that takes over the lock of a process gone from this host at once waits
``GUARD_EVERY_S`` before it goes on, so that every orphaned member has read the new token
before the new sweep writes."""
from __future__ import annotations

import asyncio
import contextlib
import functools
import hashlib
import json
import os
import socket
import tempfile
import threading
import time
import warnings
from pathlib import Path

from ...errors import StoreError, StoreWarning
from .base import CHECKPOINT_GROUP, CHECKPOINT_GROUP_DOC, Store, SweepLockLost, current_guard
from .local import LOCK_NAME, StoreLocked, pid_alive

POINTER = "checkpoint.json"
POINTER_FORMAT = 1
STATE_PREFIX = "state-"
#: seconds between two heartbeats of a sweep's lock, and the age of its last heartbeat
#: after which another sweep takes it over (several heartbeats missed: the holder is gone)
LOCK_HEARTBEAT_S = 30.0
LOCK_STALE_S = 180.0
#: schemes whose servers honour conditional writes (If-None-Match: * and If-Match)
CONDITIONAL = {"s3", "s3a"}
#: without conditional writes: seconds between writing the lock and reading it back
LOCK_SETTLE_S = 1.0
#: a sweep's member reads its sweep's lock before a write at most every this many seconds
GUARD_EVERY_S = 5.0


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
        otherwise, and would list keys that another client deleted); inside ``guarded``,
        one whose writes check the guard first."""
        from zarr.storage import FsspecStore as ZarrFsspec

        z = ZarrFsspec.from_url(self.target, storage_options={"use_listings_cache": False})
        guard = current_guard()
        if guard is None:
            return z
        return _guarded_zarr()(fs=z.fs, path=z.path, read_only=z.read_only, allowed_exceptions=z.allowed_exceptions,
                               guard=guard)

    def key(self, name: str) -> str:
        """The path in the file system of ``name`` below the store's root."""
        return f"{self.fs[1].rstrip('/')}/{name.strip('/')}"

    def lock(self):
        return _ObjectLock(self)

    def write_guard(self, lock):
        """A ``_LockGuard`` of the token of ``lock`` (an entered ``_ObjectLock``)."""
        return _LockGuard(self.target, lock.me["token"], every=GUARD_EVERY_S, orphan_s=LOCK_STALE_S / 2)

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
        guard = current_guard()
        if guard is not None:
            guard.check()
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
        if guard is not None:
            guard.check()
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


#: the tokens of the sweep locks this process holds or is taking (a lock of this process
#: with another token was left by a sweep of it that ended, its release not written: stale)
_HELD: set = set()


class _ObjectLock:
    """The sweep lock of a store at a URL (module docstring); a context yielding the
    lock's URL."""

    def __init__(self, store: FsspecStore):
        from .base import scheme

        self.store = store
        self.key = store.key(LOCK_NAME)
        self.url = f"{store.target}/{LOCK_NAME}"
        self.conditional = scheme(store.target) in CONDITIONAL
        self.me = {"host": socket.gethostname(), "pid": os.getpid(),
                   "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "token": os.urandom(8).hex()}
        self.etag = None
        self.lost = False
        #: called (no arguments, from the heartbeat's thread) when the lock is lost
        self.on_lost: list = []
        self._stop = threading.Event()
        self._beat = None

    # -- the object
    def _body(self) -> bytes:
        return json.dumps({**self.me, "heartbeat": time.strftime("%Y-%m-%dT%H:%M:%S%z")}).encode()

    def _put(self, **condition):
        """Write the lock; its new ETag (None where the file system gives none). A
        refused condition raises FileExistsError (If-None-Match) or OSError (If-Match)."""
        fs, _ = self.store.fs
        if self.conditional:
            out = fs.pipe_file(self.key, self._body(), **condition)
            return (out or {}).get("ETag") if isinstance(out, dict) else None
        fs.pipe_file(self.key, self._body())
        return None

    def _read(self):
        """(holder's record or {} when unreadable, ETag, age in seconds of its last write)
        of the lock; None when there is none."""
        return _read_lock(self.store.fs[0], self.key)

    def _stale(self, doc: dict, age: float) -> bool:
        if doc.get("host") == socket.gethostname() and isinstance(doc.get("pid"), int) and \
                doc.get("pid") != os.getpid() and not pid_alive(doc["pid"]):
            return True                  # its process is gone (this host)
        if doc.get("host") == socket.gethostname() and doc.get("pid") == os.getpid() and \
                doc.get("token") not in _HELD:
            return True                  # a sweep of this process that ended (its release could not reach the store)
        return age > LOCK_STALE_S       # no heartbeat for that long: gone, whatever host

    def _refuse(self, doc: dict, age: float):
        holder = f"pid {doc.get('pid')} on {doc.get('host')}" if doc else "another process"
        since = f", since {doc['started']}" if doc.get("started") else ""
        raise StoreLocked("store", f"{self.store.target} is in use by another sweep ({holder}{since}, last heartbeat "
                                   f"{age:.0f} s ago); wait for it to finish, or, if no sweep is running, delete "
                                   f"{self.url} (a lock without a heartbeat for {LOCK_STALE_S:.0f} s is taken "
                                   f"over)")

    # -- taking it
    def _take(self) -> None:
        for _ in range(5):
            if self.conditional:
                try:
                    self.etag = self._put(IfNoneMatch="*")
                except FileExistsError:
                    pass
                else:
                    if self._mine():
                        return
                    continue
            else:
                if self._read() is None:
                    self._put()
                    time.sleep(LOCK_SETTLE_S)
                    if self._mine():
                        return
            held = self._read()
            if held is None:
                continue                  # released meanwhile: try again
            doc, etag, age = held
            if doc.get("token") == self.me["token"]:
                return
            if not self._stale(doc, age):
                self._refuse(doc, age)
            if self.conditional:          # taken over: one of several contenders wins
                try:
                    self.etag = self._put(IfMatch=etag)
                except OSError:
                    continue
                if self._mine():
                    return self._fence(age)
            else:
                self._put()
                time.sleep(LOCK_SETTLE_S)
                if self._mine():
                    return self._fence(age)
        raise StoreLocked("store", f"{self.store.target}: could not take the sweep lock {self.url}; try again")

    def _fence(self, age: float) -> None:
        """After taking over the lock of a sweep whose heartbeat is younger than its
        members' orphan age (its process gone from this host): wait until each of its
        orphaned members has read the lock (they do before a write, at most
        ``GUARD_EVERY_S`` apart) and stopped, before this sweep writes."""
        if age <= LOCK_STALE_S / 2 + GUARD_EVERY_S:
            time.sleep(GUARD_EVERY_S + 1.0)

    def _mine(self) -> bool:
        held = self._read()
        if held is None or held[0].get("token") != self.me["token"]:
            return False
        self.etag = held[1] or self.etag
        return True

    # -- keeping it
    def _heartbeat(self) -> None:
        while not self._stop.wait(LOCK_HEARTBEAT_S):
            try:
                if self.conditional:
                    self.etag = self._put(IfMatch=self.etag) or self.etag
                    continue
                if self._mine():
                    self._put()
                    continue
            except Exception:  # noqa: BLE001 - refused, or a network error: told apart below
                try:
                    if self._mine():
                        continue            # still this sweep's (a network error): the next beat
                except Exception:  # noqa: BLE001 - the store cannot be reached: the next beat
                    continue
            # taken over (this sweep was thought gone): say so once, stop beating; the
            # sweep stops (``on_lost``) and its members stop at their next write (their guard)
            self.lost = True
            warnings.warn(StoreWarning(f"store {self.store.target}: the sweep lock {self.url} was taken over by "
                                       f"another sweep; this sweep stops, and its members stop before their next "
                                       f"write"), stacklevel=1)
            for call in list(self.on_lost):
                with contextlib.suppress(Exception):
                    call()
            return

    def __enter__(self):
        _HELD.add(self.me["token"])      # before it may be written: held, for this process's other sweeps
        try:
            self._take()
        except BaseException:
            _HELD.discard(self.me["token"])
            raise
        self._beat = threading.Thread(target=self._heartbeat, name="cracklab-sweep-lock", daemon=True)
        self._beat.start()
        return self.url

    def __exit__(self, *exc):
        _HELD.discard(self.me["token"])
        self._stop.set()
        if self._beat is not None:
            self._beat.join(timeout=10)
        if self.lost:
            return False
        fs, _ = self.store.fs
        with contextlib.suppress(Exception):       # a lock left behind is stale once its heartbeat stops
            if self.conditional:
                fs.call_s3("delete_object", **_bucket_key(fs, self.key), IfMatch=self.etag) if self.etag else \
                    (self._mine() and fs.rm_file(self.key))
            elif self._mine():
                fs.rm_file(self.key)
        return False


def _read_lock(fs, key: str):
    """(holder's record or {} when unreadable, ETag, age in seconds of its last write) of
    the lock object at ``key``; None when there is none."""
    try:
        info = fs.info(key)
        body = fs.cat_file(key)
    except FileNotFoundError:
        return None
    try:
        doc = json.loads(body)
        doc = doc if isinstance(doc, dict) else {}
    except (ValueError, UnicodeDecodeError):
        doc = {}
    modified = info.get("LastModified") or info.get("mtime") or info.get("created")
    try:
        stamp = modified.timestamp() if hasattr(modified, "timestamp") else float(modified)
        age = time.time() - stamp
    except (TypeError, ValueError):
        age = 0.0
    return doc, info.get("ETag"), age


class _LockGuard:
    """What a member of a sweep into a URL checks before it writes (module docstring):
    that the lock at ``<target>/.cracklab-sweep.lock`` still holds its sweep's ``token``
    and had a heartbeat within ``orphan_s``. Sent to the workers with each member (its
    file system is made again there)."""

    def __init__(self, target: str, token: str, *, every: float, orphan_s: float):
        self.target, self.token, self.every, self.orphan_s = target, token, every, orphan_s
        self.url = f"{target}/{LOCK_NAME}"
        self._fs = None
        self._last = None

    def __getstate__(self):
        return {**self.__dict__, "_fs": None, "_last": None}

    def _lost(self, why: str):
        raise SweepLockLost(self.target, f"{why}; this member stopped before its next write (nothing more written "
                                         f"by it): the sweep that holds the store, or the next one, runs it")

    def check(self, force: bool = False) -> None:
        """Raise ``SweepLockLost`` when the sweep no longer holds the store; reads the
        lock at most every ``every`` seconds (always with ``force``)."""
        now = time.monotonic()
        if not force and self._last is not None and now - self._last < self.every:
            return
        if self._fs is None:
            from ..objectstore import filesystem

            self._fs = filesystem(self.target)
        fs, path = self._fs
        held = _read_lock(fs, f"{path.rstrip('/')}/{LOCK_NAME}")
        if held is None:
            self._lost(f"its sweep's lock {self.url} is gone (the sweep ended, or the lock was deleted)")
        doc, _, age = held
        if doc.get("token") != self.token:
            holder = f"pid {doc.get('pid')} on {doc.get('host')}" if doc else "another process"
            self._lost(f"its sweep's lock {self.url} was taken over by another sweep ({holder})")
        if age > self.orphan_s:
            self._lost(f"its sweep's lock {self.url} has had no heartbeat for {age:.0f} s: the sweep was killed")
        self._last = now


@functools.cache
def _guarded_zarr():
    """zarr's fsspec store whose writes check a guard first (made on first use)."""
    from zarr.storage import FsspecStore as ZarrFsspec

    class GuardedFsspec(ZarrFsspec):
        def __init__(self, *args, guard, **kwargs):
            super().__init__(*args, **kwargs)
            self.guard = guard

        def with_read_only(self, read_only: bool = False):
            return type(self)(fs=self.fs, path=self.path, allowed_exceptions=self.allowed_exceptions,
                              read_only=read_only, guard=self.guard)

        async def _check(self):
            await asyncio.to_thread(self.guard.check)

        async def set(self, *args, **kwargs):
            await self._check()
            return await super().set(*args, **kwargs)

        async def delete(self, *args, **kwargs):
            await self._check()
            return await super().delete(*args, **kwargs)

        async def delete_dir(self, *args, **kwargs):
            await self._check()
            return await super().delete_dir(*args, **kwargs)

        async def clear(self):
            await self._check()
            return await super().clear()

    return GuardedFsspec


def _bucket_key(fs, key: str) -> dict:
    bucket, name, _ = fs.split_path(key)
    return {"Bucket": bucket, "Key": name}


def _digest(path: Path) -> tuple[str, int]:
    h, size = hashlib.sha256(), 0
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
            size += len(block)
    return h.hexdigest(), size
