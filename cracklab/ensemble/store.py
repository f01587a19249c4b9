"""The ensemble store: its paths and kind, checks before a sweep writes, the root group,
each member's status record, and the atomic replacement of a complete member."""
from __future__ import annotations

import contextlib
import errno
import json
import os
import shutil
import traceback
import warnings
from pathlib import Path

from ..errors import InputError, StoreError
from ..output.stores import is_url, store_for, zarr_of
from .identity import FORMAT, canonical_json
from .lock import LOCK_NAME
from .spec import Member

MEMBERS = "members"


def store_str(store) -> str:
    """A store path as the text used everywhere: a URL as given (no trailing /), a local
    path absolute."""
    s = os.fspath(store)
    if is_url(s):
        return s.rstrip("/")
    return str(Path(s).expanduser().resolve())


def member_path(store, mid: str) -> str:
    """The path of member ``mid``'s group: STORE/members/<id>."""
    return f"{store_str(store)}/{MEMBERS}/{mid}"


def open_group(path, mode, *, consolidated=None):
    """The Zarr group at ``path``; created as Zarr v3 in a writing mode. Read ("r") from its
    own metadata, never from consolidated metadata (which a running sweep may have made
    stale). ``consolidated=False`` in a writing mode: the group's next metadata write
    drops its consolidated metadata. Opened through the store protocol (``zarr_of``: a
    URL without a listings cache, its writes guarded while a member runs)."""
    import zarr

    if mode in ("w", "a", "w-"):
        return zarr.open_group(zarr_of(path), mode=mode, zarr_format=3, use_consolidated=consolidated)
    return zarr.open_group(zarr_of(path), mode=mode, use_consolidated=False)


def consolidate(path):
    """Write the consolidated metadata of the group at ``path`` and everything below it
    into its zarr.json, where ``xarray.open_zarr`` and ``open_datatree`` look first (zarr's
    warning that Zarr v3 does not standardise it yet is silenced)."""
    import zarr

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        zarr.consolidate_metadata(zarr_of(path))


def is_ensemble(store) -> bool:
    """True when ``store`` is an ensemble store (root attr cracklab_ensemble)."""
    try:
        root = open_group(store_str(store), "r")
    except Exception:  # noqa: BLE001 - not a Zarr group at all
        return False
    return "cracklab_ensemble" in root.attrs


def store_kind(store) -> str:
    """"ensemble" or "run" for a cracklab store; an InputError naming ``store`` for
    anything else (no such path, a file, a directory or Zarr group that cracklab did
    not write, an ensemble store of a newer format)."""
    s = store_str(store)
    if is_url(s):
        store_for(s).check(exists=True)     # its scheme, credentials, bucket and zarr.json: one line each
    elif not Path(s).exists():
        raise InputError("store", f"{s} does not exist")
    check_metadata(s, Path(s) / "zarr.json" if not is_url(s) else None,
                    "restore it, or delete the store and run it again")
    try:
        root = open_group(s, "r")
    except Exception:  # noqa: BLE001 - reported as one clear line
        raise InputError("store", f"{s} is not a Zarr store (no Zarr group there); expected a cracklab "
                                  f"run or ensemble store") from None
    attrs = dict(root.attrs)
    if "cracklab_ensemble" in attrs:
        fmt = attrs["cracklab_ensemble"]
        if not isinstance(fmt, int) or isinstance(fmt, bool) or fmt > FORMAT:
            raise InputError("store", f"{s} is an ensemble store of format {fmt!r}; this cracklab reads "
                                      f"format {FORMAT} (written by another cracklab version)")
        return "ensemble"
    if isinstance(attrs.get("scene"), str):
        return "run"
    raise InputError("store", f"{s} is a Zarr group but not a cracklab run or ensemble store "
                              f"(no 'scene' or 'cracklab_ensemble' attribute)")


def check_metadata(store, meta, remedy):
    """StoreError naming ``meta`` (a zarr.json) when it exists but does not parse."""
    if meta is None or not meta.exists():
        return
    from ..output.verify import read_json

    doc, why = read_json(meta)
    if doc is None:
        raise StoreError(store, f"its metadata file {meta} is {why}; {remedy} (cracklab verify {store} "
                                f"lists all damage)")


def check_store(store: str):
    """Refuse, before anything is written, a path that cannot become or be an ensemble
    store: a file, a non-empty directory that is not a Zarr group, a Zarr group that is
    not an ensemble (e.g. a single run), or a store of a newer ensemble format; a URL
    whose scheme has no store, whose credentials are missing or whose bucket does not
    exist (StoreError, ``Store.check``)."""
    import zarr

    if is_url(store):
        store_for(store).check()    # its scheme, credentials and bucket
    else:
        p = Path(store)
        if p.exists() and not p.is_dir():
            raise InputError("store", f"{store} is a file, not a Zarr store; choose another path")
    try:
        root = zarr.open_group(zarr_of(store), mode="r", use_consolidated=False)
    except Exception:  # noqa: BLE001 - no group there (yet)
        root = None
    if root is None:
        if not is_url(store) and Path(store).is_dir() and any(
                n != LOCK_NAME for n in os.listdir(store)):
            raise InputError("store", f"{store} is a directory with other content, not a Zarr store; "
                                      f"choose another path")
        return
    attrs = dict(root.attrs)
    if "cracklab_ensemble" not in attrs:
        what = "the store of a single cracklab run" if "scene" in attrs else "a Zarr group"
        if "scene" in attrs or list(root.keys()):
            raise InputError("store", f"{store} is {what}, not an ensemble store; choose another path")
        return
    fmt = attrs.get("cracklab_ensemble")
    if not isinstance(fmt, int) or isinstance(fmt, bool) or fmt > FORMAT:
        raise InputError("store", f"{store} is an ensemble store of format {fmt!r}; this cracklab reads "
                                  f"format {FORMAT} (written by another cracklab version)")


def init_store(store: str, study_spec: dict, members: list[Member], axes=()):
    """Create (or reopen) the root group and members/; record the study and member order."""
    check_store(store)
    root = open_group(store, "a", consolidated=False)   # the consolidated metadata goes until the sweep ends
    old = list(root.attrs.get("members", []))
    ids = old + [m.id for m in members if m.id not in set(old)]
    root.update_attributes({
        "cracklab_ensemble": FORMAT,
        "title": f"cracklab ensemble: {study_spec.get('name', 'study')}",
        "study": json.dumps(study_spec, sort_keys=True),
        "members": ids,
        "axes": json.dumps(list(axes)),
    })
    if not is_url(store):
        from ..output.verify import read_json

        meta = Path(store) / MEMBERS / "zarr.json"
        if meta.exists() and read_json(meta)[0] is None:     # damaged: the members group holds no attrs
            meta.write_text(json.dumps({"zarr_format": 3, "node_type": "group", "attributes": {}}))
        for left in (Path(store) / MEMBERS).glob(f".*{SWAP_TAG}*"):    # replacements of killed workers
            shutil.rmtree(left, ignore_errors=True)
    root.require_group(MEMBERS)
    return root


# ---------------------------------------------------------------------------- members
def member_attrs(store, mid):
    """The attrs of member ``mid``'s group, or None when it is missing or unreadable."""
    try:
        return dict(open_group(member_path(store, mid), "r").attrs)
    except Exception:  # noqa: BLE001 - missing or unreadable group
        return None


def is_complete(store, mid) -> bool:
    """True when member ``mid``'s group says ``complete``."""
    attrs = member_attrs(store, mid)
    return bool(attrs and attrs.get("complete") is True)


def damage_of(store, member: Member):
    """None when the complete member ``member`` is sound (every chunk read and checked, its
    metadata and parameters against what is stored: ``checks.check_member``); else a line
    naming the damage, after marking the member damaged and incomplete (so that no reader
    takes it, and the sweep runs it again). At a URL the same checks, over the member's
    keys only (``verify.store_tree``)."""
    from ..output.verify import store_tree
    from .checks import check_member

    report = check_member(store_tree(store, members=[member.id]) if is_url(store) else store, member.id)
    if report.ok:
        return None
    line = report.first()
    with contextlib.suppress(Exception):
        open_group(member_path(store, member.id), "a").update_attributes(
            {"complete": False, "status": "damaged", "error": f"damaged: {line}"})
    return line


def traceback_summary(exc, limit=12) -> str:
    """The last lines of ``exc``'s traceback, for a failed member's ``traceback`` attr."""
    lines = traceback.format_exception(type(exc), exc, exc.__traceback__)
    text = "".join(lines).rstrip().splitlines()
    return "\n".join(text[-limit * 2:])


def error_line(exc) -> str:
    """One line for ``exc``: "Type: first line of its message"."""
    msg = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__


def record_failure(store, member: Member, error: str, tb: str, elapsed: float | None = None):
    """Mark ``member`` failed (and incomplete) in its group, with its error and traceback."""
    path = member_path(store, member.id)
    try:
        g = open_group(path, "a")
        g.update_attributes({"member_id": member.id, "member_params": canonical_json(member.params),
                             "member_swept": json.dumps(list(member.swept)), "status": "failed",
                             "error": error, "traceback": tb, "complete": False,
                             **({"elapsed_s": round(elapsed, 3)} if elapsed is not None else {})})
    except Exception:  # noqa: BLE001 - the store unreachable: the member stays incomplete (run again)
        return


# ---------------------------------------------------------------------------- atomic member replacement
SWAP_TAG = ".replacement-"     # members/.<id>.replacement-<token>: a complete member's new run


def _exchange(a: str, b: str) -> bool:
    """Swap the directories ``a`` and ``b`` in one atomic step (Linux renameat2 with
    RENAME_EXCHANGE); False where the system or file system cannot."""
    import ctypes

    try:
        fn = ctypes.CDLL(None, use_errno=True).renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd, rename_exchange = -100, 2
    if fn(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EPERM):
        return False
    raise OSError(code, os.strerror(code), b)


def swap_in(new: str, path: str):
    """Put the member group written at ``new`` in the place of the one at ``path``: one
    atomic exchange of the two directories (readers see the old group or the new one,
    each whole), then the old one is deleted. Without renameat2: two renames, between
    which the member is briefly absent (never a mixture)."""
    if _exchange(new, path):
        shutil.rmtree(new, ignore_errors=True)          # now the old group
        return
    old = f"{new}.old"
    os.rename(path, old)
    os.rename(new, path)
    shutil.rmtree(old, ignore_errors=True)
