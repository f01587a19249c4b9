"""Ensembles: parameter sweeps run on dask.distributed into one Zarr v3 store.

A sweep turns one base (a ``Scene``, or a scene builder with its base arguments) into
members: the Cartesian product of the ``product`` axes, plus explicit ``members``, each
optionally repeated ``replicates`` times with its own random seed. Parameter names are

* builder arguments (``diameter``, ``contrast``, ``n1``, ...): any keyword the builder
  accepts; ``builder`` itself may be a member parameter (another builder for that member);
* scene paths: ``<section>.<key>`` with section one of material, grid, law, loading,
  record, numerics (``law.tau_c``, ``loading.tau0_2``, ``record.every``), or the top-level
  ``t_end``, ``beta``, ``name`` when the builder does not take them itself. They are
  applied to the built scene with ``dataclasses.replace`` (so they are validated).

Every member has an id: the first 16 hex digits of the SHA-256 of the canonical JSON
(sorted keys, no whitespace) of its resolved parameters and its base; the id does not
depend on the order in which parameters are given and is the same in every run.

Store layout (one Zarr v3 store)::

    STORE.zarr/                  root group, attrs: cracklab_ensemble (format), study, members
      members/
        <id>/                    what ``cracklab.simulate(scene, store=...)`` writes, plus attrs
                                 member_id, member_params (JSON), member_swept (JSON),
                                 status (running | complete | failed | damaged), elapsed_s,
                                 worker, error and traceback (failed), and complete (true,
                                 written last)

Workers write their member group directly; only a small status record goes back to
the client. A rerun verifies the members whose group says ``complete`` (``cracklab.output.verify``),
skips the sound ones and redoes the others, damaged ones included. A complete member
that is run again is written to a hidden sibling group and swapped in whole.

See docs/ensembles.md for the STUDY.toml format and examples.
"""
from __future__ import annotations

import contextlib
import dataclasses
import errno
import functools
import hashlib
import inspect
import itertools
import json
import math
import os
import shutil
import socket
import sys
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError, StoreError

FORMAT = 1
MEMBERS = "members"
SECTIONS = ("material", "grid", "law", "loading", "record", "numerics")
TOP_LEVEL = ("t_end", "beta", "name")
ID_LENGTH = 16
SEED_BITS = 53          # seeds fit exactly in float64, int64 and JSON numbers

__all__ = ["Builder", "Sweep", "Study", "Member", "SweepResult", "load_study", "plan", "run",
           "run_study", "open_ensemble", "open_member", "member_status", "member_scene",
           "build_scene", "is_ensemble", "store_kind", "coordinate_name", "export_netcdf", "store_lock",
           "StoreLocked", "register_builder", "unregister_builder", "registered_builders",
           "resolve_builder", "ENTRY_POINT_GROUP"]


# ---------------------------------------------------------------------------- specification
class Builder:
    """A scene builder and its base arguments: ``Builder("asperity_row", n1=128, n3=64)``.

    ``builder``: the name of a registered builder (one of cracklab's own, ``scenes.BUILDERS``,
    one registered with ``register_builder``, or an entry point of the group
    "cracklab.builders"), or a function (registered under its name, "module:qualname",
    unless it is registered already)."""

    def __init__(self, builder, **args):
        self.name = builder_name(builder)
        self.args = args
        self.func = resolve_builder(self.name)

    def __repr__(self):
        return f"Builder({self.name!r}, **{self.args!r})"


@dataclass
class Sweep:
    """Members of an ensemble: the Cartesian product of ``product`` ({name: [values]}),
    then the explicit ``members`` (each a {name: value} dict), each ``replicates`` times.

    ``entropy``: root of one ``numpy.random.SeedSequence``; every member whose builder
    accepts ``seed_arg`` and does not set it gets ``seed`` = a 53-bit integer from the
    child ``SeedSequence(entropy, spawn_key=(hash of its builder and swept parameters,
    replicate))``, i.e. independent, reproducible streams that do not depend on member
    order nor on the base parameters (a longer t_end keeps the same random field)."""

    product: dict = field(default_factory=dict)
    members: list = field(default_factory=list)
    entropy: int | None = None
    replicates: int = 1
    seed_arg: str = "seed"
    base: dict = field(default_factory=dict)   # extra base parameters (merged over the Builder's)


@dataclass
class Study:
    """What a STUDY.toml holds: a base (Builder or Scene), a Sweep and a name."""

    base: object
    sweep: Sweep
    name: str = "study"
    spec: dict = field(default_factory=dict)    # the TOML tables, kept in the store's attrs


@dataclass(frozen=True)
class Member:
    index: int
    id: str
    params: dict          # resolved parameters (canonical, JSON-able)
    swept: tuple          # names of the parameters that vary by sweep (coordinates)


@dataclass
class SweepResult:
    store: str
    members: list
    ran: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    failed: dict = field(default_factory=dict)      # id -> error line
    elapsed: float = 0.0
    damaged: dict = field(default_factory=dict)     # id -> damage found in a complete member (run again)

    @property
    def ok(self) -> bool:
        return not self.failed

    def summary(self) -> str:
        lines = [f"{len(self.members)} members: {len(self.ran) - len(self.failed)} ran, "
                 f"{len(self.skipped)} already complete, {len(self.failed)} failed "
                 f"({self.elapsed:.1f} s) -> {self.store}"]
        by_id = {m.id: m for m in self.members}
        for mid, err in self.failed.items():
            m = by_id.get(mid)
            shown = ", ".join(f"{k}={m.params[k]!r}" for k in m.swept) if m else ""
            lines.append(f"  FAILED {mid} ({shown}): {err}")
        for mid, problem in self.damaged.items():
            lines.append(f"  DAMAGED {mid} (was complete; run again): {problem}")
        return "\n".join(lines)


# ---------------------------------------------------------------------------- builders
ENTRY_POINT_GROUP = "cracklab.builders"
_REGISTERED: dict = {}          # name -> function, from register_builder
_ENTRY_POINT_CACHE: dict = {}   # (name, entry point value) -> loaded function


def _own_builders() -> dict:
    """cracklab's own builders: the functions of cracklab.scenes listed in scenes.BUILDERS."""
    from .. import scenes

    return {name: getattr(scenes, name) for name in scenes.BUILDERS}


def _entry_points() -> dict:
    """{name: entry point} of the group "cracklab.builders" (installed packages)."""
    from importlib.metadata import entry_points

    try:
        eps = entry_points(group=ENTRY_POINT_GROUP)
    except Exception:  # noqa: BLE001 - broken package metadata: no entry-point builders
        return {}
    return {ep.name: ep for ep in eps}


def _same_function(a, b) -> bool:
    """The same function, or the same module-level name (a module reloaded, a notebook cell
    run again)."""
    if a is b:
        return True
    key = (getattr(a, "__module__", None), getattr(a, "__qualname__", None))
    return None not in key and "<" not in key[1] and \
        key == (getattr(b, "__module__", None), getattr(b, "__qualname__", None))


def register_builder(name, func=None, *, replace=False):
    """Let study files and sweeps name the scene builder ``func`` as ``name``.

    ``func(**arguments)`` must return a ``cracklab.Scene``. ``name`` is any non-empty
    string other than the names of cracklab's own builders (``scenes.BUILDERS``), e.g.
    ``"my_crack"`` or ``"mypackage.scenes:my_crack"``. Registering another function
    under a name already taken needs ``replace=True``. Without ``func`` this is a
    decorator: ``@cracklab.register_builder("my_crack")``. Returns ``func``.

    A study file can name only registered builders: cracklab's own, those registered
    here, and those of installed packages under the entry-point group
    ``"cracklab.builders"`` (see docs/ensembles.md); it never imports a module itself.
    The function object goes to the workers with each task (by reference when it is
    importable there, else by value), so the workers need no registration."""
    if func is None:
        return functools.partial(register_builder, name, replace=replace)
    if not isinstance(name, str) or not name.strip():
        raise InputError("builder", f"a builder name must be a non-empty string, got {name!r}")
    if not callable(func):
        raise InputError("builder", f"{name!r}: a builder must be a function returning a Scene, got {func!r}")
    if name in _own_builders():
        raise InputError("builder", f"{name!r} is one of cracklab's own builders; register yours under "
                                    f"another name")
    old = _REGISTERED.get(name)
    if old is not None and not replace and not _same_function(old, func):
        raise InputError("builder", f"{name!r} is already registered to {_describe(old)}; pass replace=True "
                                    f"to register {_describe(func)} instead")
    _REGISTERED[name] = func
    return func


def unregister_builder(name) -> None:
    """Forget a builder registered with ``register_builder`` (no error when there is none)."""
    _REGISTERED.pop(name, None)


def registered_builders() -> dict:
    """{name: where it comes from} of every builder a study may name: "cracklab" (its own,
    ``scenes.BUILDERS``), "registered" (``register_builder``), or "entry point
    <package.module:function>" (group "cracklab.builders"; an entry point does not shadow
    the others)."""
    out = {name: "cracklab" for name in _own_builders()}
    for name in _REGISTERED:
        out.setdefault(name, "registered")
    for name, ep in _entry_points().items():
        out.setdefault(name, f"entry point {ep.value}")
    return out


def _describe(func) -> str:
    module, qual = getattr(func, "__module__", None), getattr(func, "__qualname__", None)
    return f"{module}:{qual}" if module and qual else repr(func)


def builder_name(builder) -> str:
    """The name of a builder: a string as given; for a function, the name it is
    registered under (cracklab's own builders by their name), else "module:qualname",
    under which it is registered now (a function given in Python is trusted)."""
    if isinstance(builder, str):
        return builder
    if callable(builder):
        for name, func in _own_builders().items():
            if func is builder:
                return name
        for name, func in _REGISTERED.items():
            if func is builder:
                return name
        module, qual = getattr(builder, "__module__", None), getattr(builder, "__qualname__", None)
        if not module or not qual or "<" in qual:
            raise InputError("builder", f"must be a module-level function, got {qual or builder!r}; give another "
                                        f"function a name with cracklab.register_builder(name, function)")
        name = f"{module}:{qual}"
        register_builder(name, builder)
        return name
    raise InputError("builder", f"must be a builder name or function, got {builder!r}")


def resolve_builder(name, field: str = "builder"):
    """The function registered as ``name``: one of cracklab's own builders
    (``scenes.BUILDERS``), one registered with ``register_builder``, or an entry point of
    the group "cracklab.builders". Any other name, "package.module:function" included,
    is an InputError naming ``field`` and the registered builders: a name never imports
    a module nor reaches another attribute of cracklab.scenes."""
    if not isinstance(name, str) or not name:
        raise InputError(field, f"must be the name of a registered scene builder, got {name!r}")
    own = _own_builders()
    if name in own:
        return own[name]
    if name in _REGISTERED:
        return _REGISTERED[name]
    ep = _entry_points().get(name)
    if ep is not None:
        key = (name, ep.value)
        if key not in _ENTRY_POINT_CACHE:
            try:
                func = ep.load()
            except Exception as exc:  # noqa: BLE001 - reported as one clear line
                raise InputError(field, f"{name!r}: the entry point {ep.value!r} (group {ENTRY_POINT_GROUP!r}) "
                                        f"cannot be loaded: {type(exc).__name__}: {exc}") from None
            if not callable(func):
                raise InputError(field, f"{name!r}: the entry point {ep.value!r} (group {ENTRY_POINT_GROUP!r}) "
                                        f"is not a function")
            _ENTRY_POINT_CACHE[key] = func
        return _ENTRY_POINT_CACHE[key]
    names = sorted(registered_builders())
    shown = repr(name) if len(name) <= 80 else repr(name[:77] + "...")
    raise InputError(field, f"{shown} is not a scene builder registered with cracklab; registered: "
                            f"{', '.join(names)}. Register your own in Python with "
                            f"cracklab.register_builder(name, function), or in an installed package "
                            f"under the entry-point group {ENTRY_POINT_GROUP!r}")


def _accepts(func):
    """(names of keyword parameters, accepts **kwargs)."""
    try:
        sig = inspect.signature(func)
    except (TypeError, ValueError):     # no signature to read (some built-in callables)
        return set(), True
    names = {p.name for p in sig.parameters.values()
             if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)}
    return names, any(p.kind == p.VAR_KEYWORD for p in sig.parameters.values())


def _is_path(key: str) -> bool:
    return "." in key


def _check_path(key: str, where: str):
    section, _, rest = key.partition(".")
    if section not in SECTIONS or not rest or "." in rest:
        raise InputError(f"{where}.{key}", f"a dotted name must be a scene path <section>.<key> with section "
                                           f"one of {', '.join(SECTIONS)}")


# ---------------------------------------------------------------------------- canonical values
def canonical(value, where="value"):
    """JSON-able canonical form: numpy -> Python, tuples/arrays -> lists, sorted dicts,
    non-finite floats as {"float": "inf"}."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else {"float": repr(v)}
    if isinstance(value, str):
        return value
    if value is None:
        return None
    if isinstance(value, np.ndarray):
        return canonical(value.tolist(), where)
    if isinstance(value, (list, tuple)):
        return [canonical(v, where) for v in value]
    if isinstance(value, dict):
        return {str(k): canonical(value[k], f"{where}.{k}") for k in sorted(value, key=str)}
    raise InputError(where, f"must be a number, string, boolean, list or table, got {type(value).__name__}")


def _decode(value):
    """Undo ``canonical`` for the builder: {"float": "inf"} -> inf (recursively)."""
    if isinstance(value, dict):
        if set(value) == {"float"}:
            return float(value["float"])
        return {k: _decode(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_decode(v) for v in value]
    return value


def canonical_json(obj) -> str:
    return json.dumps(canonical(obj), sort_keys=True, separators=(",", ":"), allow_nan=False)


def member_id(base_key: str, params: dict) -> str:
    text = canonical_json({"cracklab_member": FORMAT, "base": base_key, "params": params})
    return hashlib.sha256(text.encode()).hexdigest()[:ID_LENGTH]


def scene_digest(scene) -> str:
    """A digest of a scene's parameters and input arrays (identifies a Scene base)."""
    from ..model.scene_io import scene_to_json

    text, arrays = scene_to_json(scene)
    h = hashlib.sha256(text.encode())
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()[:ID_LENGTH]


def coordinate_name(param: str) -> str:
    """Coordinate name of a parameter in ``open_ensemble``: dots become underscores."""
    return param.replace(".", "_")


# ---------------------------------------------------------------------------- planning
def _as_sweep(sweep) -> Sweep:
    if isinstance(sweep, Sweep):
        return sweep
    if isinstance(sweep, dict):
        return Sweep(product=dict(sweep))
    if isinstance(sweep, (list, tuple)):
        return Sweep(members=list(sweep))
    raise InputError("sweep", f"must be a Sweep, a dict of axes or a list of members, got {type(sweep).__name__}")


def _base_of(base_scene):
    """(builder name or None, base args, base key, Scene or None)."""
    from ..model.scene import Scene

    if isinstance(base_scene, Scene):
        return None, {}, f"scene:{scene_digest(base_scene)}", base_scene
    if isinstance(base_scene, Builder):
        return base_scene.name, dict(base_scene.args), "builder", None
    if isinstance(base_scene, str) or callable(base_scene):
        b = Builder(base_scene)
        return b.name, {}, "builder", None
    raise InputError("base_scene", f"must be a Scene, a Builder, or a builder name, got {type(base_scene).__name__}")


def _classify(key, accepted, varkw, where, builder):
    """'builder', 'arg' or 'path' for a parameter name (raises on unknown names)."""
    if key == "builder":
        return "builder"
    if _is_path(key):
        _check_path(key, where)
        return "path"
    if builder is not None and (key in accepted or varkw):
        return "arg"
    if key in TOP_LEVEL:
        return "path"
    if builder is None:
        raise InputError(f"{where}.{key}", f"is not a scene path: give <section>.<key> "
                                           f"({', '.join(SECTIONS)}) or one of {', '.join(TOP_LEVEL)}")
    raise InputError(f"{where}.{key}", f"is neither an argument of the builder {builder!r} (accepted: "
                                       f"{', '.join(sorted(accepted))}) nor a scene path <section>.<key>")


def plan(base_scene, sweep) -> list[Member]:
    """The members of a sweep, in order (product first, then explicit members), with
    resolved parameters and ids. Unknown parameter names fail here, before any work;
    parameter values are checked when each member's scene is built (on the worker)."""
    sweep = _as_sweep(sweep)
    default_builder, base_args, base_key, _ = _base_of(base_scene)
    base_args = {**base_args, **(sweep.base or {})}
    if not isinstance(sweep.replicates, int) or isinstance(sweep.replicates, bool) or sweep.replicates < 1:
        raise InputError("study.replicates", f"must be an integer >= 1, got {sweep.replicates!r}")
    if sweep.entropy is not None and (not isinstance(sweep.entropy, (int, np.integer)) or sweep.entropy < 0):
        raise InputError("study.entropy", f"must be an integer >= 0, got {sweep.entropy!r}")
    for name, values in sweep.product.items():
        if not isinstance(values, (list, tuple, np.ndarray)) or len(values) == 0:
            raise InputError(f"sweep.{name}", f"must be a non-empty list of values, got {values!r}")
    combos = []
    axes = list(sweep.product)
    if axes:
        for values in itertools.product(*(list(sweep.product[a]) for a in axes)):
            combos.append(("sweep", dict(zip(axes, values))))
    for i, m in enumerate(sweep.members):
        if not isinstance(m, dict):
            raise InputError(f"members[{i}]", f"must be a table of parameters, got {m!r}")
        combos.append((f"members[{i}]", dict(m)))
    if not combos:
        combos.append(("base", {}))

    if "builder" in base_args:
        raise InputError("base.builder", "the builder is named by the study ([study] builder, or Builder(...)) "
                                         "or by a member, not among the base parameters")
    members, seen = [], {}
    for where, given in combos:
        builder = given.get("builder", default_builder)
        if builder is not None and not isinstance(builder, str):
            builder = builder_name(builder)
            given["builder"] = builder
        if default_builder is None and "builder" in given:
            raise InputError(f"{where}.builder", "a member of a sweep over a base Scene cannot name a builder")
        if builder is not None:
            func = resolve_builder(builder, f"{where}.builder" if "builder" in given else "builder")
            accepted, varkw = _accepts(func)
        else:
            accepted, varkw = set(), False
        params = {}
        if builder is not None:
            params["builder"] = builder
        for key, value in base_args.items():
            try:
                _classify(key, accepted, varkw, "base", builder)
            except InputError:
                if builder != default_builder:
                    continue        # base arguments of the study's builder another builder lacks
                raise
            params[key] = canonical(value, f"base.{key}")
        for key, value in given.items():
            if key == "builder":
                continue
            _classify(key, accepted, varkw, where, builder)
            params[key] = canonical(value, f"{where}.{key}")
        swept = [k for k in given if k != "builder" or given["builder"] != default_builder]
        seeded = builder is not None and sweep.seed_arg in accepted and sweep.seed_arg not in params \
            and sweep.entropy is not None
        if sweep.replicates > 1 and not seeded:
            raise InputError("study.replicates", f"replicates > 1 need study.entropy and a builder taking "
                                                 f"{sweep.seed_arg!r} ({builder!r} in {where})")
        for r in range(sweep.replicates):
            p = dict(params)
            s = list(swept)
            if seeded:
                own = {"builder": builder, **{k: params[k] for k in given if k != "builder"}}
                h = hashlib.sha256(canonical_json(own).encode()).digest()
                key = (int.from_bytes(h[:4], "little"), int.from_bytes(h[4:8], "little"), r)
                state = np.random.SeedSequence(int(sweep.entropy), spawn_key=key).generate_state(1, np.uint64)
                p[sweep.seed_arg] = int(state[0] >> np.uint64(64 - SEED_BITS))
                s.append(sweep.seed_arg)
            mid = member_id(base_key, p)
            if mid in seen:
                raise InputError(where, f"member {len(members)} has the same parameters as member {seen[mid]} "
                                        f"(id {mid}): {p}")
            seen[mid] = len(members)
            members.append(Member(len(members), mid, p, tuple(dict.fromkeys(s))))
    return members


# ---------------------------------------------------------------------------- building one member
def _field_value(section, value):
    if isinstance(value, list) and section in ("law", "loading"):
        arr = np.asarray(value)
        return arr.astype(float) if arr.dtype.kind in "iu" else arr
    if isinstance(value, list):
        return tuple(value)
    return value


def apply_paths(scene, paths: dict):
    """``scene`` with the scene paths ``{"law.tau_c": 2.0, "beta": 0.4, ...}`` set; every
    changed part is rebuilt with ``dataclasses.replace`` and so validated again."""
    sections, top = {}, {}
    for key, value in paths.items():
        value = _decode(value)
        if _is_path(key):
            section, _, name = key.partition(".")
            sections.setdefault(section, {})[name] = _field_value(section, value)
        elif key in TOP_LEVEL:
            top[key] = value
        else:
            raise InputError(key, "is not a scene path")
    changes = dict(top)
    for section, values in sections.items():
        obj = getattr(scene, section)
        known = {f.name for f in dataclasses.fields(obj)}
        for name in values:
            if name not in known:
                raise InputError(f"{section}.{name}", f"unknown key for {type(obj).__name__}; accepted: "
                                                      f"{', '.join(sorted(known))}")
        changes[section] = dataclasses.replace(obj, **values)
    return scene.replace(**changes) if changes else scene


def build_scene(base_scene, params: dict, *, fft_threads: int | None = 1, builders: dict | None = None):
    """The Scene of one member: the builder called with its arguments (or the base Scene),
    then the scene paths applied. ``fft_threads`` sets numerics.fft_threads unless the
    member sets it (None: leave it). ``builders``: {name: function} to use for these
    names (what a worker is sent); other names are resolved with ``resolve_builder``."""
    from ..model.scene import Scene

    params = dict(params)
    if isinstance(base_scene, Scene):
        scene, paths = base_scene, params
    else:
        name = params.pop("builder")
        func = (builders or {}).get(name) if isinstance(name, str) else None
        func = func or resolve_builder(name)
        accepted, varkw = _accepts(func)
        args = {k: _decode(v) for k, v in params.items() if not _is_path(k) and (k in accepted or varkw)}
        paths = {k: v for k, v in params.items() if k not in args}
        scene = func(**args)
        if not isinstance(scene, Scene):
            raise InputError("builder", f"must return a cracklab.Scene, got {type(scene).__name__}")
    scene = apply_paths(scene, paths)
    if fft_threads is not None and "numerics.fft_threads" not in params \
            and scene.numerics.fft_threads != fft_threads:
        scene = scene.replace(numerics=dataclasses.replace(scene.numerics, fft_threads=int(fft_threads)))
    return scene


# ---------------------------------------------------------------------------- store helpers
def _store_str(store) -> str:
    s = os.fspath(store)
    if "://" in s:
        return s.rstrip("/")
    return str(Path(s).expanduser().resolve())


def member_path(store, mid: str) -> str:
    return f"{_store_str(store)}/{MEMBERS}/{mid}"


def _open_group(path, mode):
    import zarr

    return zarr.open_group(path, mode=mode, zarr_format=3) if mode in ("w", "a", "w-") else \
        zarr.open_group(path, mode=mode)


def is_ensemble(store) -> bool:
    """True when ``store`` is an ensemble store (root attr cracklab_ensemble)."""
    try:
        root = _open_group(_store_str(store), "r")
    except Exception:  # noqa: BLE001 - not a Zarr group at all
        return False
    return "cracklab_ensemble" in root.attrs


def store_kind(store) -> str:
    """"ensemble" or "run" for a cracklab store; an InputError naming ``store`` for
    anything else (no such path, a file, a directory or Zarr group that cracklab did
    not write, an ensemble store of a newer format)."""
    s = _store_str(store)
    if "://" not in s and not Path(s).exists():
        raise InputError("store", f"{s} does not exist")
    _check_metadata(s, Path(s) / "zarr.json" if "://" not in s else None,
                    "restore it, or delete the store and run it again")
    try:
        root = _open_group(s, "r")
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


def _check_metadata(store, meta, remedy):
    """StoreError naming ``meta`` (a zarr.json) when it exists but does not parse."""
    if meta is None or not meta.exists():
        return
    from ..output.verify import read_json

    doc, why = read_json(meta)
    if doc is None:
        raise StoreError(store, f"its metadata file {meta} is {why}; {remedy} (cracklab verify {store} "
                                f"lists all damage)")


def _check_store(store: str):
    """Refuse, before anything is written, a path that cannot become or be an ensemble
    store: a file, a non-empty directory that is not a Zarr group, a Zarr group that is
    not an ensemble (e.g. a single run), or a store of a newer ensemble format."""
    import zarr

    if "://" not in store:
        p = Path(store)
        if p.exists() and not p.is_dir():
            raise InputError("store", f"{store} is a file, not a Zarr store; choose another path")
    try:
        root = zarr.open_group(store, mode="r")
    except Exception:  # noqa: BLE001 - no group there (yet)
        root = None
    if root is None:
        if "://" not in store and Path(store).is_dir() and any(
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


def _init_store(store: str, study_spec: dict, members: list[Member], axes=()):
    """Create (or reopen) the root group and members/; record the study and member order."""
    _check_store(store)
    root = _open_group(store, "a")
    old = list(root.attrs.get("members", []))
    ids = old + [m.id for m in members if m.id not in set(old)]
    root.attrs.update({
        "cracklab_ensemble": FORMAT,
        "title": f"cracklab ensemble: {study_spec.get('name', 'study')}",
        "study": json.dumps(study_spec, sort_keys=True),
        "members": ids,
        "axes": json.dumps(list(axes)),
    })
    if "://" not in store:
        from ..output.verify import read_json

        meta = Path(store) / MEMBERS / "zarr.json"
        if meta.exists() and read_json(meta)[0] is None:     # damaged: the members group holds no attrs
            meta.write_text(json.dumps({"zarr_format": 3, "node_type": "group", "attributes": {}}))
        for left in (Path(store) / MEMBERS).glob(f".*{SWAP_TAG}*"):    # replacements of killed workers
            shutil.rmtree(left, ignore_errors=True)
    root.require_group(MEMBERS)
    return root


# ---------------------------------------------------------------------------- store lock
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


def _member_attrs(store, mid):
    import zarr

    try:
        return dict(zarr.open_group(member_path(store, mid), mode="r").attrs)
    except Exception:  # noqa: BLE001 - missing or unreadable group
        return None


def _is_complete(store, mid) -> bool:
    attrs = _member_attrs(store, mid)
    return bool(attrs and attrs.get("complete") is True)


def _damage_of(store, member: Member):
    """None when the complete member ``member`` is sound (every chunk read and checked,
    ``cracklab.output.verify``); else a line naming the damage, after marking the member
    damaged and incomplete (so that no reader takes it, and the sweep runs it again)."""
    if "://" in store:
        return None             # only local stores are verified
    from ..output.verify import check_member

    report = check_member(store, member.id)
    if report.ok:
        return None
    line = report.first()
    with contextlib.suppress(Exception):
        _open_group(member_path(store, member.id), "a").attrs.update(
            {"complete": False, "status": "damaged", "error": f"damaged: {line}"})
    return line


def _traceback_summary(exc, limit=12) -> str:
    lines = traceback.format_exception(type(exc), exc, exc.__traceback__)
    text = "".join(lines).rstrip().splitlines()
    return "\n".join(text[-limit * 2:])


def _error_line(exc) -> str:
    msg = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__


def _record_failure(store, member: Member, error: str, tb: str, elapsed: float | None = None):
    path = member_path(store, member.id)
    try:
        g = _open_group(path, "a")
    except Exception:  # noqa: BLE001
        return
    g.attrs.update({"member_id": member.id, "member_params": canonical_json(member.params),
                    "member_swept": json.dumps(list(member.swept)), "status": "failed",
                    "error": error, "traceback": tb, "complete": False,
                    **({"elapsed_s": round(elapsed, 3)} if elapsed is not None else {})})


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


def _swap_in(new: str, path: str):
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


def _run_member(store: str, member: Member, base, fft_threads=1, builders=None) -> dict:
    """Worker task: build, run and write one member; mark it complete last. Never raises
    for a member's own failure: the error goes to the member's attrs and the result.

    A member whose group is complete (a ``resume=False`` sweep) is replaced atomically
    for readers: the new run is written to a hidden sibling group and swapped in when
    complete (or failed), so that a reader never finds a group marked complete whose
    arrays are being rewritten. Other groups (absent, failed, interrupted, damaged:
    none marked complete) are cleared and written in place. ``builders``: {name: function}
    of the member's builder, resolved by the client (a worker has no registrations of its own)."""
    t0 = time.perf_counter()
    os.environ.setdefault("CRACKLAB_FFT_THREADS", "1")
    path = member_path(store, member.id)
    worker = f"{socket.gethostname()}:{os.getpid()}"
    meta = {"member_id": member.id, "member_params": canonical_json(member.params),
            "member_swept": json.dumps(list(member.swept)), "worker": worker}
    target = path
    try:
        from ..output.simulate import simulate

        old = _member_attrs(store, member.id)
        if old is not None and old.get("complete") is True:
            if "://" in store:      # no rename: mark it incomplete before any array is touched
                _open_group(path, "a").attrs.update({"complete": False, "status": "running"})
            else:
                target = f"{_store_str(store)}/{MEMBERS}/.{member.id}{SWAP_TAG}{os.urandom(4).hex()}"
        g = _open_group(target, "w")          # clears whatever an earlier attempt left
        g.attrs.update({**meta, "status": "running", "complete": False})
        scene = build_scene(base, member.params, fft_threads=fft_threads, builders=builders)
        simulate(scene, store=target)
        g = _open_group(target, "a")
        elapsed = time.perf_counter() - t0
        g.attrs.update({**meta, "status": "complete", "elapsed_s": round(elapsed, 3)})
        g.attrs.update({"complete": True})   # last: the member is complete only now
        if target != path:
            _swap_in(target, path)
        return {"id": member.id, "status": "complete", "elapsed": elapsed, "worker": worker}
    except Exception as exc:  # noqa: BLE001 - recorded, the sweep goes on
        elapsed = time.perf_counter() - t0
        error, tb = _error_line(exc), _traceback_summary(exc)
        if target != path and Path(target).is_dir():
            with contextlib.suppress(OSError):  # what this attempt wrote replaces the old run
                _swap_in(target, path)
        _record_failure(store, member, error, tb, elapsed)
        return {"id": member.id, "status": "failed", "error": error, "traceback": tb,
                "elapsed": elapsed, "worker": worker}


# ---------------------------------------------------------------------------- running
def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


@contextlib.contextmanager
def _client(client=None, scheduler=None, workers=None, n_tasks=None):
    """The client to use: ``client``; else one connected to ``scheduler`` (or env
    DASK_SCHEDULER_ADDRESS); else an embedded LocalCluster of one-thread worker
    processes, one per core (at most one per task)."""
    if client is not None:
        yield client
        return
    import logging

    from distributed import Client, LocalCluster

    address = scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS")
    if address:
        c = Client(address)
        try:
            yield c
        finally:
            c.close()
        return
    n = workers or _cores()
    if n_tasks:
        n = max(1, min(n, n_tasks))
    env = {"CRACKLAB_FFT_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
           "OPENBLAS_NUM_THREADS": "1"}
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                           silence_logs=logging.ERROR, env=env)
    c = Client(cluster)
    try:
        yield c
    finally:
        c.close()
        cluster.close()


def run(base_scene, sweep, store, *, client=None, resume=True, scheduler=None, workers=None,
        progress=None, fft_threads=1, study_spec=None) -> SweepResult:
    """Run every member of ``sweep`` over ``base_scene`` into the Zarr v3 ``store``.

    ``base_scene``: a Scene (parameters are scene paths), a ``Builder``, or a builder
    name. ``sweep``: a ``Sweep``, a dict of product axes, or a list of member dicts.
    With ``resume`` complete members are skipped; incomplete and failed ones are run
    again. Tasks go to ``client``, else to the scheduler at ``scheduler`` (or env
    DASK_SCHEDULER_ADDRESS), else to an embedded LocalCluster with ``workers`` one-thread
    processes (default: one per core); ``scheduler="synchronous"`` runs the members one
    after the other in this process (debugging, tiny sweeps). A failing member does not
    stop the others: see ``SweepResult.failed`` (and the member's attrs error and
    traceback). ``progress``: a bar over members (default: when stderr is a terminal).
    ``fft_threads``: numerics.fft_threads of every member that does not set it (None: as
    built). Holds the store's sweep lock while it runs: a second sweep into the same
    store at the same time raises ``StoreLocked`` (see ``store_lock``)."""
    t0 = time.perf_counter()
    sweep = _as_sweep(sweep)
    members = plan(base_scene, sweep)
    store = _store_str(store)
    spec = study_spec or _spec_of(base_scene, sweep)
    _check_store(store)                  # before the lock: a wrong path is left untouched
    with store_lock(store):
        return _run_locked(base_scene, sweep, members, store, spec, t0, client=client, resume=resume,
                           scheduler=scheduler, workers=workers, progress=progress,
                           fft_threads=fft_threads)


def _run_locked(base_scene, sweep, members, store, spec, t0, *, client, resume, scheduler, workers,
                progress, fft_threads) -> SweepResult:
    from ..model.scene import Scene

    _init_store(store, spec, members, axes=list(sweep.product))
    todo, damaged = [], {}
    for m in members:
        if resume and _is_complete(store, m.id):
            problem = _damage_of(store, m)
            if problem is None:
                continue                    # complete and sound: skipped
            damaged[m.id] = problem         # marked incomplete: recomputed below
        todo.append(m)
    result = SweepResult(store, members, ran=[m.id for m in todo],
                         skipped=[m.id for m in members if m not in todo], damaged=damaged)
    if damaged and progress is not False:
        for mid, problem in damaged.items():
            print(f"cracklab: member {mid} is damaged ({problem}); it is run again", file=sys.stderr, flush=True)
    if progress is None:
        progress = sys.stderr.isatty()
    base = base_scene if isinstance(base_scene, Scene) else None
    # the builders were resolved by plan (only registered ones); each task carries its own
    funcs = {}
    for m in todo:
        name = m.params.get("builder")
        if name is not None and name not in funcs:
            funcs[name] = resolve_builder(name)

    def own(m):
        name = m.params.get("builder")
        return {name: funcs[name]} if name is not None else None

    if todo and client is None and scheduler == "synchronous":
        from tqdm import tqdm

        for m in tqdm(todo, desc="members", unit="member", disable=not progress, file=sys.stderr):
            r = _run_member(store, m, base, fft_threads, own(m))
            if r["status"] != "complete":
                result.failed[m.id] = r.get("error", "failed")
    elif todo:
        from distributed import as_completed
        from tqdm import tqdm

        if progress and client is None:
            address = scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS")
            n = max(1, min(workers or _cores(), len(todo)))
            print(f"cracklab: {len(todo)} members to run; " +
                  (f"connecting to {address}" if address else
                   f"starting a local cluster of {n} worker process{'es' if n > 1 else ''}"),
                  file=sys.stderr, flush=True)
        with _client(client, scheduler, workers, len(todo)) as c:
            base_arg = c.scatter(base, broadcast=True) if base is not None else None
            futures = {c.submit(_run_member, store, m, base_arg, fft_threads, own(m), pure=False,
                                key=f"cracklab-member-{m.id}-{os.urandom(3).hex()}"): m for m in todo}
            bar = tqdm(total=len(todo), desc="members", unit="member", disable=not progress,
                       file=sys.stderr, dynamic_ncols=True)
            try:
                for fut in as_completed(futures):
                    m = futures[fut]
                    try:
                        r = fut.result()
                    except Exception as exc:  # noqa: BLE001 - the worker died, or the task was lost
                        r = {"id": m.id, "status": "failed", "error": _error_line(exc),
                             "traceback": _traceback_summary(exc)}
                        _record_failure(store, m, r["error"], r["traceback"])
                    # forget the task at once: were the worker that holds its (small) result
                    # to die later, dask would otherwise run the member again and rewrite it
                    fut.release()
                    if r["status"] != "complete":
                        result.failed[m.id] = r.get("error", "failed")
                    bar.update(1)
                    if result.failed:
                        bar.set_postfix(failed=len(result.failed))
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise
            finally:
                bar.close()
    for m in todo:      # what the result says complete is complete in the store
        if m.id not in result.failed and not _is_complete(store, m.id):
            error = "IncompleteMember: the member's group is not marked complete after the run"
            _record_failure(store, m, error, "")
            result.failed[m.id] = error
    result.elapsed = time.perf_counter() - t0
    _open_group(store, "a").attrs.update({"last_run": json.dumps({
        "members": len(members), "ran": len(todo), "skipped": len(result.skipped),
        "failed": result.failed, "damaged": result.damaged, "elapsed_s": round(result.elapsed, 3)})})
    return result


def _spec_of(base_scene, sweep: Sweep) -> dict:
    from ..model.scene import Scene

    base = {"scene_digest": scene_digest(base_scene)} if isinstance(base_scene, Scene) else \
        {"builder": builder_name(base_scene.name if isinstance(base_scene, Builder) else base_scene),
         "args": canonical(base_scene.args if isinstance(base_scene, Builder) else {})}
    return {"name": "sweep", "base": base, "sweep": canonical(dataclasses.asdict(sweep))}


# ---------------------------------------------------------------------------- STUDY.toml
def _flatten(table: dict, where: str) -> dict:
    """TOML nests dotted keys (law.tau_c = ...); bring section tables back to paths."""
    out = {}
    for key, value in table.items():
        if key in SECTIONS and isinstance(value, dict):
            for k2, v2 in value.items():
                out[f"{key}.{k2}"] = v2
        else:
            out[key] = value
    return out


STUDY_KEYS = ("name", "builder", "scene", "entropy", "replicates", "seed_arg", "description")


def load_study(path) -> Study:
    """Read a STUDY.toml (see docs/ensembles.md)::

        [study]
        name = "asperity_ensemble"
        builder = "asperity_row"        # a registered builder (ensemble.registered_builders())
        # scene = "base.toml"           # or: a base scene file (then only scene paths)
        entropy = 2024                  # SeedSequence root for builders taking `seed`
        [base]                          # base builder arguments and scene paths
        n1 = 128
        record.every = 16
        [sweep]                         # product axes
        diameter = [0.125, 0.25]
        law.tau_c = [1.0, 2.0]
        [[members]]                     # explicit members (merged over [base])
        builder = "random_toughness"
    """
    from ..model.scene_io import read_toml_file, scene_from_data

    path = Path(path)
    if not path.exists():
        raise InputError(str(path), "no such study file")
    data = read_toml_file(path)
    for key in data:
        if key not in ("study", "base", "sweep", "members"):
            raise InputError(key, "unknown table; accepted: study, base, sweep, members")
    for key in ("study", "base", "sweep"):
        if not isinstance(data.get(key, {}), dict):
            raise InputError(key, f"must be a table [{key}], got {data[key]!r}")
    members = data.get("members", [])
    if not isinstance(members, list) or not all(isinstance(m, dict) for m in members):
        raise InputError("members", "must be an array of tables [[members]]")
    study = data.get("study", {})
    for key in study:
        if key not in STUDY_KEYS:
            raise InputError(f"study.{key}", f"unknown key; accepted: {', '.join(STUDY_KEYS)}")
    if ("builder" in study) == ("scene" in study):
        raise InputError("study.builder", "give exactly one of study.builder and study.scene")
    base = _flatten(data.get("base", {}), "base")
    if "builder" in study:
        if not isinstance(study["builder"], str):
            raise InputError("study.builder", f"must be the name of a registered scene builder, got "
                                              f"{study['builder']!r}")
        resolve_builder(study["builder"], "study.builder")     # before anything else is done
        builder = Builder(study["builder"])
    else:
        if not isinstance(study["scene"], str):
            raise InputError("study.scene", f"must be the path of a scene TOML file, got {study['scene']!r}")
        scene_path = (path.parent / study["scene"])
        if not scene_path.is_file():
            raise InputError("study.scene", f"no such scene file {scene_path}")
        builder = scene_from_data(read_toml_file(scene_path, "study.scene"))
    for key in ("name", "seed_arg", "description"):
        if key in study and not isinstance(study[key], str):
            raise InputError(f"study.{key}", f"must be a string, got {study[key]!r}")
    sweep = Sweep(product=_flatten(data.get("sweep", {}), "sweep"),
                  members=[_flatten(m, f"members[{i}]") for i, m in enumerate(members)],
                  entropy=study.get("entropy"), replicates=study.get("replicates", 1),
                  seed_arg=study.get("seed_arg", "seed"), base=base)
    spec = {"name": study.get("name", path.stem), "file": path.name, **canonical(data)}
    return Study(builder, sweep, study.get("name", path.stem), spec)


def run_study(study, store, **kwargs) -> SweepResult:
    """``run`` for a ``Study`` or the path of a STUDY.toml."""
    if not isinstance(study, Study):
        study = load_study(study)
    return run(study.base, study.sweep, store, study_spec=study.spec, **kwargs)


# ---------------------------------------------------------------------------- reading
def member_status(store) -> list[dict]:
    """One dict per member group in the store (plan order): id, status, complete, params,
    swept, error, traceback, elapsed_s."""
    store = _store_str(store)
    if store_kind(store) != "ensemble":
        raise InputError("store", f"{store} is not a cracklab ensemble store (it is a single run)")
    root = _open_group(store, "r")
    ids = list(root.attrs.get("members", []))
    local = "://" not in store
    if local:
        _check_metadata(store, Path(store) / MEMBERS / "zarr.json",
                        "rerun the sweep (cracklab sweep STUDY.toml -o STORE) to repair it")
    try:
        members_group = root[MEMBERS] if MEMBERS in root else None
        if members_group is None:
            present = []
        elif local:         # listed by their directories: one damaged member must not hide the others
            present = sorted(e.name for e in os.scandir(Path(store) / MEMBERS)
                             if e.is_dir() and not e.name.startswith(".") and Path(e.path, "zarr.json").exists())
        else:
            present = sorted(k for k in members_group.group_keys() if not k.startswith("."))
    except (ValueError, KeyError, OSError) as exc:
        raise StoreError(store, f"its members group {store}/{MEMBERS} cannot be read ({exc}); rerun the sweep "
                                f"(cracklab sweep STUDY.toml -o STORE) to repair it") from None
    order = [i for i in ids if i in set(present)] + [i for i in present if i not in set(ids)]
    out = []
    for mid in order:
        try:
            a = dict(members_group[mid].attrs)
            entry = {"id": mid, "status": a.get("status", "unknown"), "complete": a.get("complete") is True,
                     "params": json.loads(a.get("member_params", "{}")),
                     "swept": json.loads(a.get("member_swept", "[]")),
                     "error": a.get("error"), "traceback": a.get("traceback"),
                     "elapsed_s": a.get("elapsed_s")}
        except (ValueError, KeyError, TypeError, OSError) as exc:     # damaged metadata: reported, never read
            meta = f"{store}/{MEMBERS}/{mid}/zarr.json"
            entry = {"id": mid, "status": "damaged", "complete": False, "params": {}, "swept": [],
                     "error": f"damaged: {meta}: {UNREADABLE} ({_error_line(exc)})",
                     "traceback": None, "elapsed_s": None}
        out.append(entry)
    return out


UNREADABLE = "the member's metadata cannot be read"


def _member_damage(store, mid):
    """None, or a StoreError for the complete member ``mid`` whose metadata or chunk
    listing is damaged (cheap: no data is read; a changed byte raises when read)."""
    if "://" in store:
        return None
    from ..output.verify import check_member

    report = check_member(store, mid, read=False)
    if report.ok:
        return None
    return StoreError(store, f"member {mid} is damaged: {report.first()}; rerun the sweep (cracklab sweep "
                             f"STUDY.toml -o STORE): it recomputes damaged members")


def open_member(store, member: str):
    """One member's Dataset, as ``cracklab.simulate`` wrote it (``scene_of`` works on it)."""
    import xarray as xr

    store = _store_str(store)
    attrs = _member_attrs(store, member)
    if attrs is None and "://" not in store and (Path(store) / MEMBERS / member / "zarr.json").exists():
        _check_metadata(store, Path(store) / MEMBERS / member / "zarr.json",
                        "rerun the sweep (cracklab sweep STUDY.toml -o STORE): it recomputes the member")
    if attrs is not None and attrs.get("complete") is True:
        err = _member_damage(store, member)
        if err is not None:
            raise err
    try:
        return xr.open_zarr(store, group=f"{MEMBERS}/{member}", consolidated=False)
    except FileNotFoundError:
        raise InputError("member", f"{member!r} is not a member of {store}") from None
    except (ValueError, KeyError, OSError) as exc:
        raise StoreError(store, f"member {member} cannot be read ({_error_line(exc)}); cracklab verify {store} "
                                f"names the damaged files; rerun the sweep to recompute it") from None


def _coord_values(values):
    """A 1-D coordinate array from per-member values (None where a member lacks it)."""
    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present) and len(present) == len(values):
        return np.array(values, dtype=bool)
    if present and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        if all(isinstance(v, int) for v in present) and len(present) == len(values):
            return np.array(values, dtype=np.int64)
        return np.array([np.nan if v is None else float(v) for v in values])
    return np.array(["" if v is None else (v if isinstance(v, str) else json.dumps(v)) for v in values],
                    dtype=object)


def open_ensemble(store, *, members=None, complete_only=True, tree=False):
    """The ensemble as one lazily loaded xarray Dataset with a ``member`` dimension.

    Coordinates along ``member``: the member ids (``member``), every swept parameter
    (dots in names become underscores: law.tau_c -> law_tau_c; a member without the
    parameter has NaN, or "" for strings), ``scene_name`` and ``scene`` (the member's
    scene as JSON, see ``member_scene``). Members on different grids or snapshot times are
    aligned by an outer join (the union of the coordinates, NaN where a member has no
    value). With ``tree=True`` a DataTree /members/<id> is returned instead (no padding).
    Only complete members are read unless ``complete_only=False``; ``members``: only
    these ids (e.g. ``[m.id for m in result.members]`` of one sweep). Ready for
    ``ds.groupby("contrast")`` and ``ds.set_xindex("diameter").sel(diameter=...)``."""
    import xarray as xr

    store = _store_str(store)
    status = member_status(store)
    if members is not None:
        wanted = [getattr(m, "id", m) for m in members]
        by_id = {s["id"]: s for s in status}
        missing = [m for m in wanted if m not in by_id]
        if missing:
            raise InputError("members", f"not in {store}: {', '.join(missing[:5])}")
        status = [by_id[m] for m in wanted]
    unreadable = [s for s in status if s["status"] == "damaged" and UNREADABLE in str(s.get("error"))]
    if unreadable:
        raise StoreError(store, f"member {unreadable[0]['id']} is {unreadable[0]['error']}; rerun the sweep "
                                f"(cracklab sweep STUDY.toml -o STORE): it recomputes damaged members")
    if complete_only:
        status = [s for s in status if s["complete"]]
    if not status:
        raise InputError("store", f"{store} holds no complete members")
    root_attrs = dict(_open_group(store, "r").attrs)
    swept = list(dict.fromkeys(k for s in status for k in s["swept"]))
    if len({s["params"].get("builder") for s in status}) > 1 and "builder" not in swept:
        swept.append("builder")
    datasets, scenes, names, kept = [], [], [], []
    for s in status:
        try:
            ds = open_member(store, s["id"])
        except InputError:
            if complete_only:           # replaced meanwhile (a sweep swapping it): not complete now
                continue
            raise
        if complete_only and ds.attrs.get("complete") is not True:
            continue                    # rewritten since it was listed: the group read is not complete
        kept.append(s)
        scene_json = ds.attrs.get("scene", "{}")
        try:
            name = json.loads(scene_json).get("name", "")
        except ValueError:
            name = ""
        scenes.append(scene_json)
        names.append(name)
        ds = _with_input_coords(ds, scene_json)
        ds.attrs = {k: v for k, v in ds.attrs.items() if k in ("Conventions", "source", "cracklab_version")}
        datasets.append(ds)
    status = kept
    if not status:
        raise InputError("store", f"{store} holds no complete members")
    if tree:
        nodes = {"/": xr.Dataset(attrs=_ensemble_attrs(root_attrs, store))}
        for s, ds, text in zip(status, datasets, scenes):
            nodes[f"/{MEMBERS}/{s['id']}"] = ds.assign_attrs(scene=text, member_id=s["id"],
                                                             member_params=canonical_json(s["params"]))
        return xr.DataTree.from_dict(nodes)
    try:
        ens = xr.concat(datasets, dim="member", join="outer", data_vars="all", coords="different",
                        compat="equals", combine_attrs="drop_conflicts", fill_value=np.nan)
    except (ValueError, KeyError) as exc:
        raise StoreError(store, f"its members cannot be combined ({_error_line(exc)}); a member is probably "
                                f"damaged: cracklab verify {store} names the files, and rerunning the sweep "
                                f"recomputes damaged members") from None
    coords = {"member": ("member", np.array([s["id"] for s in status], dtype=object),
                         {"long_name": "ensemble member id"}),
              "scene": ("member", np.array(scenes, dtype=object),
                        {"long_name": "the member's scene as JSON (cracklab.ensemble.member_scene)"}),
              "scene_name": ("member", np.array(names, dtype=object), {"long_name": "scene name"})}
    for name in swept:
        values = [s["params"].get(name) for s in status]
        coords[coordinate_name(name)] = ("member", _coord_values(values),
                                         {"long_name": f"swept parameter {name}", "parameter": name})
    ens = ens.assign_coords(coords)
    ens.attrs.update(_ensemble_attrs(root_attrs, store))
    ens.attrs["swept"] = json.dumps(swept)
    return ens


def _with_input_coords(ds, scene_json):
    """Give the input_x1/input_x3 dims (full-grid scene inputs) their coordinates, so that
    members on different grids align on them."""
    dims = [d for d in ("input_x1", "input_x3") if d in ds.dims and d not in ds.coords]
    if not dims:
        return ds
    try:
        grid = json.loads(scene_json)["grid"]
    except (ValueError, KeyError, TypeError):
        return ds
    coords = {}
    for d, n, L in (("input_x1", "n1", "L1"), ("input_x3", "n3", "L3")):
        if d in dims and n in grid and L in grid and int(grid[n]) == ds.sizes[d]:
            coords[d] = (d, np.arange(int(grid[n])) * float(grid[L]) / int(grid[n]),
                         {"long_name": f"{d[len('input_'):]} of the scene inputs"})
    return ds.assign_coords(coords)


def _ensemble_attrs(root_attrs, store):
    return {"title": root_attrs.get("title", "cracklab ensemble"), "cracklab_ensemble": FORMAT,
            "study": root_attrs.get("study", "{}"), "axes": root_attrs.get("axes", "[]"),
            "ensemble_store": store}


def member_scene(ens, member):
    """The Scene of one member of an ``open_ensemble`` Dataset (or of any Dataset with a
    ``scene`` attr or coordinate)."""
    from ..model.scene_io import scene_from_data

    ds = ens.sel(member=member) if "member" in ens.dims else ens
    text = ds["scene"].item() if "scene" in ds.coords else ds.attrs["scene"]
    arrays = {}
    for n in ds.data_vars:
        if n.startswith("input_"):
            a = ds[n]
            a = a.dropna("input_x1", how="all").dropna("input_x3", how="all") if a.dtype.kind == "f" else a
            arrays[n] = np.asarray(a.values)
    data = json.loads(text)
    wanted = set()

    def refs(d):
        if isinstance(d, dict):
            if set(d) == {"array"}:
                wanted.add(d["array"])
            for v in d.values():
                refs(v)

    refs(data)
    arrays = {k: (v.astype(bool) if k.endswith(("bonded", "initial_crack")) and v.dtype != bool else v)
              for k, v in arrays.items() if k in wanted}
    return scene_from_data(data, arrays)


# ---------------------------------------------------------------------------- netCDF export
def _nc_attr(value):
    """An attr value netCDF4 can hold: booleans as "true"/"false", tables and mixed lists
    as JSON text, None dropped."""
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (dict,)):
        return json.dumps(canonical(value), sort_keys=True)
    if isinstance(value, (list, tuple)):
        if len(value) == 0:
            return ""
        if all(isinstance(v, str) for v in value):
            return json.dumps(list(value))
        if all(isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) for v in value):
            return np.asarray(value)
        return json.dumps(canonical(value))
    return value


def _nc_attrs(attrs):
    out = {}
    for k, v in attrs.items():
        v = _nc_attr(v)
        if v is not None:
            out[k] = v
    return out


def netcdf_ready(ds):
    """A copy of ``ds`` that netCDF4 can store: Zarr encodings dropped, attrs made netCDF
    types, string and object arrays as plain str."""
    ds = ds.copy()
    strings = {}
    for name, var in ds.variables.items():
        var.encoding = {}
        var.attrs = _nc_attrs(var.attrs)
        if var.dtype.kind in "OU":
            vals = np.asarray(var.values)
            fixed = np.array(["" if v is None or (isinstance(v, float) and np.isnan(v)) else str(v)
                              for v in vals.ravel()], dtype=object).reshape(vals.shape)
            strings[name] = (var.dims, fixed, var.attrs)
    coords = {k: v for k, v in strings.items() if k in ds.coords}
    data = {k: v for k, v in strings.items() if k not in ds.coords}
    ds = ds.assign_coords(coords).assign(data)
    for var in ds.variables.values():
        var.encoding = {}
    ds.attrs = _nc_attrs(ds.attrs)
    return ds


def _read_error(store, exc) -> StoreError:
    """A StoreError naming the damaged files of ``store`` (found by ``cracklab.output.verify``)
    for an error met while reading its data."""
    if "://" not in store:
        from ..output.verify import verify

        with contextlib.suppress(Exception):
            report = verify(store)
            if not report.ok:
                return StoreError(store, f"is damaged: {report.first()}; {report.remedy()}")
    return StoreError(store, f"cannot be read ({_error_line(exc)}); cracklab verify {store} names the damaged "
                             f"files")


def export_netcdf(store, out, *, member=None):
    """Write a run's store, one member of an ensemble (``member`` id), or the whole
    ensemble (``open_ensemble``) to the netCDF4 file ``out``; returns its path."""
    import xarray as xr

    store = _store_str(store)
    if store_kind(store) == "ensemble":
        if member and member not in {st["id"] for st in member_status(store)}:
            raise InputError("member", f"{member!r} is not a member of {store}")
        ds = open_member(store, member) if member else open_ensemble(store)
        if member:
            ds.attrs["member_id"] = member
    else:
        if member:
            raise InputError("member", f"{store} is a single run, not an ensemble")
        if "://" not in store:
            from ..output.verify import check_run

            report = check_run(store, read=False)
            if not report.ok:
                raise StoreError(store, f"is damaged: {report.first()}; {report.remedy()}")
        try:
            ds = xr.open_zarr(store, consolidated=False)
        except (ValueError, KeyError, OSError) as exc:
            raise _read_error(store, exc) from None
    try:
        ds = ds.load()
    except (ValueError, RuntimeError, OSError) as exc:    # checksum, decompression, decoding errors
        raise _read_error(store, exc) from None
    ds = netcdf_ready(ds)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    ds.to_netcdf(out, engine="netcdf4", format="NETCDF4")
    return out
