"""Zarr on a local (or shared POSIX) disk: the store is a directory. Its writes go through
``LocalStore.write`` (zarr's atomic write of one file: a temporary file renamed into
place), and a sweep holds it with a lock file created by a hard link."""
from __future__ import annotations

import asyncio
import contextlib
import functools
import json
import os
import shutil
import socket
import time
from pathlib import Path

from ...errors import InputError, StoreError
from .base import CHECKPOINT_GROUP, CHECKPOINT_GROUP_DOC, Store

CHECKPOINT_FILE = "state.npz"

LOCK_NAME = ".cracklab-sweep.lock"
LOCK_GRACE_S = 10.0     # an empty or unreadable lock younger than this is being written


class StoreLocked(InputError):
    """Another sweep is running into this store (see ``LocalStore.lock``)."""


class LocalStore(Store):
    """A store in a directory of the local file system."""

    kind = "local"
    local = True
    accepts = "local paths"
    checkpoints = True

    @classmethod
    def handles(cls, scheme: str) -> bool:
        return scheme == ""

    @property
    def path(self) -> Path:
        return Path(self.target).expanduser()

    def check(self, *, exists: bool = False) -> None:
        if exists and not (self.path / "zarr.json").exists():
            raise StoreError(self.target, "does not exist (no zarr.json there); check the path")

    def write(self, path: Path, value, exclusive: bool = False) -> int:
        """Write one file of the store (a chunk or a zarr.json) with zarr's own atomic
        write: every write of a run into this store comes here."""
        from zarr.storage._local import _put

        return _put(path, value, exclusive=exclusive)

    def zarr_store(self):
        return _zarr_dir()(self.path, owner=self)

    def lock(self):
        return _lock(self.target)

    # -- the layout of a run --------------------------------------------------------------
    def tree(self) -> Path:
        return self.path

    def children(self) -> list[str] | None:
        try:
            return sorted(e.name for e in os.scandir(self.path) if e.is_dir())
        except FileNotFoundError:
            return None

    def remove(self, name: str) -> None:
        shutil.rmtree(self.path / name)

    def clear(self) -> None:
        shutil.rmtree(self.path)

    # -- checkpoints: one file, <store>/_checkpoint/state.npz ---------------------------
    def write_checkpoint(self, fill, before_commit=None) -> None:
        """The new checkpoint is written to a temporary file in the same directory,
        flushed to disk and moved over the previous one (``os.replace``), then the rename
        itself made durable: a kill leaves the previous checkpoint or the new one."""
        d = self.path / CHECKPOINT_GROUP
        d.mkdir(exist_ok=True)
        if not (d / "zarr.json").exists():
            # a Zarr group: readers of the store then ignore the directory silently
            (d / "zarr.json").write_text(CHECKPOINT_GROUP_DOC)
        tmp = d / f"{CHECKPOINT_FILE}.{os.getpid()}.tmp"
        try:
            with open(tmp, "wb") as fh:
                fill(fh)
                fh.flush()
                os.fsync(fh.fileno())
            if before_commit is not None:
                before_commit()
            os.replace(tmp, d / CHECKPOINT_FILE)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
        try:  # make the rename itself durable
            fd = os.open(d, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        except OSError:
            pass

    @contextlib.contextmanager
    def checkpoint_file(self):
        f = self.path / CHECKPOINT_GROUP / CHECKPOINT_FILE
        yield f if f.exists() else None

    def remove_checkpoint(self) -> None:
        shutil.rmtree(self.path / CHECKPOINT_GROUP, ignore_errors=True)

    def clean(self) -> None:
        """zarr's temporary files of a write a kill interrupted (``*.partial``), and the
        checkpoint's temporary file."""
        for tmp in self.path.rglob("*.partial"):
            tmp.unlink(missing_ok=True)
        for tmp in (self.path / CHECKPOINT_GROUP).glob("*.tmp"):
            tmp.unlink(missing_ok=True)


@functools.cache
def _zarr_dir():
    """zarr's LocalStore whose file writes go through its owner's ``write`` (made on first
    use: zarr is imported only when a store is written)."""
    from zarr.storage import LocalStore as ZarrLocal

    class ZarrDir(ZarrLocal):
        def __init__(self, root, *, read_only: bool = False, owner: LocalStore):
            super().__init__(root, read_only=read_only)
            self.owner = owner

        def with_read_only(self, read_only: bool = False):
            return type(self)(self.root, read_only=read_only, owner=self.owner)

        async def _set(self, key, value, exclusive: bool = False) -> None:
            from zarr.core.buffer import Buffer

            if not self._is_open:
                await self._open()
            self._check_writable()
            if not isinstance(value, Buffer):
                raise TypeError(f"LocalStore.set(): `value` must be a Buffer instance, got {type(value)}")
            await asyncio.to_thread(self.owner.write, self.root / key, value, exclusive)

    return ZarrDir


def pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:       # exists, owned by someone else
        return True
    except (OverflowError, ValueError):
        return False
    return True


def _read_lock(path: Path):
    try:
        info = json.loads(path.read_text())
        return info if isinstance(info, dict) else {}
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        return {}


def _lock_is_stale(path: Path, info: dict) -> bool:
    """A lock is stale when its process is gone: same host and no such pid, or an
    empty/unreadable lock older than LOCK_GRACE_S (a sweep killed while creating it)."""
    if not info:
        try:
            return time.time() - path.stat().st_mtime > LOCK_GRACE_S
        except FileNotFoundError:
            return True
    if info.get("host") == socket.gethostname():
        pid = info.get("pid")
        return not (isinstance(pid, int) and pid_alive(pid))
    return False        # another host: cannot tell, refuse


@contextlib.contextmanager
def _lock(store: str):
    """Hold the sweep lock of ``store`` (a file ``.cracklab-sweep.lock`` in the store,
    created atomically, holding host, pid and start time). A second sweep into the same
    store raises ``StoreLocked`` naming the holder; a lock left by a sweep that was
    killed (same host, process gone) is detected as stale and taken over."""
    path = Path(store) / LOCK_NAME
    Path(store).mkdir(parents=True, exist_ok=True)
    me = {"host": socket.gethostname(), "pid": os.getpid(), "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
          "token": os.urandom(8).hex()}
    # the lock appears with its content: written to a private file, then hard-linked into
    # place (atomic, and it fails when the lock exists), so no reader sees an empty lock
    tmp = path.with_name(f"{LOCK_NAME}.{os.getpid()}-{me['token']}.tmp")
    tmp.write_text(json.dumps(me))
    try:
        for _ in range(5):
            try:
                os.link(tmp, path)
            except FileExistsError:
                info = _read_lock(path)
                if info is None:
                    continue                      # released meanwhile: try again
                if _lock_is_stale(path, info):
                    stale = path.with_name(f"{LOCK_NAME}.stale-{os.getpid()}-{os.urandom(3).hex()}")
                    try:
                        os.replace(path, stale)   # atomic: one of several contenders wins
                        if _read_lock(stale) != info:   # we moved a fresh lock: put it back
                            os.replace(stale, path)
                            continue
                        stale.unlink()
                    except FileNotFoundError:
                        pass
                    continue
                holder = f"pid {info.get('pid')} on {info.get('host')}" if info else "another process"
                since = f", since {info['started']}" if info.get("started") else ""
                raise StoreLocked("store", f"{store} is in use by another sweep ({holder}{since}); wait for it "
                                           f"to finish, or, if no sweep is running, delete {path}") from None
            break
        else:
            raise StoreLocked("store", f"{store}: could not take the sweep lock {path}")
    finally:
        tmp.unlink(missing_ok=True)
    try:
        yield path
    finally:
        if _read_lock(path) == me:
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
