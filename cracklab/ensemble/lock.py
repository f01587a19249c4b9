"""The store lock: one sweep at a time into a store (``store_lock``, ``StoreLocked``)."""
from __future__ import annotations

import contextlib
import json
import os
import socket
import time
from pathlib import Path

from ..errors import InputError

LOCK_NAME = ".cracklab-sweep.lock"
LOCK_GRACE_S = 10.0     # an empty or unreadable lock younger than this is being written


class StoreLocked(InputError):
    """Another sweep is running into this store (see ``store_lock``)."""


def _pid_alive(pid: int) -> bool:
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
        return not (isinstance(pid, int) and _pid_alive(pid))
    return False        # another host: cannot tell, refuse


@contextlib.contextmanager
def store_lock(store: str):
    """Hold the sweep lock of ``store`` (a file ``.cracklab-sweep.lock`` in the store,
    created atomically, holding host, pid and start time). A second sweep into the same
    store raises ``StoreLocked`` naming the holder; a lock left by a sweep that was
    killed (same host, process gone) is detected as stale and taken over. Only local
    paths are locked (a URL store is not)."""
    if "://" in store:
        yield None
        return
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
