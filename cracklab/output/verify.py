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
  older cracklab) are noted: a flipped byte there can go unnoticed;
* the metadata readers see matches what is stored: the consolidated metadata (what plain
  xarray reads) lists the groups and arrays present with their own metadata; the scene
  (attr and input arrays) matches ``cracklab_scene_digest``; every array's shape, data
  type and units are those the scene gives. Each mismatch names its remedy.

An ensemble store is checked member by member (the complete ones; the others are rerun
by the next sweep anyway), and its root's consolidated metadata against the members
present; a member's parameters and the member table are checked by
``cracklab.ensemble.verify``, which ``cracklab verify`` runs. ``check_run`` and
``check_ensemble`` return a ``Report``; reading every chunk costs about as much as
loading the store once (``read=False`` checks the metadata and the chunk listing only).
"""
from __future__ import annotations

import contextlib
import json
import math
import os
import warnings
from dataclasses import dataclass, field
from itertools import product
from pathlib import Path

import numpy as np

from ..errors import StoreWarning
from .checkpoint import is_final_array, scene_digest
from .stores import is_url, zarr_of

CHECKSUM_CODEC = "crc32c"
SCENE_CHANGED = "the run's scene"      # how a scene that is not the run's own is named
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
    remedy: str | None = None  # what repairs it (a metadata mismatch), shown in its line

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
            if any(d.member is None and d.remedy is None for d in self.damage):
                return ("rerun the sweep (cracklab sweep STUDY.toml -o STORE) to repair the store's groups; "
                        "if the root zarr.json is damaged, restore it or delete the store and run the sweep again")
            if any(d.member is None for d in self.damage):
                return ("rerun the sweep (cracklab sweep STUDY.toml -o STORE): it runs the damaged and missing members "
                        "and rewrites the member table and the consolidated metadata")
            return ("rerun the sweep (cracklab sweep STUDY.toml -o STORE): it recomputes the damaged members "
                    "(--no-resume recomputes every member)")
        if is_url(self.store):
            return ("run it again from its scene file: cracklab run SCENE.toml -o STORE (a damaged store at a URL is "
                    "run again from the start and replaced)")
        if any(d.what.startswith(SCENE_CHANGED) for d in self.damage):
            return ("run it again from its scene file with --resume, which recomputes a damaged store: cracklab run "
                    "SCENE.toml -o STORE --resume (not the store itself: its scene was changed)")
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
            out.append(f"  DAMAGED {who}{d}" + (f"; remedy: {d.remedy}" if d.remedy else ""))
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


# ---------------------------------------------------------------------------- where
def root_of(store):
    """The tree of ``store`` as given: an ``objectstore.StoredTree`` as is, anything else
    as a local ``Path``."""
    return store if hasattr(store, "subdirs") else Path(os.fspath(store)).expanduser()


def store_tree(store, members=None):
    """The read-only view of ``store`` the checks read: a local ``Path``, or for a URL an
    ``objectstore.StoredTree`` (the URL checked first: ``Store.check``, a StoreError naming
    it). ``members``: the ids of the only members to list (with the root's metadata and
    the sweep lock), for the check of a few members of a large store at a URL."""
    from .objectstore import StoredTree
    from .stores import store_for

    if hasattr(store, "subdirs"):
        return store
    if not is_url(store):
        return Path(os.fspath(store)).expanduser()
    url = os.fspath(store).rstrip("/")
    fs, path = store_for(url).check(exists=True)
    if members is None:
        return StoredTree(fs, path, url)
    return StoredTree.listing(fs, path, url, [f"{MEMBERS}/{m}" for m in members])


def _zarr(p):
    """What zarr opens for the node at ``p`` (a local path, or a StoredTree: its URL
    through its ``Store.zarr_store``, no listings cache: ``stores.zarr_of``)."""
    url = getattr(p, "url", None)
    return zarr_of(url) if url is not None else str(p)


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
    if hasattr(path, "subdirs"):        # a store at a URL (objectstore.StoredTree)
        return [n for n in path.subdirs() if not n.startswith(".")]
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
        arr = zarr.open_array(store=_zarr(adir), mode="r")
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


# ---------------------------------------------------------------------------- what readers see
def run_remedy(store) -> str:
    """What repairs a run store whose metadata no longer matches its data."""
    if is_url(store):
        return f"cracklab run SCENE.toml -o {store} writes the run again"
    return f"cracklab run SCENE.toml -o {store} --resume recomputes the run"


def member_remedy(store) -> str:
    """What repairs an ensemble member whose metadata no longer matches its data."""
    return f"cracklab sweep STUDY.toml -o {store} recomputes the member"


def store_remedy(store) -> str:
    """What repairs the root of an ensemble store (its member table, its consolidated metadata)."""
    return (f"cracklab sweep STUDY.toml -o {store} runs the members that are not there and rewrites the member "
            f"table and the consolidated metadata")


def add(report: Report, damage: Damage) -> None:
    """Add ``damage`` unless its file is named already (one line per file)."""
    if not any(d.path == damage.path for d in report.damage):
        report.damage.append(damage)


def _nodes(p: Path, prefix: str = "") -> dict:
    """{path below ``p``: its zarr.json document, None when unreadable} of the groups and
    arrays stored below the group at ``p`` (hidden entries and checkpoints left out)."""
    out = {}
    for name in _subdirs(p):
        if name == CHECKPOINT_GROUP or not (p / name / "zarr.json").exists():
            continue
        doc, _ = read_json(p / name / "zarr.json")
        out[prefix + name] = doc
        if doc is not None and doc.get("node_type") == "group":
            out.update(_nodes(p / name, f"{prefix}{name}/"))
    return out


def _differences(own: dict, copy) -> list[str]:
    """The keys (``attribute scene`` for an attribute) in which a node's own metadata and
    its consolidated copy differ."""
    if not isinstance(copy, dict):
        return ["all"]
    out = []
    for key in sorted(set(own) | set(copy)):
        if key == "consolidated_metadata" or own.get(key) == copy.get(key):
            continue
        a, b = own.get(key), copy.get(key)
        if key == "attributes" and isinstance(a, dict) and isinstance(b, dict):
            out += [f"attribute {k}" for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
        else:
            out.append(key)
    return out


def check_consolidated(p: Path, doc: dict, report: Report, remedy: str, member=None) -> None:
    """The consolidated metadata in ``doc`` (the zarr.json of the group at ``p``), which plain
    xarray reads instead of each node's own, against the groups and arrays stored: every
    node it lists is there with the same metadata, and every node there is listed.
    ``member``: the member id a node's damage is reported under (a function of its path)."""
    cm = doc.get("consolidated_metadata")
    listed = cm.get("metadata") if isinstance(cm, dict) else None
    if not isinstance(listed, dict):
        return
    who = member if callable(member) else (lambda key: member)
    root = p / "zarr.json"
    stored = _nodes(p)
    for key, copy in listed.items():
        parts = key.split("/")
        if CHECKPOINT_GROUP in parts or any(x.startswith(".") for x in parts):
            continue
        if key not in stored:
            parent = key.rpartition("/")[0]
            if (p / key).exists() or (parent in listed and not (p / parent).exists()):
                continue        # its metadata is damaged (named by the array checks), or its group is gone
            add(report, Damage(str(p / key), f"listed in the consolidated metadata of {root} but not in the store: "
                                             f"plain xarray (xr.open_zarr, xr.open_datatree) reads it as fill "
                                             f"values (NaN)", who(key), remedy))
        elif stored[key] is not None and (diff := _differences(stored[key], copy)):
            add(report, Damage(str(p / key / "zarr.json"), f"differs from its copy in the consolidated metadata of "
                                                           f"{root} ({', '.join(diff)}): changed after the store "
                                                           f"was written; plain xarray reads the copy",
                               who(key), remedy))
    for key in stored:
        parent = key.rpartition("/")[0]
        if key not in listed and not (parent in stored and parent not in listed):     # a group: named once
            add(report, Damage(str(p / key / "zarr.json"), f"not in the consolidated metadata of {root}: plain "
                                                           f"xarray does not see it", who(key), remedy))


def stored_inputs(p: Path, names) -> dict | None:
    """The scene input arrays stored in ``p`` (None when one cannot be read: named elsewhere)."""
    import zarr

    out = {}
    for name in names:
        try:
            out[name] = np.asarray(zarr.open_array(store=_zarr(p / name), mode="r")[...])
        except Exception:  # noqa: BLE001 - missing or damaged: the array checks name it
            return None
    return out


def _expected(scene, names) -> tuple[dict, dict, set]:
    """({dimension: size}, {array: units}, arrays written as float64) of the run of
    ``scene`` (dimension sizes of t and t_station are upper bounds for a failed run)."""
    from .attrs import field_attrs, input_attrs

    grid, record, u = scene.grid, scene.record, scene.units
    s1, s3 = record.region_slices(grid)
    sizes = {"x1": len(grid.x1[s1]), "x3": len(grid.x3[s3])}
    if scene.sequence is None:
        sizes["t"] = int(np.asarray(record.snapshot_steps(scene.nsteps, scene.dt)).size) if record.fields else 0
        if record.stations:
            sizes["station"] = len(record.station_nodes(grid))
            sizes["t_station"] = scene.nsteps + 1
    units, floats = {}, set()
    for name in names:
        field = name[len("station_"):] if name.startswith("station_") else name
        if name in ("t", "t_station", "rupture_time"):
            units[name] = u["time"]
        elif name in ("x1", "x3", "station_x1", "station_x3"):
            units[name] = u["length"]
        elif name.startswith("input_"):
            with contextlib.suppress(Exception):
                units[name] = input_attrs(scene, name)["units"]
            continue
        elif field in record.fields or (name.startswith("station_") and field.split("_")[0] in
                                         ("delta", "v", "tau", "strength")):
            try:
                units[name] = field_attrs(scene, field)["units"]
            except (KeyError, ValueError, AttributeError):
                continue
        else:
            continue
        floats.add(name)
    return sizes, units, floats


def _check_scene(p: Path, attrs: dict, inputs, names, status, report: Report, member, remedy) -> None:
    """What the run's ``scene`` attribute says against what is stored: the scene (attr and
    input arrays) against the digest written with the run, then the shape, data type and
    units of every array against those the scene gives."""
    arrays = stored_inputs(p, inputs)
    if arrays is None:
        return
    digest = attrs.get("cracklab_scene_digest")
    if isinstance(digest, str) and scene_digest(attrs["scene"], arrays) != digest:
        add(report, Damage(str(p / "zarr.json"), f"{SCENE_CHANGED} (its 'scene' attribute and input arrays) does not "
                                                 f"match the digest cracklab_scene_digest written with the run: "
                                                 f"changed after the run", member, remedy))
        return
    try:
        from ..model.scene_io import read_scene_json, scene_from_data

        scene = scene_from_data(read_scene_json(attrs["scene"]), arrays)
        sizes, units, floats = _expected(scene, names)
    except Exception:  # noqa: BLE001 - a scene this cracklab cannot build: its digest is what is checked
        return
    docs = {name: read_json(p / name / "zarr.json")[0] for name in names}
    docs = {k: v for k, v in docs.items() if v is not None and v.get("node_type", "array") == "array"}
    coords = {k: v["shape"][0] for k, v in docs.items()
              if v.get("dimension_names") == [k] and isinstance(v.get("shape"), list) and len(v["shape"]) == 1}
    at_most = status == "failed"
    for name, doc in docs.items():
        meta = str(p / name / "zarr.json")
        shape, dims = doc.get("shape"), doc.get("dimension_names")
        if isinstance(shape, list) and isinstance(dims, list) and len(shape) == len(dims):
            for n, dim in zip(shape, dims):
                want = sizes.get(dim)
                if want is not None and (n > want if at_most and dim in ("t", "t_station") else n != want):
                    add(report, Damage(meta, f"array {name} has shape {tuple(shape)} along {tuple(dims)}, but the "
                                             f"run's scene gives {dim} = {'at most ' if at_most else ''}{want}: its "
                                             f"metadata was changed after the run", member, remedy))
                    break
                if status in ENDED and dim in coords and n != coords[dim]:
                    add(report, Damage(meta, f"array {name} has shape {tuple(shape)} along {tuple(dims)}, but its "
                                             f"coordinate {dim} has {coords[dim]} values: its metadata was changed "
                                             f"after the run", member, remedy))
                    break
        if name in floats and doc.get("data_type") != "float64":
            add(report, Damage(meta, f"array {name} has data type {doc.get('data_type')!r}, but cracklab writes it as "
                                     f"float64 (its chunks hold float64): its metadata was changed after the run",
                               member, remedy))
        if name in units:
            got = (doc.get("attributes") or {}).get("units")
            if got != units[name]:
                add(report, Damage(meta, f"variable {name} has units {got!r}, but the run's scene gives "
                                         f"{units[name]!r}: its metadata was changed after the run", member, remedy))


# ---------------------------------------------------------------------------- a run
def check_run(path, *, read: bool = True, snapshots: int | None = None, final: bool | None = None,
              member: str | None = None, report: Report | None = None) -> Report:
    """Check the run store at ``path`` (a local directory, or an ``objectstore.StoredTree``).

    ``snapshots``: how many snapshots must be written (default: all, for a run that
    ended; those up to its checkpoint for a running one); ``final``: whether the
    end-of-run arrays must be there (default: when ``cracklab_status`` is complete or
    failed). ``member``: the ensemble member id the damage is reported under."""
    p = path if hasattr(path, "subdirs") else Path(path)      # a local path, or a StoredTree (a URL)
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
    remedy = member_remedy(p.parent.parent) if member else run_remedy(p)
    if expect is not None:
        checked = [n for n in present if n != CHECKPOINT_GROUP and (ended or not is_final_array(n))]
        _check_scene(p, attrs, inputs, checked, status if ended else "running", rep, member, remedy)
    check_consolidated(p, doc, rep, remedy, member)
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
    """Check one complete member of an ensemble store (its group and run); ``store``: a
    local path or a tree (``store_tree``)."""
    p = root_of(store) / MEMBERS / mid
    rep = report if report is not None else Report(str(p), "run")
    doc, why = read_json(p / "zarr.json")
    if doc is None:
        rep.damage.append(Damage(str(p / "zarr.json"), f"the member's group metadata is {why}", mid))
        return rep
    return check_run(p, read=read, final=True, member=mid, report=rep)


def check_ensemble(store, *, read: bool = True) -> Report:
    """Check an ensemble store (a local path or a tree, ``store_tree``): each complete
    member, and the root's consolidated metadata against the members present."""
    p = root_of(store)
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
    members_of = {f"{MEMBERS}/{m}": m for m in present}

    def owner(key):
        return members_of.get("/".join(key.split("/")[:2]))

    check_consolidated(p, doc, rep, store_remedy(p), owner)
    for d in rep.damage:
        if rep.members.get(d.member) == "sound":
            rep.members[d.member] = "damaged"
    statuses = [v for v in rep.members.values() if v not in ("sound", "damaged")]
    for s in sorted(set(statuses)):
        rep.notes.append(f"{statuses.count(s)} member(s) {s}: not complete, the next sweep runs them again")
    missing = [m for m in listed if m not in present]
    if missing:
        rep.notes.append(f"{len(missing)} planned member(s) not run yet")
    rep.notes = list(dict.fromkeys(rep.notes))
    return rep


def verify(store, *, read: bool = True) -> Report:
    """The ``Report`` of a run or ensemble store: a local path, or a URL
    (``s3://bucket/ens.zarr``; its keys listed once, every chunk read over the network;
    checked first by its ``Store.check``), or its tree (``store_tree``)."""
    from ..errors import StoreError

    if hasattr(store, "subdirs") or is_url(store):
        p = store_tree(store)
    else:
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
