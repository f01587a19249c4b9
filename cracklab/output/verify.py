"""Verification of run and ensemble stores (``cracklab verify STORE``).

One job: say whether what a store holds can be trusted, and name what cannot. For a run
store (what ``cracklab.simulate(scene, store=...)`` writes) it checks that

* every metadata document (``zarr.json``) parses and describes a Zarr group or array;
* the arrays the run holds are there: the coordinates, the recorded snapshot fields,
  the scene's input fields and, once the run has ended (``cracklab_status`` complete or
  failed), its station series and rupture times;
* every chunk that should be written is present: a missing chunk would read as the fill
  value (NaN); cracklab writes every chunk of the written extent, NaN-only ones included;
* every present chunk reads: decompression and, for arrays written with a ``crc32c``
  codec (every array of this cracklab), its checksum. Arrays without one (written by an
  older cracklab) are noted: a flipped byte there can go unnoticed.

An ensemble store is checked member by member (the complete ones; the others are rerun
by the next sweep anyway). ``check_run``/``check_ensemble`` return a ``Report``; reading
every chunk costs about as much as loading the store once (``read=False`` checks the
metadata and the chunk listing only).
"""
from __future__ import annotations

import json
import math
import os
import warnings
from dataclasses import dataclass, field
from itertools import product
from pathlib import Path

from ..errors import StoreWarning
from .checkpoint import is_final_array

CHECKSUM_CODEC = "crc32c"
CHECKPOINT_GROUP = "_checkpoint"
MEMBERS = "members"
ENDED = ("complete", "failed")


def final_arrays_fallback(stations: bool) -> list[str]:
    """The end-of-run arrays of a store that does not list them (older cracklab)."""
    out = ["rupture_time"]
    if stations:
        out += ["station", "station_x1", "station_x3", "t_station", "station_strength"]
    return out


@dataclass
class Damage:
    path: str                 # the damaged (or missing) file or directory
    what: str                 # what is wrong with it
    member: str | None = None

    def __str__(self):
        return f"{self.path}: {self.what}"


@dataclass
class Report:
    store: str
    kind: str                                   # "run" or "ensemble"
    damage: list = field(default_factory=list)  # Damage
    notes: list = field(default_factory=list)   # informational lines (status, no checksums)
    status: str | None = None                   # run: cracklab_status
    members: dict = field(default_factory=dict)  # ensemble: id -> "sound", "damaged" or a status
    unchecksummed: list = field(default_factory=list)   # arrays written without checksums
    arrays: int = 0
    chunks: int = 0

    @property
    def ok(self) -> bool:
        return not self.damage

    def damaged_members(self) -> list[str]:
        return list(dict.fromkeys(d.member for d in self.damage if d.member))

    def remedy(self) -> str:
        if self.ok:
            return ""
        if self.kind == "ensemble":
            if any(d.member is None for d in self.damage):
                return ("rerun the sweep (cracklab sweep STUDY.toml -o STORE) to repair the store's groups; "
                        "if the root zarr.json is damaged, restore it or delete the store and run the sweep again")
            return ("rerun the sweep (cracklab sweep STUDY.toml -o STORE): it recomputes the damaged members "
                    "(--no-resume recomputes every member)")
        return ("run it again with --resume, which recomputes a damaged store: cracklab run SCENE.toml -o STORE "
                "--resume (SCENE may be the store itself while its scene inputs are intact)")

    def summary(self) -> str:
        what = f"{self.arrays} arrays, {self.chunks} chunks read" if self.chunks else f"{self.arrays} arrays"
        if self.kind == "ensemble":
            n = len(self.members)
            bad = self.damaged_members()
            head = (f"ensemble, {n} member group{'s' if n != 1 else ''} "
                    f"({sum(v == 'sound' for v in self.members.values())} complete and sound), {what}")
            if bad:
                head += f": {len(bad)} damaged member{'s' if len(bad) != 1 else ''}"
        else:
            head = f"run (status {self.status}), {what}"
        return head + (": sound" if self.ok else f": {len(self.damage)} damaged")

    def lines(self) -> list[str]:
        out = [f"{self.store}: {self.summary()}"]
        for d in self.damage:
            who = f"member {d.member}: " if d.member else ""
            out.append(f"  DAMAGED {who}{d}")
        if self.unchecksummed:
            n = len(self.unchecksummed)
            out.append(f"  note: no checksums in {n} array{'s' if n != 1 else ''} (e.g. {self.unchecksummed[0]}): "
                       f"written by an older cracklab; a changed byte there may go unnoticed")
        out += [f"  note: {n}" for n in self.notes]
        if not self.ok:
            out.append(f"  what to do: {self.remedy()}")
        return out

    def first(self, n=3) -> str:
        """The first ``n`` damaged files as one line."""
        shown = "; ".join(str(d) for d in self.damage[:n])
        more = len(self.damage) - n
        return shown + (f"; and {more} more (cracklab verify lists them)" if more > 0 else "")


# ---------------------------------------------------------------------------- metadata
def read_json(path: Path):
    """(document, None) or (None, what is wrong) for a metadata file."""
    try:
        text = path.read_text()
    except FileNotFoundError:
        return None, "missing"
    except (OSError, UnicodeDecodeError) as exc:
        return None, f"cannot be read ({exc})"
    try:
        doc = json.loads(text)
    except ValueError as exc:
        return None, f"not valid JSON ({exc}): the metadata is damaged"
    if not isinstance(doc, dict) or doc.get("zarr_format") not in (2, 3):
        return None, "not a Zarr metadata document: the metadata is damaged"
    return doc, None


def _subdirs(path: Path) -> list[str]:
    try:
        return sorted(e.name for e in os.scandir(path) if e.is_dir() and not e.name.startswith("."))
    except OSError:
        return []


def _scene_expectations(attrs: dict):
    """(snapshot fields, input arrays, has stations) from the ``scene`` attr (None: unreadable)."""
    try:
        scene = json.loads(attrs["scene"])
        record = scene.get("record", {}) or {}
    except (KeyError, TypeError, ValueError, AttributeError):
        return None
    fields = record.get("fields", [])
    fields = [fields] if isinstance(fields, str) else list(fields or [])
    inputs = set()

    def refs(d):
        if isinstance(d, dict):
            if set(d) == {"array"} and isinstance(d["array"], str):
                inputs.add(d["array"])
            for v in d.values():
                refs(v)
        elif isinstance(d, list):
            for v in d:
                refs(v)

    refs(scene)
    return fields, sorted(inputs), bool(record.get("stations"))


# ---------------------------------------------------------------------------- one array
def _check_array(adir: Path, name: str, *, read: bool, t_extent, report: Report, member):
    """Check one array directory; ``t_extent``: snapshots along t that must be written
    (None: every chunk)."""
    import zarr

    doc, why = read_json(adir / "zarr.json")
    if doc is None:
        report.damage.append(Damage(str(adir / "zarr.json"), f"array {name}: metadata {why}", member))
        return
    if doc.get("node_type", "array") != "array" and doc.get("zarr_format") == 3:
        report.damage.append(Damage(str(adir / "zarr.json"), f"{name} is not an array", member))
        return
    try:
        arr = zarr.open_array(store=str(adir), mode="r")
    except Exception as exc:  # noqa: BLE001 - any unreadable metadata is damage
        report.damage.append(Damage(str(adir / "zarr.json"), f"array {name}: metadata cannot be used ({exc})",
                                    member))
        return
    report.arrays += 1
    names = [c.get("name") if isinstance(c, dict) else None for c in doc.get("codecs", [])]
    checksummed = CHECKSUM_CODEC in names
    # an older cracklab wrote no checksums, nor the chunks that held only the fill value
    # (an all-NaN rupture time, an all-False mask): there a missing chunk may be fill
    tolerant = False
    if not checksummed:
        report.unchecksummed.append(str(adir))
        tolerant = name == "rupture_time" or name.startswith("input_")
    shape = tuple(arr.shape)
    chunks = tuple(arr.metadata.chunk_grid.chunk_shape) if hasattr(arr.metadata, "chunk_grid") else tuple(arr.chunks)
    grid = [range(math.ceil(n / c)) if n else range(0) for n, c in zip(shape, chunks)]
    dims = tuple(getattr(arr.metadata, "dimension_names", None) or ())
    along_t = bool(dims) and dims[0] == "t" and name != "t"
    for coords in product(*grid):
        key = arr.metadata.encode_chunk_key(coords) if hasattr(arr.metadata, "encode_chunk_key") else \
            ".".join(map(str, coords))
        f = adir / key
        required = not (along_t and t_extent is not None and coords[0] * chunks[0] >= t_extent)
        if not f.exists():
            if required and not tolerant:
                report.damage.append(Damage(str(f), f"chunk {coords} of {name} is missing (it would read as "
                                                    f"fill values, NaN)", member))
            continue
        if not read or not required:
            continue
        sel = tuple(slice(c * s, min((c + 1) * s, n)) for c, s, n in zip(coords, chunks, shape))
        try:
            arr[sel]
        except Exception as exc:  # noqa: BLE001 - checksum, decompression, decoding errors
            report.damage.append(Damage(str(f), f"chunk {coords} of {name} cannot be read ({_why(exc)})", member))
            continue
        report.chunks += 1


def _why(exc) -> str:
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    if "checksum" in text.lower():
        return f"checksum mismatch: its bytes changed after it was written; {text}"
    return text


# ---------------------------------------------------------------------------- a run
def check_run(path, *, read: bool = True, snapshots: int | None = None, final: bool | None = None,
              member: str | None = None, report: Report | None = None) -> Report:
    """Check the run store at ``path`` (a local directory).

    ``snapshots``: how many snapshots must be written (default: all, for a run that
    ended; those up to its checkpoint for a running one); ``final``: whether the
    end-of-run arrays must be there (default: when ``cracklab_status`` is complete or
    failed). ``member``: the ensemble member id the damage is reported under."""
    p = Path(path)
    rep = report if report is not None else Report(str(p), "run")
    doc, why = read_json(p / "zarr.json")
    if doc is None:
        rep.damage.append(Damage(str(p / "zarr.json"), f"the run's group metadata is {why}", member))
        return rep
    attrs = doc.get("attributes", {}) or {}
    status = attrs.get("cracklab_status", "complete" if "scene" in attrs else None)
    if report is None:
        rep.status = status
    expect = _scene_expectations(attrs)
    if expect is None:
        rep.damage.append(Damage(str(p / "zarr.json"), "the 'scene' attribute is missing or not valid JSON", member))
        fields, inputs, stations = [], [], False
    else:
        fields, inputs, stations = expect
    ended = status in ENDED if final is None else final
    if snapshots is None and not ended:
        snapshots = int(attrs.get("cracklab_checkpoint_snapshots", 0) or 0)
    listed = attrs.get("cracklab_final_arrays")
    finals = list(listed) if isinstance(listed, list) else final_arrays_fallback(stations)
    expected = ["t", "x1", "x3", *fields, *inputs] + (finals if ended else [])
    present = _subdirs(p)
    for name in expected:
        if name not in present:
            rep.damage.append(Damage(str(p / name), f"array {name} is missing", member))
    for name in present:
        if name == CHECKPOINT_GROUP:
            continue
        if not ended and is_final_array(name):
            continue            # rewritten at the end of the run
        adir = p / name
        if not (adir / "zarr.json").exists() and name not in expected:
            rep.damage.append(Damage(str(adir / "zarr.json"), f"array {name}: metadata missing", member))
            continue
        _check_array(adir, name, read=read, t_extent=None if ended else snapshots, report=rep, member=member)
    if report is None:
        if status == "running":
            step = attrs.get("cracklab_checkpoint_step")
            rep.notes.append("the run has not finished (status running: killed, or still running); "
                             + (f"it keeps a checkpoint after step {step}: cracklab run --resume continues it"
                                if step is not None else "no checkpoint: cracklab run --resume starts it over"))
        elif status == "failed":
            rep.notes.append(f"the run failed: {attrs.get('cracklab_error', '?')}")
    return rep


# ---------------------------------------------------------------------------- an ensemble
def check_member(store, mid: str, *, read: bool = True, report: Report | None = None) -> Report:
    """Check one complete member of an ensemble store (its group and run)."""
    p = Path(store) / MEMBERS / mid
    rep = report if report is not None else Report(str(p), "run")
    doc, why = read_json(p / "zarr.json")
    if doc is None:
        rep.damage.append(Damage(str(p / "zarr.json"), f"the member's group metadata is {why}", mid))
        return rep
    return check_run(p, read=read, final=True, member=mid, report=rep)


def check_ensemble(store, *, read: bool = True) -> Report:
    p = Path(store)
    rep = Report(str(p), "ensemble")
    doc, why = read_json(p / "zarr.json")
    if doc is None:
        rep.damage.append(Damage(str(p / "zarr.json"), f"the ensemble's root metadata is {why}"))
        return rep
    listed = (doc.get("attributes", {}) or {}).get("members", [])
    mdoc, why = read_json(p / MEMBERS / "zarr.json")
    if mdoc is None:
        if why != "missing" or _subdirs(p / MEMBERS):
            rep.damage.append(Damage(str(p / MEMBERS / "zarr.json"), f"the members group metadata is {why}"))
    present = _subdirs(p / MEMBERS)
    for mid in present:
        gdoc, why = read_json(p / MEMBERS / mid / "zarr.json")
        if gdoc is None:
            rep.damage.append(Damage(str(p / MEMBERS / mid / "zarr.json"), f"the member's group metadata is {why}",
                                     mid))
            rep.members[mid] = "damaged"
            continue
        attrs = gdoc.get("attributes", {}) or {}
        if attrs.get("complete") is not True:
            rep.members[mid] = str(attrs.get("status", "incomplete"))
            continue
        n = len(rep.damage)
        check_run(p / MEMBERS / mid, read=read, final=True, member=mid, report=rep)
        rep.members[mid] = "sound" if len(rep.damage) == n else "damaged"
    statuses = [v for v in rep.members.values() if v not in ("sound", "damaged")]
    for s in sorted(set(statuses)):
        rep.notes.append(f"{statuses.count(s)} member(s) {s}: not complete, the next sweep runs them again")
    missing = [m for m in listed if m not in present]
    if missing:
        rep.notes.append(f"{len(missing)} planned member(s) not run yet")
    rep.notes = list(dict.fromkeys(rep.notes))
    return rep


def verify(store, *, read: bool = True) -> Report:
    """The ``Report`` of a run or ensemble store (a local path)."""
    from ..errors import StoreError

    p = Path(os.fspath(store)).expanduser()
    if not p.is_dir():
        raise StoreError(p, "does not exist or is not a directory (a Zarr store)")
    doc, why = read_json(p / "zarr.json")
    if doc is None:
        rep = Report(str(p), "run")
        rep.damage.append(Damage(str(p / "zarr.json"), f"the store's root metadata is {why}"))
        return rep
    attrs = doc.get("attributes", {}) or {}
    if "cracklab_ensemble" in attrs:
        return check_ensemble(p, read=read)
    if "scene" in attrs or "cracklab_run_format" in attrs:
        return check_run(p, read=read)
    raise StoreError(p, "is not a cracklab run or ensemble store (no 'scene' or 'cracklab_ensemble' attribute)")


def warn_damaged(path, report, doing) -> None:
    """A StoreWarning that the store at ``path`` is damaged (``report``: its check), and
    what the run does about it (``doing``), attributed to the caller of the run."""
    warnings.warn(StoreWarning(f"store {path} is damaged: {report.first()}; {doing}"), stacklevel=3)
