"""Scenes as data: plain dicts, TOML and xarray Datasets, all lossless.

Three representations, one strict decoder (``scene_from_data``):

* **plain data** (``scene_to_data``): a JSON-able nested dict plus ``{name: array}``
  for the spatial fields; array-valued parameters appear as ``{"array": name}`` and
  non-finite floats as ``{"float": "inf"}``. A run's output stores it as the JSON
  attr ``scene`` plus ``input_<section>_<key>`` variables (``cracklab.scene_of``).
* **TOML** (``scene_to_toml`` / ``scene_from_toml``): the same nested dict with
  the fields inline as nested lists; floats are written repr-exact, ``inf`` as TOML
  ``inf``. A field may instead be a **file reference** ``{ file = "x.nc", var = "tau_c" }``
  (netCDF, Zarr, or ``.npy`` without ``var``), resolved relative to the scene file's
  directory and checked against the grid (``read_field_file``); ``write_scene_toml``
  writes the scalars to a TOML file and every field into one netCDF sidecar next to it.
* **xarray** (``scene_to_dataset`` / ``scene_from_dataset``): every scalar parameter
  is one global attr named ``<section>.<key>`` (``material.mu``, ``law.kind``,
  ``record.stations.<name>``, ``units.length``; the top-level ones are ``t_end``,
  ``beta`` and ``scene``, the scene's name); every array-valued parameter is a data
  variable ``<section>_<key>`` on dims (x1, x3) with the grid's coordinates. See
  docs/reference/scenes.md for the full layout.

Every path validates at the boundary: unknown keys at any level, a string where a
number goes, a float grid size, a list of numbers where booleans go, ... each end in
one ``InputError`` naming the field, before any work starts; the ranges are checked
by the dataclasses themselves (``Scene`` and its parts).
"""
from __future__ import annotations

import dataclasses
import json
import math
import numbers
import os
import re
import uuid
from pathlib import Path

import numpy as np

from ..errors import MAX_NESTING, InputError, check_nesting
from .grid import Grid
from ..laws import LAWS, law_parameters
from .field_files import (describe as describe_reference, is_file_reference, read_field_file, sidecar_path,
                          write_sidecar)
from .units import check_scene_units, input_unit, parameter_kind, unit
from .loading import Loading
from .material import Material
from .record import Record
from .sequence import Sequence

SECTIONS = ("material", "grid", "law", "loading", "record", "numerics", "sequence")
#: sections a scene may leave out (None), written only when present
OPTIONAL_SECTIONS = ("sequence",)
TOP = ("t_end", "beta", "units", "name")
UNIT_KEYS = ("length", "time", "stress")
DEFAULT_UNITS = {"length": "1", "time": "1", "stress": "1"}

# kinds of values, decided from the dataclass annotations (overridable per field)
_BASE_KINDS = {"float": "number", "int": "integer", "bool": "boolean", "str": "string",
               "tuple": "numbers", "dict": "any"}
_OVERRIDES = {
    ("record", "fields"): "strings",
    ("record", "times"): "numbers",
    ("record", "region"): "region",
    ("record", "stations"): "stations",
    ("sequence", "creep"): "mask",
}
_EXPECT = {
    "number": "a number",
    "integer": "an integer",
    "boolean": "a boolean (true or false)",
    "string": "a string",
    "numbers": "a list of numbers",
    "strings": "a list of strings",
    "field": "a number or an (n1, n3) array of numbers, or a file reference {file = ..., var = ...}",
    "mask": "a boolean or an (n1, n3) array of booleans (true/false), or a file reference {file = ..., var = ...}",
}


def section_classes() -> dict:
    """{section: dataclass} of the scene's sections other than the law."""
    from .scene import Numerics

    return {"material": Material, "grid": Grid, "loading": Loading, "record": Record,
            "numerics": Numerics, "sequence": Sequence}


def _kind(section: str, f: dataclasses.Field) -> tuple[str, bool]:
    """(kind, optional) of one dataclass field."""
    ann = str(f.type).replace(" ", "")
    optional = "None" in ann.split("|")
    if (section, f.name) in _OVERRIDES:
        return _OVERRIDES[(section, f.name)], optional
    if section == "law" and f.metadata.get("kind") == "mask":
        return "mask", True
    if "ndarray" in ann:
        return "field", optional
    base = "|".join(p for p in ann.split("|") if p != "None")
    return _BASE_KINDS.get(base, "any"), optional


def section_schema(section: str, cls) -> dict:
    """{field: (kind of value, optional)} of a section's dataclass, from its annotations."""
    return {f.name: _kind(section, f) for f in dataclasses.fields(cls)}


# ---------------------------------------------------------------------------- encode
def _plain(value):
    """numpy scalars -> Python scalars, tuples -> lists (recursively)."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (tuple, list)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    return value


#: keys left out at their default (added after scenes were stored without them: the
#: TOML, attrs and JSON of every scene without the option, and so its digest, stay as they were)
_OMITTED_AT_DEFAULT = {("grid", "free_surface"): False}


def _items(scene):
    """(section, key, value) of every parameter of the scene's parts."""
    for section in SECTIONS:
        obj = getattr(scene, section)
        if obj is None and section in OPTIONAL_SECTIONS:
            continue
        items = law_parameters(obj) if section == "law" else {f.name: getattr(obj, f.name)
                                                               for f in dataclasses.fields(obj)}
        for key, value in items.items():
            if (section, key) in _OMITTED_AT_DEFAULT and value is _OMITTED_AT_DEFAULT[(section, key)]:
                continue
            yield section, key, value


def _two_materials(scene, plain):
    """{"top": {...}, "bottom": {...}} of a scene with two different materials (None with
    one): they are written as the tables materials.top and materials.bottom instead of
    ``material``."""
    top, bottom = scene.materials
    if top == bottom:
        return None
    return {side: {f.name: plain(getattr(m, f.name)) for f in dataclasses.fields(m)}
            for side, m in (("top", top), ("bottom", bottom))}


def _is_array(value) -> bool:
    return isinstance(value, np.ndarray) and value.ndim > 0


def scene_to_data(scene) -> tuple[dict, dict]:
    """Split a scene into a JSON-able dict and {name: array} for its spatial fields.

    Array-valued parameters appear in the dict as {"array": "input_<section>_<key>"},
    non-finite floats as {"float": "inf"}, None values are left out."""
    arrays = {}
    data = {s: {} for s in SECTIONS if s not in OPTIONAL_SECTIONS or getattr(scene, s) is not None}
    data["law"]["kind"] = scene.law.kind
    for section, key, value in _items(scene):
        if value is None:
            continue
        if _is_array(value):
            name = f"input_{section}_{key}"
            arrays[name] = value
            data[section][key] = {"array": name}
            continue
        value = _plain(value)
        if isinstance(value, float) and not math.isfinite(value):
            value = {"float": repr(value)}
        data[section][key] = value
    data.update(t_end=_plain(scene.t_end), beta=_plain(scene.beta), units=dict(scene.units),
                name=scene.name)
    two = _two_materials(scene, _plain)
    if two is not None:
        del data["material"]
        data["materials"] = two
    return data, arrays


def scene_to_json(scene) -> tuple[str, dict]:
    data, arrays = scene_to_data(scene)
    return json.dumps(data, allow_nan=False), arrays


def _toml_text(scene, field) -> str:
    """The scene as TOML text, each array-valued parameter written as ``field(section, key,
    value)`` gives it."""
    import tomli_w

    data = {"name": scene.name, "t_end": _plain(scene.t_end), "beta": _plain(scene.beta),
            "units": dict(scene.units)}
    for section in SECTIONS:
        if section in OPTIONAL_SECTIONS and getattr(scene, section) is None:
            continue
        data[section] = {"kind": scene.law.kind} if section == "law" else {}
    for section, key, value in _items(scene):
        if value is None:
            continue
        data[section][key] = field(section, key, value) if _is_array(value) else _plain(value)
    two = _two_materials(scene, _plain)
    if two is not None:
        del data["material"]
        data["materials"] = two
    return _compact_arrays(tomli_w.dumps(data))


#: a key's array of scalars as tomli_w writes it, one item a line; and a row of a field
_SCALAR_ARRAY = re.compile(r"^([^\n]* = )\[\n((?:    [^\[\]\n]+,\n)+)\]$", re.MULTILINE)
_FIELD_ROW = re.compile(r"^(    )\[\n((?:        [^\[\]\n]+,\n)+)    \](,)$", re.MULTILINE)


def _compact_arrays(text: str, width: int = 100) -> str:
    """Arrays of scalars on one line where it fits in ``width`` (a station's (x1, x3), the
    recorded fields), as a person writes them, and each row of a field (a nested list) on
    a line of its own. Every line of tomli_w's output is structure (its strings escape
    newlines), so an item line is one scalar followed by a comma."""
    def one_line(m, limit=width):
        items = [ln.strip()[:-1] for ln in m.group(2).splitlines()]
        line = f"{m.group(1)}[{', '.join(items)}]" + (m.group(3) if m.re is _FIELD_ROW else "")
        return line if limit is None or len(line) <= limit else m.group(0)

    return _SCALAR_ARRAY.sub(one_line, _FIELD_ROW.sub(lambda m: one_line(m, None), text))


def scene_to_toml(scene) -> str:
    """The scene as TOML text: sections as tables, fields as nested lists, floats
    repr-exact (TOML reads them back bit for bit), inf as TOML ``inf``."""
    return _toml_text(scene, lambda section, key, value: np.asarray(value).tolist())


def _toml_string(text: str) -> str:
    """``text`` as a TOML basic string (quoted and escaped)."""
    import tomli_w

    return tomli_w.dumps({"x": text})[len("x = "):-1]


def _replace_file(path: Path, write) -> None:
    """Call ``write(tmp)`` and move ``tmp`` onto ``path`` (readers never see half a file)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_scene_toml(scene, path) -> Path:
    """Write the scene to the TOML file ``path``: its scalars in the TOML, and every
    array-valued parameter (law fields and masks, the loads) into one netCDF sidecar next
    to it, ``<stem>.fields.nc`` (``field_files.sidecar_path``), each referenced from the TOML
    as ``{ file = "<stem>.fields.nc", var = "<section>_<key>" }``. A scene without arrays
    writes the TOML alone. Both files are replaced whole. Returns ``path``; ``Scene.from_toml
    (path)`` reads the scene back bit for bit (dtypes included)."""
    path = Path(path)
    sidecar = sidecar_path(path)
    token = uuid.uuid4().hex
    fields, refs = {}, {}

    def field(section, key, value):
        name = f"{section}_{key}"
        fields[name] = (section, key, value)
        placeholder = f"{token}:{name}"
        refs[_toml_string(placeholder)] = (f"{{ file = {_toml_string(sidecar.name)}, "
                                           f"var = {_toml_string(name)} }}")
        return placeholder

    text = _toml_text(scene, field)
    for placeholder, ref in refs.items():
        text = text.replace(placeholder, ref)
    head = f"# cracklab scene {scene.name!r} (keys: docs/reference/toml.md)"
    if fields:
        head += f"\n# its fields are in the netCDF file {sidecar.name} next to this one: {', '.join(fields)}"
        write_sidecar(scene, sidecar, fields, path.name)
    _replace_file(path, lambda tmp: tmp.write_text(f"{head}\n{text}", encoding="utf-8"))
    return path


def read_scene_json(text, where: str = "scene") -> dict:
    """The scene of a run's ``scene`` attr (JSON text): a damaged attr (not JSON, nested
    too deeply for the decoder, not a table) is one InputError naming ``where``."""
    if not isinstance(text, str):
        raise InputError(where, f"must be the scene as JSON text, got {type(text).__name__}")
    try:
        data = json.loads(text)
    except (ValueError, RecursionError) as exc:
        reason = "nested too deeply" if isinstance(exc, RecursionError) else str(exc)
        raise InputError(where, f"must be the scene as JSON text (written by cracklab), not valid JSON: "
                                f"{reason}") from None
    if not isinstance(data, dict):
        raise InputError(where, f"must be the scene as a JSON table, got {type(data).__name__}")
    return data


def read_toml_file(path, where: str | None = None) -> dict:
    """``read_toml`` of the file at ``path``; a file that cannot be read (none there, a
    directory, no permission) is one InputError naming ``where`` (default: the path)."""
    where = str(path) if where is None else where
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except FileNotFoundError:
        raise InputError(where, "no such file") from None
    except OSError as exc:
        raise InputError(where, f"cannot be read: {exc.strerror or exc}") from None
    return read_toml(raw, where)


def read_toml(source, where: str = "toml") -> dict:
    """The tables of a TOML document (``source``: text, or the bytes of a file), checked
    for nesting (``check_nesting``). Bytes that are not UTF-8 text (a binary file), malformed
    TOML, and arrays nested too deeply for the parser each end in one InputError naming
    ``where`` (or the field)."""
    import tomllib

    if isinstance(source, (bytes, bytearray, memoryview)):
        try:
            source = bytes(source).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise InputError(where, f"not valid TOML: not UTF-8 text (byte 0x{exc.object[exc.start]:02x} at "
                                    f"offset {exc.start}); the file must be TOML text, not binary") from None
    if not isinstance(source, str):
        raise InputError(where, f"must be TOML text, got {type(source).__name__}")
    try:
        data = tomllib.loads(source)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(where, f"not valid TOML: {exc}") from None
    except RecursionError:
        raise InputError(where, f"not valid TOML: arrays or tables nested too deeply (more than "
                                f"{MAX_NESTING} levels are refused)") from None
    check_nesting(data)
    return data


def looks_like_path(source) -> bool:
    """True for what ``scene_from_toml`` reads as a file name rather than TOML text: a
    path object, or one line ending in ".toml" that is no TOML statement."""
    if isinstance(source, os.PathLike):
        return True
    if not isinstance(source, str):
        return False
    text = source.strip()
    return ("\n" not in text and text.lower().endswith(".toml") and "=" not in text
            and not text.startswith(("[", "#")))


def scene_from_toml_file(path, where: str | None = None, allow=()):
    """The scene of the TOML file at ``path``, its file references resolved relative to
    the file's directory (and read from it and below, or the ``allow`` folders); a file
    that cannot be read is one InputError naming ``where`` (default: the path)."""
    path = Path(path)
    return scene_from_data(read_toml_file(path, where), base=path.absolute().parent, allow=allow)


def scene_from_toml(source, base=None, allow=()):
    """Inverse of ``scene_to_toml`` and ``write_scene_toml``; the same format as ``cracklab
    run SCENE.toml``. ``source``: the TOML text, the bytes of a file, or the path of a file
    (a ``pathlib.Path``, or a one-line string ending in ".toml"). File references are
    resolved relative to the file's directory, or for text to ``base`` (default: the
    current directory)."""
    if looks_like_path(source):
        return scene_from_toml_file(Path(str(source).strip()) if isinstance(source, str) else source,
                                    allow=allow)
    return scene_from_data(read_toml(source, "toml"), base=base, allow=allow)


def _field_attrs(scene, section, key):
    attrs = {"long_name": f"scene parameter {section}.{key}", "units": input_unit(scene, section, key)}
    source = scene.sources.get(f"{section}.{key}")
    if source:
        attrs["source"] = source   # where the field was read (cracklab.model.field_files.source_of)
    return attrs


def scene_attrs(scene) -> dict:
    """The scene's scalar parameters as flat attrs ``<section>.<key>`` (see module doc)."""
    attrs = {"scene": scene.name, "t_end": _plain(scene.t_end), "beta": _plain(scene.beta)}
    for k, v in scene.units.items():
        attrs[f"units.{k}"] = v
    attrs["law.kind"] = scene.law.kind
    for section, key, value in _items(scene):
        if value is None or _is_array(value):
            continue
        value = _plain(value)
        if isinstance(value, bool):
            value = "true" if value else "false"     # netCDF attrs have no booleans
        if (section, key) == ("record", "fields"):
            value = ",".join(value)                  # netCDF-3 attrs have no string lists
        if isinstance(value, dict):
            if not value:
                attrs[f"{section}.{key}"] = []
            for name, v in value.items():
                attrs[f"{section}.{key}.{name}"] = v
        else:
            attrs[f"{section}.{key}"] = value
    return attrs


def scene_to_dataset(scene):
    """The scene as an xarray Dataset: scalar parameters as flat global attrs
    (``material.mu``, ``law.kind``, ...; booleans as the strings "true"/"false",
    ``record.fields`` as one comma-separated string),
    array-valued parameters as variables ``<section>_<key>`` on (x1, x3) with the
    grid's coordinates. Lossless in memory and through Zarr or netCDF."""
    import xarray as xr

    grid, length = scene.grid, scene.units.get("length", "1")
    coords = {
        "x1": ("x1", grid.x1, {"units": length, "long_name": "distance along x1", "axis": "X"}),
        "x3": ("x3", grid.x3, {"units": length, "long_name": "distance along x3", "axis": "Y"}),
    }
    ds = xr.Dataset(coords=coords)
    for section, key, value in _items(scene):
        if _is_array(value):
            ds[f"{section}_{key}"] = (("x1", "x3"), value, _field_attrs(scene, section, key))
    ds.attrs = scene_attrs(scene)
    return ds


# ---------------------------------------------------------------------------- decode
def _fail(path, kind, value):
    shown = repr(value) if not isinstance(value, (list, np.ndarray)) else f"a {type(value).__name__}"
    raise InputError(path, f"must be {_EXPECT.get(kind, kind)}, got {shown}")


def _is_number(v) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))


#: ``scene_from_data(base=NO_FILES)``: file references are refused (the plain data of a run's
#: output holds its fields itself, so that it alone reruns the run)
NO_FILES = "no files"


class _Files:
    """Where a scene's file references are read: the directory relative paths start from
    (None: the current one; NO_FILES: none are read), the grid the fields must fit, and the
    scene's units and law class, which give each field the unit a file's values are
    converted to."""

    def __init__(self, base, grid, units=None, law_class=None, allow=()):
        self.base, self.grid, self.units, self.law_class = base, grid, units or DEFAULT_UNITS, law_class
        self.allow = tuple(allow)
        self.sources: dict = {}   # {field: where it was read}, Scene.sources

    def read(self, path, ref, kind):
        if self.base is NO_FILES:
            raise InputError(path, f"got the file reference {describe_reference(ref)}: files are read only for a "
                                   f"TOML scene (cracklab run, Scene.from_toml); here the field must be given as "
                                   f"an array")
        section, key = path.split(".", 1)
        scene_unit = unit(self.units, parameter_kind(self.law_class, section, key)) if kind == "field" else None
        return read_field_file(path, ref, self.grid, kind, self.base, self.allow, self.sources, unit=scene_unit)


def _coerce(path, kind, value, arrays, files=None):
    """Check the type of one value and bring it into the form the dataclass takes."""
    if is_file_reference(value):
        if kind in ("field", "mask") and files is not None:
            value = files.read(path, value, kind)
        else:
            raise InputError(path, f"must be {_EXPECT.get(kind, kind)}, got the file reference "
                                   f"{describe_reference(value)}: only fields (law parameters of kind field or "
                                   f"mask, loading.tau0_*) are read from files")
    elif isinstance(value, dict) and set(value) == {"array"}:
        name = value["array"]
        if name not in arrays:
            raise InputError(path, f"refers to the array {name!r}, which is not given")
        value = np.asarray(arrays[name])
    elif isinstance(value, dict) and set(value) == {"float"}:
        try:
            value = float(value["float"])
        except (TypeError, ValueError):
            raise InputError(path, f"must be a number, got {value['float']!r}") from None
    if kind == "number":
        if not _is_number(value):
            _fail(path, kind, value)
        return value.item() if isinstance(value, np.generic) else value
    if kind == "integer":
        if not isinstance(value, (int, np.integer)) or isinstance(value, (bool, np.bool_)):
            _fail(path, kind, value)
        return int(value)
    if kind == "boolean":
        if not isinstance(value, (bool, np.bool_)):
            _fail(path, kind, value)
        return bool(value)
    if kind == "string":
        if not isinstance(value, str):
            _fail(path, kind, value)
        return value
    if kind == "strings":
        if isinstance(value, str):
            return (value,)
        if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
            _fail(path, kind, value)
        return tuple(value)
    if kind == "numbers":
        if not isinstance(value, (list, tuple, np.ndarray)) or not all(_is_number(v) for v in value):
            _fail(path, kind, value)
        return tuple(v.item() if isinstance(v, np.generic) else v for v in value)
    if kind in ("field", "mask"):
        if kind == "field" and _is_number(value):
            return value.item() if isinstance(value, np.generic) else value
        if kind == "mask" and isinstance(value, (bool, np.bool_)):
            return bool(value)
        if isinstance(value, (list, tuple, np.ndarray)):
            try:
                arr = np.array(value)
            except ValueError:
                arr = None
            if arr is not None and arr.dtype != object and arr.size > 0:
                ok = arr.dtype.kind in "fiu" if kind == "field" else arr.dtype == bool
                if ok:
                    return arr.astype(float) if arr.dtype.kind in "iu" else arr
        _fail(path, kind, value)
    if kind == "region":
        if not isinstance(value, dict):
            raise InputError(path, "must be a table {x1 = [lo, hi], x3 = [lo, hi]}")
        out = {}
        for key, bounds in value.items():
            if key not in ("x1", "x3"):
                raise InputError(f"{path}.{key}", "unknown key; accepted: x1, x3")
            b = _coerce(f"{path}.{key}", "numbers", bounds, arrays)
            if len(b) != 2 or not b[0] <= b[1]:
                raise InputError(f"{path}.{key}", f"must be [lo, hi] with lo <= hi, got {list(b)}")
            out[key] = b
        return out
    if kind == "stations":
        if not isinstance(value, dict):
            raise InputError(path, "must be a table {name = [x1, x3]}")
        out = {}
        for name, xy in value.items():
            p = _coerce(f"{path}.{name}", "numbers", xy, arrays)
            if len(p) not in (1, 2):
                raise InputError(f"{path}.{name}", f"must be [x1, x3] (or [x1] in 2D), got {list(p)}")
            out[str(name)] = p
        return out
    return value


def _build(section, cls, d, arrays, schema=None, files=None):
    if d is None:
        d = {}
    if not isinstance(d, dict):
        raise InputError(section, f"must be a table of parameters, got {d!r}")
    schema = schema or section_schema(section, cls)
    kwargs = {}
    for key, value in d.items():
        if key not in schema:
            raise InputError(f"{section}.{key}", f"unknown key; accepted: {', '.join(sorted(schema))}")
        kind, optional = schema[key]
        if value is None:
            if not optional:
                raise InputError(f"{section}.{key}", f"must be {_EXPECT.get(kind, kind)}, got None")
            kwargs[key] = None
            continue
        kwargs[key] = _coerce(f"{section}.{key}", kind, value, arrays, files)
    missing = [f.name for f in dataclasses.fields(cls)
               if f.name not in kwargs and f.default is dataclasses.MISSING
               and f.default_factory is dataclasses.MISSING]
    if missing:
        raise InputError(f"{section}.{missing[0]}", "is required")
    try:
        return cls(**kwargs)
    except TypeError as exc:
        raise InputError(section, str(exc)) from None


def scene_from_data(data: dict, arrays: dict | None = None, *, base=NO_FILES, allow=()):
    """A Scene from the nested dict of ``scene_to_data`` / TOML; strict: unknown keys,
    wrong types and out-of-range values raise one InputError naming the field. File
    references ``{file = ..., var = ...}`` of fields are read relative to ``base`` (a
    directory; None: the current one), from that folder and below or the ``allow``
    folders (cracklab.model.field_files), and checked against the grid; by default
    (``NO_FILES``) they are refused. Where each was read is kept in ``Scene.sources``."""
    from .scene import Scene

    arrays = arrays or {}
    if not isinstance(data, dict):
        raise InputError("scene", f"must be a table, got {type(data).__name__}")
    check_nesting(data)
    allowed = set(SECTIONS) | set(TOP) | {"materials"}
    for key in data:
        if key not in allowed:
            raise InputError(key, f"unknown key; accepted: {', '.join(sorted(allowed))}")
    units = _units(data["units"]) if "units" in data else None   # a stray key there is named first
    law_data = data.get("law")
    if not isinstance(law_data, dict) or "kind" not in law_data:
        raise InputError("law.kind", f"is required; accepted: {', '.join(sorted(LAWS))}")
    law_data = dict(law_data)
    kind = law_data.pop("kind")
    if not isinstance(kind, str) or kind not in LAWS:
        raise InputError("law.kind", f"must be one of {', '.join(sorted(LAWS))}, got {kind!r}")
    for required in ("material", "grid", "t_end"):
        if required not in data and not (required == "material" and "materials" in data):
            raise InputError(required, "is required (or, for the material, the tables materials.top and "
                                       "materials.bottom)" if required == "material" else "is required")
    classes = section_classes()
    parts = {s: _build(s, classes[s], data.get(s), arrays) for s in ("grid",) + (("material",) * ("material" in data))}
    if "materials" in data:
        parts["materials"] = _materials(data["materials"], arrays)
    files = _Files(base, parts["grid"], units, LAWS[kind], allow)
    parts["law"] = _build("law", LAWS[kind], law_data, arrays, files=files)
    for s in ("loading", "record", "numerics"):
        parts[s] = _build(s, classes[s], data.get(s), arrays, files=files if s == "loading" else None)
    for s in OPTIONAL_SECTIONS:
        if s in data:
            parts[s] = _build(s, classes[s], data[s], arrays, files=files)
    top = {"t_end": _coerce("t_end", "number", data["t_end"], arrays)}
    if "beta" in data:
        top["beta"] = _coerce("beta", "number", data["beta"], arrays)
    if "name" in data:
        top["name"] = _coerce("name", "string", data["name"], arrays)
    if units is not None:
        top["units"] = units
    return Scene(**parts, **top, sources=dict(files.sources))


def _materials(d, arrays) -> tuple:
    """(top, bottom) of a ``[materials.top]`` / ``[materials.bottom]`` pair of tables."""
    if not isinstance(d, dict) or set(d) != {"top", "bottom"}:
        got = sorted(d) if isinstance(d, dict) else repr(d)
        raise InputError("materials", f"must be the two tables materials.top (x2 > 0) and materials.bottom "
                                      f"(x2 < 0), each with mu, cs and nu, got {got}")
    out = []
    for side in ("top", "bottom"):
        name = f"materials.{side}"
        try:
            out.append(_build(name, Material, d[side], arrays, schema=section_schema("material", Material)))
        except InputError as exc:  # Material names its fields material.<key>
            field = exc.field.replace("material", name, 1) if exc.field.startswith("material") else exc.field
            raise InputError(field, str(exc).split(": ", 1)[1]) from None
    return tuple(out)


def _units(units) -> dict:
    if not isinstance(units, dict):
        raise InputError("units", f"must be a table {{{', '.join(UNIT_KEYS)}}}, got {units!r}")
    for key, value in units.items():
        if key not in UNIT_KEYS:
            raise InputError(f"units.{key}", f"unknown key; accepted: {', '.join(UNIT_KEYS)}")
        if not isinstance(value, str):
            raise InputError(f"units.{key}", f"must be a string, got {value!r}")
    for key in UNIT_KEYS:
        if key not in units:
            raise InputError(f"units.{key}", f"is required when units are given ({', '.join(UNIT_KEYS)})")
    check_scene_units(units)
    return dict(units)


def _from_attr(value):
    """Undo what netCDF / Zarr do to attrs: numpy arrays and scalars -> Python."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def _field_vars(ds):
    """{(section, key): values} of the array-valued parameters held by ``ds``:
    ``<section>_<key>`` on (x1, x3), or ``input_<section>_<key>`` on (input_x1, input_x3)."""
    out = {}
    for name in ds.data_vars:
        stem = name[len("input_"):] if name.startswith("input_") else name
        section, _, key = stem.partition("_")
        if section not in ("law", "loading") + OPTIONAL_SECTIONS or not key:
            continue
        var = ds[name]
        prefix = "input_" if name.startswith("input_") else ""
        dims = (f"{prefix}x1", f"{prefix}x3")
        if set(var.dims) != set(dims):
            raise InputError(f"{section}.{key}", f"variable {name!r} must be on dims {dims}, got {var.dims}")
        if (section, key) in out:
            raise InputError(f"{section}.{key}", "is given twice (as law_/loading_ and input_ variables)")
        out[(section, key)] = np.asarray(var.transpose(*dims).values)
    return out


def scene_from_dataset(ds):
    """Inverse of ``scene_to_dataset``; also reads the scene of a run's output
    (``cracklab.simulate``), i.e. ``scene_from_dataset(result) == scene_of(result)``."""
    attrs = dict(ds.attrs)
    fields = _field_vars(ds)
    legacy = attrs.get("scene")
    if isinstance(legacy, str) and legacy.lstrip().startswith("{"):
        data = read_scene_json(legacy)
        arrays = {f"input_{s}_{k}": v for (s, k), v in fields.items()}
        return scene_from_data(data, arrays)
    data: dict = {}
    for key, value in attrs.items():
        head, dot, rest = key.partition(".")
        value = _from_attr(value)
        if key in ("t_end", "beta"):
            data[key] = value
        elif key == "scene":
            data["name"] = value
        elif dot and head == "units":
            data.setdefault("units", {})[rest] = value
        elif dot and head in SECTIONS:
            section = data.setdefault(head, {})
            sub, dot2, name = rest.partition(".")
            if head == "record" and sub in ("stations", "region"):
                table = section.setdefault(sub, {})
                if dot2:
                    table[name] = value
                elif value not in ([], "", None):
                    raise InputError(f"record.{sub}", f"must be a table, got {value!r}")
            else:
                section[rest] = value
    for (section, key), values in fields.items():
        if key in data.get(section, {}):
            raise InputError(f"{section}.{key}", "is given twice (as an attr and as a variable)")
        data.setdefault(section, {})[key] = values
    _restore_attr_types(data)
    return scene_from_data(data)


def _restore_attr_types(data):
    """Booleans were stored as "true"/"false" and one-element lists may come back as
    scalars from netCDF: restore them where the schema says so (attrs path only)."""
    classes = section_classes()
    for section, d in data.items():
        if section not in SECTIONS or not isinstance(d, dict):
            continue
        if section == "law":
            kind = d.get("kind")
            cls = LAWS.get(kind) if isinstance(kind, str) else None
            if cls is None:
                continue
        else:
            cls = classes[section]
        schema = section_schema(section, cls)
        for key, value in list(d.items()):
            kind = schema.get(key, ("any", False))[0]
            if kind in ("boolean", "mask") and isinstance(value, str) and value in ("true", "false"):
                d[key] = value == "true"
            elif kind == "strings" and isinstance(value, str):
                d[key] = [v for v in value.split(",") if v]
            elif kind == "numbers" and _is_number(value):
                d[key] = [value]
            elif kind in ("stations", "region") and isinstance(value, dict):
                d[key] = {k: [v] if _is_number(v) else v for k, v in value.items()}


# ---------------------------------------------------------------------------- comparison
def _same(a, b) -> bool:
    if type(a) is not type(b):
        return False
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and a.shape == b.shape and bool(np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))
    if isinstance(a, float):
        return a == b or (a != a and b != b)
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, dict):
        return list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    if dataclasses.is_dataclass(a):
        return all(_same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a) if f.compare)
    return a == b


def scenes_equal(a, b) -> bool:
    """True when two scenes are identical: same parameter types, bit-identical floats
    and arrays (dtype included). ``Scene.__eq__`` cannot compare array fields."""
    return _same(a, b)
