"""Checkpoints of long runs and the checks on a run's Zarr store.

A checkpoint holds the full solver state after some step n (stepper locals, the interface,
its half spaces and their history engines, the recorder's station series and rupture
times) and the number of snapshots the store held when it was written: one ``.npz`` of
arrays with the rest as one JSON document (nested dicts of arrays, numbers, strings and
None; int or str keys), never a pickle. It is kept by the run's store
(``cracklab.output.stores``: ``Store.write_checkpoint``), which commits it atomically: on a
local disk ``<store>/_checkpoint/state.npz``, written to a temporary file, flushed and
moved over the previous one with ``os.replace``; on an object store under a fresh key,
then a pointer object with its SHA-256 written last. A kill leaves either the previous
checkpoint or the new one. The run's store has its final size from the start (snapshots
NaN until written); snapshots written after the checkpoint are written again, with the
same values, when the run resumes.
"""
from __future__ import annotations

import errno
import hashlib
import json
import os
import time
import warnings
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import StoreError
from .stores.base import CHECKPOINT_GROUP as GROUP, Store, is_url
from .stores.local import CHECKPOINT_FILE as FILE

RUN_FORMAT = 1          # attr ``cracklab_run_format`` of a run store
CHECKPOINT_FORMAT = 1   # layout of the checkpoint file
# test hook only: seconds to sleep inside a checkpoint write, with the new file written
# but not yet moved into place (lets a test SIGKILL the run in the middle of a write)
SLEEP_ENV = "CRACKLAB_TEST_CHECKPOINT_SLEEP"


# ----------------------------------------------------------------------------- encoding
def _encode(obj, arrays: dict):
    if isinstance(obj, dict):
        items = []
        for k, v in obj.items():
            if isinstance(k, (bool, np.bool_)) or not isinstance(k, (int, np.integer, str)):
                raise TypeError(f"checkpoint state keys must be int or str, got {k!r}")
            items.append(["i" if isinstance(k, (int, np.integer)) else "s",
                          int(k) if isinstance(k, (int, np.integer)) else k, _encode(v, arrays)])
        return {"dict": items}
    if isinstance(obj, (list, tuple)):
        return {"list": [_encode(v, arrays) for v in obj]}
    if isinstance(obj, np.ndarray) or isinstance(obj, np.generic) and not isinstance(
            obj, (np.integer, np.floating, np.bool_)):
        a = np.asarray(obj)
        if a.dtype == object:
            raise TypeError("checkpoint state arrays must not have dtype object")
        name = f"a{len(arrays)}"
        arrays[name] = a
        return {"array": name}
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return {"float": float(obj).hex()}   # exact, and inf / nan safe
    raise TypeError(f"cannot checkpoint a value of type {type(obj).__name__}")


def _decode(obj, arrays):
    if isinstance(obj, dict):
        if "dict" in obj:
            return {(int(k) if t == "i" else k): _decode(v, arrays) for t, k, v in obj["dict"]}
        if "list" in obj:
            return [_decode(v, arrays) for v in obj["list"]]
        if "array" in obj:
            return np.array(arrays[obj["array"]])
        if "float" in obj:
            return float.fromhex(obj["float"])
    return obj


def _sleep_hook():
    delay = os.environ.get(SLEEP_ENV)
    if delay:
        time.sleep(float(delay))


def as_store(store) -> Store:
    """The ``Store`` of ``store`` (a Store, a local path or a URL)."""
    if isinstance(store, Store):
        return store
    from .stores import store_for

    return store_for(store)


def write(path, state: dict) -> float:
    """Write ``state`` as the checkpoint of store ``path`` (a local path, a URL or a
    ``Store``), replacing the previous one atomically; return seconds taken."""
    t0 = time.perf_counter()
    arrays: dict = {}
    meta = json.dumps({"checkpoint_format": CHECKPOINT_FORMAT, "state": _encode(state, arrays)})

    def fill(fh):
        np.savez(fh, __meta__=np.frombuffer(meta.encode(), dtype=np.uint8), **arrays)

    as_store(path).write_checkpoint(fill, before_commit=_sleep_hook)
    return time.perf_counter() - t0


def read(path) -> dict | None:
    """The checkpoint of store ``path`` (None when there is none)."""
    with as_store(path).checkpoint_file() as f:
        if f is None:
            return None
        try:
            with np.load(f, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
            meta = json.loads(arrays.pop("__meta__").tobytes().decode())
        except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError) as exc:
            raise StoreError(path, f"its checkpoint {f} is unreadable ({exc}); run again without resume") from None
    if meta.get("checkpoint_format") != CHECKPOINT_FORMAT:
        raise StoreError(path, f"its checkpoint has format {meta.get('checkpoint_format')!r}, this cracklab "
                               f"reads format {CHECKPOINT_FORMAT}; run again without resume")
    return _decode(meta["state"], arrays)


def remove(path) -> None:
    """Delete the checkpoint of store ``path`` (after the run finished)."""
    as_store(path).remove_checkpoint()


def scene_digest(scene_json: str, inputs: dict) -> str:
    """A hash of a scene (its JSON and input arrays): a resume must run the same scene."""
    h = hashlib.sha256(scene_json.encode())
    for k in sorted(inputs):
        a = np.ascontiguousarray(inputs[k])
        h.update(k.encode() + str(a.dtype).encode() + str(a.shape).encode() + a.tobytes())
    return h.hexdigest()


# ----------------------------------------------------------------------------- the store
def encoding(ds, skip=()) -> dict:
    """Zarr encodings of the variables of ``ds`` (but ``skip``, already in the store): zstd,
    then a crc32c checksum of every chunk (a changed byte raises on read instead of giving
    wrong values)."""
    from zarr.codecs import Crc32cCodec, ZstdCodec

    skip = set(skip)
    return {name: {"compressors": (ZstdCodec(level=0, checksum=False), Crc32cCodec())}
            for name in ds.variables if name not in skip}


def local_path(store):
    """The filesystem path of ``store`` (None for Zarr store objects and URLs)."""
    if isinstance(store, (str, os.PathLike)):
        s = os.fspath(store)
        if not is_url(s):
            return Path(s).expanduser()
    return None


def inspect(path) -> tuple[str, dict]:
    """(kind, attrs) of a store path (or URL, or ``Store``): kind is "absent", "empty" (an
    empty directory or Zarr group), "run" (a single cracklab run), "ensemble" or "other"."""
    st = as_store(path)
    if not st.local:
        return _inspect_url(st)
    p = st.path
    if not p.exists():
        return "absent", {}
    if not p.is_dir():
        return "other", {}
    try:
        entries = [e for e in os.listdir(p)]
    except OSError as exc:
        raise StoreError(path, f"cannot be read ({os.strerror(exc.errno) if exc.errno else exc})") from None
    if not entries:
        return "empty", {}
    meta = p / "zarr.json"
    if meta.exists():
        try:
            json.loads(meta.read_text())
        except (OSError, ValueError) as exc:
            raise StoreError(path, f"its metadata file {meta} is damaged ({exc}); the store cannot be "
                                   f"identified or resumed: restore the file, or delete the store and run again") from None
    return _classify(str(p))


def _classify(target, **open_kw) -> tuple[str, dict]:
    """(kind, attrs) of the Zarr group at ``target`` (a path or zarr store): "ensemble", "run",
    "empty", or "other" (not a Zarr group, or one of something else)."""
    import zarr

    try:
        with warnings.catch_warnings():     # a damaged array directory is for cracklab.output.verify to name
            warnings.simplefilter("ignore")
            g = zarr.open_group(target, mode="r", **open_kw)
            attrs = dict(g.attrs)
            members = [k for k in g.array_keys()] + [k for k in g.group_keys() if k != GROUP]
    except Exception:  # noqa: BLE001 - not a Zarr group
        return "other", {}
    if "cracklab_ensemble" in attrs:
        return "ensemble", attrs
    if "scene" in attrs or "cracklab_run_format" in attrs:
        return "run", attrs
    return ("empty", attrs) if not members else ("other", attrs)


def _inspect_url(st) -> tuple[str, dict]:
    """``inspect`` of a store at a URL (an object store has no empty directories: a
    prefix with nothing below it is "absent")."""
    fs, root = st.fs
    try:
        entries = fs.ls(root, detail=False, refresh=True)
    except FileNotFoundError:
        entries = []
    except OSError as exc:
        raise StoreError(st.target, f"cannot be read ({exc})") from None
    if not entries:
        return "absent", {}
    try:
        text = fs.cat_file(st.key("zarr.json"))
    except FileNotFoundError:
        text = None
    if text is not None:
        try:
            json.loads(text)
        except (ValueError, UnicodeDecodeError) as exc:
            raise StoreError(st.target, f"its metadata {st.target}/zarr.json is damaged ({exc}); the store cannot "
                                        f"be identified or resumed: restore it, or delete the store and run "
                                        f"again") from None
    return _classify(st.zarr_store(), use_consolidated=False)


def check_writable_target(path) -> None:
    """Refuse to overwrite a path that is not a cracklab run store (or empty)."""
    kind, _ = inspect(path)
    if kind == "ensemble":
        raise StoreError(path, "is an ensemble store (cracklab sweep); a single run needs its own path")
    if kind == "other":
        raise StoreError(path, "exists and is not a cracklab run store (nor empty); refusing to overwrite "
                               "it: choose another output path or delete it")


def check_resumable(path, version: str) -> tuple[dict, dict | None]:
    """(attrs, checkpoint) of a run store to resume; raise StoreError when it cannot be."""
    kind, attrs = inspect(path)
    if kind in ("absent", "empty"):
        return attrs, None
    if kind != "run":
        raise StoreError(path, f"is not a cracklab run store ({'an ensemble store' if kind == 'ensemble' else 'unknown content'}); "
                               "cannot resume from it")
    fmt = attrs.get("cracklab_run_format")
    if fmt != RUN_FORMAT:
        raise StoreError(path, f"was written by cracklab {attrs.get('cracklab_version', '?')} with store format "
                               f"{fmt if fmt is not None else '0 (no cracklab_run_format attr)'}; this cracklab "
                               f"({version}) resumes format {RUN_FORMAT} only: run again without resume")
    ck = read(path)
    if ck is not None and ck.get("cracklab_version") != version:
        raise StoreError(path, f"its checkpoint was written by cracklab {ck.get('cracklab_version')}, this is "
                               f"cracklab {version}: resume with that version or run again without resume")
    return attrs, ck


def _t_arrays(g):
    for name in list(g.array_keys()):
        arr = g[name]
        dims = getattr(arr.metadata, "dimension_names", None) or arr.attrs.get("_ARRAY_DIMENSIONS") or ()
        yield name, arr, tuple(dims)


def is_final_array(name: str) -> bool:
    """True for the arrays the end of a run writes (station series, rupture time)."""
    return name == "rupture_time" or name == "t_station" or name.startswith("station")


def prepare_resume(path, t_all) -> None:
    """Put the store of a killed run back in shape to continue: snapshot variables at
    their full length (their values past the checkpoint are rewritten as the run goes
    on), without what the end of a run writes (station series, rupture time), without
    temporary files (``Store.clean``); ``path``: a local path, a URL or a ``Store``."""
    import zarr

    st = as_store(path)
    for name in st.children() or ():       # by name: their metadata may be what a kill damaged
        if is_final_array(name):
            st.remove(name)
    # temporary files of a write the kill interrupted, before zarr lists the hierarchy
    st.clean()
    g = zarr.open_group(str(st.path) if st.local else st.zarr_store(), mode="a")
    for name, arr, dims in _t_arrays(g):
        if dims and dims[0] == "t":
            if arr.shape[0] != len(t_all):
                arr.resize((len(t_all),) + tuple(arr.shape[1:]))
                if name == "t":
                    arr[:] = t_all


def cut_snapshots(store, nsnap: int) -> None:
    """Shorten the snapshot variables of a run store to the first ``nsnap`` (a failed run)."""
    import zarr

    g = zarr.open_group(str(store) if isinstance(store, (str, os.PathLike)) else store, mode="a")
    for _, arr, dims in _t_arrays(g):
        if dims and dims[0] == "t" and arr.shape[0] != nsnap:
            arr.resize((nsnap,) + tuple(arr.shape[1:]))


def store_error(path, exc: OSError, doing: str) -> StoreError:
    """One clear StoreError for an OSError met while writing the store."""
    code = getattr(exc, "errno", None)
    why = {errno.ENOSPC: "no space left on device", errno.EDQUOT: "disk quota exceeded",
           errno.EACCES: "permission denied (read-only location?)", errno.EPERM: "operation not permitted "
           "(read-only location?)", errno.EROFS: "read-only file system"}.get(code) or \
        (os.strerror(code) if code else str(exc))
    return StoreError(path, f"{why} while {doing}")


# ----------------------------------------------------------------------------- what a store holds
def read_entry(path, key):
    """One top-level entry of the checkpoint of store ``path`` (e.g. "rupture", "n"),
    reading only the arrays it holds; None without a (readable) checkpoint."""
    try:
        with as_store(path).checkpoint_file() as f:
            if f is None:
                return None
            with np.load(f, allow_pickle=False) as z:
                meta = json.loads(z["__meta__"].tobytes().decode())
                items = meta["state"]["dict"]
                for _, k, v in items:
                    if k == key:
                        return _decode(v, z)
    except (OSError, ValueError, KeyError, TypeError, zipfile.BadZipFile, EOFError, StoreError):
        return None
    return None


def _frame_written(arr, k) -> bool:
    frame = np.asarray(arr[k])
    return not bool(np.isnan(frame).all()) if frame.dtype.kind == "f" else True


def written_snapshots(group, fields, start=0, flush=8) -> int:
    """How many snapshots, from the first, the arrays ``fields`` of the Zarr group ``group``
    hold (an unfinished run's store is created at full size, NaN until written): a
    bisection over the frames, then the last ``flush`` frames below the boundary each
    checked (one flush's chunks may land in any order). Reads one chunk at a time."""
    best = None
    for name in fields:
        arr = group[name]
        n = int(arr.shape[0])
        lo, hi = min(start, n), n           # frames < lo are written; the boundary is in [lo, hi]
        while lo < hi:
            mid = (lo + hi) // 2
            if _frame_written(arr, mid):
                lo = mid + 1
            else:
                hi = mid
        for k in range(max(start, lo - flush), lo):
            if not _frame_written(arr, k):
                lo = k
                break
        best = lo if best is None else min(best, lo)
    return 0 if best is None else best


@dataclass(frozen=True)
class RunProgress:
    """What a run's store holds: ``status`` "complete", "running" (unfinished: killed or
    still running) or "failed"; ``snapshots`` complete ones of ``total``; the checkpoint's
    ``step`` (None without one); the run's ``error`` (failed runs)."""

    status: str
    snapshots: int
    total: int
    step: int | None = None
    error: str | None = None

    @property
    def finished(self) -> bool:
        return self.status == "complete"

    def describe(self) -> str:
        """"unfinished (status running): 8 of 33 snapshots written, checkpoint after step 120"."""
        if self.status == "complete":
            return f"complete: {self.total} snapshots"
        if self.status == "failed":
            return (f"failed ({self.error or 'no error recorded'}): {self.snapshots} snapshot"
                    f"{'s' if self.snapshots != 1 else ''} recorded")
        ck = f", checkpoint after step {self.step}" if self.step is not None else ", no checkpoint"
        return f"unfinished (status {self.status}): {self.snapshots} of {self.total} snapshots written{ck}"


def run_progress(path) -> RunProgress:
    """The ``RunProgress`` of the run store (or ensemble member group) at ``path``, read
    lazily: the attrs, then for an unfinished run one chunk at a time (``written_snapshots``);
    ``path``: a local path or a URL (read through its ``Store.zarr_store``)."""
    import zarr

    from .stores import zarr_of

    g = zarr.open_group(zarr_of(path), mode="r")
    attrs = dict(g.attrs)
    status = attrs.get("cracklab_status", "complete" if "scene" in attrs else "running")
    if attrs.get("status") == "failed" and status != "complete":
        status = "failed"
    fields = [name for name, arr, dims in _t_arrays(g) if dims and dims[0] == "t" and name != "t"]
    total = int(g["t"].shape[0]) if "t" in g.array_keys() else 0
    error = attrs.get("cracklab_error") or attrs.get("error")
    if status == "running" and fields:
        start = int(attrs.get("cracklab_checkpoint_snapshots") or 0)
        n = written_snapshots(g, fields, start=start)
    else:
        n = total
    step = attrs.get("cracklab_checkpoint_step")
    return RunProgress(status, n, total, None if step is None else int(step), error)
